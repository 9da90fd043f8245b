//! `transform compare`'s rows: one variant over the seeds (means and 95 %
//! confidence intervals of the arrival, the measures, the pairing's terms and the
//! scenario's facts; its columns, its JSON and its point of the λ plot), and the
//! least-effort plans' subgroups over the seeds.

use super::shared::finite_or_null;
use super::transform_scenario::{facts_json, facts_text};
use super::transform_svg;
use super::variant::Variant;
use crowdtouch::crowd::transform::{interval, window_mean, Interval, Measures, MoveParams, Mover};
use serde_json::{json, Value};

/// The subgroups of one seed's least-effort plan.
pub struct GroupFacts {
    pub count: usize,
    pub converged: bool,
    pub iterations: u32,
    pub locality: f64,
}

/// `mean ± ci95` to `digits` decimals.
pub fn pm(i: &Interval, digits: usize) -> String {
    format!("{:.digits$} ± {:.digits$}", i.mean, i.ci95)
}

/// One variant over the seeds.
pub struct Row {
    pub name: &'static str,
    pub cost: &'static str,
    pub lambda: Option<f64>,
    /// The pairing's travel and local-structure terms (m²) and the fraction of
    /// agents paired differently from travel-only.
    pub terms: (Interval, Interval, Interval),
    pub params: MoveParams,
    pub seeds: usize,
    /// Over the runs that arrived.
    pub arrival: Interval,
    pub arrived_runs: usize,
    pub arrived_fraction: Interval,
    /// The paper's "time": until every agent arrived or (without settling) the
    /// crowd came to rest, over the runs that did either.
    pub finish: Interval,
    pub finished_runs: usize,
    /// Over the runs that ended with the crowd at rest short of its targets.
    pub rest_runs: usize,
    /// Mean distance of the agents from their targets at the end (m).
    pub offset_m: Interval,
    /// I_d, σ_min_dis, σ_curr_eft over the common window.
    pub window: (Interval, Interval, Interval),
    /// The same over each run's own length.
    pub progress: (Interval, Interval, Interval),
    /// The heading-change rate over the common window and over each run's length.
    pub heading: (Interval, Interval),
    /// The scenario's facts over the seeds.
    pub facts: Value,
    pub facts_text: String,
    pub swaps: Interval,
    /// The subgroups' spread at the end and over the run (`RunSummary`).
    pub spread: (Interval, Interval),
    pub overlaps: Interval,
    pub min_distance_m: f64,
    pub prepare_ms: Interval,
    pub step_us_p99: u64,
}

impl Row {
    pub fn of(runs: Vec<&Variant>, window_s: f64) -> Row {
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
    pub fn cost_label(&self) -> String {
        match (self.cost, self.lambda) {
            ("least-effort", Some(l)) => format!("ΔE λ{l}"),
            ("least-effort-normalised", Some(l)) => format!("ΔE' λ{l}"),
            (c, _) => c.to_string(),
        }
    }

    /// This row as a point of the λ plot.
    pub fn sweep_point(&self) -> transform_svg::SweepPoint {
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

    pub fn mover_label(&self) -> String {
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

    pub fn arrival_text(&self) -> String {
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

    pub fn json(&self) -> Value {
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
pub struct GroupSummary {
    pub count: Interval,
    pub converged: usize,
    pub seeds: usize,
    pub iterations: Interval,
    pub locality: Interval,
}

impl GroupSummary {
    pub fn of(g: &[GroupFacts]) -> GroupSummary {
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

    pub fn json(&self) -> Value {
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
