//! A recording of gesture commands drawn in open space, for `bench e2e --gestures`:
//! two people at opposite ends of the config's glass, each drawing generated
//! gestures (`gesture::synth`) one after another, the second person half a gesture
//! behind the first. So whenever one person's gesture ends and is recognised and
//! synthesised on the formation thread, the other person's fingers are moving and
//! their frames' latency is being measured.
//!
//! The people stand 0.09 and 0.91 of the glass's width from its left edge, at
//! 0.3–0.7 of its height (on the default config: 1.4 m and 14.6 m of the 16 m
//! world, the crowd between 6 and 10 m), drawing 40–100 mm gestures with one or
//! two fingers per hand, so that their fingers stay more than
//! `controls.gesture_span_mm` apart (two gestures, not one) and away from the
//! crowd (gestures, not direct control).

use anyhow::{Context, Result};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::MotionClass;
use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle, StyleRanges};
use crowdtouch::gesture::track::{GestureTracks, TouchTrack, TrackSample};
use crowdtouch::input::recording::JsonlWriter;
use crowdtouch::input::{AxisRange, SurfaceInfo};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::Micros;
use std::path::Path;

/// Gestures each person draws.
pub const GESTURES_PER_PERSON: usize = 12;
/// Pause after a person's finger lifts before their next gesture (µs): longer than
/// the default `controls.gesture_grace_ms`, so each is a gesture of its own.
const PAUSE_US: u64 = 450_000;
/// Where the two people draw (fractions of the glass's width).
const PEOPLE_X: [f64; 2] = [0.09, 0.91];

/// What was written.
pub struct OpenSpace {
    /// Gestures in the recording.
    pub gestures: usize,
    /// Its length (s).
    pub seconds: f64,
}

/// Writes the recording (module doc) for a glass of `glass_mm` to `path`.
///
/// # Errors
/// The file's write errors.
pub fn write_recording(glass_mm: (f64, f64), path: &Path, seed: u64) -> Result<OpenSpace> {
    let ranges = StyleRanges {
        fingers: (1, 2),
        size_mm: (40.0, 100.0),
        devices_mm: vec![glass_mm],
        early_lift_chance: 0.0,
        ..StyleRanges::default()
    };
    let mut rng = SplitMix64::new(seed);
    let mut all = GestureTracks {
        fingers: Vec::new(),
    };
    // Each person's clock: when their next gesture may start (µs).
    let mut next = [0u64, 0u64];
    let mut gestures = 0;
    for k in 0..2 * GESTURES_PER_PERSON {
        let person = k % 2;
        let class = MotionClass::ALL[k % MotionClass::ALL.len()];
        let s = rng.next_u64();
        let mut style = GestureStyle::random(class, s, &ranges);
        style.placement = Vec2::new(PEOPLE_X[person], rng.uniform(0.3, 0.7));
        let tracks = generate(class, &style, s ^ 0x0BE2_C4E5);
        let start = next[person];
        let end = tracks
            .fingers
            .iter()
            .filter_map(|f| f.samples.last())
            .map(|s| s.t.0)
            .max()
            .unwrap_or(0);
        if k == 0 {
            // The second person starts half way through the first one's gesture.
            next[1] = end / 2;
        }
        next[person] = start + end + PAUSE_US;
        all.fingers.extend(tracks.fingers.into_iter().map(|f| {
            TouchTrack {
                samples: f
                    .samples
                    .into_iter()
                    .map(|s| TrackSample {
                        t: Micros(s.t.0 + start),
                        mm: s.mm,
                    })
                    .collect(),
            }
        }));
        gestures += 1;
    }
    let frames = to_frames(&all, glass_mm, Micros(0));
    let surface = SurfaceInfo {
        name: format!("bench gestures {:.0}x{:.0} mm", glass_mm.0, glass_mm.1),
        x: AxisRange {
            min: 0.0,
            max: glass_mm.0 * 10.0,
            resolution: 10.0,
        },
        y: AxisRange {
            min: 0.0,
            max: glass_mm.1 * 10.0,
            resolution: 10.0,
        },
        max_contacts: 64,
    };
    let file = std::fs::File::create(path)
        .with_context(|| format!("{}: cannot create", path.display()))?;
    let mut w = JsonlWriter::new(&surface, std::io::BufWriter::new(file))?;
    for f in &frames {
        w.frame(f)?;
    }
    w.flush()?;
    let seconds = frames.last().map_or(0.0, |f| f.t.0 as f64 / 1e6);
    Ok(OpenSpace { gestures, seconds })
}
