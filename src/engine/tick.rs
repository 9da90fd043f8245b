//! One tick: segment the touches, deform the mesh, step the agents, publish a
//! snapshot and, with inline assignment, solve the next assignment.

use super::state::{Engine, MAX_TICK_S};
use crate::crowd::environment::steer_target;
use crate::geom::Vec2;
use crate::gesture::segment::{control_kind, Segment, TouchPoint};
use crate::vocab::{AgentView, ContactFlags, ContactId, Event, MeshView, Micros, Snapshot};
use crate::vocab::{
    EditView, PlanView, ScenePoses, SceneView, TouchFrame, TouchView, TracksView, TransformSummary,
    TransformView,
};
use std::sync::Arc;

/// What one tick produced.
pub struct TickOutput<'a> {
    /// The new snapshot.
    pub snapshot: Arc<Snapshot>,
    /// The mesh, when it changed this tick.
    pub mesh: Option<Arc<MeshView>>,
    /// Events of this tick.
    pub events: &'a [Event],
    /// The planned trajectories of a gesture motion that started this tick.
    pub plan: Option<Arc<PlanView>>,
    /// A running transform's progress this tick.
    pub transform: Option<Arc<TransformView>>,
    /// A transform that ended this tick, summarised.
    pub transform_end: Option<Arc<TransformSummary>>,
    /// Edit mode: the tracks, when they changed this tick.
    pub tracks: Option<Arc<TracksView>>,
    /// Edit mode: its state, when it changed this tick.
    pub edit: Option<Arc<EditView>>,
    /// The scene, when it changed (and at the first tick).
    pub scene: Option<Arc<SceneView>>,
    /// Where the scene's moving things are, when it has any.
    pub scene_poses: Option<Arc<ScenePoses>>,
}

impl Engine {
    pub(super) fn to_world(&self, x: f32, y: f32) -> Vec2 {
        Vec2::new(
            self.world.min[0] + x as f64 * self.world.width(),
            self.world.min[1] + y as f64 * self.world.height(),
        )
    }

    /// Feeds one input frame (segmentation happens at the frame's own time stamp).
    pub fn push_frame(&mut self, frame: &TouchFrame) {
        let t = frame.t;
        if !frame.contacts().is_empty() {
            self.collect_note_device(frame.device);
        }
        for c in frame.contacts() {
            let world = self.to_world(c.x, c.y);
            let tp = TouchPoint {
                id: c.id,
                world,
                glass_mm: Vec2::new(c.x as f64 * self.glass_mm.x, c.y as f64 * self.glass_mm.y),
                flags: c.flags,
            };
            let down = c.flags.contains(ContactFlags::DOWN);
            let on_crowd = down
                && if self.edits.active() {
                    self.edit_hits(world)
                } else if self.gestures.playing() || self.transforms.active() {
                    self.near_agent(world)
                } else {
                    self.direct.hits(world, self.grab_radius_m)
                };
            self.segmenter.touch(t, &tp, on_crowd, &mut self.seg_out);
            self.capture_touch(t, &tp);
            if on_crowd && self.gestures.playing() && !self.segmenter.all_touches_are_gestures() {
                // The person takes the crowd in hand: the motion stops where it is.
                self.cancel_gesture_motion(t);
            }
            if on_crowd && !self.segmenter.all_touches_are_gestures() {
                // The same during a transform: direct control from where they are.
                self.touch_transform(t);
            }
            if c.flags.ended() {
                self.touches.retain(|v| v.id != c.id.0);
            } else if let Some(v) = self.touches.iter_mut().find(|v| v.id == c.id.0) {
                v.pos = world;
            } else if !c.flags.contains(ContactFlags::PALM) {
                self.touches.push(TouchView {
                    id: c.id.0,
                    pos: world,
                    control: None,
                });
            }
        }
        self.pending_input_t = Some(self.pending_input_t.map_or(t, |p| p.max(t)));
    }

    /// Uses an assignment solved elsewhere on the state of tick `seq` of `generation`.
    /// Returns false (and ignores it) when the crowd has changed since.
    pub fn apply_assignment(&mut self, generation: u64, seq: u64, goal_of: &[u32]) -> bool {
        self.apply_plan(generation, seq, goal_of, &[])
    }

    /// [`apply_assignment`](Self::apply_assignment) with each agent's waypoint
    /// (NaN, or an empty slice: none).
    pub fn apply_plan(
        &mut self,
        generation: u64,
        seq: u64,
        goal_of: &[u32],
        waypoints: &[Vec2],
    ) -> bool {
        if generation != self.generation
            || self.transforms.active()
            || goal_of.len() != self.agents.len()
            || seq < self.assignment_seq
        {
            self.counters.stale_assignments += 1;
            return false;
        }
        self.goal_of.clear();
        self.goal_of.extend_from_slice(goal_of);
        if waypoints.len() == self.waypoints.len() {
            self.waypoints.copy_from_slice(waypoints);
        } else {
            self.waypoints.fill(Vec2::repeat(f64::NAN));
        }
        self.assignment_seq = seq;
        self.counters.assignments += 1;
        true
    }

    /// One tick at `now`.
    pub fn tick(&mut self, now: Micros) -> TickOutput<'_> {
        let dt = match self.last_t {
            Some(t0) => now.saturating_since(t0).as_secs_f64().min(MAX_TICK_S),
            None => 0.0,
        };
        self.last_t = Some(now);
        self.seq += 1;
        self.segmenter.tick(now, &mut self.seg_out);
        self.poll_continuous(now);
        self.poll_collect(now);
        let t0 = *self.scene_t0.get_or_insert(now);
        self.scene_t_s = now.saturating_since(t0).as_secs_f64();
        if self.scene.as_ref().is_some_and(|s| s.terrain_moves()) {
            // The terrain kept is last tick's: its patches have moved since.
            self.terrain.forget();
        }
        self.direct.set_time(self.scene_t_s);
        let lag = self
            .agents
            .mean_goal_distance(self.direct.goals(), &self.goal_of);
        // A cancelled control (a palm, a device gone) does not go on through its
        // remaining check points as a lifted one does.
        for s in &self.seg_out {
            if let Segment::ControlEnd {
                id,
                cancelled: true,
                ..
            } = *s
            {
                self.direct.cancel(id);
            }
        }
        // In edit mode the fingers edit tracks, not the crowd's mesh.
        let controls = if self.edits.active() {
            &[][..]
        } else {
            self.segmenter.controls()
        };
        if let Err(e) = self.direct.update(controls, dt, lag) {
            self.counters.deform_errors += 1;
            if self.counters.deform_errors.is_power_of_two() {
                log::warn!(
                    "internal: mesh deformation failed ({} times): {e}",
                    self.counters.deform_errors
                );
            }
        }
        self.transforms.view = None;
        let inline = !self.switch_worker;
        if self.step_edit(dt, now, inline) {
            // Edit mode: the crowd is the tracks' people at the play time.
        } else if self.step_gesture_motion(dt, now) {
            // A gesture's crowd motion moves the agents.
        } else if self.step_transform(dt, now) {
            // A formation transform moves the agents.
        } else if !self.paused {
            if self.scene.is_some() {
                self.step_in_scene(dt);
            } else {
                self.agents
                    .step(self.direct.goals(), &self.goal_of, dt, &self.agent_params);
            }
        }
        if let Some(scene) = &self.scene {
            let scene = scene.at(self.scene_t_s, &mut self.scene_placements);
            // What the step read where each agent ended; read afresh where an
            // agent was moved after that (out of an obstacle) or some other way
            // (a transform, edit mode, a reset), or the patches moved.
            let under = self
                .terrain
                .values_at(self.agents.positions(), |p| scene.terrain_at(p));
            self.motions.clear();
            self.motions.extend(under.map(|t| t.motion));
        }
        self.pass_checkpoints(now);
        self.translate_segments(now);
        for v in &mut self.touches {
            v.control = self.segmenter.control_of(ContactId(v.id)).map(|c| c.id);
        }
        let mesh = if self.direct.take_changed() {
            let mut m = self.meshes.acquire();
            {
                let mv = Arc::make_mut(&mut m);
                mv.seq = self.seq;
                mv.vertices.clear();
                mv.vertices.extend_from_slice(self.direct.vertices());
                mv.triangles = Arc::clone(&self.triangles);
                mv.outline = Arc::clone(&self.outline);
                mv.outlines = Arc::clone(&self.outlines);
                mv.topology = self.topology;
            }
            self.meshes.keep(&m);
            Some(m)
        } else {
            None
        };
        let mut snap = self.snapshots.acquire();
        {
            let s = Arc::make_mut(&mut snap);
            s.seq = self.seq;
            s.t = now;
            s.input_t = self.pending_input_t.take();
            s.agents.clear();
            s.goals.clear();
            let editing = self.edits.mode.is_some();
            if !editing {
                s.agents.extend(
                    self.agents
                        .positions()
                        .iter()
                        .zip(self.agents.velocities())
                        .zip(&self.goal_of)
                        .map(|((&pos, &vel), &goal)| AgentView { pos, vel, goal }),
                );
                match self.transform_goals() {
                    Some(targets) => s.goals.extend_from_slice(targets),
                    None => s.goals.extend_from_slice(self.direct.goals()),
                }
            }
            s.assignment_seq = self.assignment_seq;
            s.touches.clear();
            s.touches.extend_from_slice(&self.touches);
            s.motions.clear();
            s.motions.extend_from_slice(&self.motions);
            s.paused = self.paused;
        }
        if self.edits.mode.is_some() {
            let s = Arc::make_mut(&mut snap);
            let (mut agents, mut goals) =
                (std::mem::take(&mut s.agents), std::mem::take(&mut s.goals));
            self.edit_agents(&mut agents, &mut goals);
            s.agents = agents;
            s.goals = goals;
        }
        self.snapshots.keep(&snap);
        self.counters.ticks += 1;
        // Inline assignment: solved on this tick's state, used from the next tick.
        // (The error's text is formed only on a failure, which is logged.)
        // While a transform drives the agents, its pairing is not overwritten.
        let result = match (&mut self.planner, &mut self.inline) {
            _ if self.transforms.active() || self.edits.active() => None,
            (Some(p), _) => Some(
                p.plan(
                    self.agents.positions(),
                    self.direct.goals(),
                    self.scene_t_s,
                    &mut self.goal_of,
                    &mut self.waypoints,
                )
                .map_err(|e| e.to_string()),
            ),
            (None, Some(a)) => Some(
                a.solve(
                    self.agents.positions(),
                    self.direct.goals(),
                    &mut self.goal_of,
                )
                .map_err(|e| e.to_string()),
            ),
            (None, None) => None,
        };
        match result {
            Some(Ok(())) => {
                self.assignment_seq = self.seq;
                self.counters.assignments += 1;
            }
            Some(Err(e)) => {
                self.counters.assign_errors += 1;
                if self.counters.assign_errors.is_power_of_two() {
                    log::warn!(
                        "internal: assignment failed ({} times): {e}",
                        self.counters.assign_errors
                    );
                }
            }
            None => {}
        }
        TickOutput {
            snapshot: snap,
            mesh,
            plan: self.take_plan(),
            transform: self.transforms.view.take(),
            transform_end: self.transforms.ended.take(),
            tracks: self.take_tracks(now),
            edit: self.take_edit_view(),
            scene: self.take_scene_view(),
            scene_poses: self.take_scene_poses(),
            events: &self.events,
        }
    }

    /// One agent step in the scene: steer at the goal or the waypoint, speed limit
    /// scaled by the terrain, then out of obstacles by one agent radius
    /// (mesh-formation-control sections 6.2.1 and 6.2.3). No allocation once the
    /// buffers have the crowd's size.
    pub(super) fn step_in_scene(&mut self, dt: f64) {
        let Some(scene) = &self.scene else {
            return;
        };
        let scene = scene.at(self.scene_t_s, &mut self.scene_placements);
        let goals = self.direct.goals();
        self.targets.clear();
        for (i, &p) in self.agents.positions().iter().enumerate() {
            let g = goals[self.goal_of[i] as usize];
            let w = self
                .waypoints
                .get(i)
                .copied()
                .unwrap_or(Vec2::repeat(f64::NAN));
            self.targets.push(steer_target(&scene, p, g, w));
        }
        self.agents.step_over(
            &self.targets,
            &mut self.terrain,
            |x| scene.terrain_at(x),
            |t| t.speed_factor,
            dt,
            &self.agent_params,
        );
        let r = self.agent_params.radius_m;
        for i in 0..self.agents.len() {
            let p = self.agents.positions()[i];
            if scene.closer_than(p, r) {
                let q = scene.project_out(p, r);
                self.agents.set_position(i, q);
            }
        }
    }

    /// Clears the events of the last tick (call after publishing them).
    pub fn clear_events(&mut self) {
        self.events.clear();
    }

    pub(super) fn translate_segments(&mut self, now: Micros) {
        for k in 0..self.seg_out.len() {
            let s = self.seg_out[k].clone();
            let ev = match s {
                Segment::ControlBegin(id) | Segment::ControlUpdate(id) => {
                    let fingers = self
                        .segmenter
                        .controls()
                        .iter()
                        .find(|c| c.id == id)
                        .map(|c| c.fingers.iter().map(|f| f.id.0).collect::<Vec<_>>())
                        .unwrap_or_default();
                    let kind = control_kind(fingers.len());
                    let vertices = self.direct.handle_vertices(id);
                    if matches!(s, Segment::ControlBegin(_)) {
                        Event::ControlBegin {
                            id,
                            kind,
                            fingers,
                            vertices,
                            t: now,
                        }
                    } else {
                        Event::ControlUpdate {
                            id,
                            kind,
                            fingers,
                            vertices,
                            t: now,
                        }
                    }
                }
                Segment::ControlEnd {
                    id,
                    kind,
                    cancelled,
                } => Event::ControlEnd {
                    id,
                    kind,
                    cancelled,
                    t: now,
                },
                Segment::GestureBegin(id) => {
                    self.continuous_begin(id, now);
                    Event::GestureBegin { id, t: now }
                }
                Segment::GestureEnd {
                    id,
                    fingers,
                    contacts,
                    duration,
                    cancelled,
                } => match self.gesture_ended(id, fingers, contacts, duration.0, cancelled, now) {
                    Some(e) => e,
                    // Its event goes out with its recognition.
                    None => continue,
                },
            };
            self.events.push(ev);
        }
        self.seg_out.clear();
    }
}
