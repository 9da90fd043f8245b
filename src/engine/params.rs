//! The one place where the config becomes the parameters of the crowd, gesture and
//! assignment code, which know nothing of the config.

use crate::config::{
    AssignmentCost, Config, SubgroupSimilarity, TransformAttraction, TransformCost,
};
use crate::crowd::agents::AgentParams;
use crate::crowd::assign::PointMetric;
use crate::crowd::control::DirectParams;
use crate::crowd::environment::{FieldParams, Planner, PlannerParams, Scene, MESH_FIELD_RANGE_M};
use crate::crowd::transform::{
    ApParams, MoveParams, Mover, PairCost, Preference, Similarity, SubgroupAttraction,
};
use crate::gesture::capture::TapThresholds;
use crate::gesture::dtw::Weights;
use crate::gesture::knn::SearchParams;
use crate::gesture::segment::SegmentParams;
use crate::vocab::Micros;
use std::sync::Arc;

/// The planner's parameters for `cfg` (the agents' speed limit as preferred speed).
pub fn planner_params(cfg: &Config) -> PlannerParams {
    PlannerParams::new(cfg.crowd.max_speed_m_s)
}

/// The travel-cost planner over `cfg`'s scene (`None` without a scene, or when the
/// scene makes no planning grid: then Euclidean costs, with a warning). Building it
/// rasterises the scene and sizes the fast-marching workspaces: the daemon does it
/// off the control thread.
pub fn inline_planner(cfg: &Config) -> Option<Planner> {
    planner_for(cfg.loaded_scene()?, planner_params(cfg))
}

/// The travel-cost planner over `scene` (see [`inline_planner`]).
pub fn planner_for(scene: &Arc<Scene>, params: PlannerParams) -> Option<Planner> {
    Planner::new(Arc::clone(scene), params)
        .map_err(|err| log::warn!("scene: no travel-cost planner ({err}); Euclidean costs"))
        .ok()
}

/// Whether two optional scenes are the same: one `Arc`, or equal content.
pub fn same_scene(a: Option<&Arc<Scene>>, b: Option<&Arc<Scene>>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => Arc::ptr_eq(a, b) || a == b,
        (None, None) => true,
        _ => false,
    }
}

/// The assignment cost the config names, as the solver's metric.
pub fn point_metric(cost: AssignmentCost) -> PointMetric {
    match cost {
        AssignmentCost::SquaredDistance => PointMetric::Squared,
        AssignmentCost::Distance => PointMetric::Euclidean,
    }
}

pub(super) fn agent_params(cfg: &Config) -> AgentParams {
    let c = &cfg.crowd;
    AgentParams {
        radius_m: c.agent_radius_m,
        max_speed_m_s: c.max_speed_m_s,
        max_accel_m_s2: c.max_accel_m_s2,
        kp_per_s2: c.kp_per_s2,
        kd_per_s: c.kd_per_s,
        push_stiffness_per_s2: c.push_stiffness_per_s2,
    }
}

/// The tap and length thresholds of the config's `gestures` section.
pub fn tap_thresholds(cfg: &Config) -> TapThresholds {
    let g = &cfg.gestures;
    TapThresholds {
        min_duration: Micros(g.min_duration_ms.saturating_mul(1000)),
        min_travel_mm: g.min_travel_mm,
        max_duration: Micros::from_secs_f64(g.max_duration_s),
    }
}

/// The search parameters of the config's `gestures` section (K, eq. 12's weights,
/// the band).
pub fn search_params(cfg: &Config) -> SearchParams {
    let g = &cfg.gestures;
    SearchParams {
        k: g.k as usize,
        weights: Weights {
            alpha: g.weights.alpha,
            beta: g.weights.beta,
            gamma: g.weights.gamma,
            delta: g.weights.delta,
        },
        band: g.band.map(|b| b as usize),
    }
}

/// The segmenter's parameters (grouping window, hand span, gesture grace).
pub fn segment_params(cfg: &Config) -> SegmentParams {
    SegmentParams {
        group_window: Micros(cfg.controls.group_window_ms * 1000),
        hand_span_mm: cfg.controls.hand_span_mm,
        gesture_span_mm: cfg.controls.gesture_span_mm,
        gesture_grace: Micros(cfg.controls.gesture_grace_ms * 1000),
    }
}

pub(super) fn direct_params(cfg: &Config) -> DirectParams {
    DirectParams {
        handle_weight: cfg.mesh.handle_weight,
        soft_weight: cfg.mesh.soft_weight,
        checkpoint_spacing_m: cfg.controls.checkpoint_spacing_m,
        max_constraint_speed_m_s: cfg.controls.max_constraint_speed_m_s,
        opposing_gain_per_s: cfg.controls.opposing_gain_per_s,
    }
}

/// How the environment's potential field moves the crowd's mesh
/// (mesh-formation-control sections 5 and 6.1): the field's range, the configured
/// step `mesh.field_step_m` (m per unit of field), and `margin_m` (the agent radius)
/// kept between projected vertices and obstacles. `None` for values the config
/// validation refuses.
pub(super) fn mesh_field_params(step_m: f64, margin_m: f64) -> Option<FieldParams> {
    FieldParams::new(MESH_FIELD_RANGE_M, step_m, margin_m).ok()
}

/// The pairing cost `cfg` names (least effort with `formations.lambda`).
pub fn pair_cost(cfg: &Config) -> PairCost {
    match cfg.formations.cost {
        TransformCost::LeastEffort => PairCost::LeastEffort {
            lambda: cfg.formations.lambda,
        },
        TransformCost::Euclidean => PairCost::Euclidean,
        TransformCost::Manhattan => PairCost::Manhattan,
        TransformCost::LeastEffortNormalised => PairCost::LeastEffortNormalised {
            lambda: cfg.formations.lambda,
        },
    }
}

/// How a transform moves the agents (`formations.transform`), at agent radius
/// `radius_m`.
pub fn move_params(cfg: &Config, radius_m: f64) -> MoveParams {
    let t = &cfg.formations.transform;
    MoveParams {
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
        subgroup_attraction: match t.subgroup_attraction {
            TransformAttraction::Place => SubgroupAttraction::Place,
            TransformAttraction::AsPrinted => SubgroupAttraction::AsPrinted,
            TransformAttraction::Decaying => SubgroupAttraction::Decaying,
            TransformAttraction::Dt => SubgroupAttraction::DelaunayGraph,
        },
        interaction_range_m: t.interaction_range_m,
        fluctuation_m_s2: t.fluctuation_m_s2,
        bin_m: t.bin_m,
        sectors: t.sectors,
        settle_speed_m_s: t.settle_speed_m_s,
        ..MoveParams::default()
    }
}

/// Affinity propagation's parameters (`formations.subgroups`); `None` when
/// subgroups are off.
pub fn ap_params(cfg: &Config) -> Option<ApParams> {
    let s = &cfg.formations.subgroups;
    s.enabled.then_some(ApParams {
        damping: s.damping,
        max_iterations: s.max_iterations,
        convergence_iterations: s.convergence_iterations,
        preference: s.preference.map_or(Preference::Median, Preference::Value),
        ring: s.ring,
        dense_up_to: s.dense_up_to,
        similarity: match s.similarity {
            SubgroupSimilarity::Local => Similarity::Local,
            SubgroupSimilarity::Paper => Similarity::Paper,
        },
    })
}
