//! `crowdtouch library …`: the gesture library — build it from the simulator and the
//! gesture generator, show it, evaluate its recognition (gesture-driven section
//! 8.2), add a person's gestures to it, and make a labelled test set.

use super::gesture::gestures_in;
use super::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::motion::{build_library, BuildParams, FeatureParams, SHIPPED_SEED};
use crowdtouch::engine::search_params;
use crowdtouch::gesture::dtw::{gesture_distance, Dtw};
use crowdtouch::gesture::eval::{leave_one_out_report, train_test_report, Evaluation, Report};
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::library::{
    read_library, read_library_with, shipped, write_library, Library, LibraryGesture, LoadPolicy,
    MotionClass, MAX_LIBRARY_BYTES,
};
use crowdtouch::gesture::resample::{prepare, prepare_scaled};
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle, StyleRanges};
use crowdtouch::input::recording::JsonlWriter;
use crowdtouch::input::{AxisRange, SurfaceInfo};
use crowdtouch::vocab::Micros;
use std::path::{Path, PathBuf};

/// `crowdtouch library` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum LibraryCmd {
    /// Build a library: crowd motions from the simulator (ten classes), each
    /// paired with gestures from the generator of human-like multi-touch gestures.
    /// Deterministic; the defaults build the shipped `config/gestures/library.ctgl`.
    Build {
        /// Output file.
        #[arg(long, short, default_value = "config/gestures/library.ctgl")]
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = SHIPPED_SEED)]
        seed: u64,
        /// Crowd motions per class.
        #[arg(long, default_value_t = 15)]
        motions_per_class: usize,
        /// Gestures drawn for each motion.
        #[arg(long, default_value_t = 5)]
        gestures_per_motion: usize,
        /// Config whose `gestures.gmm_components` and `gestures.auto_components_max`
        /// fit the motions' mixtures (default: 2 components, as shipped).
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Summarise a library: motions and gestures per class.
    Show {
        /// Library file (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Evaluate recognition (gesture-driven section 8.2): leave-one-out with
    /// weighted KNN voting over the library, or the classification of a labelled
    /// test directory (`DIR/<class>/*`, any recording format). Prints the confusion
    /// matrices and accuracies on the six basic classes and on all ten, and the
    /// accuracy with each feature removed.
    Eval {
        /// Library file (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
        /// Labelled test directory (default: leave-one-out on the library).
        #[arg(long)]
        test: Option<PathBuf>,
        /// Config (its `gestures` weights, K and band; `controls` for segmenting).
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Add a person's gestures of class CLASS from recordings (any format): every
    /// gesture found in each recording, paired with the library's motion of that
    /// class whose gestures it is nearest to (or `--motion N`).
    Add {
        /// The class the gestures ask for.
        #[arg(long)]
        class: MotionClass,
        /// Pair with this motion (an index into the library's motions).
        #[arg(long)]
        motion: Option<u32>,
        /// Library to add to (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
        /// Where to write the new library.
        #[arg(long, short)]
        out: PathBuf,
        /// Config (its `controls` for segmenting, `surface.size_mm`).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Recordings.
        #[arg(required = true)]
        recordings: Vec<PathBuf>,
    },
    /// Write a labelled test set of generated gestures, `DIR/<class>/<class>-NN.jsonl`,
    /// drawn with other seeds, devices and style ranges than the shipped library.
    TestSet {
        /// Output directory.
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = 8_960)]
        seed: u64,
        /// Gestures per class.
        #[arg(long, default_value_t = 50)]
        per_class: usize,
    },
}

/// Runs a `library` subcommand with the config found for it.
pub fn library(cmd: LibraryCmd, cfg: Option<&Config>) -> Result<()> {
    let cfg = || cfg.context("internal: no config for a library command");
    match cmd {
        LibraryCmd::Build {
            out,
            seed,
            motions_per_class,
            gestures_per_motion,
            config,
        } => {
            let mixtures = match config {
                Some(p) => {
                    let c = Config::load(&p)?;
                    (
                        c.gestures.gmm_components as usize,
                        c.gestures.auto_components_max.map(|k| k as usize),
                    )
                }
                None => (2, None),
            };
            build(&out, seed, motions_per_class, gestures_per_motion, mixtures)
        }
        LibraryCmd::TestSet {
            out,
            seed,
            per_class,
        } => test_set(&out, seed, per_class),
        LibraryCmd::Show { library } => show(&load(library.as_deref())?),
        LibraryCmd::Eval { library, test, .. } => {
            eval(cfg()?, &load(library.as_deref())?, test.as_deref())
        }
        LibraryCmd::Add {
            class,
            motion,
            library,
            out,
            recordings,
            ..
        } => add(cfg()?, library.as_deref(), class, motion, &out, &recordings),
    }
}

/// A library file, or the shipped library.
pub fn load(path: Option<&Path>) -> Result<Library> {
    load_with(path, LoadPolicy::Complete)
}

fn load_with(path: Option<&Path>, policy: LoadPolicy) -> Result<Library> {
    match path {
        None => Ok(shipped()?),
        Some(p) => {
            let bytes = crowdtouch::located::read_bytes(p, MAX_LIBRARY_BYTES as u64)
                .map_err(|e| anyhow!("cannot read library: {e}"))?;
            Ok(read_library_with(&bytes, &p.display().to_string(), policy)?)
        }
    }
}

fn build(
    out: &Path,
    seed: u64,
    per_class: usize,
    per_motion: usize,
    (gmm_components, auto_components): (usize, Option<usize>),
) -> Result<()> {
    let defaults = BuildParams::default();
    let p = BuildParams {
        seed,
        motions_per_class: per_class,
        gestures_per_motion: per_motion,
        features: FeatureParams {
            gmm_components,
            auto_components,
            ..defaults.features
        },
        ..defaults
    };
    let lib = build_library(&p)?;
    let bytes = write_library(&lib);
    // The file read back is the file written.
    read_library(&bytes, &out.display().to_string())?;
    std::fs::write(out, &bytes).with_context(|| format!("{}: cannot write", out.display()))?;
    outln!(
        "{}: {} motions, {} gestures, {} bytes",
        out.display(),
        lib.motions.len(),
        lib.gestures.len(),
        bytes.len()
    )?;
    Ok(())
}

fn show(lib: &Library) -> Result<()> {
    outln!("{:<24} {:>8} {:>9}", "class", "motions", "gestures")?;
    for c in MotionClass::ALL {
        let m = lib.motions.iter().filter(|m| m.class == c).count();
        let g = lib.gestures.iter().filter(|g| g.class == c).count();
        outln!("{:<24} {m:>8} {g:>9}", c.as_str())?;
    }
    outln!(
        "{:<24} {:>8} {:>9}",
        "total",
        lib.motions.len(),
        lib.gestures.len()
    )?;
    Ok(())
}

fn labelled(lib: &Library) -> Vec<(MotionClass, GestureFeatures)> {
    lib.gestures
        .iter()
        .map(|g| (g.class, GestureFeatures::of(&g.gesture)))
        .collect()
}

fn eval(cfg: &Config, lib: &Library, test: Option<&Path>) -> Result<()> {
    let params = search_params(cfg);
    let train = labelled(lib);
    let report = match test {
        None => {
            outln!(
                "leave-one-out over {} library gestures (K = {}, weighted voting)",
                train.len(),
                params.k
            )?;
            leave_one_out_report(&train, &params)
        }
        Some(dir) => {
            let test = read_test_dir(dir, cfg)?;
            outln!(
                "{} test gestures from {} against {} library gestures (K = {})",
                test.len(),
                dir.display(),
                train.len(),
                params.k
            )?;
            train_test_report(&train, &test, &params)
        }
    };
    print_report(&report)
}

/// `DIR/<class>/*`: every gesture in every recording, labelled by its folder.
fn read_test_dir(dir: &Path, cfg: &Config) -> Result<Vec<(MotionClass, GestureFeatures)>> {
    let mut out = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read test directory", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    entries.sort();
    for sub in entries {
        let name = sub.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let class: MotionClass = name
            .parse()
            .with_context(|| format!("{}: folder is not a class", sub.display()))?;
        let mut files: Vec<PathBuf> = std::fs::read_dir(&sub)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file())
            .collect();
        files.sort();
        for f in files {
            for g in gestures_in(&f, cfg)? {
                match g.tracks {
                    Ok(t) => match prepare(&t) {
                        Ok(r) => out.push((class, GestureFeatures::of(&r))),
                        Err(e) => outln!("{}: gesture skipped: {e}", f.display())?,
                    },
                    Err(why) => outln!("{}: gesture skipped: {why}", f.display())?,
                }
            }
        }
    }
    if out.is_empty() {
        bail!("{}: no labelled gesture found", dir.display());
    }
    Ok(out)
}

fn print_report(r: &Report) -> Result<()> {
    outln!()?;
    outln!("six basic classes")?;
    print_eval(&r.basic)?;
    outln!()?;
    outln!("all ten classes")?;
    print_eval(&r.all)?;
    outln!()?;
    outln!("with one feature removed (others renormalised):")?;
    outln!("{:<10} {:>8} {:>8}", "removed", "basic", "all")?;
    for a in &r.ablation {
        outln!(
            "{:<10} {:>7.1}% {:>7.1}%",
            a.removed.as_str(),
            100.0 * a.accuracy_basic,
            100.0 * a.accuracy_all
        )?;
    }
    Ok(())
}

/// The short column names of the confusion matrix.
fn short(c: MotionClass) -> &'static str {
    match c {
        MotionClass::Translate => "trans",
        MotionClass::Twist => "twist",
        MotionClass::Contract => "contr",
        MotionClass::Expand => "expan",
        MotionClass::Join => "join",
        MotionClass::Split => "split",
        MotionClass::SplitThenTranslate => "sp+tr",
        MotionClass::TranslateThenJoin => "tr+jo",
        MotionClass::TwistWhileExpanding => "tw+ex",
        MotionClass::TwistWhileContracting => "tw+co",
    }
}

fn print_eval(e: &Evaluation) -> Result<()> {
    let classes = &e.confusion.classes;
    let mut head = format!("{:<24}", "true \\ recognised");
    for c in classes {
        head.push_str(&format!(" {:>5}", short(*c)));
    }
    head.push_str("  accuracy");
    outln!("{head}")?;
    for (i, c) in classes.iter().enumerate() {
        let mut row = format!("{:<24}", c.as_str());
        for n in &e.confusion.counts[i] {
            row.push_str(&format!(" {n:>5}"));
        }
        if let Some(pc) = e.per_class.iter().find(|p| p.class == *c) {
            row.push_str(&format!("  {:>6.1}%", 100.0 * pc.accuracy()));
        }
        outln!("{row}")?;
    }
    outln!(
        "accuracy {:.1}% (mean of classes {:.1}%)",
        100.0 * e.accuracy,
        100.0 * e.mean_class_accuracy
    )?;
    Ok(())
}

fn add(
    cfg: &Config,
    library: Option<&Path>,
    class: MotionClass,
    motion: Option<u32>,
    out: &Path,
    files: &[PathBuf],
) -> Result<()> {
    let mut lib = load_with(library, LoadPolicy::Partial)?;
    let mut added = 0;
    for f in files {
        for g in gestures_in(f, cfg)? {
            let tracks = match g.tracks {
                Ok(t) => t,
                Err(why) => {
                    outln!(
                        "{}: gesture at {:.3} s skipped: {why}",
                        f.display(),
                        g.t.as_secs_f64()
                    )?;
                    continue;
                }
            };
            let (gesture, scale_mm) = prepare_scaled(&tracks).with_context(|| {
                format!("{}: gesture at {:.3} s", f.display(), g.t.as_secs_f64())
            })?;
            let motion = match motion {
                Some(m) => match lib.motions.get(m as usize) {
                    Some(mf) if mf.class == class => m,
                    Some(mf) => bail!("motion {m} is a {} motion, not {class}", mf.class),
                    None => bail!("motion {m}: the library has {} motions", lib.motions.len()),
                },
                None => nearest_motion(&lib, class, &GestureFeatures::of(&gesture), cfg)?,
            };
            lib.gestures.push(LibraryGesture {
                class,
                motion,
                gesture,
                origin: format!("recording {} t={:.3}s", f.display(), g.t.as_secs_f64()),
                scale_mm: Some(scale_mm),
            });
            added += 1;
        }
    }
    let bytes = write_library(&lib);
    read_library_with(&bytes, &out.display().to_string(), LoadPolicy::Partial)?;
    std::fs::write(out, &bytes).with_context(|| format!("{}: cannot write", out.display()))?;
    outln!(
        "{}: {added} {class} gestures added; {} gestures, {} motions",
        out.display(),
        lib.gestures.len(),
        lib.motions.len()
    )?;
    Ok(())
}

/// The motion of `class` whose library gestures are nearest to `f` (eq. 12).
fn nearest_motion(
    lib: &Library,
    class: MotionClass,
    f: &GestureFeatures,
    cfg: &Config,
) -> Result<u32> {
    // The nearest library gesture of the class (eq. 12; the first of equals).
    let p = search_params(cfg);
    let mut dtw = Dtw::new();
    let mut best: Option<(f64, u32)> = None;
    for g in lib.gestures.iter().filter(|g| g.class == class) {
        let d = gesture_distance(
            &mut dtw,
            f,
            &GestureFeatures::of(&g.gesture),
            &p.weights,
            p.band,
        );
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, g.motion));
        }
    }
    match (best, lib.motions.iter().position(|m| m.class == class)) {
        (Some((_, motion)), _) => Ok(motion),
        (None, Some(m)) => Ok(m as u32),
        (None, None) => bail!("the library has no {class} motion to pair the gesture with"),
    }
}

fn test_set(out: &Path, seed: u64, per_class: usize) -> Result<()> {
    let ranges = StyleRanges::test_set();
    let mut n = 0;
    for class in MotionClass::ALL {
        let dir = out.join(class.as_str());
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("{}: cannot create", dir.display()))?;
        for i in 0..per_class {
            let s = seed
                .wrapping_mul(1_000_003)
                .wrapping_add((class.index() * 10_000 + i) as u64);
            let style = GestureStyle::random(class, s, &ranges);
            let tracks = generate(class, &style, s ^ 0xa5a5);
            let frames = to_frames(&tracks, style.device_mm, Micros(1_000_000));
            let surface = SurfaceInfo {
                name: format!(
                    "test set {:.0}x{:.0} mm",
                    style.device_mm.0, style.device_mm.1
                ),
                x: AxisRange {
                    min: 0.0,
                    max: style.device_mm.0 * 10.0,
                    resolution: 10.0,
                },
                y: AxisRange {
                    min: 0.0,
                    max: style.device_mm.1 * 10.0,
                    resolution: 10.0,
                },
                max_contacts: 10,
            };
            let path = dir.join(format!("{}-{i:02}.jsonl", class.as_str()));
            let file = std::fs::File::create(&path)
                .with_context(|| format!("{}: cannot create", path.display()))?;
            let mut w = JsonlWriter::new(&surface, std::io::BufWriter::new(file))?;
            for f in &frames {
                w.frame(f)?;
            }
            w.flush()?;
            n += 1;
        }
    }
    outln!(
        "{}: {n} gestures in {} classes",
        out.display(),
        MotionClass::ALL.len()
    )?;
    Ok(())
}
