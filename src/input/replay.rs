//! Replaying recordings as a touch source.
//!
//! A [`ReplaySource`] plays a playlist of recordings into a [`FrameSink`], on the
//! input thread, as a simulated device would: frames are emitted at their
//! recorded offsets ([`Pacing::RealTime`]) or as fast as the sink takes them on a
//! virtual clock ([`Pacing::Virtual`], for tests and benchmarks). A recording is
//! either held in memory ([`ReplayItem::new`]) or read from its file a frame at a
//! time ([`ReplayItem::open`]), going back to the start to loop: a file of any
//! length is played in the same memory.
//!
//! # Gaps
//!
//! A gap between two frames is played for at most [`MAX_GAP_US`]: nothing
//! touches the surface in a gap, so a longer one (a pause in a recording, a
//! clock jump) is shortened to it, and the frames after it come that much
//! earlier. A frame that lists no contact while none is down carries nothing: it
//! is not emitted, so a run of them is one gap. With [`Pacing::RealTime`] the
//! input thread sleeps through a gap in steps of at most [`STOP_POLL_US`],
//! checking the stop flag.
//!
//! # Contact ids
//!
//! Every contact gets a fresh [`ContactId`] from one counter when it first
//! appears, whatever file and loop iteration it comes from: ids are unique across
//! files and loop iterations and never reused while the source runs (the 32-bit
//! space wraps only after about four billion contacts).
//!
//! # Ends
//!
//! Contacts still down when a file ends (a recording cut mid-touch) are ended
//! `CANCELLED` in one more frame at the file's last frame time, so no touch
//! leaks into the next file. When `stop` is set mid-file, the contacts down are
//! likewise emitted `CANCELLED` in a final frame. A file that fails to read on
//! (it changed on disk since it was checked) ends there, with a warning logged.
//!
//! # Real time
//!
//! The per-frame loop neither allocates nor locks: it copies each frame into one
//! preallocated [`TouchFrame`], remaps ids, and pushes it. Reading a file adds a
//! buffered `read` now and then; the crowdtouch JSON Lines, evemu and
//! hid-recorder readers reuse their buffers (the libinput record YAML reader
//! allocates its parser's scalars). Going back to a file's start reads its
//! header again, once per loop.

use super::recording::{OnBadFrame, RecordingError, RecordingIssue, RecordingStream};
use super::{FrameSink, SurfaceInfo};
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Longest sleep between two checks of the stop flag, in µs.
pub const STOP_POLL_US: u64 = 50_000;

/// Longest gap between two frames a replay plays, in µs (2 s); see the module doc.
pub const MAX_GAP_US: u64 = 2_000_000;

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

/// Where an item's frames come from.
#[derive(Debug)]
enum Frames {
    Memory(Vec<TouchFrame>),
    Stream(Box<RecordingStream>),
}

/// One recording of a playlist.
#[derive(Debug)]
pub struct ReplayItem {
    name: String,
    frames: Frames,
}

impl ReplayItem {
    /// An item from a name and its frames, held in memory (time relative to the
    /// start of the recording).
    pub fn new(name: impl Into<String>, frames: Vec<TouchFrame>) -> ReplayItem {
        ReplayItem {
            name: name.into(),
            frames: Frames::Memory(frames),
        }
    }

    /// An item read from `stream` a frame at a time, from its start.
    pub fn stream(name: impl Into<String>, stream: RecordingStream) -> ReplayItem {
        ReplayItem {
            name: name.into(),
            frames: Frames::Stream(Box::new(stream)),
        }
    }

    /// Opens a recording (or the shipped one of that name, as
    /// [`RecordingStream::load`]) and reads it through once, so that a bad frame
    /// is found before it is played; returns the item, ready at its start, the
    /// recorded surface and the warnings of the reading.
    ///
    /// # Errors
    /// What reading the file reports, at its line.
    pub fn open(
        path: &Path,
        on_bad: OnBadFrame,
    ) -> Result<(ReplayItem, SurfaceInfo, Vec<RecordingIssue>), RecordingError> {
        let mut stream = RecordingStream::load(path, on_bad)?;
        let mut warnings = Vec::new();
        while stream.next_frame()?.is_some() {
            warnings.append(&mut stream.take_warnings());
        }
        warnings.append(&mut stream.take_warnings());
        stream.rewind()?;
        let surface = stream.surface().clone();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| path.display().to_string());
        Ok((ReplayItem::stream(name, stream), surface, warnings))
    }

    /// A name for logs (usually the file name).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether the item is known to hold no frame.
    fn is_empty(&self) -> bool {
        matches!(&self.frames, Frames::Memory(f) if f.is_empty())
    }
}

/// What the playing loop mutates; kept apart from the items it reads.
#[derive(Clone, Debug)]
struct PlayState {
    out: TouchFrame,
    /// Remapped contacts currently down, and their ids in their file.
    active: [Contact; MAX_CONTACTS],
    active_file_id: [u32; MAX_CONTACTS],
    active_len: usize,
    /// The id the next new contact gets.
    next_id: u32,
    emitted: u64,
    /// Time stamped on the last emitted frame.
    last_t: Micros,
}

impl PlayState {
    /// Emits `f` at `t` with its contacts' ids remapped.
    fn emit(&mut self, f: &TouchFrame, t: Micros, sink: &mut dyn FrameSink) {
        self.out.clear();
        self.out.t = t;
        self.out.t_queued = Micros::ZERO;
        self.out.device = f.device;
        for c in f.contacts() {
            let mut m = *c;
            let pos = self.active_file_id[..self.active_len]
                .iter()
                .position(|&id| id == c.id.0);
            m.id = match pos {
                Some(i) => self.active[i].id,
                None => {
                    let id = ContactId(self.next_id);
                    self.next_id = self.next_id.wrapping_add(1);
                    id
                }
            };
            // Cannot overflow: `f` held no more than MAX_CONTACTS.
            let _ = self.out.push(m);
            match (pos, m.flags.ended()) {
                (Some(i), true) => {
                    let last = self.active_len - 1;
                    self.active[i] = self.active[last];
                    self.active_file_id[i] = self.active_file_id[last];
                    self.active_len = last;
                }
                (Some(i), false) => self.active[i] = m,
                (None, false) if self.active_len < MAX_CONTACTS => {
                    self.active[self.active_len] = m;
                    self.active_file_id[self.active_len] = c.id.0;
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

/// The frames of one item, one at a time.
enum ItemFrames<'a> {
    Memory(std::slice::Iter<'a, TouchFrame>),
    Stream(&'a mut RecordingStream),
}

impl ItemFrames<'_> {
    fn next(&mut self) -> Result<Option<&TouchFrame>, RecordingError> {
        match self {
            ItemFrames::Memory(it) => Ok(it.next()),
            ItemFrames::Stream(s) => s.next_frame(),
        }
    }
}

/// How playing one item ended.
enum ItemEnd {
    /// Played through; the time played, from the item's start to its last frame.
    Done(Micros),
    /// `stop` was set.
    Stopped,
}

/// Plays recordings into a [`FrameSink`].
#[derive(Debug)]
pub struct ReplaySource {
    items: Vec<ReplayItem>,
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
        ReplaySource {
            items,
            looped,
            gap,
            pacing,
            state: PlayState {
                out: TouchFrame::default(),
                active: [Contact::default(); MAX_CONTACTS],
                active_file_id: [0; MAX_CONTACTS],
                active_len: 0,
                next_id: 1,
                emitted: 0,
                last_t: Micros::ZERO,
            },
        }
    }

    /// Starts contact ids at `first` (to keep them apart from another source's).
    pub fn with_first_id(mut self, first: u32) -> ReplaySource {
        self.state.next_id = first;
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

    /// The id the next new contact will get.
    pub fn next_id(&self) -> u32 {
        self.state.next_id
    }

    /// Plays into `sink` until the end (forever when looped) or until `stop` is set.
    ///
    /// `on_item(index)` is called before each file starts. Returns right away
    /// when the playlist holds no frame at all (also when a whole pass over it
    /// emitted none). With [`Pacing::RealTime`] the stop flag is checked at least
    /// every [`STOP_POLL_US`]; with [`Pacing::Virtual`] before every frame.
    pub fn run(
        &mut self,
        sink: &mut dyn FrameSink,
        stop: &AtomicBool,
        on_item: &mut dyn FnMut(usize),
    ) {
        if self.items.iter().all(ReplayItem::is_empty) {
            return;
        }
        let start = match self.pacing {
            Pacing::RealTime => monotonic_now(),
            Pacing::Virtual => Micros::ZERO,
        };
        // Start of the current file, relative to `start`.
        let mut offset = Micros::ZERO;
        loop {
            let emitted_before = self.state.emitted;
            for idx in 0..self.items.len() {
                if stop.load(Ordering::Relaxed) {
                    self.stop_now(sink);
                    return;
                }
                on_item(idx);
                let played = match self.play_item(idx, start, offset, sink, stop) {
                    ItemEnd::Done(played) => played,
                    ItemEnd::Stopped => {
                        self.stop_now(sink);
                        return;
                    }
                };
                // A file cut mid-touch must not leak contacts into the next one.
                let end = match self.pacing {
                    Pacing::RealTime => monotonic_now(),
                    Pacing::Virtual => offset + played,
                };
                self.state.cancel(end, sink);
                offset = offset + played + self.gap;
            }
            if !self.looped || self.state.emitted == emitted_before {
                return;
            }
        }
    }

    /// Plays item `idx`, starting `offset` after `start`.
    fn play_item(
        &mut self,
        idx: usize,
        start: Micros,
        offset: Micros,
        sink: &mut dyn FrameSink,
        stop: &AtomicBool,
    ) -> ItemEnd {
        let ReplaySource {
            items,
            pacing,
            state,
            ..
        } = self;
        let item = &mut items[idx];
        let mut frames = match &mut item.frames {
            Frames::Memory(f) => ItemFrames::Memory(f.iter()),
            Frames::Stream(s) => {
                if s.frames_read() > 0 {
                    if let Err(e) = s.rewind() {
                        log::warn!("replay of {}: {e}; the file is skipped", item.name);
                        return ItemEnd::Done(Micros::ZERO);
                    }
                }
                ItemFrames::Stream(s)
            }
        };
        // Time played since the item's start, and the recorded time it stands for.
        let mut played = Micros::ZERO;
        let mut prev: Option<Micros> = None;
        loop {
            let f = match frames.next() {
                Ok(Some(f)) => f,
                Ok(None) => break,
                Err(e) => {
                    log::warn!("replay of {}: {e}; the file ends here", item.name);
                    break;
                }
            };
            let prev_t = *prev.get_or_insert(f.t);
            if f.is_empty() && state.active_len == 0 {
                continue;
            }
            played = played + Micros(f.t.saturating_since(prev_t).0.min(MAX_GAP_US));
            prev = Some(f.t);
            let at = offset + played;
            let t = match pacing {
                Pacing::RealTime => {
                    if !sleep_until(start + at, stop, sink) {
                        return ItemEnd::Stopped;
                    }
                    monotonic_now()
                }
                Pacing::Virtual => {
                    if stop.load(Ordering::Relaxed) {
                        return ItemEnd::Stopped;
                    }
                    at
                }
            };
            state.emit(f, t, sink);
        }
        if let ItemFrames::Stream(s) = frames {
            // Noted when the file was opened; not repeated on every loop.
            drop(s.take_warnings());
        }
        ItemEnd::Done(played)
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
    use std::path::Path;

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

    #[test]
    fn a_long_gap_is_shortened_and_empty_frames_are_not_emitted() {
        let gapped = ReplayItem::new(
            "gapped",
            vec![
                frame(0, &[]),
                frame(300_000, &[(1, ContactFlags::DOWN)]),
                frame(310_000, &[(1, ContactFlags::NONE)]),
                frame(1_000_000_000_000, &[(1, ContactFlags::UP)]),
                frame(1_000_000_008_000, &[]),
                frame(u64::MAX, &[]),
                frame(u64::MAX, &[(2, ContactFlags::DOWN | ContactFlags::UP)]),
            ],
        );
        let mut src = ReplaySource::new(vec![gapped], false, Micros(0), Pacing::Virtual);
        let mut out: Vec<TouchFrame> = Vec::new();
        src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
        let ts: Vec<u64> = out.iter().map(|f| f.t.0).collect();
        // The lead-in before the first touch is kept; the gaps are shortened.
        assert_eq!(
            ts,
            vec![
                300_000,
                310_000,
                310_000 + MAX_GAP_US,
                310_000 + 2 * MAX_GAP_US
            ]
        );
        assert_eq!(ids(&out), vec![vec![1], vec![1], vec![1], vec![2]]);
    }

    #[test]
    fn real_time_plays_a_huge_gap_in_bounded_time_and_stays_stoppable() {
        let long = || {
            ReplayItem::new(
                "long",
                vec![
                    frame(0, &[(1, ContactFlags::DOWN)]),
                    frame(u64::MAX, &[(1, ContactFlags::UP)]),
                ],
            )
        };
        let mut src = ReplaySource::new(vec![long()], false, Micros(0), Pacing::RealTime);
        let mut out: Vec<TouchFrame> = Vec::new();
        let t0 = monotonic_now();
        src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
        let took = monotonic_now().saturating_since(t0).0;
        assert_eq!(out.len(), 2);
        // The gap is waited out (never less), and does not hang: 2 s, not ages.
        assert!((MAX_GAP_US..10_000_000).contains(&took), "took {took} us");
        // Stop during the gap: the thread does not sleep it out.
        let mut src = ReplaySource::new(vec![long()], true, Micros(0), Pacing::RealTime);
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
        assert!(took < MAX_GAP_US, "took {took} us");
        assert_eq!(
            out.last().unwrap().contacts()[0].flags,
            ContactFlags::CANCELLED
        );
    }

    #[test]
    fn a_streamed_file_loops_by_rewinding() {
        let text = concat!(
            r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":0,"max":100},"y":{"min":0,"max":100},"max_contacts":2}}"#,
            "\n",
            r#"{"t_us":0,"contacts":[{"id":4,"x":10,"y":10}]}"#,
            "\n",
            r#"{"t_us":9000,"contacts":[{"id":4,"x":20,"y":10},{"id":5,"x":1,"y":1}]}"#,
            "\n",
            r#"{"t_us":18000,"contacts":[{"id":5,"x":2,"y":2}]}"#,
            "\n",
        );
        let stream = RecordingStream::from_bytes(
            text.as_bytes().to_vec(),
            Path::new("loop.jsonl"),
            OnBadFrame::Stop,
        )
        .unwrap();
        let stop = AtomicBool::new(false);
        // Three loops of 4 frames (the last one cancels id 5).
        let mut sink = StopAfter {
            frames: Vec::new(),
            n: 12,
            stop: &stop,
        };
        let mut src = ReplaySource::new(
            vec![ReplayItem::stream("loop", stream)],
            true,
            Micros(1_000),
            Pacing::Virtual,
        );
        let mut started = 0;
        src.run(&mut sink, &stop, &mut |_| started += 1);
        let frames = sink.frames;
        assert_eq!(frames.len(), 12);
        for k in 0..3 {
            let base = 2 * k as u32;
            let loop_ids = &ids(&frames[4 * k..4 * k + 4]);
            assert_eq!(
                loop_ids,
                &vec![
                    vec![base + 1],
                    vec![base + 1, base + 2],
                    vec![base + 1, base + 2],
                    vec![base + 2]
                ]
            );
            // 18 ms of frames, the reader's cancel 1 ms later, then the 1 ms gap.
            assert_eq!(frames[4 * k].t, Micros(k as u64 * 20_000));
        }
        assert_eq!(frames[3].contacts()[0].flags, ContactFlags::CANCELLED);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(0x9a95), failure_persistence: None, ..proptest::prelude::ProptestConfig::default() })]

        /// Any timestamps up to `u64::MAX`: a virtual replay ends, stamps never
        /// go back, no gap between emitted frames is longer than [`MAX_GAP_US`]
        /// (plus the pause between files, where a file's lead-in follows it).
        #[test]
        fn any_timestamps_play_with_bounded_gaps(
            steps in proptest::collection::vec((proptest::prop_oneof![0u64..100_000, proptest::prelude::any::<u64>()], 0u8..3), 1..16),
            looped_gap in 0u64..3_000_000,
        ) {
            let mut t = 0u64;
            let mut frames = Vec::new();
            let mut down = false;
            for (dt, what) in steps {
                t = t.saturating_add(dt);
                let f = match (down, what) {
                    (false, 0) => frame(t, &[]),
                    (false, _) => {
                        down = true;
                        frame(t, &[(1, ContactFlags::DOWN)])
                    }
                    (true, 0) => frame(t, &[(1, ContactFlags::NONE)]),
                    (true, _) => {
                        down = false;
                        frame(t, &[(1, ContactFlags::UP)])
                    }
                };
                frames.push(f);
            }
            let mut src = ReplaySource::new(
                vec![ReplayItem::new("a", frames.clone()), ReplayItem::new("b", frames)],
                false,
                Micros(looped_gap),
                Pacing::Virtual,
            );
            let mut out: Vec<TouchFrame> = Vec::new();
            src.run(&mut out, &AtomicBool::new(false), &mut |_| {});
            for w in out.windows(2) {
                proptest::prop_assert!(w[0].t <= w[1].t);
                proptest::prop_assert!(w[1].t.0 - w[0].t.0 <= MAX_GAP_US + looped_gap);
            }
        }
    }
}
