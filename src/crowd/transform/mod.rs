//! Formation transforms (formation-transform, Xu et al. 2015): the crowd morphs from
//! where it stands into a new formation shape, each agent walking to a target of its
//! own, neighbours staying neighbours.
//!
//! | step | file | paper |
//! |---|---|---|
//! | target points sampled in the shape | [`crate::crowd::formation`] (`sample.rs`) | 3.1, eq. 1 |
//! | agents paired with targets (least effort, Euclidean, Manhattan) | `pairing.rs` | 3.2, eqs. 2–6; 5.2 |
//! | subgroups by affinity propagation (eq. 20 as written, or with a spatial term and a merge of small subgroups) | `subgroups.rs`, `subgroup_merge.rs`; tests on the shipped pairs in `subgroups_shipped.rs` | 3.4, eq. 20 |
//! | a request prepared off the control thread | `prepare.rs` | 3 |
//! | social forces with subgroup terms, mutual-information feedback | `run.rs` (the step), `params.rs` (its constants), `social.rs` (forces), `social_groups.rs` (eq. 21 three ways, the subgroup as a whole on its Delaunay graph), `feedback.rs` (eqs. 11–19), `crate::crowd::agents::NeighbourGrid` (neighbours and nearest distances) | 3.3, 3.5, eqs. 7–19, 21–23; 3 step 3 |
//! | the objective measures, and the heading-change rate (fluctuation) | `measures.rs` | 5.1, eqs. 17, 24–26; 5.3, Fig. 12 |
//! | the baselines of the comparison (Table 3): ORCA, RVO, OpenSteer-style steering | `baseline.rs` (one call for `run.rs`), `orca.rs`, `rvo.rs`, `steer.rs`, `nearest.rs` (their neighbour lists); runs under them in `baseline_tests.rs` | 5.4 |
//! | comparing variants over seeds: means with 95 % intervals, a common time window, subgroup locality | `experiment.rs` | 5 |

mod baseline;
#[cfg(test)]
mod baseline_tests;
mod experiment;
mod feedback;
mod measures;
mod nearest;
mod orca;
mod pairing;
mod params;
mod prepare;
mod run;
mod rvo;
mod social;
mod social_groups;
#[cfg(test)]
mod social_groups_tests;
mod steer;
mod subgroup_merge;
mod subgroups;
#[cfg(test)]
mod subgroups_shipped;

pub use experiment::{interval, locality, t_975, window_mean, Interval};
pub use measures::{HeadingChange, Measures, MOVING_SPEED_M_S};
pub use pairing::{pair, pairing_terms, raw_lambda, term_means, PairCost};
pub use prepare::{PreparedTransform, TransformError, TransformPlan, TransformRequest};
pub use run::{
    MoveParams, Mover, RunSummary, StepReport, SubgroupAttraction, TransformRun,
    OVERLAP_TOLERANCE_M, REST_HOLD_S, REST_SPEED_M_S,
};
pub use subgroup_merge::{min_group_size, MIN_SIZE_PER_SQRT_N};
pub use subgroups::{subgroups, ApParams, Preference, Similarity, Subgroups, SPATIAL_WEIGHT};
