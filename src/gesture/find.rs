//! Every gesture in a stream of touch frames, for tools (`crowdtouch gesture
//! classify`, `crowdtouch library add`, `library eval --test`): every touch is
//! treated as a gesture in open space (no crowd to land on), segmented with the
//! daemon's own state machine (grouping, grace period) and captured as the daemon
//! captures it, so a recording is cut into gestures exactly as the table would cut
//! it.

use super::capture::{CaptureParams, GestureCapture, Rejected, TapThresholds};
use super::capture::{DEFAULT_MAX_GESTURES, DEFAULT_SAMPLES_PER_TRACK};
use super::segment::{Segment, SegmentParams, Segmenter, TouchPoint};
use super::track::GestureTracks;
use crate::geom::Vec2;
use crate::vocab::{ContactFlags, Micros, TouchFrame};

/// A gesture found in a stream.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// When its first finger landed (the stream's clock, µs).
    pub t: Micros,
    /// Most fingers down at once.
    pub fingers: u32,
    /// Its tracks (mm of glass), or why it is not one to recognise (a tap, too long).
    pub tracks: Result<GestureTracks, Rejected>,
}

/// Cuts frames into gestures (see the module doc).
pub struct GestureFinder {
    seg: Segmenter,
    capture: GestureCapture,
    glass_mm: Vec2,
    out: Vec<Segment>,
    begun: Vec<(u32, Micros)>,
    buf: GestureTracks,
    found: Vec<Found>,
}

impl GestureFinder {
    /// A finder for a surface of `glass_mm` (width, height in mm), segmenting with
    /// `params` and refusing taps and over-long gestures by `thresholds`.
    pub fn new(glass_mm: Vec2, params: SegmentParams, thresholds: TapThresholds) -> GestureFinder {
        let mut seg = Segmenter::new(params);
        seg.set_all_touches_are_gestures(true);
        let capture = GestureCapture::new(
            CaptureParams {
                max_gestures: DEFAULT_MAX_GESTURES,
                samples_per_track: DEFAULT_SAMPLES_PER_TRACK,
            },
            thresholds,
        );
        let buf = capture.tracks_buffer();
        GestureFinder {
            seg,
            capture,
            glass_mm,
            out: Vec::new(),
            begun: Vec::new(),
            buf,
            found: Vec::new(),
        }
    }

    /// Feeds one frame (surface coordinates in `[0, 1]²`). The frame's lifted
    /// contacts go first, as the evdev decoders emit them, so that a contact
    /// replacing one in the same frame (a new tracking id) is re-attached to its
    /// finger whatever order the recording lists them in.
    pub fn frame(&mut self, f: &TouchFrame) {
        self.seg.tick(f.t, &mut self.out);
        self.collect();
        let lifted =
            |c: &&crate::vocab::Contact| c.flags.ended() && !c.flags.contains(ContactFlags::DOWN);
        let first = f.contacts().iter().filter(lifted);
        let then = f.contacts().iter().filter(|c| !lifted(c));
        for c in first.chain(then) {
            let mm = Vec2::new(c.x as f64 * self.glass_mm.x, c.y as f64 * self.glass_mm.y);
            let tp = TouchPoint {
                id: c.id,
                world: mm,
                glass_mm: mm,
                flags: c.flags,
            };
            self.seg.touch(f.t, &tp, false, &mut self.out);
            self.capture.observe(f.t, &self.seg, &tp);
        }
        self.collect();
    }

    /// Ends the stream at `t`: gestures still open end (after their grace period).
    pub fn finish(&mut self, t: Micros) {
        let end = Micros(t.0.saturating_add(60_000_000));
        self.seg.tick(end, &mut self.out);
        self.collect();
        self.seg.cancel_all(end, &mut self.out);
        self.collect();
    }

    /// The gestures found so far, oldest first (taken).
    pub fn take(&mut self) -> Vec<Found> {
        std::mem::take(&mut self.found)
    }

    fn collect(&mut self) {
        for s in self.out.drain(..) {
            match s {
                Segment::GestureBegin(id) => {
                    let t = self
                        .seg
                        .gestures()
                        .iter()
                        .find(|g| g.id == id)
                        .map_or(Micros::ZERO, |g| g.t_begin);
                    self.begun.push((id, t));
                }
                Segment::GestureEnd { id, fingers, .. } => {
                    let t = self
                        .begun
                        .iter()
                        .position(|b| b.0 == id)
                        .map_or(Micros::ZERO, |k| self.begun.swap_remove(k).1);
                    let tracks = self
                        .capture
                        .finish(id, &mut self.buf)
                        .map(|_| self.buf.clone());
                    self.found.push(Found { t, fingers, tracks });
                }
                _ => {}
            }
        }
    }
}

/// Every gesture in `frames` (see the module doc).
pub fn find_gestures<'a>(
    frames: impl IntoIterator<Item = &'a TouchFrame>,
    glass_mm: Vec2,
    params: SegmentParams,
    thresholds: TapThresholds,
) -> Vec<Found> {
    let mut f = GestureFinder::new(glass_mm, params, thresholds);
    let mut last = Micros::ZERO;
    for fr in frames {
        f.frame(fr);
        last = fr.t;
    }
    f.finish(last);
    f.take()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::library::MotionClass;
    use crate::gesture::synth::{generate, to_frames, GestureStyle};
    use crate::vocab::{Contact, ContactId};

    /// The default config's segmentation.
    fn params() -> SegmentParams {
        SegmentParams {
            group_window: Micros(150_000),
            hand_span_mm: 200.0,
            gesture_span_mm: 600.0,
            gesture_grace: Micros(250_000),
        }
    }

    #[test]
    fn a_two_hand_join_is_one_gesture_with_all_its_fingers() {
        let style = GestureStyle {
            fingers: vec![3, 2],
            duration_s: 1.2,
            size_mm: 200.0,
            placement: Vec2::new(0.5, 0.5),
            orientation_rad: 0.2,
            jitter_mm: 0.5,
            device_mm: (1210.0, 680.0),
            rate_hz: 120.0,
            stagger_ms: 60.0,
            early_lifts: 0,
            bow: 0.1,
            spacing_mm: 20.0,
            clockwise: true,
        };
        let tracks = generate(MotionClass::Join, &style, 77);
        assert_eq!(tracks.fingers.len(), 5);
        let frames = to_frames(&tracks, style.device_mm, Micros(3_000_000));
        let found = find_gestures(
            &frames,
            Vec2::new(1210.0, 680.0),
            params(),
            TapThresholds::default(),
        );
        assert_eq!(found.len(), 1, "{found:?}");
        let g = &found[0];
        assert_eq!(g.t, Micros(3_000_000));
        assert_eq!(g.fingers, 5);
        let got = g.tracks.as_ref().unwrap();
        assert_eq!(got.fingers.len(), 5);
        // Every finger comes back whole: its landing and its lift (within f32).
        for (a, b) in got.fingers.iter().zip(&tracks.fingers) {
            let (a0, b0) = (a.samples[0], b.samples[0]);
            assert_eq!(a0.t, Micros(3_000_000) + b0.t);
            assert!((a0.mm - b0.mm).norm() < 1e-3, "{a0:?} {b0:?}");
            let (a1, b1) = (a.samples.last().unwrap(), b.samples.last().unwrap());
            assert!((a1.mm - b1.mm).norm() < 1e-3, "{a1:?} {b1:?}");
        }
    }

    fn touch(t_ms: u64, id: u32, x: f32, flags: ContactFlags) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t_ms * 1000));
        f.push(Contact {
            id: ContactId(id),
            x,
            y: 0.5,
            flags,
            ..Contact::default()
        })
        .unwrap();
        f
    }

    #[test]
    fn a_new_id_listed_before_the_lift_it_replaces_is_the_same_finger() {
        let contact = |id: u32, x: f32, flags: ContactFlags| Contact {
            id: ContactId(id),
            x,
            y: 0.5,
            flags,
            ..Contact::default()
        };
        let mut frames = Vec::new();
        for k in 0..40u32 {
            let mut f = TouchFrame::new(Micros(u64::from(k) * 10_000));
            let x = 0.2 + 0.01 * k as f32;
            let (a, b) = (
                contact(1, x, ContactFlags::NONE),
                contact(2, x + 0.05, ContactFlags::NONE),
            );
            match k {
                0 => {
                    f.push(Contact {
                        flags: ContactFlags::DOWN,
                        ..a
                    })
                    .unwrap();
                    f.push(Contact {
                        flags: ContactFlags::DOWN,
                        ..b
                    })
                    .unwrap();
                }
                // Finger 1's new id listed before its old id's end.
                20 => {
                    f.push(Contact {
                        id: ContactId(9),
                        flags: ContactFlags::DOWN,
                        ..a
                    })
                    .unwrap();
                    f.push(Contact {
                        flags: ContactFlags::UP,
                        ..a
                    })
                    .unwrap();
                    f.push(b).unwrap();
                }
                39 => {
                    f.push(Contact {
                        id: ContactId(9),
                        flags: ContactFlags::UP,
                        ..a
                    })
                    .unwrap();
                    f.push(Contact {
                        flags: ContactFlags::UP,
                        ..b
                    })
                    .unwrap();
                }
                _ => {
                    let id = if k > 20 { 9 } else { 1 };
                    f.push(Contact {
                        id: ContactId(id),
                        ..a
                    })
                    .unwrap();
                    f.push(b).unwrap();
                }
            }
            frames.push(f);
        }
        let found = find_gestures(
            &frames,
            Vec2::new(1210.0, 680.0),
            params(),
            TapThresholds::default(),
        );
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].fingers, 2);
        let tracks = found[0].tracks.as_ref().unwrap();
        assert_eq!(tracks.fingers.len(), 2);
        assert_eq!(tracks.fingers[0].samples.len(), 40);
    }

    #[test]
    fn two_taps_are_two_rejected_taps() {
        let mut frames = Vec::new();
        // Two quick touches a second apart, each 80 ms long and still.
        for (start, id) in [(0, 1), (1000, 2)] {
            frames.push(touch(start, id, 0.3, ContactFlags::DOWN));
            frames.push(touch(start + 40, id, 0.3, ContactFlags::NONE));
            frames.push(touch(start + 80, id, 0.3, ContactFlags::UP));
        }
        let found = find_gestures(
            &frames,
            Vec2::new(1210.0, 680.0),
            params(),
            TapThresholds::default(),
        );
        assert_eq!(found.len(), 2, "{found:?}");
        assert_eq!(found[0].t, Micros(0));
        assert_eq!(found[1].t, Micros(1_000_000));
        for f in &found {
            assert_eq!(f.fingers, 1);
            assert!(
                matches!(f.tracks, Err(Rejected::Tap { .. })),
                "{:?}",
                f.tracks
            );
        }
    }
}
