//! The control core: one tick of segment → deform → assign → step → snapshot.
//!
//! The engine owns the world (segmenter, mesh controller, agents) and knows nothing
//! about threads or clocks: it is given frames and `now`. The control thread drives it
//! in real time (`pipeline`); `replay` drives it on a virtual clock, which makes
//! replays deterministic.

use crate::config::{AssignmentCost, Config, MAX_AGENTS};
use crate::crowd::agents::{AgentParams, Agents};
use crate::crowd::assign::{Assigner, PointMetric};
use crate::crowd::control::{DirectController, DirectParams};
use crate::crowd::environment::FieldParams;
use crate::crowd::environment::Scene;
use crate::crowd::environment::{
    steer_target, Planner, PlannerParams, MESH_FIELD_RANGE_M, MESH_FIELD_STEP_M,
};
use crate::crowd::formation::{FormationLibrary, Placement, PreparedSwitch, SwitchRequest, START};
use crate::crowd::mesh::GoalSample;
use crate::crowd::mesh::TriMesh;
use crate::geom::{Rect, Vec2};
use crate::gesture::segment::{Segment, SegmentParams, Segmenter, TouchPoint};
use crate::vocab::Micros;
use crate::vocab::MotionType;
use crate::vocab::{AgentView, Command, Event, MeshView, Snapshot, TouchView};
use crate::vocab::{ContactFlags, TouchFrame};
use std::sync::Arc;

/// Longest time step the engine integrates in one tick (s); a longer gap (a stall,
/// a paused replay) is treated as this long.
pub const MAX_TICK_S: f64 = 0.1;
/// Fraction of the mean goal spacing an agent's radius may take when the formation
/// is too small for the configured radius.
pub const RADIUS_FIT: f64 = 0.45;
/// Pooled snapshots kept for reuse.
const POOL_CAP: usize = 32;

/// Why the engine could not be built or reconfigured.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The agent count is out of range.
    #[error("agent count {count} is out of range 1..={max}")]
    AgentCount {
        /// Requested.
        count: u32,
        /// Maximum.
        max: u32,
    },
}

/// What one tick produced.
pub struct TickOutput<'a> {
    /// The new snapshot.
    pub snapshot: Arc<Snapshot>,
    /// The mesh, when it changed this tick.
    pub mesh: Option<Arc<MeshView>>,
    /// Events of this tick.
    pub events: &'a [Event],
}

/// A recycling pool of `Arc`s: an item is reused once every other holder dropped it.
struct ArcPool<T> {
    items: Vec<Arc<T>>,
}

impl<T: Default + Clone> ArcPool<T> {
    fn new() -> Self {
        ArcPool {
            items: Vec::with_capacity(POOL_CAP),
        }
    }
    fn acquire(&mut self) -> Arc<T> {
        match self
            .items
            .iter()
            .position(|a| Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0)
        {
            Some(i) => self.items.swap_remove(i),
            None => Arc::new(T::default()),
        }
    }
    fn keep(&mut self, a: &Arc<T>) {
        if self.items.len() < POOL_CAP {
            self.items.push(Arc::clone(a));
        }
    }
}

/// Counters the engine keeps.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct EngineCounters {
    /// Ticks.
    pub ticks: u64,
    /// Assignments applied.
    pub assignments: u64,
    /// Assignment results discarded because the crowd changed meanwhile.
    pub stale_assignments: u64,
    /// Deformation failures.
    pub deform_errors: u64,
    /// Assignment failures.
    pub assign_errors: u64,
    /// Formation switches at checkpoints.
    pub formation_switches: u64,
    /// Checkpoint formations that could not be built (the crowd kept its formation).
    pub formation_errors: u64,
}

/// The control core.
pub struct Engine {
    world: Rect,
    glass_mm: Vec2,
    grab_radius_m: f64,
    formation: Rect,
    agent_params: AgentParams,
    configured_radius_m: f64,
    segmenter: Segmenter,
    direct: DirectController,
    agents: Agents,
    goal_of: Vec<u32>,
    assignment_seq: u64,
    generation: u64,
    inline: Option<Assigner>,
    scene: Option<Arc<Scene>>,
    planner: Option<Planner>,
    planner_params: PlannerParams,
    scene_t0: Option<Micros>,
    scene_t_s: f64,
    waypoints: Vec<Vec2>,
    targets: Vec<Vec2>,
    speed_factor: Vec<f64>,
    motions: Vec<MotionType>,
    seq: u64,
    last_t: Option<Micros>,
    pending_input_t: Option<Micros>,
    paused: bool,
    seg_out: Vec<Segment>,
    events: Vec<Event>,
    touches: Vec<TouchView>,
    snapshots: ArcPool<Snapshot>,
    meshes: ArcPool<MeshView>,
    triangles: Arc<Vec<[u32; 3]>>,
    outline: Arc<Vec<u32>>,
    topology: u64,
    counters: EngineCounters,
    /// Formation shapes the scene's checkpoints name.
    formations: Arc<FormationLibrary>,
    /// `λ` of the least-effort pairing at a switch.
    formation_lambda: f64,
    /// The formation the crowd is in ([`START`] or a library name).
    formation_name: String,
    /// The mesh the crowd starts in (and a reset brings back).
    start_mesh: Arc<TriMesh>,
    /// Agent centroid after the last tick, to see checkpoints being crossed.
    prev_centroid: Option<Vec2>,
    /// Goal samples of the start mesh for the current crowd size (for a reset).
    start_samples: Vec<GoalSample>,
    /// Switches are prepared by the daemon's formation thread
    /// ([`Engine::take_switch_request`], [`Engine::apply_switch`]), not in the tick.
    switch_worker: bool,
    /// Bumped by a reset or resize: a switch prepared before it is stale.
    switch_epoch: u64,
    /// The formation a request is out for.
    switch_pending: Option<String>,
    /// The last switch asked for while one was out: `(name, checkpoint, heading)`.
    switch_queued: Option<(String, Option<String>, Vec2)>,
    /// A request for the formation thread, until the pipeline takes it.
    switch_outbox: Option<SwitchRequest>,
}

impl Engine {
    /// An engine for `cfg`. `glass_mm` is the surface's physical size when the device
    /// reports it (else the config's). `inline_assignment` solves the assignment
    /// inside every tick (replays) instead of accepting results from a worker.
    pub fn new(cfg: &Config, glass_mm: Option<(f64, f64)>, inline_assignment: bool) -> Engine {
        let mesh = TriMesh::grid(
            cfg.crowd.formation,
            cfg.mesh.cols as usize,
            cfg.mesh.rows as usize,
        );
        let agents_n = cfg.crowd.agents as usize;
        let start_mesh = Arc::new(mesh.clone());
        let direct = DirectController::new(mesh, agents_n, direct_params(cfg));
        let agents = Agents::new(direct.goals());
        let triangles = Arc::new(direct.mesh().triangles().to_vec());
        let outline = Arc::new(direct.mesh().outline().to_vec());
        let (gw, gh) = glass_mm.or(cfg.surface.size_mm).unwrap_or_else(|| {
            let w = cfg.surface.world;
            (1000.0, 1000.0 * w.height() / w.width())
        });
        let mut e = Engine {
            world: cfg.surface.world,
            glass_mm: Vec2::new(gw, gh),
            grab_radius_m: cfg.controls.grab_radius_m,
            formation: cfg.crowd.formation,
            agent_params: agent_params(cfg),
            configured_radius_m: cfg.crowd.agent_radius_m,
            segmenter: Segmenter::new(segment_params(cfg)),
            direct,
            agents,
            goal_of: (0..agents_n as u32).collect(),
            assignment_seq: 0,
            generation: 0,
            inline: inline_assignment.then(|| Assigner::new(point_metric(cfg.assignment.cost))),
            scene: cfg.loaded_scene().cloned(),
            planner: None,
            planner_params: planner_params(cfg),
            scene_t0: None,
            scene_t_s: 0.0,
            waypoints: vec![Vec2::repeat(f64::NAN); agents_n],
            targets: Vec::with_capacity(agents_n),
            speed_factor: Vec::with_capacity(agents_n),
            motions: Vec::with_capacity(agents_n),
            seq: 0,
            last_t: None,
            pending_input_t: None,
            paused: false,
            seg_out: Vec::with_capacity(64),
            events: Vec::with_capacity(64),
            touches: Vec::with_capacity(64),
            snapshots: ArcPool::new(),
            meshes: ArcPool::new(),
            triangles,
            outline,
            topology: 1,
            counters: EngineCounters::default(),
            formations: Arc::clone(cfg.formation_library()),
            formation_lambda: cfg.formations.lambda,
            formation_name: START.to_string(),
            start_mesh,
            prev_centroid: None,
            start_samples: Vec::new(),
            switch_worker: false,
            switch_epoch: 0,
            switch_pending: None,
            switch_queued: None,
            switch_outbox: None,
        };
        e.start_samples = e.direct.samples().to_vec();
        e.fit_radius();
        if inline_assignment {
            e.planner = inline_planner(cfg);
        }
        e.set_mesh_environment();
        e
    }

    /// The mesh's environment field at the current agent radius.
    fn set_mesh_environment(&mut self) {
        let env = self.scene.as_ref().and_then(|s| {
            FieldParams::new(
                MESH_FIELD_RANGE_M,
                MESH_FIELD_STEP_M,
                self.agent_params.radius_m,
            )
            .ok()
            .map(|p| (Arc::clone(s), p))
        });
        self.direct.set_environment(env);
    }

    /// The scene in use, if any.
    pub fn scene(&self) -> Option<&Arc<Scene>> {
        self.scene.as_ref()
    }

    /// The parameters a planner for the current scene and config uses (the worker
    /// builds its planner with them).
    pub fn planner_params(&self) -> PlannerParams {
        self.planner_params
    }

    /// Whether the engine solves the assignment inside the tick (and so keeps its
    /// own planner when it has a scene).
    pub fn assigns_inline(&self) -> bool {
        self.inline.is_some()
    }

    /// Scene time of the last tick (s since the first tick): where moving obstacles
    /// are.
    pub fn scene_time_s(&self) -> f64 {
        self.scene_t_s
    }

    /// Each agent's waypoint (NaN: none; see [`crate::crowd::environment`]).
    pub fn waypoints(&self) -> &[Vec2] {
        &self.waypoints
    }

    /// Each agent's current motion type (empty without a scene).
    pub fn motions(&self) -> &[MotionType] {
        &self.motions
    }

    /// Applies a reloaded config's tunables and its scene. The crowd size,
    /// formation, mesh and world mapping need a restart (or `set_agent_count`);
    /// returns the names of changed settings that were not applied.
    ///
    /// A scene that differs from the running one (another file, an edited one, or
    /// none) replaces it from the next tick; see [`Engine::reconfigure_with`]. With
    /// inline assignment this builds the new scene's planner here; the daemon builds
    /// it off the control thread and passes it to `reconfigure_with` instead.
    pub fn reconfigure(&mut self, cfg: &Config) -> Vec<&'static str> {
        self.reconfigure_with(cfg, None)
    }

    /// [`Engine::reconfigure`] with the inline planner for `cfg`'s scene already
    /// built ([`inline_planner`]), so the swap itself is cheap: no allocation
    /// beyond what dropping the old scene frees, O(mesh vertices × obstacle parts)
    /// work to push the mesh out of the new obstacles. `planner` is used only when
    /// the scene changes, the engine assigns inline, and it plans over that very
    /// scene; otherwise it is dropped.
    ///
    /// On a scene change the agents keep their positions and velocities; their
    /// waypoints are cleared and assignment results solved for the old scene are
    /// discarded (the crowd generation changes), the mesh goals are pushed out of
    /// the new obstacles, and from the next tick agents move at the new patches'
    /// speeds, are kept out of the new obstacles and report the new motions. Scene
    /// time runs on, so moving obstacles continue from where the clock is.
    pub fn reconfigure_with(
        &mut self,
        cfg: &Config,
        planner: Option<Planner>,
    ) -> Vec<&'static str> {
        let mut ignored = Vec::new();
        if cfg.surface.world != self.world {
            ignored.push("surface.world");
        }
        if cfg.crowd.formation != self.formation {
            ignored.push("crowd.formation");
        }
        if cfg.mesh.cols as usize * cfg.mesh.rows as usize != self.direct.mesh().vertex_count() {
            ignored.push("mesh.cols/rows");
        }
        self.grab_radius_m = cfg.controls.grab_radius_m;
        self.configured_radius_m = cfg.crowd.agent_radius_m;
        self.formations = Arc::clone(cfg.formation_library());
        self.formation_lambda = cfg.formations.lambda;
        self.agent_params = agent_params(cfg);
        self.segmenter.set_params(segment_params(cfg));
        self.direct.set_params(direct_params(cfg));
        self.fit_radius();
        let params = planner_params(cfg);
        let scene_changed = !same_scene(cfg.loaded_scene(), self.scene.as_ref());
        let params_changed = params != self.planner_params;
        self.planner_params = params;
        if scene_changed {
            self.set_scene(cfg.loaded_scene().cloned());
        }
        if self.inline.is_some() && (scene_changed || params_changed) {
            self.planner = match planner.filter(|p| {
                self.scene
                    .as_ref()
                    .is_some_and(|s| Arc::ptr_eq(s, p.scene()))
            }) {
                Some(p) => Some(p),
                None => self.scene.as_ref().and_then(|s| planner_for(s, params)),
            };
        }
        self.set_mesh_environment();
        ignored
    }

    /// Swaps the scene (see [`Engine::reconfigure_with`]).
    fn set_scene(&mut self, scene: Option<Arc<Scene>>) {
        self.scene = scene;
        self.prev_centroid = None;
        if self.scene.is_none() {
            self.motions.clear();
        }
        self.waypoints.fill(Vec2::repeat(f64::NAN));
        self.generation += 1;
        if let Some(a) = &mut self.inline {
            a.forget();
        }
    }

    /// Counters.
    pub fn counters(&self) -> EngineCounters {
        self.counters
    }

    /// Number of agents.
    pub fn agent_count(&self) -> usize {
        self.agents.len()
    }

    /// Live controls.
    pub fn control_count(&self) -> usize {
        self.segmenter.controls().len()
    }

    /// The agent radius in use (m): the configured one, shrunk to fit the formation.
    pub fn agent_radius_m(&self) -> f64 {
        self.agent_params.radius_m
    }

    /// The world rectangle (m).
    pub fn world(&self) -> Rect {
        self.world
    }

    /// Identifies the current crowd; assignment results for another generation are stale.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Sequence number of the last tick.
    pub fn seq(&self) -> u64 {
        self.seq
    }

    /// Agent positions (m).
    pub fn agent_positions(&self) -> &[Vec2] {
        self.agents.positions()
    }

    /// Agent velocities (m/s).
    pub fn agent_velocities(&self) -> &[Vec2] {
        self.agents.velocities()
    }

    /// Goal index of each agent.
    pub fn goal_of(&self) -> &[u32] {
        &self.goal_of
    }

    /// Goal positions (m).
    pub fn goals(&self) -> &[Vec2] {
        self.direct.goals()
    }

    /// The current mesh as published.
    pub fn mesh_view(&self) -> MeshView {
        MeshView {
            seq: self.seq,
            vertices: self.direct.vertices().to_vec(),
            triangles: Arc::clone(&self.triangles),
            outline: Arc::clone(&self.outline),
            topology: self.topology,
        }
    }

    fn fit_radius(&mut self) {
        let n = self.agents.len().max(1) as f64;
        let area = self.formation.width() * self.formation.height();
        let fit = RADIUS_FIT * (area / n).sqrt();
        self.agent_params.radius_m = self.configured_radius_m.min(fit);
    }

    fn to_world(&self, x: f32, y: f32) -> Vec2 {
        Vec2::new(
            self.world.min[0] + x as f64 * self.world.width(),
            self.world.min[1] + y as f64 * self.world.height(),
        )
    }

    /// Feeds one input frame (segmentation happens at the frame's own time stamp).
    pub fn push_frame(&mut self, frame: &TouchFrame) {
        let t = frame.t;
        for c in frame.contacts() {
            let world = self.to_world(c.x, c.y);
            let tp = TouchPoint {
                id: c.id,
                world,
                glass_mm: Vec2::new(c.x as f64 * self.glass_mm.x, c.y as f64 * self.glass_mm.y),
                flags: c.flags,
            };
            let on_crowd =
                c.flags.contains(ContactFlags::DOWN) && self.direct.hits(world, self.grab_radius_m);
            self.segmenter.touch(t, &tp, on_crowd, &mut self.seg_out);
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

    /// Applies a client command at `now`.
    ///
    /// # Errors
    /// A message for the client when the command cannot be applied.
    pub fn command(&mut self, cmd: &Command, now: Micros) -> Result<(), String> {
        match cmd {
            Command::Reset { hard } => {
                self.reset(*hard, now);
                Ok(())
            }
            Command::SetAgentCount { count } => {
                self.set_agent_count(*count, now).map_err(|e| e.to_string())
            }
            Command::SetFormation { formation } => self.set_formation(formation, now),
            Command::Pause => {
                if !self.paused {
                    self.paused = true;
                    self.events.push(Event::Paused {
                        paused: true,
                        t: now,
                    });
                }
                Ok(())
            }
            Command::Resume => {
                if self.paused {
                    self.paused = false;
                    self.events.push(Event::Paused {
                        paused: false,
                        t: now,
                    });
                }
                Ok(())
            }
        }
    }

    /// Mesh back to rest in the start formation; controls end. `hard` teleports
    /// agents to their goals.
    pub fn reset(&mut self, hard: bool, now: Micros) {
        self.segmenter.cancel_all(now, &mut self.seg_out);
        self.forget_switches();
        if self.formation_name != START {
            self.restore_start(now);
        }
        self.direct.reset();
        if hard {
            self.prev_centroid = None;
            self.agents.teleport(self.direct.goals());
            self.goal_of.clear();
            self.goal_of.extend(0..self.agents.len() as u32);
            self.waypoints.fill(Vec2::repeat(f64::NAN));
            self.generation += 1;
            if let Some(a) = &mut self.inline {
                a.forget();
            }
            if let Some(p) = &mut self.planner {
                p.forget();
            }
        }
        self.events.push(Event::Reset {
            agents: self.agents.len() as u32,
            hard,
            t: now,
        });
    }

    /// New crowd size: agents are placed on the new goals of the current mesh.
    ///
    /// # Errors
    /// [`Error::AgentCount`] when out of range.
    pub fn set_agent_count(&mut self, count: u32, now: Micros) -> Result<(), Error> {
        if count == 0 || count > MAX_AGENTS {
            return Err(Error::AgentCount {
                count,
                max: MAX_AGENTS,
            });
        }
        self.direct.set_agent_count(count as usize);
        self.agents = Agents::new(self.direct.goals());
        self.prev_centroid = None;
        self.forget_switches();
        self.start_samples = if self.formation_name == START {
            self.direct.samples().to_vec()
        } else {
            crate::crowd::mesh::sample_goals(&self.start_mesh, count as usize)
        };
        self.goal_of.clear();
        self.goal_of.extend(0..count);
        self.waypoints.clear();
        self.waypoints
            .resize(count as usize, Vec2::repeat(f64::NAN));
        self.generation += 1;
        if let Some(a) = &mut self.inline {
            a.forget();
        }
        if let Some(p) = &mut self.planner {
            p.forget();
        }
        self.fit_radius();
        self.set_mesh_environment();
        self.events.push(Event::Reset {
            agents: count,
            hard: true,
            t: now,
        });
        Ok(())
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
        let t0 = *self.scene_t0.get_or_insert(now);
        self.scene_t_s = now.saturating_since(t0).as_secs_f64();
        self.direct.set_time(self.scene_t_s);
        let lag = self
            .agents
            .mean_goal_distance(self.direct.goals(), &self.goal_of);
        if let Err(e) = self.direct.update(self.segmenter.controls(), dt, lag) {
            self.counters.deform_errors += 1;
            if self.counters.deform_errors.is_power_of_two() {
                log::warn!(
                    "internal: mesh deformation failed ({} times): {e}",
                    self.counters.deform_errors
                );
            }
        }
        if !self.paused {
            if self.scene.is_some() {
                self.step_in_scene(dt);
            } else {
                self.agents
                    .step(self.direct.goals(), &self.goal_of, dt, &self.agent_params);
            }
        }
        if let Some(scene) = &self.scene {
            self.motions.clear();
            let t = self.scene_t_s;
            self.motions.extend(
                self.agents
                    .positions()
                    .iter()
                    .map(|&p| scene.terrain_at(p, t).motion),
            );
        }
        self.pass_checkpoints(now);
        self.translate_segments(now);
        for v in &mut self.touches {
            v.control = self
                .segmenter
                .control_of(crate::vocab::ContactId(v.id))
                .map(|c| c.id);
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
            s.agents.extend(
                self.agents
                    .positions()
                    .iter()
                    .zip(self.agents.velocities())
                    .zip(&self.goal_of)
                    .map(|((&pos, &vel), &goal)| AgentView { pos, vel, goal }),
            );
            s.goals.clear();
            s.goals.extend_from_slice(self.direct.goals());
            s.assignment_seq = self.assignment_seq;
            s.touches.clear();
            s.touches.extend_from_slice(&self.touches);
            s.motions.clear();
            s.motions.extend_from_slice(&self.motions);
            s.paused = self.paused;
        }
        self.snapshots.keep(&snap);
        self.counters.ticks += 1;
        // Inline assignment: solved on this tick's state, used from the next tick.
        // (The error's text is formed only on a failure, which is logged.)
        let result = match (&mut self.planner, &mut self.inline) {
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
            events: &self.events,
        }
    }

    /// The formation the crowd is in: [`START`] (the config's `crowd.formation`
    /// grid) or the name of a formation a checkpoint switched to.
    pub fn formation(&self) -> &str {
        &self.formation_name
    }

    /// Switches to formation `name`, as a checkpoint would (see
    /// [`Engine::formation`]), heading the way the crowd moves (`+x` when it
    /// stands still). Asking for the current formation changes nothing. With the
    /// formation thread ([`Engine::set_switch_worker`]) the switch happens a few
    /// ticks later, when it is ready; a `formation` event says when.
    ///
    /// # Errors
    /// A message naming the known formations when `name` is not one; without the
    /// formation thread, also why the formation could not be built.
    pub fn set_formation(&mut self, name: &str, now: Micros) -> Result<(), String> {
        if !self.formations.knows(name) {
            let shown: String = name.chars().take(64).collect();
            let cut = if shown.len() < name.len() { "…" } else { "" };
            return Err(format!(
                "no formation is called `{shown}{cut}`; the config defines {}",
                self.formations.names_list()
            ));
        }
        let n = self.agents.len().max(1) as f64;
        let v = self.agents.velocities().iter().sum::<Vec2>() / n;
        let heading = if v.norm() > 1e-3 {
            v
        } else {
            Vec2::new(1.0, 0.0)
        };
        self.request_switch(name, None, heading, now)
            .map_err(|e| format!("formation `{name}` could not be built: {e}"))
    }

    /// Prepares formation switches on the daemon's formation thread instead of
    /// inside the tick (the daemon; replays keep them in the tick, deterministic).
    pub fn set_switch_worker(&mut self, on: bool) {
        self.switch_worker = on;
    }

    /// The switch request for the formation thread, if one is waiting
    /// ([`SwitchRequest::prepare`] it, then [`Engine::apply_switch`]).
    pub fn take_switch_request(&mut self) -> Option<SwitchRequest> {
        self.switch_outbox.take()
    }

    /// Switches formation when the crowd's centroid passed a scene checkpoint since
    /// the last tick (mesh-formation-control section 7.3; the last one passed wins
    /// when a tick crosses several). Passing a checkpoint that names the current
    /// formation (or the one being prepared) changes nothing. No allocation unless
    /// a switch is asked for.
    fn pass_checkpoints(&mut self, now: Micros) {
        let n = self.agents.len();
        if n == 0 {
            return;
        }
        let c = self.agents.positions().iter().sum::<Vec2>() / n as f64;
        let prev = self.prev_centroid.replace(c);
        let (Some(scene), Some(prev)) = (&self.scene, prev) else {
            return;
        };
        let Some(k) = scene
            .checkpoints()
            .iter()
            .rposition(|cp| cp.crossed(prev, c))
        else {
            return;
        };
        let target = self
            .switch_pending
            .as_deref()
            .unwrap_or(&self.formation_name);
        if scene.checkpoints()[k].formation == target {
            return;
        }
        // The scene outlives the request (an `Arc` clone, no allocation).
        let scene = Arc::clone(scene);
        let cp = &scene.checkpoints()[k];
        let _ = self.request_switch(&cp.formation, Some(&cp.name), c - prev, now);
    }

    /// Asks for formation `name` (mesh-formation-control section 7.3).
    ///
    /// A library formation is laid out with the user mesh's current area and
    /// centroid, its `+x` along `heading` (the crowd's motion), shifted inside the
    /// world when it fits, with about as many vertices as the start mesh; [`START`]
    /// is the start mesh's grid moved to the crowd (a reset, by contrast, brings it
    /// back where it was configured). The mesh, its goal samples and
    /// the least-effort pairing (formation-transform eq. 3) are prepared by
    /// [`SwitchRequest::prepare`]: here at once, or on the formation thread, in
    /// which case a request asked for while one is out waits for it (the last
    /// one asked for wins).
    fn request_switch(
        &mut self,
        name: &str,
        checkpoint: Option<&str>,
        heading: Vec2,
        now: Micros,
    ) -> Result<(), String> {
        if self.switch_pending.is_some() {
            self.switch_queued = Some((name.to_string(), checkpoint.map(str::to_string), heading));
            return Ok(());
        }
        if name == self.formation_name {
            return Ok(());
        }
        let centre = self.user_centroid();
        let mut start_at_m = centre;
        let target = if name == START {
            // The start grid's shape where the crowd is, inside the world.
            let r = self.start_mesh.rest();
            let c = r.iter().sum::<Vec2>() / r.len().max(1) as f64;
            let moved: Vec<Vec2> = r.iter().map(|p| p - c + centre).collect();
            start_at_m += shift_inside(&moved, self.world);
            None
        } else {
            let Some(f) = self.formations.get(name) else {
                let why = "the config defines no formation of that name";
                self.formation_failed(name, why);
                return Err(why.to_string());
            };
            let mut place = Placement {
                centre_m: centre,
                heading,
                area_m2: self.user_mesh_area(),
            };
            place.centre_m += shift_inside(&f.placed_outline(&place), self.world);
            Some((f.clone(), place))
        };
        let req = SwitchRequest {
            name: name.to_string(),
            checkpoint: checkpoint.map(str::to_string),
            epoch: self.switch_epoch,
            target,
            start_at_m,
            anchor_m: centre,
            start_mesh: Arc::clone(&self.start_mesh),
            vertices: self.start_mesh.vertex_count(),
            agents: self.agents.positions().to_vec(),
            lambda: self.formation_lambda,
        };
        self.switch_pending = Some(name.to_string());
        if self.switch_worker {
            self.switch_outbox = Some(req);
            Ok(())
        } else {
            self.apply_switch(req.prepare(), now)
        }
    }

    /// Uses a prepared switch: the new mesh replaces the old one (moved by as much
    /// as the crowd moved since it was asked for, so a drag does not jump back),
    /// live drags go on over it ([`DirectController::set_mesh_sampled`]), agents
    /// take the least-effort pairing at once and the running assignment (Euclidean
    /// or Eikonal) takes over from its next result; results solved for the old
    /// goals are discarded. A switch asked for before a reset or resize is dropped.
    /// Allocates (a one-off, like a resize). A formation that could not be meshed
    /// is logged and counted, and the crowd keeps its formation; the error says why.
    pub fn apply_switch(&mut self, p: PreparedSwitch, now: Micros) -> Result<(), String> {
        if p.epoch != self.switch_epoch {
            return Ok(());
        }
        self.switch_pending = None;
        let result = match p.built {
            Err(e) => {
                self.formation_failed(&p.name, &e);
                Err(e)
            }
            Ok(b) => {
                let mut mesh = b.mesh;
                mesh.translate(self.user_centroid() - p.anchor_m);
                self.install(mesh, b.samples, &b.goal_of);
                if p.checkpoint.is_some() {
                    self.counters.formation_switches += 1;
                }
                self.switched(p.name, p.checkpoint, now);
                Ok(())
            }
        };
        if let Some((name, checkpoint, heading)) = self.switch_queued.take() {
            let _ = self.request_switch(&name, checkpoint.as_deref(), heading, now);
        }
        result
    }

    /// The crowd is in formation `name` now: logged, and a `formation` event.
    fn switched(&mut self, name: String, checkpoint: Option<String>, now: Micros) {
        let vertices = self.direct.mesh().vertex_count();
        log::info!(
            "formation `{name}`{} ({vertices} vertices)",
            checkpoint
                .as_ref()
                .map(|c| format!(" at checkpoint `{c}`"))
                .unwrap_or_default(),
        );
        self.formation_name.clear();
        self.formation_name.push_str(&name);
        self.events.push(Event::Formation {
            name,
            checkpoint,
            vertices: vertices as u32,
            t: now,
        });
    }

    /// The new mesh in the controller, its topology for clients, `goal_of` (when
    /// it pairs every agent), a new crowd generation.
    fn install(&mut self, mesh: TriMesh, samples: Vec<GoalSample>, goal_of: &[u32]) {
        self.direct.set_mesh_sampled(mesh, samples);
        self.triangles = Arc::new(self.direct.mesh().triangles().to_vec());
        self.outline = Arc::new(self.direct.mesh().outline().to_vec());
        self.topology += 1;
        if goal_of.len() == self.goal_of.len() {
            self.goal_of.copy_from_slice(goal_of);
        }
        self.waypoints.fill(Vec2::repeat(f64::NAN));
        self.generation += 1;
        self.assignment_seq = self.seq;
        if let Some(a) = &mut self.inline {
            a.forget();
        }
        if let Some(p) = &mut self.planner {
            p.forget();
        }
    }

    /// The start mesh back where it was configured (a reset), with its cached goal
    /// samples: no slow work.
    fn restore_start(&mut self, now: Micros) {
        let samples = self.start_samples.clone();
        self.install((*self.start_mesh).clone(), samples, &[]);
        self.switched(START.to_string(), None, now);
    }

    /// Drops switches asked for or queued (a reset or resize).
    fn forget_switches(&mut self) {
        self.switch_epoch += 1;
        self.switch_pending = None;
        self.switch_queued = None;
        self.switch_outbox = None;
    }

    fn formation_failed(&mut self, name: &str, why: &str) {
        self.counters.formation_errors += 1;
        if self.counters.formation_errors.is_power_of_two() {
            log::warn!(
                "formation `{name}` not used ({} times): {why}; the crowd keeps formation `{}`",
                self.counters.formation_errors,
                self.formation_name
            );
        }
    }

    /// Mean of the user mesh's vertices (m).
    fn user_centroid(&self) -> Vec2 {
        let user = self.direct.user_vertices();
        user.iter().sum::<Vec2>() / user.len().max(1) as f64
    }

    /// Area of the user mesh in its current pose (m²).
    fn user_mesh_area(&self) -> f64 {
        let a = self.direct.mesh().area_at(self.direct.user_vertices());
        if a.is_finite() && a > 0.0 {
            a
        } else {
            self.start_mesh.area()
        }
    }

    /// One agent step in the scene: steer at the goal or the waypoint, speed limit
    /// scaled by the terrain, then out of obstacles by one agent radius
    /// (mesh-formation-control sections 6.2.1 and 6.2.3). No allocation once the
    /// buffers have the crowd's size.
    fn step_in_scene(&mut self, dt: f64) {
        let Some(scene) = &self.scene else {
            return;
        };
        let t = self.scene_t_s;
        let goals = self.direct.goals();
        self.targets.clear();
        self.speed_factor.clear();
        for (i, &p) in self.agents.positions().iter().enumerate() {
            let g = goals[self.goal_of[i] as usize];
            let w = self
                .waypoints
                .get(i)
                .copied()
                .unwrap_or(Vec2::repeat(f64::NAN));
            self.targets.push(steer_target(scene, p, g, w, t));
            self.speed_factor.push(scene.terrain_at(p, t).speed_factor);
        }
        self.agents
            .step_towards(&self.targets, &self.speed_factor, dt, &self.agent_params);
        let r = self.agent_params.radius_m;
        for i in 0..self.agents.len() {
            let p = self.agents.positions()[i];
            if scene.signed_distance(p, t) < r {
                let q = scene.project_out(p, r, t);
                self.agents.set_position(i, q);
            }
        }
    }

    /// Clears the events of the last tick (call after publishing them).
    pub fn clear_events(&mut self) {
        self.events.clear();
    }

    fn translate_segments(&mut self, now: Micros) {
        for s in self.seg_out.drain(..) {
            let ev = match s {
                Segment::ControlBegin(id) | Segment::ControlUpdate(id) => {
                    let fingers = self
                        .segmenter
                        .controls()
                        .iter()
                        .find(|c| c.id == id)
                        .map(|c| c.fingers.iter().map(|f| f.id.0).collect::<Vec<_>>())
                        .unwrap_or_default();
                    let kind = crate::gesture::segment::control_kind(fingers.len());
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
                Segment::GestureBegin(id) => Event::GestureBegin { id, t: now },
                Segment::GestureEnd {
                    id,
                    fingers,
                    contacts,
                    duration,
                    cancelled,
                } => Event::GestureEnd {
                    id,
                    fingers,
                    contacts,
                    duration_us: duration.0,
                    cancelled,
                    t: now,
                },
            };
            self.events.push(ev);
        }
    }
}

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

fn agent_params(cfg: &Config) -> AgentParams {
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

fn segment_params(cfg: &Config) -> SegmentParams {
    SegmentParams {
        group_window: Micros(cfg.controls.group_window_ms * 1000),
        hand_span_mm: cfg.controls.hand_span_mm,
        gesture_grace: Micros(cfg.controls.gesture_grace_ms * 1000),
    }
}

/// The translation that brings `poly`'s bounding box inside `world` (centred on
/// an axis where it does not fit).
fn shift_inside(poly: &[Vec2], world: Rect) -> Vec2 {
    let mut d = Vec2::zeros();
    if poly.is_empty() {
        return d;
    }
    for k in 0..2 {
        let lo = poly.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = poly.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        let (w0, w1) = (world.min[k], world.max[k]);
        d[k] = if hi - lo > w1 - w0 {
            0.5 * (w0 + w1) - 0.5 * (lo + hi)
        } else if lo < w0 {
            w0 - lo
        } else if hi > w1 {
            w1 - hi
        } else {
            0.0
        };
    }
    if d.x.is_finite() && d.y.is_finite() {
        d
    } else {
        Vec2::zeros()
    }
}

fn direct_params(cfg: &Config) -> DirectParams {
    DirectParams {
        handle_weight: cfg.mesh.handle_weight,
        soft_weight: cfg.mesh.soft_weight,
        checkpoint_spacing_m: cfg.controls.checkpoint_spacing_m,
        max_constraint_speed_m_s: cfg.controls.max_constraint_speed_m_s,
        opposing_gain_per_s: cfg.controls.opposing_gain_per_s,
    }
}

/// Plays frames through `engine` on a virtual clock: a tick at every frame's time
/// stamp and, between frames, every `period` as the daemon's timer would; then
/// `settle` more time of timer ticks. `on_tick` sees every tick's output (events are
/// cleared after it returns). `pace(t)` is called before each tick (a no-op for
/// as-fast-as-possible replays; a sleep for real-time ones).
///
/// Deterministic: the same frames and config give the same ticks.
///
/// # Errors
/// The first error `on_tick` returns stops the replay and is returned.
pub fn replay_virtual<E>(
    engine: &mut Engine,
    frames: &[TouchFrame],
    period: Micros,
    settle: Micros,
    mut pace: impl FnMut(Micros),
    mut on_tick: impl FnMut(&TickOutput<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let period = Micros(period.0.max(1));
    let mut t = frames.first().map_or(Micros::ZERO, |f| f.t);
    let mut step = |engine: &mut Engine, now: Micros| -> Result<(), E> {
        pace(now);
        let r = {
            let o = engine.tick(now);
            on_tick(&o)
        };
        engine.clear_events();
        r
    };
    for f in frames {
        while t + period < f.t {
            t = t + period;
            step(engine, t)?;
        }
        t = t.max(f.t);
        engine.push_frame(f);
        step(engine, t)?;
    }
    let end = t + settle;
    while t + period <= end {
        t = t + period;
        step(engine, t)?;
    }
    Ok(())
}
