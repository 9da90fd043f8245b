//! What `transform` and `transform compare` share: the virtual clock, the common
//! arguments, one recorded run (`run`), and the output helpers.

use clap::{Args, ValueEnum};
use crowdtouch::crowd::transform::{
    Measures, MoveParams, RunSummary, SubgroupAttraction, TransformPlan, TransformRun,
};
use crowdtouch::geom::Vec2;
use hdrhistogram::Histogram;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::time::Instant;

/// The virtual clock's step (s): the daemon's tick at 60 Hz.
pub const DT_S: f64 = 1.0 / 60.0;
/// Seed of a run when `--seed` is not given.
pub const DEFAULT_SEED: u64 = 16;
/// Longest step recorded in the step-time histogram (µs).
pub const MAX_STEP_US: u64 = 60_000_000;

/// What every transform run needs.
#[derive(Args, Debug, Clone)]
pub struct Common {
    /// Source formation: a name from the config's library (`crowdtouch
    /// formations` lists them) or a file (a polygon `.ron` FormationDef, or a PNG
    /// or PGM image whose dark pixels are the shape).
    #[arg(long, required = true)]
    pub from: Option<String>,
    /// Target formation, as --from.
    #[arg(long, required = true)]
    pub to: Option<String>,
    /// Agents (default: the config's crowd.agents), 1 to 10000.
    #[arg(long)]
    pub agents: Option<u32>,
    /// Config (default: the embedded default).
    #[arg(long, short)]
    pub config: Option<PathBuf>,
    /// One JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write a picture (SVG) to this file.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Seed of the sampling and the run (same seed, same result but timings).
    #[arg(long, default_value_t = DEFAULT_SEED)]
    pub seed: u64,
}

/// `--subgroup-attraction`: eq. 21 three ways, or the subgroup as a whole on
/// its Delaunay graph (`crowd/transform/social_groups.rs`).
#[derive(ValueEnum, Copy, Clone, Debug, PartialEq, Eq)]
pub enum AttractionArg {
    /// Ours: a bounded pull towards the agent's place in its group.
    Place,
    /// Eq. 21 as printed: A' e^d towards every other member (d in metres).
    AsPrinted,
    /// A' e^(−d/B') towards every other member (a guess at a misprint).
    Decaying,
    /// Damped springs on the Delaunay edges of each group (section 3, step 3).
    Dt,
}

impl AttractionArg {
    /// The model's variant.
    pub fn attraction(self) -> SubgroupAttraction {
        match self {
            AttractionArg::Place => SubgroupAttraction::Place,
            AttractionArg::AsPrinted => SubgroupAttraction::AsPrinted,
            AttractionArg::Decaying => SubgroupAttraction::Decaying,
            AttractionArg::Dt => SubgroupAttraction::DelaunayGraph,
        }
    }
}

/// `--cost`.
#[derive(ValueEnum, Copy, Clone, Debug, PartialEq, Eq)]
pub enum CostArg {
    /// ΔE of eq. 3 with the config's formations.lambda.
    LeastEffort,
    /// Euclidean distance.
    Euclidean,
    /// Manhattan distance.
    Manhattan,
}

/// What one run recorded.
pub struct Recorded {
    /// The run's own summary.
    pub summary: RunSummary,
    /// Wall-clock time of each `TransformRun::step` (µs).
    pub step_us: Histogram<u64>,
    /// Each step's simulated time (s), measures and fraction arrived.
    pub series: Vec<(f64, Measures, f64)>,
    /// Every agent's positions, every [`PATH_EVERY_STEPS`] steps and at the end
    /// (when asked for).
    pub paths: Option<Vec<Vec<Vec2>>>,
    /// The agents that had not settled at their targets at the end: index,
    /// distance to the target (m) and speed (m/s).
    pub short: Vec<(usize, f64, f64)>,
}

/// Agents short of their targets listed in a report.
pub const SHORT_LISTED: usize = 10;

/// Steps between two recorded path points (0.2 s).
pub const PATH_EVERY_STEPS: u64 = 12;

impl Recorded {
    /// The step time at `q` (µs).
    pub fn step_us_at(&self, q: f64) -> u64 {
        self.step_us.value_at_quantile(q)
    }

    /// Arrival time (s): when every agent had arrived; `None` when the run timed
    /// out or ended with the crowd at rest short of its targets.
    pub fn arrival_s(&self) -> Option<f64> {
        let s = &self.summary;
        (!s.timed_out && s.rest_s.is_none()).then_some(s.simulated_s)
    }
}

/// Runs `plan` with `params` from its sources at rest, steps of [`DT_S`], until
/// every agent settled or the timeout.
pub fn run(plan: &TransformPlan, params: &MoveParams, seed: u64, keep_paths: bool) -> Recorded {
    let mut pos = plan.sources_m.clone();
    let mut vel = vec![Vec2::zeros(); pos.len()];
    let mut r = TransformRun::new(plan, params, run_seed(seed));
    let mut step_us = match Histogram::new_with_bounds(1, MAX_STEP_US, 3) {
        Ok(h) => h,
        Err(e) => unreachable!("constant histogram bounds: {e}"),
    };
    let mut series = Vec::new();
    let mut paths = keep_paths.then(|| pos.iter().map(|&p| vec![p]).collect::<Vec<_>>());
    // The run ends itself at its timeout; this bounds a run that would not.
    let max_steps = (params.timeout_s / DT_S).ceil() as u64 + 2;
    let mut steps = 0u64;
    while !r.done() && steps < max_steps {
        let t0 = Instant::now();
        let report = r.step(&mut pos, &mut vel, DT_S, None);
        step_us.saturating_record(t0.elapsed().as_micros().max(1) as u64);
        steps += 1;
        series.push((r.elapsed_s(), report.measures, report.arrived_fraction));
        if let Some(p) = &mut paths {
            if steps % PATH_EVERY_STEPS == 0 {
                for (path, &x) in p.iter_mut().zip(&pos) {
                    path.push(x);
                }
            }
        }
    }
    if let Some(p) = &mut paths {
        if steps % PATH_EVERY_STEPS != 0 {
            for (path, &x) in p.iter_mut().zip(&pos) {
                path.push(x);
            }
        }
    }
    // Short: not within arrive_m of the target, or (with settling) not settled.
    let short = (0..pos.len())
        .filter(|&i| {
            (pos[i] - r.targets()[i]).norm() > params.arrive_m || (params.settling && !r.settled(i))
        })
        .map(|i| (i, (pos[i] - r.targets()[i]).norm(), vel[i].norm()))
        .collect();
    Recorded {
        summary: r.summary(),
        step_us,
        series,
        paths,
        short,
    }
}

/// `on` or `off`.
pub fn on_off(b: bool) -> &'static str {
    if b {
        "on"
    } else {
        "off"
    }
}

/// `x` as JSON, `null` when not finite.
pub fn finite_or_null(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// Seed of the run's fluctuation and desired speeds.
pub fn run_seed(seed: u64) -> u64 {
    seed ^ 0x5eed_7a45
}
