//! `crowdtouch transform`: one formation transform (formation-transform, Xu et al.
//! 2015) run headless on a virtual clock, set up as the daemon sets one up
//! (`engine/transform.rs`), and measured: arrival, the closest two agents came,
//! travel, the paper's three measures of section 5.1 averaged over the run (`I_d`
//! eq. 17, `σ_min_dis` eq. 24, `σ_curr_eft` eq. 26) and the wall-clock time of
//! each `TransformRun::step`. `transform compare` (`transform_compare.rs`) runs
//! the paper's comparisons on the same start; `transform_svg.rs` draws both.
//!
//! ```text
//!  --from A ──► A.sample(place, N)  = sources s_i        (section 3.1)
//!  --to   B ──► TransformRequest::prepare: B sampled,   (sections 3.1, 3.2, 3.4)
//!               paired (eq. 3 or a distance), subgroups
//!          ──► TransformRun::step at 1/60 s until done   (sections 3.3, 3.5)
//! ```

use super::output::outln;
use super::transform_svg;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use crowdtouch::config::{Config, MAX_AGENTS};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::formation::{
    hex_fit, BitmapDef, Formation, FormationDef, FormationLibrary, Placement, SampleParams, START,
};
use crowdtouch::crowd::transform::{
    ApParams, Measures, MoveParams, Mover, PairCost, Preference, RunSummary, TransformPlan,
    TransformRequest, TransformRun,
};
use crowdtouch::geom::Vec2;
use crowdtouch::located::{format_issues, locate_field, parse_strict, Issue};
use hdrhistogram::Histogram;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The virtual clock's step (s): the daemon's tick at 60 Hz.
pub const DT_S: f64 = 1.0 / 60.0;
/// Seed of a run when `--seed` is not given.
pub const DEFAULT_SEED: u64 = 16;
/// Share of the area the agents' hexagonal cells may fill before the area is
/// scaled up (a crowd packed tighter has no room to pass through itself).
pub const PACKING_SLACK: f64 = 0.6;
/// Targets are sampled at least this many agent radii apart (as the daemon's
/// `SAMPLE_SPACING_RADII`).
pub const SPACING_RADII: f64 = 2.0;
/// Relaxation iterations of the sampling (as the daemon's `SAMPLE_RELAX_ITERATIONS`).
pub const RELAX_ITERATIONS: u32 = 30;
/// A bare image file given as a formation: its pixels with every channel at most
/// this are the shape (eq. 1's `c_max`, `c_min` = black), as the shipped heart.
pub const BITMAP_DARK_MAX: u8 = 127;
/// Largest formation file read (bytes), as the config's bitmap cap.
pub const MAX_FORMATION_FILE_BYTES: u64 = 16 << 20;
/// Longest step recorded in the step-time histogram (µs).
const MAX_STEP_US: u64 = 60_000_000;

/// `transform`: run one formation transform, or `transform compare`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct TransformCmd {
    /// `compare`: the paper's comparisons.
    #[command(subcommand)]
    pub sub: Option<TransformSub>,
    /// The single run's arguments.
    #[command(flatten)]
    pub run: TransformArgs,
}

/// Subcommands of `transform`.
#[derive(Subcommand, Debug)]
pub enum TransformSub {
    /// The paper's comparisons on one start and one set of targets: least-effort,
    /// Euclidean and Manhattan pairing (section 5.2, Table 2), without the
    /// mutual-information feedback (section 5.3), and ORCA on the least-effort
    /// pairing (section 5.4); a table of arrival time and the three measures,
    /// `--svg` plots the measures over time.
    Compare(Common),
}

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
    /// Agents (default: the config's crowd.agents), 1 to 5000.
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

/// `transform --from A --to B`.
#[derive(Args, Debug)]
pub struct TransformArgs {
    /// Source, target, crowd and output.
    #[command(flatten)]
    pub common: Common,
    /// Pairing cost (default: the config's formations.cost).
    #[arg(long, value_enum)]
    pub cost: Option<CostArg>,
    /// Without the mutual-information feedback (eqs. 18–19).
    #[arg(long)]
    pub no_feedback: bool,
    /// Without subgroups (no clustering, no forces of eqs. 21–22).
    #[arg(long)]
    pub no_subgroups: bool,
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

/// Runs `transform` or `transform compare`.
pub fn transform(c: TransformCmd) -> Result<()> {
    match c.sub {
        Some(TransformSub::Compare(common)) => super::transform_compare::compare(&common),
        None => single(&c.run),
    }
}

/// The config's transform settings: what `engine/params.rs` (`pair_cost`,
/// `ap_params`, `move_params`) builds for the daemon, rebuilt here because the
/// engine does not export them.
#[derive(Clone, Debug)]
pub struct Settings {
    /// `formations.cost` with `formations.lambda`.
    pub cost: PairCost,
    /// `formations.subgroups`; `None` when off.
    pub ap: Option<ApParams>,
    /// `formations.transform` at the crowd's radius.
    pub moves: MoveParams,
}

impl Settings {
    /// The settings of `cfg` for agents of radius `radius_m`.
    pub fn of(cfg: &Config, radius_m: f64) -> Settings {
        use crowdtouch::config::TransformCost;
        let f = &cfg.formations;
        let cost = match f.cost {
            TransformCost::LeastEffort => PairCost::LeastEffort { lambda: f.lambda },
            TransformCost::Euclidean => PairCost::Euclidean,
            TransformCost::Manhattan => PairCost::Manhattan,
        };
        let s = &f.subgroups;
        let ap = s.enabled.then_some(ApParams {
            damping: s.damping,
            max_iterations: s.max_iterations,
            convergence_iterations: s.convergence_iterations,
            preference: s.preference.map_or(Preference::Median, Preference::Value),
            ring: s.ring,
            dense_up_to: s.dense_up_to,
        });
        let t = &f.transform;
        let moves = MoveParams {
            mover: Mover::SocialForce,
            radius_m,
            desired_speed_m_s: t.desired_speed_m_s,
            feedback: t.feedback,
            subgroup_forces: t.subgroup_forces,
            arrive_m: t.arrive_m,
            timeout_s: t.timeout_s,
            desired_speed_spread_m_s: t.desired_speed_spread_m_s,
            max_speed_m_s: t.max_speed_m_s,
            max_accel_m_s2: t.max_accel_m_s2,
            tau_s: t.tau_s,
            arrival_decel_m_s2: t.arrival_decel_m_s2,
            fade_m: t.fade_m,
            repulsion_a_m_s2: t.repulsion_a_m_s2,
            repulsion_b_m: t.repulsion_b_m,
            obstacle_a_m_s2: t.obstacle_a_m_s2,
            subgroup_a_m_s2: t.subgroup_a_m_s2,
            subgroup_b_m: t.subgroup_b_m,
            interaction_range_m: t.interaction_range_m,
            fluctuation_m_s2: t.fluctuation_m_s2,
            bin_m: t.bin_m,
            sectors: t.sectors,
            settle_speed_m_s: t.settle_speed_m_s,
            ..MoveParams::default()
        };
        Settings { cost, ap, moves }
    }
}

/// A transform's start: the config, both shapes, where they are laid out and the
/// agents sampled in the source.
pub struct Setup {
    /// The config.
    pub cfg: Config,
    /// As given on the command line.
    pub from_label: String,
    /// As given on the command line.
    pub to_label: String,
    /// The target shape.
    pub to: Formation,
    /// Agents.
    pub agents: usize,
    /// Agent radius (m).
    pub radius_m: f64,
    /// Where both shapes are laid out.
    pub place: Placement,
    /// Why the area is not `crowd.formation`'s, when it is not.
    pub area_note: Option<String>,
    /// How targets are sampled.
    pub sample: SampleParams,
    /// `s_i`: the agents, sampled in the source shape (m).
    pub sources: Vec<Vec2>,
    /// The seed given.
    pub seed: u64,
    /// The config's transform settings.
    pub settings: Settings,
}

impl Setup {
    /// Loads the config, resolves both formations and samples the agents in the
    /// source.
    ///
    /// # Errors
    /// An unreadable or invalid config, an unknown formation name (with the known
    /// ones), a formation file that cannot be read or is not valid (named), an
    /// agent count out of `1..=5000`, more agents than fit in the source (the
    /// sampling's message).
    pub fn new(c: &Common) -> Result<Setup> {
        let cfg = match &c.config {
            Some(p) => Config::load(p)?,
            None => Config::embedded_default(),
        };
        let agents = c.agents.unwrap_or(cfg.crowd.agents);
        if !(1..=MAX_AGENTS).contains(&agents) {
            bail!("--agents must be 1 to {MAX_AGENTS}, got {agents}");
        }
        let agents = agents as usize;
        let (from_label, to_label) = (
            c.from.clone().unwrap_or_default(),
            c.to.clone().unwrap_or_default(),
        );
        let from = resolve(&cfg, &from_label).context("--from")?;
        let to = resolve(&cfg, &to_label).context("--to")?;
        let radius_m = cfg.crowd.agent_radius_m;
        let spacing_m = SPACING_RADII * radius_m;
        let rect = cfg.crowd.formation;
        let rect_area = rect.width() * rect.height();
        // Each agent takes a hexagonal cell of √3/2 · spacing² at the closest
        // packing; at most PACKING_SLACK of the area is filled.
        let needed = agents as f64 * 0.5 * 3f64.sqrt() * spacing_m * spacing_m / PACKING_SLACK;
        let (area_m2, area_note) = if needed > rect_area {
            (
                needed,
                Some(format!(
                    "{needed:.1} m², crowd.formation's {rect_area:.1} m² scaled up so that {agents} agents {spacing_m:.2} m apart fill at most {:.0} % of it (hex fit {})",
                    100.0 * PACKING_SLACK,
                    hex_fit(needed, spacing_m)
                )),
            )
        } else {
            (rect_area, None)
        };
        let place = Placement {
            centre_m: rect.center(),
            heading: Vec2::new(1.0, 0.0),
            area_m2,
        };
        let sample = SampleParams {
            min_spacing_m: spacing_m,
            relax_iterations: RELAX_ITERATIONS,
        };
        let sources = from
            .sample(&place, agents, &sample, source_seed(c.seed), &|| false)
            .map_err(|e| anyhow!("--from {from_label}: {e}"))?
            .ok_or_else(|| anyhow!("sampling the source was cancelled"))?;
        let settings = Settings::of(&cfg, radius_m);
        Ok(Setup {
            cfg,
            from_label,
            to_label,
            to,
            agents,
            radius_m,
            place,
            area_note,
            sample,
            sources,
            seed: c.seed,
            settings,
        })
    }

    /// The request the daemon's formation thread would prepare, for `cost` and
    /// subgroups `ap`.
    pub fn request(&self, cost: PairCost, ap: Option<ApParams>) -> TransformRequest {
        TransformRequest {
            name: self.to.name().to_string(),
            epoch: 0,
            formation: self.to.clone(),
            placement: self.place,
            agents: self.sources.clone(),
            cost,
            subgroups: ap,
            sample: self.sample,
            seed: target_seed(self.seed),
        }
    }

    /// Samples the target shape (as [`TransformRequest::prepare`] does with the
    /// same seed), so several pairings can share the targets.
    ///
    /// # Errors
    /// More agents than fit in the target.
    pub fn targets(&self) -> Result<Vec<Vec2>> {
        self.to
            .sample(
                &self.place,
                self.agents,
                &self.sample,
                target_seed(self.seed),
                &|| false,
            )
            .map_err(|e| anyhow!("--to {}: {e}", self.to_label))?
            .ok_or_else(|| anyhow!("sampling the target was cancelled"))
    }
}

/// Seed of the source sampling.
fn source_seed(seed: u64) -> u64 {
    seed ^ 0x5a3c_0f00_d15e_a5e5
}

/// Seed of the target sampling.
fn target_seed(seed: u64) -> u64 {
    seed ^ 0x7a5f_0e11
}

/// Seed of the run's fluctuation and desired speeds.
pub fn run_seed(seed: u64) -> u64 {
    seed ^ 0x5eed_7a45
}

/// The formation `arg` names: a library name (`start`: the `crowd.formation`
/// rectangle) or a file.
///
/// # Errors
/// An unknown name (listing the known ones), a file that cannot be read or is not
/// a valid formation.
pub fn resolve(cfg: &Config, arg: &str) -> Result<Formation> {
    let lib: &FormationLibrary = cfg.formation_library();
    if arg == START {
        let r = cfg.crowd.formation;
        let def = FormationDef {
            name: "start rectangle".to_string(),
            outline: vec![
                (r.min[0], r.min[1]),
                (r.max[0], r.min[1]),
                (r.max[0], r.max[1]),
                (r.min[0], r.max[1]),
            ],
            ..FormationDef::default()
        };
        return Formation::new(&def).map_err(|e| anyhow!("crowd.formation: {e}"));
    }
    if let Some(f) = lib.get(arg) {
        return Ok(f.clone());
    }
    let path = Path::new(arg);
    let looks_like_file = path.exists()
        || arg.contains('/')
        || matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("ron" | "png" | "pgm")
        );
    if !looks_like_file {
        bail!(
            "unknown formation `{arg}`: known formations are {}; or give a file (a polygon .ron, a .png or .pgm image)",
            lib.names_list()
        );
    }
    load_file(path)
}

/// A formation from a file: a PNG or PGM image (its dark pixels, scaled to the
/// crowd's area) or a polygon FormationDef in RON (a bitmap it names is read
/// relative to it).
///
/// # Errors
/// The file named, with what is wrong (and where, for RON).
pub fn load_file(path: &Path) -> Result<Formation> {
    let shown = path.display();
    let meta = std::fs::metadata(path).with_context(|| format!("{shown}: cannot read"))?;
    if meta.len() > MAX_FORMATION_FILE_BYTES {
        bail!(
            "{shown}: {} bytes, more than the {MAX_FORMATION_FILE_BYTES} byte limit",
            meta.len()
        );
    }
    let bytes = std::fs::read(path).with_context(|| format!("{shown}: cannot read"))?;
    if bytes.starts_with(b"\x89PNG") || bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("bitmap")
            .to_string();
        let def = BitmapDef {
            path: shown.to_string(),
            c_min: (0, 0, 0),
            c_max: (BITMAP_DARK_MAX, BITMAP_DARK_MAX, BITMAP_DARK_MAX),
            size_m: None,
        };
        return Formation::from_bitmap(&name, &bytes, &def).map_err(|e| anyhow!("{e}"));
    }
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(_) => bail!("{shown}: neither a PNG or PGM image nor a RON formation (not UTF-8 text)"),
    };
    let def: FormationDef =
        parse_strict(&text).map_err(|issue| anyhow!("{}", format_issues(path, &[issue])))?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let read = move |p: &str| -> Result<Vec<u8>, String> {
        let file = base.join(p);
        let meta =
            std::fs::metadata(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
        if meta.len() > MAX_FORMATION_FILE_BYTES {
            return Err(format!(
                "{} is {} bytes, more than the {MAX_FORMATION_FILE_BYTES} byte limit",
                file.display(),
                meta.len()
            ));
        }
        std::fs::read(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))
    };
    Formation::from_def(&def, &read).map_err(|e| {
        let field = e.field();
        let (line, column) = locate_field(&text, field).unwrap_or((0, 0));
        let issue = Issue {
            field: field.to_string(),
            line,
            column,
            message: e.to_string(),
        };
        anyhow!("{}", format_issues(path, &[issue]))
    })
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
}

/// Steps between two recorded path points (0.2 s).
pub const PATH_EVERY_STEPS: u64 = 12;

impl Recorded {
    /// The step time at `q` (µs).
    pub fn step_us_at(&self, q: f64) -> u64 {
        self.step_us.value_at_quantile(q)
    }

    /// Arrival time (s), `None` when the run timed out.
    pub fn arrival_s(&self) -> Option<f64> {
        (!self.summary.timed_out).then_some(self.summary.simulated_s)
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
    Recorded {
        summary: r.summary(),
        step_us,
        series,
        paths,
    }
}

/// `transform --from A --to B`.
fn single(a: &TransformArgs) -> Result<()> {
    let c = &a.common;
    let setup = Setup::new(c)?;
    let s = &setup.settings;
    let cost = match a.cost {
        None => s.cost,
        Some(CostArg::LeastEffort) => PairCost::LeastEffort {
            lambda: setup.cfg.formations.lambda,
        },
        Some(CostArg::Euclidean) => PairCost::Euclidean,
        Some(CostArg::Manhattan) => PairCost::Manhattan,
    };
    let ap = if a.no_subgroups { None } else { s.ap };
    let mut params = s.moves.clone();
    params.feedback = params.feedback && !a.no_feedback;
    params.subgroup_forces = params.subgroup_forces && !a.no_subgroups;
    let t0 = Instant::now();
    let prepared = setup
        .request(cost, ap)
        .prepare(Cancel::default())
        .ok_or_else(|| anyhow!("preparing the transform was cancelled"))?;
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let plan = prepared
        .plan
        .map_err(|e| anyhow!("--to {}: {e}", setup.to_label))?;
    let rec = run(&plan, &params, setup.seed, c.svg.is_some());
    if let Some(path) = &c.svg {
        let title = format!(
            "{} → {}: {} agents, {} cost, feedback {}, {} subgroups",
            setup.from_label,
            setup.to_label,
            setup.agents,
            cost.name(),
            on_off(params.feedback),
            plan.subgroups.count()
        );
        let text = transform_svg::run_picture(&plan, &rec, setup.radius_m, &title);
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    let sm = &rec.summary;
    if c.json {
        let v = json!({
            "from": setup.from_label,
            "to": setup.to_label,
            "cost": cost.name(),
            "feedback": params.feedback,
            "subgroups": plan.subgroups.count(),
            "seed": setup.seed,
            "agents": sm.agents,
            "radius_m": setup.radius_m,
            "area_m2": setup.place.area_m2,
            "steps": sm.steps,
            "simulated_s": sm.simulated_s,
            "timed_out": sm.timed_out,
            "arrived_fraction": sm.arrived_fraction,
            "min_distance_m": finite_or_null(sm.min_distance_m),
            "overlapping_pairs": sm.overlapping_pairs,
            "mean_travel_m": sm.mean_travel_m,
            "max_travel_m": sm.max_travel_m,
            "I_d": sm.mean.i_d,
            "sigma_min_dis": sm.mean.sigma_min_dis_m,
            "sigma_curr_eft": sm.mean.sigma_curr_eft_m,
            "step_us_p50": rec.step_us_at(0.5),
            "step_us_p99": rec.step_us_at(0.99),
            "prepare_ms": prepare_ms,
        });
        outln!("{v}")?;
    } else {
        let cost_text = match cost {
            PairCost::LeastEffort { lambda } => format!("least-effort (λ {lambda})"),
            c => c.name().to_string(),
        };
        outln!(
            "transform {} → {}: {} agents (radius {} m), {cost_text} pairing, feedback {}, {}",
            setup.from_label,
            setup.to_label,
            sm.agents,
            setup.radius_m,
            on_off(params.feedback),
            if params.subgroup_forces {
                format!("{} subgroups", plan.subgroups.count())
            } else {
                "no subgroups".to_string()
            }
        )?;
        if let Some(note) = &setup.area_note {
            outln!("  area                {note}")?;
        }
        outln!("  prepare             {prepare_ms:.1} ms (sampling, pairing, subgroups)")?;
        outln!(
            "  steps               {} of 1/60 s = {:.2} s simulated{}",
            sm.steps,
            sm.simulated_s,
            if sm.timed_out { " (timed out)" } else { "" }
        )?;
        outln!("  arrived             {:.1} %", 100.0 * sm.arrived_fraction)?;
        outln!(
            "  closest two agents  {:.4} m at any time (two radii {:.2} m); {} pairs overlapped",
            sm.min_distance_m,
            2.0 * setup.radius_m,
            sm.overlapping_pairs
        )?;
        outln!(
            "  travel              mean {:.2} m, max {:.2} m",
            sm.mean_travel_m,
            sm.max_travel_m
        )?;
        outln!("  measures averaged over the run (formation-transform section 5.1):")?;
        outln!("    I_d (eq. 17)        {:.4} bits", sm.mean.i_d)?;
        outln!("    σ_min_dis (eq. 24)  {:.4} m", sm.mean.sigma_min_dis_m)?;
        outln!("    σ_curr_eft (eq. 26) {:.4} m", sm.mean.sigma_curr_eft_m)?;
        outln!(
            "  step time           p50 {} µs, p99 {} µs",
            rec.step_us_at(0.5),
            rec.step_us_at(0.99)
        )?;
        if let Some(path) = &c.svg {
            outln!("wrote {}", path.display())?;
        }
    }
    Ok(())
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
