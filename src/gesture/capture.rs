//! Gesture capture: every finger's trajectory of each gesture the segmenter tracks,
//! kept on the control thread in buffers allocated once (gesture-driven section 4:
//! a gesture is `G_raw`, the fingers' paths from the first touch to the last lift,
//! eq. 1).
//!
//! # What is kept
//! The engine feeds each touch to the [`Segmenter`] and then to
//! [`GestureCapture::observe`]; the capture finds the gesture (and which of its
//! contacts) the touch belongs to from the segmenter's live gestures, so the two
//! always agree: a finger bouncing within the grace period, or joining mid-gesture,
//! lands in the same gesture, as a new track (one track per finger, in landing
//! order, exactly [`Gesture::fingers`](super::segment::Gesture::fingers)); a contact
//! the segmenter re-attaches to a lifted finger (a finger lost for a few frames, a
//! new tracking id) continues that finger's track, and a ghost contact's track is
//! dropped (see the segmenter's module doc). On
//! [`Segment::GestureEnd`](super::segment::Segment::GestureEnd) the engine calls
//! [`GestureCapture::finish`], which copies the tracks into a caller-owned
//! [`GestureTracks`] (reusing its capacity) or says why there is nothing to
//! recognise ([`Rejected`]).
//!
//! # Fixed memory, decimated not truncated
//! [`CaptureParams`] fixes how many gestures are captured at once and how many
//! samples a track holds; every buffer is allocated in [`GestureCapture::new`] and
//! never grows. A track that fills is decimated: every other stored sample is
//! dropped and from then on only every 2nd incoming sample is stored (then every
//! 4th, 8th, ...), so the stored samples stay evenly spaced in sample count over the
//! whole gesture and the first sample is always kept. The latest sample is kept
//! apart and is always the track's last point. A 10-minute gesture costs the same
//! memory as a 2-second one.
//!
//! # Taps, long gestures, overflow
//! A gesture shorter than `min_duration` or whose fingers each stay within
//! `min_travel_mm` of where they landed is a tap: [`Rejected::Tap`]. A gesture that
//! lasts longer than `max_duration` is captured all along (decimated) and then
//! refused with [`Rejected::TooLong`]: a hand resting on the table for a minute is not
//! a command, and a crowd motion played at its end would surprise. More gestures at
//! once than the capture has slots for are not captured ([`Rejected::NotCaptured`],
//! counted in [`GestureCapture::overflowed`]).

use super::segment::{Segmenter, MAX_GESTURE_CONTACTS};
use super::track::{GestureTracks, TouchTrack, TrackSample};
use crate::geom::Vec2;
use crate::vocab::{ContactFlags, Micros};

/// Gestures captured at once by default.
pub const DEFAULT_MAX_GESTURES: usize = 4;

/// Samples one finger's track holds by default (the latest included).
pub const DEFAULT_SAMPLES_PER_TRACK: usize = 256;

/// Fewest samples a track may be given (first, one stored, latest).
pub const MIN_SAMPLES_PER_TRACK: usize = 4;

/// The capture's fixed sizes.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct CaptureParams {
    /// Gestures captured at once (more are counted and not captured).
    pub max_gestures: usize,
    /// Samples a track returns at most, the latest included (at least
    /// [`MIN_SAMPLES_PER_TRACK`]).
    pub samples_per_track: usize,
}

impl Default for CaptureParams {
    fn default() -> Self {
        CaptureParams {
            max_gestures: DEFAULT_MAX_GESTURES,
            samples_per_track: DEFAULT_SAMPLES_PER_TRACK,
        }
    }
}

/// When a finished gesture is something to recognise (config `gestures`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TapThresholds {
    /// Shorter gestures (first sample to last) are taps (µs).
    pub min_duration: Micros,
    /// A gesture whose every finger stays within this distance of where it landed is
    /// a tap (mm of glass).
    pub min_travel_mm: f64,
    /// Longer gestures are refused (µs).
    pub max_duration: Micros,
}

impl Default for TapThresholds {
    fn default() -> Self {
        TapThresholds {
            min_duration: Micros(150_000),
            min_travel_mm: 10.0,
            max_duration: Micros(60_000_000),
        }
    }
}

/// Why a finished gesture yields no tracks to recognise.
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum Rejected {
    /// Too short or too small.
    #[error("a tap: {duration_us} us, fingers moved at most {travel_mm:.1} mm")]
    Tap {
        /// First sample to last (µs).
        duration_us: u64,
        /// Farthest any finger got from where it landed (mm).
        travel_mm: f64,
    },
    /// Longer than `max_duration`.
    #[error("too long: {duration_us} us")]
    TooLong {
        /// First sample to last (µs).
        duration_us: u64,
    },
    /// The gesture was not captured: more gestures at once than slots, or no sample.
    #[error("not captured")]
    NotCaptured,
}

impl Rejected {
    /// The reason's name on the wire (`gesture` event, key `rejected`).
    pub fn as_str(&self) -> &'static str {
        match self {
            Rejected::Tap { .. } => "tap",
            Rejected::TooLong { .. } => "too_long",
            Rejected::NotCaptured => "not_captured",
        }
    }
}

/// What [`GestureCapture::finish`] tells about an accepted gesture.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Captured {
    /// Tracks copied (one per contact).
    pub tracks: usize,
    /// First sample to last (µs).
    pub duration: Micros,
    /// Farthest any finger got from where it landed (mm).
    pub travel_mm: f64,
    /// Largest decimation stride of a track (1: every sample kept).
    pub stride: u64,
}

/// One finger's buffer.
#[derive(Debug)]
struct Track {
    /// Stored samples, every `stride`-th incoming one (capacity fixed: `cap`).
    stored: Vec<TrackSample>,
    /// Most samples `stored` holds.
    cap: usize,
    /// The latest incoming sample.
    latest: TrackSample,
    /// Whether `latest` is also the last of `stored`.
    latest_stored: bool,
    /// Incoming samples so far.
    seen: u64,
    /// Keep every `stride`-th incoming sample (a power of two).
    stride: u64,
    /// Where it landed (mm).
    origin: Vec2,
    /// Farthest from `origin` so far, squared (mm²).
    reach2: f64,
    /// The contact is still down (its end not yet seen).
    open: bool,
    /// The segmenter called it a ghost contact: not a finger, not copied.
    ghost: bool,
}

impl Track {
    fn new(cap: usize) -> Track {
        Track {
            stored: Vec::with_capacity(cap),
            cap,
            latest: TrackSample {
                t: Micros::ZERO,
                mm: Vec2::new(0.0, 0.0),
            },
            latest_stored: false,
            seen: 0,
            stride: 1,
            origin: Vec2::new(0.0, 0.0),
            reach2: 0.0,
            open: false,
            ghost: false,
        }
    }

    fn reset(&mut self) {
        self.stored.clear();
        self.latest_stored = false;
        self.seen = 0;
        self.stride = 1;
        self.reach2 = 0.0;
        self.open = true;
        self.ghost = false;
    }

    /// Whether this track is one of the gesture's fingers (it has a sample and is
    /// not a ghost).
    fn is_finger(&self) -> bool {
        self.seen > 0 && !self.ghost
    }

    fn push(&mut self, s: TrackSample) {
        if self.seen == 0 {
            self.origin = s.mm;
        }
        let d2 = (s.mm - self.origin).norm_squared();
        if d2.is_finite() && d2 > self.reach2 {
            self.reach2 = d2;
        }
        if self.seen > 0 && s.t == self.latest.t {
            // A second position in one frame (a contact re-attached in the frame
            // its predecessor ended): the frame's latest position stands.
            self.latest = s;
            if self.latest_stored {
                if let Some(last) = self.stored.last_mut() {
                    *last = s;
                }
            }
            return;
        }
        let index = self.seen;
        self.seen += 1;
        self.latest = s;
        self.latest_stored = false;
        if index % self.stride != 0 {
            return;
        }
        if self.stored.len() == self.cap {
            // Keep stored positions 0, 2, 4, ...: incoming indices that are
            // multiples of twice the stride.
            let kept = self.stored.len().div_ceil(2);
            for i in 1..kept {
                self.stored[i] = self.stored[2 * i];
            }
            self.stored.truncate(kept);
            self.stride *= 2;
            if index % self.stride != 0 {
                return;
            }
        }
        self.stored.push(s);
        self.latest_stored = true;
    }

    /// Copies the samples (stored, then the latest) into `out`.
    fn copy_into(&self, out: &mut TouchTrack) {
        out.samples.clear();
        if self.seen == 0 {
            return;
        }
        out.samples.extend_from_slice(&self.stored);
        if !self.latest_stored {
            out.samples.push(self.latest);
        }
    }

    fn first_t(&self) -> Option<Micros> {
        self.stored.first().map(|s| s.t)
    }

    fn last_t(&self) -> Option<Micros> {
        (self.seen > 0).then_some(self.latest.t)
    }
}

/// One gesture's tracks.
#[derive(Debug)]
struct Slot {
    /// The gesture captured here, `None` when free.
    gesture: Option<u32>,
    /// One per contact of the gesture, in landing order (index = the contact's index
    /// in the segmenter's gesture); `used` of them in use.
    tracks: Vec<Track>,
    used: usize,
}

impl Slot {
    fn tracks(&self) -> &[Track] {
        &self.tracks[..self.used]
    }
}

/// The gestures' trajectories, captured on the control thread (see the module doc).
#[derive(Debug)]
pub struct GestureCapture {
    params: CaptureParams,
    thresholds: TapThresholds,
    slots: Vec<Slot>,
    /// Gestures not captured because every slot was taken.
    pub overflowed: u64,
}

impl GestureCapture {
    /// A capture with every buffer allocated: `max_gestures` × [`MAX_GESTURE_CONTACTS`]
    /// tracks of `samples_per_track` samples (sizes below the minimums are raised to
    /// them: one gesture, [`MIN_SAMPLES_PER_TRACK`]).
    pub fn new(params: CaptureParams, thresholds: TapThresholds) -> GestureCapture {
        let params = CaptureParams {
            max_gestures: params.max_gestures.max(1),
            samples_per_track: params.samples_per_track.max(MIN_SAMPLES_PER_TRACK),
        };
        // One sample of each track is the latest, kept apart.
        let cap = params.samples_per_track - 1;
        let slots = (0..params.max_gestures)
            .map(|_| Slot {
                gesture: None,
                tracks: (0..MAX_GESTURE_CONTACTS).map(|_| Track::new(cap)).collect(),
                used: 0,
            })
            .collect();
        GestureCapture {
            params,
            thresholds,
            slots,
            overflowed: 0,
        }
    }

    /// The sizes in force.
    pub fn params(&self) -> CaptureParams {
        self.params
    }

    /// Replaces the tap and length thresholds (config reload); captures go on.
    pub fn set_thresholds(&mut self, thresholds: TapThresholds) {
        self.thresholds = thresholds;
    }

    /// The thresholds in force.
    pub fn thresholds(&self) -> TapThresholds {
        self.thresholds
    }

    /// A [`GestureTracks`] with room for the largest capture, so that
    /// [`finish`](Self::finish) into it never allocates.
    pub fn tracks_buffer(&self) -> GestureTracks {
        GestureTracks {
            fingers: (0..MAX_GESTURE_CONTACTS)
                .map(|_| TouchTrack {
                    samples: Vec::with_capacity(self.params.samples_per_track),
                })
                .collect(),
        }
    }

    /// Records one touch of a frame at time `now`, after [`Segmenter::touch`] has
    /// seen it. Touches of controls and palms are ignored. Never allocates.
    pub fn observe(&mut self, now: Micros, seg: &Segmenter, t: &super::segment::TouchPoint) {
        if t.flags.contains(ContactFlags::PALM) {
            return;
        }
        let ended = t.flags.ended();
        let sample = TrackSample {
            t: now,
            mm: t.glass_mm,
        };
        for g in seg.gestures() {
            // The latest record of this contact in the gesture: the live one.
            let Some(k) = g.fingers.iter().rposition(|f| f.id == t.id) else {
                continue;
            };
            let f = &g.fingers[k];
            let slot = self.slots.iter().position(|s| s.gesture == Some(g.id));
            if !f.down {
                // Just lifted (this frame) and still open here; a lifted record of a
                // reused contact id is someone else's.
                let open = slot
                    .map(|i| &self.slots[i])
                    .is_some_and(|s| k < s.used && s.tracks[k].open);
                if !(ended && open) {
                    continue;
                }
            }
            let Some(i) = slot.or_else(|| self.claim(g.id, seg)) else {
                return;
            };
            let s = &mut self.slots[i];
            if k >= s.tracks.len() {
                return;
            }
            while s.used <= k {
                s.tracks[s.used].reset();
                s.used += 1;
            }
            let tr = &mut s.tracks[k];
            if f.down && !tr.open && tr.seen > 0 {
                // The segmenter re-attached a landing to this lifted finger: its
                // track goes on (a finger lost for a few frames, a new tracking id).
                tr.open = true;
                tr.ghost = false;
            }
            if tr.open {
                tr.push(sample);
                tr.open = !ended;
                if ended {
                    tr.ghost = g.spans.get(k).is_some_and(|sp| sp.ghost);
                }
            }
            return;
        }
    }

    /// A free slot for gesture `id` (a slot of a gesture the segmenter no longer has
    /// is free: it ended without [`finish`](Self::finish)).
    fn claim(&mut self, id: u32, seg: &Segmenter) -> Option<usize> {
        let free = self.slots.iter().position(|s| {
            s.gesture
                .is_none_or(|g| !seg.gestures().iter().any(|sg| sg.id == g))
        });
        match free {
            Some(i) => {
                let s = &mut self.slots[i];
                s.gesture = Some(id);
                s.used = 0;
                Some(i)
            }
            None => {
                self.overflowed += 1;
                None
            }
        }
    }

    /// Whether gesture `id` is being captured.
    pub fn is_capturing(&self, id: u32) -> bool {
        self.slots.iter().any(|s| s.gesture == Some(id))
    }

    /// Copies gesture `id`'s tracks so far into `out` (reusing its capacity) without
    /// ending the capture: the sliding-window recogniser's view of a long gesture.
    /// Returns false (and leaves `out` empty) when `id` is not captured.
    pub fn snapshot(&self, id: u32, out: &mut GestureTracks) -> bool {
        match self.slots.iter().find(|s| s.gesture == Some(id)) {
            Some(s) => {
                copy_tracks(s.tracks(), out);
                true
            }
            None => {
                out.fingers.clear();
                false
            }
        }
    }

    /// Ends gesture `id`'s capture: copies its tracks into `out` (reusing its
    /// capacity; see [`tracks_buffer`](Self::tracks_buffer)) and frees its slot.
    ///
    /// # Errors
    /// [`Rejected::Tap`] and [`Rejected::TooLong`] (`out` still holds the tracks, for
    /// tools that record them), [`Rejected::NotCaptured`] (`out` is empty).
    pub fn finish(&mut self, id: u32, out: &mut GestureTracks) -> Result<Captured, Rejected> {
        let Some(slot) = self.slots.iter_mut().find(|s| s.gesture == Some(id)) else {
            out.fingers.clear();
            return Err(Rejected::NotCaptured);
        };
        slot.gesture = None;
        let tracks = slot.tracks();
        let copied = copy_tracks(tracks, out);
        let fingers = || tracks.iter().filter(|t| t.is_finger());
        let first = fingers().filter_map(Track::first_t).min();
        let last = fingers().filter_map(Track::last_t).max();
        let (Some(first), Some(last)) = (first, last) else {
            return Err(Rejected::NotCaptured);
        };
        let duration = last.saturating_since(first);
        let travel_mm = fingers().map(|t| t.reach2).fold(0.0, f64::max).sqrt();
        let stride = fingers().map(|t| t.stride).max().unwrap_or(1);
        let th = self.thresholds;
        if duration > th.max_duration {
            return Err(Rejected::TooLong {
                duration_us: duration.0,
            });
        }
        if duration < th.min_duration || travel_mm < th.min_travel_mm {
            return Err(Rejected::Tap {
                duration_us: duration.0,
                travel_mm,
            });
        }
        Ok(Captured {
            tracks: copied,
            duration,
            travel_mm,
            stride,
        })
    }

    /// Drops gesture `id`'s capture, if any.
    pub fn discard(&mut self, id: u32) {
        for s in self.slots.iter_mut().filter(|s| s.gesture == Some(id)) {
            s.gesture = None;
        }
    }

    /// Drops every capture (reset).
    pub fn clear(&mut self) {
        for s in &mut self.slots {
            s.gesture = None;
        }
    }
}

/// Copies the fingers' tracks (a sample at least, no ghost) into `out`, reusing its
/// tracks' capacity. Returns how many.
fn copy_tracks(tracks: &[Track], out: &mut GestureTracks) -> usize {
    let n = tracks.iter().filter(|t| t.is_finger()).count();
    out.fingers.truncate(n);
    while out.fingers.len() < n {
        out.fingers.push(TouchTrack::default());
    }
    let with_samples = tracks.iter().filter(|t| t.is_finger());
    for (t, o) in with_samples.zip(out.fingers.iter_mut()) {
        t.copy_into(o);
    }
    n
}

#[cfg(test)]
#[path = "capture_tests.rs"]
mod tests;
