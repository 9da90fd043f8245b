//! Formation switches (mesh-formation-control section 7.3): the slow part of a
//! switch — meshing the new shape where the crowd is, drawing a goal per agent and
//! pairing agents with goals by the least-effort cost of formation-transform eq. 3 —
//! as a request the daemon's formation thread prepares off the control thread; and
//! the slow part of a new crowd size (drawing a goal per agent), likewise. Both can
//! be given up half-way ([`Cancel`]) when they are no longer wanted.

use crate::crowd::assign::{AssignError, Cancel};
use crate::crowd::formation::{Formation, Placement};
use crate::crowd::mesh::{
    goal_positions, sample_goals_cancellable, GoalSample, MeshError, TriMesh,
};
use crate::crowd::transform::{pair, PairCost};
use crate::geom::Vec2;
use std::sync::Arc;

/// The slow part of a formation switch, for one crowd state: what the engine hands
/// the daemon's formation thread (or prepares itself in a replay).
#[derive(Clone, Debug)]
pub struct SwitchRequest {
    /// Formation to switch to ([`START`](crate::crowd::formation::START) or a library name).
    pub name: String,
    /// The checkpoint passed (`None`: a command).
    pub checkpoint: Option<String>,
    /// The engine's switch epoch when asked; a reset or resize makes it stale.
    pub epoch: u64,
    /// The shape and where it goes; `None`: the start mesh's grid, its vertex
    /// centroid moved to `start_at_m`.
    pub target: Option<(Formation, Placement)>,
    /// Where the start mesh goes when `target` is `None` (m).
    pub start_at_m: Vec2,
    /// The user mesh's centroid when asked (m): the applied mesh follows the crowd
    /// by as much as this moved meanwhile.
    pub anchor_m: Vec2,
    /// The crowd's start mesh.
    pub start_mesh: Arc<TriMesh>,
    /// Vertices to ask the shape's mesh for.
    pub vertices: usize,
    /// Agent positions when asked (m).
    pub agents: Vec<Vec2>,
    /// `λ` of formation-transform eq. 3.
    pub lambda: f64,
}

/// A switch made ready: the new mesh, one goal sample per agent, the pairing.
#[derive(Clone, Debug)]
pub struct BuiltSwitch {
    /// The new mesh, placed as requested.
    pub mesh: TriMesh,
    /// One goal sample per agent on it.
    pub samples: Vec<GoalSample>,
    /// `goal_of[i]`: the goal agent `i` is paired with (empty when the pairing
    /// failed; the running assignment then pairs them).
    pub goal_of: Vec<u32>,
}

/// The answer to a [`SwitchRequest`].
#[derive(Clone, Debug)]
pub struct PreparedSwitch {
    /// As requested.
    pub name: String,
    /// As requested.
    pub checkpoint: Option<String>,
    /// As requested.
    pub epoch: u64,
    /// The user mesh's centroid when asked (m).
    pub anchor_m: Vec2,
    /// The result, or why the shape could not be meshed.
    pub built: Result<BuiltSwitch, MeshError>,
}

impl SwitchRequest {
    /// Meshes the shape, draws the goal samples and pairs the agents with the new
    /// goals by the least-effort cost of formation-transform eq. 3 (exact solve).
    ///
    /// # Complexity
    /// [`Formation::mesh`], then [`sample_goals`](crate::crowd::mesh::sample_goals)
    /// (`O(K n log(K n))` for `n` agents), then the exact assignment on `n × n`
    /// least-effort costs ([`crate::crowd::transform::pair`]: computed as the
    /// solver reads them, no matrix in memory). Allocates.
    pub fn prepare(self) -> PreparedSwitch {
        self.prepare_cancellable(Cancel::NEVER)
            .expect("a switch that is never cancelled is always prepared")
    }

    /// [`SwitchRequest::prepare`] that gives up (`None`) when `cancel` says so:
    /// checked in the goal sampling and in the pairing's solve, well under a
    /// millisecond of work apart.
    pub fn prepare_cancellable(self, cancel: Cancel<'_>) -> Option<PreparedSwitch> {
        let SwitchRequest {
            name,
            checkpoint,
            epoch,
            target,
            start_at_m,
            anchor_m,
            start_mesh,
            vertices,
            agents,
            lambda,
        } = self;
        let mesh = match &target {
            None => {
                let mut m = (*start_mesh).clone();
                let c = m.rest().iter().sum::<Vec2>() / m.vertex_count().max(1) as f64;
                m.translate(start_at_m - c);
                Ok(m)
            }
            Some((f, place)) => f.mesh(place, vertices),
        };
        let built = match mesh {
            Err(e) => Err(e),
            Ok(mesh) => {
                let samples = sample_goals_cancellable(&mesh, agents.len(), &cancel.as_fn())?;
                let mut goals = Vec::with_capacity(samples.len());
                goal_positions(&mesh, &samples, mesh.rest(), &mut goals);
                let goal_of = match pair(&agents, &goals, PairCost::LeastEffort { lambda }, cancel)
                {
                    Ok(cols) => cols,
                    Err(AssignError::Cancelled) => return None,
                    Err(e) => {
                        log::warn!("formation `{name}`: least-effort pairing failed: {e}");
                        Vec::new()
                    }
                };
                Ok(BuiltSwitch {
                    mesh,
                    samples,
                    goal_of,
                })
            }
        };
        Some(PreparedSwitch {
            name,
            checkpoint,
            epoch,
            anchor_m,
            built,
        })
    }
}

/// The slow part of a resize: goal samples for `count` agents on the current mesh
/// (and on the start mesh, for a reset, when the crowd is in another formation).
#[derive(Clone, Debug)]
pub struct ResizeRequest {
    /// The new crowd size.
    pub count: u32,
    /// The requester's resize ticket when asked (the engine's `resize_ticket`): a
    /// later resize makes this one stale.
    pub ticket: u64,
    /// The mesh topology the samples are drawn on.
    pub topology: u64,
    /// The crowd's mesh (its rest pose is what is sampled).
    pub mesh: TriMesh,
    /// The start mesh, when the crowd is in another formation (its samples are
    /// what a reset brings back).
    pub start_mesh: Option<Arc<TriMesh>>,
}

/// A [`ResizeRequest`] made ready.
#[derive(Clone, Debug)]
pub struct PreparedResize {
    /// As requested.
    pub count: u32,
    /// As requested.
    pub ticket: u64,
    /// As requested.
    pub topology: u64,
    /// One goal sample per agent on the crowd's mesh.
    pub samples: Vec<GoalSample>,
    /// One goal sample per agent on the start mesh (when asked for).
    pub start_samples: Option<Vec<GoalSample>>,
}

impl ResizeRequest {
    /// Draws the goal samples ([`crate::crowd::mesh::sample_goals`]); `None` when
    /// `cancel` said so (checked well under a millisecond of work apart).
    ///
    /// # Complexity
    /// `O(K n log(K n))` for `n` agents (seconds at 20,000). Allocates.
    pub fn prepare(self, cancel: Cancel<'_>) -> Option<PreparedResize> {
        let check = cancel.as_fn();
        let n = self.count as usize;
        let samples = sample_goals_cancellable(&self.mesh, n, &check)?;
        let start_samples = match &self.start_mesh {
            Some(m) => Some(sample_goals_cancellable(m, n, &check)?),
            None => None,
        };
        Some(PreparedResize {
            count: self.count,
            ticket: self.ticket,
            topology: self.topology,
            samples,
            start_samples,
        })
    }
}
