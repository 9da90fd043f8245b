//! The `gestures` section: gesture commands (gesture-driven-crowd-motion). A gesture
//! drawn in open space is captured, recognised against a library of gestures paired
//! with crowd motions (K nearest neighbours by weighted DTW, sections 5 and 7.1), and
//! the blended motion is synthesised for the crowd (sections 6 and 7).
//!
//! The whole section may be left out (`#[serde(default)]`): a config written before
//! it existed gets [`GesturesConfig::default`].

use crate::gesture::library::T_H;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Gesture commands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GesturesConfig {
    /// Recognise gestures and play the crowd motion they name (false: gestures are
    /// only published as `gesture` events).
    pub enabled: bool,
    /// The library file (`.ctgl`), relative to the config file; `None`: the shipped
    /// library embedded in the binary. Read at start and on every SIGHUP; a file that
    /// does not load leaves the running library in use.
    pub library: Option<PathBuf>,
    /// Classes of the library that are recognised but ignored: their `gesture`
    /// event carries the recognition and `rejected: "class_disabled"`, and no
    /// crowd motion plays. Each must be a class of the library (checked when the
    /// library loads), named once, and not also mapped by `formations.gestures`.
    pub disabled: Vec<String>,
    /// Every touch is a gesture, wherever it lands (a table with no direct control).
    pub all_touches_are_gestures: bool,
    /// Shorter gestures (first touch to last lift) are taps, ignored (ms).
    pub min_duration_ms: u64,
    /// A gesture whose every finger stays within this distance of where it landed is
    /// a tap, ignored (mm of glass).
    pub min_travel_mm: f64,
    /// Longer gestures are captured (decimated) but not recognised: a hand resting
    /// on the table is not a command (s).
    pub max_duration_s: f64,
    /// Neighbours a recognition weighs, K (section 7.1).
    pub k: u32,
    /// Weights of the four gesture features in the distance (eq. 12).
    pub weights: GestureWeights,
    /// Sakoe–Chiba half-width of the DTW warping path, in resampled samples
    /// (0..=64); `None`: unconstrained, the paper's DTW.
    pub band: Option<u32>,
    /// Gaussians in each motion's eigenscore mixture (section 6.2) when a library
    /// is built with `library build --config`; a loaded library keeps the
    /// mixtures it was built with.
    pub gmm_components: u32,
    /// When set, each motion's mixture takes the number of Gaussians in
    /// `gmm_components ..= auto_components_max` with the best penalised likelihood.
    pub auto_components_max: Option<u32>,
    /// Seed of the eigenscore sampling and the mixtures' fitting (fixed: the same
    /// gesture on the same crowd gives the same motion).
    pub seed: u64,
    /// Longest the agents walk to their trajectories' starts before the motion
    /// begins anyway (s).
    pub approach_timeout_s: f64,
    /// How fast a motion plays: its duration is the longest agent path divided by
    /// this speed, so the agent that travels farthest walks at about it (m/s; at most
    /// `crowd.max_speed_m_s`, so agents keep up). At 1.0 a motion of the crowd's own
    /// size (a 4 m crowd moved by its width, turned a quarter, doubled) plays in
    /// 2–5 s.
    pub motion_speed_m_s: f64,
    /// Recognition while a long gesture goes on (a sliding window); `None`: only
    /// when the gesture ends.
    pub continuous: Option<ContinuousConfig>,
    /// Gestures people drew (`library collect`, `library add --participant`)
    /// against the generated ones, the cold start: `Weigh(w)` makes each such
    /// neighbour count `w` times (1 ..= 100) in the vote and the blend;
    /// `Replace` recognises a class that has people's gestures from those alone.
    pub collected: Collected,
    /// How a recognised motion moves the crowd: `keep_formation` applies the
    /// motion's translation, turn and scale (each part's, for a split or a crowd in
    /// several parts) to the formation as it stands, with a bounded residual;
    /// `as_sampled` is the paper's section 7.3 (agents walk to trajectory starts
    /// sampled from the motion, then along them), which reshapes the crowd.
    pub apply: GestureApply,
    /// The mesh rebuilt after a motion has no piece of fewer agents: a smaller part
    /// (a straggler) joins the nearest part (1..=1000).
    pub min_piece_agents: u32,
}

/// How a gesture's motion moves the crowd (`gestures.apply`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GestureApply {
    /// The motion's group part applied to the formation as it stands.
    #[default]
    KeepFormation,
    /// Agents walk to sampled trajectory starts, then along the trajectories.
    AsSampled,
}

/// Default `min_piece_agents`.
pub const DEFAULT_MIN_PIECE_AGENTS: u32 = 5;

/// How gestures people drew count against generated ones (`gestures.collected`).
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Collected {
    /// Each collected neighbour's weight (eq. 18) is multiplied by this, then the
    /// weights renormalised.
    Weigh(f64),
    /// A class with collected gestures is recognised from them alone.
    Replace,
}

/// Default `gestures.collected`: a person's gesture counts twice a generated one.
pub const DEFAULT_COLLECTED: Collected = Collected::Weigh(2.0);
/// Largest `Weigh` of `gestures.collected`.
pub const MAX_COLLECTED_WEIGHT: f64 = 100.0;

/// Default `min_duration_ms`.
pub const DEFAULT_MIN_DURATION_MS: u64 = 150;
/// Default `min_travel_mm`.
pub const DEFAULT_MIN_TRAVEL_MM: f64 = 10.0;
/// Default `max_duration_s`.
pub const DEFAULT_MAX_DURATION_S: f64 = 60.0;
/// Default `k` (section 7.1).
pub const DEFAULT_K: u32 = 10;
/// Default `gmm_components` (section 6.2).
pub const DEFAULT_GMM_COMPONENTS: u32 = 2;
/// Most Gaussians a motion's mixture may have.
pub const MAX_GMM_COMPONENTS: u32 = 8;
/// Default `approach_timeout_s`.
pub const DEFAULT_APPROACH_TIMEOUT_S: f64 = 3.0;
/// Default `motion_speed_m_s`.
pub const DEFAULT_MOTION_SPEED_M_S: f64 = 1.0;
/// Most neighbours `k` may ask for.
pub const MAX_K: u32 = 100;

impl Default for GesturesConfig {
    fn default() -> Self {
        GesturesConfig {
            enabled: true,
            library: None,
            disabled: Vec::new(),
            all_touches_are_gestures: false,
            min_duration_ms: DEFAULT_MIN_DURATION_MS,
            min_travel_mm: DEFAULT_MIN_TRAVEL_MM,
            max_duration_s: DEFAULT_MAX_DURATION_S,
            k: DEFAULT_K,
            weights: GestureWeights::default(),
            band: None,
            gmm_components: DEFAULT_GMM_COMPONENTS,
            auto_components_max: None,
            seed: 15,
            approach_timeout_s: DEFAULT_APPROACH_TIMEOUT_S,
            motion_speed_m_s: DEFAULT_MOTION_SPEED_M_S,
            continuous: None,
            collected: DEFAULT_COLLECTED,
            apply: GestureApply::KeepFormation,
            min_piece_agents: DEFAULT_MIN_PIECE_AGENTS,
        }
    }
}

/// Weights of the gesture features in the distance (gesture-driven eq. 12): centroid
/// α, spread β, rotation γ, bounding box δ. Each at least 0, their sum positive; only
/// their ratios matter.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GestureWeights {
    /// α, the centroid's path C(G).
    pub alpha: f64,
    /// β, the spread S(G).
    pub beta: f64,
    /// γ, the cumulative rotation R(G).
    pub gamma: f64,
    /// δ, the minimum oriented bounding box B(G).
    pub delta: f64,
}

impl Default for GestureWeights {
    /// The paper's weights (section 5.3): α 0.04, β 0.36, γ 0.36, δ 0.24.
    fn default() -> Self {
        GestureWeights {
            alpha: 0.04,
            beta: 0.36,
            gamma: 0.36,
            delta: 0.24,
        }
    }
}

/// The sliding-window recogniser of long gestures (gesture-driven section 10).
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContinuousConfig {
    /// The window of the gesture recognised each time: its last this many ms.
    pub window_ms: u64,
    /// A class fires when it stays ahead for this long (ms).
    pub hold_ms: u64,
}

impl GesturesConfig {
    /// Range checks, as `(field path, message)` pairs pushed to `p`;
    /// `max_speed_m_s` is `crowd.max_speed_m_s` when that is valid (`None`: it is
    /// reported at its own field, and `motion_speed_m_s` is only checked positive).
    pub(super) fn validate_into(&self, max_speed_m_s: Option<f64>, p: &mut Vec<(String, String)>) {
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                p.push((format!("gestures.{field}"), msg));
            }
        };
        if let Some(l) = &self.library {
            check(
                !l.as_os_str().is_empty(),
                "library",
                "library path is empty (None uses the shipped library)".to_string(),
            );
        }
        for (k, name) in self.disabled.iter().enumerate() {
            if let Err(e) = crate::gesture::library::check_class_name(name) {
                check(false, &format!("disabled[{k}]"), e.to_string());
            } else if let Some(j) = self.disabled[..k].iter().position(|o| o == name) {
                check(
                    false,
                    &format!("disabled[{k}]"),
                    format!("class `{name}` is disabled twice (also disabled[{j}])"),
                );
            }
        }
        check(
            self.min_duration_ms <= 10_000,
            "min_duration_ms",
            format!(
                "minimum gesture duration must be at most 10000 ms, got {}",
                self.min_duration_ms
            ),
        );
        check(
            (0.0..=1000.0).contains(&self.min_travel_mm),
            "min_travel_mm",
            format!(
                "minimum travel must be in [0, 1000] mm, got {}",
                self.min_travel_mm
            ),
        );
        let max_ok = self.max_duration_s.is_finite()
            && self.max_duration_s > 0.0
            && self.max_duration_s <= 3600.0;
        check(
            max_ok,
            "max_duration_s",
            format!(
                "maximum gesture duration must be in (0, 3600] s, got {}",
                self.max_duration_s
            ),
        );
        if max_ok {
            check(
                self.max_duration_s * 1000.0 > self.min_duration_ms as f64,
                "max_duration_s",
                format!(
                    "maximum gesture duration {} s is not longer than min_duration_ms {} ms",
                    self.max_duration_s, self.min_duration_ms
                ),
            );
        }
        check(
            (1..=1000).contains(&self.min_piece_agents),
            "min_piece_agents",
            format!(
                "the smallest mesh piece must be 1..=1000 agents, got {}",
                self.min_piece_agents
            ),
        );
        check(
            (1..=MAX_K).contains(&self.k),
            "k",
            format!("neighbours must be 1..={MAX_K}, got {}", self.k),
        );
        let w = &self.weights;
        let all = [w.alpha, w.beta, w.gamma, w.delta];
        for (name, v) in ["alpha", "beta", "gamma", "delta"].into_iter().zip(all) {
            check(
                v.is_finite() && v >= 0.0,
                &format!("weights.{name}"),
                format!("a feature weight must be zero or positive, got {v}"),
            );
        }
        if all.iter().all(|v| v.is_finite() && *v >= 0.0) {
            check(
                all.iter().sum::<f64>() > 0.0,
                "weights",
                "the feature weights sum to zero: at least one must be positive".to_string(),
            );
        }
        if let Some(b) = self.band {
            check(
                b as usize <= T_H,
                "band",
                format!("band half-width must be 0..={T_H} samples (None: no band), got {b}"),
            );
        }
        check(
            (1..=MAX_GMM_COMPONENTS).contains(&self.gmm_components),
            "gmm_components",
            format!(
                "mixture components must be 1..={MAX_GMM_COMPONENTS}, got {}",
                self.gmm_components
            ),
        );
        if let Some(m) = self.auto_components_max {
            check(
                (self.gmm_components..=MAX_GMM_COMPONENTS).contains(&m),
                "auto_components_max",
                format!(
                    "most mixture components must be gmm_components ({})..={MAX_GMM_COMPONENTS}, got {m}",
                    self.gmm_components
                ),
            );
        }
        check(
            self.approach_timeout_s.is_finite()
                && self.approach_timeout_s > 0.0
                && self.approach_timeout_s <= 60.0,
            "approach_timeout_s",
            format!(
                "approach timeout must be in (0, 60] s, got {}",
                self.approach_timeout_s
            ),
        );
        let v = self.motion_speed_m_s;
        let limit = max_speed_m_s.unwrap_or(f64::INFINITY);
        check(
            v.is_finite() && v > 0.0 && v <= limit,
            "motion_speed_m_s",
            match max_speed_m_s {
                Some(m) => format!(
                    "motion speed must be positive and at most crowd.max_speed_m_s ({m} m/s), got {v}"
                ),
                None => format!("motion speed must be positive, got {v}"),
            },
        );
        if let Collected::Weigh(w) = self.collected {
            check(
                w.is_finite() && (1.0..=MAX_COLLECTED_WEIGHT).contains(&w),
                "collected",
                format!(
                    "a collected gesture's weight must be in 1..={MAX_COLLECTED_WEIGHT}, got {w}"
                ),
            );
        }
        if let Some(c) = self.continuous {
            check(
                (100..=10_000).contains(&c.window_ms),
                "continuous.window_ms",
                format!(
                    "recognition window must be 100..=10000 ms, got {}",
                    c.window_ms
                ),
            );
            check(
                c.hold_ms <= 10_000,
                "continuous.hold_ms",
                format!("hold time must be at most 10000 ms, got {}", c.hold_ms),
            );
        }
    }
}
