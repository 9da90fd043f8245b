//! Replaying recordings as a touch source.
//!
//! A [`ReplaySource`] plays a playlist of already-parsed recordings into a
//! [`FrameSink`], on the input thread, as a simulated device would: frames are
//! emitted at their recorded offsets ([`Pacing::RealTime`]) or as fast as the
//! sink takes them on a virtual clock ([`Pacing::Virtual`], for tests and
//! benchmarks).
//!
//! # Contact ids
//!
//! Every file, and every loop iteration of it, gets a fresh block of
//! [`ContactId`]s: a contact's id is the block's base plus its id in the file
//! minus the file's smallest id. Ids are therefore unique across files and loop
//! iterations and never reused while the source runs (the 32-bit space wraps
//! only after about four billion contacts).
//!
//! # Ends
//!
//! Contacts still down when a file ends (a recording cut mid-touch) are ended
//! `CANCELLED` in one more frame at the file's last frame time, so no touch
//! leaks into the next file. When `stop` is set mid-file, the contacts down are
//! likewise emitted `CANCELLED` in a final frame.
//!
//! # Real time
//!
//! The per-frame loop neither allocates nor locks: it copies each recorded frame
//! into one preallocated [`TouchFrame`], remaps ids, and pushes it.

use super::FrameSink;
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Longest sleep between two checks of the stop flag, in µs.
pub const STOP_POLL_US: u64 = 50_000;

/// How a replay is timed.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Pacing {
    /// Each frame is emitted at the run's start plus its offset, and stamped with
    /// `monotonic_now()` at emission, like a kernel event of a real device.
    RealTime,
    /// No sleeping; frames are stamped with a virtual clock starting at zero
    /// (offsets accumulated across files and gaps).
    Virtual,
}

/// One recording of a playlist.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayItem {
    /// A name for logs (usually the file name).
    pub name: String,
    /// The frames, with time relative to the start of the recording.
    pub frames: Vec<TouchFrame>,
}

impl ReplayItem {
    /// An item from a name and its frames.
    pub fn new(name: impl Into<String>, frames: Vec<TouchFrame>) -> ReplayItem {
        ReplayItem {
            name: name.into(),
            frames,
        }
    }
}

/// Per-item id range, computed once.
#[derive(Copy, Clone, Debug)]
struct IdSpan {
    min: u32,
    /// `max - min + 1` (0 for an item without contacts).
    len: u32,
}

/// What the playing loop mutates; kept apart from the items it reads.
#[derive(Clone, Debug)]
struct PlayState {
    out: TouchFrame,
    /// Remapped contacts currently down.
    active: [Contact; MAX_CONTACTS],
    active_len: usize,
    /// Base of the next id block.
    next_base: u32,
    emitted: u64,
    /// Time stamped on the last emitted frame.
    last_t: Micros,
}

impl PlayState {
    /// Emits `f` with ids moved into the block starting at `base`.
    fn emit(
        &mut self,
        f: &TouchFrame,
        base: u32,
        span: IdSpan,
        t: Micros,
        sink: &mut dyn FrameSink,
    ) {
        self.out.clear();
        self.out.t = t;
        self.out.t_queued = Micros::ZERO;
        self.out.device = f.device;
        for c in f.contacts() {
            let mut m = *c;
            m.id = ContactId(base.wrapping_add(c.id.0.wrapping_sub(span.min)));
            // Cannot overflow: `f` held no more than MAX_CONTACTS.
            let _ = self.out.push(m);
            let pos = self.active[..self.active_len]
                .iter()
                .position(|a| a.id == m.id);
            match (pos, m.flags.ended()) {
                (Some(i), true) => {
                    self.active[i] = self.active[self.active_len - 1];
                    self.active_len -= 1;
                }
                (Some(i), false) => self.active[i] = m,
                (None, false) if self.active_len < MAX_CONTACTS => {
                    self.active[self.active_len] = m;
                    self.active_len += 1;
                }
                _ => {}
            }
        }
        self.last_t = t;
        self.emitted += 1;
        sink.push(&self.out);
    }

    /// Ends every active contact as `CANCELLED` in one frame at `t` (if any).
    fn cancel(&mut self, t: Micros, sink: &mut dyn FrameSink) {
        if self.active_len == 0 {
            return;
        }
        self.out.clear();
        self.out.t = t;
        self.out.t_queued = Micros::ZERO;
        for a in &self.active[..self.active_len] {
            let mut c = *a;
            c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
            c.flags.insert(ContactFlags::CANCELLED);
            let _ = self.out.push(c);
        }
        self.active_len = 0;
        self.last_t = t;
        self.emitted += 1;
        sink.push(&self.out);
    }
}

/// Plays recordings into a [`FrameSink`].
#[derive(Clone, Debug)]
pub struct ReplaySource {
    items: Vec<ReplayItem>,
    spans: Vec<IdSpan>,
    looped: bool,
    gap: Micros,
    pacing: Pacing,
    state: PlayState,
}

impl ReplaySource {
    /// A source playing `items` in order, `gap` apart, forever when `looped`.
    ///
    /// Contact ids start at 1; see [`ReplaySource::with_first_id`].
    pub fn new(items: Vec<ReplayItem>, looped: bool, gap: Micros, pacing: Pacing) -> ReplaySource {
        let spans = items
            .iter()
            .map(|it| {
                let ids = it
                    .frames
                    .iter()
                    .flat_map(|f| f.contacts().iter().map(|c| c.id.0));
                let (min, max) =
                    ids.fold((u32::MAX, 0u32), |(lo, hi), id| (lo.min(id), hi.max(id)));
                if min > max {
                    IdSpan { min: 0, len: 0 }
                } else {
                    IdSpan {
                        min,
                        len: (max - min).saturating_add(1),
                    }
                }
            })
            .collect();
        ReplaySource {
            items,
            spans,
            looped,
            gap,
            pacing,
            state: PlayState {
                out: TouchFrame::default(),
                active: [Contact::default(); MAX_CONTACTS],
                active_len: 0,
                next_base: 1,
                emitted: 0,
                last_t: Micros::ZERO,
            },
        }
    }

    /// Starts contact ids at `first` (to keep them apart from another source's).
    pub fn with_first_id(mut self, first: u32) -> ReplaySource {
        self.state.next_base = first;
        self
    }

    /// The playlist.
    pub fn items(&self) -> &[ReplayItem] {
        &self.items
    }

    /// Frames emitted so far (cancel frames included).
    pub fn frames_emitted(&self) -> u64 {
        self.state.emitted
    }

    /// The id the next file's first contact will get.
    pub fn next_id(&self) -> u32 {
        self.state.next_base
    }

    /// Plays into `sink` until the end (forever when looped) or until `stop` is set.
    ///
    /// `on_item(index)` is called before each file starts. Returns right away
    /// when the playlist holds no frame at all. With [`Pacing::RealTime`] the
    /// stop flag is checked at least every [`STOP_POLL_US`]; with
    /// [`Pacing::Virtual`] before every frame.
    pub fn run(
        &mut self,
        sink: &mut dyn FrameSink,
        stop: &AtomicBool,
        on_item: &mut dyn FnMut(usize),
    ) {
        if self.items.iter().all(|it| it.frames.is_empty()) {
            return;
        }
        let start = match self.pacing {
            Pacing::RealTime => monotonic_now(),
            Pacing::Virtual => Micros::ZERO,
        };
        // Start of the current file, relative to `start`.
        let mut offset = Micros::ZERO;
        loop {
            for idx in 0..self.items.len() {
                if stop.load(Ordering::Relaxed) {
                    self.stop_now(sink);
                    return;
                }
                on_item(idx);
                let frames = &self.items[idx].frames;
                let (Some(first), Some(last)) = (frames.first(), frames.last()) else {
                    continue;
                };
                let (t0, duration) = (first.t, last.t.saturating_since(first.t));
                let span = self.spans[idx];
                let base = self.state.next_base;
                for f in frames {
                    let at = offset + f.t.saturating_since(t0);
                    let t = match self.pacing {
                        Pacing::RealTime => {
                            if !sleep_until(start + at, stop, sink) {
                                self.stop_now(sink);
                                return;
                            }
                            monotonic_now()
                        }
                        Pacing::Virtual => {
                            if stop.load(Ordering::Relaxed) {
                                self.stop_now(sink);
                                return;
                            }
                            at
                        }
                    };
                    self.state.emit(f, base, span, t, sink);
                }
                // A file cut mid-touch must not leak contacts into the next one.
                let end = match self.pacing {
                    Pacing::RealTime => monotonic_now(),
                    Pacing::Virtual => offset + duration,
                };
                self.state.cancel(end, sink);
                self.state.next_base = base.wrapping_add(span.len);
                offset = offset + duration + self.gap;
            }
            if !self.looped {
                return;
            }
        }
    }

    /// Cancels what is down, at the time the pacing gives for "now".
    fn stop_now(&mut self, sink: &mut dyn FrameSink) {
        let t = match self.pacing {
            Pacing::RealTime => monotonic_now(),
            Pacing::Virtual => self.state.last_t,
        };
        self.state.cancel(t, sink);
    }
}

/// Sleeps until `deadline` (CLOCK_MONOTONIC); `false` when `stop` was set first.
fn sleep_until(deadline: Micros, stop: &AtomicBool, sink: &mut dyn FrameSink) -> bool {
    loop {
        if stop.load(Ordering::Relaxed) {
            return false;
        }
        let now = monotonic_now();
        if now >= deadline {
            return true;
        }
        // Frames the sink held back go on as soon as it can take them, not with the
        // next frame of the recording.
        let poll = if sink.flush() {
            STOP_POLL_US
        } else {
            super::FLUSH_RETRY_US
        };
        let wait = deadline.saturating_since(now).0.min(poll);
        std::thread::sleep(Duration::from_micros(wait));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn frame(t: u64, contacts: &[(u32, ContactFlags)]) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t));
        for &(id, flags) in contacts {
            f.push(Contact {
                id: ContactId(id),
                x: 0.5,
                y: 0.5,
                flags,
                ..Contact::default()
            })
            .unwrap();
        }
        f
    }

    /// Two contacts: 1 from 0 to 20 ms, 2 from 10 to 20 ms.
    fn tap_item(name: &str) -> ReplayItem {
        ReplayItem::new(
            name,
            vec![
                frame(0, &[(1, ContactFlags::DOWN)]),
                frame(10_000, &[(1, ContactFlags::NONE), (2, ContactFlags::DOWN)]),
                frame(20_000, &[(1, ContactFlags::UP), (2, ContactFlags::UP)]),
            ],
        )
    }

    fn ids(frames: &[TouchFrame]) -> Vec<Vec<u32>> {
        frames
            .iter()
            .map(|f| f.contacts().iter().map(|c| c.id.0).collect())
            .collect()
    }

    #[test]
    fn virtual_playlist_times_and_ids() {
        let mut src = ReplaySource::new(
            vec![tap_item("a"), tap_item("b")],
            false,
            Micros(100_000),
            Pacing::Virtual,
        );
        let mut out: Vec<TouchFrame> = Vec::new();
        let mut started = Vec::new();
        src.run(&mut out, &AtomicBool::new(false), &mut |i| started.push(i));
        assert_eq!(started, vec![0, 1]);
        let ts: Vec<u64> = out.iter().map(|f| f.t.0).collect();
        assert_eq!(ts, vec![0, 10_000, 20_000, 120_000, 130_000, 140_000]);
        assert_eq!(
            ids(&out),
            vec![
                vec![1],
                vec![1, 2],
                vec![1, 2],
                vec![3],
                vec![3, 4],
                vec![3, 4]
            ]
        );
        assert_eq!(src.frames_emitted(), 6);
        assert_eq!(src.next_id(), 5);
    }

    /// A sink that raises `stop` after `n` frames.
    struct StopAfter<'a> {
        frames: Vec<TouchFrame>,
        n: usize,
        stop: &'a AtomicBool,
    }

    impl FrameSink for StopAfter<'_> {
        fn push(&mut self, frame: &TouchFrame) {
            self.frames.push(*frame);
            if self.frames.len() == self.n {
                self.stop.store(true, Ordering::Relaxed);
            }
        }
    }

    #[test]
    fn looped_ids_never_repeat_and_stop_cancels() {
        let stop = AtomicBool::new(false);
        let mut sink = StopAfter {
            frames: Vec::new(),
            n: 3 * 7 + 2,
            stop: &stop,
        };
        let mut src = ReplaySource::new(vec![tap_item("a")], true, Micros(5_000), Pacing::Virtual)
            .with_first_id(100);
        let mut items = 0;
        src.run(&mut sink, &stop, &mut |_| items += 1);
        assert_eq!(items, 8);
        let frames = sink.frames;
        // 7 whole loops, 2 frames of the 8th, then the cancel frame.
        assert_eq!(frames.len(), 3 * 7 + 3);
        let last = frames.last().unwrap();
        assert_eq!(last.t, frames[frames.len() - 2].t);
        assert!(last
            .contacts()
            .iter()
            .all(|c| c.flags == ContactFlags::CANCELLED));
        assert_eq!(last.len(), 2);
        // Every DOWN id is new.
        let mut seen = HashSet::new();
        for f in &frames {
            for c in f.contacts() {
                if c.flags.contains(ContactFlags::DOWN) {
                    assert!(seen.insert(c.id.0), "id {} reused", c.id.0);
                }
            }
        }
        assert_eq!(seen.len(), 16);
        assert_eq!(seen.iter().min(), Some(&100));
        // Virtual time keeps growing across loops: 20 ms file + 5 ms gap.
        assert_eq!(frames[3].t, Micros(25_000));
        assert!(frames.windows(2).all(|w| w[0].t <= w[1].t));
    }

    #[test]
    fn file_cut_mid_touch_is_cancelled_at_its_end() {
        let cut = ReplayItem::new(
            "cut",
            vec![
                frame(0, &[(7, ContactFlags::DOWN)]),
                frame(8_000, &[(7, ContactFlags::NONE)]),
            ],
        );
        let mut src =
            ReplaySource::new(vec![cut, tap_item("b")], false, Micros(0), Pacing::Virtual);
        let mut out: Vec<TouchFrame> = Vec::new();
        src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
        assert_eq!(out[2].t, Micros(8_000));
        assert_eq!(out[2].contacts()[0].flags, ContactFlags::CANCELLED);
        assert_eq!(out[2].contacts()[0].id, ContactId(1));
        assert_eq!(out[3].contacts()[0].id, ContactId(2));
        assert_eq!(out[3].t, Micros(8_000));
    }

    #[test]
    fn empty_playlist_returns() {
        let mut src = ReplaySource::new(
            vec![ReplayItem::new("e", Vec::new())],
            true,
            Micros(0),
            Pacing::Virtual,
        );
        let mut out: Vec<TouchFrame> = Vec::new();
        src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
        assert!(out.is_empty());
    }

    #[test]
    fn real_time_paces_and_stops_promptly() {
        let mut src = ReplaySource::new(vec![tap_item("a")], false, Micros(0), Pacing::RealTime);
        let mut out: Vec<TouchFrame> = Vec::new();
        let t0 = monotonic_now();
        src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
        assert_eq!(out.len(), 3);
        assert!(out[0].t >= t0);
        // Offsets are honoured (the sleep may overshoot, never undershoot).
        assert!(out[1].t.saturating_since(t0).0 >= 10_000);
        assert!(out[2].t.saturating_since(t0).0 >= 20_000);

        // A frame 10 s away; stop after 100 ms must end the run well before.
        let long = ReplayItem::new(
            "long",
            vec![
                frame(0, &[(1, ContactFlags::DOWN)]),
                frame(10_000_000, &[(1, ContactFlags::UP)]),
            ],
        );
        let mut src = ReplaySource::new(vec![long], false, Micros(0), Pacing::RealTime);
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let s2 = stop.clone();
        let h = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(100));
            s2.store(true, Ordering::Relaxed);
        });
        let mut out: Vec<TouchFrame> = Vec::new();
        let t0 = monotonic_now();
        src.run(&mut out, &stop, &mut |_| {});
        let took = monotonic_now().saturating_since(t0).0;
        h.join().unwrap();
        assert!(took < 1_000_000, "took {took} us");
        assert_eq!(out.len(), 2);
        assert_eq!(out[1].contacts()[0].flags, ContactFlags::CANCELLED);
    }
}
