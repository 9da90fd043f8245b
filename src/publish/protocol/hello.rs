//! The hello negotiation: the protocol version, what a client may ask for (format,
//! streams, rate, snapshot fields) and what the server's `hello` tells it.

use super::frame::{FLAG_ASSIGNMENT, FLAG_GOALS, FLAG_POSITIONS, FLAG_TOUCHES, FLAG_VELOCITIES};
use crate::vocab::ClientId;

/// The protocol version this server speaks.
pub const PROTOCOL_VERSION: u32 = 1;

/// Longest client line accepted (bytes, without the newline); longer is a fatal error.
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// How a client wants its messages.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub enum Format {
    /// One JSON object per line.
    #[default]
    Json,
    /// Length-prefixed frames; snapshots in the binary layout.
    Binary,
}

impl Format {
    /// Name on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            Format::Json => "json",
            Format::Binary => "binary",
        }
    }
}

/// Which message streams a client receives. Replies (`hello`, `ack`, `error`,
/// `dropped`, `bye`) are always sent. `plan`, `transform`, `edit` and `scene` are off unless a client
/// names them, so a client written before they existed gets none of their message
/// types.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Subscriptions {
    /// `snapshot` messages.
    pub snapshot: bool,
    /// `mesh` messages.
    pub mesh: bool,
    /// Events: `control`, `gesture`, `reset`, `paused`.
    pub events: bool,
    /// `stats` messages.
    pub stats: bool,
    /// `plan`, `demo_motion` and `gesture_motion` messages: the crowd's planned
    /// trajectories and the life of the motion a gesture started.
    pub plan: bool,
    /// `transform` and `transform_end` messages: a formation transform's progress
    /// every tick and its summary.
    pub transform: bool,
    /// `tracks` and `edit` messages: the edit mode's tracks and its state.
    pub edit: bool,
    /// `scene` and `scene_poses` messages: the scene's obstacles, patches and
    /// checkpoints, and where its moving things are.
    pub scene: bool,
}

impl Subscriptions {
    /// Every stream.
    pub const ALL: Subscriptions = Subscriptions {
        snapshot: true,
        mesh: true,
        events: true,
        stats: true,
        plan: true,
        transform: true,
        edit: true,
        scene: true,
    };
    /// What a client that names no stream gets: every stream but `plan`,
    /// `transform`, `edit` and `scene`.
    pub const DEFAULT: Subscriptions = Subscriptions {
        plan: false,
        transform: false,
        edit: false,
        scene: false,
        ..Subscriptions::ALL
    };
    /// No stream.
    pub const NONE: Subscriptions = Subscriptions {
        snapshot: false,
        mesh: false,
        events: false,
        stats: false,
        plan: false,
        transform: false,
        edit: false,
        scene: false,
    };
    /// Wire names known to the parser, in wire order.
    pub const NAMES: [&'static str; 8] = [
        "snapshot",
        "mesh",
        "events",
        "stats",
        "plan",
        "transform",
        "edit",
        "scene",
    ];

    /// The names of the streams switched on, in wire order.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [
            self.snapshot,
            self.mesh,
            self.events,
            self.stats,
            self.plan,
            self.transform,
            self.edit,
            self.scene,
        ];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    pub(super) fn set(&mut self, name: &str) -> bool {
        match name {
            "snapshot" => self.snapshot = true,
            "mesh" => self.mesh = true,
            "events" => self.events = true,
            "stats" => self.stats = true,
            "plan" => self.plan = true,
            "transform" => self.transform = true,
            "edit" => self.edit = true,
            "scene" => self.scene = true,
            _ => return false,
        }
        true
    }
}

impl Default for Subscriptions {
    fn default() -> Self {
        Subscriptions::DEFAULT
    }
}

/// Which per-agent arrays a snapshot carries.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct FieldSet {
    /// `positions`.
    pub positions: bool,
    /// `velocities`.
    pub velocities: bool,
    /// `goals` (goal positions).
    pub goals: bool,
    /// `assignment` (goal index per agent) and `assignment_seq`.
    pub assignment: bool,
    /// `touches`.
    pub touches: bool,
    /// `motions` (each agent's motion type on its terrain; sent only when the daemon
    /// runs a scene). Binary clients get it only when they name it in `fields`
    /// ([`FieldSet::BINARY_DEFAULT`]).
    pub motions: bool,
}

impl FieldSet {
    /// Every field (the default).
    pub const ALL: FieldSet = FieldSet {
        positions: true,
        velocities: true,
        goals: true,
        assignment: true,
        touches: true,
        motions: true,
    };
    /// What a binary client gets when its `hello` has no `fields`: every array of
    /// the original binary layout, not `motions`, so a client written before the
    /// motions array existed keeps its exact layout. Naming `motions` adds it.
    pub const BINARY_DEFAULT: FieldSet = FieldSet {
        motions: false,
        ..FieldSet::ALL
    };
    /// The fields a `hello` without `fields` gets in `format`.
    pub fn default_for(format: Format) -> FieldSet {
        match format {
            Format::Json => FieldSet::ALL,
            Format::Binary => FieldSet::BINARY_DEFAULT,
        }
    }
    /// No per-agent array: only the scalar header fields.
    pub const NONE: FieldSet = FieldSet {
        positions: false,
        velocities: false,
        goals: false,
        assignment: false,
        touches: false,
        motions: false,
    };
    /// Wire names known to the parser, in wire order.
    pub const NAMES: [&'static str; 6] = [
        "positions",
        "velocities",
        "goals",
        "assignment",
        "touches",
        "motions",
    ];

    /// The names of the fields switched on, in wire order.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [
            self.positions,
            self.velocities,
            self.goals,
            self.assignment,
            self.touches,
            self.motions,
        ];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    /// The binary flag bits for this set's arrays that every snapshot carries when
    /// asked ([`FLAG_MOTIONS`](super::FLAG_MOTIONS) also needs a scene: see
    /// [`encode_snapshot_binary`](super::encode_snapshot_binary)).
    pub fn flags(&self) -> u16 {
        let mut f = 0;
        if self.positions {
            f |= FLAG_POSITIONS;
        }
        if self.velocities {
            f |= FLAG_VELOCITIES;
        }
        if self.goals {
            f |= FLAG_GOALS;
        }
        if self.assignment {
            f |= FLAG_ASSIGNMENT;
        }
        if self.touches {
            f |= FLAG_TOUCHES;
        }
        f
    }

    pub(super) fn set(&mut self, name: &str) -> bool {
        match name {
            "positions" => self.positions = true,
            "velocities" => self.velocities = true,
            "goals" => self.goals = true,
            "assignment" => self.assignment = true,
            "touches" => self.touches = true,
            "motions" => self.motions = true,
            _ => return false,
        }
        true
    }
}

impl Default for FieldSet {
    fn default() -> Self {
        FieldSet::ALL
    }
}

/// What one client asked for. A client `hello` replaces all of it; omitted keys take
/// the defaults ([`ClientSettings::default`]: JSON, every stream but `plan`, full
/// rate, every field).
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub struct ClientSettings {
    /// Wire format.
    pub format: Format,
    /// Streams received.
    pub subscriptions: Subscriptions,
    /// Most snapshots per second, `None` for every tick.
    pub max_rate_hz: Option<f64>,
    /// Arrays in each snapshot.
    pub fields: FieldSet,
}

impl ClientSettings {
    /// Smallest interval between two snapshots for this client (µs), if rate limited.
    pub fn min_interval_us(&self) -> Option<u64> {
        // `as` saturates: a tiny rate gives u64::MAX (effectively "once").
        self.max_rate_hz.map(|hz| (1.0e6 / hz).round() as u64)
    }
}

/// The server `hello`: static facts plus the settings in force for this client.
#[derive(Clone, Debug)]
pub struct ServerHello<'a> {
    /// Static facts.
    pub info: &'a HelloInfo,
    /// The client's id (appears in the daemon's log lines about it).
    pub client: ClientId,
    /// Current agent count.
    pub agents: u32,
    /// Settings now in force.
    pub settings: &'a ClientSettings,
    /// Snapshots queued for this client before the oldest are dropped.
    pub client_queue: u32,
    /// Whether the client is privileged: it receives the raw touches and may send
    /// commands. A read-only client gets neither.
    pub privileged: bool,
}

/// Static facts sent in the server hello.
#[derive(Clone, Debug)]
pub struct HelloInfo {
    /// The world rectangle (m).
    pub world: crate::geom::Rect,
    /// Agent count at start (the hello reports the current count once snapshots flow).
    pub agents: u32,
    /// Agent radius (m).
    pub agent_radius_m: f64,
}
