//! Formation switches (mesh-formation-control section 7.3): at scene checkpoints
//! and on request; prepared here (replays) or on the daemon's formation thread, and
//! installed between two ticks.

use super::error::{CommandError, SwitchError};
use super::state::Engine;
use crate::crowd::control::{PreparedSwitch, SwitchRequest};
use crate::crowd::formation::{Placement, START};
use crate::crowd::mesh::{GoalSample, TriMesh};
use crate::geom::{Rect, Vec2};
use crate::vocab::{Event, Micros};
use std::fmt;
use std::sync::Arc;

impl Engine {
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
    /// [`CommandError::UnknownFormation`] naming the known formations when `name` is
    /// not one; without the formation thread, [`CommandError::FormationNotBuilt`]
    /// when the formation could not be built.
    pub fn set_formation(&mut self, name: &str, now: Micros) -> Result<(), CommandError> {
        self.set_formation_by(name, None, None, now)
    }

    /// Prepares formation switches on the daemon's formation thread instead of
    /// inside the tick (the daemon; replays keep them in the tick, deterministic).
    /// Transforms are prepared there too.
    pub fn set_switch_worker(&mut self, on: bool) {
        self.switch_worker = on;
        self.transforms.inline = !on;
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
    pub(super) fn pass_checkpoints(&mut self, now: Micros) {
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
        if scene.checkpoints()[k].formation == self.formation_target() {
            return;
        }
        // The scene outlives the request (an `Arc` clone, no allocation).
        let scene = Arc::clone(scene);
        let cp = &scene.checkpoints()[k];
        let method = self.transforms.settings.method;
        let _ = self.request_formation(&cp.formation, Some(&cp.name), method, None, c - prev, now);
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
    pub(super) fn request_switch(
        &mut self,
        name: &str,
        checkpoint: Option<&str>,
        heading: Vec2,
        now: Micros,
    ) -> Result<(), SwitchError> {
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
                let why = SwitchError::NotInLibrary;
                self.formation_failed(name, &why);
                return Err(why);
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
    /// live drags go on over it ([`DirectController::set_mesh_sampled`](crate::crowd::control::DirectController::set_mesh_sampled)), agents
    /// take the least-effort pairing at once and the running assignment (Euclidean
    /// or Eikonal) takes over from its next result; results solved for the old
    /// goals are discarded. A switch asked for before a reset or resize is dropped.
    /// Allocates (a one-off, like a resize). A formation that could not be meshed
    /// is logged and counted, and the crowd keeps its formation; the error says why.
    ///
    /// # Errors
    /// [`SwitchError::Mesh`] when the shape could not be meshed.
    pub fn apply_switch(&mut self, p: PreparedSwitch, now: Micros) -> Result<(), SwitchError> {
        if p.epoch != self.switch_epoch {
            return Ok(());
        }
        self.switch_pending = None;
        let result = match p.built {
            Err(e) => {
                let why = SwitchError::Mesh(e);
                self.formation_failed(&p.name, &why);
                Err(why)
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
    pub(super) fn switched(&mut self, name: String, checkpoint: Option<String>, now: Micros) {
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
    pub(super) fn install(&mut self, mesh: TriMesh, samples: Vec<GoalSample>, goal_of: &[u32]) {
        self.direct.set_mesh_sampled(mesh, samples);
        self.triangles = Arc::new(self.direct.mesh().triangles().to_vec());
        self.outline = Arc::new(self.direct.mesh().outline().to_vec());
        let loops = self.direct.mesh().outlines();
        self.outlines = Arc::new(if loops.len() > 1 {
            loops.to_vec()
        } else {
            Vec::new()
        });
        self.topology += 1;
        if goal_of.len() == self.goal_of.len() {
            self.goal_of.copy_from_slice(goal_of);
        }
        self.waypoints.fill(Vec2::repeat(f64::NAN));
        self.forget_assignments();
        self.assignment_seq = self.seq;
    }

    /// The start mesh back where it was configured (a reset), with its cached goal
    /// samples: no slow work.
    pub(super) fn restore_start(&mut self, now: Micros) {
        let samples = self.start_samples.clone();
        self.install((*self.start_mesh).clone(), samples, &[]);
        self.switched(START.to_string(), None, now);
    }

    /// Drops switches asked for or queued (a reset or resize).
    pub(super) fn forget_switches(&mut self) {
        self.switch_epoch += 1;
        self.switch_pending = None;
        self.switch_queued = None;
        self.switch_outbox = None;
    }

    pub(super) fn formation_failed(&mut self, name: &str, why: &dyn fmt::Display) {
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
    pub(super) fn user_centroid(&self) -> Vec2 {
        let user = self.direct.user_vertices();
        user.iter().sum::<Vec2>() / user.len().max(1) as f64
    }

    /// Area of the user mesh in its current pose (m²).
    pub(super) fn user_mesh_area(&self) -> f64 {
        let a = self.direct.mesh().area_at(self.direct.user_vertices());
        if a.is_finite() && a > 0.0 {
            a
        } else {
            self.start_mesh.area()
        }
    }
}

/// The translation that brings `poly`'s bounding box inside `world` (centred on
/// an axis where it does not fit).
pub(super) fn shift_inside(poly: &[Vec2], world: Rect) -> Vec2 {
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
