//! Direct manipulation: fingers on the crowd deform its mesh
//! (mesh-formation-control sections 4.1–4.2).
//!
//! Each control from the segmenter becomes a *rig*: one handle per finger (the
//! nearest mesh vertex when the finger landed, kept at its offset from the finger)
//! plus supplementary soft constraints — for a line control the vertices between its
//! two handles, moved by linear interpolation of the handles; for an area control
//! the vertices on and inside the convex hull of its handles, moved by their mean
//! value coordinates in that hull. All rigs' constraints go to one ARAP solve, so
//! several controls (two hands, two people) act on the mesh together.
//!
//! The mesh is as rigid as possible relative to its pose when the constraint set
//! last changed (a finger landed or lifted): a deformation persists until another
//! control changes it, and `reset` returns to the formation.
//!
//! Handles follow their finger through check points spaced along its trajectory
//! (section 4.1: "We represent each trajectory as a set of two-dimensional check
//! points by dividing the trajectory into segments of a pre-defined length"), at the
//! constraint speed less the opposing force proportional to the agents' lag.

use crate::crowd::environment::Scene;
use crate::crowd::environment::{displace_vertices, FieldParams};
use crate::crowd::mesh::{convex_hull, mean_value_coordinates, point_in_convex_polygon};
use crate::crowd::mesh::{goal_positions, nearest_vertex, GoalSample, TriMesh};
use crate::crowd::mesh::{Arap, ArapError, Constraint};
use crate::geom::Vec2;
use crate::gesture::segment::Control;
use crate::vocab::ContactId;
use crate::vocab::ControlKind;
use std::sync::Arc;

/// Tunables of direct manipulation.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DirectParams {
    /// ARAP weight of a finger's own vertex.
    pub handle_weight: f64,
    /// ARAP weight of supplementary line/area points.
    pub soft_weight: f64,
    /// Spacing of trajectory check points (m).
    pub checkpoint_spacing_m: f64,
    /// Fastest a handle moves towards its finger (m/s).
    pub max_constraint_speed_m_s: f64,
    /// Opposing force per metre of mean agent lag (1/s).
    pub opposing_gain_per_s: f64,
}

/// Check points a handle keeps ahead of it; older ones are merged when full.
const PATH_CAPACITY: usize = 128;

/// Check points along a finger's trajectory, oldest first (fixed capacity).
#[derive(Clone, Debug)]
struct Path {
    pts: [Vec2; PATH_CAPACITY],
    head: usize,
    len: usize,
}

impl Path {
    fn new() -> Path {
        Path {
            pts: [Vec2::zeros(); PATH_CAPACITY],
            head: 0,
            len: 0,
        }
    }
    fn get(&self, i: usize) -> Vec2 {
        self.pts[(self.head + i) % PATH_CAPACITY]
    }
    fn last(&self) -> Option<Vec2> {
        (self.len > 0).then(|| self.get(self.len - 1))
    }
    fn push(&mut self, p: Vec2) {
        if self.len == PATH_CAPACITY {
            // Drop the oldest check point: the handle shortcuts a little.
            self.pop_front();
        }
        self.pts[(self.head + self.len) % PATH_CAPACITY] = p;
        self.len += 1;
    }
    fn pop_front(&mut self) {
        if self.len > 0 {
            self.head = (self.head + 1) % PATH_CAPACITY;
            self.len -= 1;
        }
    }
    fn front(&self) -> Option<Vec2> {
        (self.len > 0).then(|| self.get(0))
    }
    /// Moves every check point by `d`.
    fn shift(&mut self, d: Vec2) {
        for i in 0..self.len {
            let k = (self.head + i) % PATH_CAPACITY;
            self.pts[k] += d;
        }
    }
}

#[derive(Clone, Debug)]
struct Handle {
    finger: ContactId,
    vertex: u32,
    /// Vertex position minus finger position when the finger landed (m).
    offset: Vec2,
    /// Current constraint target (m).
    pos: Vec2,
    /// Where the finger wants the handle: latest finger position + offset (m).
    goal: Vec2,
    path: Path,
}

impl Handle {
    fn remaining(&self) -> f64 {
        let mut d = 0.0;
        let mut prev = self.pos;
        for i in 0..self.path.len {
            let p = self.path.get(i);
            d += (p - prev).norm();
            prev = p;
        }
        d + (self.goal - prev).norm()
    }

    /// Adds check points up to the finger's latest target.
    fn record(&mut self, goal: Vec2, spacing: f64) {
        self.goal = goal;
        let mut last = self.path.last().unwrap_or(self.pos);
        let mut d = goal - last;
        let mut n = d.norm();
        while n >= spacing {
            last += d * (spacing / n);
            self.path.push(last);
            d = goal - last;
            n = d.norm();
        }
    }

    /// Moves along the check points by `dist` metres.
    fn advance(&mut self, mut dist: f64) {
        while dist > 0.0 {
            let next = self.path.front().unwrap_or(self.goal);
            let d = next - self.pos;
            let n = d.norm();
            if n <= dist {
                self.pos = next;
                dist -= n;
                if self.path.len == 0 {
                    return;
                }
                self.path.pop_front();
            } else {
                self.pos += d * (dist / n);
                return;
            }
        }
    }
}

#[derive(Clone, Debug)]
enum Support {
    /// Line control: position `t` along handle a→b and `d` across it, both relative
    /// to the handle distance.
    Line { t: f64, d: f64 },
    /// Area control: mean value coordinates over the hull handles.
    Area { weights: Vec<f64> },
}

#[derive(Clone, Debug)]
struct Supplementary {
    vertex: u32,
    support: Support,
}

#[derive(Clone, Debug)]
struct Rig {
    id: u32,
    kind: ControlKind,
    handles: Vec<Handle>,
    /// Handle indices forming the hull (area) or the two ends (line).
    frame: Vec<usize>,
    supp: Vec<Supplementary>,
}

/// Why the controller could not update.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum DirectError {
    /// The deformation failed.
    #[error("mesh deformation failed: {0}")]
    Arap(#[from] ArapError),
}

/// The direct-manipulation controller: the mesh, its rigs and the goals.
pub struct DirectController {
    mesh: TriMesh,
    arap: Arap,
    params: DirectParams,
    /// The user mesh `V_u` (ARAP output).
    verts: Vec<Vec2>,
    /// The final mesh `V_f`: `verts` displaced by the environment (section 6.1).
    final_verts: Vec<Vec2>,
    env: Option<(Arc<Scene>, FieldParams)>,
    t_s: f64,
    anchor: Vec<Vec2>,
    solved: Vec<Vec2>,
    rigs: Vec<Rig>,
    constraints: Vec<Constraint>,
    targets: Vec<Vec2>,
    best_weight: Vec<f64>,
    best_target: Vec<Vec2>,
    samples: Vec<GoalSample>,
    goals: Vec<Vec2>,
    spacing_m: f64,
    changed: bool,
    /// Whether the scene time moved with moving obstacles since the final mesh was
    /// computed ([`DirectController::set_time`]).
    stale: bool,
}

impl DirectController {
    /// A controller over `mesh` with `agents` goal points, at the rest pose.
    pub fn new(mesh: TriMesh, agents: usize, params: DirectParams) -> DirectController {
        let arap = Arap::new(&mesh);
        let verts = mesh.rest().to_vec();
        let n = verts.len();
        let samples = crate::crowd::mesh::sample_goals(&mesh, agents);
        let mut goals = Vec::with_capacity(agents);
        goal_positions(&mesh, &samples, &verts, &mut goals);
        let spacing_m = mean_edge_length(&mesh);
        DirectController {
            arap,
            params,
            anchor: verts.clone(),
            solved: verts.clone(),
            final_verts: verts.clone(),
            env: None,
            t_s: 0.0,
            verts,
            rigs: Vec::new(),
            constraints: Vec::with_capacity(n),
            targets: Vec::with_capacity(n),
            best_weight: vec![0.0; n],
            best_target: vec![Vec2::zeros(); n],
            samples,
            goals,
            spacing_m,
            changed: true,
            stale: false,
            mesh,
        }
    }

    /// Replaces the tunables (config reload).
    pub fn set_params(&mut self, params: DirectParams) {
        self.params = params;
    }

    /// The mesh (topology and rest pose).
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// Current vertex positions of the final mesh (m).
    pub fn vertices(&self) -> &[Vec2] {
        &self.final_verts
    }

    /// Current vertex positions of the user mesh (m): the ARAP output before the
    /// environment moved it (the same as [`vertices`](Self::vertices) without a
    /// scene).
    pub fn user_vertices(&self) -> &[Vec2] {
        &self.verts
    }

    /// Sets the environment: the final mesh becomes the user mesh displaced by the
    /// scene's potential field and projected out of obstacles
    /// (mesh-formation-control sections 5 and 6.1). `None`: the final mesh is the
    /// user mesh.
    pub fn set_environment(&mut self, env: Option<(Arc<Scene>, FieldParams)>) {
        self.env = env;
        self.finalize();
    }

    /// Sets the scene time (s) at which the environment is evaluated; with moving
    /// obstacles the final mesh is recomputed by the next [`update`](Self::update)
    /// (once, whether or not a control deforms the mesh in that tick).
    pub fn set_time(&mut self, t_s: f64) {
        self.t_s = t_s;
        if self
            .env
            .as_ref()
            .is_some_and(|(s, _)| !s.dynamic().is_empty())
        {
            self.stale = true;
        }
    }

    /// `V_f` from `V_u`, then the goals from `V_f`.
    fn finalize(&mut self) {
        self.stale = false;
        self.final_verts.clone_from(&self.verts);
        if let Some((scene, params)) = &self.env {
            displace_vertices(scene, self.t_s, params, &mut self.final_verts);
        }
        goal_positions(
            &self.mesh,
            &self.samples,
            &self.final_verts,
            &mut self.goals,
        );
        self.changed = true;
    }

    /// Goal points on the current mesh (m), one per agent.
    pub fn goals(&self) -> &[Vec2] {
        &self.goals
    }

    /// Whether the mesh moved since the last call (clears the flag).
    pub fn take_changed(&mut self) -> bool {
        std::mem::replace(&mut self.changed, false)
    }

    /// Whether a world point is on the crowd (within `radius_m` of the mesh).
    pub fn hits(&self, p: Vec2, radius_m: f64) -> bool {
        crate::crowd::mesh::distance_to_mesh(&self.mesh, &self.final_verts, p) <= radius_m
    }

    /// Back to the rest pose; rigs are dropped.
    pub fn reset(&mut self) {
        self.rigs.clear();
        self.verts.clear();
        self.verts.extend_from_slice(self.mesh.rest());
        self.anchor.clone_from(&self.verts);
        // The rest shape is re-based at the next constraint change; forget the
        // current constraint set so that happens on the first touch.
        let _ = self.arap.set_constraints(&[]);
        self.finalize();
    }

    /// Replaces the mesh: a formation switch (mesh-formation-control section 7.3).
    ///
    /// The new mesh at its rest pose becomes the user mesh and the rest shape ARAP
    /// keeps rigid to; the goals come from `samples`. Live
    /// rigs keep their fingers: each handle moves to the new mesh's vertex nearest
    /// to it, and its finger offset takes up the difference, so a drag goes on
    /// without a jump; line and area supports are rebuilt on the new vertices.
    ///
    /// `samples` are the goal samples drawn on `mesh`, one per agent
    /// ([`crate::crowd::mesh::sample_goals`]: the slow part, which the daemon does off the
    /// control thread). Allocates (a new ARAP system): meant for a switch, not for
    /// every tick.
    pub fn set_mesh_sampled(&mut self, mesh: TriMesh, samples: Vec<GoalSample>) {
        self.arap = Arap::new(&mesh);
        self.verts.clear();
        self.verts.extend_from_slice(mesh.rest());
        self.anchor.clone_from(&self.verts);
        self.solved.clone_from(&self.verts);
        let n = self.verts.len();
        self.best_weight.clear();
        self.best_weight.resize(n, 0.0);
        self.best_target.clear();
        self.best_target.resize(n, Vec2::zeros());
        self.samples = samples;
        self.spacing_m = mean_edge_length(&mesh);
        self.mesh = mesh;
        let mut rigs = std::mem::take(&mut self.rigs);
        for rig in &mut rigs {
            for h in &mut rig.handles {
                let (v, _) = nearest_vertex(&self.verts, h.pos);
                let d = self.verts[v] - h.pos;
                h.vertex = v as u32;
                h.offset += d;
                h.pos += d;
                h.goal += d;
                h.path.shift(d);
            }
            self.build_support(rig);
        }
        self.rigs = rigs;
        self.finalize();
    }

    /// The goal samples on the mesh, one per agent.
    pub fn samples(&self) -> &[GoalSample] {
        &self.samples
    }

    /// New goal samples for a different agent count.
    pub fn set_agent_count(&mut self, agents: usize) {
        self.samples = crate::crowd::mesh::sample_goals(&self.mesh, agents);
        goal_positions(
            &self.mesh,
            &self.samples,
            &self.final_verts,
            &mut self.goals,
        );
    }

    /// One tick: follow the segmenter's controls, deform, update goals.
    ///
    /// `lag_m` is the agents' mean distance to their goals (section 4.1 opposing
    /// force); `dt_s` the time since the last update.
    ///
    /// # Errors
    /// [`DirectError::Arap`] when the solve fails; the mesh keeps its last pose.
    pub fn update(
        &mut self,
        controls: &[Control],
        dt_s: f64,
        lag_m: f64,
    ) -> Result<(), DirectError> {
        let r = self.deform(controls, dt_s, lag_m);
        if self.stale {
            self.finalize();
        }
        r
    }

    /// The deformation of [`update`](Self::update): rigs, handles, ARAP, final mesh.
    fn deform(&mut self, controls: &[Control], dt_s: f64, lag_m: f64) -> Result<(), DirectError> {
        self.sync_rigs(controls);
        if self.rigs.is_empty() {
            return Ok(());
        }
        self.move_handles(controls, dt_s, lag_m);
        self.build_constraints();
        let same_set = self.constraints.as_slice() == self.arap.constraints();
        if !same_set {
            // The pose at this moment becomes the shape to stay rigid to: what one
            // control shaped stays shaped when it ends while others go on.
            self.anchor.clone_from(&self.verts);
            self.arap.set_rest(&self.verts)?;
            self.arap.set_constraints(&self.constraints)?;
        }
        self.arap
            .solve(&self.targets, &self.anchor, &mut self.solved)?;
        std::mem::swap(&mut self.verts, &mut self.solved);
        self.finalize();
        Ok(())
    }

    fn sync_rigs(&mut self, controls: &[Control]) {
        self.rigs.retain(|r| controls.iter().any(|c| c.id == r.id));
        for c in controls {
            let pos = self.rigs.iter().position(|r| r.id == c.id);
            match pos {
                Some(i) if self.rigs[i].handles.len() == c.fingers.len() => {}
                Some(i) => {
                    let mut rig = self.rigs.swap_remove(i);
                    for f in &c.fingers[rig.handles.len()..] {
                        rig.handles.push(self.new_handle(f.id, f.world_down));
                    }
                    self.build_support(&mut rig);
                    self.rigs.push(rig);
                }
                None => {
                    let mut rig = Rig {
                        id: c.id,
                        kind: c.kind(),
                        handles: c
                            .fingers
                            .iter()
                            .map(|f| self.new_handle(f.id, f.world_down))
                            .collect(),
                        frame: Vec::new(),
                        supp: Vec::new(),
                    };
                    self.build_support(&mut rig);
                    self.rigs.push(rig);
                }
            }
        }
    }

    fn new_handle(&self, finger: ContactId, at: Vec2) -> Handle {
        let (v, _) = nearest_vertex(&self.verts, at);
        let p = self.verts[v];
        Handle {
            finger,
            vertex: v as u32,
            offset: p - at,
            pos: p,
            goal: p,
            path: Path::new(),
        }
    }

    /// Supplementary points of section 4.2 for a rig whose handles are in place.
    fn build_support(&self, rig: &mut Rig) {
        rig.kind = crate::gesture::segment::control_kind(rig.handles.len());
        rig.supp.clear();
        rig.frame.clear();
        let handle_vertex = |v: u32| rig.handles.iter().any(|h| h.vertex == v);
        match rig.kind {
            ControlKind::Point => {}
            ControlKind::Line => {
                let (a, b) = (rig.handles[0].pos, rig.handles[1].pos);
                let ab = b - a;
                let l2 = ab.norm_squared();
                rig.frame.extend([0, 1]);
                if l2 < 1e-12 {
                    return;
                }
                // Vertices within half a mesh spacing of the segment, strictly between its ends.
                let tol = 0.5 * self.spacing_m;
                for (v, p) in self.verts.iter().enumerate() {
                    if handle_vertex(v as u32) {
                        continue;
                    }
                    let t = (p - a).dot(&ab) / l2;
                    if !(0.0..=1.0).contains(&t) {
                        continue;
                    }
                    let across = perp(ab).dot(&(p - a)) / l2;
                    if (across * l2.sqrt()).abs() <= tol {
                        rig.supp.push(Supplementary {
                            vertex: v as u32,
                            support: Support::Line { t, d: across },
                        });
                    }
                }
            }
            ControlKind::Area => {
                let pts: Vec<Vec2> = rig.handles.iter().map(|h| h.pos).collect();
                let hull = convex_hull(&pts);
                if hull.len() < 3 {
                    // Collinear fingers: behave as a line between the extreme two.
                    let (i, j) = farthest_pair(&pts);
                    let (a, b) = (pts[i], pts[j]);
                    let ab = b - a;
                    let l2 = ab.norm_squared().max(1e-12);
                    rig.frame.extend([i, j]);
                    let tol = 0.5 * self.spacing_m;
                    for (v, p) in self.verts.iter().enumerate() {
                        let t = (p - a).dot(&ab) / l2;
                        let across = perp(ab).dot(&(p - a)) / l2;
                        if !handle_vertex(v as u32)
                            && (0.0..=1.0).contains(&t)
                            && (across * l2.sqrt()).abs() <= tol
                        {
                            rig.supp.push(Supplementary {
                                vertex: v as u32,
                                support: Support::Line { t, d: across },
                            });
                        }
                    }
                    return;
                }
                let poly: Vec<Vec2> = hull.iter().map(|&i| pts[i]).collect();
                rig.frame.extend_from_slice(&hull);
                for (v, p) in self.verts.iter().enumerate() {
                    if handle_vertex(v as u32) {
                        continue;
                    }
                    if point_in_convex_polygon(&poly, *p) || distance_to_polygon(&poly, *p) <= 1e-9
                    {
                        let mut w = vec![0.0; poly.len()];
                        if mean_value_coordinates(&poly, *p, &mut w).is_ok() {
                            rig.supp.push(Supplementary {
                                vertex: v as u32,
                                support: Support::Area { weights: w },
                            });
                        }
                    }
                }
            }
        }
    }

    fn move_handles(&mut self, controls: &[Control], dt_s: f64, lag_m: f64) {
        let p = self.params;
        for rig in &mut self.rigs {
            let Some(c) = controls.iter().find(|c| c.id == rig.id) else {
                continue;
            };
            // The fingers' similarity since they landed turns each handle's offset
            // with the hand, so a twisted or pinched hand twists or pinches its
            // vertices exactly (a single finger only translates).
            let z = hand_similarity(c);
            for h in &mut rig.handles {
                let Some(f) = c.fingers.iter().find(|f| f.id == h.finger) else {
                    continue;
                };
                let offset = Vec2::new(
                    z.x * h.offset.x - z.y * h.offset.y,
                    z.y * h.offset.x + z.x * h.offset.y,
                );
                h.record(f.world + offset, p.checkpoint_spacing_m);
                // Constraint velocity: catch up this tick, within the speed limit.
                let remaining = h.remaining();
                let v_c = if dt_s > 0.0 {
                    (remaining / dt_s).min(p.max_constraint_speed_m_s)
                } else {
                    0.0
                };
                // Section 4.1: opposing force ∝ mean agent lag, never more than v_c.
                let f_opp = (p.opposing_gain_per_s * lag_m).min(v_c);
                h.advance((v_c - f_opp) * dt_s);
            }
        }
    }

    /// One constraint per vertex, in vertex order: a handle beats a supplementary
    /// point; among equals the later rig wins. No allocation.
    fn build_constraints(&mut self) {
        self.best_weight.iter_mut().for_each(|w| *w = 0.0);
        let (hw, sw) = (self.params.handle_weight, self.params.soft_weight);
        let (best_w, best_t) = (&mut self.best_weight, &mut self.best_target);
        let mut put = |v: u32, weight: f64, target: Vec2| {
            let vi = v as usize;
            if best_w[vi] <= weight {
                best_w[vi] = weight;
                best_t[vi] = target;
            }
        };
        for rig in &self.rigs {
            for s in &rig.supp {
                let target = match &s.support {
                    Support::Line { t, d } => {
                        let a = rig.handles[rig.frame[0]].pos;
                        let b = rig.handles[rig.frame[1]].pos;
                        let ab = b - a;
                        a + ab * *t + perp(ab) * *d
                    }
                    Support::Area { weights } => rig
                        .frame
                        .iter()
                        .zip(weights)
                        .fold(Vec2::zeros(), |acc, (&hi, &w)| {
                            acc + rig.handles[hi].pos * w
                        }),
                };
                put(s.vertex, sw, target);
            }
        }
        for rig in &self.rigs {
            for h in &rig.handles {
                put(h.vertex, hw, h.pos);
            }
        }
        self.constraints.clear();
        self.targets.clear();
        for (v, (&w, &t)) in self.best_weight.iter().zip(&self.best_target).enumerate() {
            if w > 0.0 {
                self.constraints.push(Constraint {
                    vertex: v as u32,
                    weight: w,
                });
                self.targets.push(t);
            }
        }
    }

    /// Handle positions of a control (m), for tests and the watch view.
    pub fn handle_positions(&self, control: u32) -> Vec<Vec2> {
        self.rigs
            .iter()
            .find(|r| r.id == control)
            .map(|r| r.handles.iter().map(|h| h.pos).collect())
            .unwrap_or_default()
    }

    /// Vertices a control drives: its handles then its supplementary points.
    pub fn control_vertices(&self, control: u32) -> Vec<u32> {
        self.rigs
            .iter()
            .find(|r| r.id == control)
            .map(|r| {
                r.handles
                    .iter()
                    .map(|h| h.vertex)
                    .chain(r.supp.iter().map(|s| s.vertex))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Handle vertices of a control, in finger order.
    pub fn handle_vertices(&self, control: u32) -> Vec<u32> {
        self.rigs
            .iter()
            .find(|r| r.id == control)
            .map(|r| r.handles.iter().map(|h| h.vertex).collect())
            .unwrap_or_default()
    }
}

/// The least-squares similarity (rotation × scale, as a complex number `x + iy`)
/// carrying the fingers' landing positions to their current ones; `(1, 0)` for one
/// finger or when the fingers landed on one point.
fn hand_similarity(c: &Control) -> Vec2 {
    let n = c.fingers.len();
    if n < 2 {
        return Vec2::new(1.0, 0.0);
    }
    let a0 = c.fingers.iter().map(|f| f.world_down).sum::<Vec2>() / n as f64;
    let b0 = c.fingers.iter().map(|f| f.world).sum::<Vec2>() / n as f64;
    let (mut re, mut im, mut norm) = (0.0, 0.0, 0.0);
    for f in &c.fingers {
        let (a, b) = (f.world_down - a0, f.world - b0);
        // conj(a) * b
        re += a.x * b.x + a.y * b.y;
        im += a.x * b.y - a.y * b.x;
        norm += a.norm_squared();
    }
    if norm < 1e-12 {
        return Vec2::new(1.0, 0.0);
    }
    Vec2::new(re / norm, im / norm)
}

/// `v` rotated by +90°.
fn perp(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

fn farthest_pair(p: &[Vec2]) -> (usize, usize) {
    let mut best = (0, 0, -1.0);
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let d = (p[i] - p[j]).norm_squared();
            if d > best.2 {
                best = (i, j, d);
            }
        }
    }
    (best.0, best.1)
}

fn distance_to_polygon(poly: &[Vec2], p: Vec2) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let ab = b - a;
        let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
        best = best.min((a + ab * t - p).norm());
    }
    best
}

fn mean_edge_length(mesh: &TriMesh) -> f64 {
    let r = mesh.rest();
    let (mut sum, mut n) = (0.0, 0usize);
    for t in mesh.triangles() {
        for k in 0..3 {
            sum += (r[t[k] as usize] - r[t[(k + 1) % 3] as usize]).norm();
            n += 1;
        }
    }
    if n == 0 {
        1.0
    } else {
        sum / n as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Rect;
    use crate::gesture::segment::{ControlState, Finger};
    use crate::vocab::Micros;

    fn params() -> DirectParams {
        DirectParams {
            handle_weight: 1000.0,
            soft_weight: 100.0,
            checkpoint_spacing_m: 0.05,
            max_constraint_speed_m_s: 3.0,
            opposing_gain_per_s: 2.0,
        }
    }

    fn ctl(id: u32, fingers: &[(u32, Vec2, Vec2)]) -> Control {
        Control {
            id,
            state: ControlState::Held,
            t_begin: Micros(0),
            fingers: fingers
                .iter()
                .map(|&(fid, down, now)| Finger {
                    id: ContactId(fid),
                    world: now,
                    world_down: down,
                    glass_mm: now * 100.0,
                    down: true,
                    cancelled: false,
                })
                .collect(),
        }
    }

    fn controller() -> DirectController {
        let mesh = TriMesh::grid(
            Rect {
                min: [0.0, 0.0],
                max: [4.0, 3.0],
            },
            9,
            7,
        );
        DirectController::new(mesh, 63, params())
    }

    fn run(dc: &mut DirectController, make: impl Fn(f64) -> Vec<Control>, secs: f64) {
        let dt = 1.0 / 120.0;
        let steps = (secs / dt) as usize;
        for k in 0..=steps {
            let s = (k as f64 * dt / secs).min(1.0);
            dc.update(&make(s), dt, 0.0).unwrap();
        }
        for _ in 0..240 {
            dc.update(&make(1.0), dt, 0.0).unwrap();
        }
    }

    #[test]
    fn one_finger_translates_the_mesh() {
        let mut dc = controller();
        let rest = dc.vertices().to_vec();
        let d = Vec2::new(1.5, 0.5);
        let start = Vec2::new(4.0, 1.5);
        run(&mut dc, |s| vec![ctl(1, &[(1, start, start + d * s)])], 1.0);
        for (p, r) in dc.vertices().iter().zip(&rest) {
            assert!((p - r - d).norm() < 0.02, "{p} vs {}", r + d);
        }
    }

    #[test]
    fn line_control_keeps_its_segment_straight_and_evenly_spaced() {
        let mut dc = controller();
        // Left edge, from (0, 0.5) to (0, 2.5); drag left by 1 m and pinch to 1.2 m.
        let (a0, b0) = (Vec2::new(0.0, 0.5), Vec2::new(0.0, 2.5));
        let (a1, b1) = (Vec2::new(-1.0, 0.9), Vec2::new(-1.0, 2.1));
        run(
            &mut dc,
            |s| {
                vec![ctl(
                    1,
                    &[(1, a0, a0 + (a1 - a0) * s), (2, b0, b0 + (b1 - b0) * s)],
                )]
            },
            1.0,
        );
        let vs = dc.control_vertices(1);
        assert!(
            vs.len() >= 4,
            "line should pick the vertices between its ends: {vs:?}"
        );
        let h = dc.handle_positions(1);
        assert!((h[0] - a1).norm() < 1e-6 && (h[1] - b1).norm() < 1e-6);
        for &v in &vs {
            let p = dc.vertices()[v as usize];
            // On the line x = -1 between the handles, within 2 cm.
            assert!((p.x + 1.0).abs() < 0.02, "vertex {v} at {p}");
            assert!(p.y > 0.9 - 0.02 && p.y < 2.1 + 0.02);
        }
    }

    #[test]
    fn area_control_moves_its_region_rigidly_under_a_twist() {
        let mut dc = controller();
        let c = Vec2::new(2.0, 1.5);
        let fingers: Vec<Vec2> = (0..4)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_2 + 0.3;
                c + Vec2::new(a.cos(), a.sin()) * 1.0
            })
            .collect();
        let rot = |p: Vec2, th: f64| {
            let d = p - c;
            c + Vec2::new(
                d.x * th.cos() - d.y * th.sin(),
                d.x * th.sin() + d.y * th.cos(),
            )
        };
        let before = dc.vertices().to_vec();
        let theta = 1.0;
        run(
            &mut dc,
            |s| {
                let fs: Vec<(u32, Vec2, Vec2)> = fingers
                    .iter()
                    .enumerate()
                    .map(|(i, &f)| (i as u32 + 1, f, rot(f, theta * s)))
                    .collect();
                vec![ctl(1, &fs)]
            },
            1.5,
        );
        let vs = dc.control_vertices(1);
        assert!(vs.len() >= 6, "{vs:?}");
        for &v in &vs {
            let want = rot(before[v as usize], theta);
            let got = dc.vertices()[v as usize];
            assert!((got - want).norm() < 0.03, "vertex {v}: {got} vs {want}");
        }
    }

    #[test]
    fn opposing_force_slows_handles_when_agents_lag() {
        let mut a = controller();
        let mut b = controller();
        let start = Vec2::new(4.0, 1.5);
        let end = start + Vec2::new(3.0, 0.0);
        let c = vec![ctl(1, &[(1, start, end)])];
        for _ in 0..30 {
            a.update(&c, 1.0 / 120.0, 0.0).unwrap();
            b.update(&c, 1.0 / 120.0, 1.0).unwrap();
        }
        let (pa, pb) = (a.handle_positions(1)[0], b.handle_positions(1)[0]);
        assert!(
            pb.x < pa.x - 0.1,
            "lagging crowd should slow the handle: {pa} vs {pb}"
        );
        assert!(pb.x >= start.x, "never backwards");
    }

    #[test]
    fn two_controls_act_together() {
        let mut dc = controller();
        let (l, r) = (Vec2::new(0.0, 1.5), Vec2::new(4.0, 1.5));
        run(
            &mut dc,
            |s| {
                vec![
                    ctl(1, &[(1, l, l - Vec2::new(s, 0.0))]),
                    ctl(2, &[(2, r, r + Vec2::new(s, 0.0))]),
                ]
            },
            1.0,
        );
        let xs: Vec<f64> = dc.vertices().iter().map(|p| p.x).collect();
        let (lo, hi) = xs
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(lo < -0.9 && hi > 4.9, "stretched to [{lo}, {hi}]");
    }
}
