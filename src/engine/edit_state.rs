//! The engine's edit-mode state (`edit.rs` drives it): the track set being edited
//! and its undo stack, the playback clock, the fingers' grab, the jobs out on the
//! formation thread and what is published about them.

use crate::crowd::agents::NeighbourGrid;
use crate::crowd::edit::{Cage, CageParams, SampleRef, TrackSet};
use crate::crowd::environment::Scene;
use crate::geom::Vec2;
use crate::vocab::{CollisionView, Micros, PreviewView, TracksView};
use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;

/// Edits `edit.undo` can take back.
pub const MAX_UNDO: usize = 32;
/// People closer than this at the play time are one group: a touch on one grabs
/// the group's tracks (m).
pub const GROUP_LINK_M: f64 = 2.0;
/// Collision threshold of the edit mode: two people closer than this collide (m).
pub const EDIT_THRESHOLD_M: f64 = 0.3;
/// Seconds the playback rests at the end of the set before it loops.
pub const LOOP_REST_S: f64 = 1.0;
/// Controls landing while a release settles that are remembered, and grabbed
/// when its result arrives (more are dropped, and logged).
pub const MAX_QUEUED_CONTROLS: usize = 4;

/// What a finger holds, as the control thread knows it (the cage, and so its
/// vertices, exists only on the formation thread).
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) enum HoldSpec {
    /// A selected sample.
    Sample(SampleRef),
    /// A hull vertex of the grab's cage.
    Hull(usize),
    /// The hull vertex of the grab's cage nearest this place (m), as deformed
    /// when the job that resolves it runs; the job says which vertex it was.
    NearVertex(Vec2),
}

/// People grabbed (track indices, ascending) and the time window of their samples
/// in the cage (s; `None`: every sample).
pub(super) type Grabbed = (Arc<[usize]>, Option<(f64, f64)>);

/// The people selected for the next grab (`edit.select`, or a lasso on the table).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct EditSelection {
    /// Track indices, ascending.
    pub(super) tracks: Arc<[usize]>,
    /// Their ids, in the same order.
    pub(super) ids: Vec<u64>,
    /// Only samples in this window (s) are grabbed.
    pub(super) window_s: Option<(f64, f64)>,
    /// The lasso the people were selected with (m).
    pub(super) lasso: Option<Vec<Vec2>>,
}

/// What `edit.select` (or a lasso) asks for: worked out on the formation thread.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct SelectRequest {
    pub(super) ids: Option<Vec<u64>>,
    pub(super) lasso: Option<Vec<Vec2>>,
    pub(super) window_s: Option<(f64, f64)>,
}

/// A grab's cage, travelling between the control thread and the formation thread.
pub(super) struct CageBox(pub(super) Box<Cage>);

impl std::fmt::Debug for CageBox {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Cage({} hull vertices, {} samples)",
            self.0.hull().len(),
            self.0.selection().len()
        )
    }
}

/// What the edit mode keeps people apart by.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) struct AvoidSettings {
    /// Two people closer than this collide (m).
    pub(super) threshold_m: f64,
    /// Show a release's or a retime's result as a preview (`edit.preview`).
    pub(super) preview: bool,
}

/// A file job for the daemon's formation thread: reading or writing tracks is file
/// work the control thread never does.
#[derive(Debug)]
pub enum EditFileJob {
    /// Read a track file; the result goes to [`Engine::apply_edit_load`](super::Engine::apply_edit_load).
    Load {
        /// The edit directory (the config's `edit.dir`, resolved).
        dir: Arc<Path>,
        /// The entry's name, as the client gave it (checked by the reader).
        entry: String,
        /// The edit epoch asked at.
        epoch: u64,
    },
    /// Write the tracks (JSON Lines).
    Save {
        /// The tracks.
        set: Arc<TrackSet>,
        /// The edit directory.
        dir: Arc<Path>,
        /// The entry's name (checked by the writer).
        entry: String,
        /// Replace an existing entry (asked by the client and allowed by the config).
        overwrite: bool,
    },
}

/// Slow edit work for the formation thread (or the tick, in replays): a drag
/// solved on the selection's cage, or what follows a release.
#[derive(Debug)]
pub struct EditJob {
    pub(super) epoch: u64,
    pub(super) grab: u64,
    pub(super) kind: EditJobKind,
}

#[derive(Debug)]
pub(super) enum EditJobKind {
    /// Deform: build the cage first when `cage` is `None`.
    Drag {
        base: Arc<TrackSet>,
        selected: Arc<[usize]>,
        /// Only samples in this window (s) are in the cage.
        window_s: Option<(f64, f64)>,
        cage: Option<CageBox>,
        params: CageParams,
        handles: Arc<[HoldSpec]>,
        /// Each handle's displacement since its finger landed (m).
        deltas: Vec<Vec2>,
        /// Points held where they were before the grab (eq. 6).
        pins: Arc<[HoldSpec]>,
        /// The tracks' version the result will have.
        version: u64,
        source: Arc<str>,
    },
    /// The fingers lifted: the group kept out of the scene's obstacles (section
    /// 4.2, by the grab's cage, then sample by sample), speeds corrected (eq. 9)
    /// and collisions avoided by retiming (section 4.1.2) on the edited tracks.
    Release {
        base: Arc<TrackSet>,
        edited: Arc<TrackSet>,
        selected: Arc<[usize]>,
        /// The grab's cage with its handles, their displacements and the pins
        /// (`None` when a drag job failed to build it).
        cage: Option<CageBox>,
        handles: Arc<[HoldSpec]>,
        deltas: Vec<Vec2>,
        pins: Arc<[HoldSpec]>,
        obstacles: Option<Arc<Scene>>,
        avoid: AvoidSettings,
        version: u64,
        source: Arc<str>,
    },
    /// The collisions of tracks just loaded or brought back by an undo.
    Check {
        set: Arc<TrackSet>,
        threshold_m: f64,
        /// The tracks' version they are of.
        version: u64,
    },
    /// A temporal edit (section 3.3) of `people` (track indices; empty: everyone).
    Retime {
        base: Arc<TrackSet>,
        people: Arc<[usize]>,
        at_s: f64,
        to_s: f64,
        avoid: AvoidSettings,
        version: u64,
        source: Arc<str>,
    },
    /// The people an `edit.select` or a lasso picks.
    Select {
        set: Arc<TrackSet>,
        request: SelectRequest,
        version: u64,
    },
}

/// A finished [`EditJob`].
#[derive(Debug)]
pub struct EditDone {
    pub(super) epoch: u64,
    pub(super) grab: u64,
    pub(super) kind: EditDoneKind,
}

#[derive(Debug)]
pub(super) enum EditDoneKind {
    Dragged {
        cage: Option<CageBox>,
        /// The edited tracks and their `tracks` message (the grabbed people).
        edited: Result<(Arc<TrackSet>, Arc<TracksView>), String>,
        hull: Vec<Vec2>,
        deltas: Vec<Vec2>,
        /// The handles and pins the job had, resolved (no `NearVertex` left).
        handles: Vec<HoldSpec>,
        pins: Vec<HoldSpec>,
        /// Where the handles and pins are now (m).
        handles_at: Vec<Vec2>,
        pins_at: Vec<Vec2>,
    },
    Checked {
        collisions: Vec<CollisionView>,
        version: u64,
    },
    Settled {
        result: Result<Settled, String>,
        /// Whether it was a release (else a retime command).
        release: bool,
    },
    Selected {
        /// The people picked (track indices, ascending).
        result: Result<Vec<usize>, String>,
        request: SelectRequest,
        version: u64,
    },
}

/// What a release or retime leaves: the tracks, the collisions that remain, the
/// `tracks` message, and what the preview shows.
#[derive(Debug)]
pub(super) struct Settled {
    pub(super) set: Arc<TrackSet>,
    pub(super) collisions: Vec<CollisionView>,
    pub(super) view: Arc<TracksView>,
    pub(super) preview: PreviewView,
}

/// The fingers holding a selection.
#[derive(Debug)]
pub(super) struct Grab {
    /// Bumped per grab: results of an earlier grab are stale.
    pub(super) id: u64,
    /// The control holding it.
    pub(super) control: u32,
    /// The tracks as they were when grabbed (the cage's rest).
    pub(super) base: Arc<TrackSet>,
    /// The grabbed people (track indices).
    pub(super) selected: Arc<[usize]>,
    /// Only their samples in this window (s) are grabbed (a selection's window).
    pub(super) window_s: Option<(f64, f64)>,
    /// Per finger (contact id): where it was when it landed (the handle it holds
    /// is the same entry of `held`).
    pub(super) fingers: Vec<(u64, Vec2)>,
    /// The cage between drags (`None` while a job has it, or before it is built).
    pub(super) cage: Option<CageBox>,
    /// A drag job is out.
    pub(super) out: bool,
    /// The displacements the last job was sent with.
    pub(super) sent: Vec<Vec2>,
    /// The fingers' displacements now (kept after a lift).
    pub(super) latest: Vec<Vec2>,
    /// What the fingers hold, in the order of `fingers` (shared with jobs).
    pub(super) held: Arc<[HoldSpec]>,
    /// Points pinned by a second control (eq. 6), for the rest of the grab.
    pub(super) pins: Arc<[HoldSpec]>,
    /// How many pins the last job was sent with.
    pub(super) pins_sent: usize,
    /// Where the handles and the pins were after the last drag (m).
    pub(super) handles_at: Vec<Vec2>,
    pub(super) pins_at: Vec<Vec2>,
    /// A displacements buffer back from the last job, reused for the next.
    pub(super) spare: Vec<Vec2>,
    /// The newest edited tracks.
    pub(super) edited: Option<Arc<TrackSet>>,
    /// The fingers lifted; the release follows when the last drag is back.
    pub(super) released: bool,
}

/// The track set being edited.
#[derive(Debug)]
pub(super) struct EditMode {
    pub(super) set: Arc<TrackSet>,
    pub(super) source: Arc<str>,
    pub(super) version: u64,
    pub(super) undo: Vec<Arc<TrackSet>>,
    pub(super) play_t_s: f64,
    pub(super) grab: Option<Grab>,
    pub(super) collisions: Vec<CollisionView>,
    /// A release or retime is out.
    pub(super) settling: bool,
    /// Hull of the last grab, deformed (m).
    pub(super) hull: Vec<Vec2>,
    /// The people and window of `hull`'s cage: a touch on one of its vertices
    /// grabs them again by that vertex.
    pub(super) hull_of: Option<Grabbed>,
    /// The selection for the next grab.
    pub(super) selection: Option<EditSelection>,
    /// The edit shown as a preview (its tracks are `set`; the tracks before it
    /// are on top of `undo`).
    pub(super) preview: Option<PreviewView>,
    /// Controls that landed while a release settled, grabbed when it is back.
    pub(super) queued: Vec<u32>,
}

/// Edit mode: off (no tracks) or on.
#[derive(Debug)]
pub(super) struct Edits {
    pub(super) mode: Option<Box<EditMode>>,
    /// Bumped by a load installed and an exit: edit jobs of older tracks are stale.
    pub(super) epoch: u64,
    /// Bumped by `edit.load` and an exit: a file read for an older load is stale.
    pub(super) load_epoch: u64,
    pub(super) next_grab: u64,
    pub(super) loading: Option<String>,
    /// The edit directory clients' entries are in (`None`: none configured, and
    /// no state directory to default to).
    pub(super) dir: Option<Arc<Path>>,
    /// Whether `edit.save` may replace an existing entry (`edit.allow_overwrite`).
    pub(super) allow_overwrite: bool,
    /// The entry of the edit directory the tracks being edited came from (`None`
    /// for the config's track file).
    pub(super) loaded_entry: Option<String>,
    pub(super) file_out: Option<EditFileJob>,
    /// Jobs for the formation thread, in order (the pipeline sends one at a
    /// time; at most one drag, release or retime is out per grab, a selection
    /// replaces a waiting one).
    pub(super) outbox: VecDeque<EditJob>,
    pub(super) tracks_out: Option<Arc<TracksView>>,
    /// When the last `tracks` message went out.
    pub(super) tracks_sent_at: Option<Micros>,
    pub(super) view_dirty: bool,
    pub(super) cage: CageParams,
    pub(super) avoid: AvoidSettings,
    pub(super) edits: u64,
    /// The config's tracks as last loaded (a reload loads them again only when
    /// they changed).
    pub(super) from_config: Option<Arc<TrackSet>>,
    /// Buffers of a grab, kept from grab to grab.
    pub(super) buffers: GrabBuffers,
}

/// What finding a grabbed group needs, kept from grab to grab.
#[derive(Debug, Default)]
pub(super) struct GrabBuffers {
    /// The people on the scene at the play time: their track indices.
    pub(super) on_idx: Vec<usize>,
    /// Their positions (m).
    pub(super) on_pos: Vec<Vec2>,
    /// Union–find parents over all people.
    pub(super) parent: Vec<usize>,
    /// Neighbours within [`GROUP_LINK_M`].
    pub(super) grid: NeighbourGrid,
}

impl Edits {
    pub(super) fn new() -> Edits {
        Edits {
            mode: None,
            epoch: 0,
            load_epoch: 0,
            next_grab: 0,
            loading: None,
            dir: None,
            allow_overwrite: false,
            loaded_entry: None,
            file_out: None,
            outbox: VecDeque::new(),
            tracks_out: None,
            tracks_sent_at: None,
            view_dirty: false,
            cage: CageParams::default(),
            avoid: AvoidSettings {
                threshold_m: EDIT_THRESHOLD_M,
                preview: true,
            },
            edits: 0,
            from_config: None,
            buffers: GrabBuffers::default(),
        }
    }

    /// Whether the crowd is the edited tracks' people.
    pub(super) fn active(&self) -> bool {
        self.mode.is_some()
    }
}
