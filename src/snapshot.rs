//! What the control thread publishes, and what clients may ask of it.
//!
//! These are the types that cross from the control thread to the publisher thread
//! (and back, for commands). They are plain data: the publisher turns them into wire
//! bytes (`publish::protocol`), the control thread fills them. Positions are world
//! metres, velocities metres per second, times CLOCK_MONOTONIC microseconds.

use crate::geom::Vec2;
use crate::time::Micros;
use serde::{Deserialize, Serialize};
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
    pub motions: Vec<crate::crowd::scene::MotionType>,
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
    /// Boundary loop of the mesh, as vertex indices in order.
    pub outline: Arc<Vec<u32>>,
    /// Incremented whenever `triangles` changes.
    pub topology: u64,
}

/// The three control kinds of mesh-formation-control section 4.2.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControlKind {
    /// One finger: the nearest vertex follows it.
    Point,
    /// Two fingers: the vertices between them follow by linear interpolation.
    Line,
    /// Three or more: the region of their convex hull follows by mean value coordinates.
    Area,
}

impl ControlKind {
    /// The kind for a number of fingers (1 point, 2 line, 3+ area).
    pub fn for_fingers(n: usize) -> ControlKind {
        match n {
            0 | 1 => ControlKind::Point,
            2 => ControlKind::Line,
            _ => ControlKind::Area,
        }
    }

    /// Lower-case name, as on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            ControlKind::Point => "point",
            ControlKind::Line => "line",
            ControlKind::Area => "area",
        }
    }
}

/// Discrete things that happened, published as they happen.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A control began (fingers landed on the crowd).
    ControlBegin {
        /// Control id, unique while the daemon runs.
        id: u32,
        /// Point, line or area.
        kind: ControlKind,
        /// Contact ids of its fingers.
        fingers: Vec<u32>,
        /// Mesh vertices the fingers picked.
        vertices: Vec<u32>,
        /// When.
        t: Micros,
    },
    /// A finger joined a control within the grouping window; its kind may change.
    ControlUpdate {
        /// Control id.
        id: u32,
        /// Kind after the change.
        kind: ControlKind,
        /// Contact ids of its fingers.
        fingers: Vec<u32>,
        /// Mesh vertices the fingers picked.
        vertices: Vec<u32>,
        /// When.
        t: Micros,
    },
    /// A control ended (all its fingers lifted, or were cancelled).
    ControlEnd {
        /// Control id.
        id: u32,
        /// Its kind.
        kind: ControlKind,
        /// Whether it ended by cancellation rather than a lift.
        cancelled: bool,
        /// When.
        t: Micros,
    },
    /// A gesture began: fingers landed in open space.
    GestureBegin {
        /// Gesture id, unique while the daemon runs.
        id: u32,
        /// When the first finger landed.
        t: Micros,
    },
    /// A gesture ended: all fingers lifted and the grace period passed.
    GestureEnd {
        /// Gesture id.
        id: u32,
        /// Most fingers down at once.
        fingers: u32,
        /// Total contacts that took part.
        contacts: u32,
        /// From first touch to last lift (µs).
        duration_us: u64,
        /// Whether a finger was cancelled rather than lifted.
        cancelled: bool,
        /// When it ended.
        t: Micros,
    },
    /// The crowd was reset or resized by a command.
    Reset {
        /// Agent count after the reset.
        agents: u32,
        /// Whether agents were moved instantly (`true`) or walk back (`false`).
        hard: bool,
        /// When.
        t: Micros,
    },
    /// A touch device was attached, went away, or failed.
    Device {
        /// Index of the input in the config.
        input: u16,
        /// What happened.
        state: DeviceState,
        /// Device name.
        name: String,
        /// Node it was read through (`/dev/input/event5`).
        node: String,
        /// Stable identity (udev ID_PATH, else vendor:product:serial).
        stable_id: String,
        /// Why, for `failed` (and a hint for `unplugged`).
        message: Option<String>,
        /// When.
        t: Micros,
    },
    /// The crowd switched formation: it passed a scene checkpoint
    /// (mesh-formation-control section 7.3), a `set_formation` command asked for
    /// it, or a reset brought back the start.
    Formation {
        /// The formation now (`start` for the config's starting formation).
        name: String,
        /// The checkpoint passed (`None`: a command or a reset).
        checkpoint: Option<String>,
        /// Vertices of the new mesh (its triangles come with the next `mesh`).
        vertices: u32,
        /// When.
        t: Micros,
    },
    /// The simulation was paused or resumed.
    Paused {
        /// Paused after this event.
        paused: bool,
        /// When.
        t: Micros,
    },
}

/// Life of a touch device.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviceState {
    /// Opened and being read (first time, or back after an unplug).
    Attached,
    /// Gone (unplugged, driver unbound); its touches were cancelled; waiting for it.
    Unplugged,
    /// Could not be opened or read (permissions, busy, not a touch device); retried
    /// when the node changes.
    Failed,
}

impl DeviceState {
    /// Lower-case name, as on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            DeviceState::Attached => "attached",
            DeviceState::Unplugged => "unplugged",
            DeviceState::Failed => "failed",
        }
    }
}

/// Timing of one pipeline stage over the last stats interval.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageStats {
    /// Stage name (`input`, `queue`, `control`, `publish`, `end_to_end`, ...).
    pub stage: String,
    /// Samples in the interval.
    pub count: u64,
    /// Median (µs).
    pub p50_us: u64,
    /// 99th percentile (µs).
    pub p99_us: u64,
    /// Maximum (µs).
    pub max_us: u64,
    /// Budget from the config (µs).
    pub budget_us: u64,
    /// Samples over budget in the interval.
    pub overruns: u64,
}

/// Pipeline health, published periodically.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StatsReport {
    /// Time of the report (CLOCK_MONOTONIC µs).
    pub t: Micros,
    /// Length of the interval these figures cover (µs).
    pub interval_us: u64,
    /// Per-stage timings over the interval.
    pub stages: Vec<StageStats>,
    /// Touch frames received since start.
    pub frames: u64,
    /// Motion-only frames merged into others because the queue was full, since start.
    pub frames_coalesced: u64,
    /// Touch-down or touch-up transitions lost since start (must stay 0).
    pub transitions_lost: u64,
    /// Control ticks since start.
    pub ticks: u64,
    /// Assignments applied since start.
    pub assignments: u64,
    /// Assignments applied per second over the interval.
    pub assignment_hz: f64,
    /// Snapshots dropped for slow clients since start (all clients).
    pub snapshots_dropped: u64,
    /// Connected clients.
    pub clients: u32,
    /// Agents.
    pub agents: u32,
    /// Active controls.
    pub controls: u32,
    /// Resident memory of the process (bytes), when known.
    pub rss_bytes: Option<u64>,
    /// The most recent control or gesture, described for people (`"area control, 3
    /// fingers"`).
    pub last_gesture: Option<String>,
    /// The formation the crowd is in (`start`, or the last one switched to).
    #[serde(default)]
    pub formation: String,
    /// Formation switches at scene checkpoints since start.
    #[serde(default)]
    pub formation_switches: u64,
}

/// A command a client may send (protocol `command` message).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "snake_case", deny_unknown_fields)]
pub enum Command {
    /// Mesh back to its rest pose; agents walk back (`hard: false`) or jump there.
    Reset {
        /// Move agents instantly.
        #[serde(default)]
        hard: bool,
    },
    /// Change the number of agents (resets the crowd).
    SetAgentCount {
        /// New count (1 ..= the configured maximum).
        count: u32,
    },
    /// Switch to a formation of the config's library (mesh-formation-control
    /// section 7.3: "a basic button interface"), or `start`.
    SetFormation {
        /// Formation name.
        formation: String,
    },
    /// Freeze agents.
    Pause,
    /// Unfreeze agents.
    Resume,
}

/// Identifies a connected client.
pub type ClientId = u64;

/// A command travelling from the publisher to the control thread.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandRequest {
    /// Who sent it.
    pub client: ClientId,
    /// The client's id for the command, echoed in the reply.
    pub id: serde_json::Value,
    /// The command.
    pub command: Command,
}

/// What the control thread sends to the publisher thread.
#[derive(Clone, Debug)]
pub enum Outgoing {
    /// A new snapshot (every tick).
    Snapshot(Arc<Snapshot>),
    /// The mesh changed.
    Mesh(Arc<MeshView>),
    /// Something happened.
    Event(Arc<Event>),
    /// Periodic stats.
    Stats(Arc<StatsReport>),
    /// The answer to a command: `Ok` becomes `ack`, `Err` becomes `error`.
    Reply {
        /// The client that asked.
        client: ClientId,
        /// Its id for the command.
        id: serde_json::Value,
        /// Outcome.
        result: Result<(), String>,
    },
}
