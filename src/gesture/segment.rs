//! Segmentation: which touches form a control on the crowd, and which a gesture in
//! open space.
//!
//! mesh-formation-control section 4.2: "the timing that the fingers are placed on the
//! multi-touch screen is examined. A single touch input gives basic point-based
//! control, two simultaneous touch points indicates a line control, whilst three or
//! more simultaneous touch points creates an area control." We read "simultaneous" as
//! *within the grouping window of the control's first finger* and add a spatial test
//! (within one hand's span on the glass), so that several people at one table, or two
//! hands of one person, make separate controls that act on the mesh together.
//!
//! A touch that lands on the crowd (within the grab radius of the mesh) starts or
//! joins a control; elsewhere it starts or joins a gesture (gesture-driven section 4:
//! first touch to all fingers lifted, plus a grace period).
//!
//! # State machines
//!
//! ```text
//!  control:   ┌──────────┐ window over ┌──────┐ last finger up ┌───────┐
//!   finger ──►│ Grouping │────────────►│ Held │───────────────►│ Ended │
//!   down      └──────────┘             └──────┘                └───────┘
//!               │  ▲ finger down (near, in window): kind upgrades   ▲
//!               └──┘                                                │
//!               └─────────────── last finger up ────────────────────┘
//!
//!  gesture:   ┌────────┐ last finger up ┌───────┐ grace over ┌───────┐
//!   finger ──►│ Active │───────────────►│ Grace │───────────►│ Ended │
//!   down      └────────┘◄───────────────└───────┘            └───────┘
//!                  ▲ finger down (near)   finger down (near)
//!                  └─┘
//! ```
//! Fingers of a control that lift while others stay keep their handle pinned where
//! they left it; the control ends when its last finger is up.
//!
//! # One hand, one gesture, on real hardware
//! Touch surfaces lose a finger for a few frames, give a finger a new tracking id
//! mid-stroke (the slot's id changes: the old contact ends and a new one begins in
//! the same frame), and optical or infrared frames report ghost contacts for a frame
//! or two where two real fingers' shadows cross. A gesture therefore counts
//! *fingers*, not contact ids:
//! - a contact landing within [`REATTACH_WINDOW`] of a lift in the same gesture and
//!   within [`REATTACH_MM`] of where that finger lifted is the same finger again
//!   (its record takes the new id and goes on; the capture continues its track);
//! - a gesture whose records are full ([`MAX_GESTURE_CONTACTS`]) re-attaches any
//!   further landing to its nearest lifted finger instead of starting a gesture of
//!   its own, so no id churn cuts a hand into one gesture per finger;
//! - a contact that lives less than [`GHOST_LIFE`], landing after another finger of
//!   the gesture and lifting while that finger is still down, is a ghost: it is not
//!   a finger (not counted in `max_down`, its track dropped by the capture);
//! - a finger landing in open space joins the *nearest* live gesture within
//!   `gesture_span_mm`, whatever the time since that gesture began, so fingers of a
//!   hand landing apart in time (the first lifting before the last lands within the
//!   grace period) or in space (a hand's span) are one gesture;
//! - a finger landing within `group_window` of a control's or a gesture's first
//!   finger and within `hand_span_mm` of its fingers joins it whether or not it
//!   landed on the crowd: a hand straddling the crowd's edge is one control, or one
//!   gesture, as its first finger decided.
//!
//! `max_down`, the gesture's finger count, is the most non-ghost fingers down at
//! once, counted from every finger's [`FingerSpan`] (a re-attached finger counts as
//! down through its gap).

use crate::geom::Vec2;
use crate::vocab::ControlKind;
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, ContactId};

/// The control kind for a number of fingers: one a point control, two a line, three
/// or more an area (mesh-formation-control section 4.2).
pub fn control_kind(fingers: usize) -> ControlKind {
    match fingers {
        0 | 1 => ControlKind::Point,
        2 => ControlKind::Line,
        _ => ControlKind::Area,
    }
}

/// Most fingers one control holds, and most fingers one gesture has down at once;
/// an eleventh finger landing near starts a new control or gesture of its own.
pub const MAX_FINGERS: usize = 10;

/// Most contacts one gesture takes part in over its life (each landing is a contact,
/// so a finger that bounces counts twice); a further landing starts a new gesture.
/// The capture ([`GestureCapture`](super::capture::GestureCapture)) keeps a track
/// for each of them.
pub const MAX_GESTURE_CONTACTS: usize = 2 * MAX_FINGERS;

/// A contact landing this soon after a finger of the same gesture lifted may be that
/// finger again (a finger lost for a few frames, or given a new tracking id):
/// 100 ms, a dozen frames at 120 Hz.
pub const REATTACH_WINDOW: Micros = Micros(100_000);

/// ...if it lands within this distance of where that finger lifted (mm of glass):
/// a finger at 250 mm/s covers 25 mm in [`REATTACH_WINDOW`]; neighbouring fingers of
/// a hand are about 20 mm apart, but only *lifted* fingers are candidates, the
/// nearest first.
pub const REATTACH_MM: f64 = 25.0;

/// A contact of a gesture that lives less than this, landing after another of its
/// fingers and lifting while that finger is down, is a ghost (40 ms: one to three
/// frames of an optical or infrared frame at 60–100 Hz). Fingers landing together
/// (a two-finger tap of 30 ms) are not ghosts: none landed before the other.
pub const GHOST_LIFE: Micros = Micros(40_000);

/// Tunables of the segmenter.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SegmentParams {
    /// Fingers within this time of a control's first finger may join it (µs).
    pub group_window: Micros,
    /// ...if within this distance of one of its fingers on the glass (mm).
    pub hand_span_mm: f64,
    /// A finger landing in open space joins a gesture under way if within this
    /// distance of one of its fingers on the glass (mm): a person's second hand
    /// (gesture-driven section 4: join and split are drawn with two hands). Farther,
    /// it starts a gesture of its own (another person at the table).
    pub gesture_span_mm: f64,
    /// A gesture ends this long after its last lift (µs).
    pub gesture_grace: Micros,
}

/// A touch as the segmenter sees it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TouchPoint {
    /// Contact id.
    pub id: ContactId,
    /// World position (m).
    pub world: Vec2,
    /// Position on the glass (mm), for the hand-span test.
    pub glass_mm: Vec2,
    /// Life-cycle flags of this frame.
    pub flags: ContactFlags,
}

/// State of a control.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ControlState {
    /// Within the grouping window: more fingers may join.
    Grouping,
    /// Window closed, at least one finger down.
    Held,
    /// Every finger lifted.
    Ended,
}

impl ControlState {
    /// Name for logs.
    pub fn as_str(self) -> &'static str {
        match self {
            ControlState::Grouping => "grouping",
            ControlState::Held => "held",
            ControlState::Ended => "ended",
        }
    }
}

/// State of a gesture.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum GestureState {
    /// Fingers are down.
    Active,
    /// All fingers up; waiting out the grace period for more.
    Grace,
    /// Done.
    Ended,
}

impl GestureState {
    /// Name for logs.
    pub fn as_str(self) -> &'static str {
        match self {
            GestureState::Active => "active",
            GestureState::Grace => "grace",
            GestureState::Ended => "ended",
        }
    }
}

/// Inputs to both machines.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum SegEvent {
    /// A finger landed near (in space and time).
    FingerDown,
    /// A finger lifted (or was cancelled); `last` when no finger remains down.
    FingerUp {
        /// Whether this was the last finger down.
        last: bool,
    },
    /// Time passed.
    Tick,
}

impl SegEvent {
    /// Name for logs.
    pub fn as_str(&self) -> &'static str {
        match self {
            SegEvent::FingerDown => "finger-down",
            SegEvent::FingerUp { .. } => "finger-up",
            SegEvent::Tick => "tick",
        }
    }
}

/// One finger of a control or gesture.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Finger {
    /// Contact id.
    pub id: ContactId,
    /// Latest world position (m).
    pub world: Vec2,
    /// World position when it landed (m).
    pub world_down: Vec2,
    /// Latest position on the glass (mm).
    pub glass_mm: Vec2,
    /// Whether it is still down.
    pub down: bool,
    /// Whether it ended by cancellation.
    pub cancelled: bool,
}

/// A control: fingers on the crowd acting together.
#[derive(Clone, Debug, PartialEq)]
pub struct Control {
    /// Id, unique while the segmenter lives.
    pub id: u32,
    /// State.
    pub state: ControlState,
    /// When the first finger landed.
    pub t_begin: Micros,
    /// Fingers in landing order (lifted ones stay, pinned).
    pub fingers: Vec<Finger>,
}

impl Control {
    /// Point, line or area, from the number of fingers.
    pub fn kind(&self) -> ControlKind {
        control_kind(self.fingers.len())
    }
    fn down_count(&self) -> usize {
        self.fingers.iter().filter(|f| f.down).count()
    }
}

/// When one finger of a gesture was down (its first landing to its last lift).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FingerSpan {
    /// Its first landing.
    pub t_down: Micros,
    /// Its last lift; `None` while down.
    pub t_up: Option<Micros>,
    /// Whether it was a ghost contact (see [`GHOST_LIFE`]).
    pub ghost: bool,
}

/// A gesture: fingers in open space from first touch to last lift plus grace.
#[derive(Clone, Debug, PartialEq)]
pub struct Gesture {
    /// Id, unique while the segmenter lives.
    pub id: u32,
    /// State.
    pub state: GestureState,
    /// When the first finger landed.
    pub t_begin: Micros,
    /// When the last finger lifted (valid in `Grace`).
    pub t_last_up: Micros,
    /// Fingers that took part (current and lifted), one record per finger: a
    /// re-attached contact takes over its finger's record.
    pub fingers: Vec<Finger>,
    /// When each finger was down, `spans[k]` for `fingers[k]`.
    pub spans: Vec<FingerSpan>,
    /// Most fingers down at once, ghosts not counted.
    pub max_down: u32,
    /// Landings that continued a lifted finger (new ids, fingers lost for a while).
    pub reattached: u32,
    /// Most fingers down at once before the last forced re-attachment (a landing
    /// given to a long-lifted finger restarts that finger's span).
    max_down_before: u32,
}

impl Gesture {
    fn down_count(&self) -> usize {
        self.fingers.iter().filter(|f| f.down).count()
    }

    /// Distance from `p` to the nearest of its fingers (mm).
    fn distance_mm(&self, p: Vec2) -> f64 {
        self.fingers
            .iter()
            .map(|f| (f.glass_mm - p).norm_squared())
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }

    /// The lifted finger a landing at `p` at `now` continues, if any (see the
    /// module doc): the nearest within [`REATTACH_MM`] that lifted within
    /// [`REATTACH_WINDOW`], not a ghost; when the records are full, the nearest
    /// lifted finger.
    fn reattach_candidate(&self, now: Micros, p: Vec2) -> Option<(usize, bool)> {
        let full = self.fingers.len() >= MAX_GESTURE_CONTACTS;
        let mut best: Option<(usize, f64, bool)> = None;
        for (k, (f, s)) in self.fingers.iter().zip(&self.spans).enumerate() {
            let Some(t_up) = s.t_up else { continue };
            if f.down {
                continue;
            }
            let d2 = (f.glass_mm - p).norm_squared();
            let near = !s.ghost
                && now.saturating_since(t_up) <= REATTACH_WINDOW
                && d2 <= REATTACH_MM * REATTACH_MM;
            if (near || full) && best.is_none_or(|(_, b, _)| d2 < b) {
                best = Some((k, d2, near));
            }
        }
        best.map(|(k, _, near)| (k, near))
    }

    /// Most non-ghost fingers down at once, from the spans (at least 1) and what
    /// was counted before the last forced re-attachment. A finger counts at its own
    /// landing even when it lifted in the same frame.
    fn count_max_down(&self) -> u32 {
        let real = || self.spans.iter().enumerate().filter(|(_, s)| !s.ghost);
        let mut most = 0;
        for (k, sk) in real() {
            let at = sk.t_down;
            let n = real()
                .filter(|(j, sj)| sj.t_down <= at && (*j == k || sj.t_up.is_none_or(|u| u > at)))
                .count();
            most = most.max(n);
        }
        (most.max(1) as u32).max(self.max_down_before)
    }
}

/// What the segmenter reports.
#[derive(Clone, Debug, PartialEq)]
pub enum Segment {
    /// A control began (its index in [`Segmenter::controls`] is stable until it ends).
    ControlBegin(u32),
    /// A control gained a finger.
    ControlUpdate(u32),
    /// A control ended.
    ControlEnd {
        /// Id.
        id: u32,
        /// Kind when it ended.
        kind: ControlKind,
        /// Whether a finger was cancelled rather than lifted.
        cancelled: bool,
    },
    /// A gesture began.
    GestureBegin(u32),
    /// A gesture ended.
    GestureEnd {
        /// Id.
        id: u32,
        /// Most fingers down at once.
        fingers: u32,
        /// Fingers that took part, ghosts included: each once, however many
        /// contact ids it had (a re-attached contact is its finger again).
        contacts: u32,
        /// First touch to last lift (µs).
        duration: Micros,
        /// Whether a finger was cancelled.
        cancelled: bool,
    },
}

/// The segmenter: owns the live controls and gestures.
#[derive(Debug)]
pub struct Segmenter {
    params: SegmentParams,
    controls: Vec<Control>,
    gestures: Vec<Gesture>,
    next_control: u32,
    next_gesture: u32,
    /// Every touch is a gesture, whatever it lands on (a table with no direct control).
    all_gestures: bool,
    /// Transitions a handler did not expect (internal bugs), counted.
    pub bad_transitions: u64,
}

impl Segmenter {
    /// A segmenter with no touches.
    pub fn new(params: SegmentParams) -> Segmenter {
        Segmenter {
            params,
            controls: Vec::with_capacity(16),
            gestures: Vec::with_capacity(16),
            next_control: 1,
            next_gesture: 1,
            all_gestures: false,
            bad_transitions: 0,
        }
    }

    /// With `on`, every touch that lands starts or joins a gesture, whatever
    /// `on_crowd` says (config `gestures.all_touches_are_gestures`: a table with no
    /// direct control). Touches already down keep what they are.
    pub fn set_all_touches_are_gestures(&mut self, on: bool) {
        self.all_gestures = on;
    }

    /// Whether every touch is a gesture ([`set_all_touches_are_gestures`](Self::set_all_touches_are_gestures)).
    pub fn all_touches_are_gestures(&self) -> bool {
        self.all_gestures
    }

    /// Replaces the tunables (config reload); live controls keep going.
    pub fn set_params(&mut self, params: SegmentParams) {
        self.params = params;
    }

    /// Live controls (state `Grouping` or `Held`).
    pub fn controls(&self) -> &[Control] {
        &self.controls
    }

    /// Live gestures.
    pub fn gestures(&self) -> &[Gesture] {
        &self.gestures
    }

    /// Finds the live control holding a contact.
    pub fn control_of(&self, id: ContactId) -> Option<&Control> {
        self.controls
            .iter()
            .find(|c| c.fingers.iter().any(|f| f.id == id && f.down))
    }

    /// Feeds one touch of a frame. `on_crowd` says whether it is on the crowd (only
    /// read for touches that begin). Reports what changed into `out`.
    pub fn touch(&mut self, now: Micros, t: &TouchPoint, on_crowd: bool, out: &mut Vec<Segment>) {
        if t.flags.contains(ContactFlags::PALM) {
            return;
        }
        if t.flags.contains(ContactFlags::DOWN) {
            let on_crowd = match self.young_hand(now, t.glass_mm) {
                // A finger of a hand that just landed goes where the hand went.
                Some(control) => control,
                None => on_crowd,
            } && !self.all_gestures;
            self.finger_down(now, t, on_crowd, out);
        } else {
            self.finger_moved(t);
        }
        if t.flags.ended() {
            self.finger_up(now, t, out);
        }
    }

    /// Advances time-based transitions (window closing, grace over).
    pub fn tick(&mut self, now: Micros, out: &mut Vec<Segment>) {
        for i in 0..self.controls.len() {
            self.control_event(i, now, SegEvent::Tick, out);
        }
        for i in 0..self.gestures.len() {
            self.gesture_event(i, now, SegEvent::Tick, out);
        }
        self.controls.retain(|c| c.state != ControlState::Ended);
        self.gestures.retain(|g| g.state != GestureState::Ended);
    }

    /// Ends every control and gesture (reset, shutdown).
    pub fn cancel_all(&mut self, now: Micros, out: &mut Vec<Segment>) {
        for c in &self.controls {
            out.push(Segment::ControlEnd {
                id: c.id,
                kind: c.kind(),
                cancelled: true,
            });
        }
        for g in &self.gestures {
            out.push(Segment::GestureEnd {
                id: g.id,
                fingers: g.max_down,
                contacts: g.fingers.len() as u32,
                duration: now.saturating_since(g.t_begin),
                cancelled: true,
            });
        }
        self.controls.clear();
        self.gestures.clear();
    }

    /// Whether a finger landing at `p` belongs to a hand that began within the
    /// grouping window and within a hand's span of it: `Some(true)` for a control
    /// still grouping, `Some(false)` for a gesture, the nearer when both; `None`
    /// when no hand is that young and near. The fingers of one hand land up to
    /// `group_window` apart and may straddle the crowd's edge: they stay together.
    fn young_hand(&self, now: Micros, p: Vec2) -> Option<bool> {
        let span2 = self.params.hand_span_mm * self.params.hand_span_mm;
        let young = |t_begin: Micros| now.saturating_since(t_begin) <= self.params.group_window;
        let nearest = |fingers: &[Finger]| {
            fingers
                .iter()
                .map(|f| (f.glass_mm - p).norm_squared())
                .fold(f64::INFINITY, f64::min)
        };
        let control = self
            .controls
            .iter()
            .filter(|c| c.state == ControlState::Grouping && young(c.t_begin))
            .filter(|c| c.fingers.len() < MAX_FINGERS)
            .map(|c| nearest(&c.fingers))
            .fold(f64::INFINITY, f64::min);
        let gesture = self
            .gestures
            .iter()
            .filter(|g| g.state == GestureState::Active && young(g.t_begin))
            .filter(|g| g.down_count() < MAX_FINGERS)
            .map(|g| nearest(&g.fingers))
            .fold(f64::INFINITY, f64::min);
        match (control <= span2, gesture <= span2) {
            (false, false) => None,
            (true, false) => Some(true),
            (false, true) => Some(false),
            (true, true) => Some(control <= gesture),
        }
    }

    fn near(&self, fingers: &[Finger], p: Vec2) -> bool {
        let span2 = self.params.hand_span_mm * self.params.hand_span_mm;
        fingers
            .iter()
            .any(|f| (f.glass_mm - p).norm_squared() <= span2)
    }

    fn finger_down(&mut self, now: Micros, t: &TouchPoint, on_crowd: bool, out: &mut Vec<Segment>) {
        let finger = Finger {
            id: t.id,
            world: t.world,
            world_down: t.world,
            glass_mm: t.glass_mm,
            down: true,
            cancelled: false,
        };
        if on_crowd {
            let join = self.controls.iter().position(|c| {
                c.state == ControlState::Grouping
                    && now.saturating_since(c.t_begin) <= self.params.group_window
                    && c.fingers.len() < MAX_FINGERS
                    && self.near(&c.fingers, t.glass_mm)
            });
            match join {
                Some(i) => {
                    self.controls[i].fingers.push(finger);
                    self.control_event(i, now, SegEvent::FingerDown, out);
                }
                None => {
                    let id = self.next_control;
                    self.next_control = self.next_control.wrapping_add(1).max(1);
                    let mut fingers = Vec::with_capacity(4);
                    fingers.push(finger);
                    self.controls.push(Control {
                        id,
                        state: ControlState::Grouping,
                        t_begin: now,
                        fingers,
                    });
                    out.push(Segment::ControlBegin(id));
                }
            }
        } else {
            // A finger landing near a gesture joins the nearest, in `Active` (a finger
            // joining mid-gesture) and in `Grace` (a bounce: the gesture goes on).
            let span2 = self.params.gesture_span_mm * self.params.gesture_span_mm;
            let join = self
                .gestures
                .iter()
                .enumerate()
                .filter(|(_, g)| g.state != GestureState::Ended && g.down_count() < MAX_FINGERS)
                .map(|(i, g)| (i, g.distance_mm(t.glass_mm)))
                .filter(|&(_, d)| d * d <= span2)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(i, _)| i);
            match join {
                Some(i) => {
                    let g = &mut self.gestures[i];
                    match g.reattach_candidate(now, t.glass_mm) {
                        Some((k, near)) => {
                            if !near {
                                // Forced (records full): the finger's gap is not a
                                // time it was down; keep what was counted so far.
                                g.max_down_before = g.count_max_down();
                                g.spans[k].t_down = now;
                            }
                            g.fingers[k] = Finger {
                                world_down: g.fingers[k].world_down,
                                ..finger
                            };
                            g.spans[k].t_up = None;
                            g.spans[k].ghost = false;
                            g.reattached += 1;
                        }
                        None => {
                            g.fingers.push(finger);
                            g.spans.push(FingerSpan {
                                t_down: now,
                                t_up: None,
                                ghost: false,
                            });
                        }
                    }
                    self.gesture_event(i, now, SegEvent::FingerDown, out);
                }
                None => {
                    let id = self.next_gesture;
                    self.next_gesture = self.next_gesture.wrapping_add(1).max(1);
                    let mut fingers = Vec::with_capacity(4);
                    fingers.push(finger);
                    let mut spans = Vec::with_capacity(4);
                    spans.push(FingerSpan {
                        t_down: now,
                        t_up: None,
                        ghost: false,
                    });
                    self.gestures.push(Gesture {
                        id,
                        state: GestureState::Active,
                        t_begin: now,
                        t_last_up: now,
                        fingers,
                        spans,
                        max_down: 1,
                        reattached: 0,
                        max_down_before: 0,
                    });
                    out.push(Segment::GestureBegin(id));
                }
            }
        }
    }

    fn finger_moved(&mut self, t: &TouchPoint) {
        let update = |f: &mut Finger| {
            if f.id == t.id && f.down {
                f.world = t.world;
                f.glass_mm = t.glass_mm;
            }
        };
        self.controls
            .iter_mut()
            .flat_map(|c| c.fingers.iter_mut())
            .for_each(update);
        self.gestures
            .iter_mut()
            .flat_map(|g| g.fingers.iter_mut())
            .for_each(update);
    }

    fn finger_up(&mut self, now: Micros, t: &TouchPoint, out: &mut Vec<Segment>) {
        let cancelled = t.flags.contains(ContactFlags::CANCELLED);
        for i in 0..self.controls.len() {
            let c = &mut self.controls[i];
            if let Some(f) = c.fingers.iter_mut().find(|f| f.id == t.id && f.down) {
                f.down = false;
                f.cancelled = cancelled;
                f.world = t.world;
                let last = c.down_count() == 0;
                self.control_event(i, now, SegEvent::FingerUp { last }, out);
            }
        }
        for i in 0..self.gestures.len() {
            let g = &mut self.gestures[i];
            if let Some(k) = g.fingers.iter().position(|f| f.id == t.id && f.down) {
                let f = &mut g.fingers[k];
                f.down = false;
                f.cancelled = cancelled;
                f.world = t.world;
                let landed = g.spans[k].t_down;
                let ghost = !cancelled
                    && now.saturating_since(landed) < GHOST_LIFE
                    && g.fingers
                        .iter()
                        .zip(&g.spans)
                        .any(|(o, s)| o.down && s.t_down < landed);
                g.spans[k].t_up = Some(now);
                g.spans[k].ghost = ghost;
                let last = g.down_count() == 0;
                self.gesture_event(i, now, SegEvent::FingerUp { last }, out);
            }
        }
        self.controls.retain(|c| c.state != ControlState::Ended);
        self.gestures.retain(|g| g.state != GestureState::Ended);
    }

    fn bad(&mut self, what: &str, state: &str, ev: SegEvent) {
        self.bad_transitions += 1;
        log::error!(
            "internal bug: {what} in state {state} got event {}",
            ev.as_str()
        );
        debug_assert!(false, "{what} in state {state} got event {}", ev.as_str());
    }

    fn control_event(&mut self, i: usize, now: Micros, ev: SegEvent, out: &mut Vec<Segment>) {
        let state = self.controls[i].state;
        match state {
            ControlState::Grouping => self.control_grouping(i, now, ev, out),
            ControlState::Held => self.control_held(i, ev, out),
            ControlState::Ended => {
                if ev != SegEvent::Tick {
                    self.bad("control", state.as_str(), ev);
                }
            }
        }
    }

    fn control_grouping(&mut self, i: usize, now: Micros, ev: SegEvent, out: &mut Vec<Segment>) {
        let c = &mut self.controls[i];
        match ev {
            SegEvent::FingerDown => out.push(Segment::ControlUpdate(c.id)),
            SegEvent::FingerUp { last: true } => self.end_control(i, out),
            SegEvent::FingerUp { last: false } => {}
            SegEvent::Tick => {
                if now.saturating_since(c.t_begin) > self.params.group_window {
                    c.state = ControlState::Held;
                }
            }
        }
    }

    fn control_held(&mut self, i: usize, ev: SegEvent, out: &mut Vec<Segment>) {
        match ev {
            SegEvent::FingerUp { last: true } => self.end_control(i, out),
            SegEvent::FingerUp { last: false } | SegEvent::Tick => {}
            SegEvent::FingerDown => self.bad("control", ControlState::Held.as_str(), ev),
        }
    }

    fn end_control(&mut self, i: usize, out: &mut Vec<Segment>) {
        let c = &mut self.controls[i];
        c.state = ControlState::Ended;
        out.push(Segment::ControlEnd {
            id: c.id,
            kind: c.kind(),
            cancelled: c.fingers.iter().any(|f| f.cancelled),
        });
    }

    fn gesture_event(&mut self, i: usize, now: Micros, ev: SegEvent, out: &mut Vec<Segment>) {
        let g = &mut self.gestures[i];
        match (g.state, ev) {
            (GestureState::Active, SegEvent::FingerDown)
            | (GestureState::Grace, SegEvent::FingerDown) => {
                g.state = GestureState::Active;
                g.max_down = g.count_max_down();
            }
            (GestureState::Active, SegEvent::FingerUp { last: true }) => {
                g.state = GestureState::Grace;
                g.t_last_up = now;
                g.max_down = g.count_max_down();
            }
            (GestureState::Active, SegEvent::FingerUp { last: false }) => {
                g.max_down = g.count_max_down();
            }
            (GestureState::Active, SegEvent::Tick) => {}
            (GestureState::Grace, SegEvent::Tick) => {
                if now.saturating_since(g.t_last_up) >= self.params.gesture_grace {
                    g.state = GestureState::Ended;
                    out.push(Segment::GestureEnd {
                        id: g.id,
                        fingers: g.max_down,
                        contacts: g.fingers.len() as u32,
                        duration: g.t_last_up.saturating_since(g.t_begin),
                        cancelled: g.fingers.iter().any(|f| f.cancelled),
                    });
                }
            }
            (GestureState::Ended, SegEvent::Tick) => {}
            (state, ev) => self.bad("gesture", state.as_str(), ev),
        }
    }
}

#[cfg(test)]
#[path = "segment_tests.rs"]
mod tests;
