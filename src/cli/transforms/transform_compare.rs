//! `crowdtouch transform compare`: the comparisons of formation-transform section
//! 5, on `--seeds` starts (each seed samples the agents in the source, the targets
//! and the run's own draws):
//!
//! | variant | pairing | mover | feedback | paper |
//! |---|---|---|---|---|
//! | `least-effort` | ΔE, eq. 3, the config's λ | social forces | on | 5.2, Table 2 |
//! | `travel-only` | ΔE at λ = 1: squared distance | social forces | on | 5.2 (λ's end) |
//! | `euclidean` | Euclidean | social forces | on | 5.2, Table 2 |
//! | `manhattan` | Manhattan | social forces | on | 5.2, Table 2 |
//! | `no-feedback` | ΔE, eq. 3 | social forces | off | 5.3 |
//! | `orca` | ΔE, eq. 3 | ORCA as RVO2 runs it | off | 5.4, Table 3 |
//! | `rvo` | ΔE, eq. 3 | RVO as the RVO library ran it | off | 5.4, Table 3 |
//! | `steering` | ΔE, eq. 3 | OpenSteer-style steering | off | 5.4, Table 3 |
//!
//! The social-force rows use the config's movement model, with the project's
//! additions (fades, settling, positional contacts, exchanges of targets) unless
//! `--preset paper` turns them off; the baseline rows never have them
//! ([`MoveParams::rvo2_orca`], [`MoveParams::rvo`], [`MoveParams::steering`]).
//! The baselines, what they are and are not, are in docs/transforms.md
//! ("Baselines"). Each row gives, over the seeds, the mean and the
//! 95 % confidence interval of the arrival time, of the three measures of section
//! 5.1 averaged over a *common window* (the first seconds every run of every row
//! lasted, or `--window`) and over each run's own length (normalised progress), the
//! heading-change rate (section 5.3's fluctuation) over the same window, the
//! exchanges of targets per run and the overlaps. `--scenario` runs every row in
//! one of the paper's section 4 scenarios (`transform_scenario.rs`). `--svg`
//! plots the first seed's measures over time.

use super::shared::{finite_or_null, Common};
use super::transform_scenario::{facts_json, facts_text, Scenario, Stage};
use super::transform_setup::Setup;
use super::transform_svg;
use super::variant::Variant;
use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::transform::{
    interval, locality, pairing_terms, window_mean, Interval, Measures, MoveParams, Mover,
    PairCost, SubgroupAttraction, TransformPlan, REST_HOLD_S, REST_SPEED_M_S,
};
use serde_json::{json, Value};
use std::time::Instant;

/// `transform compare`.
#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// Source, target, crowd, output; `--seed` is the first seed.
    #[command(flatten)]
    pub common: Common,
    /// Runs per variant, with seeds `--seed`, `--seed` + 1, …: means and 95 %
    /// confidence intervals over them.
    #[arg(long, default_value_t = 1)]
    pub seeds: u32,
    /// `paper`: the social-force rows without the project's additions (no fades,
    /// no settling, no positional contacts, no exchanges of targets).
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// The common window of the measures (s); default: the shortest run of all.
    #[arg(long)]
    pub window: Option<f64>,
    /// End every run after this long if not every agent arrived (s); default:
    /// the config's `formations.transform.timeout_s`.
    #[arg(long)]
    pub timeout: Option<f64>,
    /// Where every row runs: `direct` (the target where the source is), `path`
    /// (the target's anchor walks a path with a turn, Figs. 6–7), `obstacles` (a
    /// disc between source and target, Fig. 8), `crossing` (two mirrored groups
    /// through each other, Fig. 9).
    #[arg(long, value_enum, default_value_t = Scenario::Direct)]
    pub scenario: Scenario,
    /// A sweep of eq. 3's λ instead of the comparison's rows: for each λ given
    /// (comma-separated, each in [0, 1]) a least-effort row on the raw terms
    /// and one on the normalised terms (`least-effort-normalised`), with the
    /// pairing's two terms and how many agents it pairs differently from
    /// λ = 1; `--svg` then plots the measures against λ.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub lambdas: Option<Vec<f64>>,
    /// What holds a subgroup together in every social-force row (default: the
    /// config's `formations.transform.subgroup_attraction`, `place`).
    #[arg(long, value_enum)]
    pub subgroup_attraction: Option<super::shared::AttractionArg>,
    /// The rows to run (comma-separated, in the table's order whatever the order
    /// given): `least-effort`, `travel-only`, `euclidean`, `manhattan`,
    /// `no-feedback`, `orca`, `rvo`, `steering`, or `all`; default the first six
    /// (RVO and steering cost 10 to 60 times a social-force step and mostly run
    /// to the timeout). Not with `--lambdas`.
    #[arg(long, value_delimiter = ',', num_args = 1..)]
    pub variants: Option<Vec<String>>,
}

/// The rows a comparison runs without `--variants`: Table 2's and ORCA.
pub const DEFAULT_VARIANTS: usize = 6;

/// The rows of a comparison, in order (`--variants`; `all` is every one).
pub const VARIANTS: [&str; 8] = [
    "least-effort",
    "travel-only",
    "euclidean",
    "manhattan",
    "no-feedback",
    "orca",
    "rvo",
    "steering",
];

/// `--preset`.
#[derive(ValueEnum, Copy, Clone, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Only what formation-transform has.
    Paper,
}

/// Most seeds of one comparison.
const MAX_SEEDS: u32 = 100;

/// Most values of `--lambdas`.
const MAX_LAMBDAS: usize = 21;

/// The subgroups of one seed's least-effort plan.
struct GroupFacts {
    count: usize,
    converged: bool,
    iterations: u32,
    locality: f64,
}

/// `transform compare`.
pub fn compare(a: &CompareArgs) -> Result<()> {
    if !(1..=MAX_SEEDS).contains(&a.seeds) {
        bail!("--seeds must be 1 to {MAX_SEEDS}, got {}", a.seeds);
    }
    for (name, v) in [("--window", a.window), ("--timeout", a.timeout)] {
        if let Some(w) = v {
            if !(w.is_finite() && w > 0.0) {
                bail!("{name} must be a positive number of seconds, got {w}");
            }
        }
    }
    if let Some(ls) = &a.lambdas {
        if let Some(bad) = ls.iter().find(|l| !(0.0..=1.0).contains(*l)) {
            bail!("--lambdas: each λ must be in [0, 1], got {bad}");
        }
        if ls.is_empty() || ls.len() > MAX_LAMBDAS {
            bail!("--lambdas: 1 to {MAX_LAMBDAS} values, got {}", ls.len());
        }
    }
    if let Some(vs) = &a.variants {
        if a.lambdas.is_some() {
            bail!("--variants and --lambdas do not go together: a λ sweep has its own rows");
        }
        if let Some(bad) = vs
            .iter()
            .find(|v| *v != "all" && !VARIANTS.contains(&v.as_str()))
        {
            bail!(
                "--variants: no row {bad:?}; the rows are {}, or all",
                VARIANTS.join(", ")
            );
        }
        if vs.is_empty() {
            bail!("--variants: name at least one of {}", VARIANTS.join(", "));
        }
    }
    let c = &a.common;
    let mut runs: Vec<Vec<Variant>> = Vec::new();
    let mut groups = Vec::new();
    let mut first: Option<(Setup, Stage)> = None;
    for k in 0..a.seeds {
        let mut ck = c.clone();
        ck.seed = c.seed.wrapping_add(u64::from(k));
        let setup = Setup::new(&ck)?;
        let (row, g, stage) = one_seed(
            &setup,
            a.preset,
            a.timeout,
            a.scenario,
            a.lambdas.as_deref(),
            a.subgroup_attraction.map(|x| x.attraction()),
            a.variants.as_deref(),
        )?;
        runs.push(row);
        groups.push(g);
        if first.is_none() {
            first = Some((setup, stage));
        }
    }
    let (setup, stage) = first.ok_or_else(|| anyhow!("no seed ran"))?;
    let lambda = setup.cfg.formations.lambda;
    let window_s = a.window.unwrap_or_else(|| {
        runs.iter()
            .flatten()
            .map(|v| v.rec.summary.simulated_s)
            .fold(f64::INFINITY, f64::min)
    });
    let rows: Vec<Row> = (0..runs[0].len())
        .map(|r| Row::of(runs.iter().map(|seed| &seed[r]).collect(), window_s))
        .collect();
    if let Some(path) = &c.svg {
        let title = format!(
            "{} → {}, {} agents, seed {}: the measures of formation-transform section 5.1 over time",
            setup.from_label, setup.to_label, setup.agents, c.seed
        );
        let text = if a.lambdas.is_some() {
            let title = format!(
                "{} → {}, {} agents, {} seed{}{}: eq. 3's λ, raw and normalised",
                setup.from_label,
                setup.to_label,
                setup.agents,
                a.seeds,
                if a.seeds == 1 { "" } else { "s" },
                if a.preset.is_some() {
                    ", preset paper"
                } else {
                    ""
                }
            );
            transform_svg::lambda_plot(
                &rows.iter().map(Row::sweep_point).collect::<Vec<_>>(),
                &title,
            )
        } else {
            transform_svg::measures_plot(&runs[0], &title)
        };
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    let sub = GroupSummary::of(&groups);
    if c.json {
        let v = json!({
            "from": setup.from_label,
            "to": setup.to_label,
            "agents": setup.agents,
            "radius_m": setup.radius_m,
            "area_m2": setup.place.area_m2,
            "seed": c.seed,
            "seeds": a.seeds,
            "scenario": a.scenario.name(),
            "scenario_layout": stage.json(),
            "preset": a.preset.map(|_| "paper"),
            "lambda": lambda,
            "window_s": window_s,
            "timeout_s": runs[0][0].params.timeout_s,
            "rows": rows.iter().map(Row::json).collect::<Vec<_>>(),
            "subgroups": sub.json(),
        });
        outln!("{v}")?;
        return Ok(());
    }
    outln!(
        "transform compare {} → {}: {} agents (radius {} m), λ {lambda}, {} seed{} from {}{}, subgroup attraction {}",
        setup.from_label,
        setup.to_label,
        setup.agents,
        setup.radius_m,
        a.seeds,
        if a.seeds == 1 { "" } else { "s" },
        c.seed,
        if a.preset.is_some() {
            ", preset paper"
        } else {
            ""
        },
        runs[0][0].params.subgroup_attraction.name()
    )?;
    if let Some(note) = &setup.area_note {
        outln!("area: {note}")?;
    }
    outln!("{}", stage.text())?;
    let nw = rows
        .iter()
        .map(|r| r.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(13);
    outln!(
        "{:<nw$} {:<12} {:<13} {:>17} {:>15} {:>17} {:>17} {:>15} {:>8} {:>9}",
        "variant",
        "pairing",
        "mover",
        "arrival (s)",
        "I_d",
        "σ_min_dis (m)",
        "σ_curr_eft (m)",
        "turn (rad/s)",
        "swaps",
        "overlaps"
    )?;
    for r in &rows {
        outln!(
            "{:<nw$} {:<12} {:<13} {:>17} {:>15} {:>17} {:>17} {:>15} {:>8.1} {:>9.1}",
            r.name,
            r.cost_label(),
            r.mover_label(),
            r.arrival_text(),
            pm(&r.window.0, 3),
            pm(&r.window.1, 4),
            pm(&r.window.2, 4),
            pm(&r.heading.0, 3),
            r.swaps.mean,
            r.overlaps.mean
        )?;
    }
    for r in rows.iter().filter(|r| !r.facts_text.is_empty()) {
        outln!("{:<nw$} {}", r.name, r.facts_text)?;
    }
    outln!(
        "measures averaged over the first {window_s:.2} s of every run (I_d eq. 17 in bits, σ_min_dis eq. 24, σ_curr_eft eq. 26, turn: the moving agents' mean heading-change rate, section 5.3); ± is the 95 % confidence interval over the seeds; SF: social forces, MI: mutual-information feedback, +ours: fades, settling, contacts and exchanges of targets; rest T: without settling, the crowd came to rest (no agent faster than {} m/s for {} s) at T s short of its targets",
        REST_SPEED_M_S,
        REST_HOLD_S
    )?;
    outln!(
        "subgroups (least effort): {:.1} ± {:.1}, converged in {} of {} seeds, locality {} (agents whose nearest neighbour is in their own subgroup)",
        sub.count.mean,
        sub.count.ci95,
        sub.converged,
        a.seeds,
        pm(&sub.locality, 3)
    )?;
    if let Some(path) = &c.svg {
        outln!("wrote {}", path.display())?;
    }
    Ok(())
}

/// `mean ± ci95` to `digits` decimals.
fn pm(i: &Interval, digits: usize) -> String {
    format!("{:.digits$} ± {:.digits$}", i.mean, i.ci95)
}

/// One seed: the four pairings and the eight runs, in `scenario`.
fn one_seed(
    setup: &Setup,
    preset: Option<Preset>,
    timeout_s: Option<f64>,
    scenario: Scenario,
    lambdas: Option<&[f64]>,
    attraction: Option<SubgroupAttraction>,
    only: Option<&[String]>,
) -> Result<(Vec<Variant>, GroupFacts, Stage)> {
    let want = |name: &str| match only {
        None => VARIANTS[..DEFAULT_VARIANTS].contains(&name),
        Some(o) => o.iter().any(|x| x == name || x == "all"),
    };
    let sampled = setup.targets()?;
    let s = &setup.settings;
    let lambda = setup.cfg.formations.lambda;
    let stage = Stage::new(scenario, &setup.place, &setup.sources, &sampled, &s.moves)?;
    let targets = stage.targets(&sampled);
    let plan_for = |cost: PairCost| -> Result<(TransformPlan, f64)> {
        let t0 = Instant::now();
        let plan = TransformPlan::new(
            &setup.sources,
            &targets,
            cost,
            s.ap.as_ref(),
            Cancel::default(),
        )
        .map_err(|e| anyhow!("--to {}: {e}", setup.to_label))?
        .ok_or_else(|| anyhow!("pairing was cancelled"))?;
        Ok((stage.complete(plan), t0.elapsed().as_secs_f64() * 1e3))
    };
    let mut moves = s.moves.clone();
    if let Some(t) = timeout_s {
        moves.timeout_s = t;
    }
    if let Some(x) = attraction {
        moves.subgroup_attraction = x;
    }
    let social = match preset {
        Some(Preset::Paper) => moves.clone().paper(),
        None => moves.clone(),
    };
    let (least, least_ms) = plan_for(PairCost::LeastEffort { lambda })?;
    let facts = GroupFacts {
        count: least.subgroups.count(),
        converged: least.subgroups.converged,
        iterations: least.subgroups.iterations,
        locality: locality(&least.sources_m, &least.subgroups.group_of),
    };
    let (travel, travel_ms) = plan_for(PairCost::LeastEffort { lambda: 1.0 })?;
    let mut variants = Vec::new();
    let mut add = |name: &'static str, plan: &TransformPlan, ms, params: MoveParams| {
        if lambdas.is_none() && !want(name) {
            return;
        }
        let (rec, facts) = stage.run(plan, &params, setup.seed);
        let (tr, local) = pairing_terms(&plan.sources_m, &plan.targets_m);
        let moved = plan
            .targets_m
            .iter()
            .zip(&travel.targets_m)
            .filter(|(a, b)| a != b)
            .count();
        variants.push(Variant {
            name,
            cost: plan.cost,
            params,
            prepare_ms: ms,
            rec,
            facts,
            terms: (tr, local, moved as f64 / plan.targets_m.len().max(1) as f64),
        });
    };
    if let Some(ls) = lambdas {
        for &lambda in ls {
            for cost in [
                PairCost::LeastEffort { lambda },
                PairCost::LeastEffortNormalised { lambda },
            ] {
                let (plan, ms) = plan_for(cost)?;
                add(cost.name(), &plan, ms, social.clone());
            }
        }
        return Ok((variants, facts, stage));
    }
    add("least-effort", &least, least_ms, social.clone());
    add("travel-only", &travel, travel_ms, social.clone());
    for (name, cost) in [
        ("euclidean", PairCost::Euclidean),
        ("manhattan", PairCost::Manhattan),
    ] {
        if !want(name) {
            continue;
        }
        let (plan, ms) = plan_for(cost)?;
        add(name, &plan, ms, social.clone());
    }
    let mut quiet = social.clone();
    quiet.feedback = false;
    add("no-feedback", &least, 0.0, quiet);
    add("orca", &least, 0.0, moves.clone().rvo2_orca());
    add("rvo", &least, 0.0, moves.clone().rvo());
    add("steering", &least, 0.0, moves.steering());
    Ok((variants, facts, stage))
}

/// One variant over the seeds.
struct Row {
    name: &'static str,
    cost: &'static str,
    lambda: Option<f64>,
    /// The pairing's travel and local-structure terms (m²) and the fraction of
    /// agents paired differently from travel-only.
    terms: (Interval, Interval, Interval),
    params: MoveParams,
    seeds: usize,
    /// Over the runs that arrived.
    arrival: Interval,
    arrived_runs: usize,
    arrived_fraction: Interval,
    /// The paper's "time": until every agent arrived or (without settling) the
    /// crowd came to rest, over the runs that did either.
    finish: Interval,
    finished_runs: usize,
    /// Over the runs that ended with the crowd at rest short of its targets.
    rest_runs: usize,
    /// Mean distance of the agents from their targets at the end (m).
    offset_m: Interval,
    /// I_d, σ_min_dis, σ_curr_eft over the common window.
    window: (Interval, Interval, Interval),
    /// The same over each run's own length.
    progress: (Interval, Interval, Interval),
    /// The heading-change rate over the common window and over each run's length.
    heading: (Interval, Interval),
    /// The scenario's facts over the seeds.
    facts: Value,
    facts_text: String,
    swaps: Interval,
    /// The subgroups' spread at the end and over the run (`RunSummary`).
    spread: (Interval, Interval),
    overlaps: Interval,
    min_distance_m: f64,
    prepare_ms: Interval,
    step_us_p99: u64,
}

impl Row {
    fn of(runs: Vec<&Variant>, window_s: f64) -> Row {
        let v0 = runs[0];
        let collect =
            |f: &dyn Fn(&Variant) -> f64| -> Vec<f64> { runs.iter().map(|v| f(v)).collect() };
        let arrivals: Vec<f64> = runs.iter().filter_map(|v| v.rec.arrival_s()).collect();
        let finishes: Vec<f64> = runs
            .iter()
            .filter_map(|v| v.rec.arrival_s().or(v.rec.summary.rest_s))
            .collect();
        let windows: Vec<Option<Measures>> = runs
            .iter()
            .map(|v| window_mean(v.rec.series.iter().map(|&(t, m, _)| (t, m)), window_s))
            .collect();
        let w = |f: &dyn Fn(&Measures) -> f64| -> Interval {
            interval(
                &windows
                    .iter()
                    .map(|m| m.as_ref().map_or(f64::NAN, f))
                    .collect::<Vec<_>>(),
            )
        };
        let p = |f: &dyn Fn(&Measures) -> f64| -> Interval {
            interval(&collect(&|v| f(&v.rec.summary.mean)))
        };
        Row {
            name: v0.name,
            cost: v0.cost.name(),
            lambda: v0.cost.lambda(),
            terms: (
                interval(&collect(&|v| v.terms.0)),
                interval(&collect(&|v| v.terms.1)),
                interval(&collect(&|v| v.terms.2)),
            ),
            params: v0.params.clone(),
            seeds: runs.len(),
            arrival: interval(&arrivals),
            arrived_runs: arrivals.len(),
            arrived_fraction: interval(&collect(&|v| v.rec.summary.arrived_fraction)),
            finish: interval(&finishes),
            finished_runs: finishes.len(),
            rest_runs: runs
                .iter()
                .filter(|v| v.rec.arrival_s().is_none() && v.rec.summary.rest_s.is_some())
                .count(),
            offset_m: interval(&collect(&|v| v.rec.summary.mean_offset_m)),
            window: (
                w(&|m| m.i_d),
                w(&|m| m.sigma_min_dis_m),
                w(&|m| m.sigma_curr_eft_m),
            ),
            progress: (
                p(&|m| m.i_d),
                p(&|m| m.sigma_min_dis_m),
                p(&|m| m.sigma_curr_eft_m),
            ),
            heading: (
                w(&|m| m.heading_change_rad_s),
                p(&|m| m.heading_change_rad_s),
            ),
            facts: facts_json(&runs.iter().map(|v| &v.facts).collect::<Vec<_>>()),
            facts_text: facts_text(&runs.iter().map(|v| &v.facts).collect::<Vec<_>>()),
            swaps: interval(&collect(&|v| v.rec.summary.swaps as f64)),
            spread: (
                interval(&collect(&|v| {
                    v.rec.summary.subgroup_spread.unwrap_or(f64::NAN)
                })),
                interval(&collect(&|v| {
                    v.rec.summary.subgroup_spread_mean.unwrap_or(f64::NAN)
                })),
            ),
            overlaps: interval(&collect(&|v| v.rec.summary.overlapping_pairs as f64)),
            min_distance_m: runs
                .iter()
                .map(|v| v.rec.summary.min_distance_m)
                .fold(f64::INFINITY, f64::min),
            prepare_ms: interval(&collect(&|v| v.prepare_ms)),
            step_us_p99: runs
                .iter()
                .map(|v| v.rec.step_us_at(0.99))
                .max()
                .unwrap_or(0),
        }
    }

    /// The pairing column: the cost, with λ for the least-effort ones (`ΔE'`:
    /// normalised terms).
    fn cost_label(&self) -> String {
        match (self.cost, self.lambda) {
            ("least-effort", Some(l)) => format!("ΔE λ{l}"),
            ("least-effort-normalised", Some(l)) => format!("ΔE' λ{l}"),
            (c, _) => c.to_string(),
        }
    }

    /// This row as a point of the λ plot.
    fn sweep_point(&self) -> transform_svg::SweepPoint {
        let pair = |i: &Interval| (i.mean, i.ci95);
        transform_svg::SweepPoint {
            lambda: self.lambda.unwrap_or(f64::NAN),
            normalised: self.cost == "least-effort-normalised",
            values: [
                pair(&Interval {
                    mean: 100.0 * self.terms.2.mean,
                    ci95: 100.0 * self.terms.2.ci95,
                    n: self.terms.2.n,
                }),
                pair(&self.terms.0),
                pair(&self.finish),
                pair(&self.window.0),
                pair(&self.window.1),
                pair(&self.window.2),
            ],
        }
    }

    fn mover_label(&self) -> String {
        match self.params.mover {
            Mover::Orca => "ORCA (RVO2)".to_string(),
            Mover::Rvo => "RVO (sampled)".to_string(),
            Mover::Steering => "steering".to_string(),
            Mover::SocialForce => format!(
                "SF, MI {}{}",
                super::shared::on_off(self.params.feedback),
                if self.params.exchanges || self.params.settling {
                    " +ours"
                } else {
                    ""
                }
            ),
        }
    }

    fn arrival_text(&self) -> String {
        if self.arrived_runs == self.seeds {
            pm(&self.arrival, 2)
        } else if self.finished_runs == self.seeds {
            format!("rest {}", pm(&self.finish, 2))
        } else {
            format!(
                "{}/{} ({:.1} % in)",
                self.arrived_runs,
                self.seeds,
                100.0 * self.arrived_fraction.mean
            )
        }
    }

    fn json(&self) -> Value {
        let iv = |i: &Interval| json!({"mean": finite_or_null(i.mean), "ci95": finite_or_null(i.ci95), "n": i.n});
        let p = &self.params;
        json!({
            "variant": self.name,
            "cost": self.cost,
            "lambda": self.lambda,
            "pairing": {
                "travel_m2": iv(&self.terms.0),
                "local_m2": iv(&self.terms.1),
                "changed_vs_travel_only": iv(&self.terms.2),
            },
            "mover": mover_name(p.mover),
            "seeds": self.seeds,
            "feedback": p.feedback,
            "exchanges": p.exchanges,
            "contacts": p.contacts,
            "settling": p.settling,
            "fades": p.fades,
            "subgroup_forces": p.subgroup_forces,
            "subgroup_attraction": (p.mover == Mover::SocialForce && p.subgroup_forces)
                .then(|| p.subgroup_attraction.name()),
            "subgroup_spread": {"end": iv(&self.spread.0), "run": iv(&self.spread.1)},
            "swaps": iv(&self.swaps),
            "arrival_s": iv(&self.arrival),
            "arrived_runs": self.arrived_runs,
            "arrived_fraction": iv(&self.arrived_fraction),
            "finish_s": iv(&self.finish),
            "finished_runs": self.finished_runs,
            "rest_runs": self.rest_runs,
            "mean_offset_m": iv(&self.offset_m),
            "i_d": iv(&self.window.0),
            "sigma_min_dis": iv(&self.window.1),
            "sigma_curr_eft": iv(&self.window.2),
            "heading_change_rad_s": iv(&self.heading.0),
            "progress": {
                "i_d": iv(&self.progress.0),
                "sigma_min_dis": iv(&self.progress.1),
                "sigma_curr_eft": iv(&self.progress.2),
                "heading_change_rad_s": iv(&self.heading.1),
            },
            "scenario": self.facts,
            "overlapping_pairs": iv(&self.overlaps),
            "min_distance_m": finite_or_null(self.min_distance_m),
            "prepare_ms": iv(&self.prepare_ms),
            "step_us_p99": self.step_us_p99,
        })
    }
}

/// The least-effort plans' subgroups over the seeds.
struct GroupSummary {
    count: Interval,
    converged: usize,
    seeds: usize,
    iterations: Interval,
    locality: Interval,
}

impl GroupSummary {
    fn of(g: &[GroupFacts]) -> GroupSummary {
        GroupSummary {
            count: interval(&g.iter().map(|f| f.count as f64).collect::<Vec<_>>()),
            converged: g.iter().filter(|f| f.converged).count(),
            seeds: g.len(),
            iterations: interval(
                &g.iter()
                    .map(|f| f64::from(f.iterations))
                    .collect::<Vec<_>>(),
            ),
            locality: interval(&g.iter().map(|f| f.locality).collect::<Vec<_>>()),
        }
    }

    fn json(&self) -> Value {
        let iv = |i: &Interval| json!({"mean": finite_or_null(i.mean), "ci95": finite_or_null(i.ci95), "n": i.n});
        json!({
            "count": iv(&self.count),
            "converged": self.converged == self.seeds,
            "converged_runs": self.converged,
            "iterations": iv(&self.iterations),
            "locality": iv(&self.locality),
        })
    }
}

/// `social-force`, `orca`, `rvo` or `steering`.
pub fn mover_name(m: Mover) -> &'static str {
    match m {
        Mover::SocialForce => "social-force",
        Mover::Orca => "orca",
        Mover::Rvo => "rvo",
        Mover::Steering => "steering",
    }
}
