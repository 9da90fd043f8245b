//! One client's queue: what the publisher thread and the I/O thread share about a
//! client, under one mutex.
//!
//! The publisher pushes snapshots, meshes, events, stats and command answers; the
//! I/O thread pushes hellos and its own replies, and pops what it writes. Neither
//! holds the mutex across I/O or encoding, so a push never waits on a socket.
//!
//! # Replies in order
//! Every command and every non-fatal error a client causes takes a *slot* in
//! [`Queue::replies`], in the order the client's lines were read. A command the
//! control thread will answer holds a pending slot; an answer given on the spot
//! ("busy", a malformed command) is a ready slot. Ready slots at the front go to the
//! stream; a ready slot behind a pending one waits for it. So a client's `ack` and
//! `error` replies come back in the order of its requests, whoever answers them.

use crate::publish::protocol::{self, ClientSettings, Format};
use crate::vocab::Micros;
use serde_json::Value;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Most non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_MESSAGES: usize = 4096;
/// Most bytes of non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_BYTES: usize = 16 << 20;
/// Time a closing client gets to read its last messages (`error`, `bye`).
pub const CLOSE_GRACE: Duration = Duration::from_secs(1);
/// A command the control thread has not answered after this long is answered with
/// an `error` (its reply was lost), so that the replies after it can go out.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(10);

/// A snapshot encoded once for every client with the same format and field set.
#[derive(Debug)]
pub(crate) struct EncodedSnapshot {
    /// Wire format of `bytes`.
    pub format: Format,
    /// JSON line (without the dropped digits) or binary frame (dropped = 0).
    pub bytes: Vec<u8>,
    /// JSON: where the dropped digits go. Binary: unused ([`protocol::BINARY_DROPPED_OFFSET`]).
    pub dropped_at: usize,
    /// Input timestamp, for end-to-end latency after the write.
    pub input_t: Option<Micros>,
}

/// One queued message.
#[derive(Debug)]
pub(crate) enum Item {
    /// A snapshot (droppable).
    Snapshot(Arc<EncodedSnapshot>),
    /// A mesh (replaced by a newer one while queued).
    Mesh {
        /// JSON line.
        json: Arc<[u8]>,
        /// Framing at its place in the stream.
        framing: Format,
        /// Whether `json` carries the triangles.
        with_triangles: bool,
    },
    /// Where the scene's moving things are (replaced by newer poses while queued).
    Poses {
        /// JSON line.
        json: Arc<[u8]>,
        /// Framing at its place in the stream.
        framing: Format,
    },
    /// Anything else (events, stats, replies, hello, bye): never dropped.
    Message {
        /// JSON line.
        json: Arc<[u8]>,
        /// Framing at its place in the stream.
        framing: Format,
    },
}

impl Item {
    fn backlog_bytes(&self) -> usize {
        match self {
            Item::Snapshot(_) => 0,
            Item::Mesh { json, .. } | Item::Poses { json, .. } | Item::Message { json, .. } => {
                json.len()
            }
        }
    }
}

/// The non-snapshot backlog passed its cap.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Overflow {
    messages: usize,
    bytes: usize,
}

impl std::fmt::Display for Overflow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "client is not reading: {} messages ({} bytes) waiting, more than the limit of {} messages or {} bytes; disconnecting",
            self.messages, self.bytes, MAX_BACKLOG_MESSAGES, MAX_BACKLOG_BYTES
        )
    }
}

/// A reply's place in the client's order of replies.
#[derive(Debug)]
enum Slot {
    /// Sent to the control thread at `since`; its answer has not come yet.
    Pending { id: Value, since: Instant },
    /// Answered; waits for the slots before it.
    Ready(Arc<[u8]>),
}

/// A client's queue and the per-client state the publisher and I/O thread share.
#[derive(Debug)]
pub(crate) struct Queue {
    items: VecDeque<Item>,
    snapshots: usize,
    backlog_messages: usize,
    backlog_bytes: usize,
    dropped_total: u64,
    dropped_unnotified: u64,
    replies: VecDeque<Slot>,
    /// What the client asked for.
    pub settings: ClientSettings,
    /// Earliest time (µs) the next snapshot may be queued under `max_rate_hz`.
    pub rate_next_due_us: u64,
    /// Topology of the last mesh queued with triangles.
    pub mesh_topology: Option<u64>,
    /// Set when the client is being closed: its queue is written out, then the socket shut.
    pub closing_since: Option<Instant>,
    /// Set when the connection is gone: nothing more is queued or written.
    pub dead: bool,
}

impl Queue {
    fn new() -> Queue {
        Queue {
            items: VecDeque::new(),
            snapshots: 0,
            backlog_messages: 0,
            backlog_bytes: 0,
            dropped_total: 0,
            dropped_unnotified: 0,
            replies: VecDeque::new(),
            settings: ClientSettings::default(),
            rate_next_due_us: 0,
            mesh_topology: None,
            closing_since: None,
            dead: false,
        }
    }

    /// Whether new stream messages should still be queued.
    pub fn accepting(&self) -> bool {
        !self.dead && self.closing_since.is_none()
    }

    /// Queues a snapshot; when more than `capacity` are queued the oldest is removed.
    /// Returns how many were dropped (0 or 1).
    pub fn push_snapshot(&mut self, enc: Arc<EncodedSnapshot>, capacity: usize) -> u64 {
        self.items.push_back(Item::Snapshot(enc));
        self.snapshots += 1;
        let mut dropped = 0;
        while self.snapshots > capacity.max(1) {
            match self
                .items
                .iter()
                .position(|i| matches!(i, Item::Snapshot(_)))
            {
                Some(at) => {
                    self.items.remove(at);
                    self.snapshots -= 1;
                    dropped += 1;
                }
                None => break,
            }
        }
        self.dropped_total += dropped;
        self.dropped_unnotified += dropped;
        dropped
    }

    /// Queues a non-snapshot message.
    ///
    /// # Errors
    /// [`Overflow`] when the backlog is over its cap; the caller should [`Queue::fail`].
    pub fn push_message(&mut self, json: Arc<[u8]>, framing: Format) -> Result<(), Overflow> {
        self.push_counted(Item::Message { json, framing })
    }

    /// Removes a queued (not yet written) mesh; returns whether it carried triangles.
    pub fn take_queued_mesh(&mut self) -> Option<bool> {
        let at = self
            .items
            .iter()
            .position(|i| matches!(i, Item::Mesh { .. }))?;
        let item = self.items.remove(at)?;
        self.uncount(&item);
        match item {
            Item::Mesh { with_triangles, .. } => Some(with_triangles),
            _ => None,
        }
    }

    /// Queues a mesh.
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn push_mesh(&mut self, json: Arc<[u8]>, with_triangles: bool) -> Result<(), Overflow> {
        let framing = self.settings.format;
        self.push_counted(Item::Mesh {
            json,
            framing,
            with_triangles,
        })
    }

    /// Queues a `scene_poses` line, in the place of one still queued: a client that
    /// reads slowly gets the newest poses, never a growing backlog of them.
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn push_poses(&mut self, json: Arc<[u8]>) -> Result<(), Overflow> {
        let framing = self.settings.format;
        if let Some(at) = self
            .items
            .iter()
            .position(|i| matches!(i, Item::Poses { .. }))
        {
            if let Some(old) = self.items.remove(at) {
                self.uncount(&old);
            }
        }
        self.push_counted(Item::Poses { json, framing })
    }

    fn push_counted(&mut self, item: Item) -> Result<(), Overflow> {
        self.backlog_messages += 1;
        self.backlog_bytes += item.backlog_bytes();
        self.items.push_back(item);
        if self.backlog_messages > MAX_BACKLOG_MESSAGES || self.backlog_bytes > MAX_BACKLOG_BYTES {
            Err(Overflow {
                messages: self.backlog_messages,
                bytes: self.backlog_bytes,
            })
        } else {
            Ok(())
        }
    }

    fn uncount(&mut self, item: &Item) {
        match item {
            Item::Snapshot(_) => self.snapshots -= 1,
            other => {
                self.backlog_messages -= 1;
                self.backlog_bytes -= other.backlog_bytes();
            }
        }
    }

    /// Takes the next message to write, with the drops not yet told to the client
    /// and the cumulative drop count.
    pub fn pop(&mut self) -> Option<(Item, u64, u64)> {
        let item = self.items.pop_front()?;
        self.uncount(&item);
        let unnotified = std::mem::take(&mut self.dropped_unnotified);
        Some((item, unnotified, self.dropped_total))
    }

    /// Discards everything queued, queues a fatal `error` and starts closing.
    pub fn fail(&mut self, message: &str) {
        self.items.clear();
        self.replies.clear();
        self.snapshots = 0;
        self.backlog_messages = 0;
        self.backlog_bytes = 0;
        let mut json = Vec::new();
        protocol::encode_error(None, message, true, &mut json);
        let framing = self.settings.format;
        let _ = self.push_counted(Item::Message {
            json: json.into(),
            framing,
        });
        self.closing_since.get_or_insert_with(Instant::now);
    }

    /// Queues a last message after everything queued and starts closing.
    pub fn close_with(&mut self, json: Arc<[u8]>) {
        let framing = self.settings.format;
        // A closing queue may exceed the cap by this one message.
        let _ = self.push_counted(Item::Message { json, framing });
        self.closing_since.get_or_insert_with(Instant::now);
    }

    /// Whether the client has been closing for longer than [`CLOSE_GRACE`].
    pub fn close_overdue(&self) -> bool {
        self.closing_since
            .is_some_and(|t| t.elapsed() >= CLOSE_GRACE)
    }

    /// Replies the client is owed or that wait for an earlier one.
    pub fn replies_waiting(&self) -> usize {
        self.replies.len()
    }

    /// Takes the next slot for a command sent to the control thread now; its
    /// answer comes through [`Queue::answer`].
    pub fn expect_reply(&mut self, id: Value, now: Instant) {
        self.replies.push_back(Slot::Pending { id, since: now });
    }

    /// Answers the command of the newest slot on the spot (it never reached the
    /// control thread: the command queue was full).
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn refuse_newest(&mut self, json: Arc<[u8]>) -> Result<(), Overflow> {
        match self.replies.back_mut() {
            Some(slot @ Slot::Pending { .. }) => *slot = Slot::Ready(json),
            _ => self.replies.push_back(Slot::Ready(json)),
        }
        self.release_replies()
    }

    /// Queues a reply given on the spot, after the replies owed before it.
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn reply(&mut self, json: Arc<[u8]>) -> Result<(), Overflow> {
        self.replies.push_back(Slot::Ready(json));
        self.release_replies()
    }

    /// The control thread's answer to command `id`: fills the oldest pending slot
    /// with that id (the control thread answers a client's commands in order) and
    /// releases the replies it held back. An answer no slot waits for (it came
    /// after [`REPLY_TIMEOUT`]) is discarded.
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn answer(&mut self, id: &Value, json: Arc<[u8]>) -> Result<(), Overflow> {
        let slot = self
            .replies
            .iter_mut()
            .find(|s| matches!(s, Slot::Pending { id: p, .. } if p == id));
        match slot {
            Some(slot) => *slot = Slot::Ready(json),
            None => return Ok(()),
        }
        self.release_replies()
    }

    /// Answers with an `error` every pending command older than [`REPLY_TIMEOUT`]
    /// at `now` that holds replies back at the front.
    ///
    /// # Errors
    /// As [`Queue::push_message`].
    pub fn expire_replies(&mut self, now: Instant) -> Result<(), Overflow> {
        while let Some(Slot::Pending { id, since }) = self.replies.front() {
            if now.saturating_duration_since(*since) < REPLY_TIMEOUT {
                break;
            }
            let mut json = Vec::new();
            let message = format!(
                "no answer from the daemon within {} s; the command may or may not have been applied",
                REPLY_TIMEOUT.as_secs()
            );
            protocol::encode_error(Some(id), &message, false, &mut json);
            self.replies[0] = Slot::Ready(json.into());
            self.release_replies()?;
        }
        Ok(())
    }

    /// Moves the ready replies at the front into the stream.
    fn release_replies(&mut self) -> Result<(), Overflow> {
        let mut result = Ok(());
        while let Some(Slot::Ready(_)) = self.replies.front() {
            let Some(Slot::Ready(json)) = self.replies.pop_front() else {
                break;
            };
            let framing = self.settings.format;
            result = result.and(self.push_message(json, framing));
        }
        result
    }
}

/// The settings a client may have: a read-only client never gets the raw touches.
pub(crate) fn restrict(mut settings: ClientSettings, privileged: bool) -> ClientSettings {
    settings.fields.touches &= privileged;
    settings
}

/// What the publisher and the I/O thread share about one client.
#[derive(Debug)]
pub(crate) struct ClientShared {
    /// The client's id.
    pub id: crate::vocab::ClientId,
    /// Whether the client is privileged (raw touches, commands); fixed at connect.
    pub privileged: bool,
    queue: Mutex<Queue>,
}

impl ClientShared {
    /// A new privileged client with default settings and an empty queue.
    #[cfg(test)]
    pub fn new(id: crate::vocab::ClientId) -> ClientShared {
        ClientShared::with_privilege(id, true)
    }

    /// A new client with default settings (a read-only client's without the raw
    /// touches) and an empty queue.
    pub fn with_privilege(id: crate::vocab::ClientId, privileged: bool) -> ClientShared {
        let mut q = Queue::new();
        q.settings = restrict(q.settings, privileged);
        ClientShared {
            id,
            privileged,
            queue: Mutex::new(q),
        }
    }

    /// Locks the queue.
    pub fn lock(&self) -> MutexGuard<'_, Queue> {
        super::stats::lock(&self.queue)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn enc(seq: u8) -> Arc<EncodedSnapshot> {
        Arc::new(EncodedSnapshot {
            format: Format::Json,
            bytes: vec![seq],
            dropped_at: 0,
            input_t: None,
        })
    }

    fn seqs(q: &Queue) -> Vec<u8> {
        q.items
            .iter()
            .map(|i| match i {
                Item::Snapshot(e) => e.bytes[0],
                _ => 0,
            })
            .collect()
    }

    /// The JSON lines queued as messages, in order.
    fn messages(q: &Queue) -> Vec<Value> {
        q.items
            .iter()
            .filter_map(|i| match i {
                Item::Message { json, .. } => Some(serde_json::from_slice(json).unwrap()),
                _ => None,
            })
            .collect()
    }

    fn line(v: Value) -> Arc<[u8]> {
        format!("{v}\n").into_bytes().into()
    }

    #[test]
    fn full_queue_drops_oldest_snapshot_only() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        q.push_snapshot(enc(1), 2);
        q.push_message(Arc::from(&b"{}\n"[..]), Format::Json)
            .unwrap();
        q.push_snapshot(enc(2), 2);
        assert_eq!(q.push_snapshot(enc(3), 2), 1);
        assert_eq!(seqs(&q), vec![0, 2, 3]);
        assert_eq!((q.dropped_total, q.dropped_unnotified), (1, 1));
        let (_, unnotified, total) = q.pop().unwrap();
        assert_eq!((unnotified, total), (1, 1));
        assert_eq!(q.dropped_unnotified, 0, "the drop is told once");
    }

    #[test]
    fn queued_mesh_is_replaced_and_remembers_triangles() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        q.push_mesh(Arc::from(&b"a"[..]), true).unwrap();
        assert_eq!(q.take_queued_mesh(), Some(true));
        assert_eq!(q.take_queued_mesh(), None);
        assert_eq!((q.backlog_messages, q.backlog_bytes), (0, 0));
    }

    #[test]
    fn queued_poses_are_replaced_by_newer_ones() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        q.push_poses(Arc::from(&b"p1\n"[..])).unwrap();
        q.push_message(Arc::from(&b"m\n"[..]), Format::Json)
            .unwrap();
        for _ in 0..10_000 {
            q.push_poses(Arc::from(&b"p2\n"[..])).unwrap();
        }
        assert_eq!((q.backlog_messages, q.backlog_bytes), (2, 5));
        let first = q.pop().unwrap().0;
        assert!(matches!(first, Item::Message { .. }));
        match q.pop().unwrap().0 {
            Item::Poses { json, .. } => assert_eq!(&json[..], b"p2\n"),
            other => panic!("{other:?}"),
        }
        assert!(q.pop().is_none());
    }

    #[test]
    fn backlog_cap_reports_overflow() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        let mut over = false;
        for _ in 0..=MAX_BACKLOG_MESSAGES {
            over |= q
                .push_message(Arc::from(&b"{}\n"[..]), Format::Json)
                .is_err();
        }
        assert!(over);
        q.fail("x");
        assert_eq!(q.items.len(), 1);
        assert!(q.closing_since.is_some());
    }

    #[test]
    fn replies_go_out_in_the_order_of_the_requests() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        let t = Instant::now();
        q.expect_reply(json!(1), t);
        q.expect_reply(json!(2), t);
        // A malformed command after them is answered on the spot, but waits.
        q.reply(line(json!({"type":"error","id":3}))).unwrap();
        q.expect_reply(json!(4), t);
        q.refuse_newest(line(json!({"type":"error","id":4,"busy":true})))
            .unwrap();
        assert!(messages(&q).is_empty());
        assert_eq!(q.replies_waiting(), 4);
        // The control thread answers 2 first? It cannot (it answers in order), but
        // an answer to a later slot still waits for the earlier ones.
        q.answer(&json!(2), line(json!({"type":"ack","id":2})))
            .unwrap();
        assert!(messages(&q).is_empty());
        q.answer(&json!(1), line(json!({"type":"ack","id":1})))
            .unwrap();
        let ids: Vec<Value> = messages(&q).iter().map(|m| m["id"].clone()).collect();
        assert_eq!(ids, vec![json!(1), json!(2), json!(3), json!(4)]);
        assert_eq!(q.replies_waiting(), 0);
        // An answer nobody waits for is discarded.
        q.answer(&json!(9), line(json!({"type":"ack","id":9})))
            .unwrap();
        assert_eq!(messages(&q).len(), 4);
    }

    #[test]
    fn a_lost_answer_times_out_and_releases_the_replies_behind_it() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        let t0 = Instant::now();
        q.expect_reply(json!("a"), t0);
        q.reply(line(json!({"type":"error","id":"b"}))).unwrap();
        q.expire_replies(t0 + REPLY_TIMEOUT / 2).unwrap();
        assert!(messages(&q).is_empty());
        q.expire_replies(t0 + REPLY_TIMEOUT).unwrap();
        let m = messages(&q);
        assert_eq!(m.len(), 2);
        assert_eq!(
            (m[0]["id"].clone(), m[0]["fatal"].clone()),
            (json!("a"), json!(false))
        );
        assert!(
            m[0]["message"].as_str().unwrap().contains("no answer"),
            "{}",
            m[0]
        );
        assert_eq!(m[1]["id"], "b");
        // The late answer finds no slot.
        q.answer(&json!("a"), line(json!({"type":"ack","id":"a"})))
            .unwrap();
        assert_eq!(messages(&q).len(), 2);
    }

    #[test]
    fn failing_forgets_the_replies_owed() {
        let s = ClientShared::new(1);
        let mut q = s.lock();
        q.expect_reply(json!(1), Instant::now());
        q.fail("bad");
        assert_eq!(q.replies_waiting(), 0);
        q.answer(&json!(1), line(json!({"type":"ack","id":1})))
            .unwrap();
        assert_eq!(messages(&q).len(), 1, "only the fatal error");
    }
}
