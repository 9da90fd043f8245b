//! A generator of human-like multi-touch gestures for the ten motion classes, the
//! gestures of the shipped library and of the separate test set (gesture-driven
//! section 4: every crowd motion is paired with gestures drawn for it).
//!
//! # What each class looks like (the convention of the shipped library)
//!
//! | class | hands × fingers | the gesture |
//! |---|---|---|
//! | translate | 1 × 1–5 | the hand moves `size` mm in one direction |
//! | twist | 1 × 2–5 | fingers on a circle of diameter `size` turn 60–200° about their centre |
//! | twist | 1 × 1 | one finger draws a circle (or spiral) arc of 180–330°, diameter `size` |
//! | contract | 1 × 2–5 | fingers converge from diameter `size` to 15–40 % of it |
//! | expand | 1 × 2–5 | fingers spread from 15–40 % of `size` to diameter `size` |
//! | join | 2 × 1–3 | hands `size` apart (at least twice their closest) move towards each other |
//! | split | 2 × 1–3 | hands starting close move `size` apart (at least as far again) |
//! | split_then_translate | 2 × 1–3 | split, then both move on together (roughly across the split) |
//! | translate_then_join | 2 × 1–3 | both move together, then towards each other |
//! | twist_while_expanding | 1 × 2–5 | turning 90–270° while spreading (outward spiral) |
//! | twist_while_contracting | 1 × 2–5 | turning 90–270° while converging (inward spiral) |
//!
//! # How a hand moves
//!
//! Each hand has a rest layout of fingers about its centre (on a circle for the
//! turning and scaling classes, along a slightly curved row otherwise). At motion
//! progress `u ∈ [0, 1]` (smoothstep-eased per phase, so speed rises and falls as a
//! person's does) finger `i` is at
//! `centre + Σ_phases (D_p e_p + bow_p) + s(u) R(θ(u)) r_i`, where `D_p` is a phase's
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
            .map(|_| pick_count(&mut rng, lo, hi.max(lo)))
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
        c + rot(self.layout[i], self.turn * u) * s
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
    let single = |layout: Vec<Vec2>, phases: Vec<Phase>, turn: f64, scale: (f64, f64)| {
        vec![Hand {
            centre: Vec2::zeros(),
            layout,
            phases,
            turn,
            scale,
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
            let r = (size / 2.0).clamp(15.0, 90.0);
            let turn = sign * rng.uniform(60.0, 200.0).to_radians();
            single(ring(rng, n0, r), Vec::new(), turn, (1.0, 1.0))
        }
        MotionClass::Contract | MotionClass::Expand => {
            let r = (size / 2.0).clamp(20.0, 110.0);
            let small = rng.uniform(0.15, 0.4);
            let scale = if class == MotionClass::Contract {
                (1.0, small)
            } else {
                (small, 1.0)
            };
            let drift = unit(rng.uniform(0.0, 2.0 * PI)) * rng.uniform(0.0, 0.1) * r;
            single(ring(rng, n0, r), one_phase(drift, 0.0), 0.0, scale)
        }
        MotionClass::TwistWhileExpanding | MotionClass::TwistWhileContracting => {
            let r = (size / 2.0).clamp(20.0, 110.0);
            let small = rng.uniform(0.2, 0.45);
            let scale = if class == MotionClass::TwistWhileContracting {
                (1.0, small)
            } else {
                (small, 1.0)
            };
            let turn = sign * rng.uniform(90.0, 270.0).to_radians();
            single(ring(rng, n0, r), Vec::new(), turn, scale)
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
    // Hands close: their centres this far apart.
    let close = half_width(&layouts[0]) + half_width(&layouts[1]) + rng.uniform(15.0, 35.0);
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
