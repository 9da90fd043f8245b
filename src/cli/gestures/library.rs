//! `crowdtouch library …`: the gesture library — build it from the simulator and the
//! gesture generator, or start one with classes of your own (`new`), import crowd
//! motions from track files (`import-motion`), add a person's gestures to it, remove
//! a class, show it, evaluate its recognition (gesture-driven section 8.2), and make
//! a labelled test set.

use super::library_build::{build, mixtures, test_set};
use super::library_edit::{add, import, new, remove};
use super::library_file::{load, load_with};
use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::motion::{
    FeatureParams, ImportWindow, DEFAULT_IMPORT_DURATION_S, SHIPPED_SEED,
};
use crowdtouch::gesture::generator::Generator;
use crowdtouch::gesture::library::{Library, LoadPolicy, MotionClass};
use std::path::PathBuf;

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
        /// The simulator's classes to build, in this order (default: all ten).
        #[arg(long, value_delimiter = ',')]
        classes: Vec<MotionClass>,
        /// The gesture generator (`synth` or `style2`; `both`, as shipped: the
        /// motion's gestures alternate between them).
        #[arg(long, default_value = "both")]
        generator: GeneratorChoice,
    },
    /// Start a library of your own: the classes named (none: an empty library),
    /// no motion, no gesture. Fill it with `import-motion` and `add`.
    New {
        /// Output file (refused if it exists, unless `--force`).
        #[arg(long, short)]
        out: PathBuf,
        /// A class name (an ASCII letter, then letters, digits, `_` or `-`);
        /// repeat or separate with commas.
        #[arg(long = "class", value_delimiter = ',')]
        classes: Vec<String>,
        /// Replace an existing file.
        #[arg(long)]
        force: bool,
    },
    /// Import a crowd motion for class CLASS from a track file (our JSON Lines, CSV
    /// `t,id,x,y`, the pedestrian datasets' ETH/UCY format, or a daemon run's
    /// `replay --tracks`): the people present throughout a time window (given, or
    /// the busiest `--duration-s` of the file), turned into the library's motion
    /// representation as `library build` turns a simulated crowd (FPCA and a
    /// Gaussian mixture, gesture-driven section 6). A class the library lacks is
    /// added.
    ImportMotion {
        /// The class the motion belongs to.
        #[arg(long)]
        class: String,
        /// The track file.
        tracks: PathBuf,
        /// Library to add to (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
        /// Where to write the new library.
        #[arg(long, short)]
        out: PathBuf,
        /// Window start in the file's time (s).
        #[arg(long)]
        from_s: Option<f64>,
        /// Window end in the file's time (s).
        #[arg(long)]
        to_s: Option<f64>,
        /// Length of the window when it is chosen or given by one end (s).
        #[arg(long, default_value_t = DEFAULT_IMPORT_DURATION_S)]
        duration_s: f64,
        /// Seed of the mixture's fitting.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Config whose `gestures.gmm_components` and `gestures.auto_components_max`
        /// fit the motion's mixture (default: 2 components, as shipped).
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Remove a class with its motions and gestures.
    Remove {
        /// The class.
        #[arg(long)]
        class: String,
        /// Library to remove it from (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
        /// Where to write the new library.
        #[arg(long, short)]
        out: PathBuf,
    },
    /// Summarise a library: its classes with their motions and gestures, and who
    /// drew the gestures.
    Show {
        /// Library file (default: the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
    },
    /// Evaluate recognition (gesture-driven section 8.2): leave-one-out with
    /// weighted KNN voting over the library, or the classification of a labelled
    /// test directory (`DIR/<class>/*`, any recording format). Prints the confusion
    /// matrices and accuracies on the six basic classes and on all ten (eq. 12 plus
    /// the physical features), eq. 12 alone beside them, and the accuracy with each
    /// of eq. 12's features removed. `--cross-style` instead trains on one gesture
    /// generator and tests on the other, both ways, plus leave-one-out on each.
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
        /// Cross-style evaluation on generated sets of both generators.
        #[arg(long, conflicts_with_all = ["library", "test"])]
        cross_style: bool,
        /// Gestures per class and generator (`--cross-style`).
        #[arg(long, default_value_t = 30, requires = "cross_style")]
        per_class: usize,
        /// Seed of the evaluation sets (`--cross-style`).
        #[arg(long, default_value_t = 28, requires = "cross_style")]
        seed: u64,
        /// Fit the physical features' weights across styles first, on sets of
        /// seed + 1, and evaluate with them (`--cross-style`).
        #[arg(long, requires = "cross_style")]
        fit: bool,
        /// `participant`: leave one participant out — each named participant's
        /// gestures classified against everyone else's (gestures of no one named,
        /// such as generated ones, are always in the training set).
        #[arg(long, value_enum, conflicts_with_all = ["test", "cross_style"])]
        by: Option<EvalBy>,
    },
    /// Add a person's gestures of class CLASS from recordings (any format): every
    /// gesture found in each recording, paired with the library's motion of that
    /// class whose gestures it is nearest to (or `--motion N`).
    Add {
        /// The class the gestures ask for (one of the library's).
        #[arg(long)]
        class: String,
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
        /// Who drew the gestures (stored with each, for leave-one-participant-out).
        #[arg(long)]
        participant: Option<String>,
        /// The device they were drawn on (default: each recording's device name).
        #[arg(long)]
        device: Option<String>,
        /// Recordings.
        #[arg(required = true)]
        recordings: Vec<PathBuf>,
    },
    /// Collect gestures from a person at the table: each chosen motion is shown by
    /// the crowd (and to renderers as `demo_motion`), the gesture drawn for it is
    /// stored with the participant id and the device; the library is saved after
    /// every gesture. Skip, undo and show again from a client or the viewer.
    Collect(super::library_collect::CollectArgs),
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
        /// The gesture generator (`synth`: its test-set ranges; `style2`).
        #[arg(long, default_value = "synth")]
        generator: Generator,
    },
}

/// `--by` of `library eval`.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EvalBy {
    /// Leave one participant out (section 8.2's evaluation by person).
    Participant,
}

/// `--generator` of `library build`: one generator, or both alternating.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum GeneratorChoice {
    /// One generator.
    One(Generator),
    /// Both, alternating gesture by gesture.
    Both,
}

impl std::str::FromStr for GeneratorChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<GeneratorChoice, String> {
        match s {
            "both" => Ok(GeneratorChoice::Both),
            g => g.parse().map(GeneratorChoice::One).map_err(
                |e: crowdtouch::gesture::generator::UnknownGenerator| format!("{e}, or both"),
            ),
        }
    }
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
            classes,
            generator,
        } => {
            let mixtures = mixtures(config.as_deref())?;
            let classes = if classes.is_empty() {
                MotionClass::ALL.to_vec()
            } else {
                classes
            };
            let generators = match generator {
                GeneratorChoice::One(g) => vec![g],
                GeneratorChoice::Both => Generator::ALL.to_vec(),
            };
            build(
                &out,
                seed,
                classes,
                (motions_per_class, gestures_per_motion),
                mixtures,
                generators,
            )
        }
        LibraryCmd::New {
            out,
            classes,
            force,
        } => new(&out, classes, force),
        LibraryCmd::ImportMotion {
            class,
            tracks,
            library,
            out,
            from_s,
            to_s,
            duration_s,
            seed,
            config,
        } => {
            let (gmm_components, auto_components) = mixtures(config.as_deref())?;
            let fp = FeatureParams {
                gmm_components,
                auto_components,
                seed,
                ..FeatureParams::default()
            };
            let window = ImportWindow {
                from_s,
                to_s,
                duration_s,
            };
            import(library.as_deref(), &class, &tracks, &window, &fp, &out)
        }
        LibraryCmd::Remove {
            class,
            library,
            out,
        } => remove(library.as_deref(), &class, &out),
        LibraryCmd::TestSet {
            out,
            seed,
            per_class,
            generator,
        } => test_set(&out, seed, per_class, generator),
        // Run by `cli.rs`, which starts the daemon.
        LibraryCmd::Collect(_) => bail!("internal: library collect reached the library tools"),
        LibraryCmd::Show { library } => show(&load_with(library.as_deref(), LoadPolicy::Partial)?),
        LibraryCmd::Eval {
            cross_style: true,
            per_class,
            seed,
            fit,
            ..
        } => super::library_eval::cross(
            cfg()?,
            &super::library_eval::CrossArgs {
                per_class,
                seed,
                fit,
            },
        ),
        LibraryCmd::Eval {
            library,
            by: Some(EvalBy::Participant),
            ..
        } => super::library_eval::by_participant(cfg()?, &load(library.as_deref())?),
        LibraryCmd::Eval { library, test, .. } => {
            super::library_eval::eval(cfg()?, &load(library.as_deref())?, test.as_deref())
        }
        LibraryCmd::Add {
            class,
            motion,
            library,
            out,
            recordings,
            participant,
            device,
            ..
        } => add(
            cfg()?,
            library.as_deref(),
            &class,
            motion,
            &out,
            &recordings,
            (participant, device),
        ),
    }
}

fn show(lib: &Library) -> Result<()> {
    let width = lib
        .classes
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(0)
        .max(24);
    outln!("{:<width$} {:>8} {:>9}", "class", "motions", "gestures")?;
    for (name, c) in lib.classes.iter().zip(lib.counts()) {
        let warn = match (c.motions, c.gestures) {
            (0, 0) => "  (empty)",
            (_, 0) => "  (no gesture: never recognised)",
            _ => "",
        };
        outln!("{name:<width$} {:>8} {:>9}{warn}", c.motions, c.gestures)?;
    }
    outln!(
        "{:<width$} {:>8} {:>9}",
        "total",
        lib.motions.len(),
        lib.gestures.len()
    )?;
    let mut participants: Vec<&str> = lib
        .gestures
        .iter()
        .map(|g| g.participant.as_str())
        .filter(|p| !p.is_empty())
        .collect();
    participants.sort_unstable();
    participants.dedup();
    let mut devices: Vec<&str> = lib
        .gestures
        .iter()
        .map(|g| g.device.as_str())
        .filter(|d| !d.is_empty())
        .collect();
    devices.sort_unstable();
    devices.dedup();
    let unknown = lib
        .gestures
        .iter()
        .filter(|g| g.participant.is_empty())
        .count();
    outln!(
        "classes {}, participants {} ({unknown} gestures by no one named), devices {}",
        lib.classes.len(),
        participants.len(),
        devices.len()
    )?;
    Ok(())
}
