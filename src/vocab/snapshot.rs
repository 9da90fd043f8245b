//! What the control thread publishes every tick: the crowd and the mesh.
//!
//! Plain data, immutable once published (shared as `Arc`). Positions are world
//! metres, velocities metres per second, times CLOCK_MONOTONIC microseconds.

use super::motion::MotionType;
use super::time::Micros;
use crate::geom::Vec2;
use std::sync::Arc;

/// One agent in a snapshot.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct AgentView {
    /// Position (m).
    pub pos: Vec2,
    /// Velocity (m/s).
    pub vel: Vec2,
    /// Index into [`Snapshot::goals`] of the goal the agent is assigned to.
    pub goal: u32,
}

/// One active touch in a snapshot, mapped into the world.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct TouchView {
    /// Contact id.
    pub id: u32,
    /// Position (m).
    pub pos: Vec2,
    /// The control it drives, or `None` when it is part of a gesture in open space.
    pub control: Option<u32>,
}

/// The crowd at one control tick. Immutable once published (shared as `Arc`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// Tick sequence number, starting at 1, incremented every tick.
    pub seq: u64,
    /// Tick time (CLOCK_MONOTONIC µs, or the virtual clock in replays).
    pub t: Micros,
    /// Input timestamp of the newest touch frame this tick consumed, if any.
    pub input_t: Option<Micros>,
    /// Agents.
    pub agents: Vec<AgentView>,
    /// Goal positions (m): points of the deformed mesh the agents are assigned to.
    pub goals: Vec<Vec2>,
    /// Sequence number of the tick whose agent and goal positions the assignment in
    /// use was solved on.
    pub assignment_seq: u64,
    /// Active touches.
    pub touches: Vec<TouchView>,
    /// Whether the simulation is paused (agents hold still).
    pub paused: bool,
    /// Each agent's motion type: the patch it stands on (mesh-formation-control
    /// section 6.2.3, Table 1); empty when the engine has no scene.
    pub motions: Vec<MotionType>,
}

/// The deformable mesh: vertex positions (every change) and topology.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshView {
    /// Tick sequence number when this mesh state was produced.
    pub seq: u64,
    /// Vertex positions of the final mesh (m).
    pub vertices: Vec<Vec2>,
    /// Triangles as vertex index triples; shared while the topology is unchanged.
    pub triangles: Arc<Vec<[u32; 3]>>,
    /// Boundary loop of the mesh, as vertex indices in order (of its largest piece
    /// when it has several).
    pub outline: Arc<Vec<u32>>,
    /// Every piece's boundary loop, when the mesh has more than one piece (a crowd
    /// split into far groups after a gesture); empty for a mesh of one piece.
    pub outlines: Arc<Vec<Vec<u32>>>,
    /// Incremented whenever `triangles` changes.
    pub topology: u64,
}
