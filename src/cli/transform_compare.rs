//! `crowdtouch transform compare`: the comparisons of formation-transform section
//! 5 on one start (the agents sampled in the source) and one set of targets:
//!
//! | variant | pairing | mover | feedback | paper |
//! |---|---|---|---|---|
//! | `least-effort` | ΔE, eq. 3 | social forces | on | 5.2, Table 2 |
//! | `euclidean` | Euclidean | social forces | on | 5.2, Table 2 |
//! | `manhattan` | Manhattan | social forces | on | 5.2, Table 2 |
//! | `no-feedback` | ΔE, eq. 3 | social forces | off | 5.3 |
//! | `orca` | ΔE, eq. 3 | ORCA | — | 5.4, Table 3 |
//!
//! The last two share the first's pairing and subgroups. Each row gives the time
//! to arrive (or the share arrived at the timeout) and the three measures of
//! section 5.1 averaged over the run; `--svg` plots them over time.

use super::output::outln;
use super::transform::{finite_or_null, run, Common, Recorded};
use super::transform_setup::Setup;
use super::transform_svg;
use anyhow::{anyhow, Context, Result};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::transform::{Mover, PairCost, TransformPlan};
use serde_json::json;
use std::time::Instant;

/// One row of the comparison.
pub struct Variant {
    /// Its name in the table.
    pub name: &'static str,
    /// The pairing cost.
    pub cost: PairCost,
    /// What moves the agents.
    pub mover: Mover,
    /// Mutual-information feedback (eqs. 18–19).
    pub feedback: bool,
    /// How long its pairing and subgroups took (ms; 0 for a shared one).
    pub prepare_ms: f64,
    /// Subgroups of its plan.
    pub subgroups: usize,
    /// The run.
    pub rec: Recorded,
}

/// `transform compare`.
pub fn compare(c: &Common) -> Result<()> {
    let setup = Setup::new(c)?;
    let targets = setup.targets()?;
    let s = &setup.settings;
    let lambda = setup.cfg.formations.lambda;
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
        Ok((plan, t0.elapsed().as_secs_f64() * 1e3))
    };
    let (least, least_ms) = plan_for(PairCost::LeastEffort { lambda })?;
    let mut variants = Vec::new();
    let mut add = |name, plan: &TransformPlan, ms, mover, feedback: bool| {
        let mut p = s.moves.clone();
        p.mover = mover;
        p.feedback = feedback;
        let rec = run(plan, &p, setup.seed, false);
        variants.push(Variant {
            name,
            cost: plan.cost,
            mover,
            feedback,
            prepare_ms: ms,
            subgroups: plan.subgroups.count(),
            rec,
        });
    };
    let feedback = s.moves.feedback;
    add(
        "least-effort",
        &least,
        least_ms,
        Mover::SocialForce,
        feedback,
    );
    for (name, cost) in [
        ("euclidean", PairCost::Euclidean),
        ("manhattan", PairCost::Manhattan),
    ] {
        let (plan, ms) = plan_for(cost)?;
        add(name, &plan, ms, Mover::SocialForce, feedback);
    }
    add("no-feedback", &least, 0.0, Mover::SocialForce, false);
    add("orca", &least, 0.0, Mover::Orca, feedback);
    if let Some(path) = &c.svg {
        let title = format!(
            "{} → {}, {} agents: the measures of formation-transform section 5.1 over time",
            setup.from_label, setup.to_label, setup.agents
        );
        let text = transform_svg::measures_plot(&variants, &title);
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    if c.json {
        let rows: Vec<_> = variants
            .iter()
            .map(|v| {
                let sm = &v.rec.summary;
                json!({
                    "variant": v.name,
                    "cost": v.cost.name(),
                    "mover": mover_name(v.mover),
                    "feedback": v.feedback,
                    "subgroups": v.subgroups,
                    "arrival_s": v.rec.arrival_s(),
                    "timed_out": sm.timed_out,
                    "arrived_fraction": sm.arrived_fraction,
                    "steps": sm.steps,
                    "simulated_s": sm.simulated_s,
                    "I_d": sm.mean.i_d,
                    "sigma_min_dis": sm.mean.sigma_min_dis_m,
                    "sigma_curr_eft": sm.mean.sigma_curr_eft_m,
                    "overlapping_pairs": sm.overlapping_pairs,
                    "min_distance_m": finite_or_null(sm.min_distance_m),
                    "mean_travel_m": sm.mean_travel_m,
                    "max_travel_m": sm.max_travel_m,
                    "prepare_ms": v.prepare_ms,
                    "step_us_p50": v.rec.step_us_at(0.5),
                    "step_us_p99": v.rec.step_us_at(0.99),
                })
            })
            .collect();
        let v = json!({
            "from": setup.from_label,
            "to": setup.to_label,
            "agents": setup.agents,
            "radius_m": setup.radius_m,
            "area_m2": setup.place.area_m2,
            "seed": setup.seed,
            "lambda": lambda,
            "variants": rows,
        });
        outln!("{v}")?;
        return Ok(());
    }
    outln!(
        "transform compare {} → {}: {} agents (radius {} m), same start and targets, λ {lambda}",
        setup.from_label,
        setup.to_label,
        setup.agents,
        setup.radius_m
    )?;
    if let Some(note) = &setup.area_note {
        outln!("area: {note}")?;
    }
    outln!(
        "{:<14} {:<13} {:<13} {:>14} {:>9} {:>14} {:>15} {:>9}",
        "variant",
        "pairing",
        "mover",
        "arrival",
        "I_d",
        "σ_min_dis (m)",
        "σ_curr_eft (m)",
        "overlaps"
    )?;
    for v in &variants {
        let sm = &v.rec.summary;
        let arrival = match v.rec.arrival_s() {
            Some(t) => format!("{t:.2} s"),
            None => format!("{:.1} % arrived", 100.0 * sm.arrived_fraction),
        };
        let mover = match v.mover {
            Mover::Orca => "ORCA".to_string(),
            Mover::SocialForce => format!("SF, MI {}", super::transform::on_off(v.feedback)),
        };
        outln!(
            "{:<14} {:<13} {:<13} {:>14} {:>9.4} {:>14.4} {:>15.4} {:>9}",
            v.name,
            v.cost.name(),
            mover,
            arrival,
            sm.mean.i_d,
            sm.mean.sigma_min_dis_m,
            sm.mean.sigma_curr_eft_m,
            sm.overlapping_pairs
        )?;
    }
    outln!(
        "measures averaged over each run's steps (I_d eq. 17 in bits, σ_min_dis eq. 24, σ_curr_eft eq. 26); SF: social forces, MI: mutual-information feedback"
    )?;
    if let Some(path) = &c.svg {
        outln!("wrote {}", path.display())?;
    }
    Ok(())
}

/// `social-force` or `orca`.
pub fn mover_name(m: Mover) -> &'static str {
    match m {
        Mover::SocialForce => "social-force",
        Mover::Orca => "orca",
    }
}
