//! `crowdtouch library eval --cross-style`: recognition trained on one gesture
//! generator and tested on the other, both ways, plus leave-one-out on each
//! (issue 28), for the recogniser (eq. 12 plus the physical features) beside eq. 12
//! alone; `--fit` chooses the physical weights across styles; and how the rejection
//! thresholds fare on held-out gestures and on touches that are not gestures.
//! Also plain `library eval`: leave-one-out over a library, or the library against
//! a labelled directory of recordings, with the confusion matrices both print.

use super::classes::class_of;
use super::gesture::gestures_in;
use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use crowdtouch::config::Config;
use crowdtouch::engine::search_params;
use crowdtouch::gesture::eval::{
    cross_style, evaluate, fit_weights, leave_one_out_report, outcomes, train_test_report,
    ClassLabel, Evaluation, Example, Label, Outcome, Report,
};
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::generator::{labelled_set, Generator};
use crowdtouch::gesture::library::{Library, MotionClass};
use crowdtouch::gesture::physical::{PhysicalFeatures, PhysicalWeights, PHYSICAL_NAMES};
use crowdtouch::gesture::reject::{Movement, RejectParams};
use crowdtouch::gesture::style2::draw_still;
use crowdtouch::gesture::synth::StyleRanges;
use std::path::{Path, PathBuf};

/// What `--cross-style` runs.
pub struct CrossArgs {
    /// Gestures per class and generator.
    pub per_class: usize,
    /// Seed of the evaluation sets.
    pub seed: u64,
    /// Fit the weights first (on sets of seed `seed + 1`), then evaluate with them.
    pub fit: bool,
}

/// Both generators' labelled sets of `seed` as examples (a gesture that cannot be
/// prepared is left out and counted).
pub fn examples(per_class: usize, seed: u64) -> Result<(Vec<Example>, Vec<Example>)> {
    let ranges = StyleRanges::default();
    let mut sets = Vec::new();
    for g in Generator::ALL {
        let drawn = labelled_set(g, &MotionClass::ALL, per_class, seed, Some(&ranges));
        let mut out = Vec::with_capacity(drawn.len());
        for d in &drawn {
            match Example::of(d.class, &d.tracks) {
                Ok(e) => out.push(e),
                Err(e) => outln!("{g} {}: gesture skipped: {e}", d.class)?,
            }
        }
        sets.push(out);
    }
    let b = sets.pop().unwrap_or_default();
    let a = sets.pop().unwrap_or_default();
    Ok((a, b))
}

/// Runs `library eval --cross-style`.
pub fn cross(cfg: &Config, args: &CrossArgs) -> Result<()> {
    let p = search_params(cfg);
    let mut weights = PhysicalWeights::default();
    if args.fit {
        let (fa, fb) = examples(args.per_class, args.seed + 1)?;
        outln!(
            "fitting the physical weights on {} synth and {} style2 gestures (seed {})",
            fa.len(),
            fb.len(),
            args.seed + 1
        )?;
        let (w, score) = fit_weights(&fa, &fb, weights, &p, 3);
        weights = w;
        outln!(
            "fitted: score {score:.4} (worst of the four basic-class figures + 0.1 x their mean)"
        )?;
        outln!("  eq12 {:.4}", w.eq12)?;
        for (name, v) in PHYSICAL_NAMES.iter().zip(w.features) {
            outln!("  {name} {v:.4}")?;
        }
        outln!()?;
    }
    let (a, b) = examples(args.per_class, args.seed)?;
    outln!(
        "cross-style evaluation: {} synth and {} style2 gestures ({} per class, seed {}), K = {}",
        a.len(),
        b.len(),
        args.per_class,
        args.seed,
        p.k
    )?;
    let runs = cross_style(("synth", &a), ("style2", &b), &weights, &p);
    for r in &runs {
        outln!()?;
        outln!("== {} ==", r.name)?;
        outln!("six basic classes (eq. 12 + physical features)")?;
        print_eval(&r.basic, &kind_name)?;
        outln!("all ten classes (eq. 12 + physical features)")?;
        print_eval(&r.all, &kind_name)?;
        outln!(
            "eq. 12 alone (baseline): basic {:.1}%, all {:.1}%; rejected by the default thresholds: {} of {}",
            100.0 * r.baseline_basic.accuracy,
            100.0 * r.baseline_all.accuracy,
            r.rejected,
            r.tested
        )?;
    }
    outln!()?;
    outln!("summary                        basic (eq.12)      all (eq.12)")?;
    for r in &runs {
        outln!(
            "{:<30} {:>5.1}% ({:>5.1}%)  {:>5.1}% ({:>5.1}%)",
            r.name,
            100.0 * r.basic.accuracy,
            100.0 * r.baseline_basic.accuracy,
            100.0 * r.all.accuracy,
            100.0 * r.baseline_all.accuracy
        )?;
    }
    rejection(&a, &b, &weights, &p, args)
}

/// Quantile `q` of `v` (sorted in place).
fn quantile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Rejection on held-out data: the library is both generators' sets of the
/// evaluation seed; the held-out gestures are both generators' sets of seed
/// `seed + 2`, and touches that are not gestures are `style2::draw_still`.
fn rejection(
    a: &[Example],
    b: &[Example],
    w: &PhysicalWeights,
    p: &crowdtouch::gesture::knn::SearchParams,
    args: &CrossArgs,
) -> Result<()> {
    let train: Vec<Example> = a.iter().chain(b).cloned().collect();
    let (ha, hb) = examples(args.per_class, args.seed + 2)?;
    let held: Vec<Example> = ha.into_iter().chain(hb).collect();
    let valid = outcomes(&train, Some(&held), w, p);
    let mut still_movement: Vec<Movement> = Vec::new();
    let mut still_examples: Vec<Example> = Vec::new();
    for s in 0..(10 * args.per_class) as u64 {
        let d = draw_still(args.seed.wrapping_mul(31).wrapping_add(s));
        let m = Movement::of(&d.tracks);
        still_movement.push(m);
        if let Ok(e) = Example::of(MotionClass::Translate, &d.tracks) {
            still_examples.push(e);
        }
    }
    let still = outcomes(&train, Some(&still_examples), w, p);
    let r = RejectParams::default();
    let rate = |o: &[Outcome]| o.iter().filter(|o| o.rejected(&r)).count();
    let right = |o: &&Outcome| o.voted == Some(o.truth);
    let mut weights: Vec<f64> = valid.iter().filter(right).map(|o| o.weight).collect();
    let mut nearest: Vec<f64> = valid.iter().filter(right).map(|o| o.nearest).collect();
    let mut ratio: Vec<f64> = valid.iter().map(|o| o.movement.ratio()).collect();
    let mut travel: Vec<f64> = valid.iter().map(|o| o.movement.travel_mm).collect();
    let mut still_ratio: Vec<f64> = still_movement.iter().map(|m| m.ratio()).collect();
    let mut still_travel: Vec<f64> = still_movement.iter().map(|m| m.travel_mm).collect();
    outln!()?;
    outln!(
        "rejection (thresholds: vote >= {}, nearest <= {}, travel >= {} x jitter and >= {} mm)",
        r.min_vote,
        r.max_nearest,
        r.min_travel_to_jitter,
        r.min_travel_mm
    )?;
    outln!(
        "held-out gestures (seed {}, both generators, against both sets of seed {}): {} of {} rejected",
        args.seed + 2,
        args.seed,
        rate(&valid),
        valid.len()
    )?;
    outln!(
        "  correctly voted: vote weight 1% / 5% quantile {:.2} / {:.2}; nearest distance 95% / 99% {:.2} / {:.2}",
        quantile(&mut weights, 0.01),
        quantile(&mut weights, 0.05),
        quantile(&mut nearest, 0.95),
        quantile(&mut nearest, 0.99)
    )?;
    outln!(
        "  travel / jitter 1% quantile {:.1}; travel 1% quantile {:.1} mm",
        quantile(&mut ratio, 0.01),
        quantile(&mut travel, 0.01)
    )?;
    let still_rejected = still_movement
        .iter()
        .filter(|m| m.check(&r).is_some())
        .count()
        + still
            .iter()
            .filter(|o| o.movement.check(&r).is_none() && o.rejected(&r))
            .count();
    outln!(
        "touches that are not gestures (resting fingers, touch and release, taps; style2): {} of {} rejected",
        still_rejected,
        still_movement.len()
    )?;
    outln!(
        "  travel / jitter 99% quantile {:.1}; travel 99% quantile {:.1} mm",
        quantile(&mut still_ratio, 0.99),
        quantile(&mut still_travel, 0.99)
    )?;
    Ok(())
}

/// A generator's kind by its name in files and on the command line.
fn kind_name(c: MotionClass) -> String {
    c.as_str().to_string()
}

fn labelled(lib: &Library) -> Vec<Example<ClassLabel>> {
    lib.gestures
        .iter()
        .map(|g| Example {
            class: ClassLabel::of(lib, g.class),
            features: GestureFeatures::of(&g.gesture),
            physical: PhysicalFeatures::of(&g.gesture, g.scale_mm),
            // A library gesture moved (it was drawn as one).
            movement: Movement {
                travel_mm: f64::INFINITY,
                jitter_mm: 0.0,
            },
        })
        .collect()
}

/// `library eval`: leave-one-out over `lib`, or `lib` against a labelled test
/// directory, by the recogniser and by eq. 12 alone.
pub(super) fn eval(cfg: &Config, lib: &Library, test: Option<&Path>) -> Result<()> {
    let params = search_params(cfg);
    let train = labelled(lib);
    let test = match test {
        None => {
            outln!(
                "leave-one-out over {} library gestures (K = {}, weighted voting)",
                train.len(),
                params.k
            )?;
            None
        }
        Some(dir) => {
            let test = read_test_dir(dir, cfg, lib)?;
            outln!(
                "{} test gestures from {} against {} library gestures (K = {})",
                test.len(),
                dir.display(),
                train.len(),
                params.k
            )?;
            Some(test)
        }
    };
    let name = |c: ClassLabel| lib.class_name(c.id).to_string();
    let w = PhysicalWeights::default();
    let basic = |s: &[Example<ClassLabel>]| -> Vec<Example<ClassLabel>> {
        s.iter().filter(|e| e.class.is_basic()).cloned().collect()
    };
    let (train_b, test_b) = (basic(&train), test.as_deref().map(basic));
    let all = outcomes(&train, test.as_deref(), &w, &params);
    let rejected = all
        .iter()
        .filter(|o| o.rejected(&RejectParams::default()))
        .count();
    outln!()?;
    outln!("recogniser: eq. 12 + physical features")?;
    outln!("six basic classes")?;
    if train_b.is_empty() {
        outln!("(none: the library has no translate, twist, contract, expand, join or split)")?;
    } else {
        print_eval(
            &evaluate(&outcomes(&train_b, test_b.as_deref(), &w, &params)),
            &name,
        )?;
    }
    outln!()?;
    outln!("{}", all_classes(lib.classes.len()))?;
    print_eval(&evaluate(&all), &name)?;
    outln!(
        "rejected by the default thresholds: {rejected} of {}",
        all.len()
    )?;
    // The paper's recogniser, eq. 12 alone, with its feature ablation.
    let plain = |s: &[Example<ClassLabel>]| -> Vec<(ClassLabel, GestureFeatures)> {
        s.iter().map(|e| (e.class, e.features.clone())).collect()
    };
    let report = match &test {
        None => leave_one_out_report(&plain(&train), &params),
        Some(t) => train_test_report(&plain(&train), &plain(t), &params),
    };
    outln!()?;
    outln!(
        "eq. 12 alone (the paper's baseline): basic {:.1}%, all {:.1}%",
        100.0 * report.basic.accuracy,
        100.0 * report.all.accuracy
    )?;
    print_report(&report)
}

/// `library eval --by participant`: leave one participant out. Each participant
/// named in the library in turn: their gestures are classified (recogniser and
/// rejection as the daemon runs them) against every other gesture of the library,
/// theirs left out; gestures of no one named always train (a library collected on
/// top of the generated one keeps those as its cold start). One confusion matrix
/// over all folds, each participant's accuracy, and the rejections.
///
/// # Errors
/// Fewer than two named participants (nothing to leave out against).
pub(super) fn by_participant(cfg: &Config, lib: &Library) -> Result<()> {
    let params = search_params(cfg);
    let all = labelled(lib);
    let mut people: Vec<&str> = lib
        .gestures
        .iter()
        .map(|g| g.participant.as_str())
        .filter(|p| !p.is_empty())
        .collect();
    people.sort_unstable();
    people.dedup();
    if people.len() < 2 {
        bail!(
            "leave-one-participant-out needs gestures of at least two named participants; \
             the library has {} (`library add --participant P` names them)",
            people.len()
        );
    }
    let unnamed = lib
        .gestures
        .iter()
        .filter(|g| g.participant.is_empty())
        .count();
    outln!(
        "leave one participant out: {} participants, {} of their gestures; {unnamed} gestures of no one named always train (K = {})",
        people.len(),
        lib.gestures.len() - unnamed,
        params.k
    )?;
    let w = PhysicalWeights::default();
    let reject = RejectParams::default();
    let mut folds: Vec<Outcome<ClassLabel>> = Vec::new();
    outln!(
        "{:<24} {:>8} {:>9} {:>9}",
        "participant",
        "gestures",
        "accuracy",
        "rejected"
    )?;
    for p in &people {
        let (mut train, mut test) = (Vec::new(), Vec::new());
        for (e, g) in all.iter().zip(&lib.gestures) {
            if g.participant == *p {
                test.push(e.clone());
            } else {
                train.push(e.clone());
            }
        }
        let outs = outcomes(&train, Some(&test), &w, &params);
        let right = outs.iter().filter(|o| o.voted == Some(o.truth)).count();
        let rejected = outs.iter().filter(|o| o.rejected(&reject)).count();
        outln!(
            "{p:<24} {:>8} {:>8.1}% {:>9}",
            outs.len(),
            100.0 * right as f64 / outs.len().max(1) as f64,
            rejected
        )?;
        folds.extend(outs);
    }
    let name = |c: ClassLabel| lib.class_name(c.id).to_string();
    outln!()?;
    outln!(
        "{}, every participant's gestures",
        all_classes(lib.classes.len())
    )?;
    print_eval(&evaluate(&folds), &name)?;
    let basic: Vec<Outcome<ClassLabel>> = folds
        .iter()
        .filter(|o| o.truth.is_basic())
        .copied()
        .collect();
    if !basic.is_empty() {
        outln!()?;
        outln!("the basic classes among them (the paper's 89.6 % is on the six, by participant)")?;
        print_eval(&evaluate(&basic), &name)?;
    }
    outln!(
        "rejected by the default thresholds: {} of {}",
        folds.iter().filter(|o| o.rejected(&reject)).count(),
        folds.len()
    )?;
    Ok(())
}

/// "all ten classes", "all 12 classes".
fn all_classes(n: usize) -> String {
    const WORDS: [&str; 11] = [
        "no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
    ];
    match WORDS.get(n) {
        Some(w) => format!("all {w} classes"),
        None => format!("all {n} classes"),
    }
}

/// `DIR/<class>/*`: every gesture in every recording, labelled by its folder (a
/// class of `lib`).
fn read_test_dir(dir: &Path, cfg: &Config, lib: &Library) -> Result<Vec<Example<ClassLabel>>> {
    let mut out = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot read test directory", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    entries.sort();
    for sub in entries {
        let name = sub.file_name().and_then(|n| n.to_str()).unwrap_or("");
        let class = ClassLabel::of(
            lib,
            class_of(lib, name)
                .with_context(|| format!("{}: folder is not a class", sub.display()))?,
        );
        let mut files: Vec<PathBuf> = std::fs::read_dir(&sub)?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file())
            .collect();
        files.sort();
        for f in files {
            for g in gestures_in(&f, cfg)? {
                match g.tracks {
                    Ok(t) => match Example::of(class, &t) {
                        Ok(e) => out.push(e),
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

fn print_report<C: Label>(r: &Report<C>) -> Result<()> {
    outln!("with one of eq. 12's features removed (others renormalised; eq. 12 alone):")?;
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

/// The short column name of a class in the confusion matrix: the built-in
/// classes' abbreviations, else the first five characters of its name.
fn short(name: &str) -> String {
    match name.parse::<MotionClass>() {
        Ok(MotionClass::Translate) => "trans".into(),
        Ok(MotionClass::Twist) => "twist".into(),
        Ok(MotionClass::Contract) => "contr".into(),
        Ok(MotionClass::Expand) => "expan".into(),
        Ok(MotionClass::Join) => "join".into(),
        Ok(MotionClass::Split) => "split".into(),
        Ok(MotionClass::SplitThenTranslate) => "sp+tr".into(),
        Ok(MotionClass::TranslateThenJoin) => "tr+jo".into(),
        Ok(MotionClass::TwistWhileExpanding) => "tw+ex".into(),
        Ok(MotionClass::TwistWhileContracting) => "tw+co".into(),
        Err(_) => name.chars().take(5).collect(),
    }
}

/// Prints a confusion matrix with per-class and overall accuracy, each class
/// named by `name`.
pub(super) fn print_eval<C: Label>(e: &Evaluation<C>, name: &impl Fn(C) -> String) -> Result<()> {
    let classes = &e.confusion.classes;
    let width = classes
        .iter()
        .map(|&c| name(c).len())
        .max()
        .unwrap_or(0)
        .max(24);
    let mut head = format!("{:<width$}", "true \\ recognised");
    for &c in classes {
        head.push_str(&format!(" {:>5}", short(&name(c))));
    }
    head.push_str("  accuracy");
    outln!("{head}")?;
    for (i, &c) in classes.iter().enumerate() {
        let mut row = format!("{:<width$}", name(c));
        for n in &e.confusion.counts[i] {
            row.push_str(&format!(" {n:>5}"));
        }
        if let Some(pc) = e.per_class.iter().find(|p| p.class == c) {
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
