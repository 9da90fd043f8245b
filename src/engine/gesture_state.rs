//! The engine's gesture-command state (`gesture.rs` drives it): the capture, the
//! library in use, the search and follow parameters, work out on the worker and the
//! motion playing.

use super::params::{search_params, tap_thresholds};
use crate::config::{Config, GestureApply};
use crate::crowd::motion::{
    ApplyMode, FollowParams, FollowPhase, Follower, GestureJob, KeepParams, Synthesiser,
};
use crate::gesture::capture::{CaptureParams, GestureCapture, TapThresholds};
use crate::gesture::continuous::{
    ContinuousParams, ContinuousRecogniser, WindowBuffers, WindowParams,
    DEFAULT_WINDOW_MIN_TRAVEL_MM,
};
use crate::gesture::knn::{SearchParams, Searcher};
use crate::gesture::recognise::Recogniser;
use crate::gesture::track::GestureTracks;
use crate::vocab::{Micros, MotionPhase, PlanView, Recognition};
use std::sync::Arc;

/// A gesture's end, held back until its recognition is known.
#[derive(Clone, Debug)]
pub(super) struct PendingEnd {
    pub(super) id: u32,
    pub(super) fingers: u32,
    pub(super) contacts: u32,
    pub(super) duration_us: u64,
    pub(super) t: Micros,
    /// A continuous recognition's fire: the gesture goes on, its end event comes
    /// later (with this recognition).
    pub(super) live: bool,
}

/// A crowd motion playing.
#[derive(Debug)]
pub(super) struct Playing {
    pub(super) id: u32,
    /// The class's name in the library that recognised it.
    pub(super) class: String,
    pub(super) follower: Follower,
    pub(super) phase: FollowPhase,
    /// The motion's parts and each agent's planned end when it keeps the
    /// formation (the mesh afterwards is built there); empty as sampled.
    pub(super) kept: Kept,
}

/// Where a motion that keeps the formation plans the crowd: the parts that moved
/// together and each agent's end (m). Empty for a motion played as sampled.
#[derive(Clone, Debug, Default)]
pub(super) struct Kept {
    pub(super) parts: Vec<Vec<usize>>,
    pub(super) ends_m: Vec<crate::geom::Vec2>,
}

/// The engine's gesture commands (see the module doc).
pub(super) struct Gestures {
    pub(super) capture: GestureCapture,
    pub(super) tracks: GestureTracks,
    pub(super) recogniser: Option<Arc<Recogniser>>,
    pub(super) enabled: bool,
    /// `gestures.disabled`: classes recognised but not played.
    pub(super) disabled: Vec<String>,
    pub(super) search: SearchParams,
    pub(super) follow: FollowParams,
    /// `gestures.apply`, and what keeping the formation needs.
    pub(super) apply: ApplyMode,
    pub(super) keep: KeepParams,
    /// `gestures.min_piece_agents`.
    pub(super) min_piece_agents: usize,
    pub(super) speed_m_s: f64,
    pub(super) seed: u64,
    /// Bumped by a reset, a resize or a cancelled motion: a result of another epoch
    /// is stale.
    pub(super) epoch: u64,
    /// Slow work for the worker, until the pipeline takes it.
    pub(super) outbox: Vec<GestureJob>,
    pub(super) waiting: Vec<PendingEnd>,
    pub(super) playing: Option<Playing>,
    /// A mesh is being rebuilt (the crowd holds still until it is installed).
    pub(super) remesh_pending: bool,
    pub(super) plan: Option<Arc<PlanView>>,
    /// Prepared in the tick (replays) rather than by the worker.
    pub(super) inline: Option<Box<(Searcher, Synthesiser)>>,
    /// Gestures recognised and played, for stats.
    pub(super) played: u64,
    /// Continuous recognition (`gestures.continuous`), when configured.
    pub(super) continuous: Option<ContinuousRecogniser>,
    /// How its windows are recognised.
    pub(super) window: WindowParams,
    /// Live gestures with a window out on the worker.
    pub(super) windows_out: Vec<u32>,
    /// Recognitions of live gestures that fired, for their end events (with why
    /// no motion played, for a disabled class).
    pub(super) fired: Vec<(u32, Recognition, Option<String>)>,
    /// Window workspaces, in the tick (replays).
    pub(super) inline_windows: Option<Box<WindowBuffers>>,
}

impl Gestures {
    pub(super) fn new(cfg: &Config, inline: bool) -> Gestures {
        let mut g = Gestures {
            capture: GestureCapture::new(
                CaptureParams {
                    max_gestures: crate::gesture::capture::DEFAULT_MAX_GESTURES,
                    samples_per_track: crate::gesture::capture::DEFAULT_SAMPLES_PER_TRACK,
                },
                TapThresholds::default(),
            ),
            tracks: GestureTracks::default(),
            recogniser: None,
            enabled: false,
            disabled: Vec::new(),
            search: SearchParams::default(),
            follow: follow_params(cfg),
            apply: ApplyMode::KeepFormation,
            keep: KeepParams::default(),
            min_piece_agents: 1,
            speed_m_s: 1.0,
            seed: 0,
            epoch: 0,
            outbox: Vec::with_capacity(2),
            waiting: Vec::with_capacity(4),
            playing: None,
            remesh_pending: false,
            plan: None,
            inline: inline.then(|| Box::new((Searcher::new(), Synthesiser::new()))),
            played: 0,
            continuous: None,
            window: WindowParams {
                window: Micros(1_000_000),
                min_travel_mm: DEFAULT_WINDOW_MIN_TRAVEL_MM,
                search: SearchParams::default(),
            },
            windows_out: Vec::with_capacity(4),
            fired: Vec::with_capacity(4),
            inline_windows: inline.then(|| Box::new(WindowBuffers::new())),
        };
        g.tracks = g.capture.tracks_buffer();
        g.configure(cfg);
        g
    }

    /// Applies the config's `gestures` section (live on reload).
    pub(super) fn configure(&mut self, cfg: &Config) {
        let gc = &cfg.gestures;
        self.capture.set_thresholds(tap_thresholds(cfg));
        self.enabled = gc.enabled;
        self.disabled.clone_from(&gc.disabled);
        self.recogniser = cfg.gesture_recogniser().cloned();
        self.search = search_params(cfg);
        self.follow = follow_params(cfg);
        self.apply = match gc.apply {
            GestureApply::KeepFormation => ApplyMode::KeepFormation,
            GestureApply::AsSampled => ApplyMode::AsSampled,
        };
        self.min_piece_agents = gc.min_piece_agents.max(1) as usize;
        self.keep = KeepParams {
            min_part_agents: self.min_piece_agents,
            radius_m: cfg.crowd.agent_radius_m,
            ..KeepParams::default()
        };
        self.speed_m_s = gc.motion_speed_m_s;
        self.seed = gc.seed;
        match gc.continuous {
            Some(c) => {
                let p = ContinuousParams::from_ms(c.window_ms, c.hold_ms);
                if self.continuous.as_ref().map(|r| r.params()) != Some(p) {
                    self.continuous = Some(ContinuousRecogniser::new(p));
                }
                self.window = WindowParams {
                    window: p.window,
                    min_travel_mm: DEFAULT_WINDOW_MIN_TRAVEL_MM.max(gc.min_travel_mm),
                    search: self.search,
                };
            }
            None => self.continuous = None,
        }
    }

    /// Whether `gestures.disabled` names the class `name`.
    pub(super) fn is_disabled(&self, name: &str) -> bool {
        self.disabled.iter().any(|d| d == name)
    }

    /// Whether a crowd motion is playing (or holding for its new mesh).
    pub(super) fn playing(&self) -> bool {
        self.playing.is_some()
    }
}

pub(super) fn follow_params(cfg: &Config) -> FollowParams {
    FollowParams {
        approach_tolerance_m: (2.0 * cfg.crowd.agent_radius_m).max(0.05),
        approach_timeout_s: cfg.gestures.approach_timeout_s,
        time_scale: 1.0,
        settle_s: 2.0,
    }
}

pub(super) fn phase_of(p: FollowPhase) -> MotionPhase {
    match p {
        FollowPhase::Approach => MotionPhase::Approach,
        FollowPhase::Follow => MotionPhase::Follow,
        FollowPhase::Done => MotionPhase::Done,
        FollowPhase::Cancelled => MotionPhase::Cancelled,
    }
}
