//! What a person draws for each class (docs/gestures.md "The classes and what to
//! draw"), as hands in the gesture's own frame (mm, main axis along +x): each hand's
//! fingertips, the strokes its centre makes, how it turns and opens, and when.
//!
//! Conventions of motion, chosen to differ from `gesture::synth`:
//! - strokes are minimum-jerk, and a combined class's second stroke starts before
//!   the first has ended (people blend them);
//! - a pinch closes on the thumb, not on the fingers' centre (the anchor sits between
//!   the centroid and the thumb), and a hand turns about a pivot off its centre;
//! - every finger follows its hand with its own lag (0–90 ms) and share of the
//!   motion (85–105 %), and drifts slowly (under 1 Hz) while the others move;
//! - in two-hand classes one hand often does most of the moving, and the second
//!   hand starts late;
//! - one finger's twist is a curved path timed by the two-thirds power law, 0.5 to 2
//!   turns, its radius growing or shrinking (a spiral) or not (a circle).

use super::motor::{power_law_times, rot, unit, Stroke, Wobble};
use crate::geom::Vec2;
use crate::gesture::library::MotionClass;
use crate::rng::SplitMix64;
use std::f64::consts::{PI, TAU};

/// Which way the gesture should go (a library motion's heading; `None`: any).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Aim {
    /// Translate, and the common travel of split then translate and translate then
    /// join: the direction, rad (+x towards +y).
    pub direction_rad: Option<f64>,
    /// Join and split: the axis from one hand to the other, rad.
    pub axis_rad: Option<f64>,
    /// Twists: turning +x towards +y (clockwise on glass with y down).
    pub clockwise: Option<bool>,
}

/// One hand: fingertips about its origin and what it does over time.
#[derive(Clone, Debug)]
pub(super) struct Hand {
    /// Fingertips at rest about the hand's origin, mm.
    pub offsets: Vec<Vec2>,
    /// The origin's strokes (summed).
    pub strokes: Vec<Stroke>,
    /// Per finger: the share of the strokes it follows.
    pub follow: Vec<f64>,
    /// Per finger: how late it follows the hand, s.
    pub lag_s: Vec<f64>,
    /// Turn of the fingertips about `pivot`, rad, timed by `shape`.
    pub turn_rad: f64,
    /// The pivot, about the origin, mm.
    pub pivot: Vec2,
    /// Scale of the fingertips about `anchor`, from and to, timed by `shape`.
    pub scale: (f64, f64),
    /// The anchor of scaling, about the origin, mm.
    pub anchor: Vec2,
    /// Timing of turn and scale (its `d` is unused).
    pub shape: Stroke,
    /// Per finger: a slow drift.
    pub drift: Vec<Wobble>,
    /// One finger drawing a curve: its points and their times (s), instead of the
    /// above.
    pub curve: Option<(Vec<Vec2>, Vec<f64>)>,
    /// When the hand's motion starts and ends, s.
    pub motion_s: (f64, f64),
}

impl Hand {
    /// Finger `i` at `t_s`, mm in the gesture's frame.
    pub fn at(&self, i: usize, t_s: f64) -> Vec2 {
        let t = t_s - self.lag_s.get(i).copied().unwrap_or(0.0);
        let drift = self.drift.get(i).map_or(Vec2::zeros(), |w| w.at(t_s));
        if let Some((pts, times)) = &self.curve {
            let k = times.partition_point(|&x| x < t).min(pts.len() - 1);
            let p = if k == 0 {
                pts[0]
            } else {
                let (t0, t1) = (times[k - 1], times[k]);
                let a = if t1 > t0 {
                    ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                pts[k - 1] * (1.0 - a) + pts[k] * a
            };
            return p + drift;
        }
        let follow = self.follow.get(i).copied().unwrap_or(1.0);
        let origin: Vec2 = self.strokes.iter().map(|s| s.at(t)).sum::<Vec2>() * follow;
        let u = self.shape.progress(t);
        let s = self.scale.0 + (self.scale.1 - self.scale.0) * u;
        let local = self.anchor + (self.offsets[i] - self.anchor) * s;
        origin + self.pivot + rot(local - self.pivot, self.turn_rad * u) + drift
    }
}

/// The hands of one gesture.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    /// One or two hands.
    pub hands: Vec<Hand>,
}

/// Fingers per hand for `class`, drawn.
fn finger_count(class: MotionClass, rng: &mut SplitMix64) -> usize {
    let pick = |rng: &mut SplitMix64, weights: &[(usize, f64)]| {
        let total: f64 = weights.iter().map(|w| w.1).sum();
        let mut x = rng.uniform(0.0, total);
        for &(n, w) in weights {
            if x < w {
                return n;
            }
            x -= w;
        }
        weights[weights.len() - 1].0
    };
    match class {
        MotionClass::Translate => pick(rng, &[(1, 0.25), (2, 0.3), (3, 0.2), (4, 0.15), (5, 0.1)]),
        MotionClass::Twist => pick(rng, &[(1, 0.35), (2, 0.3), (3, 0.15), (4, 0.1), (5, 0.1)]),
        MotionClass::Contract
        | MotionClass::Expand
        | MotionClass::TwistWhileExpanding
        | MotionClass::TwistWhileContracting => {
            pick(rng, &[(2, 0.45), (3, 0.25), (4, 0.15), (5, 0.15)])
        }
        _ => pick(rng, &[(1, 0.5), (2, 0.35), (3, 0.15)]),
    }
}

/// Fingertips of one hand: `n` tips along an arc `spacing_mm` apart (no thumb).
fn row(rng: &mut SplitMix64, n: usize, spacing_mm: f64) -> Vec<Vec2> {
    let mid = (n as f64 - 1.0) / 2.0;
    let pts: Vec<Vec2> = (0..n)
        .map(|i| {
            let k = i as f64 - mid;
            // Middle fingers reach further: the tips lie on an arc.
            Vec2::new(-0.25 * k * k * spacing_mm, k * spacing_mm)
                + Vec2::new(rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5))
        })
        .collect();
    centred(pts)
}

/// A thumb opposite `n − 1` fingertips, `reach_mm` from them (a pinching hand); the
/// thumb is the first offset.
fn pinch_hand(rng: &mut SplitMix64, n: usize, spacing_mm: f64, reach_mm: f64) -> Vec<Vec2> {
    let mut pts = vec![Vec2::new(-reach_mm, rng.uniform(-0.2, 0.2) * reach_mm)];
    pts.extend(
        row(rng, n.saturating_sub(1).max(1), spacing_mm)
            .into_iter()
            .take(n - 1),
    );
    // The fingers fan out a little around the thumb.
    let k = pts.len();
    for (j, p) in pts.iter_mut().enumerate().skip(1) {
        let fan = (j as f64 - k as f64 / 2.0) * rng.uniform(0.0, 0.15);
        *p = rot(*p, fan);
    }
    centred(pts)
}

fn centred(pts: Vec<Vec2>) -> Vec<Vec2> {
    let c = pts.iter().sum::<Vec2>() / pts.len().max(1) as f64;
    pts.into_iter().map(|p| p - c).collect()
}

/// A hand with fingertips `offsets` and nothing moving yet.
fn hand(rng: &mut SplitMix64, offsets: Vec<Vec2>, start_s: f64, dur_s: f64) -> Hand {
    let n = offsets.len();
    let lag_max = rng.uniform(0.0, 0.09);
    Hand {
        follow: (0..n).map(|_| rng.uniform(0.85, 1.05)).collect(),
        lag_s: (0..n).map(|_| rng.uniform(0.0, lag_max)).collect(),
        drift: (0..n)
            .map(|_| {
                let amp = rng.uniform(0.0, 3.0);
                Wobble::new(rng, amp, (0.2, 0.9))
            })
            .collect(),
        offsets,
        strokes: Vec::new(),
        turn_rad: 0.0,
        pivot: Vec2::zeros(),
        scale: (1.0, 1.0),
        anchor: Vec2::zeros(),
        shape: Stroke {
            d: Vec2::zeros(),
            bow: 0.0,
            start_s,
            dur_s,
        },
        curve: None,
        motion_s: (start_s, start_s + dur_s),
    }
}

/// How long a move of `dist_mm` takes at an average speed drawn for this person.
fn duration(rng: &mut SplitMix64, dist_mm: f64) -> f64 {
    (dist_mm / rng.uniform(90.0, 450.0)).clamp(0.35, 2.8)
}

/// The turning sense: `aim`'s, or either.
fn sense(rng: &mut SplitMix64, aim: &Aim) -> f64 {
    match aim.clockwise {
        Some(true) => 1.0,
        Some(false) => -1.0,
        None if rng.unit() < 0.5 => 1.0,
        None => -1.0,
    }
}

/// The plan of a gesture of `class` starting its motion at `start_s`; the whole
/// plan is in the gesture's frame, turned by the caller.
pub(super) fn plan(class: MotionClass, rng: &mut SplitMix64, start_s: f64, aim: &Aim) -> Plan {
    let n = finger_count(class, rng);
    let spacing = rng.uniform(15.0, 25.0);
    let one_hand = |hands: Hand| Plan { hands: vec![hands] };
    match class {
        MotionClass::Translate => {
            let dist = rng.uniform(40.0, 320.0);
            let dur = duration(rng, dist);
            let offsets = row_or_one(rng, n, spacing);
            let mut h = hand(rng, offsets, start_s, dur);
            h.strokes.push(Stroke {
                d: Vec2::new(dist, 0.0),
                bow: rng.uniform(-0.22, 0.22),
                start_s,
                dur_s: dur,
            });
            h.turn_rad = rng.uniform(-0.2, 0.2);
            one_hand(h)
        }
        MotionClass::Twist if n == 1 => one_finger_curve(rng, start_s, aim),
        MotionClass::Twist => {
            let r = rng.uniform(20.0, 60.0);
            let offsets = pinch_hand(rng, n, spacing, 2.0 * r);
            let turn = sense(rng, aim) * rng.uniform(45.0, 300.0).to_radians();
            let dur = (turn.abs() / rng.uniform(2.0, 6.0)).clamp(0.4, 2.5);
            let mut h = hand(rng, offsets, start_s, dur);
            h.turn_rad = turn;
            h.pivot = unit(rng.uniform(0.0, TAU)) * rng.uniform(0.0, 0.4) * r;
            h.scale = (1.0, rng.uniform(0.9, 1.1));
            h.strokes.push(Stroke {
                d: unit(rng.uniform(0.0, TAU)) * rng.uniform(0.0, 15.0),
                bow: 0.0,
                start_s,
                dur_s: dur,
            });
            one_hand(h)
        }
        MotionClass::Contract
        | MotionClass::Expand
        | MotionClass::TwistWhileExpanding
        | MotionClass::TwistWhileContracting => {
            let reach = rng.uniform(45.0, 140.0);
            let offsets = pinch_hand(rng, n, spacing, reach);
            let small = rng.uniform(0.1, 0.45);
            let closing = matches!(
                class,
                MotionClass::Contract | MotionClass::TwistWhileContracting
            );
            let turning = matches!(
                class,
                MotionClass::TwistWhileExpanding | MotionClass::TwistWhileContracting
            );
            let dur = duration(rng, reach * (1.0 - small)).max(0.4);
            let mut h = hand(rng, offsets, start_s, dur);
            h.scale = if closing { (1.0, small) } else { (small, 1.0) };
            // Closing on the thumb: the anchor sits between the centre and the thumb.
            let thumb = h.offsets[0];
            h.anchor = if turning {
                Vec2::zeros()
            } else {
                thumb * rng.uniform(0.0, 0.8)
            };
            h.turn_rad = if turning {
                sense(rng, aim) * rng.uniform(60.0, 300.0).to_radians()
            } else {
                rng.uniform(-0.25, 0.25)
            };
            h.strokes.push(Stroke {
                d: unit(rng.uniform(0.0, TAU)) * rng.uniform(0.0, 12.0),
                bow: 0.0,
                start_s,
                dur_s: dur,
            });
            one_hand(h)
        }
        MotionClass::Join
        | MotionClass::Split
        | MotionClass::SplitThenTranslate
        | MotionClass::TranslateThenJoin => two_hands(class, rng, start_s, spacing, aim),
    }
}

/// `n` fingertips of one hand in a row across the motion (one finger: the origin).
fn row_or_one(rng: &mut SplitMix64, n: usize, spacing: f64) -> Vec<Vec2> {
    if n == 1 {
        vec![Vec2::zeros()]
    } else {
        row(rng, n, spacing)
    }
}

/// One finger drawing a circle or spiral of 0.5–2 turns.
fn one_finger_curve(rng: &mut SplitMix64, start_s: f64, aim: &Aim) -> Plan {
    let turns = rng.uniform(0.5, 2.0);
    let r0 = rng.uniform(15.0, 60.0);
    // A circle, an outward or an inward spiral.
    let ratio = match rng.next_u64() % 3 {
        0 => rng.uniform(0.9, 1.1),
        1 => rng.uniform(1.3, 2.2),
        _ => rng.uniform(0.4, 0.75),
    };
    let sign = sense(rng, aim);
    let a0 = rng.uniform(0.0, TAU);
    let squash = rng.uniform(0.8, 1.0);
    let k = 1500;
    let pts: Vec<Vec2> = (0..=k)
        .map(|i| {
            let s = i as f64 / k as f64;
            let a = a0 + sign * TAU * turns * s;
            let r = r0 * ratio.powf(s);
            let p = Vec2::new(r * a.cos(), r * a.sin() * squash);
            p - Vec2::new(r0 * a0.cos(), r0 * a0.sin() * squash)
        })
        .collect();
    let length: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let dur = (length / rng.uniform(120.0, 450.0)).clamp(0.5, 3.0);
    let times = power_law_times(&pts, dur)
        .into_iter()
        .map(|t| t + start_s)
        .collect();
    let mut h = hand(rng, vec![Vec2::zeros()], start_s, dur);
    h.curve = Some((pts, times));
    Plan { hands: vec![h] }
}

/// Two hands along +x: join, split and their combinations.
fn two_hands(
    class: MotionClass,
    rng: &mut SplitMix64,
    start_s: f64,
    spacing: f64,
    aim: &Aim,
) -> Plan {
    let near = rng.uniform(60.0, 130.0);
    let far = rng.uniform(near.max(80.0) * 2.0, 420.0f64.max(near * 2.2));
    let (from, to) = match class {
        MotionClass::Join | MotionClass::TranslateThenJoin => (far, near),
        _ => (near, far),
    };
    let apart_dur = duration(rng, (far - near) * 0.6).max(0.4);
    // The common travel of the combined classes, across the axis either way (or the
    // aimed direction, relative to the axis).
    let travel_dist = rng.uniform(60.0, 250.0);
    let travel_dir = match (aim.direction_rad, aim.axis_rad) {
        (Some(d), Some(a)) => d - a + rng.uniform(-0.2, 0.2),
        _ => {
            let side = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
            side * (PI / 2.0 + rng.uniform(-0.8, 0.8))
        }
    };
    let travel_dur = duration(rng, travel_dist);
    // The second stroke begins before the first ends.
    let overlap = rng.uniform(0.0, 0.35);
    let (apart_start, travel_start) = match class {
        MotionClass::SplitThenTranslate => (start_s, start_s + apart_dur * (1.0 - overlap)),
        MotionClass::TranslateThenJoin => (start_s + travel_dur * (1.0 - overlap), start_s),
        _ => (start_s, start_s),
    };
    // One hand may do most of the moving.
    let share = rng.uniform(0.2, 0.8);
    let second_late = rng.uniform(0.0, 0.2);
    let mut hands = Vec::with_capacity(2);
    for h in 0..2 {
        let side = if h == 0 { -1.0 } else { 1.0 };
        let n = finger_count(class, rng);
        let offsets: Vec<Vec2> = row_or_one(rng, n, spacing)
            .into_iter()
            .map(|p| rot(p, rng.uniform(-0.3, 0.3)) + Vec2::new(side * from / 2.0, 0.0))
            .collect();
        let late = if h == 1 { second_late } else { 0.0 };
        let mine = if h == 0 { share } else { 1.0 - share };
        let mut hd = hand(rng, offsets, apart_start + late, apart_dur);
        hd.strokes.push(Stroke {
            d: Vec2::new(
                -side * (from - to) * mine,
                rng.uniform(-0.08, 0.08) * (far - near),
            ),
            bow: rng.uniform(-0.15, 0.15),
            start_s: apart_start + late,
            dur_s: apart_dur,
        });
        if matches!(
            class,
            MotionClass::SplitThenTranslate | MotionClass::TranslateThenJoin
        ) {
            let dur = travel_dur * rng.uniform(0.9, 1.1);
            hd.strokes.push(Stroke {
                d: unit(travel_dir + rng.uniform(-0.1, 0.1)) * travel_dist * rng.uniform(0.9, 1.1),
                bow: rng.uniform(-0.1, 0.1),
                start_s: travel_start + late,
                dur_s: dur,
            });
        }
        let first = hd
            .strokes
            .iter()
            .map(|s| s.start_s)
            .fold(f64::INFINITY, f64::min);
        let last = hd
            .strokes
            .iter()
            .map(|s| s.start_s + s.dur_s)
            .fold(0.0, f64::max);
        hd.motion_s = (first, last);
        hands.push(hd);
    }
    Plan { hands }
}
