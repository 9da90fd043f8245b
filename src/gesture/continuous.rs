//! Continuous recognition of long gestures: a sliding-window recogniser that fires
//! when one class stays ahead for a configurable time (gesture-driven section 10,
//! the paper's future work: "the input gesture is continuously being recognized
//! using a ... sliding window"; config `gestures.continuous`).
//!
//! # What it is for
//! The paper recognises a gesture once, when it ends. A user who keeps a hand on
//! the table and draws a long motion (translating for several seconds, then
//! twisting) gets nothing until the lift. Here, while a gesture lasts, its last
//! `window` of samples is recognised every `period` (by the same KNN vote as a whole
//! gesture, section 8.2), and a class *fires* as soon as it has won every window
//! with a vote weight of at least `min_weight` for `hold`.
//!
//! # Three parts, so each is testable alone
//! - [`window`]: cuts a gesture's tracks to their last `window` (pure, no library).
//! - [`recognise_window`]: window → [`prepare_scaled`] → [`GestureFeatures::of`]
//!   and [`PhysicalFeatures::of`] → [`Searcher::search_with`] (the recogniser's
//!   combined distance) → [`vote`], with reused buffers ([`WindowBuffers`]); what
//!   the engine's worker calls.
//! - [`ContinuousRecogniser`]: the state machine, fed votes (`Option<(class,
//!   weight)>`), never a library; it decides when a window is due and when a class
//!   fires.
//!
//! # How the engine drives it
//! ```text
//!  Segment::GestureBegin(id)  ─► begin(id, t_begin)         (false: no free slot, counted)
//!  every control tick         ─► due(id, now)?  ─► snapshot the capture's tracks, hand
//!                                                   (tracks, now) to the worker
//!  worker                     ─► recognise_window(tracks, now, ...) -> WindowVote
//!  result back on the tick    ─► observe(id, now, vote.vote()) -> Option<Fire>
//!  Segment::GestureEnd{id}    ─► end(id) -> Option<Ended>;  Ended::fired > 0: the
//!                                gesture already commanded the crowd, skip its full
//!                                recognition
//! ```
//! `now` given to `observe` is the end of the window that was recognised (the `now`
//! of the `due` that asked for it), not the time the result came back, so a slow
//! worker delays a fire but does not change which windows count. A window the engine
//! never recognises (worker busy) is simply absent: the lead is judged over the votes
//! that arrive, in order; a vote older than the latest one is stale and ignored.
//!
//! # When it fires
//! A class fires when it has been the winner of every vote, each with weight at
//! least `min_weight`, from the first of those votes (`since`) until a vote at
//! `now ≥ since + hold`. A vote for another class, no vote (an empty or refused
//! window) or a weight below the floor ends the lead. A gesture may fire more than
//! once, but only for a *change* of class: after `translate` fired, `translate`
//! never fires again until another class has fired (a hand that keeps translating,
//! pauses and translates on does not restart the crowd's motion; translate → twist →
//! translate fires three times). With votes every `period`, the first window due at
//! `begin + window` and `hold` a multiple of `period`, a class that wins from the
//! start fires at exactly `begin + window + hold`.
//!
//! # State machine (one per live gesture, in a fixed slot)
//! ```text
//!          begin           due: lasted window       c ahead,
//!  Free ─────────► Filling ─────────────────► Watching ───────────► Leading(c, since)
//!   ▲                                          ▲   ▲  c ≠ last fired    │      │ ▲
//!   │ end                            none ahead│   │                    │      │ │ c' ahead,
//!   │ (any state)                              │   └──── none ahead ────┘      │ │ c' ≠ last
//!   │                                          │                c still ahead, │ │ fired
//!   │                                          │              now − since ≥ hold │ │
//!   │                                          │                     FIRE      ▼ │
//!   │                                          └─────────────────────────── Fired(c)
//! ```
//! Every transition on a vote, by the class ahead (the winner, if its weight is at
//! least `min_weight`):
//!
//! | state \ vote      | `c` ahead, `c` ≠ last fired              | `c` ahead, `c` = last fired | none ahead |
//! |-------------------|------------------------------------------|-----------------------------|------------|
//! | Watching          | Leading(c, now); FIRE now if `hold` = 0   | Fired(c)                    | Watching   |
//! | Leading(c, since) | same `c`: FIRE → Fired(c) once `now − since ≥ hold`; another: Leading(c, now) | Fired(c) | Watching |
//! | Fired(k)          | Leading(c, now)                          | (`c` = `k`) stays           | Watching   |
//!
//! `Fired(c)` means "the class ahead has already fired": it stays quiet while `c`
//! stays ahead. A vote while `Filling` (before the gesture has lasted a window)
//! cannot come from a due window; it is counted in [`ContinuousStats::early`] and
//! ignored.
//!
//! # Fixed memory
//! [`ContinuousRecogniser::new`] allocates its slots once; `begin`, `due`, `observe`
//! and `end` never allocate. More gestures at once than slots are not watched and
//! are counted ([`ContinuousStats::overflowed`]); their end is recognised as usual.
//! [`window`] and [`recognise_window`] reuse their output buffers' capacity
//! ([`prepare_scaled`] itself allocates its small result: they are meant for the worker).

use super::error::GestureError;
use super::features::GestureFeatures;
use super::knn::{vote, GestureIndex, SearchParams, Searcher};
use super::library::ClassId;
use super::physical::PhysicalFeatures;
use super::resample::prepare_scaled;
use super::track::{GestureTracks, TouchTrack, TrackSample};
use crate::vocab::Micros;

/// How often a window of a live gesture is recognised by default (µs).
pub const DEFAULT_PERIOD: Micros = Micros(100_000);

/// The shortest period accepted (µs); shorter ones are raised to it.
pub const MIN_PERIOD: Micros = Micros(1_000);

/// The least vote weight (eq. 18 sums, in `[0, 1]`) for a class to count as ahead
/// by default: a majority of the K neighbours' weight.
pub const DEFAULT_MIN_WEIGHT: f64 = 0.5;

/// Gestures watched at once by default (as many as the capture captures).
pub const DEFAULT_SLOTS: usize = super::capture::DEFAULT_MAX_GESTURES;

/// A window in which no finger moves farther than this from where it was at the
/// window's start is not recognised by default (mm of glass; the tap threshold of a
/// whole gesture).
pub const DEFAULT_WINDOW_MIN_TRAVEL_MM: f64 = 10.0;

/// The recogniser's timing and sizes.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ContinuousParams {
    /// Length of the window recognised: the gesture's last this long (µs; config
    /// `window_ms`). A gesture is first recognised when it has lasted this long.
    pub window: Micros,
    /// How long a class must stay ahead to fire (µs; config `hold_ms`).
    pub hold: Micros,
    /// Time between two windows of a gesture (µs, at least [`MIN_PERIOD`]).
    pub period: Micros,
    /// Least vote weight for a class to be ahead (in `[0, 1]`; a NaN is replaced by
    /// [`DEFAULT_MIN_WEIGHT`]).
    pub min_weight: f64,
    /// Gestures watched at once (at least 1).
    pub slots: usize,
}

impl ContinuousParams {
    /// The config's `window_ms` and `hold_ms` with the default period, floor and
    /// slots.
    pub fn from_ms(window_ms: u64, hold_ms: u64) -> ContinuousParams {
        ContinuousParams {
            window: Micros(window_ms.saturating_mul(1000)),
            hold: Micros(hold_ms.saturating_mul(1000)),
            period: DEFAULT_PERIOD,
            min_weight: DEFAULT_MIN_WEIGHT,
            slots: DEFAULT_SLOTS,
        }
    }

    /// With out-of-range values brought in range (see the fields).
    fn sanitised(self) -> ContinuousParams {
        ContinuousParams {
            period: self.period.max(MIN_PERIOD),
            min_weight: if self.min_weight.is_nan() {
                DEFAULT_MIN_WEIGHT
            } else {
                self.min_weight.clamp(0.0, 1.0)
            },
            slots: self.slots.max(1),
            ..self
        }
    }
}

/// A class fired for a live gesture.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Fire {
    /// The gesture (segmenter id).
    pub id: u32,
    /// The class that stayed ahead.
    pub class: ClassId,
    /// Its vote weight in the window that fired (in `[min_weight, 1]`).
    pub weight: f64,
    /// The window that fired, `(start, end)` (µs): `end` is the `now` of that vote.
    pub window: (Micros, Micros),
    /// When the class took the lead: the end of its first winning window (µs).
    pub since: Micros,
    /// How many times this gesture has fired, this one included (1 for the first).
    pub count: u32,
}

/// What a gesture's continuous recognition did, told by [`ContinuousRecogniser::end`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Ended {
    /// Times it fired; when positive, the gesture already commanded the crowd and
    /// its recognition as a whole should be skipped.
    pub fired: u32,
    /// The class that fired last.
    pub last: Option<ClassId>,
}

/// Counters of what the recogniser ignored or did, since it was made.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct ContinuousStats {
    /// Gestures not watched: every slot was taken at their `begin`.
    pub overflowed: u64,
    /// Votes no older than the gesture's previous vote (out of order, or repeated).
    pub stale: u64,
    /// Votes for a gesture that had not lasted a window yet.
    pub early: u64,
    /// Votes for a gesture not watched (ended, or never begun).
    pub unknown: u64,
    /// Fires.
    pub fired: u64,
}

/// The state of one slot (see the module doc's diagram).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ContinuousState {
    /// No gesture.
    Free,
    /// The gesture has lasted less than a window.
    Filling,
    /// Windows are recognised; no class is ahead.
    Watching,
    /// `class` has been ahead since `since`, not yet for `hold`.
    Leading {
        /// The class ahead.
        class: ClassId,
        /// End of its first winning window (µs).
        since: Micros,
    },
    /// `class` is ahead and has already fired.
    Fired {
        /// The class ahead.
        class: ClassId,
    },
}

impl ContinuousState {
    /// Name for logs.
    pub fn as_str(&self) -> &'static str {
        match self {
            ContinuousState::Free => "free",
            ContinuousState::Filling => "filling",
            ContinuousState::Watching => "watching",
            ContinuousState::Leading { .. } => "leading",
            ContinuousState::Fired { .. } => "fired",
        }
    }
}

/// The inputs of the machine.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ContinuousEvent {
    /// The gesture began at `at`.
    Begin {
        /// When its first finger landed (µs).
        at: Micros,
    },
    /// Time passed (a control tick).
    Tick {
        /// Now (µs).
        now: Micros,
    },
    /// The vote of the window ending at `now`: the winning class and its weight, or
    /// `None` (nothing to recognise in the window).
    Vote {
        /// End of the window (µs).
        now: Micros,
        /// The vote.
        vote: Option<(ClassId, f64)>,
    },
    /// The gesture ended.
    End,
}

impl ContinuousEvent {
    /// Name for logs.
    pub fn as_str(&self) -> &'static str {
        match self {
            ContinuousEvent::Begin { .. } => "begin",
            ContinuousEvent::Tick { .. } => "tick",
            ContinuousEvent::Vote { .. } => "vote",
            ContinuousEvent::End => "end",
        }
    }
}

/// One watched gesture.
#[derive(Copy, Clone, Debug)]
struct Slot {
    id: u32,
    state: ContinuousState,
    /// When the gesture began.
    start: Micros,
    /// When the next window is due.
    next_due: Micros,
    /// End of the latest vote's window.
    last_vote: Option<Micros>,
    /// The class that fired last.
    last_fired: Option<ClassId>,
    fired: u32,
}

impl Slot {
    const FREE: Slot = Slot {
        id: 0,
        state: ContinuousState::Free,
        start: Micros::ZERO,
        next_due: Micros::ZERO,
        last_vote: None,
        last_fired: None,
        fired: 0,
    };
}

/// What a transition asks of the recogniser.
enum Outcome {
    None,
    Fire(Fire),
    /// A vote while filling.
    Early,
}

/// The sliding-window recogniser's state machines, one per live gesture (see the
/// module doc).
#[derive(Clone, Debug)]
pub struct ContinuousRecogniser {
    params: ContinuousParams,
    slots: Vec<Slot>,
    stats: ContinuousStats,
}

impl ContinuousRecogniser {
    /// A recogniser with its `params.slots` slots allocated (parameters out of range
    /// are brought in range: see [`ContinuousParams`]).
    pub fn new(params: ContinuousParams) -> ContinuousRecogniser {
        let params = params.sanitised();
        ContinuousRecogniser {
            params,
            slots: vec![Slot::FREE; params.slots],
            stats: ContinuousStats::default(),
        }
    }

    /// The parameters in force.
    pub fn params(&self) -> ContinuousParams {
        self.params
    }

    /// The counters.
    pub fn stats(&self) -> ContinuousStats {
        self.stats
    }

    /// Gesture `id`'s state (`Free` when it is not watched).
    pub fn state(&self, id: u32) -> ContinuousState {
        self.find(id)
            .map_or(ContinuousState::Free, |i| self.slots[i].state)
    }

    /// Times gesture `id` has fired so far (0 when it is not watched).
    pub fn fired(&self, id: u32) -> u32 {
        self.find(id).map_or(0, |i| self.slots[i].fired)
    }

    fn find(&self, id: u32) -> Option<usize> {
        self.slots
            .iter()
            .position(|s| s.state != ContinuousState::Free && s.id == id)
    }

    /// Starts watching gesture `id`, which began at `at` (the segmenter's
    /// `t_begin`). Returns false when every slot is taken (counted in
    /// [`ContinuousStats::overflowed`]); a gesture already watched is left as it is
    /// (true).
    pub fn begin(&mut self, id: u32, at: Micros) -> bool {
        if self.find(id).is_some() {
            return true;
        }
        let Some(i) = self
            .slots
            .iter()
            .position(|s| s.state == ContinuousState::Free)
        else {
            self.stats.overflowed += 1;
            return false;
        };
        self.slots[i] = Slot { id, ..Slot::FREE };
        self.step(i, ContinuousEvent::Begin { at });
        true
    }

    /// Whether a window of gesture `id` ending at `now` should be recognised now:
    /// true once the gesture has lasted `window`, then again every `period` (a tick
    /// that comes late is due once; the next is a period later). False for a
    /// gesture not watched.
    pub fn due(&mut self, id: u32, now: Micros) -> bool {
        let Some(i) = self.find(id) else {
            return false;
        };
        self.step(i, ContinuousEvent::Tick { now });
        let period = self.params.period;
        let s = &mut self.slots[i];
        if s.state == ContinuousState::Filling || now < s.next_due {
            return false;
        }
        s.next_due = s.next_due + period;
        if s.next_due <= now {
            s.next_due = now + period;
        }
        true
    }

    /// The vote of gesture `id`'s window ending at `now` (the `now` of the `due`
    /// that asked for it): the winning class and its weight
    /// ([`WindowVote::vote`]), or `None`. Returns the fire, when one class has now
    /// stayed ahead for `hold` (see the module doc).
    pub fn observe(&mut self, id: u32, now: Micros, vote: Option<(ClassId, f64)>) -> Option<Fire> {
        let Some(i) = self.find(id) else {
            self.stats.unknown += 1;
            return None;
        };
        if self.slots[i].last_vote.is_some_and(|t| now <= t) {
            self.stats.stale += 1;
            return None;
        }
        match self.step(i, ContinuousEvent::Vote { now, vote }) {
            Outcome::Fire(f) => {
                self.stats.fired += 1;
                Some(f)
            }
            Outcome::Early => {
                self.stats.early += 1;
                None
            }
            Outcome::None => None,
        }
    }

    /// Stops watching gesture `id` and frees its slot. `None` when it was not
    /// watched (overflowed, or already ended).
    pub fn end(&mut self, id: u32) -> Option<Ended> {
        let i = self.find(id)?;
        let s = self.slots[i];
        self.step(i, ContinuousEvent::End);
        Some(Ended {
            fired: s.fired,
            last: s.last_fired,
        })
    }

    /// Stops watching every gesture (reset; the counters stay).
    pub fn clear(&mut self) {
        for s in &mut self.slots {
            *s = Slot::FREE;
        }
    }

    /// Feeds `ev` to slot `i`'s machine: one handler per state.
    fn step(&mut self, i: usize, ev: ContinuousEvent) -> Outcome {
        let p = self.params;
        let s = &mut self.slots[i];
        if ev == ContinuousEvent::End {
            *s = Slot::FREE;
            return Outcome::None;
        }
        match s.state {
            ContinuousState::Free => on_free(s, ev, &p),
            ContinuousState::Filling => on_filling(s, ev, &p),
            ContinuousState::Watching => on_watching(s, ev, &p),
            ContinuousState::Leading { class, since } => on_leading(s, ev, &p, class, since),
            ContinuousState::Fired { class } => on_fired(s, ev, &p, class),
        }
    }
}

/// The class ahead in a vote: the winner when its weight reaches the floor (a NaN
/// weight does not).
fn ahead(vote: Option<(ClassId, f64)>, p: &ContinuousParams) -> Option<ClassId> {
    vote.filter(|&(_, w)| w >= p.min_weight).map(|(c, _)| c)
}

fn on_free(s: &mut Slot, ev: ContinuousEvent, _p: &ContinuousParams) -> Outcome {
    match ev {
        ContinuousEvent::Begin { at } => {
            s.state = ContinuousState::Filling;
            s.start = at;
            s.next_due = at;
        }
        // A free slot is never found by id, so it sees nothing else.
        other => debug_assert!(false, "continuous: {} in a free slot", other.as_str()),
    }
    Outcome::None
}

fn on_filling(s: &mut Slot, ev: ContinuousEvent, p: &ContinuousParams) -> Outcome {
    match ev {
        ContinuousEvent::Tick { now } if now >= s.start + p.window => {
            s.state = ContinuousState::Watching;
            s.next_due = s.start + p.window;
            Outcome::None
        }
        ContinuousEvent::Vote { .. } => Outcome::Early,
        _ => Outcome::None,
    }
}

fn on_watching(s: &mut Slot, ev: ContinuousEvent, p: &ContinuousParams) -> Outcome {
    match ev {
        ContinuousEvent::Vote { now, vote } => {
            s.last_vote = Some(now);
            match ahead(vote, p) {
                Some(c) => take_lead(s, c, now, vote, p),
                None => Outcome::None,
            }
        }
        _ => Outcome::None,
    }
}

fn on_leading(
    s: &mut Slot,
    ev: ContinuousEvent,
    p: &ContinuousParams,
    class: ClassId,
    since: Micros,
) -> Outcome {
    let ContinuousEvent::Vote { now, vote } = ev else {
        return Outcome::None;
    };
    s.last_vote = Some(now);
    match ahead(vote, p) {
        Some(c) if c == class => hold_or_fire(s, c, since, now, vote, p),
        Some(c) => take_lead(s, c, now, vote, p),
        None => {
            s.state = ContinuousState::Watching;
            Outcome::None
        }
    }
}

fn on_fired(s: &mut Slot, ev: ContinuousEvent, p: &ContinuousParams, class: ClassId) -> Outcome {
    let ContinuousEvent::Vote { now, vote } = ev else {
        return Outcome::None;
    };
    s.last_vote = Some(now);
    match ahead(vote, p) {
        Some(c) if c == class => Outcome::None,
        Some(c) => take_lead(s, c, now, vote, p),
        None => {
            s.state = ContinuousState::Watching;
            Outcome::None
        }
    }
}

/// Class `c` is newly ahead at `now`: it leads (and fires at once when `hold` is
/// 0), unless it is the class that fired last.
fn take_lead(
    s: &mut Slot,
    c: ClassId,
    now: Micros,
    vote: Option<(ClassId, f64)>,
    p: &ContinuousParams,
) -> Outcome {
    if s.last_fired == Some(c) {
        s.state = ContinuousState::Fired { class: c };
        return Outcome::None;
    }
    s.state = ContinuousState::Leading {
        class: c,
        since: now,
    };
    hold_or_fire(s, c, now, now, vote, p)
}

/// Class `c`, ahead since `since`, is still ahead at `now`: fires when it has held.
fn hold_or_fire(
    s: &mut Slot,
    c: ClassId,
    since: Micros,
    now: Micros,
    vote: Option<(ClassId, f64)>,
    p: &ContinuousParams,
) -> Outcome {
    if now.saturating_since(since) < p.hold {
        return Outcome::None;
    }
    s.state = ContinuousState::Fired { class: c };
    s.last_fired = Some(c);
    s.fired += 1;
    Outcome::Fire(Fire {
        id: s.id,
        class: c,
        weight: vote.map_or(0.0, |(_, w)| w),
        window: (now - p.window, now),
        since,
        count: s.fired,
    })
}

/// Cuts every finger of `tracks` to the window `[now − window, now]` into `out`
/// (reusing its tracks' capacity), and returns how many fingers it kept.
///
/// A finger is kept when it has samples on both sides of the window's start or
/// inside the window, i.e. it was down at some time in the window (a finger whose
/// last sample is before the window lifted before it: the capture records every
/// down finger in every frame). Where the window cuts a finger's path between two
/// samples, the cut point is linearly interpolated in time, so a finger down all
/// through the window starts exactly at `now − window` and ends at `min(now, its
/// last sample)`; samples after `now` are cut the same way. Fingers keep their
/// landing order.
///
/// # Units
/// Times in µs, positions in mm, as in the tracks. Each track's times are taken as
/// ascending (as captured).
///
/// # Complexity
/// `O(F log n)` to find the cuts plus the samples copied.
///
/// ```
/// use crowdtouch::geom::Vec2;
/// use crowdtouch::gesture::continuous::window;
/// use crowdtouch::gesture::track::{GestureTracks, TouchTrack, TrackSample};
/// use crowdtouch::vocab::Micros;
/// // A finger moving 100 mm/s rightwards, sampled every 100 ms for 1 s.
/// let line = TouchTrack { samples: (0..=10).map(|i| TrackSample {
///     t: Micros(i * 100_000), mm: Vec2::new(10.0 * i as f64, 0.0) }).collect() };
/// let g = GestureTracks { fingers: vec![line] };
/// let mut out = GestureTracks::default();
/// // The 300 ms ending at 750 ms: cut at 450 ms and 750 ms, between samples.
/// assert_eq!(window(&g, Micros(750_000), Micros(300_000), &mut out), 1);
/// let s = &out.fingers[0].samples;
/// assert_eq!(s.len(), 5); // 450 (cut), 500, 600, 700, 750 (cut)
/// assert!((s[0].mm.x - 45.0).abs() < 1e-12 && (s[4].mm.x - 75.0).abs() < 1e-12);
/// ```
pub fn window(
    tracks: &GestureTracks,
    now: Micros,
    window: Micros,
    out: &mut GestureTracks,
) -> usize {
    let lo = now - window;
    let mut n = 0;
    for f in &tracks.fingers {
        let s = &f.samples;
        let (Some(first), Some(last)) = (s.first(), s.last()) else {
            continue;
        };
        if last.t < lo || first.t > now {
            continue;
        }
        if n == out.fingers.len() {
            out.fingers.push(TouchTrack::default());
        }
        cut(s, lo, now, &mut out.fingers[n].samples);
        n += 1;
    }
    out.fingers.truncate(n);
    n
}

/// The samples of `s` in `[lo, hi]`, with interpolated points at `lo` and `hi`
/// where they fall between two samples.
fn cut(s: &[TrackSample], lo: Micros, hi: Micros, o: &mut Vec<TrackSample>) {
    o.clear();
    let begin = s.partition_point(|x| x.t < lo);
    let end = s.partition_point(|x| x.t <= hi);
    if begin > 0 && begin < s.len() && s[begin].t > lo {
        o.push(lerp(&s[begin - 1], &s[begin], lo));
    }
    if begin < end {
        o.extend_from_slice(&s[begin..end]);
    }
    if end > 0 && end < s.len() && s[end - 1].t < hi {
        o.push(lerp(&s[end - 1], &s[end], hi));
    }
}

/// The point on the segment `a → b` at time `t` (`a.t < t < b.t`).
fn lerp(a: &TrackSample, b: &TrackSample, t: Micros) -> TrackSample {
    let span = b.t.saturating_since(a.t).0 as f64;
    let u = if span > 0.0 {
        t.saturating_since(a.t).0 as f64 / span
    } else {
        0.0
    };
    TrackSample {
        t,
        mm: a.mm + (b.mm - a.mm) * u,
    }
}

/// How a window is recognised.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct WindowParams {
    /// Length of the window (µs; [`ContinuousParams::window`]).
    pub window: Micros,
    /// A window in which no finger moves farther than this from where it was at the
    /// window's start is [`WindowVote::Still`] (mm of glass).
    pub min_travel_mm: f64,
    /// The KNN search (K, feature weights, band: as for whole gestures).
    pub search: SearchParams,
}

/// The outcome of [`recognise_window`].
#[derive(Clone, Debug, PartialEq)]
pub enum WindowVote {
    /// The weighted KNN vote (section 8.2): the winning class and its weight.
    Voted {
        /// The class.
        class: ClassId,
        /// Its share of the K neighbours' weight (eq. 18 sums, in `[0, 1]`).
        weight: f64,
    },
    /// The fingers hardly moved in the window (a resting hand): nothing drawn.
    Still {
        /// Farthest a finger got from where it was at the window's start (mm).
        travel_mm: f64,
    },
    /// The window cannot be recognised (no finger in it, a NaN, ...).
    Refused(GestureError),
    /// The index is empty.
    NoNeighbours,
}

impl WindowVote {
    /// The vote to give [`ContinuousRecogniser::observe`].
    pub fn vote(&self) -> Option<(ClassId, f64)> {
        match *self {
            WindowVote::Voted { class, weight } => Some((class, weight)),
            _ => None,
        }
    }
}

/// Buffers reused from one [`recognise_window`] to the next.
#[derive(Clone, Debug, Default)]
pub struct WindowBuffers {
    /// The last window cut (see [`window`]).
    pub cut: GestureTracks,
    searcher: Searcher,
}

impl WindowBuffers {
    /// Empty buffers (they grow to the largest window and index, then are reused).
    pub fn new() -> WindowBuffers {
        WindowBuffers::default()
    }
}

/// Recognises the window of `tracks` ending at `now`: [`window`] →
/// [`prepare_scaled`] (eqs. 1–3) → [`GestureFeatures::of`] (eq. 11) and
/// [`PhysicalFeatures::of`] → [`Searcher::search_with`] (the index's combined
/// distance, eq. 18) → [`vote`] (section 8.2), where `class_of` names the class of
/// an index entry.
///
/// # Complexity
/// That of one KNN query over `index` (the search's buffers and the window are
/// reused; `prepare_scaled` allocates its result).
pub fn recognise_window(
    tracks: &GestureTracks,
    now: Micros,
    p: &WindowParams,
    index: &GestureIndex,
    class_of: impl Fn(usize) -> ClassId,
    buf: &mut WindowBuffers,
) -> WindowVote {
    window(tracks, now, p.window, &mut buf.cut);
    let travel_mm = buf
        .cut
        .fingers
        .iter()
        .filter_map(|f| {
            let o = f.samples.first()?.mm;
            Some(
                f.samples
                    .iter()
                    .map(|s| (s.mm - o).norm())
                    .fold(0.0, f64::max),
            )
        })
        .fold(0.0, f64::max);
    if travel_mm < p.min_travel_mm {
        return WindowVote::Still { travel_mm };
    }
    let (resampled, scale_mm) = match prepare_scaled(&buf.cut) {
        Ok(r) => r,
        Err(e) => return WindowVote::Refused(e),
    };
    // The recogniser's own distance (the index's weights: eq. 12 and the physical
    // features), so a window is judged as the whole gesture is.
    let features = GestureFeatures::of(&resampled);
    let physical = PhysicalFeatures::of(&resampled, Some(scale_mm));
    let neighbours = buf
        .searcher
        .search_with(index, &features, &physical, &p.search);
    match vote(neighbours, class_of) {
        Some((class, weight)) => WindowVote::Voted { class, weight },
        None => WindowVote::NoNeighbours,
    }
}

#[cfg(test)]
#[path = "continuous_tests.rs"]
mod tests;
