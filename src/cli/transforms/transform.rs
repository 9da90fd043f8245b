//! `crowdtouch transform`: one formation transform (formation-transform, Xu et al.
//! 2015) run headless on a virtual clock, set up as the daemon sets one up
//! (`engine/transform.rs`), and measured: arrival, the closest two agents came,
//! travel, the paper's three measures of section 5.1 averaged over the run (`I_d`
//! eq. 17, `σ_min_dis` eq. 24, `σ_curr_eft` eq. 26) and the wall-clock time of
//! each `TransformRun::step` (the start is `transform_setup.rs`). `transform
//! compare` (`transform_compare.rs`) runs the paper's comparisons on the same
//! start; `transform_svg.rs` draws both.
//!
//! ```text
//!  --from A ──► A.sample(place, N)  = sources s_i        (section 3.1)
//!  --to   B ──► TransformRequest::prepare: B sampled,   (sections 3.1, 3.2, 3.4)
//!               paired (eq. 3 or a distance), subgroups
//!          ──► TransformRun::step at 1/60 s until done   (sections 3.3, 3.5)
//! ```

use super::shared::{finite_or_null, on_off, run, AttractionArg, Common, CostArg, SHORT_LISTED};
use super::transform_setup::Setup;
use super::transform_svg;
use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Subcommand};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::transform::PairCost;
use serde_json::json;
use std::time::Instant;

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
    /// The paper's comparisons over `--seeds` starts: least-effort (and λ = 1),
    /// Euclidean and Manhattan pairing (section 5.2, Table 2), without the
    /// mutual-information feedback (section 5.3), and the Table 3 baselines on
    /// the least-effort pairing (section 5.4): ORCA as RVO2 runs it, RVO as its
    /// library ran it, OpenSteer-style steering; means and 95 % intervals of the
    /// arrival time, the three measures over a common window and the exchanges of
    /// targets; `--preset paper` without the project's additions; `--svg` plots
    /// the first seed's measures over time.
    Compare(super::transform_compare::CompareArgs),
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
    /// `paper`: without the project's additions to the movement (no fades, no
    /// settling, no positional contacts, no exchanges of targets), as
    /// `transform compare --preset paper`.
    #[arg(long, value_enum)]
    pub preset: Option<super::transform_compare::Preset>,
    /// End the run after this long if not every agent arrived (s); default: the
    /// config's `formations.transform.timeout_s`.
    #[arg(long)]
    pub timeout: Option<f64>,
    /// What holds a subgroup together (default: the config's
    /// `formations.transform.subgroup_attraction`, `place`).
    #[arg(long, value_enum)]
    pub subgroup_attraction: Option<AttractionArg>,
}

/// Runs `transform` or `transform compare`.
pub fn transform(c: TransformCmd) -> Result<()> {
    match c.sub {
        Some(TransformSub::Compare(args)) => super::transform_compare::compare(&args),
        None => single(&c.run),
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
    let mut params = match a.preset {
        Some(super::transform_compare::Preset::Paper) => s.moves.clone().paper(),
        None => s.moves.clone(),
    };
    if let Some(t) = a.timeout {
        if !(t.is_finite() && t > 0.0) {
            bail!("--timeout must be a positive number of seconds, got {t}");
        }
        params.timeout_s = t;
    }
    params.feedback = params.feedback && !a.no_feedback;
    params.subgroup_forces = params.subgroup_forces && !a.no_subgroups;
    if let Some(x) = a.subgroup_attraction {
        params.subgroup_attraction = x.attraction();
    }
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
            "subgroup_attraction": params
                .subgroup_forces
                .then(|| params.subgroup_attraction.name()),
            "subgroup_spread": sm.subgroup_spread,
            "subgroup_spread_mean": sm.subgroup_spread_mean,
            "seed": setup.seed,
            "agents": sm.agents,
            "radius_m": setup.radius_m,
            "area_m2": setup.place.area_m2,
            "steps": sm.steps,
            "simulated_s": sm.simulated_s,
            "timed_out": sm.timed_out,
            "rest_s": sm.rest_s,
            "arrived_fraction": sm.arrived_fraction,
            "mean_offset_m": sm.mean_offset_m,
            "min_distance_m": finite_or_null(sm.min_distance_m),
            "overlapping_pairs": sm.overlapping_pairs,
            "swaps": sm.swaps,
            "mean_travel_m": sm.mean_travel_m,
            "max_travel_m": sm.max_travel_m,
            "I_d": sm.mean.i_d,
            "sigma_min_dis": sm.mean.sigma_min_dis_m,
            "sigma_curr_eft": sm.mean.sigma_curr_eft_m,
            "step_us_p50": rec.step_us_at(0.5),
            "step_us_p99": rec.step_us_at(0.99),
            "prepare_ms": prepare_ms,
            "short_of_target": rec.short.iter().take(SHORT_LISTED).map(|&(i, d, v)| json!({
                "agent": i, "distance_m": d, "speed_m_s": v
            })).collect::<Vec<_>>(),
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
            match (sm.timed_out, sm.rest_s) {
                (true, _) => " (timed out)".to_string(),
                (false, Some(t)) => format!(" (the crowd came to rest at {t:.2} s)"),
                (false, None) => String::new(),
            }
        )?;
        outln!(
            "  arrived             {:.1} % (mean distance from target {:.3} m)",
            100.0 * sm.arrived_fraction,
            sm.mean_offset_m
        )?;
        if !rec.short.is_empty() {
            let listed: Vec<String> = rec
                .short
                .iter()
                .take(SHORT_LISTED)
                .map(|&(i, d, v)| format!("{i} ({d:.2} m off, {v:.2} m/s)"))
                .collect();
            outln!(
                "  short of target     {} agents: {}{}",
                rec.short.len(),
                listed.join(", "),
                if rec.short.len() > SHORT_LISTED {
                    ", …"
                } else {
                    ""
                }
            )?;
        }
        outln!(
            "  closest two agents  {:.4} m at any time (two radii {:.2} m); {} pairs overlapped",
            sm.min_distance_m,
            2.0 * setup.radius_m,
            sm.overlapping_pairs
        )?;
        if sm.swaps > 0 {
            outln!(
                "  target exchanges    {} (pairs of agents blocking each other head-on)",
                sm.swaps
            )?;
        }
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
