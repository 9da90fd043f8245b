//! A gesture command, end to end off the control thread: recognise the gesture
//! against the library (gesture-driven sections 5, 7.1), blend the crowd motions of
//! its neighbours (section 7.2) and synthesise trajectories for the crowd at hand,
//! matched to the agents by optimal assignment (section 7.3).
//!
//! The engine builds a [`GestureRequest`] when a gesture ends; the daemon's worker
//! (or the engine itself in a replay) calls [`GestureRequest::prepare`], and the
//! engine plays the [`PreparedGesture`] with a [`Follower`](super::Follower).
//!
//! # Orientation
//!
//! Eq. 12 weighs direction only through the centroid feature (α = 0.04), so the K
//! nearest translates of a swipe to the right may be library translates to the
//! right, up and left alike; blended as they are, their directions would average
//! out. Section 7.3 places the motion "relative to the crowd"; here each
//! neighbour's motion is also *turned to the gesture drawn* before the blend: by
//! the rotation that best maps the neighbour's gesture onto the drawn one (2-D
//! Procrustes of their centred centroid paths; for gestures whose centroid hardly
//! moves — twists, pinches, joins — of their fingers' principal axes, modulo a half
//! turn). A rotation is linear, so it turns the mean trajectory and every
//! eigenvector pair by pair, keeps the basis orthonormal and leaves the
//! eigenscores' mixture as it is.
//!
//! One choice differs from the paper: section 7.2 blends the motions of all K
//! neighbours. Here only the neighbours that voted for the recognised class are
//! blended (their eq. 18 weights renormalised): a minority neighbour of another
//! class (a contract among expands) would otherwise pull a motion of the wrong kind
//! into the blend. With a unanimous vote the two are the same.

use super::blend::blend;
use super::error::MotionError;
use super::keep::{
    is_split_class, keep_formation, parts_of, ApplyMode, KeepParams, GROUP_GAP_FACTOR,
};
use super::synth::{Placement, Synthesis, Synthesiser};
use crate::crowd::mesh::{mesh_around_parts, GoalSample, MeshError, TriMesh};
use crate::geom::Vec2;
use crate::gesture::continuous::{recognise_window, WindowBuffers, WindowParams};
use crate::gesture::features::GestureFeatures;
use crate::gesture::knn::{SearchParams, Searcher};
use crate::gesture::library::{ClassId, MotionFeatures};
use crate::gesture::library::{Resampled, T_H};
use crate::gesture::recognise::{RecogniseError, Recognised, Recogniser};
use crate::gesture::reject::Movement;
use crate::gesture::resample::prepare_scaled;
use crate::gesture::track::GestureTracks;
use crate::vocab::Micros;
use std::sync::Arc;

/// Slowest and fastest a synthesised motion plays (s), whatever its length.
pub const MOTION_DURATION_S: (f64, f64) = (1.0, 20.0);

/// A gesture to turn into a crowd motion.
#[derive(Clone, Debug)]
pub struct GestureRequest {
    /// The gesture's id.
    pub id: u32,
    /// The engine's gesture epoch when asked (a result of another epoch is stale).
    pub epoch: u64,
    /// The gesture's tracks (mm of glass).
    pub tracks: GestureTracks,
    /// Where the agents are (m).
    pub agents: Vec<Vec2>,
    /// The library.
    pub recogniser: Arc<Recogniser>,
    /// K, eq. 12's weights, the band.
    pub search: SearchParams,
    /// Seed of the eigenscores sampled for this crowd.
    pub seed: u64,
    /// How fast agents walk a synthesised motion (m/s): the motion lasts as long as
    /// its longest trajectory takes at this speed (within [`MOTION_DURATION_S`]).
    pub speed_m_s: f64,
    /// How the motion moves the crowd (`gestures.apply`).
    pub apply: ApplyMode,
    /// The residual's bound, the smallest part and the body radius for
    /// [`ApplyMode::KeepFormation`].
    pub keep: KeepParams,
}

/// A gesture recognised and its crowd motion synthesised.
#[derive(Clone, Debug)]
pub struct GestureMotion {
    /// What the gesture was recognised as.
    pub recognised: Recognised,
    /// The recognised class's name in the library that recognised it.
    pub class_name: String,
    /// Each neighbour's class name and origin, in `recognised.neighbours`' order.
    pub neighbours: Vec<(String, String)>,
    /// One trajectory per agent (m) and how long it plays (s).
    pub synthesis: Synthesis,
    /// With [`ApplyMode::KeepFormation`], the parts of the crowd that move together
    /// (agent indices) and each agent's planned end (m), for the mesh rebuilt
    /// afterwards; empty when the motion is played as sampled.
    pub parts: Vec<Vec<usize>>,
    /// Each agent's planned end (m); empty as sampled.
    pub ends_m: Vec<Vec2>,
}

/// Why a gesture gave no crowd motion.
#[derive(Debug, thiserror::Error)]
pub enum GestureCommandError {
    /// Not recognised.
    #[error("not recognised: {0}")]
    Recognise(#[from] RecogniseError),
    /// The neighbours' motions could not be blended or synthesised.
    #[error("no crowd motion: {0}")]
    Motion(#[from] MotionError),
    /// No agents to move.
    #[error("no agents to move")]
    NoAgents,
}

impl GestureCommandError {
    /// The reason as the `gesture` event's `rejected` field names it
    /// (docs/protocol.md): `still`, `weak_vote` or `far` for a gesture the
    /// recogniser rejects, `not_recognised` for one it cannot compare,
    /// `no_library`, `no_motion`, `no_agents`.
    pub fn reason(&self) -> &'static str {
        match self {
            GestureCommandError::Recognise(RecogniseError::Rejected(r)) => r.as_str(),
            GestureCommandError::Recognise(RecogniseError::Gesture(_)) => "not_recognised",
            GestureCommandError::Recognise(RecogniseError::EmptyLibrary) => "no_library",
            GestureCommandError::Motion(_) => "no_motion",
            GestureCommandError::NoAgents => "no_agents",
        }
    }
}

/// The outcome of a [`GestureRequest`].
#[derive(Debug)]
pub struct PreparedGesture {
    /// The gesture's id.
    pub id: u32,
    /// The epoch it was asked in.
    pub epoch: u64,
    /// The motion, or why there is none.
    pub outcome: Result<GestureMotion, GestureCommandError>,
}

impl GestureRequest {
    /// Recognises, blends and synthesises (see the module doc), reusing `searcher`
    /// and `synth`.
    pub fn prepare(self, searcher: &mut Searcher, synth: &mut Synthesiser) -> PreparedGesture {
        let outcome = self.run(searcher, synth);
        PreparedGesture {
            id: self.id,
            epoch: self.epoch,
            outcome,
        }
    }

    fn run(
        &self,
        searcher: &mut Searcher,
        synth: &mut Synthesiser,
    ) -> Result<GestureMotion, GestureCommandError> {
        if self.agents.is_empty() {
            return Err(GestureCommandError::NoAgents);
        }
        let rec = &self.recogniser;
        let (drawn, scale_mm) = prepare_scaled(&self.tracks).map_err(RecogniseError::from)?;
        let movement = Movement::of(&self.tracks);
        let c = rec.classify_prepared(&drawn, scale_mm, &movement, &self.search, searcher)?;
        if let Some(r) = c.rejection {
            return Err(RecogniseError::Rejected(r).into());
        }
        let recognised = c.recognised;
        let lib = rec.library();
        let neighbours: Vec<(String, String)> = recognised
            .neighbours
            .iter()
            .map(|n| {
                let g = &lib.gestures[n.entry];
                (lib.class_name(g.class).to_string(), g.origin.clone())
            })
            .collect();
        // Section 7.2 with the voted class's neighbours (module doc).
        let mut turned: Vec<(MotionFeatures, f64)> = Vec::new();
        for n in &recognised.neighbours {
            let g = &lib.gestures[n.entry];
            if g.class != recognised.class {
                continue;
            }
            // A neighbour drawn turning the other way (the recogniser's distance
            // does not tell the two apart) gives its motion mirrored: the
            // direction of a turn comes from the gesture drawn.
            let motion = &lib.motions[g.motion as usize];
            let (motion, theta) = if opposite_turns(&g.gesture, &drawn) {
                let flipped = mirrored_gesture(&g.gesture);
                (mirrored(motion), alignment(&flipped, &drawn))
            } else {
                (motion.clone(), alignment(&g.gesture, &drawn))
            };
            turned.push((rotated(&motion, theta), n.weight));
        }
        let mut parts: Vec<(&MotionFeatures, f64)> = turned.iter().map(|(m, w)| (m, *w)).collect();
        let total: f64 = parts.iter().map(|p| p.1).sum();
        if total > 0.0 {
            for p in &mut parts {
                p.1 /= total;
            }
        } else {
            let w = 1.0 / parts.len().max(1) as f64;
            for p in &mut parts {
                p.1 = w;
            }
        }
        let motion = blend(&parts)?;
        let placement = Placement::for_crowd(&self.agents);
        let synthesis = synth.synthesise(&motion, &self.agents, &placement, self.seed)?;
        let class_name = lib.class_name(recognised.class).to_string();
        let (mut synthesis, parts, ends_m) = match self.apply {
            ApplyMode::AsSampled => (synthesis, Vec::new(), Vec::new()),
            ApplyMode::KeepFormation => {
                let kept = keep_formation(
                    &synthesis,
                    &self.agents,
                    is_split_class(&class_name),
                    &self.keep,
                );
                let ends = kept
                    .synthesis
                    .trajectories
                    .iter()
                    .map(|t| t[crate::gesture::library::S_H - 1])
                    .collect();
                (kept.synthesis, kept.parts, ends)
            }
        };
        synthesis.duration_s = play_duration(&synthesis, self.speed_m_s);
        Ok(GestureMotion {
            class_name,
            recognised,
            neighbours,
            synthesis,
            parts,
            ends_m,
        })
    }
}

/// A centroid path whose RMS distance from its mean is below this (normalised
/// gesture units) hardly moves: the fingers' axes orient the gesture instead.
pub const STILL_CENTROID: f64 = 0.08;

/// The rotation (rad, the glass's and the world's x towards y) that best maps
/// gesture `from` onto gesture `to` (module doc).
pub fn alignment(from: &Resampled, to: &Resampled) -> f64 {
    let path = |g: &Resampled| -> Vec<Vec2> {
        let n = g.fingers.len().max(1) as f64;
        let c: Vec<Vec2> = (0..T_H)
            .map(|t| g.fingers.iter().map(|f| f[t]).sum::<Vec2>() / n)
            .collect();
        let mean = c.iter().sum::<Vec2>() / T_H as f64;
        c.into_iter().map(|p| p - mean).collect()
    };
    let (a, b) = (path(from), path(to));
    let rms =
        |v: &[Vec2]| (v.iter().map(|p| p.norm_squared()).sum::<f64>() / v.len() as f64).sqrt();
    if rms(&a) >= STILL_CENTROID && rms(&b) >= STILL_CENTROID {
        // Kabsch in 2-D: the angle maximising Σ b·R(θ)a.
        let (s, c) = a.iter().zip(&b).fold((0.0, 0.0), |(s, c), (p, q)| {
            (s + (p.x * q.y - p.y * q.x), c + p.dot(q))
        });
        return s.atan2(c);
    }
    // The principal axis of the fingers about their centroid, over the whole gesture.
    let axis = |g: &Resampled| -> Option<f64> {
        let n = g.fingers.len() as f64;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for t in 0..T_H {
            let c = g.fingers.iter().map(|f| f[t]).sum::<Vec2>() / n;
            for f in &g.fingers {
                let d = f[t] - c;
                sxx += d.x * d.x;
                sxy += d.x * d.y;
                syy += d.y * d.y;
            }
        }
        let strength = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
        (strength > 1e-9 * (sxx + syy).max(1e-300)).then(|| 0.5 * (2.0 * sxy).atan2(sxx - syy))
    };
    match (axis(from), axis(to)) {
        (Some(p), Some(q)) => {
            // Axes have no direction: the turn within a quarter turn either way.
            let mut d = q - p;
            while d > std::f64::consts::FRAC_PI_2 {
                d -= std::f64::consts::PI;
            }
            while d < -std::f64::consts::FRAC_PI_2 {
                d += std::f64::consts::PI;
            }
            d
        }
        _ => 0.0,
    }
}

/// The least net turn (rad) of a gesture whose direction counts: below it, in
/// either gesture, nothing is mirrored (a bowed stroke, a wobbling pinch).
pub const MIRROR_MIN_TURN_RAD: f64 = std::f64::consts::FRAC_PI_6;

/// Whether `a` and `b` turn clearly in opposite directions: the net cumulative
/// rotation of eq. 9 (`GestureFeatures::rotation`: the fingers about their
/// centroid, or one finger's path) of each is at least
/// [`MIRROR_MIN_TURN_RAD`], with opposite signs.
pub fn opposite_turns(a: &Resampled, b: &Resampled) -> bool {
    let net = |g: &Resampled| GestureFeatures::of(g).rotation[T_H - 1];
    let (ra, rb) = (net(a), net(b));
    ra.abs() >= MIRROR_MIN_TURN_RAD && rb.abs() >= MIRROR_MIN_TURN_RAD && ra * rb < 0.0
}

/// `g` reflected top to bottom (`y ↦ 1 − y` in its normalised square): it turns
/// the other way.
pub fn mirrored_gesture(g: &Resampled) -> Resampled {
    Resampled {
        fingers: g
            .fingers
            .iter()
            .map(|f| {
                let mut m = *f;
                for p in m.iter_mut() {
                    p.y = 1.0 - p.y;
                }
                m
            })
            .collect(),
    }
}

/// `m` reflected across the x axis of crowd units (`y ↦ −y` in the mean trajectory
/// and every eigenvector): the same motion turning the other way. The basis stays
/// orthonormal and the eigenscores' mixture applies unchanged.
pub fn mirrored(m: &MotionFeatures) -> MotionFeatures {
    let flip = |v: &[f64]| -> Vec<f64> {
        let mut out = v.to_vec();
        for k in 0..v.len() / 2 {
            out[2 * k + 1] = -v[2 * k + 1];
        }
        out
    };
    MotionFeatures {
        class: m.class,
        duration_s: m.duration_s,
        mean: flip(&m.mean),
        basis: m.basis.iter().map(|b| flip(b)).collect(),
        gmm: m.gmm.clone(),
    }
}

/// `m` turned by `theta` (rad) about the crowd's starting centroid (the origin of
/// crowd units): the mean trajectory and every eigenvector, pair by pair.
pub fn rotated(m: &MotionFeatures, theta: f64) -> MotionFeatures {
    let (s, c) = theta.sin_cos();
    let turn = |v: &[f64]| -> Vec<f64> {
        let mut out = v.to_vec();
        for k in 0..v.len() / 2 {
            let (x, y) = (v[2 * k], v[2 * k + 1]);
            out[2 * k] = c * x - s * y;
            out[2 * k + 1] = s * x + c * y;
        }
        out
    };
    MotionFeatures {
        class: m.class,
        duration_s: m.duration_s,
        mean: turn(&m.mean),
        basis: m.basis.iter().map(|b| turn(b)).collect(),
        gmm: m.gmm.clone(),
    }
}

/// How long a synthesis plays at `speed_m_s`: its longest trajectory's length over
/// the speed, within [`MOTION_DURATION_S`].
pub fn play_duration(s: &Synthesis, speed_m_s: f64) -> f64 {
    let longest = s
        .trajectories
        .iter()
        .map(|t| t.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>())
        .fold(0.0, f64::max);
    let d = longest / speed_m_s.max(1e-3);
    if d.is_finite() {
        d.clamp(MOTION_DURATION_S.0, MOTION_DURATION_S.1)
    } else {
        MOTION_DURATION_S.0
    }
}

/// A mesh to rebuild around the crowd after a gesture motion, so that direct touch
/// control goes on from there (`crate::crowd::mesh::mesh_around_parts`): around
/// where the agents stopped, or, for a motion that kept the formation, around
/// where it planned them (the formation moved, not the scatter the push-apart
/// left), one piece per part.
#[derive(Clone, Debug)]
pub struct RemeshRequest {
    /// The engine's gesture epoch when asked.
    pub epoch: u64,
    /// Where the mesh's goals go, one per agent (m).
    pub agents: Vec<Vec2>,
    /// The parts, each its own piece (agent indices); empty: the parts of
    /// `agents` by proximity ([`GROUP_GAP_FACTOR`] spacings).
    pub parts: Vec<Vec<usize>>,
    /// Agent radius (m): the mesh's spacing floor.
    pub radius_m: f64,
    /// No piece has fewer agents: smaller parts join the nearest. 0: the pieces
    /// [`crate::crowd::mesh::mesh_around`] finds, stragglers included (and `parts`
    /// ignored).
    pub min_piece_agents: usize,
}

/// A rebuilt mesh with one goal per agent at its vertex, or why there is none.
#[derive(Debug)]
pub struct PreparedRemesh {
    /// The epoch it was asked in.
    pub epoch: u64,
    /// The mesh and its goal samples (goal `i` is agent `i`'s position).
    pub built: Result<(TriMesh, Vec<GoalSample>), MeshError>,
}

impl RemeshRequest {
    /// Builds the mesh.
    pub fn prepare(self) -> PreparedRemesh {
        if self.min_piece_agents == 0 {
            return PreparedRemesh {
                epoch: self.epoch,
                built: crate::crowd::mesh::mesh_around(&self.agents, self.radius_m),
            };
        }
        let parts = if self.parts.is_empty() {
            let floor = (2.0 * self.radius_m).max(1e-3);
            let gap = GROUP_GAP_FACTOR * median_spacing(&self.agents, floor);
            parts_of(&self.agents, gap, self.min_piece_agents)
        } else {
            self.parts
        };
        PreparedRemesh {
            epoch: self.epoch,
            built: mesh_around_parts(&self.agents, &parts, self.radius_m, self.min_piece_agents),
        }
    }
}

/// The median nearest-neighbour distance of `pts`, at least `floor_m` (O(n²); a
/// strided sample of 2,000 points beyond that).
fn median_spacing(pts: &[Vec2], floor_m: f64) -> f64 {
    let stride = pts.len().div_ceil(2000).max(1);
    let mut nn: Vec<f64> = (0..pts.len())
        .step_by(stride)
        .map(|i| {
            (0..pts.len())
                .filter(|&j| j != i)
                .map(|j| (pts[j] - pts[i]).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .filter(|d| d.is_finite())
        .collect();
    if nn.is_empty() {
        return floor_m;
    }
    nn.sort_by(f64::total_cmp);
    nn[nn.len() / 2].max(floor_m)
}

/// A live gesture's latest window to recognise (continuous recognition,
/// `crate::gesture::continuous`).
#[derive(Clone, Debug)]
pub struct WindowRequest {
    /// The gesture's id.
    pub id: u32,
    /// The engine's gesture epoch when asked.
    pub epoch: u64,
    /// The window's end: the tick that asked (µs).
    pub at: Micros,
    /// The gesture's tracks so far (mm of glass).
    pub tracks: GestureTracks,
    /// The library.
    pub recogniser: Arc<Recogniser>,
    /// The window's length, its stillness threshold and the search.
    pub params: WindowParams,
}

/// A window recognised.
#[derive(Debug)]
pub struct PreparedWindow {
    /// The gesture's id.
    pub id: u32,
    /// The epoch it was asked in.
    pub epoch: u64,
    /// The window's end (µs).
    pub at: Micros,
    /// The weighted vote, if the window was recognised.
    pub vote: Option<(ClassId, f64)>,
    /// The window's tracks (to synthesise from when the vote fires).
    pub cut: GestureTracks,
}

impl WindowRequest {
    /// Recognises the window, reusing `buf`.
    pub fn prepare(self, buf: &mut WindowBuffers) -> PreparedWindow {
        let rec = &self.recogniser;
        let vote = recognise_window(
            &self.tracks,
            self.at,
            &self.params,
            rec.index(),
            |e| rec.class_of(e),
            buf,
        )
        .vote();
        PreparedWindow {
            id: self.id,
            epoch: self.epoch,
            at: self.at,
            vote,
            cut: buf.cut.clone(),
        }
    }
}

/// Slow work of gesture commands, for a worker.
#[derive(Clone, Debug)]
pub enum GestureJob {
    /// Recognise a live gesture's latest window.
    Window(WindowRequest),
    /// Recognise a gesture and synthesise its crowd motion.
    Recognise(GestureRequest),
    /// Rebuild the direct-control mesh around the crowd.
    Remesh(RemeshRequest),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::motion::features::tests::split_motion;
    use crate::crowd::motion::{features, FeatureParams};
    use crate::gesture::library::MotionClass;

    /// One finger around a circle of `turns` (positive: x towards y).
    fn circle(turns: f64) -> Resampled {
        let mut f = [Vec2::zeros(); T_H];
        for (t, p) in f.iter_mut().enumerate() {
            let a = turns * std::f64::consts::TAU * t as f64 / (T_H - 1) as f64;
            *p = Vec2::new(0.5 + 0.4 * a.cos(), 0.5 + 0.4 * a.sin());
        }
        Resampled { fingers: vec![f] }
    }

    #[test]
    fn turns_count_as_opposite_only_when_both_clearly_turn() {
        assert!(opposite_turns(&circle(0.75), &circle(-0.75)));
        assert!(!opposite_turns(&circle(0.75), &circle(0.6)));
        // A slight bow is no direction.
        assert!(!opposite_turns(&circle(0.75), &circle(-0.05)));
        // Mirroring a gesture turns it the other way.
        assert!(opposite_turns(
            &circle(0.75),
            &mirrored_gesture(&circle(0.75))
        ));
        assert!(!opposite_turns(
            &circle(-0.5),
            &mirrored_gesture(&circle(0.5))
        ));
    }

    #[test]
    fn a_mirrored_motion_is_reflected_and_mirroring_twice_gives_it_back() {
        let m = features(
            MotionClass::Split.id(),
            &split_motion(30, 2.0, 2),
            &FeatureParams::default(),
        )
        .unwrap();
        let once = mirrored(&m);
        for k in 0..m.mean.len() / 2 {
            assert_eq!(once.mean[2 * k], m.mean[2 * k]);
            assert_eq!(once.mean[2 * k + 1], -m.mean[2 * k + 1]);
        }
        // Still orthonormal.
        for (a, b) in once.basis.iter().zip(&m.basis) {
            let na: f64 = a.iter().map(|x| x * x).sum();
            let nb: f64 = b.iter().map(|x| x * x).sum();
            assert!((na - nb).abs() < 1e-12);
        }
        assert_eq!(mirrored(&once), m);
    }
}
