//! A second, independent generator of multi-touch gestures (issue 28): the same
//! convention of what to draw for each class (docs/gestures.md "The classes and
//! what to draw") as `gesture::synth`, drawn with deliberately different
//! conventions of motion, so that recognition can be trained on one generator and
//! tested on the other (cross-style evaluation, `gesture::eval`).
//!
//! What differs from `gesture::synth` (which smoothsteps every stroke, scales and
//! turns a hand about its centroid, and lands and lifts fingers together):
//!
//! | | here |
//! |---|---|
//! | strokes | minimum-jerk, bowed; a combined class's strokes overlap (`motor.rs`, `plan.rs`) |
//! | one-finger twist | a circle or spiral of 0.5–2 turns timed by the two-thirds power law |
//! | pinch | closes on the thumb; hands turn about a pivot off their centre |
//! | fingers | each with its own lag (0–90 ms) and share of the motion, drifting slowly (< 1 Hz) |
//! | hands | fingertips 15–25 mm apart, a thumb 45–140 mm from them; two hands 60–130 mm apart when close, 120–420 mm when far; one hand often does most of the moving, the other starts up to 200 ms late |
//! | lifts | in any order over 0–150 ms after a hold; a finger may lift early (20 %), or lift and land again as a new contact (10 %) |
//! | noise | 8–12 Hz tremor per hand and finger (0.05–0.4 mm), sensor noise (0.05–0.35 mm), positions quantised to 0.05–0.25 mm |
//! | devices | 60, 120 or 240 Hz with frame-time jitter and dropped frames (2 %); glasses of 75″, 46″, 24″ and 15.6″ (none of `synth`'s); a gesture too large for the glass is drawn smaller |
//!
//! Seeds are this module's own ([`STYLE2_SALT`]): the same seed draws the same
//! gesture, unrelated to what `synth` draws for it.
//!
//! [`draw_still`] draws what is *not* a gesture — resting fingers, a touch and
//! release, a tap — for choosing rejection thresholds.

pub mod motor;
mod plan;

pub use plan::Aim;

use crate::geom::Vec2;
use crate::gesture::library::MotionClass;
use crate::gesture::track::{GestureTracks, TouchTrack, TrackSample, MAX_GESTURE_FINGERS};
use crate::rng::SplitMix64;
use crate::vocab::Micros;
use motor::{normal, rot, Wobble};
use std::f64::consts::TAU;

/// Mixed into every seed, so that this generator's seeds are its own.
pub const STYLE2_SALT: u64 = 0x5e75_1e20_0000_2222;

/// The glasses it draws on (width × height, mm): 75″, 46″, 24″ and 15.6″ 16:9.
pub const GLASSES_MM: [(f64, f64); 4] = [
    (1660.0, 934.0),
    (1018.0, 573.0),
    (531.0, 299.0),
    (345.0, 194.0),
];

/// The frame rates it samples at, Hz.
pub const RATES_HZ: [f64; 3] = [60.0, 120.0, 240.0];

/// Distance kept between a gesture and the glass's edge, mm.
pub const EDGE_MARGIN_MM: f64 = 8.0;

/// A drawn gesture and the device it was drawn on.
#[derive(Clone, Debug, PartialEq)]
pub struct Drawn {
    /// Every finger's samples (mm of glass, times from 0 at the first landing).
    pub tracks: GestureTracks,
    /// The glass, width × height, mm.
    pub device_mm: (f64, f64),
    /// The frame rate, Hz.
    pub rate_hz: f64,
}

/// A person and a device: what every finger shares.
struct Person {
    rate_hz: f64,
    device_mm: (f64, f64),
    tremor_mm: f64,
    noise_mm: f64,
    resolution_mm: f64,
}

impl Person {
    fn draw(rng: &mut SplitMix64) -> Person {
        let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n as u64) as usize;
        Person {
            rate_hz: RATES_HZ[pick(rng, RATES_HZ.len())],
            device_mm: GLASSES_MM[pick(rng, GLASSES_MM.len())],
            tremor_mm: rng.uniform(0.05, 0.4),
            noise_mm: rng.uniform(0.05, 0.35),
            resolution_mm: [0.05, 0.1, 0.25][pick(rng, 3)],
        }
    }
}

/// One contact as it will be sampled: which hand and finger it follows, when it
/// is down.
struct Contact {
    hand: usize,
    finger: usize,
    land_s: f64,
    lift_s: f64,
}

/// Draws a gesture of `class` pointed by `aim`, the same for the same seed.
///
/// ```
/// use crowdtouch::gesture::library::MotionClass;
/// use crowdtouch::gesture::style2::{draw, Aim};
/// let d = draw(MotionClass::Split, 7, &Aim::default());
/// assert!(d.tracks.fingers.len() >= 2);
/// assert_eq!(d, draw(MotionClass::Split, 7, &Aim::default()));
/// ```
pub fn draw(class: MotionClass, seed: u64, aim: &Aim) -> Drawn {
    let mut rng = SplitMix64::new(seed ^ STYLE2_SALT);
    let person = Person::draw(&mut rng);
    let start_s = rng.uniform(0.1, 0.35);
    let plan = plan::plan(class, &mut rng, start_s, aim);
    // Landing, lifting, early lifts and lift-and-land-again, per hand.
    let mut contacts: Vec<Contact> = Vec::new();
    for (h, hand) in plan.hands.iter().enumerate() {
        let (m0, m1) = hand.motion_s;
        let n = hand.offsets.len();
        let hold = rng.uniform(0.02, 0.3);
        let lift_spread = rng.uniform(0.0, 0.15);
        let first = contacts.len();
        for i in 0..n {
            contacts.push(Contact {
                hand: h,
                finger: i,
                land_s: (m0 - rng.uniform(-0.05, 0.3)).max(0.0),
                lift_s: m1 + hold + rng.uniform(0.0, lift_spread),
            });
        }
        if n >= 2 && rng.unit() < 0.2 {
            // One finger (not the last to stay) lifts before the motion ends.
            let last = (first..first + n)
                .max_by(|&a, &b| contacts[a].lift_s.total_cmp(&contacts[b].lift_s))
                .unwrap_or(first);
            let k = first + (rng.next_u64() % n as u64) as usize;
            if k != last {
                contacts[k].lift_s = m0 + (m1 - m0) * rng.uniform(0.5, 0.9);
            }
        }
        if n >= 2 && rng.unit() < 0.1 && contacts.len() < MAX_GESTURE_FINGERS - 1 {
            // A finger lifts for a moment and lands again: a new contact.
            let k = first + (rng.next_u64() % n as u64) as usize;
            let up = m0 + (m1 - m0) * rng.uniform(0.3, 0.6);
            let down = up + rng.uniform(0.06, 0.15);
            if down < contacts[k].lift_s {
                let rest = Contact {
                    hand: h,
                    finger: contacts[k].finger,
                    land_s: down,
                    lift_s: contacts[k].lift_s,
                };
                contacts[k].lift_s = up;
                contacts.push(rest);
            }
        }
    }
    let orient = match class {
        MotionClass::Translate => aim.direction_rad,
        MotionClass::Join
        | MotionClass::Split
        | MotionClass::SplitThenTranslate
        | MotionClass::TranslateThenJoin => aim.axis_rad,
        _ => None,
    }
    .unwrap_or_else(|| rng.uniform(0.0, TAU));
    let tremor: Vec<Wobble> = plan
        .hands
        .iter()
        .map(|_| Wobble::new(&mut rng, person.tremor_mm, (8.0, 12.0)))
        .collect();
    let tracks = sample(&person, &contacts, &mut rng, |c, t| {
        let hand = &plan.hands[c.hand];
        rot(hand.at(c.finger, t), orient) + tremor[c.hand].at(t)
    });
    place(tracks, &person, &mut rng)
}

/// Draws what is not a gesture: resting fingers (1–5, 0.4–4 s, drifting up to
/// 4 mm), a touch and release (2–4 fingers, 0.1–0.8 s, a slide of up to 5 mm as
/// they lift), or a tap (1–2 fingers, 40–200 ms).
pub fn draw_still(seed: u64) -> Drawn {
    let mut rng = SplitMix64::new(seed ^ STYLE2_SALT ^ 0x0005_7111);
    let person = Person::draw(&mut rng);
    let kind = rng.next_u64() % 3;
    let (n, dur, drift_mm) = match kind {
        0 => (
            1 + (rng.next_u64() % 5) as usize,
            rng.uniform(0.4, 4.0),
            rng.uniform(0.0, 4.0),
        ),
        1 => (
            2 + (rng.next_u64() % 3) as usize,
            rng.uniform(0.1, 0.8),
            rng.uniform(0.0, 5.0),
        ),
        _ => (
            1 + (rng.next_u64() % 2) as usize,
            rng.uniform(0.04, 0.2),
            rng.uniform(0.0, 1.0),
        ),
    };
    let spacing = rng.uniform(15.0, 25.0);
    let slide = motor::unit(rng.uniform(0.0, TAU)) * drift_mm;
    let contacts: Vec<Contact> = (0..n)
        .map(|i| Contact {
            hand: 0,
            finger: i,
            land_s: rng.uniform(0.0, 0.08),
            lift_s: dur + rng.uniform(0.0, 0.08),
        })
        .collect();
    let offsets: Vec<Vec2> = (0..n)
        .map(|i| Vec2::new(0.0, i as f64 * spacing) + Vec2::new(rng.uniform(-3.0, 3.0), 0.0))
        .collect();
    let wander: Vec<Wobble> = (0..n)
        .map(|_| Wobble::new(&mut rng, drift_mm * 0.5, (0.2, 0.8)))
        .collect();
    let tremor = Wobble::new(&mut rng, person.tremor_mm, (8.0, 12.0));
    let tracks = sample(&person, &contacts, &mut rng, |c, t| {
        let u = (t / dur.max(1e-3)).clamp(0.0, 1.0);
        offsets[c.finger] + slide * motor::min_jerk(u) + wander[c.finger].at(t) + tremor.at(t)
    });
    place(tracks, &person, &mut rng)
}

/// Samples every contact at the device's frames: frame-time jitter, dropped
/// frames, sensor noise, quantisation. Positions are in the gesture's frame.
fn sample(
    person: &Person,
    contacts: &[Contact],
    rng: &mut SplitMix64,
    at: impl Fn(&Contact, f64) -> Vec2,
) -> Vec<Vec<(f64, Vec2)>> {
    let period = 1.0 / person.rate_hz;
    let t0 = contacts
        .iter()
        .map(|c| c.land_s)
        .fold(f64::INFINITY, f64::min);
    let end = contacts.iter().map(|c| c.lift_s).fold(0.0, f64::max);
    let mut frames = Vec::new();
    let mut k = 0u64;
    loop {
        let t = t0 + k as f64 * period + rng.uniform(-0.03, 0.03) * period;
        if t > end + period {
            break;
        }
        // A dropped frame; never the first.
        if k == 0 || rng.unit() >= 0.02 {
            frames.push(t.max(t0));
        }
        k += 1;
    }
    let q = person.resolution_mm;
    contacts
        .iter()
        .map(|c| {
            let mut out: Vec<(f64, Vec2)> = frames
                .iter()
                .filter(|&&t| t >= c.land_s - 1e-9 && t < c.lift_s)
                .map(|&t| {
                    let noise = Vec2::new(normal(rng), normal(rng)) * person.noise_mm;
                    (t - t0, at(c, t) + noise)
                })
                .collect();
            if out.is_empty() {
                // A contact shorter than a frame is seen once.
                let t = frames
                    .iter()
                    .copied()
                    .find(|&t| t >= c.land_s)
                    .unwrap_or(c.land_s);
                out.push((t - t0, at(c, t)));
            }
            for s in &mut out {
                s.1 = s.1.map(|v| (v / q).round() * q);
            }
            out
        })
        .collect()
}

/// Places samples on the person's glass: drawn smaller if they do not fit inside
/// the margins, then shifted to a random place.
fn place(raw: Vec<Vec<(f64, Vec2)>>, person: &Person, rng: &mut SplitMix64) -> Drawn {
    let (w, h) = person.device_mm;
    let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
    for p in raw.iter().flatten().map(|s| s.1) {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    }
    let ext = (hi - lo).map(|v| v.max(1e-6));
    let room = Vec2::new(w - 2.0 * EDGE_MARGIN_MM, h - 2.0 * EDGE_MARGIN_MM);
    let shrink = (room.x / ext.x).min(room.y / ext.y).min(1.0);
    let size = ext * shrink;
    let corner = Vec2::new(
        EDGE_MARGIN_MM + rng.uniform(0.0, (room.x - size.x).max(0.0)),
        EDGE_MARGIN_MM + rng.uniform(0.0, (room.y - size.y).max(0.0)),
    );
    let mut fingers: Vec<TouchTrack> = raw
        .into_iter()
        .map(|samples| TouchTrack {
            samples: samples
                .into_iter()
                .map(|(t, p)| {
                    let q = corner + (p - lo) * shrink;
                    TrackSample {
                        t: Micros((t * 1e6).round().max(0.0) as u64),
                        mm: Vec2::new(q.x.clamp(0.0, w), q.y.clamp(0.0, h)),
                    }
                })
                .collect(),
        })
        .collect();
    fingers.sort_by_key(|f| f.samples.first().map(|s| s.t));
    fingers.truncate(MAX_GESTURE_FINGERS);
    Drawn {
        tracks: GestureTracks { fingers },
        device_mm: person.device_mm,
        rate_hz: person.rate_hz,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::resample::prepare;

    #[test]
    fn every_class_draws_valid_gestures_on_its_glass() {
        for class in MotionClass::ALL {
            for seed in 0..20 {
                let d = draw(class, seed, &Aim::default());
                assert!(prepare(&d.tracks).is_ok(), "{class} {seed}");
                let (w, h) = d.device_mm;
                for s in d.tracks.fingers.iter().flat_map(|f| &f.samples) {
                    assert!((0.0..=w).contains(&s.mm.x) && (0.0..=h).contains(&s.mm.y));
                }
                assert!(d
                    .tracks
                    .fingers
                    .iter()
                    .all(|f| f.samples.windows(2).all(|w| w[0].t < w[1].t)));
                assert!(RATES_HZ.contains(&d.rate_hz));
            }
        }
    }

    #[test]
    fn two_hand_classes_have_hands_apart_and_one_hand_classes_do_not() {
        // The largest gap between fingers' landing positions: a hand's fingertips
        // are 15–25 mm apart and a thumb under 150 mm from them; hands start
        // 60 mm apart or more.
        let widest = |d: &Drawn| {
            let firsts: Vec<Vec2> = d
                .tracks
                .fingers
                .iter()
                .filter_map(|f| f.samples.first().map(|s| s.mm))
                .collect();
            let mut m = 0.0f64;
            for a in &firsts {
                for b in &firsts {
                    m = m.max((a - b).norm());
                }
            }
            m
        };
        for seed in 0..30 {
            let join = draw(MotionClass::Join, seed, &Aim::default());
            if join.device_mm.0 > 500.0 {
                assert!(widest(&join) > 100.0, "join {seed}: {}", widest(&join));
            }
            let pinch = draw(MotionClass::Contract, seed, &Aim::default());
            assert!(widest(&pinch) < 220.0, "contract {seed}");
        }
    }

    #[test]
    fn aim_points_a_translate_and_turns_a_twist() {
        for seed in 0..10 {
            let aim = Aim {
                direction_rad: Some(1.0),
                ..Aim::default()
            };
            let d = draw(MotionClass::Translate, seed, &aim);
            let f = &d.tracks.fingers[0].samples;
            let v = f[f.len() - 1].mm - f[0].mm;
            if v.norm() > 30.0 {
                assert!((v.y.atan2(v.x) - 1.0).abs() < 0.6, "{seed}: {v}");
            }
        }
    }

    #[test]
    fn still_touches_barely_move() {
        for seed in 0..30 {
            let d = draw_still(seed);
            for f in &d.tracks.fingers {
                let first = f.samples[0].mm;
                assert!(f.samples.iter().all(|s| (s.mm - first).norm() < 12.0));
            }
        }
    }
}
