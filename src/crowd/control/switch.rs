//! Formation switches (mesh-formation-control section 7.3): the slow part of a
//! switch — meshing the new shape where the crowd is, drawing a goal per agent and
//! pairing agents with goals by the least-effort cost of formation-transform eq. 3 —
//! as a request the daemon's formation thread prepares off the control thread.

use crate::crowd::assign::{CostMatrix, CostProvider, LeastEffort, Solver};
use crate::crowd::formation::{Formation, Placement};
use crate::crowd::mesh::{goal_positions, sample_goals, GoalSample, MeshError, TriMesh};
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
    /// [`Formation::mesh`], then [`sample_goals`] (`O(K n log(K n))` for `n`
    /// agents), then an `n × n` cost matrix and its exact assignment. Allocates.
    pub fn prepare(self) -> PreparedSwitch {
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
        let built = mesh.map(|mesh| {
            let samples = sample_goals(&mesh, agents.len());
            let mut goals = Vec::with_capacity(samples.len());
            goal_positions(&mesh, &samples, mesh.rest(), &mut goals);
            let mut costs = CostMatrix::new(0, 0);
            LeastEffort::new(lambda).fill(&agents, &goals, &mut costs);
            let goal_of = match Solver::new().solve(&costs) {
                Ok(cols) => cols.iter().map(|&j| j as u32).collect(),
                Err(e) => {
                    log::warn!("formation `{name}`: least-effort pairing failed: {e}");
                    Vec::new()
                }
            };
            BuiltSwitch {
                mesh,
                samples,
                goal_of,
            }
        });
        PreparedSwitch {
            name,
            checkpoint,
            epoch,
            anchor_m,
            built,
        }
    }
}
