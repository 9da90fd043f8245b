//! The edit mode as published (crowd-motion-editing): the track set being edited
//! (`tracks` messages, when it changes) and the state of the edit (`edit` messages:
//! the selection's hull, the collisions, what the fingers are doing), to clients
//! subscribed to `edit`.

use crate::geom::Vec2;
use std::sync::Arc;

/// One person's tracks as published.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrackView {
    /// The person's id.
    pub id: u64,
    /// Positions (m).
    pub points: Vec<Vec2>,
    /// Arrival time at each position (s).
    pub times_s: Vec<f64>,
}

/// The track set being edited (a `tracks` message).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TracksView {
    /// Bumped by every change of the tracks (load, edit, undo).
    pub version: u64,
    /// Where they were loaded from.
    pub source: Arc<str>,
    /// The people. `changed` says which of them the message carries.
    pub tracks: Vec<TrackView>,
    /// `true`: every person is in `tracks`; `false`: only those an edit changed.
    pub full: bool,
    /// The first and last time of the set (s).
    pub span_s: (f64, f64),
    /// `true`: these are the tracks of an edit shown as a preview (`edit.accept`
    /// keeps them, `edit.undo` drops them).
    pub preview: bool,
}

/// Two people closer than the threshold at some time (a collision, section 4.1.1).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct CollisionView {
    /// One person's id.
    pub a: u64,
    /// The other's.
    pub b: u64,
    /// When they are closest (s).
    pub t_s: f64,
    /// Midway between them then (m).
    pub place: Vec2,
    /// How close (m).
    pub distance_m: f64,
}

/// The people selected for the next grab (`edit.select`, or a lasso drawn on the
/// table).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SelectionView {
    /// The people selected (ids; empty: no selection).
    pub ids: Vec<u64>,
    /// The time window of the selection (s), if any.
    pub window_s: Option<(f64, f64)>,
    /// The lasso it was made with (m), if any.
    pub lasso: Option<Vec<Vec2>>,
}

/// What an edit shown as a preview did (after a release or a retime).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PreviewView {
    /// The people collision avoidance retimed (ids).
    pub retimed: Vec<u64>,
    /// The people obstacle avoidance moved (ids).
    pub pushed: Vec<u64>,
    /// Colliding pairs before collision avoidance (after the edit itself).
    pub pairs_before: usize,
    /// Colliding pairs after it.
    pub pairs_after: usize,
    /// The closest two people came before collision avoidance (m; `None`: no pair
    /// within the threshold).
    pub closest_before_m: Option<f64>,
    /// The closest after it (m).
    pub closest_after_m: Option<f64>,
}

/// What the edit is doing (an `edit` message).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EditView {
    /// Tick sequence number.
    pub seq: u64,
    /// The tracks' version this describes.
    pub version: u64,
    /// `idle`, `grabbed` (fingers hold a selection), `settling` (speeds,
    /// obstacles and collisions after a release or a retime are being worked
    /// out), `preview` (an edit is shown, waiting for `edit.accept` or
    /// `edit.undo`), `loading`, `off`.
    pub state: &'static str,
    /// The playback time (s).
    pub play_t_s: f64,
    /// The people selected by the fingers.
    pub selected: Vec<u64>,
    /// The selection's cage (concave hull) as deformed now (m), counter-clockwise.
    pub hull: Vec<Vec2>,
    /// Collisions at the threshold after the last edit.
    pub collisions: Vec<CollisionView>,
    /// The threshold (m).
    pub threshold_m: f64,
    /// Edits that `edit.undo` can take back.
    pub undo_depth: u32,
    /// Where the pins of the grab are held (m): points a second control put down
    /// on the grabbed group or its hull (eq. 6's fixed points, kept where they were
    /// before the grab).
    pub pins: Vec<Vec2>,
    /// Where the fingers of the grab hold the tracks now (m), deformed.
    pub handles: Vec<Vec2>,
    /// The selection for the next grab.
    pub selection: SelectionView,
    /// The edit shown as a preview, if any.
    pub preview: Option<PreviewView>,
}
