//! The state of a `library collect` session in the engine (`collect.rs` drives
//! it, `collect_jobs.rs` does its slow work): the items to ask for, the library
//! being extended and where it is saved, what was recorded (for undo).

use crate::crowd::motion::Synthesis;
use crate::geom::Vec2;
use crate::gesture::library::Library;
use crate::gesture::track::GestureTracks;
use crate::vocab::Micros;
use std::path::PathBuf;

/// A collection session (gesture-driven section 4: people are shown crowd motions
/// and draw the gesture they would use for each), handed to the engine by
/// `library collect` before the daemon starts.
#[derive(Clone, Debug)]
pub struct CollectPlan {
    /// The library being extended: its motions are shown, the gestures drawn are
    /// added to it.
    pub library: Library,
    /// Where the library is saved after every recorded or undone gesture (written
    /// whole beside it and renamed into place).
    pub path: PathBuf,
    /// Who draws (stored with every gesture; `library eval --by participant`).
    pub participant: String,
    /// The motions to ask for, in order: indices into `library.motions`.
    pub motions: Vec<u32>,
    /// The name of each input, by its index in the config (a frame's `device`);
    /// stored with every gesture.
    pub devices: Vec<String>,
    /// Seeds the crowd synthesised for each motion shown.
    pub seed: u64,
    /// How long a finished demonstration waits before it plays again (µs).
    pub replay_after: Micros,
}

/// The library and where it goes: moved into a job and back, so exactly one
/// thread has it at a time and nothing is locked.
#[derive(Debug)]
pub struct Collector {
    pub(super) library: Library,
    pub(super) path: PathBuf,
}

/// Slow work of a collection session, for the formation thread ([`CollectJob::run`];
/// in the tick for replays).
#[derive(Debug)]
pub struct CollectJob {
    pub(super) collector: Box<Collector>,
    pub(super) kind: CollectJobKind,
}

#[derive(Debug)]
pub(super) enum CollectJobKind {
    /// Synthesise item `item`'s motion for the crowd where it stands.
    Show {
        item: usize,
        motion: usize,
        agents: Vec<Vec2>,
        speed_m_s: f64,
        seed: u64,
    },
    /// Record a gesture drawn for item `item` and save the library.
    Save {
        item: usize,
        motion: usize,
        tracks: Box<GestureTracks>,
        participant: String,
        device: String,
    },
    /// Remove gesture `gesture` (the last one recorded, for item `item`) and save.
    Undo { item: usize, gesture: usize },
}

/// A collection job done: the collector comes back with the outcome.
#[derive(Debug)]
pub struct CollectDone {
    pub(super) collector: Box<Collector>,
    pub(super) kind: CollectDoneKind,
}

#[derive(Debug)]
pub(super) enum CollectDoneKind {
    Shown {
        item: usize,
        synthesis: Result<Synthesis, String>,
    },
    /// The gesture's index in the library, or why it was not recorded.
    Saved {
        item: usize,
        result: Result<usize, String>,
    },
    Undone {
        item: usize,
        result: Result<(), String>,
    },
}

/// The engine's collection session (see `collect.rs`).
#[derive(Debug)]
pub(super) struct Collecting {
    /// Home when no job has it.
    pub(super) collector: Option<Box<Collector>>,
    /// Each item's motion (index into the library's motions) and class name.
    pub(super) items: Vec<(u32, String)>,
    pub(super) participant: String,
    pub(super) devices: Vec<String>,
    pub(super) seed: u64,
    pub(super) replay_after: Micros,
    /// The item asked for (`items.len()` when finished).
    pub(super) item: usize,
    /// Recorded gestures, oldest first: (item, index in the library).
    pub(super) recorded: Vec<(usize, usize)>,
    /// What waits for the collector to come home, oldest first.
    pub(super) queued: Vec<Wanted>,
    /// A job for the pipeline to take.
    pub(super) outbox: Option<CollectJob>,
    /// The item whose motion was synthesised, with its synthesis (played again
    /// while the item waits).
    pub(super) shown: Option<(usize, Synthesis)>,
    /// The last `demo_motion` published (sent again by `collect.status`).
    pub(super) demo_plan: Option<std::sync::Arc<crate::vocab::PlanView>>,
    /// When the last demonstration ended (its motion done), for the replay.
    pub(super) demo_ended: Option<Micros>,
    /// The input index of the last frame with a contact.
    pub(super) last_device: u16,
    /// A save is out on the formation thread.
    pub(super) saving: bool,
}

/// Work asked for while the collector was out.
#[derive(Debug)]
pub(super) enum Wanted {
    Show,
    Save {
        tracks: Box<GestureTracks>,
        device: String,
    },
    Undo,
}
