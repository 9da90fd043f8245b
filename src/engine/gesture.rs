//! Gesture commands in the engine (gesture-driven-crowd-motion sections 5–7): a
//! gesture drawn in open space is captured finger by finger, recognised against the
//! library, and played as a crowd motion; afterwards the direct-control mesh is
//! rebuilt around where the crowd stopped, so touch control goes on.
//!
//! ```text
//!  gesture ends ──► capture.finish ──tap/too long/disabled──► `gesture` event (rejected)
//!                        │ tracks
//!                        ▼
//!              GestureRequest::prepare          (worker; in the tick for replays)
//!              recognise · blend · synthesise
//!                        │
//!     not recognised ◄───┴───► `gesture` event (recognition), `plan`,
//!     `gesture` event     │    `gesture_motion` approach ─► follow ─► done
//!     (rejected)          │                                            │
//!                         └─ class in `gestures.disabled`: `gesture`   │
//!                            event (recognition, `class_disabled`)     │
//!                                              RemeshRequest::prepare ◄┘ (worker)
//!                                              mesh_around → install: touch control
//! ```
//!
//! While a motion plays, agents walk towards the [`Follower`]'s targets (their
//! trajectory's start, then along it); the spring-mass push of
//! [`Agents::step_towards`](crate::crowd::agents::Agents::step_towards) keeps them
//! apart. A touch landing near an agent during a motion cancels it (the person takes
//! the crowd in hand); so do a reset, a resize and a newer gesture's motion. Nothing
//! here allocates in a steady tick: requests and plans are built once per gesture.

use super::gesture_state::{phase_of, Kept, PendingEnd, Playing};
use super::state::Engine;
use crate::crowd::motion::{
    FollowPhase, Follower, GestureJob, GestureMotion, GestureRequest, PreparedGesture,
    PreparedRemesh, PreparedWindow, RemeshRequest, WindowRequest,
};
use crate::geom::Vec2;
use crate::gesture::capture::Rejected;
use crate::gesture::continuous::WindowParams;
use crate::gesture::library::S_H;
use crate::vocab::{Event, Micros, MotionPhase, NeighbourView, PlanOrigin, PlanView, Recognition};
use std::sync::Arc;

impl Engine {
    /// Records a touch into the gesture it belongs to (after the segmenter saw it).
    pub(super) fn capture_touch(&mut self, t: Micros, tp: &crate::gesture::segment::TouchPoint) {
        self.gestures.capture.observe(t, &self.segmenter, tp);
    }

    /// Whether `p` is within the grab radius of an agent (during a motion the mesh is
    /// where the crowd was, so agents are what a finger lands on).
    pub(super) fn near_agent(&self, p: Vec2) -> bool {
        let r2 = self.grab_radius_m * self.grab_radius_m;
        self.agents
            .positions()
            .iter()
            .any(|a| (a - p).norm_squared() <= r2)
    }

    /// A gesture ended: capture its tracks and ask for its motion, or say why not
    /// (the `gesture` event then goes out at once).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn gesture_ended(
        &mut self,
        id: u32,
        fingers: u32,
        contacts: u32,
        duration_us: u64,
        cancelled: bool,
        now: Micros,
    ) -> Option<Event> {
        let g = &mut self.gestures;
        let captured = g.capture.finish(id, &mut g.tracks);
        g.windows_out.retain(|&w| w != id);
        if self.edits.active() && !cancelled && !matches!(captured, Err(Rejected::NotCaptured)) {
            // Edit mode: a one-finger loop in open space selects the people in it.
            let tracks = std::mem::take(&mut self.gestures.tracks);
            let lasso = self.edit_lasso(&tracks);
            self.gestures.tracks = tracks;
            if lasso {
                return Some(Event::GestureEnd {
                    id,
                    fingers,
                    contacts,
                    duration_us,
                    cancelled,
                    recognition: None,
                    rejected: Some(LASSO.to_string()),
                    t: now,
                });
            }
        }
        let g = &mut self.gestures;
        let end = |recognition, rejected| Event::GestureEnd {
            id,
            fingers,
            contacts,
            duration_us,
            cancelled,
            recognition,
            rejected,
            t: now,
        };
        if self.collect.is_some() {
            // `library collect`: the gesture is recorded, not recognised.
            let tracks = std::mem::take(&mut self.gestures.tracks);
            let why = self.collect_gesture(captured.as_ref().map(|_| &tracks), cancelled, now);
            self.gestures.tracks = tracks;
            return Some(end(None, why));
        }
        let fired = g
            .continuous
            .as_mut()
            .and_then(|c| c.end(id))
            .map_or(0, |e| e.fired);
        if fired > 0 {
            // Recognised while it was drawn: its motion is under way already.
            let (recognition, rejected) = g
                .fired
                .iter()
                .position(|f| f.0 == id)
                .map(|k| g.fired.swap_remove(k))
                .map_or((None, None), |(_, r, why)| (Some(r), why));
            return Some(end(recognition, rejected));
        }
        let rejected = match (&captured, &g.recogniser) {
            _ if cancelled => Some("cancelled".to_string()),
            _ if !g.enabled => Some("disabled".to_string()),
            (Err(r), _) => Some(rejected_reason(r)),
            (Ok(_), None) => Some("no_library".to_string()),
            (Ok(_), Some(_)) if self.agents.is_empty() => Some("no_agents".to_string()),
            (Ok(_), Some(_)) => None,
        };
        if let Some(rejected) = rejected {
            return Some(end(None, Some(rejected)));
        }
        let recogniser = g.recogniser.clone()?;
        let req = GestureRequest {
            id,
            epoch: g.epoch,
            tracks: g.tracks.clone(),
            agents: self.agents.positions().to_vec(),
            recogniser,
            search: g.search,
            seed: g.seed ^ u64::from(id).wrapping_mul(0x9e37_79b9_7f4a_7c15),
            speed_m_s: g.speed_m_s,
            apply: g.apply,
            keep: g.keep,
        };
        let end = PendingEnd {
            id,
            fingers,
            contacts,
            duration_us,
            t: now,
            live: false,
        };
        self.ask_for_motion(req, end, now);
        None
    }

    /// Prepares `req` (in the tick for replays) or hands it to the worker; `end`
    /// is what its `gesture` event (or, for a live gesture, its motion) waits on.
    fn ask_for_motion(&mut self, req: GestureRequest, end: PendingEnd, now: Micros) {
        let g = &mut self.gestures;
        g.waiting.retain(|w| w.id != end.id);
        g.waiting.push(end);
        match &mut g.inline {
            Some(ws) => {
                let (searcher, synth) = &mut **ws;
                let p = req.prepare(searcher, synth);
                self.apply_gesture(p, 0, now);
            }
            None => g.outbox.push(GestureJob::Recognise(req)),
        }
    }

    /// Slow gesture work for the worker ([`GestureRequest::prepare`] or
    /// [`RemeshRequest::prepare`], then [`Engine::apply_gesture`] or
    /// [`Engine::apply_remesh`]).
    pub fn take_gesture_job(&mut self) -> Option<GestureJob> {
        if self.gestures.outbox.is_empty() {
            None
        } else {
            Some(self.gestures.outbox.remove(0))
        }
    }

    /// The plan of a motion that started this tick, for `plan` subscribers.
    pub fn take_plan(&mut self) -> Option<Arc<PlanView>> {
        self.gestures.plan.take()
    }

    /// Uses a prepared gesture: its `gesture` event goes out with the recognition
    /// (or why there is no motion), and its motion starts (`synth_us`: how long the
    /// worker took, 0 in replays).
    pub fn apply_gesture(&mut self, p: PreparedGesture, synth_us: u64, now: Micros) {
        let g = &mut self.gestures;
        let Some(k) = g.waiting.iter().position(|w| w.id == p.id) else {
            return;
        };
        let end = g.waiting.remove(k);
        if end.live {
            // A continuous fire: the motion starts; the gesture's end event comes
            // when it ends, with this recognition.
            let stale = p.epoch != g.epoch || self.agents.is_empty();
            if let (false, Ok(m)) = (stale, p.outcome) {
                if m.synthesis.trajectories.len() == self.agents.len() {
                    let rec = recognition_view(&m, synth_us);
                    let disabled = self.gestures.is_disabled(&m.class_name);
                    self.gestures.fired.retain(|f| f.0 != p.id);
                    self.gestures.fired.push((
                        p.id,
                        rec,
                        disabled.then(|| CLASS_DISABLED.to_string()),
                    ));
                    if disabled {
                        log::info!("gesture {}: {} is disabled", p.id, m.class_name);
                    } else {
                        let kept = Kept {
                            parts: m.parts,
                            ends_m: m.ends_m,
                        };
                        self.play(p.id, m.class_name, m.synthesis, kept, now);
                    }
                }
            }
            return;
        }
        let mut event = Event::GestureEnd {
            id: end.id,
            fingers: end.fingers,
            contacts: end.contacts,
            duration_us: end.duration_us,
            cancelled: false,
            recognition: None,
            rejected: None,
            t: end.t,
        };
        let stale = p.epoch != g.epoch || self.agents.is_empty();
        match p.outcome {
            _ if stale => set_rejected(&mut event, "superseded".to_string()),
            Err(e) => {
                log::info!("gesture {}: {e}", p.id);
                set_rejected(&mut event, e.reason().to_string());
            }
            Ok(m) => {
                let agents = m.synthesis.trajectories.len();
                if agents != self.agents.len() {
                    set_rejected(&mut event, "superseded".to_string());
                } else {
                    let rec = recognition_view(&m, synth_us);
                    if let Event::GestureEnd { recognition, .. } = &mut event {
                        *recognition = Some(rec);
                    }
                    if self.gestures.is_disabled(&m.class_name) {
                        // Recognised, and ignored (`gestures.disabled`).
                        log::info!("gesture {}: {} is disabled", p.id, m.class_name);
                        set_rejected(&mut event, CLASS_DISABLED.to_string());
                        self.events.push(event);
                        return;
                    }
                    self.events.push(event);
                    let kept = Kept {
                        parts: m.parts,
                        ends_m: m.ends_m,
                    };
                    self.play(p.id, m.class_name, m.synthesis, kept, now);
                    return;
                }
            }
        }
        self.events.push(event);
    }

    /// Starts playing a synthesised motion of class `class` (its name in the
    /// library; a playing one is cancelled).
    fn play(
        &mut self,
        id: u32,
        class: String,
        synthesis: crate::crowd::motion::Synthesis,
        kept: Kept,
        now: Micros,
    ) {
        if self.edits.active() {
            // Edit mode: the crowd is the tracks' people; a gesture retimes them.
            self.edit_gesture(id, &class);
            return;
        }
        if let Some(name) = self.gesture_formation(&class) {
            // `formations.gestures` maps this class to a formation: a transform
            // goes there instead of the gesture's motion.
            log::info!("gesture {id}: {class} starts a transform to `{name}`");
            let heading = self.crowd_heading();
            let _ = self.request_transform(&name, None, None, heading, now);
            return;
        }
        self.start_motion(PlanOrigin::Gesture { id }, id, class, synthesis, kept, now);
    }

    /// Starts a synthesised motion on the crowd (a gesture's, or a `library
    /// collect` demonstration's with `id` 0): a playing one is cancelled, a
    /// transform dropped; its plan goes to `plan` subscribers.
    pub(super) fn start_motion(
        &mut self,
        origin: PlanOrigin,
        id: u32,
        class: String,
        synthesis: crate::crowd::motion::Synthesis,
        kept: Kept,
        now: Micros,
    ) {
        self.cancel_gesture_motion(now);
        if self.transforms.busy() {
            self.drop_transforms(crate::vocab::TransformOutcome::Superseded, now);
        }
        let points: Vec<Vec2> = synthesis
            .trajectories
            .iter()
            .flat_map(|t| t.iter().copied())
            .collect();
        let duration_s = synthesis.duration_s;
        let follower = match Follower::new(synthesis.trajectories, duration_s, self.gestures.follow)
        {
            Ok(f) => f,
            Err(e) => {
                log::warn!("gesture {id}: {class} motion not played: {e}");
                return;
            }
        };
        self.gestures.plan = Some(Arc::new(PlanView {
            origin,
            class: class.clone(),
            duration_s,
            samples: S_H as u32,
            points,
        }));
        match origin {
            PlanOrigin::Gesture { .. } => {
                log::info!(
                    "gesture {id}: {class}, {} agents over {duration_s:.1} s",
                    self.agents.len()
                );
                self.gestures.played += 1;
            }
            PlanOrigin::Demo { motion } => log::info!(
                "collect: showing motion {motion} ({class}), {} agents over {duration_s:.1} s",
                self.agents.len()
            ),
        }
        self.events.push(Event::GestureMotion {
            id,
            class: class.clone(),
            phase: MotionPhase::Approach,
            t: now,
        });
        self.gestures.playing = Some(Playing {
            id,
            class,
            follower,
            phase: FollowPhase::Approach,
            kept,
        });
    }

    /// Cancels a playing motion (a reset, a resize, a touch on the crowd, a newer
    /// motion): a `gesture_motion` `cancelled` event; the mesh is rebuilt around the
    /// crowd where it stopped.
    pub(super) fn cancel_gesture_motion(&mut self, now: Micros) {
        let Some(mut p) = self.gestures.playing.take() else {
            return;
        };
        self.gestures.epoch += 1;
        self.gestures.remesh_pending = false;
        if !p.follower.done() {
            p.follower.cancel();
            self.events.push(Event::GestureMotion {
                id: p.id,
                class: p.class.clone(),
                phase: MotionPhase::Cancelled,
                t: now,
            });
        }
    }

    /// Forgets gesture work under way (a reset or resize): motions and results
    /// asked for before are stale.
    pub(super) fn forget_gestures(&mut self, now: Micros) {
        self.cancel_gesture_motion(now);
        self.gestures.epoch += 1;
        self.gestures.outbox.clear();
    }

    /// One tick of a playing motion: agents walk to their targets; phase changes are
    /// events; at the end the mesh is rebuilt around the crowd. Returns false when
    /// no motion plays (the direct controller moves the agents).
    pub(super) fn step_gesture_motion(&mut self, dt: f64, now: Micros) -> bool {
        let t = self.scene_t_s;
        let Some(p) = &mut self.gestures.playing else {
            return false;
        };
        let targets = p.follower.targets(self.agents.positions(), t);
        self.targets.clear();
        self.targets.extend_from_slice(targets);
        let phase = p.follower.phase();
        if phase != p.phase {
            p.phase = phase;
            self.events.push(Event::GestureMotion {
                id: p.id,
                class: p.class.clone(),
                phase: phase_of(phase),
                t: now,
            });
        }
        let finished = p.follower.done() && !self.gestures.remesh_pending;
        if !self.paused {
            match &self.scene {
                Some(scene) => {
                    let scene = scene.at(t, &mut self.scene_placements);
                    self.agents.step_over(
                        &self.targets,
                        &mut self.terrain,
                        |x| scene.terrain_at(x),
                        |g| g.speed_factor,
                        dt,
                        &self.agent_params,
                    );
                    let r = self.agent_params.radius_m;
                    for i in 0..self.agents.len() {
                        let q = self.agents.positions()[i];
                        if scene.closer_than(q, r) {
                            let out = scene.project_out(q, r);
                            self.agents.set_position(i, out);
                        }
                    }
                }
                None => self
                    .agents
                    .step_towards(&self.targets, |_| 1.0, dt, &self.agent_params),
            }
        }
        if finished {
            self.gestures.remesh_pending = true;
            // A motion that kept the formation is meshed where it planned the
            // crowd, part by part; one played as sampled where the crowd stopped.
            let (agents, parts) = match &self.gestures.playing {
                Some(p) if p.kept.ends_m.len() == self.agents.len() => {
                    (p.kept.ends_m.clone(), p.kept.parts.clone())
                }
                _ => (self.agents.positions().to_vec(), Vec::new()),
            };
            let req = RemeshRequest {
                epoch: self.gestures.epoch,
                agents,
                parts,
                radius_m: self.agent_params.radius_m,
                min_piece_agents: self.gestures.min_piece_agents,
            };
            if self.gestures.inline.is_some() {
                self.apply_remesh(req.prepare(), now);
            } else {
                self.gestures.outbox.push(GestureJob::Remesh(req));
            }
        }
        true
    }

    /// Installs the mesh rebuilt around the crowd after a motion: every agent's goal
    /// is where it stands, so nothing jumps, and touch control goes on from there.
    pub fn apply_remesh(&mut self, p: PreparedRemesh, now: Micros) {
        if p.epoch != self.gestures.epoch || !self.gestures.remesh_pending {
            return;
        }
        self.gestures.remesh_pending = false;
        self.gestures.playing = None;
        match p.built {
            Ok((mesh, samples)) if samples.len() == self.agents.len() => {
                let identity: Vec<u32> = (0..self.agents.len() as u32).collect();
                self.install(mesh, samples, &identity);
                self.formation_name.clear();
                self.formation_name.push_str("gesture");
                let _ = now;
            }
            Ok(_) => log::warn!("gesture motion: the crowd changed size; the mesh stays"),
            Err(e) => log::warn!("gesture motion: no mesh around the crowd ({e}); the mesh stays"),
        }
    }

    /// A gesture began: continuous recognition watches it (when configured).
    pub(super) fn continuous_begin(&mut self, id: u32, now: Micros) {
        if let Some(c) = &mut self.gestures.continuous {
            c.begin(id, now);
        }
    }

    /// Continuous recognition (`gestures.continuous`, the paper's future work of
    /// section 10): every live gesture whose window is due has its latest window
    /// recognised (on the worker; in the tick for replays).
    pub(super) fn poll_continuous(&mut self, now: Micros) {
        let g = &mut self.gestures;
        let (Some(c), Some(rec)) = (&mut g.continuous, &g.recogniser) else {
            return;
        };
        if !g.enabled || self.collect.is_some() {
            return;
        }
        for k in 0..self.segmenter.gestures().len() {
            let live = &self.segmenter.gestures()[k];
            let id = live.id;
            if live.state != crate::gesture::segment::GestureState::Active
                || g.windows_out.contains(&id)
                || !c.due(id, now)
            {
                continue;
            }
            let mut tracks = crate::gesture::track::GestureTracks::default();
            if !g.capture.snapshot(id, &mut tracks) {
                continue;
            }
            let req = WindowRequest {
                id,
                epoch: g.epoch,
                at: now,
                tracks,
                recogniser: Arc::clone(rec),
                params: WindowParams {
                    search: g.search,
                    ..g.window
                },
            };
            g.windows_out.push(id);
            match &mut g.inline_windows {
                Some(buf) => {
                    let p = req.prepare(buf);
                    self.apply_window(p, now);
                    return self.poll_continuous(now);
                }
                None => g.outbox.push(GestureJob::Window(req)),
            }
        }
    }

    /// Uses a recognised window: when its class has stayed ahead for the hold time
    /// the gesture fires, and its motion is synthesised from the window.
    pub fn apply_window(&mut self, p: PreparedWindow, now: Micros) {
        let g = &mut self.gestures;
        g.windows_out.retain(|&w| w != p.id);
        let (Some(c), Some(rec)) = (&mut g.continuous, &g.recogniser) else {
            return;
        };
        if p.epoch != g.epoch {
            return;
        }
        let Some(fire) = c.observe(p.id, p.at, p.vote) else {
            return;
        };
        log::info!(
            "gesture {}: {} recognised while drawn (weight {:.2})",
            fire.id,
            rec.class_name(fire.class),
            fire.weight
        );
        let req = GestureRequest {
            id: p.id,
            epoch: g.epoch,
            tracks: p.cut,
            agents: self.agents.positions().to_vec(),
            recogniser: Arc::clone(rec),
            search: g.search,
            seed: g.seed
                ^ u64::from(p.id).wrapping_mul(0x9e37_79b9_7f4a_7c15)
                ^ u64::from(fire.count),
            speed_m_s: g.speed_m_s,
            apply: g.apply,
            keep: g.keep,
        };
        let end = PendingEnd {
            id: p.id,
            fingers: 0,
            contacts: 0,
            duration_us: 0,
            t: now,
            live: true,
        };
        self.ask_for_motion(req, end, now);
    }

    /// Gesture commands played since start.
    pub fn gestures_played(&self) -> u64 {
        self.gestures.played
    }
}

/// A recognition as clients see it.
fn recognition_view(m: &GestureMotion, synth_us: u64) -> Recognition {
    Recognition {
        class: m.class_name.clone(),
        weight: m.recognised.weight,
        neighbours: m
            .recognised
            .neighbours
            .iter()
            .zip(&m.neighbours)
            .map(|(n, (class, origin))| NeighbourView {
                class: class.clone(),
                distance: n.distance,
                weight: n.weight,
                origin: origin.clone(),
            })
            .collect(),
        synth_us,
        agents: m.synthesis.trajectories.len() as u32,
    }
}

/// The `rejected` reason of a recognised gesture whose class `gestures.disabled`
/// names.
pub const CLASS_DISABLED: &str = "class_disabled";

/// The `rejected` reason of a gesture that was a lasso in edit mode: it selected
/// the people inside it instead of being recognised.
pub const LASSO: &str = "lasso";

fn set_rejected(e: &mut Event, why: String) {
    if let Event::GestureEnd { rejected, .. } = e {
        *rejected = Some(why);
    }
}

fn rejected_reason(r: &Rejected) -> String {
    r.as_str().to_string()
}
