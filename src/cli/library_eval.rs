//! `crowdtouch library eval --cross-style`: recognition trained on one gesture
//! generator and tested on the other, both ways, plus leave-one-out on each
//! (issue 28), for the recogniser (eq. 12 plus the physical features) beside eq. 12
//! alone; `--fit` chooses the physical weights across styles; and how the rejection
//! thresholds fare on held-out gestures and on touches that are not gestures.

use super::library::print_eval;
use super::output::outln;
use anyhow::Result;
use crowdtouch::config::Config;
use crowdtouch::engine::search_params;
use crowdtouch::gesture::eval::{cross_style, fit_weights, outcomes, Example, Outcome};
use crowdtouch::gesture::generator::{labelled_set, Generator};
use crowdtouch::gesture::library::MotionClass;
use crowdtouch::gesture::physical::{PhysicalWeights, PHYSICAL_NAMES};
use crowdtouch::gesture::reject::{Movement, RejectParams};
use crowdtouch::gesture::style2::draw_still;
use crowdtouch::gesture::synth::StyleRanges;

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
            "fitted: score {score:.4} (worse basic cross-style accuracy + 0.1 x worse all-class)"
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
