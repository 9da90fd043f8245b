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

use super::shared::Common;
use super::transform_compare_rows::{pm, GroupFacts, GroupSummary, Row};
use super::transform_scenario::{Scenario, Stage};
use super::transform_setup::Setup;
use super::transform_svg;
use super::variant::Variant;
use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::transform::{
    locality, pairing_terms, MoveParams, PairCost, SubgroupAttraction, TransformPlan, REST_HOLD_S,
    REST_SPEED_M_S,
};
use serde_json::json;
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
