//! The engine's state: what it owns, how it is built from the config and
//! reconfigured, and what it reports.

use super::params::{
    agent_params, direct_params, inline_planner, mesh_field_params, planner_for, planner_params,
    point_metric, same_scene, segment_params,
};
use super::pool::ArcPool;
use crate::config::Config;
use crate::crowd::agents::{AgentParams, Agents, GroundCache};
use crate::crowd::assign::Assigner;
use crate::crowd::control::{DirectController, ResizeRequest, SwitchRequest};
use crate::crowd::environment::{Placement, Planner, PlannerParams, Scene, Terrain};
use crate::crowd::formation::{FormationLibrary, START};
use crate::crowd::mesh::{GoalSample, TriMesh};
use crate::geom::{Rect, Vec2};
use crate::gesture::segment::{Segment, Segmenter};
use crate::vocab::{Event, MeshView, Micros, MotionType, Snapshot, TouchView};
use std::sync::Arc;

/// Longest time step the engine integrates in one tick (s); a longer gap (a stall,
/// a paused replay) is treated as this long.
pub const MAX_TICK_S: f64 = 0.1;
/// Fraction of the mean goal spacing an agent's radius may take when the formation
/// is too small for the configured radius.
pub const RADIUS_FIT: f64 = 0.45;

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

/// The engine's resize bookkeeping.
#[derive(Debug, Default)]
pub(super) struct ResizeState {
    /// Bumped by every resize asked for: a request or result with another ticket
    /// is stale.
    pub(super) ticket: u64,
    /// The crowd size being prepared (`None`: no resize out).
    pub(super) pending: Option<u32>,
    /// A request for the formation thread, until the pipeline takes it.
    pub(super) outbox: Option<ResizeRequest>,
}

/// The control core.
pub struct Engine {
    pub(super) world: Rect,
    pub(super) glass_mm: Vec2,
    pub(super) grab_radius_m: f64,
    /// `mesh.field_step_m` (m).
    pub(super) field_step_m: f64,
    pub(super) formation: Rect,
    pub(super) agent_params: AgentParams,
    pub(super) configured_radius_m: f64,
    /// Most agents `set_agent_count` accepts ([`Config::max_agents`]).
    pub(super) max_agents: u32,
    pub(super) segmenter: Segmenter,
    pub(super) direct: DirectController,
    pub(super) agents: Agents,
    pub(super) goal_of: Vec<u32>,
    pub(super) assignment_seq: u64,
    pub(super) generation: u64,
    pub(super) inline: Option<Assigner>,
    pub(super) scene: Option<Arc<Scene>>,
    pub(super) planner: Option<Planner>,
    pub(super) planner_params: PlannerParams,
    pub(super) scene_t0: Option<Micros>,
    pub(super) scene_t_s: f64,
    pub(super) waypoints: Vec<Vec2>,
    pub(super) targets: Vec<Vec2>,
    pub(super) motions: Vec<MotionType>,
    /// The terrain under each agent, kept with the point it was read at (what
    /// `motions` and the scene's speed limits come from): read again only where
    /// an agent moved. Forgotten when the scene changes, and every tick in a
    /// scene whose patches move.
    pub(super) terrain: GroundCache<Terrain>,
    /// Where the scene's moving parts are this tick ([`Scene::at`]).
    pub(super) scene_placements: Vec<Placement>,
    pub(super) seq: u64,
    pub(super) last_t: Option<Micros>,
    pub(super) pending_input_t: Option<Micros>,
    pub(super) paused: bool,
    pub(super) seg_out: Vec<Segment>,
    pub(super) events: Vec<Event>,
    pub(super) touches: Vec<TouchView>,
    pub(super) snapshots: ArcPool<Snapshot>,
    pub(super) meshes: ArcPool<MeshView>,
    pub(super) triangles: Arc<Vec<[u32; 3]>>,
    pub(super) outline: Arc<Vec<u32>>,
    pub(super) outlines: Arc<Vec<Vec<u32>>>,
    pub(super) topology: u64,
    pub(super) counters: EngineCounters,
    /// Formation shapes the scene's checkpoints name.
    pub(super) formations: Arc<FormationLibrary>,
    /// `λ` of the least-effort pairing at a switch.
    pub(super) formation_lambda: f64,
    /// The formation the crowd is in ([`START`] or a library name).
    pub(super) formation_name: String,
    /// The mesh the crowd starts in (and a reset brings back).
    pub(super) start_mesh: Arc<TriMesh>,
    /// Agent centroid after the last tick, to see checkpoints being crossed.
    pub(super) prev_centroid: Option<Vec2>,
    /// Goal samples of the start mesh for the current crowd size (for a reset).
    pub(super) start_samples: Vec<GoalSample>,
    /// Switches are prepared by the daemon's formation thread
    /// ([`Engine::take_switch_request`], [`Engine::apply_switch`]), not in the tick.
    pub(super) switch_worker: bool,
    /// Bumped by a reset or resize: a switch prepared before it is stale.
    pub(super) switch_epoch: u64,
    /// The formation a request is out for.
    pub(super) switch_pending: Option<String>,
    /// The last switch asked for while one was out: `(name, checkpoint, heading)`.
    pub(super) switch_queued: Option<(String, Option<String>, Vec2)>,
    /// A request for the formation thread, until the pipeline takes it.
    pub(super) switch_outbox: Option<SwitchRequest>,
    /// The resize being prepared, if any (`resize.rs`).
    pub(super) resize: ResizeState,
    /// Gesture commands: capture, recognition, the motion playing (`gesture.rs`).
    pub(super) gestures: super::gesture_state::Gestures,
    /// Formation transforms: settings, the request out, the run (`transform.rs`).
    pub(super) transforms: super::transform_state::Transforms,
    /// Edit mode: the tracks, the grab, the jobs out (`edit.rs`).
    pub(super) edits: super::edit_state::Edits,
    /// A `library collect` session, when one runs.
    pub(super) collect: Option<Box<super::collect_state::Collecting>>,
    /// The scene to publish: whether it changed, the poses' pool (`scene_state.rs`).
    pub(super) scene_out: super::scene_state::SceneOut,
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
            field_step_m: cfg.mesh.field_step_m,
            formation: cfg.crowd.formation,
            agent_params: agent_params(cfg),
            configured_radius_m: cfg.crowd.agent_radius_m,
            max_agents: cfg.max_agents(),
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
            motions: Vec::with_capacity(agents_n),
            terrain: GroundCache::with_capacity(agents_n),
            scene_placements: Vec::with_capacity(
                cfg.loaded_scene().map_or(0, |s| s.dynamic().len()),
            ),
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
            outlines: Arc::default(),
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
            resize: ResizeState::default(),
            gestures: super::gesture_state::Gestures::new(cfg, inline_assignment),
            transforms: super::transform_state::Transforms::new(cfg, cfg.crowd.agent_radius_m),
            edits: super::edit_state::Edits::new(),
            collect: None,
            scene_out: super::scene_state::SceneOut::new(),
        };
        e.segmenter
            .set_all_touches_are_gestures(cfg.gestures.all_touches_are_gestures);
        e.start_samples = e.direct.samples().to_vec();
        e.fit_radius();
        if inline_assignment {
            e.planner = inline_planner(cfg);
        }
        e.set_mesh_environment();
        e.configure_edit(cfg, Micros(0));
        e
    }

    /// The mesh's environment field at the current agent radius.
    pub(super) fn set_mesh_environment(&mut self) {
        let env = self.scene.as_ref().and_then(|s| {
            mesh_field_params(self.field_step_m, self.agent_params.radius_m)
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
        self.field_step_m = cfg.mesh.field_step_m;
        self.configured_radius_m = cfg.crowd.agent_radius_m;
        self.max_agents = cfg.max_agents();
        self.formations = Arc::clone(cfg.formation_library());
        self.formation_lambda = cfg.formations.lambda;
        self.agent_params = agent_params(cfg);
        self.segmenter.set_params(segment_params(cfg));
        self.segmenter
            .set_all_touches_are_gestures(cfg.gestures.all_touches_are_gestures);
        self.gestures.configure(cfg);
        self.transforms.settings =
            super::transform_state::TransformSettings::from_config(cfg, cfg.crowd.agent_radius_m);
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
        let now = self.last_t.unwrap_or(Micros(0));
        self.configure_edit(cfg, now);
        ignored
    }

    /// Swaps the scene (see [`Engine::reconfigure_with`]).
    pub(super) fn set_scene(&mut self, scene: Option<Arc<Scene>>) {
        self.scene = scene;
        // The moving parts' placements of one tick: reserved here, not on the
        // control thread's first scene tick.
        let moving = self.scene.as_ref().map_or(0, |s| s.dynamic().len());
        self.scene_placements.clear();
        self.scene_placements.reserve(moving);
        self.scene_out.changed = true;
        self.terrain.forget();
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

    /// The goals changed: a new assignment generation (results for the old goals are
    /// stale), and the inline assigner and the planner forget what they kept.
    pub(super) fn forget_assignments(&mut self) {
        self.generation += 1;
        if let Some(a) = &mut self.inline {
            a.forget();
        }
        if let Some(p) = &mut self.planner {
            p.forget();
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
            outlines: Arc::clone(&self.outlines),
            topology: self.topology,
        }
    }

    pub(super) fn fit_radius(&mut self) {
        let n = self.agents.len().max(1) as f64;
        let area = self.formation.width() * self.formation.height();
        let fit = RADIUS_FIT * (area / n).sqrt();
        self.agent_params.radius_m = self.configured_radius_m.min(fit);
    }
}
