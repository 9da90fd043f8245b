//! The input → control queue: a bounded channel whose full-queue policy keeps every
//! touch-down and lift, and gives contacts their daemon-wide ids.

use crate::input::FrameSink;
use crate::rt::monotonic_now;
use crate::vocab::{TouchFrame, MAX_CONTACTS};
use crossbeam_channel::{Sender, TrySendError};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;

/// Frames the input thread holds back while the queue is full (its own memory,
/// allocated once).
pub const BACKLOG_FRAMES: usize = 256;

/// Counters of the input side, shared lock-free with the control thread.
#[derive(Debug, Default)]
pub struct InputCounters {
    /// Frames handed to the queue (or merged into one that was).
    pub frames: AtomicU64,
    /// Motion-only frames merged into a held-back frame because the queue was full.
    pub coalesced: AtomicU64,
    /// Touch-downs or lifts that could not be delivered (frame overflow while
    /// merging); the design keeps this at zero.
    pub transitions_lost: AtomicU64,
    /// Times the queue was found full.
    pub queue_full: AtomicU64,
    /// Contacts that appeared without a touch-down (a source bug); given fresh ids.
    pub contacts_without_down: AtomicU64,
    /// The last contact id handed out; ids are unique across every source and never
    /// reused while the daemon runs.
    pub last_contact_id: AtomicU32,
}

/// The input side of the input → control queue: a [`FrameSink`] for one source.
///
/// Channel policy: `bounded(queue_frames)`, input thread only `try_send`s, control
/// thread `recv`s. When the queue is full, frames wait in a fixed backlog on the
/// input thread; a frame that only moves contacts is merged into the newest held-back
/// frame, and when the backlog is full every new frame is merged into its newest
/// entry. Merging keeps every touch-down and lift (see [`TouchFrame::merge_later`]),
/// so transitions are never lost; only intermediate positions are.
///
/// The queue also gives contacts their daemon-wide ids: a source numbers its contacts
/// as it likes (unique while they are down); each touch-down gets the next id from
/// [`InputCounters::last_contact_id`], so ids are unique across devices, re-plugs and
/// replay loops, and never reused while the daemon runs.
pub struct FrameQueue {
    tx: Sender<TouchFrame>,
    ring: Vec<TouchFrame>,
    head: usize,
    len: usize,
    device: u16,
    counters: Arc<InputCounters>,
    /// Source id → daemon id of the contacts down, in a fixed table.
    ids: [(u32, u32); ID_MAP_CAPACITY],
    ids_len: usize,
}

/// Contacts one source may have down at once (twice a frame's capacity: ends and
/// begins of one frame).
const ID_MAP_CAPACITY: usize = 2 * MAX_CONTACTS;

impl FrameQueue {
    /// A sink for device index `device` feeding `tx`.
    pub fn new(tx: Sender<TouchFrame>, device: u16, counters: Arc<InputCounters>) -> FrameQueue {
        FrameQueue {
            tx,
            ring: vec![TouchFrame::default(); BACKLOG_FRAMES],
            head: 0,
            len: 0,
            device,
            counters,
            ids: [(0, 0); ID_MAP_CAPACITY],
            ids_len: 0,
        }
    }

    fn fresh_id(&self) -> u32 {
        self.counters
            .last_contact_id
            .fetch_add(1, Ordering::Relaxed)
            .wrapping_add(1)
    }

    /// Rewrites the frame's contact ids into daemon-wide ids.
    fn map_ids(&mut self, f: &mut TouchFrame) {
        for c in f.contacts_mut() {
            let local = c.id.0;
            let found = self.ids[..self.ids_len]
                .iter()
                .position(|&(l, _)| l == local);
            let begins = c.flags.contains(crate::vocab::ContactFlags::DOWN);
            let slot = match (found, begins) {
                (Some(i), false) => i,
                (found, _) => {
                    if !begins {
                        self.counters
                            .contacts_without_down
                            .fetch_add(1, Ordering::Relaxed);
                    }
                    let id = self.fresh_id();
                    match found {
                        // A source reusing an id for a new touch: the old one has ended.
                        Some(i) => {
                            self.ids[i].1 = id;
                            i
                        }
                        None if self.ids_len < ID_MAP_CAPACITY => {
                            self.ids[self.ids_len] = (local, id);
                            self.ids_len += 1;
                            self.ids_len - 1
                        }
                        None => {
                            // Table full (a source that never ends its contacts): drop
                            // the oldest mapping to stay allocation-free.
                            self.ids.copy_within(1..ID_MAP_CAPACITY, 0);
                            self.ids[ID_MAP_CAPACITY - 1] = (local, id);
                            ID_MAP_CAPACITY - 1
                        }
                    }
                }
            };
            c.id = crate::vocab::ContactId(self.ids[slot].1);
            if c.flags.ended() {
                self.ids.copy_within(slot + 1..self.ids_len, slot);
                self.ids_len -= 1;
            }
        }
    }

    /// Frames currently held back.
    pub fn backlog(&self) -> usize {
        self.len
    }

    /// Tries to hand held-back frames on; returns whether the backlog is empty.
    pub fn flush(&mut self) -> bool {
        while self.len > 0 {
            match self.tx.try_send(self.ring[self.head]) {
                Ok(()) => {
                    self.head = (self.head + 1) % BACKLOG_FRAMES;
                    self.len -= 1;
                }
                Err(TrySendError::Full(_)) => return false,
                Err(TrySendError::Disconnected(_)) => {
                    self.len = 0;
                    return true;
                }
            }
        }
        true
    }

    fn newest(&mut self) -> &mut TouchFrame {
        let i = (self.head + self.len - 1) % BACKLOG_FRAMES;
        &mut self.ring[i]
    }

    fn hold(&mut self, f: &TouchFrame) {
        if self.len > 0 && (!f.has_transitions() || self.len == BACKLOG_FRAMES) {
            self.counters.coalesced.fetch_add(1, Ordering::Relaxed);
            if self.newest().merge_later(f).is_err() {
                self.counters
                    .transitions_lost
                    .fetch_add(1, Ordering::Relaxed);
            }
            return;
        }
        let i = (self.head + self.len) % BACKLOG_FRAMES;
        self.ring[i] = *f;
        self.len += 1;
    }
}

impl FrameSink for FrameQueue {
    fn flush(&mut self) -> bool {
        FrameQueue::flush(self)
    }

    fn push(&mut self, frame: &TouchFrame) {
        let mut f = *frame;
        self.map_ids(&mut f);
        f.device = self.device;
        f.t_queued = monotonic_now();
        self.counters.frames.fetch_add(1, Ordering::Relaxed);
        if self.flush() {
            match self.tx.try_send(f) {
                Ok(()) | Err(TrySendError::Disconnected(_)) => (),
                Err(TrySendError::Full(back)) => {
                    self.counters.queue_full.fetch_add(1, Ordering::Relaxed);
                    self.hold(&back);
                }
            }
        } else {
            self.counters.queue_full.fetch_add(1, Ordering::Relaxed);
            self.hold(&f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::Micros;
    use crate::vocab::{Contact, ContactFlags, ContactId};
    use crossbeam_channel::bounded;

    fn frame(t: u64, contacts: &[(u32, f32, ContactFlags)]) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t));
        for &(id, x, flags) in contacts {
            f.push(Contact {
                id: ContactId(id),
                x,
                y: 0.5,
                flags,
                ..Contact::default()
            })
            .unwrap();
        }
        f
    }

    /// Reconstructs which contacts went down and up from delivered frames.
    fn transitions(frames: &[TouchFrame]) -> (Vec<u32>, Vec<u32>) {
        let (mut downs, mut ups) = (vec![], vec![]);
        for f in frames {
            for c in f.contacts() {
                if c.flags.contains(ContactFlags::DOWN) {
                    downs.push(c.id.0);
                }
                if c.flags.ended() {
                    ups.push(c.id.0);
                }
            }
        }
        (downs, ups)
    }

    #[test]
    fn full_queue_coalesces_motion_but_keeps_every_transition() {
        let (tx, rx) = bounded(2);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        let mut sent = vec![];
        // 50 contacts, each: down, 20 moves, up — 1100 frames into a queue of 2 that
        // nobody reads until the end.
        let mut t = 0;
        for id in 1..=50u32 {
            sent.push(frame(t, &[(id, 0.0, ContactFlags::DOWN)]));
            for k in 0..20 {
                t += 1;
                sent.push(frame(t, &[(id, k as f32 / 20.0, ContactFlags::NONE)]));
            }
            t += 1;
            sent.push(frame(t, &[(id, 1.0, ContactFlags::UP)]));
        }
        for f in &sent {
            q.push(f);
        }
        let mut got: Vec<TouchFrame> = vec![];
        loop {
            while let Ok(f) = rx.try_recv() {
                got.push(f);
            }
            if q.flush() {
                break;
            }
        }
        while let Ok(f) = rx.try_recv() {
            got.push(f);
        }
        let (downs, ups) = transitions(&got);
        assert_eq!(downs, (1..=50).collect::<Vec<_>>());
        assert_eq!(ups, (1..=50).collect::<Vec<_>>());
        assert!(got.len() < sent.len(), "motion should have been coalesced");
        assert!(counters.coalesced.load(Ordering::Relaxed) > 0);
        assert_eq!(counters.transitions_lost.load(Ordering::Relaxed), 0);
        // Time order is kept.
        assert!(got.windows(2).all(|w| w[0].t <= w[1].t));
    }

    #[test]
    fn contact_ids_are_unique_across_sources_and_reuse() {
        let (tx, rx) = bounded(64);
        let counters = Arc::new(InputCounters::default());
        let mut a = FrameQueue::new(tx.clone(), 0, Arc::clone(&counters));
        let mut b = FrameQueue::new(tx, 1, Arc::clone(&counters));
        // Both sources call their first contact 1, and reuse 1 after a lift.
        for q in [&mut a, &mut b] {
            q.push(&frame(0, &[(1, 0.1, ContactFlags::DOWN)]));
            q.push(&frame(1, &[(1, 0.2, ContactFlags::NONE)]));
            q.push(&frame(2, &[(1, 0.2, ContactFlags::UP)]));
            q.push(&frame(3, &[(1, 0.3, ContactFlags::DOWN)]));
            q.push(&frame(4, &[(1, 0.3, ContactFlags::CANCELLED)]));
        }
        let got: Vec<TouchFrame> = rx.try_iter().collect();
        let ids: Vec<(u16, u32)> = got
            .iter()
            .map(|f| (f.device, f.contacts()[0].id.0))
            .collect();
        assert_eq!(
            ids,
            vec![
                (0, 1),
                (0, 1),
                (0, 1),
                (0, 2),
                (0, 2),
                (1, 3),
                (1, 3),
                (1, 3),
                (1, 4),
                (1, 4)
            ]
        );
        assert_eq!(counters.contacts_without_down.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn backlog_overflow_merges_transitions_instead_of_dropping_them() {
        let (tx, rx) = bounded(1);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        // The backlog holds BACKLOG_FRAMES frames; later frames merge into its newest
        // entry, which holds up to MAX_CONTACTS contacts.
        let n = (BACKLOG_FRAMES / 2 + 40) as u32;
        for id in 1..=n {
            q.push(&frame(id as u64 * 2, &[(id, 0.5, ContactFlags::DOWN)]));
            q.push(&frame(id as u64 * 2 + 1, &[(id, 0.5, ContactFlags::UP)]));
        }
        let mut got = vec![];
        loop {
            while let Ok(f) = rx.try_recv() {
                got.push(f);
            }
            if q.flush() {
                break;
            }
        }
        while let Ok(f) = rx.try_recv() {
            got.push(f);
        }
        let (downs, ups) = transitions(&got);
        assert_eq!(downs.len() as u32, n);
        assert_eq!(ups.len() as u32, n);
        assert_eq!(counters.transitions_lost.load(Ordering::Relaxed), 0);
    }

    /// Found by the hardware-in-the-loop overload scenario: after a burst filled the
    /// queue, the last frame (a lift) stayed in the backlog until the next touch,
    /// because the reader only flushed when it pushed. A waiting reader now retries
    /// the backlog at `FLUSH_RETRY_US` and only then blocks for `STOP_CHECK_US`.
    #[test]
    fn a_waiting_reader_hands_on_held_frames_without_new_input() {
        use crate::input::{reader_timeout_ms, FrameSink, FLUSH_RETRY_US, STOP_CHECK_US};
        let (tx, rx) = bounded(1);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        q.push(&frame(1, &[(1, 0.5, ContactFlags::DOWN)]));
        q.push(&frame(2, &[(1, 0.5, ContactFlags::UP)]));
        assert_eq!(q.backlog(), 1, "the lift waits behind a full queue");
        // The consumer is still busy: the reader waits only briefly.
        assert_eq!(u64::from(reader_timeout_ms(&mut q)), FLUSH_RETRY_US / 1000);
        let first = rx.try_recv().unwrap();
        assert!(first.contacts()[0].flags.contains(ContactFlags::DOWN));
        // The consumer took a frame: the next wait hands the lift on by itself.
        assert_eq!(u64::from(reader_timeout_ms(&mut q)), STOP_CHECK_US / 1000);
        assert_eq!(q.backlog(), 0);
        let lift = rx
            .try_recv()
            .expect("the held lift reaches the control thread");
        assert!(lift.contacts()[0].flags.ended());
        assert!(FrameSink::flush(&mut q));
    }
}
