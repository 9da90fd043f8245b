//! The direct-manipulation controller: the mesh, its rigs and the goals.

use super::handle::{turn, Handle};
use super::rig::{hand_similarity, MeshPose, Rig, Scratch};
use crate::crowd::environment::Scene;
use crate::crowd::environment::{displace_vertices, FieldParams};
use crate::crowd::mesh::{goal_positions, nearest_vertex, GoalSample, TriMesh};
use crate::crowd::mesh::{Arap, ArapError, Constraint, PointConstraint};
use crate::geom::Vec2;
use crate::gesture::segment::Control;
use crate::vocab::ContactId;
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

/// Retired rigs kept for their buffers.
const SPARE_RIGS: usize = 8;

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
    /// Retired rigs, reused by the next controls.
    spare: Vec<Rig>,
    scratch: Scratch,
    constraints: Vec<Constraint>,
    points: Vec<PointConstraint>,
    /// Targets of `constraints`, then of `points`.
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
            spare: Vec::new(),
            scratch: Scratch::default(),
            constraints: Vec::with_capacity(n),
            points: Vec::new(),
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

    /// Whether a world point is on the crowd (within `radius_m` of the final mesh,
    /// the one the user sees; a finger that lands there holds the final mesh's
    /// nearest vertex).
    pub fn hits(&self, p: Vec2, radius_m: f64) -> bool {
        crate::crowd::mesh::distance_to_mesh(&self.mesh, &self.final_verts, p) <= radius_m
    }

    /// Back to the rest pose; rigs, and drags still following their check points
    /// after a lift, are dropped.
    pub fn reset(&mut self) {
        while let Some(rig) = self.rigs.pop() {
            self.retire(rig);
        }
        self.verts.clear();
        self.verts.extend_from_slice(self.mesh.rest());
        self.anchor.clone_from(&self.verts);
        // The rest shape is re-based at the next constraint change; forget the
        // current constraint set so that happens on the first touch.
        let _ = self.arap.set_constraints(&[]);
        self.finalize();
    }

    /// Ends control `id` at once: its rig does not go on through its remaining
    /// check points (a cancelled touch: a palm, a device gone). The shape it made
    /// stays.
    pub fn cancel(&mut self, id: u32) {
        if let Some(i) = self.rigs.iter().position(|r| r.id == id) {
            let rig = self.rigs.remove(i);
            self.retire(rig);
        }
    }

    /// Replaces the mesh: a formation switch (mesh-formation-control section 7.3).
    ///
    /// The new mesh at its rest pose becomes the user mesh and the rest shape ARAP
    /// keeps rigid to; the goals come from `samples`. Live
    /// rigs keep their fingers: each handle moves to the new mesh's vertex nearest
    /// to it, and its finger offset takes up the difference (turned back by the
    /// hand's rotation and scale, in which the offset is kept), so a drag — even
    /// under a twisted or pinched hand — goes on without a jump; line and area
    /// supports are rebuilt on the new vertices.
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
                h.rebase(v as u32, self.verts[v] - h.pos, rig.hand);
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
        self.set_samples(crate::crowd::mesh::sample_goals(&self.mesh, agents));
    }

    /// New goal samples drawn on this mesh, one per agent
    /// ([`crate::crowd::mesh::sample_goals`]: the slow part of a resize, which the
    /// daemon does off the control thread); the goals follow at once.
    pub fn set_samples(&mut self, samples: Vec<GoalSample>) {
        self.samples = samples;
        goal_positions(
            &self.mesh,
            &self.samples,
            &self.final_verts,
            &mut self.goals,
        );
    }

    /// One tick: follow the segmenter's controls, deform, update goals.
    ///
    /// A control whose fingers all lifted goes on: its handles keep following the
    /// check points still ahead of them (section 4.1: the trajectory is "where the
    /// control points must pass in the future frames"), at the constraint speed
    /// less the opposing force, until they reach the last one, a new control lands
    /// on the crowd, or [`reset`](Self::reset).
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
        let same_set = self.constraints.as_slice() == self.arap.constraints()
            && self.points.as_slice() == self.arap.points();
        if !same_set {
            // The pose at this moment becomes the shape to stay rigid to: what one
            // control shaped stays shaped when it ends while others go on.
            self.anchor.clone_from(&self.verts);
            self.arap.set_rest(&self.verts)?;
            self.arap
                .set_constraints_and_points(&self.constraints, &self.points)?;
        }
        let solved = self
            .arap
            .solve(&self.targets, &self.anchor, &mut self.solved);
        // A lifted drag that reached its last check point ends here, whether or
        // not the solve succeeded.
        let mut i = 0;
        while i < self.rigs.len() {
            if self.rigs[i].lifted && self.rigs[i].arrived() {
                let rig = self.rigs.remove(i);
                self.retire(rig);
            } else {
                i += 1;
            }
        }
        solved?;
        std::mem::swap(&mut self.verts, &mut self.solved);
        self.finalize();
        Ok(())
    }

    /// Keeps a retired rig's buffers for the next control.
    fn retire(&mut self, rig: Rig) {
        if self.spare.len() < SPARE_RIGS {
            self.spare.push(rig);
        }
    }

    /// Builds a rig's supplementary points on the current user mesh.
    fn build_support(&mut self, rig: &mut Rig) {
        let pose = MeshPose {
            triangles: self.mesh.triangles(),
            verts: &self.verts,
            spacing_m: self.spacing_m,
        };
        rig.build_support(&pose, &mut self.scratch);
    }

    fn sync_rigs(&mut self, controls: &[Control]) {
        // A control gone from the segmenter had its last finger lifted: its rig
        // goes on through its check points.
        for rig in &mut self.rigs {
            if !controls.iter().any(|c| c.id == rig.id) {
                rig.lifted = true;
            }
        }
        // A new control on the crowd takes over from drags still going on.
        if controls
            .iter()
            .any(|c| !self.rigs.iter().any(|r| r.id == c.id))
        {
            let mut i = 0;
            while i < self.rigs.len() {
                if self.rigs[i].lifted {
                    let rig = self.rigs.remove(i);
                    self.retire(rig);
                } else {
                    i += 1;
                }
            }
        }
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
                    let mut rig = self.spare.pop().unwrap_or_else(Rig::new);
                    rig.reuse(c.id);
                    for f in &c.fingers {
                        let h = self.new_handle(f.id, f.world_down);
                        rig.handles.push(h);
                    }
                    self.build_support(&mut rig);
                    self.rigs.push(rig);
                }
            }
        }
    }

    /// A handle for a finger landed at `at`: the vertex nearest to it on the final
    /// mesh (the one the user sees and [`hits`](Self::hits) tests), held on the
    /// user mesh at the same offset from the finger.
    fn new_handle(&self, finger: ContactId, at: Vec2) -> Handle {
        let (v, _) = nearest_vertex(&self.final_verts, at);
        Handle::new(finger, v as u32, self.verts[v], self.final_verts[v], at)
    }

    fn move_handles(&mut self, controls: &[Control], dt_s: f64, lag_m: f64) {
        let p = self.params;
        for rig in &mut self.rigs {
            if let Some(c) = controls.iter().find(|c| c.id == rig.id) {
                // The fingers' similarity since they landed turns each handle's
                // offset with the hand, so a twisted or pinched hand twists or
                // pinches its vertices exactly (a single finger only translates).
                rig.hand = hand_similarity(c);
                for h in &mut rig.handles {
                    if let Some(f) = c.fingers.iter().find(|f| f.id == h.finger) {
                        h.record(f.world + turn(rig.hand, h.offset), p.checkpoint_spacing_m);
                    }
                }
            }
            for h in &mut rig.handles {
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
    /// point; among equals the later rig wins. Then the area samples, each a point
    /// constraint. No allocation once the buffers have grown.
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
                put(s.vertex, sw, rig.target(&s.support));
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
        self.points.clear();
        for rig in &self.rigs {
            for s in &rig.samples {
                self.points.push(PointConstraint {
                    corners: s.corners,
                    bary: s.bary,
                    weight: sw,
                });
                self.targets.push(rig.target(&s.support));
            }
        }
    }

    /// The rig of a control, if it is live.
    fn rig(&self, control: u32) -> Option<&Rig> {
        self.rigs.iter().find(|r| r.id == control)
    }

    /// Handle positions of a control (m), for tests and the watch view.
    pub fn handle_positions(&self, control: u32) -> Vec<Vec2> {
        self.rig(control)
            .map(|r| r.handles.iter().map(|h| h.pos).collect())
            .unwrap_or_default()
    }

    /// Vertices a control drives: its handles then its supplementary points.
    pub fn control_vertices(&self, control: u32) -> Vec<u32> {
        self.rig(control)
            .map(|r| {
                r.handles
                    .iter()
                    .map(|h| h.vertex)
                    .chain(r.supp.iter().map(|s| s.vertex))
                    .collect()
            })
            .unwrap_or_default()
    }

    /// How many points a control samples inside its area (section 4.2), held
    /// through the triangles they lie in.
    pub fn control_samples(&self, control: u32) -> usize {
        self.rig(control).map_or(0, |r| r.samples.len())
    }

    /// Handle vertices of a control, in finger order.
    pub fn handle_vertices(&self, control: u32) -> Vec<u32> {
        self.rig(control)
            .map(|r| r.handles.iter().map(|h| h.vertex).collect())
            .unwrap_or_default()
    }

    /// Whether the user mesh is at its rest pose with no rig live: a
    /// [`reset`](Self::reset) would change nothing.
    pub fn is_at_rest(&self) -> bool {
        self.rigs.is_empty() && self.verts.as_slice() == self.mesh.rest()
    }

    /// Whether a control's rig is live: its fingers down, or lifted and its
    /// handles still following their check points.
    pub fn has_control(&self, control: u32) -> bool {
        self.rigs.iter().any(|r| r.id == control)
    }
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

    fn centroid(p: &[Vec2]) -> Vec2 {
        p.iter().sum::<Vec2>() / p.len() as f64
    }

    /// A one-finger flick from the middle of the mesh: 3 m east in 0.1 s, far
    /// faster than the 3 m/s the handle may follow, then the finger lifts.
    /// Returns the finger's last position.
    fn flick(dc: &mut DirectController, id: u32) -> Vec2 {
        let start = Vec2::new(2.0, 1.5);
        let end = start + Vec2::new(3.0, 0.0);
        let dt = 1.0 / 120.0;
        for k in 0..=12 {
            let p = start + (end - start) * (k as f64 / 12.0);
            dc.update(&[ctl(id, &[(1, start, p)])], dt, 0.0).unwrap();
        }
        end
    }

    #[test]
    fn a_lifted_drag_follows_its_remaining_check_points_to_the_end() {
        let mut dc = controller();
        let rest = centroid(dc.vertices());
        let end = flick(&mut dc, 1);
        let at_lift = dc.handle_positions(1)[0];
        assert!(
            at_lift.x < end.x - 2.0,
            "the handle lags the flick: {at_lift}"
        );
        // Fingers up: no control any more; the crowd goes on along the path,
        // slowed while the agents lag (0.5 m) but never stopped short.
        let dt = 1.0 / 120.0;
        let mut ticks = 0;
        while dc.has_control(1) {
            dc.update(&[], dt, 0.5).unwrap();
            ticks += 1;
            assert!(ticks < 2400, "the drag never arrived");
        }
        let moved = centroid(dc.vertices()) - rest;
        assert!(
            (moved - Vec2::new(3.0, 0.0)).norm() < 0.02,
            "the mesh moved by {moved}, the finger by 3 m"
        );
        // Arrived: it stays where the drag ended.
        let there = dc.vertices().to_vec();
        for _ in 0..60 {
            dc.update(&[], dt, 0.0).unwrap();
        }
        assert_eq!(dc.vertices(), there.as_slice());
    }

    #[test]
    fn a_new_touch_or_a_reset_ends_a_lifted_drag() {
        let dt = 1.0 / 120.0;
        // A new touch on the crowd, held still: the lifted drag stops there.
        let mut dc = controller();
        let rest = centroid(dc.vertices());
        flick(&mut dc, 1);
        for _ in 0..6 {
            dc.update(&[], dt, 0.0).unwrap();
        }
        assert!(dc.has_control(1), "still following its check points");
        let p = dc.vertices()[0];
        let hold = vec![ctl(2, &[(2, p, p)])];
        dc.update(&hold, dt, 0.0).unwrap();
        assert!(!dc.has_control(1), "the new control took over");
        let stopped = centroid(dc.vertices());
        for _ in 0..240 {
            dc.update(&hold, dt, 0.0).unwrap();
        }
        let after = centroid(dc.vertices());
        assert!((after - stopped).norm() < 0.02, "{stopped} then {after}");
        assert!(after.x - rest.x < 1.5, "the drag went on to {after}");

        // A reset: back to the rest pose, and nothing moves afterwards.
        let mut dc = controller();
        flick(&mut dc, 1);
        dc.update(&[], dt, 0.0).unwrap();
        dc.reset();
        assert!(!dc.has_control(1));
        for _ in 0..120 {
            dc.update(&[], dt, 0.0).unwrap();
        }
        assert_eq!(dc.vertices(), dc.mesh().rest());

        // A cancelled control: ends where it is.
        let mut dc = controller();
        flick(&mut dc, 1);
        dc.cancel(1);
        let here = centroid(dc.vertices());
        for _ in 0..120 {
            dc.update(&[], dt, 0.0).unwrap();
        }
        assert_eq!(centroid(dc.vertices()), here);
    }

    /// Where the mesh point that was at `p` on the rest pose is now: `p`'s
    /// barycentric coordinates in its rest triangle applied to the current pose.
    fn follow(dc: &DirectController, p: Vec2) -> Vec2 {
        let tris = dc.mesh().triangles();
        let all: Vec<u32> = (0..tris.len() as u32).collect();
        let (t, b) = super::super::area::locate(tris, &all, dc.mesh().rest(), p).unwrap();
        (0..3).fold(Vec2::zeros(), |acc, k| {
            acc + dc.vertices()[t[k] as usize] * b[k]
        })
    }

    #[test]
    fn an_area_control_holding_no_vertex_still_moves_its_region_rigidly() {
        // Three fingers 15 cm apart in one cell of a 0.5 m mesh: their hull holds
        // no vertex and every finger's nearest vertex is the same, (1, 1).
        let mut dc = controller();
        let fingers = [
            Vec2::new(1.05, 1.05),
            Vec2::new(1.2, 1.05),
            Vec2::new(1.1, 1.2),
        ];
        let c = centroid(&fingers);
        let (theta, shift) = (0.8f64, Vec2::new(1.0, 0.5));
        let moved = |p: Vec2, s: f64| {
            let (sin, cos) = (theta * s).sin_cos();
            let d = p - c;
            c + shift * s + Vec2::new(cos * d.x - sin * d.y, sin * d.x + cos * d.y)
        };
        let under_hand: Vec<Vec2> = [c, (fingers[0] + fingers[1]) * 0.5, fingers[2]].to_vec();
        let far = [Vec2::new(3.5, 2.5), Vec2::new(0.25, 2.75)];
        run(
            &mut dc,
            |s| {
                let fs: Vec<(u32, Vec2, Vec2)> = fingers
                    .iter()
                    .enumerate()
                    .map(|(i, &f)| (i as u32 + 1, f, moved(f, s)))
                    .collect();
                vec![ctl(1, &fs)]
            },
            1.0,
        );
        let hv = dc.handle_vertices(1);
        assert!(hv.iter().all(|&v| v == hv[0]), "{hv:?}");
        assert_eq!(dc.control_vertices(1).len(), 3, "no vertex inside the hull");
        assert!(dc.control_samples(1) >= 10, "{}", dc.control_samples(1));
        // The mesh under the hand turned and moved with it, and so (as rigidly as
        // possible) did the rest of the crowd.
        for &p in &under_hand {
            let (got, want) = (follow(&dc, p), moved(p, 1.0));
            assert!(
                (got - want).norm() < 0.02,
                "under the hand {p}: {got} vs {want}"
            );
        }
        for &p in &far {
            let (got, want) = (follow(&dc, p), moved(p, 1.0));
            assert!((got - want).norm() < 0.1, "far {p}: {got} vs {want}");
        }
    }

    #[test]
    fn a_formation_switch_under_a_twisted_pinched_hand_does_not_jump() {
        for n_fingers in [2usize, 4] {
            let mut dc = controller();
            let c = Vec2::new(2.0, 1.5);
            let fingers: Vec<Vec2> = (0..n_fingers)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / n_fingers as f64 + 0.3;
                    c + Vec2::new(a.cos(), a.sin()) * 1.0
                })
                .collect();
            // Turned by 1.2 rad and pinched to 0.6 of the span.
            let hand = |p: Vec2| {
                let d = (p - c) * 0.6;
                let (sin, cos) = 1.2f64.sin_cos();
                c + Vec2::new(cos * d.x - sin * d.y, sin * d.x + cos * d.y)
            };
            let held: Vec<(u32, Vec2, Vec2)> = fingers
                .iter()
                .enumerate()
                .map(|(i, &f)| (i as u32 + 1, f, hand(f)))
                .collect();
            let controls = vec![ctl(1, &held)];
            run(&mut dc, |_| controls.clone(), 0.5);
            // A coarser formation: every handle lands on another vertex.
            let mesh = TriMesh::grid(
                Rect {
                    min: [0.3, 0.2],
                    max: [3.7, 2.9],
                },
                6,
                5,
            );
            let samples = crate::crowd::mesh::sample_goals(&mesh, 30);
            dc.set_mesh_sampled(mesh, samples);
            let at_switch = dc.handle_positions(1);
            for _ in 0..120 {
                dc.update(&controls, 1.0 / 120.0, 0.0).unwrap();
            }
            for (a, b) in at_switch.iter().zip(dc.handle_positions(1)) {
                assert!(
                    (a - b).norm() < 1e-9,
                    "{n_fingers} fingers: handle jumped from {a} to {b}"
                );
            }
        }
    }

    #[test]
    fn a_finger_grabs_the_vertex_it_sees_on_the_final_mesh() {
        use crate::crowd::environment::FieldParams;
        // A block in the middle of the crowd pushes the final mesh off it.
        let text = "(version: 1, bounds_m: (min: (-2.0, -2.0), max: (8.0, 6.0)), \
            obstacles: [(parts: [Polygon(vertices_m: [(1.6, 1.1), (2.4, 1.1), (2.4, 1.9), (1.6, 1.9)])])])";
        let scene = Arc::new(Scene::from_str(text, std::path::Path::new("s"), 0.15).unwrap());
        let mut dc = controller();
        dc.set_environment(Some((scene, FieldParams::new(1.0, 0.3, 0.15).unwrap())));
        // A final-mesh vertex whose nearest user-mesh vertex is another one.
        let (user, seen) = (dc.user_vertices().to_vec(), dc.vertices().to_vec());
        let v = (0..seen.len())
            .find(|&v| nearest_vertex(&user, seen[v]).0 != v)
            .expect("the field moved some vertex past half a spacing");
        let p = seen[v];
        let hold = vec![ctl(1, &[(1, p, p)])];
        dc.update(&hold, 1.0 / 120.0, 0.0).unwrap();
        assert_eq!(dc.handle_vertices(1), vec![v as u32]);
        // Held still, the vertex stays under the finger.
        for _ in 0..60 {
            dc.update(&hold, 1.0 / 120.0, 0.0).unwrap();
        }
        assert!(
            (dc.vertices()[v] - p).norm() < 0.01,
            "{} vs {p}",
            dc.vertices()[v]
        );
    }
}
