//! One connected client: its queue, its writer thread and its reader thread.
//!
//! The queue is a `VecDeque` under a mutex with a condvar. The publisher thread and
//! the reader push, the writer pops; the mutex is never held across I/O, so a push
//! never waits on a socket. The writer turns queue items into bytes for this client
//! (splicing in its own `dropped` count) and writes them with blocking I/O.

use super::stats::{lock, PublisherStats};
use crate::publish::protocol::{self, ClientMessage, ClientSettings, Format, ServerHello};
use crate::vocab::Micros;
use crate::vocab::{ClientId, CommandRequest, MeshView};
use crossbeam_channel::{Sender, TrySendError};
use std::collections::VecDeque;
use std::io::{BufRead, BufReader, ErrorKind, Read};
use std::net::Shutdown;
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// Most non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_MESSAGES: usize = 4096;
/// Most bytes of non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_BYTES: usize = 16 << 20;
/// Time a closing client gets to read its last messages (`error`, `bye`).
pub const CLOSE_GRACE: Duration = Duration::from_secs(1);

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
            Item::Mesh { json, .. } | Item::Message { json, .. } => json.len(),
        }
    }

    fn framing(&self) -> Format {
        match self {
            Item::Snapshot(e) => e.format,
            Item::Mesh { framing, .. } | Item::Message { framing, .. } => *framing,
        }
    }
}

/// The non-snapshot backlog passed its cap.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Overflow {
    messages: usize,
    bytes: usize,
}

/// A client's queue and the per-client state the publisher and reader share.
#[derive(Debug)]
pub(crate) struct Queue {
    items: VecDeque<Item>,
    snapshots: usize,
    backlog_messages: usize,
    backlog_bytes: usize,
    dropped_total: u64,
    dropped_unnotified: u64,
    /// What the client asked for.
    pub settings: ClientSettings,
    /// Earliest time (µs) the next snapshot may be queued under `max_rate_hz`.
    pub rate_next_due_us: u64,
    /// Topology of the last mesh queued with triangles.
    pub mesh_topology: Option<u64>,
    /// Set when the client is being closed: its queue is written out, then the socket shut.
    pub closing_since: Option<Instant>,
    /// Set when the writer has finished (socket shut or failed).
    pub dead: bool,
}

impl Queue {
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

    /// Discards everything queued, queues a fatal `error` and starts closing.
    pub fn fail(&mut self, message: &str) {
        self.items.clear();
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

/// What the publisher, the reader and the writer of one client share.
#[derive(Debug)]
pub(crate) struct ClientShared {
    /// The client's id.
    pub id: ClientId,
    queue: Mutex<Queue>,
    ready: Condvar,
}

impl ClientShared {
    /// A new client with default settings and an empty queue.
    pub fn new(id: ClientId) -> ClientShared {
        ClientShared {
            id,
            queue: Mutex::new(Queue {
                items: VecDeque::new(),
                snapshots: 0,
                backlog_messages: 0,
                backlog_bytes: 0,
                dropped_total: 0,
                dropped_unnotified: 0,
                settings: ClientSettings::default(),
                rate_next_due_us: 0,
                mesh_topology: None,
                closing_since: None,
                dead: false,
            }),
            ready: Condvar::new(),
        }
    }

    /// Locks the queue.
    pub fn lock(&self) -> MutexGuard<'_, Queue> {
        lock(&self.queue)
    }

    /// Wakes the writer.
    pub fn notify(&self) {
        self.ready.notify_one();
    }

    /// Marks the client dead and wakes the writer so it exits.
    pub fn kill(&self) {
        self.lock().dead = true;
        self.notify();
    }
}

/// What every client's reader needs from the server.
#[derive(Debug)]
pub(crate) struct Hub {
    /// Static hello facts.
    pub info: crate::publish::protocol::HelloInfo,
    /// Current agent count (from the newest snapshot).
    pub agents: AtomicU32,
    /// `socket.client_queue`.
    pub client_queue: u32,
    /// Newest mesh, sent to clients that connect or subscribe later.
    pub latest_mesh: Mutex<Option<Arc<MeshView>>>,
    /// Commands to the control thread (bounded; `try_send` only).
    pub commands: Sender<CommandRequest>,
    /// Counters.
    pub stats: Arc<PublisherStats>,
}

impl Hub {
    /// The server hello for a client with these settings.
    pub fn hello(&self, client: ClientId, settings: &ClientSettings) -> Arc<[u8]> {
        let mut out = Vec::with_capacity(512);
        protocol::encode_server_hello(
            &ServerHello {
                info: &self.info,
                client,
                agents: self.agents.load(Ordering::Relaxed),
                settings,
                client_queue: self.client_queue,
            },
            &mut out,
        );
        out.into()
    }

    /// The newest mesh as a JSON line with triangles, if there is one.
    pub fn latest_mesh_json(&self) -> Option<(Arc<[u8]>, u64)> {
        let mesh = lock(&self.latest_mesh).clone()?;
        let mut out = Vec::new();
        protocol::encode_mesh_json(&mesh, true, &mut out);
        Some((out.into(), mesh.topology))
    }
}

/// Appends a JSON line to `buf` framed for `framing`.
fn put_json(json: &[u8], framing: Format, buf: &mut Vec<u8>) {
    match framing {
        Format::Json => buf.extend_from_slice(json),
        Format::Binary => protocol::frame_json(json, buf),
    }
}

/// Writer thread body: pops items, writes them, until the client is dead or closed.
pub(crate) fn writer_loop(
    shared: Arc<ClientShared>,
    stream: UnixStream,
    stats: Arc<PublisherStats>,
) {
    let mut buf: Vec<u8> = Vec::with_capacity(64 * 1024);
    let mut notice = Vec::with_capacity(64);
    loop {
        let (item, unnotified, dropped_total) = {
            let mut q = shared.lock();
            loop {
                if q.dead {
                    drop(q);
                    let _ = stream.shutdown(Shutdown::Both);
                    return;
                }
                if let Some(item) = q.items.pop_front() {
                    q.uncount(&item);
                    let n = std::mem::take(&mut q.dropped_unnotified);
                    break (item, n, q.dropped_total);
                }
                if q.closing_since.is_some() {
                    q.dead = true;
                    drop(q);
                    let _ = stream.shutdown(Shutdown::Both);
                    return;
                }
                q = shared
                    .ready
                    .wait(q)
                    .unwrap_or_else(std::sync::PoisonError::into_inner);
            }
        };
        buf.clear();
        if unnotified > 0 {
            notice.clear();
            protocol::encode_dropped(unnotified, dropped_total, &mut notice);
            put_json(&notice, item.framing(), &mut buf);
        }
        let mut input_t = None;
        match &item {
            Item::Snapshot(enc) => {
                input_t = enc.input_t;
                match enc.format {
                    Format::Json => protocol::splice_dropped_json(
                        &enc.bytes,
                        enc.dropped_at,
                        dropped_total,
                        &mut buf,
                    ),
                    Format::Binary => {
                        let at = buf.len() + protocol::BINARY_DROPPED_OFFSET;
                        buf.extend_from_slice(&enc.bytes);
                        if let Some(slot) = buf.get_mut(at..at + 8) {
                            slot.copy_from_slice(&dropped_total.to_le_bytes());
                        }
                    }
                }
            }
            Item::Mesh { json, framing, .. } | Item::Message { json, framing } => {
                put_json(json, *framing, &mut buf)
            }
        }
        if let Err(e) = send_all(&stream, &buf) {
            match e.kind() {
                ErrorKind::WouldBlock | ErrorKind::TimedOut => log::info!(
                    "client {}: took no data for {:?}; disconnecting",
                    shared.id,
                    super::WRITE_STALL_TIMEOUT
                ),
                _ => log::debug!("client {}: gone ({e})", shared.id),
            }
            shared.kill();
            let _ = stream.shutdown(Shutdown::Both);
            return;
        }
        stats.record_write(buf.len(), matches!(item, Item::Snapshot(_)), input_t);
    }
}

/// Writes all of `buf` with `send(MSG_NOSIGNAL)`: a vanished peer is an `EPIPE`
/// error here, never a `SIGPIPE` for the process, whatever its signal setup.
/// `SO_SNDTIMEO` (the [`super::WRITE_STALL_TIMEOUT`]) applies; it surfaces as `WouldBlock`.
pub(crate) fn send_all(stream: &UnixStream, mut buf: &[u8]) -> std::io::Result<()> {
    use nix::sys::socket::{send, MsgFlags};
    use std::os::fd::AsRawFd;
    while !buf.is_empty() {
        match send(stream.as_raw_fd(), buf, MsgFlags::MSG_NOSIGNAL) {
            Ok(0) => return Err(ErrorKind::WriteZero.into()),
            Ok(n) => buf = &buf[n..],
            Err(nix::errno::Errno::EINTR) => {}
            Err(e) => return Err(std::io::Error::from(e)),
        }
    }
    Ok(())
}

/// What reading one line gave.
enum Line {
    /// A line is in the buffer (newline removed).
    Complete,
    /// The peer closed its write side.
    Eof,
    /// The line passed the limit.
    TooLong(usize),
}

/// Reads one `\n`-terminated line of at most `max` bytes into `line`.
fn read_line_capped<R: Read>(
    r: &mut BufReader<R>,
    line: &mut Vec<u8>,
    max: usize,
) -> std::io::Result<Line> {
    line.clear();
    loop {
        let avail = match r.fill_buf() {
            Ok(a) => a,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if avail.is_empty() {
            return Ok(Line::Eof);
        }
        let (take, done) = match avail.iter().position(|&c| c == b'\n') {
            Some(i) => (i, true),
            None => (avail.len(), false),
        };
        if line.len() + take > max {
            return Ok(Line::TooLong(line.len() + take));
        }
        line.extend_from_slice(&avail[..take]);
        r.consume(take + usize::from(done));
        if done {
            return Ok(Line::Complete);
        }
    }
}

/// Reader thread body: parses client lines until EOF, a read error or a fatal error.
///
/// EOF alone does not end the session: a client may half-close (`shutdown(SHUT_WR)`)
/// and keep reading. After EOF the reader waits for the hang-up instead
/// ([`wait_for_hang_up`]): a client that is sent nothing (it subscribed to nothing)
/// gives the writer no write that would find it gone.
pub(crate) fn reader_loop(shared: Arc<ClientShared>, stream: UnixStream, hub: Arc<Hub>) {
    let mut r = BufReader::with_capacity(8 * 1024, stream);
    let mut line = Vec::with_capacity(1024);
    loop {
        let fatal = match read_line_capped(&mut r, &mut line, protocol::MAX_LINE_BYTES) {
            Ok(Line::Eof) => {
                wait_for_hang_up(r.get_ref());
                log::debug!("client {}: hung up", shared.id);
                shared.kill();
                return;
            }
            Err(e) => {
                log::debug!("client {}: read failed: {e}", shared.id);
                return;
            }
            Ok(Line::TooLong(len)) => protocol::ProtocolError::LineTooLong {
                len,
                max: protocol::MAX_LINE_BYTES,
            },
            Ok(Line::Complete) => {
                if line.iter().all(u8::is_ascii_whitespace) {
                    continue; // blank lines (someone typing in socat) are harmless
                }
                match protocol::parse_client_message(&line) {
                    Ok(msg) => {
                        handle_message(&shared, &hub, msg);
                        continue;
                    }
                    Err(e) if !e.is_fatal() => {
                        hub.stats.count_protocol_error();
                        let mut json = Vec::new();
                        protocol::encode_error(e.command_id(), &e.to_string(), false, &mut json);
                        push_reply(&shared, json);
                        continue;
                    }
                    Err(e) => e,
                }
            }
        };
        hub.stats.count_protocol_error();
        log::info!(
            "client {}: protocol error: {fatal}; disconnecting",
            shared.id
        );
        shared.lock().fail(&fatal.to_string());
        shared.notify();
        return;
    }
}

/// Blocks until the socket is hung up: the peer closed it (a half-close is not a
/// hang-up), or the daemon shut it down (when the writer ends, at reap and at
/// shutdown), whichever comes first. `poll` with no requested events reports only
/// `POLLHUP`, `POLLERR` and `POLLNVAL`.
fn wait_for_hang_up(stream: &UnixStream) {
    use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
    use std::os::fd::AsFd;
    loop {
        let mut fds = [PollFd::new(stream.as_fd(), PollFlags::empty())];
        match poll(&mut fds, PollTimeout::NONE) {
            Ok(_) if fds[0].revents().is_some_and(|r| !r.is_empty()) => return,
            Ok(_) | Err(nix::errno::Errno::EINTR) => {}
            Err(_) => return,
        }
    }
}

/// Queues a reply; a reply that overflows the backlog disconnects the client.
fn push_reply(shared: &ClientShared, json: Vec<u8>) {
    let mut q = shared.lock();
    if !q.accepting() {
        return;
    }
    let framing = q.settings.format;
    if let Err(o) = q.push_message(json.into(), framing) {
        q.fail(&o.to_string());
    }
    drop(q);
    shared.notify();
}

fn handle_message(shared: &ClientShared, hub: &Hub, msg: ClientMessage) {
    match msg {
        ClientMessage::Hello(settings) => {
            let reply = hub.hello(shared.id, &settings);
            let mesh = if settings.subscriptions.mesh {
                hub.latest_mesh_json()
            } else {
                None
            };
            let mut q = shared.lock();
            if !q.accepting() {
                return;
            }
            // The reply is the last message in the old format.
            let old = q.settings;
            let mut result = q.push_message(reply, old.format);
            q.settings = settings;
            q.rate_next_due_us = 0;
            if !settings.subscriptions.mesh {
                q.mesh_topology = None;
            } else if !old.subscriptions.mesh {
                if let Some((json, topology)) = mesh {
                    q.take_queued_mesh();
                    q.mesh_topology = Some(topology);
                    result = result.and(q.push_mesh(json, true));
                }
            }
            if let Err(o) = result {
                q.fail(&o.to_string());
            }
            drop(q);
            shared.notify();
        }
        ClientMessage::Command { id, command } => {
            let request = CommandRequest {
                client: shared.id,
                id,
                command,
            };
            let refusal = match hub.commands.try_send(request) {
                Ok(()) => return,
                Err(TrySendError::Full(r)) => {
                    hub.stats.count_busy();
                    (r.id, "busy: the daemon's command queue is full; try again")
                }
                Err(TrySendError::Disconnected(r)) => (r.id, "the daemon is shutting down"),
            };
            let mut json = Vec::new();
            protocol::encode_error(Some(&refusal.0), refusal.1, false, &mut json);
            push_reply(shared, json);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn lines_are_capped() {
        let data = b"abc\ndefgh\nxy".to_vec();
        let mut r = BufReader::with_capacity(2, &data[..]);
        let mut line = Vec::new();
        assert!(matches!(
            read_line_capped(&mut r, &mut line, 4),
            Ok(Line::Complete)
        ));
        assert_eq!(line, b"abc");
        assert!(matches!(
            read_line_capped(&mut r, &mut line, 4),
            Ok(Line::TooLong(_))
        ));
        let mut r = BufReader::new(&b"xy"[..]);
        assert!(matches!(
            read_line_capped(&mut r, &mut line, 4),
            Ok(Line::Eof)
        ));
    }
}
