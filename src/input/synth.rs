//! The shipped synthetic recordings, generated deterministically.
//!
//! Seven short touch recordings in `config/recordings/*.jsonl` exercise the
//! controls and gestures on the default scene without a touch table. They are
//! synthetic (made by this module, not recorded from hardware) and generated
//! byte for byte the same on every run: a seeded splitmix64 PRNG per file, no
//! clock, no `rand`.
//!
//! # Regenerating
//!
//! ```text
//! crowdtouch synth-recordings --out config/recordings
//! ```
//! or, without the CLI, `CROWDTOUCH_BLESS=1 cargo test --test recordings shipped`.
//! A test compares the files in `config/recordings/` with [`shipped`], so the two
//! cannot drift: change the scripts here, regenerate, commit both.
//!
//! # Device and coordinates
//!
//! A 55-inch table: [`DEVICE_NAME`], both axes `0..=32767`, glass
//! [`SURFACE_W_MM`] × [`SURFACE_H_MM`], 10 contacts. The default world is
//! [`WORLD_W_M`] × [`WORLD_H_M`] shown on the whole unit square, so
//! `surface = world / (16, 9)` and one world metre is about 75.6 mm of glass on
//! both axes. The default crowd stands in world x 6..10 m, y 3..6 m (surface x
//! 0.375..0.625, y 0.333..0.667). World y points down, like surface y; a
//! positive rotation turns +x towards +y (clockwise as seen on the table).
//!
//! # Realism
//!
//! 120 Hz frames with ±0.4 ms uniform timing jitter; ±0.3 mm uniform position
//! noise per axis and frame; fingers of one hand land 10–60 ms apart and lift
//! 10–60 ms apart; motion eases in and out (smoothstep). A lifted finger is
//! reported `UP` at its position in the previous frame, as the evdev decoder
//! does, so a file read back gives exactly the frames generated here (positions
//! within the writer's 1e-3 device-unit rounding).
//!
//! | file | fingers | what |
//! |---|---|---|
//! | `01-point-drag` | 1 | on the crowd's right edge (9.9, 4.5), drags 2.5 m right in 1.5 s, holds 0.3 s |
//! | `02-line-drag` | 2 | left edge, x 6.1, y 3.6 and 5.4 (136 mm apart), drag 2 m left |
//! | `03-line-pinch` | 2 | top edge y 3.1, x 7.0 and 9.0, pinch to 0.8 m apart |
//! | `04-area-drag` | 3 | triangle 1 m wide around (8, 4.5), translate 1 m right, 1.5 m down |
//! | `05-area-twist` | 4 | radius 0.9 m around (8, 4.5), rotate 60° in 1.5 s |
//! | `06-two-hands` | 2 + 3 | A: x 6.1, y 3.8 / 5.2, 1 m left; B (80 ms later): 3 fingers around (9.75, 4.5), 1 m right turning 20° |
//! | `07-open-space-swipe` | 2 | open space around (2.5, 7.5), swipe 3 m right |
//!
//! Hand B of `06-two-hands` is centred at x 9.75 m rather than 9.3 m: from hand
//! A at x 6.1 m, 3.2 m is only 242 mm of glass, and the hands must be more than
//! 250 mm apart (they are at least [`TWO_HANDS_MIN_GAP_MM`] apart in every frame).

use super::{AxisRange, SurfaceInfo};
use crate::geom::Vec2;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
use std::path::{Path, PathBuf};

/// Name of the synthetic device.
pub const DEVICE_NAME: &str = "crowdtouch synthetic 55in table";
/// Axis maximum of both axes (minimum 0).
pub const AXIS_MAX: f64 = 32767.0;
/// Width of the glass, mm.
pub const SURFACE_W_MM: f64 = 1210.0;
/// Height of the glass, mm.
pub const SURFACE_H_MM: f64 = 680.0;
/// Contacts the device reports.
pub const MAX_CONTACTS: u32 = 10;
/// Width of the default world shown on the surface, m.
pub const WORLD_W_M: f64 = 16.0;
/// Height of the default world shown on the surface, m.
pub const WORLD_H_M: f64 = 9.0;
/// Frame rate, Hz.
pub const FRAME_RATE_HZ: f64 = 120.0;
/// Timing jitter, ± µs (uniform).
pub const TIMING_JITTER_US: f64 = 400.0;
/// Position noise, ± mm per axis (uniform).
pub const POSITION_NOISE_MM: f64 = 0.3;
/// Shortest delay between two fingers of a hand landing or lifting, ms.
pub const STAGGER_MIN_MS: f64 = 10.0;
/// Longest delay between two fingers of a hand landing or lifting, ms.
pub const STAGGER_MAX_MS: f64 = 60.0;
/// Default time from a hand's last possible landing to the start of its motion, s.
const SETTLE_S: f64 = 0.15;
/// Smallest distance between the two hands of `06-two-hands` in any frame, mm.
pub const TWO_HANDS_MIN_GAP_MM: f64 = 250.0;

/// The synthetic device.
pub fn surface() -> SurfaceInfo {
    SurfaceInfo {
        name: DEVICE_NAME.to_string(),
        x: AxisRange {
            min: 0.0,
            max: AXIS_MAX,
            resolution: AXIS_MAX / SURFACE_W_MM,
        },
        y: AxisRange {
            min: 0.0,
            max: AXIS_MAX,
            resolution: AXIS_MAX / SURFACE_H_MM,
        },
        max_contacts: MAX_CONTACTS,
    }
}

/// World metres → surface unit square (default world).
pub fn world_to_surface(p: Vec2) -> Vec2 {
    Vec2::new(p.x / WORLD_W_M, p.y / WORLD_H_M)
}

/// The splitmix64 generator (one for the whole project: [`crate::rng`]).
pub use crate::rng::SplitMix64;

/// Smoothstep ease-in/out: 0 → 0, 1 → 1, zero slope at both ends.
fn ease(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// One hand: its fingers and what they do together.
#[derive(Clone, Debug)]
struct Hand {
    /// Finger start positions, world m, in landing order.
    fingers: Vec<Vec2>,
    /// Per-finger extra displacement over the motion (pinch), world m.
    spread: Vec<Vec2>,
    /// First finger lands, s.
    land_s: f64,
    /// Time from the last possible landing to the start of the motion, s.
    settle_s: f64,
    /// Motion duration, s.
    move_s: f64,
    /// Pause between the end of the motion and the first lift, s.
    hold_s: f64,
    /// Translation over the motion, world m.
    translate: Vec2,
    /// Rotation over the motion about `centre`, rad.
    rotate_rad: f64,
    /// Rotation centre, world m.
    centre: Vec2,
}

impl Hand {
    fn new(fingers: Vec<Vec2>, land_s: f64, move_s: f64, hold_s: f64) -> Hand {
        let n = fingers.len();
        let centre = fingers.iter().sum::<Vec2>() / n.max(1) as f64;
        Hand {
            fingers,
            spread: vec![Vec2::zeros(); n],
            land_s,
            settle_s: SETTLE_S,
            move_s,
            hold_s,
            translate: Vec2::zeros(),
            rotate_rad: 0.0,
            centre,
        }
    }

    fn move_start_s(&self) -> f64 {
        self.land_s + (self.fingers.len() as f64 - 1.0) * STAGGER_MAX_MS * 1e-3 + self.settle_s
    }

    /// Noise-free position of finger `i` at time `t_s`, world m.
    fn position(&self, i: usize, t_s: f64) -> Vec2 {
        let e = ease((t_s - self.move_start_s()) / self.move_s);
        let (s, c) = (self.rotate_rad * e).sin_cos();
        let r = self.fingers[i] - self.centre;
        self.centre
            + Vec2::new(c * r.x - s * r.y, s * r.x + c * r.y)
            + (self.translate + self.spread[i]) * e
    }
}

/// A finger's schedule, flattened across hands.
#[derive(Clone, Debug)]
struct Finger {
    hand: usize,
    index: usize,
    land_s: f64,
    lift_s: f64,
}

/// Generates the frames of a script.
fn generate(hands: &[Hand], seed: u64) -> Vec<TouchFrame> {
    let mut rng = SplitMix64::new(seed);
    let mut fingers: Vec<Finger> = Vec::new();
    for (h, hand) in hands.iter().enumerate() {
        let mut land = hand.land_s;
        let mut lift = hand.move_start_s() + hand.move_s + hand.hold_s;
        for i in 0..hand.fingers.len() {
            if i > 0 {
                land += rng.uniform(STAGGER_MIN_MS, STAGGER_MAX_MS) * 1e-3;
                lift += rng.uniform(STAGGER_MIN_MS, STAGGER_MAX_MS) * 1e-3;
            }
            fingers.push(Finger {
                hand: h,
                index: i,
                land_s: land,
                lift_s: lift,
            });
        }
    }
    // Ids in landing order, as a reader numbers them.
    fingers.sort_by(|a, b| a.land_s.total_cmp(&b.land_s));
    let period_us = 1e6 / FRAME_RATE_HZ;
    let noise_x = POSITION_NOISE_MM / SURFACE_W_MM;
    let noise_y = POSITION_NOISE_MM / SURFACE_H_MM;
    // Per finger: down, and its last reported contact.
    let mut last: Vec<Option<Contact>> = vec![None; fingers.len()];
    let mut done = vec![false; fingers.len()];
    let mut frames = Vec::new();
    for k in 0u64.. {
        let jitter = if k == 0 {
            0.0
        } else {
            rng.uniform(-TIMING_JITTER_US, TIMING_JITTER_US)
        };
        let t_us = (k as f64 * period_us + jitter).round().max(0.0) as u64;
        let t_s = t_us as f64 * 1e-6;
        let mut frame = TouchFrame::new(Micros(t_us));
        // Lifts first, at the previous position.
        for (j, f) in fingers.iter().enumerate() {
            if let Some(prev) = last[j] {
                if t_s >= f.lift_s {
                    let mut c = prev;
                    c.flags = ContactFlags::UP;
                    let _ = frame.push(c);
                    last[j] = None;
                    done[j] = true;
                }
            }
        }
        for (j, f) in fingers.iter().enumerate() {
            if done[j] || t_s < f.land_s {
                continue;
            }
            let p = world_to_surface(hands[f.hand].position(f.index, t_s));
            let x = (p.x + rng.uniform(-noise_x, noise_x)).clamp(0.0, 1.0);
            let y = (p.y + rng.uniform(-noise_y, noise_y)).clamp(0.0, 1.0);
            let flags = if last[j].is_none() {
                ContactFlags::DOWN
            } else {
                ContactFlags::NONE
            };
            let c = Contact {
                id: ContactId(j as u32 + 1),
                x: x as f32,
                y: y as f32,
                flags,
                ..Contact::default()
            };
            let _ = frame.push(c);
            last[j] = Some(c);
        }
        frames.push(frame);
        if done.iter().all(|&d| d) {
            break;
        }
    }
    frames
}

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

/// The scripts, by file name.
fn scripts() -> Vec<(&'static str, Vec<Hand>)> {
    let point = {
        let mut h = Hand::new(vec![v(9.9, 4.5)], 0.0, 1.5, 0.3);
        h.translate = v(2.5, 0.0);
        vec![h]
    };
    let line_drag = {
        let mut h = Hand::new(vec![v(6.1, 3.6), v(6.1, 5.4)], 0.0, 1.5, 0.2);
        h.translate = v(-2.0, 0.0);
        vec![h]
    };
    let pinch = {
        let mut h = Hand::new(vec![v(7.0, 3.1), v(9.0, 3.1)], 0.0, 1.2, 0.25);
        // 2 m apart to 0.8 m: each finger moves 0.6 m towards the middle.
        h.spread = vec![v(0.6, 0.0), v(-0.6, 0.0)];
        vec![h]
    };
    let area_drag = {
        let mut h = Hand::new(vec![v(7.5, 4.8), v(8.0, 4.0), v(8.5, 4.8)], 0.0, 1.5, 0.2);
        h.translate = v(1.0, 1.5);
        vec![h]
    };
    let twist = {
        let c = v(8.0, 4.5);
        let fingers = (0..4)
            .map(|i| {
                let a = (200.0 + 50.0 * i as f64).to_radians();
                c + 0.9 * v(a.cos(), a.sin())
            })
            .collect();
        let mut h = Hand::new(fingers, 0.0, 1.5, 0.2);
        h.centre = c;
        h.rotate_rad = 60f64.to_radians();
        vec![h]
    };
    let two_hands = {
        let mut a = Hand::new(vec![v(6.1, 3.8), v(6.1, 5.2)], 0.0, 1.5, 0.2);
        a.translate = v(-1.0, 0.0);
        let cb = v(9.75, 4.5);
        let fingers = [90.0f64, 210.0, 330.0]
            .iter()
            .map(|d| cb + 0.33 * v(d.to_radians().cos(), d.to_radians().sin()))
            .collect();
        let mut b = Hand::new(fingers, 0.08, 1.5, 0.2);
        b.centre = cb;
        b.translate = v(1.0, 0.0);
        b.rotate_rad = 20f64.to_radians();
        vec![a, b]
    };
    let swipe = {
        let mut h = Hand::new(vec![v(2.5, 7.3), v(2.5, 7.7)], 0.0, 0.9, 0.02);
        // The fingers rest a moment, then swipe and lift.
        h.settle_s = 0.6;
        h.translate = v(3.0, 0.0);
        vec![h]
    };
    vec![
        ("01-point-drag.jsonl", point),
        ("02-line-drag.jsonl", line_drag),
        ("03-line-pinch.jsonl", pinch),
        ("04-area-drag.jsonl", area_drag),
        ("05-area-twist.jsonl", twist),
        ("06-two-hands.jsonl", two_hands),
        ("07-open-space-swipe.jsonl", swipe),
    ]
}

/// The shipped recordings: `(file name, surface, frames)`, deterministic.
pub fn shipped() -> Vec<(String, SurfaceInfo, Vec<TouchFrame>)> {
    scripts()
        .into_iter()
        .enumerate()
        .map(|(i, (name, hands))| {
            let seed = 0xc0ff_ee00_0000_0000 ^ (i as u64 + 1);
            (name.to_string(), surface(), generate(&hands, seed))
        })
        .collect()
}

/// Writes [`shipped`] into `dir` (created if needed) as JSON Lines; returns the paths.
///
/// # Errors
/// Any I/O error creating the directory or writing a file.
pub fn write_shipped(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    let mut paths = Vec::new();
    for (name, surface, frames) in shipped() {
        let path = dir.join(&name);
        let mut w = std::io::BufWriter::new(std::fs::File::create(&path)?);
        super::recording::write_jsonl(&surface, &frames, &mut w)?;
        std::io::Write::flush(&mut w)?;
        paths.push(path);
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix_reference_values() {
        // First outputs for seed 1234567 (reference implementation by Vigna).
        let mut r = SplitMix64::new(1_234_567);
        assert_eq!(r.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(r.next_u64(), 3_203_168_211_198_807_973);
    }

    #[test]
    fn ease_ends_and_middle() {
        assert_eq!(ease(0.0), 0.0);
        assert_eq!(ease(1.0), 1.0);
        assert!((ease(0.5) - 0.5).abs() < 1e-12);
        assert_eq!(ease(-1.0), 0.0);
    }

    #[test]
    fn world_mapping_is_isotropic_on_the_glass() {
        let mm_per_m_x = SURFACE_W_MM / WORLD_W_M;
        let mm_per_m_y = SURFACE_H_MM / WORLD_H_M;
        assert!(
            (mm_per_m_x - mm_per_m_y).abs() < 0.1,
            "{mm_per_m_x} vs {mm_per_m_y}"
        );
        let p = world_to_surface(v(6.0, 3.0));
        assert!((p.x - 0.375).abs() < 1e-12 && (p.y - 1.0 / 3.0).abs() < 1e-12);
    }
}
