//! Discrete things that happened, published as they happen.

use super::plan::{MotionPhase, Recognition};
use super::time::Micros;
use serde::{Deserialize, Serialize};

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
        /// What it was recognised as, when a motion was made of it.
        recognition: Option<Recognition>,
        /// Why no motion was made (`tap`, `too_long`, `not_captured`, `still`,
        /// `weak_vote`, `far`, `not_recognised`, `no_library`, `no_motion`,
        /// `no_agents`, `superseded`, `disabled`, `class_disabled`, `lasso`:
        /// docs/protocol.md).
        rejected: Option<String>,
        /// When it ended.
        t: Micros,
    },
    /// A recognised gesture's crowd motion moved on in its life.
    GestureMotion {
        /// The gesture's id.
        id: u32,
        /// The motion class playing.
        class: String,
        /// Where the motion is now.
        phase: MotionPhase,
        /// When.
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
    /// `library collect`: what the session asks for or did (a motion shown, a
    /// gesture recorded, skipped or undone, the session finished).
    Collect(Box<CollectView>),
}

/// What a `collect` event says (`library collect`, gesture-driven section 4).
#[derive(Clone, Debug, PartialEq)]
pub struct CollectView {
    /// What happened.
    pub state: CollectState,
    /// The item the session now asks for (0-based; equal to `of` when finished).
    pub item: u32,
    /// Items in the session.
    pub of: u32,
    /// The class of the item's motion (empty when finished).
    pub class: String,
    /// The motion's index in the library (as in `demo_motion`).
    pub motion: u32,
    /// Who is drawing.
    pub participant: String,
    /// Gestures recorded by this session so far (after this event).
    pub recorded: u32,
    /// Why a gesture was not recorded, or a save failed (`refused`, `failed`).
    pub detail: Option<String>,
    /// When.
    pub t: Micros,
}

/// The states of a `collect` event.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CollectState {
    /// The item's motion is shown (`demo_motion` went out): draw its gesture.
    Showing,
    /// A gesture was recorded and saved for the previous item.
    Recorded,
    /// The previous item was skipped.
    Skipped,
    /// The last recorded gesture was removed from the library; its item is asked
    /// for again.
    Undone,
    /// A gesture was not recorded (a tap, too short, too many fingers); the item
    /// is still asked for.
    Refused,
    /// Saving the library failed; nothing was lost from memory, the item is still
    /// asked for.
    Failed,
    /// Every item was recorded or skipped.
    Finished,
}

impl CollectState {
    /// Lower-case name, as on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            CollectState::Showing => "showing",
            CollectState::Recorded => "recorded",
            CollectState::Skipped => "skipped",
            CollectState::Undone => "undone",
            CollectState::Refused => "refused",
            CollectState::Failed => "failed",
            CollectState::Finished => "finished",
        }
    }
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
