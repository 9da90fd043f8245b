//! The formation-transform settings of the `formations` section
//! (formation-transform, Xu et al. 2015): how a formation request is carried out
//! (`method`), how agents are paired with the new shape's targets (`cost`, with
//! `formations.lambda`), how the transform moves them (`transform`, the social force
//! model of sections 3.3 and 3.5), subgroups (`subgroups`, affinity propagation of
//! section 3.4) and which recognised gestures start a transform (`gestures`).
//!
//! Every part may be left out: a config written before transforms existed gets the
//! defaults below, which are the crowd-level defaults of
//! [`crate::crowd::transform::MoveParams`] and [`crate::crowd::transform::ApParams`].

use crate::vocab::FormationMethod;
use serde::{Deserialize, Serialize};

/// How agents are paired with the new formation's targets (formation-transform
/// section 3.2; the alternatives of section 5.2).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransformCost {
    /// `ΔE(i, j)` of eq. 3 with `formations.lambda`.
    #[default]
    LeastEffort,
    /// The Euclidean distance.
    Euclidean,
    /// The Manhattan distance.
    Manhattan,
    /// `ΔE(i, j)` of eq. 3 with both terms normalised by their means over every
    /// pair, so that `formations.lambda` weighs travel and local structure as
    /// the paper means it (0.5: alike); see `crowd::transform::raw_lambda`.
    LeastEffortNormalised,
}

impl TransformCost {
    /// The name on the wire and in files (`least_effort`, `euclidean`,
    /// `manhattan`, `least_effort_normalised`).
    pub fn as_str(self) -> &'static str {
        match self {
            TransformCost::LeastEffort => "least_effort",
            TransformCost::Euclidean => "euclidean",
            TransformCost::Manhattan => "manhattan",
            TransformCost::LeastEffortNormalised => "least_effort_normalised",
        }
    }
}

/// What holds a subgroup together in a transform (`transform.subgroup_attraction`;
/// formation-transform eq. 21 and section 3's "each subgroup is manipulated as a
/// whole using a DT graph"; the formulas in `crowd/transform/social_groups.rs`).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransformAttraction {
    /// The project's bounded pull towards each agent's place in its group.
    #[default]
    Place,
    /// Eq. 21 as printed: `A' e^d` towards every other member (d in metres).
    AsPrinted,
    /// `A' e^{−d/B'}` towards every other member (a guess at a misprint).
    Decaying,
    /// Damped springs on the Delaunay edges of each group's source layout.
    Dt,
}

/// Default `transform.desired_speed_m_s` (m/s): the paper's walking speed.
pub const DEFAULT_DESIRED_SPEED_M_S: f64 = 1.3;
/// Default `transform.arrive_m` (m).
pub const DEFAULT_ARRIVE_M: f64 = 0.05;
/// Default `transform.timeout_s` (s).
pub const DEFAULT_TIMEOUT_S: f64 = 120.0;
/// Fastest desired speed a transform may be given, by the config or by a
/// `set_formation` duration (m/s).
pub const MAX_DESIRED_SPEED_M_S: f64 = 10.0;
/// Longest `transform.timeout_s` (s).
pub const MAX_TIMEOUT_S: f64 = 3600.0;

/// How a transform moves the agents (formation-transform sections 3.3, 3.5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransformMoveConfig {
    /// `v⁰`, the desired walking speed (m/s), in `(0, 10]`.
    pub desired_speed_m_s: f64,
    /// Mutual-information feedback on heading and desired speed (eqs. 18–19).
    pub feedback: bool,
    /// Subgroup attraction and cross-group repulsion (eqs. 21–23).
    pub subgroup_forces: bool,
    /// An agent within this distance of its target has arrived (m), in `(0, 1]`.
    pub arrive_m: f64,
    /// A transform ends after this long even if not every agent arrived (s), in
    /// `(0, 3600]`.
    pub timeout_s: f64,
    /// Each agent's own desired speed is drawn within this much of the desired
    /// speed (m/s).
    pub desired_speed_spread_m_s: f64,
    /// Most speed of any agent (m/s).
    pub max_speed_m_s: f64,
    /// Most acceleration of any agent (m/s²).
    pub max_accel_m_s2: f64,
    /// `τ`, relaxation time of the driving force, eq. 8 (s).
    pub tau_s: f64,
    /// Arrival ramp: an agent wants at most `sqrt(2 · arrival_decel · distance)`,
    /// braking evenly to its target (m/s²).
    pub arrival_decel_m_s2: f64,
    /// The forces other than the driving force fade out over this last stretch
    /// before the target (m).
    pub fade_m: f64,
    /// `A` of eqs. 9–10 (m/s²).
    pub repulsion_a_m_s2: f64,
    /// `B` of eqs. 9–10 (m).
    pub repulsion_b_m: f64,
    /// `A` of eq. 9 for the scene's obstacles (m/s²).
    pub obstacle_a_m_s2: f64,
    /// `A'` of eqs. 21–22 (m/s²).
    pub subgroup_a_m_s2: f64,
    /// `B'` of eqs. 21–22 (m).
    pub subgroup_b_m: f64,
    /// What holds a subgroup together: `place` (default), `as_printed`,
    /// `decaying` or `dt`.
    pub subgroup_attraction: TransformAttraction,
    /// No social force beyond this distance (m).
    pub interaction_range_m: f64,
    /// `ξ`, the fluctuation of eq. 7 (m/s²).
    pub fluctuation_m_s2: f64,
    /// `R`, side of the mutual-information bins, eqs. 12–13 (m).
    pub bin_m: f64,
    /// `K`, heading sectors of eq. 14, `2..=64`.
    pub sectors: usize,
    /// An arrived agent slower than this stops and holds (m/s).
    pub settle_speed_m_s: f64,
}

impl Default for TransformMoveConfig {
    fn default() -> Self {
        TransformMoveConfig {
            desired_speed_m_s: DEFAULT_DESIRED_SPEED_M_S,
            feedback: true,
            subgroup_forces: true,
            arrive_m: DEFAULT_ARRIVE_M,
            timeout_s: DEFAULT_TIMEOUT_S,
            desired_speed_spread_m_s: 0.2,
            max_speed_m_s: 2.0,
            max_accel_m_s2: 4.0,
            tau_s: 0.4,
            arrival_decel_m_s2: 0.6,
            fade_m: 1.0,
            repulsion_a_m_s2: 2.0,
            repulsion_b_m: 0.3,
            obstacle_a_m_s2: 3.0,
            subgroup_a_m_s2: 1.0,
            subgroup_b_m: 0.5,
            subgroup_attraction: TransformAttraction::Place,
            interaction_range_m: 1.2,
            fluctuation_m_s2: 0.1,
            bin_m: 2.0,
            sectors: 8,
            settle_speed_m_s: 0.6,
        }
    }
}

/// Default `subgroups.damping`.
pub const DEFAULT_AP_DAMPING: f64 = 0.7;
/// Default `subgroups.max_iterations`.
pub const DEFAULT_AP_MAX_ITERATIONS: u32 = 500;
/// Default `subgroups.convergence_iterations`.
pub const DEFAULT_AP_CONVERGENCE_ITERATIONS: u32 = 15;
/// Default `subgroups.ring`.
pub const DEFAULT_AP_RING: u32 = 2;
/// Default `subgroups.dense_up_to`.
pub const DEFAULT_AP_DENSE_UP_TO: usize = 300;

/// The similarity of `formations.subgroups` (formation-transform section 3.4).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SubgroupSimilarity {
    /// Eq. 20 plus a spatial term, on the Delaunay ring, small subgroups merged
    /// into neighbours (spatially coherent subgroups).
    #[default]
    Local,
    /// Eq. 20 as written (dense up to `dense_up_to` agents).
    Paper,
}

/// Subgroups by affinity propagation (formation-transform section 3.4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SubgroupsConfig {
    /// Cluster the crowd into subgroups (false: one group).
    pub enabled: bool,
    /// Damping of the messages, in `[0.5, 1)`.
    pub damping: f64,
    /// Most iterations, `1..=10000`.
    pub max_iterations: u32,
    /// Iterations with unchanged exemplars that count as converged, at least 1.
    pub convergence_iterations: u32,
    /// The preference `s(k, k)`; `None`: the smallest candidate similarity (`local`)
    /// or the median similarity (`paper`; Frey & Dueck's default).
    pub preference: Option<f64>,
    /// Candidate pairs of a large crowd: the Delaunay k-ring of each agent, `1..=8`.
    pub ring: u32,
    /// Crowds up to this size use every pair (`paper` similarity only).
    pub dense_up_to: usize,
    /// `local` (default: eq. 20 with a spatial term, coherent subgroups) or `paper`
    /// (eq. 20 as written).
    pub similarity: SubgroupSimilarity,
}

impl Default for SubgroupsConfig {
    fn default() -> Self {
        SubgroupsConfig {
            enabled: true,
            damping: DEFAULT_AP_DAMPING,
            max_iterations: DEFAULT_AP_MAX_ITERATIONS,
            convergence_iterations: DEFAULT_AP_CONVERGENCE_ITERATIONS,
            preference: None,
            ring: DEFAULT_AP_RING,
            dense_up_to: DEFAULT_AP_DENSE_UP_TO,
            similarity: SubgroupSimilarity::Local,
        }
    }
}

/// One entry of `formations.gestures`: a recognised gesture class that starts a
/// transform to a formation instead of playing the gesture's crowd motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GestureFormation {
    /// A class of the gesture library (`twist`, `split`, … in the shipped one;
    /// checked against the library when it loads).
    pub class: String,
    /// A formation name (`start`, a shipped one or one of `formations.shapes`).
    pub formation: String,
}

/// The method a formation request uses when none is named.
pub const DEFAULT_METHOD: FormationMethod = FormationMethod::Transform;

/// Range checks of the transform settings and the gesture map's classes:
/// `(field path, message)` per problem.
pub(super) fn validate_transform(
    mv: &TransformMoveConfig,
    sg: &SubgroupsConfig,
    gestures: &[GestureFormation],
    p: &mut Vec<(String, String)>,
) {
    let mut check = |ok: bool, field: &str, msg: String| {
        if !ok {
            p.push((format!("formations.{field}"), msg));
        }
    };
    let v = mv.desired_speed_m_s;
    check(
        v.is_finite() && v > 0.0 && v <= MAX_DESIRED_SPEED_M_S,
        "transform.desired_speed_m_s",
        format!("desired speed must be in (0, {MAX_DESIRED_SPEED_M_S}] m/s, got {v}"),
    );
    let a = mv.arrive_m;
    check(
        a.is_finite() && a > 0.0 && a <= 1.0,
        "transform.arrive_m",
        format!("arrival distance must be in (0, 1] m, got {a}"),
    );
    let t = mv.timeout_s;
    check(
        t.is_finite() && t > 0.0 && t <= MAX_TIMEOUT_S,
        "transform.timeout_s",
        format!("timeout must be in (0, {MAX_TIMEOUT_S}] s, got {t}"),
    );
    // The force constants: finite, and positive (≥ 0 where zero switches a
    // term off).
    for (field, v, zero_ok) in [
        (
            "desired_speed_spread_m_s",
            mv.desired_speed_spread_m_s,
            true,
        ),
        ("max_speed_m_s", mv.max_speed_m_s, false),
        ("max_accel_m_s2", mv.max_accel_m_s2, false),
        ("tau_s", mv.tau_s, false),
        ("arrival_decel_m_s2", mv.arrival_decel_m_s2, false),
        ("fade_m", mv.fade_m, true),
        ("repulsion_a_m_s2", mv.repulsion_a_m_s2, true),
        ("repulsion_b_m", mv.repulsion_b_m, false),
        ("obstacle_a_m_s2", mv.obstacle_a_m_s2, true),
        ("subgroup_a_m_s2", mv.subgroup_a_m_s2, true),
        ("subgroup_b_m", mv.subgroup_b_m, false),
        ("interaction_range_m", mv.interaction_range_m, false),
        ("fluctuation_m_s2", mv.fluctuation_m_s2, true),
        ("bin_m", mv.bin_m, false),
        ("settle_speed_m_s", mv.settle_speed_m_s, true),
    ] {
        let ok = v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0)) && v <= 1e4;
        check(
            ok,
            &format!("transform.{field}"),
            format!(
                "must be a {} number up to 10000, got {v}",
                if zero_ok { "non-negative" } else { "positive" }
            ),
        );
    }
    check(
        (2..=64).contains(&mv.sectors),
        "transform.sectors",
        format!("sectors must be 2..=64, got {}", mv.sectors),
    );
    let d = sg.damping;
    check(
        (0.5..1.0).contains(&d),
        "subgroups.damping",
        format!("damping must be in [0.5, 1), got {d}"),
    );
    check(
        (1..=10_000).contains(&sg.max_iterations),
        "subgroups.max_iterations",
        format!(
            "most iterations must be 1..=10000, got {}",
            sg.max_iterations
        ),
    );
    check(
        sg.convergence_iterations >= 1 && sg.convergence_iterations <= sg.max_iterations,
        "subgroups.convergence_iterations",
        format!(
            "convergence iterations must be 1..=max_iterations ({}), got {}",
            sg.max_iterations, sg.convergence_iterations
        ),
    );
    if let Some(pref) = sg.preference {
        check(
            pref.is_finite(),
            "subgroups.preference",
            format!("preference must be a finite number (None: the median similarity), got {pref}"),
        );
    }
    check(
        (1..=8).contains(&sg.ring),
        "subgroups.ring",
        format!("ring must be 1..=8, got {}", sg.ring),
    );
    for (k, g) in gestures.iter().enumerate() {
        if let Err(e) = crate::gesture::library::check_class_name(&g.class) {
            check(false, &format!("gestures[{k}].class"), e.to_string());
        } else if let Some(j) = gestures[..k].iter().position(|o| o.class == g.class) {
            check(
                false,
                &format!("gestures[{k}].class"),
                format!(
                    "gesture class `{}` is mapped twice (also gestures[{j}])",
                    g.class
                ),
            );
        }
    }
}

/// The classes of the gesture map and of `gestures.disabled` that the library
/// (its class table `classes`) does not have, and classes both mapped and
/// disabled, as `(field path, message)`.
pub(super) fn check_gesture_classes(
    gestures: &[GestureFormation],
    disabled: &[String],
    classes: &[String],
    library: &str,
) -> Vec<(String, String)> {
    let known = |c: &str| classes.iter().any(|k| k == c);
    let list = classes.join(", ");
    let mut p = Vec::new();
    for (k, g) in gestures.iter().enumerate() {
        if !known(&g.class) {
            p.push((
                format!("formations.gestures[{k}].class"),
                format!(
                    "the gesture library {library} has no class `{}`; its classes are {list}",
                    g.class
                ),
            ));
        }
    }
    for (k, d) in disabled.iter().enumerate() {
        if !known(d) {
            p.push((
                format!("gestures.disabled[{k}]"),
                format!("the gesture library {library} has no class `{d}`; its classes are {list}"),
            ));
        } else if let Some(j) = gestures.iter().position(|g| &g.class == d) {
            p.push((
                format!("gestures.disabled[{k}]"),
                format!(
                    "class `{d}` is disabled and also mapped to formation `{}` (formations.gestures[{j}]); keep one",
                    gestures[j].formation
                ),
            ));
        }
    }
    p
}

/// The gesture map's formation names that the config does not define, as
/// `(field path, message)`; `known` is every formation name (`start` first).
pub(super) fn check_gesture_formations(
    gestures: &[GestureFormation],
    known: &[&str],
) -> Vec<(String, String)> {
    gestures
        .iter()
        .enumerate()
        .filter(|(_, g)| !known.contains(&g.formation.as_str()))
        .map(|(k, g)| {
            (
                format!("formations.gestures[{k}].formation"),
                format!(
                    "no formation is called `{}`; the config defines {}",
                    g.formation,
                    known.join(", ")
                ),
            )
        })
        .collect()
}
