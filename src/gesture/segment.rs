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
    /// Fingers that took part (current and lifted).
    pub fingers: Vec<Finger>,
    /// Most fingers down at once.
    pub max_down: u32,
}

impl Gesture {
    fn down_count(&self) -> usize {
        self.fingers.iter().filter(|f| f.down).count()
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
        /// Contacts that took part.
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
            let on_crowd = on_crowd && !self.all_gestures;
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

    fn near(&self, fingers: &[Finger], p: Vec2) -> bool {
        self.near_span(fingers, p, self.params.hand_span_mm)
    }

    fn near_span(&self, fingers: &[Finger], p: Vec2, span_mm: f64) -> bool {
        let span2 = span_mm * span_mm;
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
            // A finger landing near a gesture joins it, in `Active` (a finger joining
            // mid-gesture) and in `Grace` (a bounce: the gesture goes on).
            let join = self.gestures.iter().position(|g| {
                g.state != GestureState::Ended
                    && g.fingers.len() < MAX_GESTURE_CONTACTS
                    && g.down_count() < MAX_FINGERS
                    && self.near_span(&g.fingers, t.glass_mm, self.params.gesture_span_mm)
            });
            match join {
                Some(i) => {
                    self.gestures[i].fingers.push(finger);
                    self.gesture_event(i, now, SegEvent::FingerDown, out);
                }
                None => {
                    let id = self.next_gesture;
                    self.next_gesture = self.next_gesture.wrapping_add(1).max(1);
                    let mut fingers = Vec::with_capacity(4);
                    fingers.push(finger);
                    self.gestures.push(Gesture {
                        id,
                        state: GestureState::Active,
                        t_begin: now,
                        t_last_up: now,
                        fingers,
                        max_down: 1,
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
            if let Some(f) = g.fingers.iter_mut().find(|f| f.id == t.id && f.down) {
                f.down = false;
                f.cancelled = cancelled;
                f.world = t.world;
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
                g.max_down = g.max_down.max(g.down_count() as u32);
            }
            (GestureState::Active, SegEvent::FingerUp { last: true }) => {
                g.state = GestureState::Grace;
                g.t_last_up = now;
            }
            (GestureState::Active, SegEvent::FingerUp { last: false })
            | (GestureState::Active, SegEvent::Tick) => {}
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
mod tests {
    use super::*;

    const MS: u64 = 1000;

    fn params() -> SegmentParams {
        SegmentParams {
            group_window: Micros(150 * MS),
            hand_span_mm: 200.0,
            gesture_span_mm: 200.0,
            gesture_grace: Micros(250 * MS),
        }
    }

    /// A tiny timeline: `(t_ms, id, x_mm, y_mm, flags)`; world = glass / 100.
    fn run(
        seg: &mut Segmenter,
        steps: &[(u64, u32, f64, f64, ContactFlags)],
        crowd: impl Fn(Vec2) -> bool,
    ) -> Vec<Segment> {
        let mut out = Vec::new();
        for &(t, id, x, y, flags) in steps {
            let now = Micros(t * MS);
            seg.tick(now, &mut out);
            let glass = Vec2::new(x, y);
            let p = TouchPoint {
                id: ContactId(id),
                world: glass / 100.0,
                glass_mm: glass,
                flags,
            };
            let on = crowd(p.world);
            seg.touch(now, &p, on, &mut out);
        }
        out
    }

    const D: ContactFlags = ContactFlags::DOWN;
    const M: ContactFlags = ContactFlags::NONE;
    const U: ContactFlags = ContactFlags::UP;

    #[test]
    fn one_two_three_fingers_make_point_line_area() {
        for n in 1..=4u32 {
            let mut seg = Segmenter::new(params());
            let mut steps = vec![];
            for i in 0..n {
                steps.push((i as u64 * 30, i + 1, 100.0 + 40.0 * i as f64, 100.0, D));
            }
            run(&mut seg, &steps, |_| true);
            assert_eq!(seg.controls().len(), 1);
            assert_eq!(seg.controls()[0].kind(), control_kind(n as usize));
        }
    }

    #[test]
    fn late_finger_starts_a_new_control() {
        let mut seg = Segmenter::new(params());
        let out = run(
            &mut seg,
            &[(0, 1, 100.0, 100.0, D), (200, 2, 150.0, 100.0, D)],
            |_| true,
        );
        assert_eq!(seg.controls().len(), 2);
        assert_eq!(
            out,
            vec![Segment::ControlBegin(1), Segment::ControlBegin(2)]
        );
        assert!(seg
            .controls()
            .iter()
            .all(|c| c.kind() == ControlKind::Point));
    }

    #[test]
    fn two_hands_far_apart_make_two_controls() {
        let mut seg = Segmenter::new(params());
        run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (10, 2, 100.0, 180.0, D),
                (20, 3, 600.0, 100.0, D),
                (30, 4, 640.0, 120.0, D),
                (40, 5, 620.0, 160.0, D),
            ],
            |_| true,
        );
        let kinds: Vec<_> = seg.controls().iter().map(|c| c.kind()).collect();
        assert_eq!(kinds, vec![ControlKind::Line, ControlKind::Area]);
    }

    #[test]
    fn control_ends_when_last_finger_lifts_and_pins_the_first() {
        let mut seg = Segmenter::new(params());
        let out = run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (20, 2, 150.0, 100.0, D),
                (300, 1, 90.0, 100.0, U),
                (310, 2, 160.0, 100.0, M),
            ],
            |_| true,
        );
        assert_eq!(seg.controls().len(), 1);
        let c = &seg.controls()[0];
        assert_eq!(c.state, ControlState::Held);
        assert!(!c.fingers[0].down);
        assert_eq!(c.fingers[0].world, Vec2::new(0.9, 1.0));
        assert_eq!(out.len(), 2);
        let out = run(&mut seg, &[(400, 2, 170.0, 100.0, U)], |_| true);
        assert_eq!(
            out,
            vec![Segment::ControlEnd {
                id: 1,
                kind: ControlKind::Line,
                cancelled: false
            }]
        );
        assert!(seg.controls().is_empty());
    }

    #[test]
    fn gesture_ends_after_grace_and_a_quick_refinger_continues_it() {
        let mut seg = Segmenter::new(params());
        let off = |_: Vec2| false;
        let mut out = run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (100, 1, 120.0, 100.0, U),
                (200, 2, 130.0, 100.0, D),
            ],
            off,
        );
        assert_eq!(out, vec![Segment::GestureBegin(1)]);
        out = run(&mut seg, &[(300, 2, 140.0, 100.0, U)], off);
        assert!(out.is_empty());
        seg.tick(Micros(500 * MS), &mut out);
        assert!(out.is_empty(), "grace not over yet: {out:?}");
        seg.tick(Micros(551 * MS), &mut out);
        assert_eq!(
            out,
            vec![Segment::GestureEnd {
                id: 1,
                fingers: 1,
                contacts: 2,
                duration: Micros(300 * MS),
                cancelled: false
            }]
        );
        assert!(seg.gestures().is_empty());
    }

    #[test]
    fn cancelled_contact_is_reported_as_cancelled() {
        let mut seg = Segmenter::new(params());
        let out = run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (50, 1, 100.0, 100.0, ContactFlags::CANCELLED),
            ],
            |_| true,
        );
        assert_eq!(
            out[1],
            Segment::ControlEnd {
                id: 1,
                kind: ControlKind::Point,
                cancelled: true
            }
        );
    }

    #[test]
    fn down_and_up_in_one_coalesced_frame_begins_and_ends() {
        let mut seg = Segmenter::new(params());
        let out = run(&mut seg, &[(0, 1, 100.0, 100.0, D | U)], |_| true);
        assert_eq!(out.len(), 2);
        assert!(matches!(out[1], Segment::ControlEnd { .. }));
        assert!(seg.controls().is_empty());
    }

    #[test]
    fn palms_are_ignored() {
        let mut seg = Segmenter::new(params());
        let out = run(
            &mut seg,
            &[(0, 1, 100.0, 100.0, D | ContactFlags::PALM)],
            |_| true,
        );
        assert!(out.is_empty());
        assert!(seg.controls().is_empty());
        assert_eq!(seg.bad_transitions, 0);
    }

    #[test]
    fn a_finger_landing_after_the_grace_starts_a_new_gesture() {
        let mut seg = Segmenter::new(params());
        let off = |_: Vec2| false;
        let mut out = run(
            &mut seg,
            &[
                (0, 1, 100.0, 100.0, D),
                (100, 1, 120.0, 100.0, U),
                (400, 2, 125.0, 100.0, D),
            ],
            off,
        );
        assert_eq!(out[0], Segment::GestureBegin(1));
        assert!(matches!(out[1], Segment::GestureEnd { id: 1, .. }));
        assert_eq!(out[2], Segment::GestureBegin(2));
        out.clear();
        // A finger joining mid-gesture, far from the first but within a hand span.
        out = run(&mut seg, &[(450, 3, 250.0, 180.0, D)], off);
        assert!(out.is_empty(), "{out:?}");
        assert_eq!(seg.gestures()[0].fingers.len(), 2);
    }

    #[test]
    fn every_touch_is_a_gesture_when_switched_on() {
        let mut seg = Segmenter::new(params());
        seg.set_all_touches_are_gestures(true);
        assert!(seg.all_touches_are_gestures());
        let out = run(
            &mut seg,
            &[(0, 1, 100.0, 100.0, D), (20, 2, 140.0, 100.0, D)],
            |_| true,
        );
        assert_eq!(out, vec![Segment::GestureBegin(1)]);
        assert!(seg.controls().is_empty());
        assert_eq!(seg.gestures()[0].fingers.len(), 2);
        // Switched off again, the next touch on the crowd is a control.
        seg.set_all_touches_are_gestures(false);
        let out = run(&mut seg, &[(40, 3, 600.0, 600.0, D)], |_| true);
        assert_eq!(out, vec![Segment::ControlBegin(1)]);
    }

    #[test]
    fn an_eleventh_finger_down_starts_a_new_gesture() {
        let mut seg = Segmenter::new(params());
        let steps: Vec<_> = (0..11u32)
            .map(|i| (i as u64 * 5, i + 1, 100.0 + 10.0 * i as f64, 100.0, D))
            .collect();
        let out = run(&mut seg, &steps, |_| false);
        assert_eq!(
            out,
            vec![Segment::GestureBegin(1), Segment::GestureBegin(2)]
        );
        assert_eq!(seg.gestures()[0].fingers.len(), MAX_FINGERS);
        assert_eq!(seg.gestures()[0].max_down, MAX_FINGERS as u32);
        assert_eq!(seg.gestures()[1].fingers.len(), 1);
    }

    #[test]
    fn a_gesture_takes_at_most_max_gesture_contacts_landings() {
        let mut seg = Segmenter::new(params());
        let mut steps = vec![(0, 100, 300.0, 100.0, D)];
        // One finger stays down; another taps repeatedly beside it.
        for k in 0..MAX_GESTURE_CONTACTS as u64 {
            steps.push((10 + 20 * k, 1 + k as u32, 320.0, 100.0, D));
            steps.push((20 + 20 * k, 1 + k as u32, 320.0, 100.0, U));
        }
        let out = run(&mut seg, &steps, |_| false);
        let begins = out
            .iter()
            .filter(|s| matches!(s, Segment::GestureBegin(_)))
            .count();
        assert_eq!(begins, 2);
        assert_eq!(seg.gestures()[0].fingers.len(), MAX_GESTURE_CONTACTS);
    }
}
