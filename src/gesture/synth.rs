//! A generator of human-like multi-touch gestures for the ten motion classes, the
//! gestures of the shipped library and of the separate test set (gesture-driven
//! section 4: every crowd motion is paired with gestures drawn for it).
//!
//! # What each class looks like (the convention of the shipped library)
//!
//! | class | hands × fingers | the gesture |
//! |---|---|---|
//! | translate | 1 × 1–5 | the hand moves `size` mm in one direction |
//! | twist | 1 × 2–5 | fingers on a circle of diameter `size` (at most the hand's reach) turn 60–200° about their centre |
//! | twist | 1 × 1 | one finger draws a circle (or spiral) arc of 180–330°, diameter `size` |
//! | contract | 1 × 2–5 | a thumb and the fingers opposite it, open `size` wide (at most the hand's reach), converge to 15–40 % of it |
//! | expand | 1 × 2–5 | the same, spreading from 15–40 % to open |
//! | join | 2 × 1–3 | hands `size` further apart than when close (side by side) move towards each other |
//! | split | 2 × 1–3 | hands starting close (side by side) move `size` apart (at least as far again) |
//! | split_then_translate | 2 × 1–3 | split, then both move on together (roughly across the split) |
//! | translate_then_join | 2 × 1–3 | both move together, then towards each other |
//! | twist_while_expanding | 1 × 2–5 | turning 90–270° while spreading (outward spiral) |
//! | twist_while_contracting | 1 × 2–5 | turning 90–270° while converging (inward spiral) |
//!
//! # Hands a person has
//!
//! The hands are an adult's (issue 28; docs/gestures.md, "The generators' hands"):
//! one hand's fingertips open at most as wide as a hand reaches with that many
//! fingers ([`HAND_SPAN_MM`], [`REACH_SHARE`], [`COMFORTABLE_STRETCH`]; the size
//! of the hand follows the style's finger spacing); a pinching hand is a thumb
//! opposite the other fingers, which splay when the hand opens and close only
//! until their tips touch ([`FINGERTIP_PITCH_MM`]); two hands are never closer
//! than side by side, a palm's breadth and a gap apart ([`HAND_BREADTH_MM`],
//! [`HANDS_GAP_MM`]); and each hand of a two-hand gesture holds one finger more
//! often than two or three. Before this, one hand's pinch opened up to 234 mm
//! with two fingers and two hands of one finger each came within 15 mm, so
//! nothing in the library told a join drawn with two index fingers from a pinch.
//!
//! # How a hand moves
//!
//! Each hand has a rest layout of fingers about its centre (on a circle for a
//! twist, a thumb opposite a row of fingers for the scaling classes, along a
//! slightly curved row otherwise). At motion
//! progress `u ∈ [0, 1]` (smoothstep-eased per phase, so speed rises and falls as a
//! person's does) finger `i` is at
//! `centre + Σ_phases (D_p e_p + bow_p) + R(θ(u)) (s(u) r_i + l(u) q_i)`, where
//! `q_i` is a pinching finger's offset within the row opposite the thumb (scaled by
//! `l(u) = max(s(u), tips touching)`, zero otherwise), `D_p` is a phase's
//! displacement, `bow_p` bends its path sideways by `bow · |D_p| · 4 e_p (1 − e_p)`,
//! `s` scales the layout linearly and `θ` turns it linearly. Then the whole gesture is
//! turned by `orientation_rad`, placed on the glass at `placement` (shifted and, if
//! it is larger than the glass, shrunk to fit inside a margin), and every sample gets
//! `jitter_mm` of noise (a slow per-finger wobble plus per-sample noise).
//!
//! # Timing
//!
//! Samples are taken at the device's frame times (`rate_hz`, ±3 % jitter). A
//! hand's fingers all land within `stagger_ms` (a second hand up to 80 ms after the
//! first), the motion starts 60–150 ms after the last landing, lasts `duration_s`,
//! and after a 20–120 ms hold a hand's fingers lift within `stagger_ms`; `early_lifts` fingers (never a hand's last) lift at 60–90 % of the motion.
//! A track's last sample is its lift: the position of the frame before, at the frame
//! time the finger was gone (as the decoders report an `UP`).

use crate::geom::Vec2;
use crate::gesture::library::MotionClass;
use crate::gesture::track::{GestureTracks, TouchTrack, TrackSample, MAX_GESTURE_FINGERS};
use crate::rng::SplitMix64;
use crate::vocab::{Contact, ContactFlags, ContactId, Micros, TouchFrame};
use std::f64::consts::PI;

/// Distance kept between a gesture and the glass's edge when placing it, mm.
pub const EDGE_MARGIN_MM: f64 = 10.0;

/// An adult hand's span, thumb tip to little-finger tip at full stretch with the
/// hand flat, mm: from a small to a large hand. Boyle, Boyle and Booker, "Pianist
/// hand spans: gender and ethnic differences and implications for piano playing"
/// (2015; 473 adult pianists): mean 1–5 span 201 mm for women and 226 mm for men,
/// adults' spans differing by up to about 127 mm; this range keeps the bulk of
/// both.
pub const HAND_SPAN_MM: (f64, f64) = (180.0, 240.0);

/// An adult hand's breadth across the palm (at the knuckles), mm, for the same
/// small to large hand: British adults aged 19–65, 5th percentile of women to 95th
/// of men (City University of Hong Kong's online anthropometry, item 29 "Hand
/// breadth": women 70–85 mm, men 80–95 mm). Two hands side by side have their centres at
/// least this far apart.
pub const HAND_BREADTH_MM: (f64, f64) = (70.0, 95.0);

/// The share of a hand's span (thumb to little finger, [`HAND_SPAN_MM`]) that the
/// thumb and the farthest of `n` fingertips can reach, `n` = 2..=5 (index 0 is
/// one finger, which spans nothing). The 1–5 span is the widest a hand opens;
/// thumb to index (2), middle (3) and ring finger (4) open less. The shares are
/// this generator's own assumption, not a measurement.
pub const REACH_SHARE: [f64; 5] = [0.0, 0.8, 0.85, 0.9, 1.0];

// More fingers reach further, up to the whole span.
const _: () = assert!(
    REACH_SHARE[1] < REACH_SHARE[2]
        && REACH_SHARE[2] < REACH_SHARE[3]
        && REACH_SHARE[3] < REACH_SHARE[4]
        && REACH_SHARE[4] == 1.0
);

/// How much of its full stretch a hand uses when it opens for a gesture: nobody
/// pinches from a painful stretch.
pub const COMFORTABLE_STRETCH: f64 = 0.9;

/// The least distance between the touch points of two fingers side by side (not
/// the thumb) when a pinch has closed them together, mm: fingertips cannot
/// overlap, so they close onto each other's side, the lower end of the library's
/// resting finger spacing (15–25 mm, `StyleRanges::spacing_mm`).
pub const FINGERTIP_PITCH_MM: f64 = 15.0;

/// Extra room between two hands side by side beyond their breadth, mm.
pub const HANDS_GAP_MM: (f64, f64) = (0.0, 40.0);

/// The drawing hand's size, from the style's finger spacing: wider-spaced
/// fingertips belong to a larger hand, so spacing 15–25 mm (the library's range;
/// beyond it clamped) maps onto the small-to-large ranges of [`HAND_SPAN_MM`] and
/// [`HAND_BREADTH_MM`].
#[derive(Copy, Clone, Debug, PartialEq)]
struct HandSize {
    /// Thumb tip to little-finger tip at full stretch, mm.
    span_mm: f64,
    /// Across the palm, mm.
    breadth_mm: f64,
}

impl HandSize {
    fn of(style: &GestureStyle) -> HandSize {
        let f = ((style.spacing_mm - 15.0) / 10.0).clamp(0.0, 1.0);
        let lerp = |(a, b): (f64, f64)| a + (b - a) * f;
        HandSize {
            span_mm: lerp(HAND_SPAN_MM),
            breadth_mm: lerp(HAND_BREADTH_MM),
        }
    }

    /// The widest `n` fingertips of this hand comfortably open, tip to tip, mm.
    fn reach_mm(&self, n: usize) -> f64 {
        let share = REACH_SHARE[n.clamp(1, 5) - 1];
        COMFORTABLE_STRETCH * share * self.span_mm
    }
}

/// The style of one gesture: how a particular person draws it on a particular table.
#[derive(Clone, Debug, PartialEq)]
pub struct GestureStyle {
    /// Fingers of each hand (one entry per hand; two hands for join, split and their
    /// combinations), 1..=5 each.
    pub fingers: Vec<usize>,
    /// Motion duration, s (0.3–2.5 for people).
    pub duration_s: f64,
    /// The gesture's size, mm (20–250): travel, diameter or hand distance (module doc).
    pub size_mm: f64,
    /// Where the gesture's centre goes, as a fraction of the glass (`[0, 1]²`).
    pub placement: Vec2,
    /// Turn of the whole gesture on the glass, rad.
    pub orientation_rad: f64,
    /// Amplitude of the hand's tremor and the sensor's noise, mm.
    pub jitter_mm: f64,
    /// The glass, width × height, mm.
    pub device_mm: (f64, f64),
    /// The device's frame rate, Hz (60–240).
    pub rate_hz: f64,
    /// Longest delay between fingers of a hand landing, and lifting, ms (0–120).
    pub stagger_ms: f64,
    /// Fingers that lift before the motion ends.
    pub early_lifts: usize,
    /// Sideways bend of straight paths, as a fraction of their length (signed).
    pub bow: f64,
    /// Distance between neighbouring fingers of a hand at rest, mm.
    pub spacing_mm: f64,
    /// Turning direction of twists: `true` turns +x towards +y (clockwise on the glass).
    pub clockwise: bool,
}

/// The ranges [`GestureStyle::random`] draws from; a test set uses other ranges.
#[derive(Clone, Debug, PartialEq)]
pub struct StyleRanges {
    /// Fingers per hand, inclusive (clamped to what the class allows).
    pub fingers: (usize, usize),
    /// Motion duration, s.
    pub duration_s: (f64, f64),
    /// Size, mm.
    pub size_mm: (f64, f64),
    /// Jitter, mm.
    pub jitter_mm: (f64, f64),
    /// Frame rates, Hz.
    pub rate_hz: (f64, f64),
    /// Stagger, ms.
    pub stagger_ms: (f64, f64),
    /// Chance that a hand of two or more fingers lifts one early.
    pub early_lift_chance: f64,
    /// Largest `|bow|`.
    pub bow: f64,
    /// Finger spacing, mm.
    pub spacing_mm: (f64, f64),
    /// Devices to draw on (width × height, mm); one is picked.
    pub devices_mm: Vec<(f64, f64)>,
}

impl Default for StyleRanges {
    /// The shipped library's ranges: a 55″ and a 40″ table and a 27″ screen.
    fn default() -> StyleRanges {
        StyleRanges {
            fingers: (1, 5),
            duration_s: (0.3, 2.5),
            size_mm: (20.0, 250.0),
            jitter_mm: (0.1, 1.0),
            rate_hz: (60.0, 240.0),
            stagger_ms: (0.0, 120.0),
            early_lift_chance: 0.2,
            bow: 0.15,
            spacing_mm: (15.0, 25.0),
            devices_mm: vec![(1210.0, 680.0), (885.0, 498.0), (598.0, 336.0)],
        }
    }
}

impl StyleRanges {
    /// The ranges of the separate test set (`crowdtouch library test-set`): other
    /// devices than the library's (a 65″ and a 32″ table, a 13″ tablet), longer and
    /// larger gestures, more jitter, other rates, more stagger and early lifts.
    pub fn test_set() -> StyleRanges {
        StyleRanges {
            fingers: (1, 5),
            duration_s: (0.4, 3.0),
            size_mm: (30.0, 300.0),
            jitter_mm: (0.2, 1.5),
            rate_hz: (50.0, 200.0),
            stagger_ms: (0.0, 150.0),
            early_lift_chance: 0.3,
            bow: 0.2,
            spacing_mm: (13.0, 28.0),
            devices_mm: vec![(1430.0, 804.0), (698.0, 393.0), (286.0, 179.0)],
        }
    }
}

/// The fingers per hand a class allows, and its hand count.
fn class_hands(class: MotionClass) -> (usize, (usize, usize)) {
    match class {
        MotionClass::Translate | MotionClass::Twist => (1, (1, 5)),
        MotionClass::Contract
        | MotionClass::Expand
        | MotionClass::TwistWhileExpanding
        | MotionClass::TwistWhileContracting => (1, (2, 5)),
        MotionClass::Join
        | MotionClass::Split
        | MotionClass::SplitThenTranslate
        | MotionClass::TranslateThenJoin => (2, (1, 3)),
    }
}

fn pick(rng: &mut SplitMix64, (lo, hi): (f64, f64)) -> f64 {
    if hi > lo {
        rng.uniform(lo, hi)
    } else {
        lo
    }
}

fn pick_count(rng: &mut SplitMix64, lo: usize, hi: usize) -> usize {
    lo + (rng.next_u64() % (hi.saturating_sub(lo) as u64 + 1)) as usize
}

/// A finger count in `lo..=hi` with chance proportional to `1 / n`: a hand of a
/// two-hand gesture is most often one pointing finger (with 1–3 fingers: one
/// finger 6 times in 11, two 3 in 11, three 2 in 11, so both hands draw with one
/// finger in about 30 % of joins and splits). A join drawn with both index fingers
/// is the commonest way to bring two hands together, and the one a two-finger
/// pinch must be told from (docs/gestures.md, Accuracy): a library that rarely
/// holds it cannot tell them apart.
fn pick_count_favouring_few(rng: &mut SplitMix64, lo: usize, hi: usize) -> usize {
    let (lo, hi) = (lo.max(1), hi.max(lo.max(1)));
    let total: f64 = (lo..=hi).map(|n| 1.0 / n as f64).sum();
    let mut x = rng.uniform(0.0, total);
    for n in lo..=hi {
        x -= 1.0 / n as f64;
        if x < 0.0 {
            return n;
        }
    }
    hi
}

impl GestureStyle {
    /// A style for `class` drawn from `ranges`, the same for the same seed.
    pub fn random(class: MotionClass, seed: u64, ranges: &StyleRanges) -> GestureStyle {
        let mut rng = SplitMix64::new(seed ^ 0x5757_1e5e_ed00_0000);
        let (hands, (lo, hi)) = class_hands(class);
        let (lo, hi) = (
            ranges.fingers.0.clamp(lo, hi),
            ranges.fingers.1.clamp(lo, hi),
        );
        let fingers: Vec<usize> = (0..hands)
            .map(|_| {
                if hands == 2 {
                    pick_count_favouring_few(&mut rng, lo, hi.max(lo))
                } else {
                    pick_count(&mut rng, lo, hi.max(lo))
                }
            })
            .collect();
        let device_mm = if ranges.devices_mm.is_empty() {
            (1210.0, 680.0)
        } else {
            ranges.devices_mm[(rng.next_u64() % ranges.devices_mm.len() as u64) as usize]
        };
        let early_lifts = fingers
            .iter()
            .filter(|&&n| n >= 2 && rng.unit() < ranges.early_lift_chance)
            .count();
        GestureStyle {
            duration_s: pick(&mut rng, ranges.duration_s),
            size_mm: pick(&mut rng, ranges.size_mm),
            placement: Vec2::new(rng.uniform(0.2, 0.8), rng.uniform(0.2, 0.8)),
            orientation_rad: rng.uniform(-PI, PI),
            jitter_mm: pick(&mut rng, ranges.jitter_mm),
            device_mm,
            rate_hz: pick(&mut rng, ranges.rate_hz),
            stagger_ms: pick(&mut rng, ranges.stagger_ms),
            early_lifts,
            bow: rng.uniform(-ranges.bow, ranges.bow),
            spacing_mm: pick(&mut rng, ranges.spacing_mm),
            clockwise: rng.unit() < 0.5,
            fingers,
        }
    }
}

/// Smoothstep: 0 → 0, 1 → 1, zero slope at both ends.
fn ease(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

fn rot(v: Vec2, a: f64) -> Vec2 {
    let (s, c) = a.sin_cos();
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

fn unit(a: f64) -> Vec2 {
    Vec2::new(a.cos(), a.sin())
}

/// One straight (or bowed) stretch of a hand's path over part of the motion.
#[derive(Clone, Debug)]
struct Phase {
    /// Progress window `[from, to]` of the motion.
    from: f64,
    to: f64,
    /// Displacement, mm.
    d: Vec2,
    /// Sideways bend as a fraction of `|d|`.
    bow: f64,
}

/// One hand: its rest layout and what it does.
#[derive(Clone, Debug)]
struct Hand {
    centre: Vec2,
    /// Finger offsets at rest, mm.
    layout: Vec<Vec2>,
    phases: Vec<Phase>,
    /// Total turn, rad.
    turn: f64,
    /// Layout scale at the start and end.
    scale: (f64, f64),
    /// Per finger, an offset within its group of fingers (the fingers opposite a
    /// pinching thumb), added to `layout`; zero for other hands.
    local: Vec<Vec2>,
    /// The scale of `local` at the start and end: fingers side by side close only
    /// until their tips touch ([`FINGERTIP_PITCH_MM`]).
    local_scale: (f64, f64),
}

impl Hand {
    fn at(&self, i: usize, u: f64) -> Vec2 {
        let mut c = self.centre;
        for p in &self.phases {
            let e = ease((u - p.from) / (p.to - p.from));
            let side = Vec2::new(-p.d.y, p.d.x);
            c += p.d * e + side * (p.bow * 4.0 * e * (1.0 - e));
        }
        let u = u.clamp(0.0, 1.0);
        let s = self.scale.0 + (self.scale.1 - self.scale.0) * u;
        let ls = self.local_scale.0 + (self.local_scale.1 - self.local_scale.0) * u;
        let local = self.local.get(i).copied().unwrap_or_else(Vec2::zeros);
        c + rot(self.layout[i] * s + local * ls, self.turn * u)
    }
}

/// Fingers on a circle of `radius`, a little irregular.
fn ring(rng: &mut SplitMix64, n: usize, radius: f64) -> Vec<Vec2> {
    if n == 1 {
        return vec![Vec2::zeros()];
    }
    let a0 = rng.uniform(0.0, 2.0 * PI);
    (0..n)
        .map(|i| {
            let a = a0 + 2.0 * PI * i as f64 / n as f64 + rng.uniform(-0.25, 0.25) * PI / n as f64;
            unit(a) * radius * rng.uniform(0.85, 1.15)
        })
        .collect()
}

/// Scales `layout` about its centroid so that no two fingertips are more than
/// `max_mm` apart (a hand cannot open wider), leaving a narrower one as it is.
fn within_reach(layout: Vec<Vec2>, max_mm: f64) -> Vec<Vec2> {
    let widest = widest_mm(&layout);
    if widest <= max_mm || widest <= 0.0 {
        return layout;
    }
    let c = layout.iter().sum::<Vec2>() / layout.len() as f64;
    layout
        .into_iter()
        .map(|p| c + (p - c) * (max_mm / widest))
        .collect()
}

/// The largest distance between two of `points`, mm (0 for fewer than two).
fn widest_mm(points: &[Vec2]) -> f64 {
    let mut widest = 0.0f64;
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            widest = widest.max((a - b).norm());
        }
    }
    widest
}

/// A pinching hand, open: where each fingertip's group sits (the thumb alone; the
/// other fingers together) and each fingertip's offset within its group, mm about
/// the hand's centroid.
struct Pinch {
    groups: Vec<Vec2>,
    local: Vec<Vec2>,
    /// The fingers' spacing side by side, open, mm.
    open_pitch_mm: f64,
}

/// A pinching hand of `n` fingertips open `span_mm` wide (thumb to the farthest
/// fingertip): the thumb on one side, the other fingertips in a slightly curved
/// row on the other, facing it. The thumb opposes the fingers: a pinch closes the
/// thumb and the fingers onto each other, so a four- or five-finger pinch is two
/// groups converging (the thumb alone, the fingers together), not fingers evenly
/// round a circle. A hand opened wide also splays its fingers: adjacent fingers
/// abduct up to 14–32° from each other (Chatzioglou, Pınar and Govsa, "Biometric
/// analysis hand parameters in young adults…", Anat Cell Biol 57(2), 2024: index–
/// middle 17°, middle–ring 14°, ring–little 32° at maximum abduction; fingers
/// 53–71 mm long), which puts fingertips about twice their resting spacing apart
/// at full stretch; so the row's pitch is `spacing` times 1 plus the share of the
/// full span (`full_span_mm`) the hand is open.
fn pinch_hand(
    rng: &mut SplitMix64,
    n: usize,
    span_mm: f64,
    full_span_mm: f64,
    spacing: f64,
) -> Pinch {
    if n <= 1 {
        return Pinch {
            groups: vec![Vec2::zeros()],
            local: vec![Vec2::zeros()],
            open_pitch_mm: spacing,
        };
    }
    let fingers = n - 1;
    // Splayed, but the row stays within the span (its ends 80 % of it apart at
    // most), so the thumb still faces it.
    let pitch = (spacing * (1.0 + (span_mm / full_span_mm.max(1.0)).clamp(0.0, 1.0)))
        .min(0.8 * span_mm / (fingers as f64 - 1.0).max(1.0));
    let half_row = (fingers as f64 - 1.0) / 2.0 * pitch;
    // The farthest fingertip (a row's end) is `span_mm` from the thumb.
    let across = (span_mm * span_mm - half_row * half_row)
        .max((0.3 * span_mm).powi(2))
        .sqrt();
    let thumb = Vec2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0));
    // The row turned a quarter to run along y, its middle bowed away from the
    // thumb (the middle finger reaches furthest).
    let row: Vec<Vec2> = row(rng, fingers, pitch, 0.0)
        .into_iter()
        .map(|p| rot(p, PI / 2.0))
        .collect();
    let c = (thumb + Vec2::new(across, 0.0) * fingers as f64) / n as f64;
    let mut groups = vec![thumb - c];
    let mut local = vec![Vec2::zeros()];
    for p in row {
        groups.push(Vec2::new(across, 0.0) - c);
        local.push(p);
    }
    // The row's curve and irregularity can put a tip past `span_mm`: the hand is
    // shrunk as a whole to keep within it.
    let tips: Vec<Vec2> = groups.iter().zip(&local).map(|(g, l)| g + l).collect();
    let widest = widest_mm(&tips);
    let shrink = if widest > span_mm {
        span_mm / widest
    } else {
        1.0
    };
    Pinch {
        groups: groups.into_iter().map(|g| g * shrink).collect(),
        local: local.into_iter().map(|l| l * shrink).collect(),
        open_pitch_mm: pitch * shrink,
    }
}

/// Fingers along a slightly curved row across direction `across` (rad), `spacing` apart.
fn row(rng: &mut SplitMix64, n: usize, spacing: f64, across: f64) -> Vec<Vec2> {
    let mid = (n as f64 - 1.0) / 2.0;
    let pts: Vec<Vec2> = (0..n)
        .map(|i| {
            let k = i as f64 - mid;
            let p = Vec2::new(k * spacing, -0.15 * k * k * spacing)
                + Vec2::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0));
            rot(p, across)
        })
        .collect();
    let c = pts.iter().sum::<Vec2>() / n as f64;
    pts.into_iter().map(|p| p - c).collect()
}

fn one_phase(d: Vec2, bow: f64) -> Vec<Phase> {
    vec![Phase {
        from: 0.0,
        to: 1.0,
        d,
        bow,
    }]
}

/// The hands of `class` in the gesture's own frame (centre near the origin, main
/// axis along +x).
fn hands(class: MotionClass, style: &GestureStyle, rng: &mut SplitMix64) -> Vec<Hand> {
    let size = style.size_mm.max(1.0);
    let sign = if style.clockwise { 1.0 } else { -1.0 };
    let n0 = style.fingers.first().copied().unwrap_or(1).clamp(1, 5);
    let spacing = style.spacing_mm.max(1.0);
    let hand = HandSize::of(style);
    // The widest the fingers of this one hand open (anatomy, not the style's size:
    // a one-hand gesture larger than that cannot be drawn by one hand).
    let reach = hand.reach_mm(n0);
    // The least a pinching hand opens: 40 mm, and with three or more fingers the
    // row opposite the thumb at rest and a tenth more (five fingertips do not fit
    // in 40 mm; a hand that cannot open past its own fingers cannot pinch).
    let least_open = (1.1 * n0.saturating_sub(2) as f64 * spacing).max(40.0);
    let single = |layout: Vec<Vec2>, phases: Vec<Phase>, turn: f64, scale: (f64, f64)| {
        vec![Hand {
            centre: Vec2::zeros(),
            local: vec![Vec2::zeros(); layout.len()],
            layout,
            phases,
            turn,
            scale,
            local_scale: (1.0, 1.0),
        }]
    };
    // A pinching hand opening or closing between `scale.0` and `scale.1` of its
    // open size: the thumb and the fingers' group converge by the full scale; the
    // fingers side by side only until their tips touch.
    let pinching = |pinch: Pinch, phases: Vec<Phase>, turn: f64, scale: (f64, f64)| {
        let least = (FINGERTIP_PITCH_MM / pinch.open_pitch_mm.max(1e-9)).min(1.0);
        vec![Hand {
            centre: Vec2::zeros(),
            layout: pinch.groups,
            local: pinch.local,
            phases,
            turn,
            scale,
            local_scale: (scale.0.max(least), scale.1.max(least)),
        }]
    };
    match class {
        MotionClass::Translate => {
            let across = PI / 2.0 + rng.uniform(-0.4, 0.4);
            let layout = row(rng, n0, spacing, across);
            single(
                layout,
                one_phase(Vec2::new(size, 0.0), style.bow),
                0.0,
                (1.0, 1.0),
            )
        }
        MotionClass::Twist if n0 == 1 => {
            // One finger on an arc (or a mild spiral) about a centre `size / 2` away.
            let r = (size / 2.0).max(10.0);
            let arc = sign * rng.uniform(180.0, 330.0).to_radians();
            let spiral = rng.uniform(0.85, 1.15);
            single(vec![Vec2::new(r, 0.0)], Vec::new(), arc, (1.0, spiral))
        }
        MotionClass::Twist => {
            // Fingertips round a knob, as wide as the hand opens.
            let r = (size / 2.0).clamp(15.0, 90.0);
            let turn = sign * rng.uniform(60.0, 200.0).to_radians();
            let layout = within_reach(ring(rng, n0, r), reach);
            single(layout, Vec::new(), turn, (1.0, 1.0))
        }
        MotionClass::Contract | MotionClass::Expand => {
            // Open `size` wide, but no wider than this hand's `n0` fingers reach.
            let open = size.clamp(least_open, reach.max(least_open));
            let r = open / 2.0;
            let small = rng.uniform(0.15, 0.4);
            let scale = if class == MotionClass::Contract {
                (1.0, small)
            } else {
                (small, 1.0)
            };
            let drift = unit(rng.uniform(0.0, 2.0 * PI)) * rng.uniform(0.0, 0.1) * r;
            let pinch = pinch_hand(rng, n0, open, hand.span_mm, spacing);
            pinching(pinch, one_phase(drift, 0.0), 0.0, scale)
        }
        MotionClass::TwistWhileExpanding | MotionClass::TwistWhileContracting => {
            let open = size.clamp(least_open, reach.max(least_open));
            let small = rng.uniform(0.2, 0.45);
            let scale = if class == MotionClass::TwistWhileContracting {
                (1.0, small)
            } else {
                (small, 1.0)
            };
            let turn = sign * rng.uniform(90.0, 270.0).to_radians();
            let pinch = pinch_hand(rng, n0, open, hand.span_mm, spacing);
            pinching(pinch, Vec::new(), turn, scale)
        }
        MotionClass::Join
        | MotionClass::Split
        | MotionClass::SplitThenTranslate
        | MotionClass::TranslateThenJoin => two_hands(class, style, rng),
    }
}

fn two_hands(class: MotionClass, style: &GestureStyle, rng: &mut SplitMix64) -> Vec<Hand> {
    let spacing = style.spacing_mm.max(1.0);
    let counts: Vec<usize> = (0..2)
        .map(|h| style.fingers.get(h).copied().unwrap_or(1).clamp(1, 5))
        .collect();
    let layouts: Vec<Vec<Vec2>> = counts
        .iter()
        .map(|&n| {
            let across = PI / 2.0 + rng.uniform(-0.3, 0.3);
            row(rng, n, spacing, across)
        })
        .collect();
    let half_width = |l: &Vec<Vec2>| l.iter().map(|p| p.norm()).fold(0.0, f64::max);
    // Hands close: side by side, palm beside palm, their centres at least a hand's
    // breadth apart (two hands cannot overlap; whatever fingers they hold down).
    let breadth = HandSize::of(style).breadth_mm;
    let close = (breadth + rng.uniform(HANDS_GAP_MM.0, HANDS_GAP_MM.1))
        .max(half_width(&layouts[0]) + half_width(&layouts[1]) + 15.0);
    // The hands travel `size`, and at least as far as they are apart when close.
    let far = close + style.size_mm.max(close);
    let (start, end) = match class {
        MotionClass::Join | MotionClass::TranslateThenJoin => (far, close),
        _ => (close, far),
    };
    // Split then translate moves roughly across the split axis; translate then join
    // likewise.
    let travel =
        unit(PI / 2.0 + rng.uniform(-0.5, 0.5)) * style.size_mm.max(20.0) * rng.uniform(0.6, 1.0);
    let mut hands = Vec::with_capacity(2);
    for (h, layout) in layouts.into_iter().enumerate() {
        let side = if h == 0 { -1.0 } else { 1.0 };
        let apart = Vec2::new(side * (end - start) / 2.0, 0.0);
        let bow = style.bow * if h == 0 { 1.0 } else { -1.0 };
        let phases = match class {
            MotionClass::SplitThenTranslate => vec![
                Phase {
                    from: 0.0,
                    to: 0.5,
                    d: apart,
                    bow,
                },
                Phase {
                    from: 0.5,
                    to: 1.0,
                    d: travel,
                    bow: style.bow,
                },
            ],
            MotionClass::TranslateThenJoin => vec![
                Phase {
                    from: 0.0,
                    to: 0.5,
                    d: travel,
                    bow: style.bow,
                },
                Phase {
                    from: 0.5,
                    to: 1.0,
                    d: apart,
                    bow,
                },
            ],
            _ => one_phase(apart, bow),
        };
        hands.push(Hand {
            centre: Vec2::new(side * start / 2.0, 0.0),
            local: vec![Vec2::zeros(); layout.len()],
            local_scale: (1.0, 1.0),
            layout,
            phases,
            turn: 0.0,
            scale: (1.0, 1.0),
        });
    }
    hands
}

/// A generated gesture with each finger's hand (for tests and the library build's
/// checks).
#[derive(Clone, Debug, PartialEq)]
pub struct Generated {
    /// The fingers' tracks, in landing order, times from `Micros(0)`.
    pub tracks: GestureTracks,
    /// The hand (0 or 1) of each track.
    pub hand: Vec<usize>,
    /// When the motion starts and ends (µs from the first landing); fingers are
    /// still before and after.
    pub motion_us: (u64, u64),
}

/// Generates a gesture of `class` in `style`, the same for the same seed.
///
/// Times start at `Micros(0)` when the first finger lands; positions are mm of the
/// glass `style.device_mm`, inside it.
pub fn generate(class: MotionClass, style: &GestureStyle, seed: u64) -> GestureTracks {
    generate_detailed(class, style, seed).tracks
}

/// [`generate`], with each finger's hand and the motion's time span.
pub fn generate_detailed(class: MotionClass, style: &GestureStyle, seed: u64) -> Generated {
    let mut rng = SplitMix64::new(seed);
    let hands = hands(class, style, &mut rng);
    let period_us = 1e6 / style.rate_hz.clamp(10.0, 1000.0);
    let stagger_us = style.stagger_ms.clamp(0.0, 1000.0) * 1e3;
    let duration_us = style.duration_s.clamp(0.05, 60.0) * 1e6;
    // Schedules: (hand, finger in hand, land µs, lift µs, early lift progress).
    struct Sched {
        hand: usize,
        index: usize,
        land: f64,
        lift: f64,
        wobble: (Vec2, f64, f64),
    }
    let mut scheds = Vec::new();
    let mut motion_start = 0.0f64;
    let hand_start: Vec<f64> = (0..hands.len())
        .map(|h| if h == 0 { 0.0 } else { rng.uniform(0.0, 80e3) })
        .collect();
    for (h, hand) in hands.iter().enumerate() {
        let mut land = hand_start[h];
        for i in 0..hand.layout.len() {
            if i > 0 {
                land += rng.uniform(0.0, stagger_us / (hand.layout.len() - 1) as f64);
            }
            scheds.push(Sched {
                hand: h,
                index: i,
                land,
                lift: 0.0,
                wobble: (
                    unit(rng.uniform(0.0, 2.0 * PI)),
                    rng.uniform(1.0, 3.0),
                    rng.uniform(0.0, 2.0 * PI),
                ),
            });
            motion_start = motion_start.max(land);
        }
    }
    motion_start += rng.uniform(60e3, 150e3);
    let motion_end = motion_start + duration_us;
    let hold = rng.uniform(20e3, 120e3);
    let mut early_left = style.early_lifts;
    for h in 0..hands.len() {
        let idx: Vec<usize> = (0..scheds.len()).filter(|&j| scheds[j].hand == h).collect();
        let mut lift = motion_end + hold;
        for (k, &j) in idx.iter().enumerate() {
            if k > 0 {
                lift += rng.uniform(0.0, stagger_us / (idx.len() - 1) as f64);
            }
            scheds[j].lift = lift;
        }
        // Early lifts: never the hand's first (last to stay) finger.
        for &j in idx.iter().skip(1) {
            if early_left == 0 {
                break;
            }
            scheds[j].lift = motion_start + duration_us * rng.uniform(0.6, 0.9);
            early_left -= 1;
        }
    }
    // Noise-free positions on the frame grid, in the gesture's frame.
    let last_lift = scheds.iter().map(|s| s.lift).fold(0.0, f64::max);
    let mut times = Vec::new();
    let mut k = 0u64;
    loop {
        let t = if k == 0 {
            0.0
        } else {
            (k as f64 + rng.uniform(-0.03, 0.03)) * period_us
        };
        let t = t.round();
        times.push(t);
        if t >= last_lift {
            break;
        }
        k += 1;
    }
    let orient = style.orientation_rad;
    let mut raw: Vec<Vec<(f64, Vec2)>> = Vec::with_capacity(scheds.len());
    for s in &scheds {
        let mut samples = Vec::new();
        for &t in &times {
            if t < s.land {
                continue;
            }
            let u = (t - motion_start) / duration_us;
            if t >= s.lift {
                // The lift: the previous position, at the first frame without it.
                let prev = samples
                    .last()
                    .map(|&(_, p)| p)
                    .unwrap_or_else(|| rot(hands[s.hand].at(s.index, u), orient));
                samples.push((t, prev));
                break;
            }
            samples.push((t, rot(hands[s.hand].at(s.index, u), orient)));
        }
        raw.push(samples);
    }
    // Place on the glass: shrink to fit inside the margin, then shift.
    let (w, h) = (
        style.device_mm.0.max(2.0 * EDGE_MARGIN_MM + 1.0),
        style.device_mm.1.max(2.0 * EDGE_MARGIN_MM + 1.0),
    );
    let pad = 3.0 * style.jitter_mm.abs();
    let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
    for p in raw.iter().flatten().map(|s| s.1) {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    let avail = Vec2::new(
        w - 2.0 * (EDGE_MARGIN_MM + pad),
        h - 2.0 * (EDGE_MARGIN_MM + pad),
    )
    .map(|v| v.max(1.0));
    let ext = (hi - lo).map(|v| v.max(1e-9));
    let shrink = (avail.x / ext.x).min(avail.y / ext.y).min(1.0);
    let mid = (lo + hi) / 2.0;
    let half = ext * shrink / 2.0;
    let inside = |v: f64, len: f64, half: f64| {
        let (lo, hi) = (
            EDGE_MARGIN_MM + pad + half,
            len - EDGE_MARGIN_MM - pad - half,
        );
        if lo < hi {
            v.clamp(lo, hi)
        } else {
            len / 2.0
        }
    };
    let place = Vec2::new(
        inside(style.placement.x.clamp(0.0, 1.0) * w, w, half.x),
        inside(style.placement.y.clamp(0.0, 1.0) * h, h, half.y),
    );
    let jitter = style.jitter_mm.abs();
    let mut order: Vec<usize> = (0..scheds.len()).collect();
    order.sort_by(|&a, &b| scheds[a].land.total_cmp(&scheds[b].land));
    let mut fingers = Vec::with_capacity(order.len());
    let mut hand = Vec::with_capacity(order.len());
    for &j in &order {
        let (dir, freq, phase) = scheds[j].wobble;
        let mut samples: Vec<TrackSample> = Vec::with_capacity(raw[j].len());
        let n = raw[j].len();
        for (k, &(t, p)) in raw[j].iter().enumerate() {
            let mm = if k + 1 == n && k > 0 {
                // The lift repeats the last reported position exactly.
                samples[k - 1].mm
            } else {
                let wob = dir * (0.5 * jitter * (2.0 * PI * freq * t * 1e-6 + phase).sin());
                let noise = Vec2::new(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)) * jitter;
                let q = place + (p - mid) * shrink + wob + noise;
                Vec2::new(q.x.clamp(0.0, w), q.y.clamp(0.0, h))
            };
            samples.push(TrackSample {
                t: Micros(t as u64),
                mm,
            });
        }
        fingers.push(TouchTrack { samples });
        hand.push(scheds[j].hand);
    }
    debug_assert!(fingers.len() <= 2 * 5 && fingers.len() <= MAX_GESTURE_FINGERS);
    Generated {
        tracks: GestureTracks { fingers },
        hand,
        motion_us: (motion_start as u64, motion_end as u64),
    }
}

/// Turns tracks into the touch frames a decoder would emit for them on a glass of
/// `device_mm` (width × height, mm), times shifted by `t0`.
///
/// Every distinct sample time is a frame holding every finger that is down: its
/// first sample carries [`ContactFlags::DOWN`], its last [`ContactFlags::UP`] (both
/// for a one-sample track), and a finger with no sample at a frame's time is
/// reported at its latest position. Contact ids are `1 + track index`. Positions are
/// `mm / device_mm`, clamped to `[0, 1]`. Tracks sampled on one clock, as
/// [`generate`] makes them, come back from the frames unchanged (within f32).
pub fn to_frames(tracks: &GestureTracks, device_mm: (f64, f64), t0: Micros) -> Vec<TouchFrame> {
    let (w, h) = (device_mm.0.max(1e-9), device_mm.1.max(1e-9));
    let mut times: Vec<Micros> = tracks
        .fingers
        .iter()
        .flat_map(|f| f.samples.iter().map(|s| s.t))
        .collect();
    times.sort_unstable();
    times.dedup();
    let mut next = vec![0usize; tracks.fingers.len()];
    let mut frames = Vec::with_capacity(times.len());
    for &t in &times {
        let mut frame = TouchFrame::new(t0 + t);
        for (j, f) in tracks.fingers.iter().enumerate() {
            let s = &f.samples;
            let (Some(first), Some(last)) = (s.first(), s.last()) else {
                continue;
            };
            if t < first.t || t > last.t {
                continue;
            }
            while next[j] + 1 < s.len() && s[next[j] + 1].t <= t {
                next[j] += 1;
            }
            let k = next[j];
            let mut flags = ContactFlags::NONE;
            if t == first.t {
                flags.insert(ContactFlags::DOWN);
            }
            if t == last.t {
                flags.insert(ContactFlags::UP);
            }
            let c = Contact {
                id: ContactId(j as u32 + 1),
                x: (s[k].mm.x / w).clamp(0.0, 1.0) as f32,
                y: (s[k].mm.y / h).clamp(0.0, 1.0) as f32,
                flags,
                ..Contact::default()
            };
            // A gesture has at most ten fingers; tracks beyond the frame's
            // MAX_CONTACTS are left out.
            let _ = frame.push(c);
        }
        frames.push(frame);
    }
    frames
}

#[cfg(test)]
#[path = "synth_tests.rs"]
mod tests;
