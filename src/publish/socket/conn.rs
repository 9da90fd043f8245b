//! One client's connection as the I/O thread serves it: the message being written
//! (resumed after a partial write), the bytes read and not yet acted on, and the
//! limits on what the client may ask.
//!
//! # What a client may send
//! Lines are taken in order, each under [`protocol::MAX_LINE_BYTES`]. A line waits
//! (unread bytes stay in the socket, so a flooding client is slowed by its own full
//! buffer) while:
//! * `COMMAND_WINDOW` of the client's replies are owed: commands the control
//!   thread has not answered, and replies waiting behind them;
//! * the client has used its budget of lines (`LINES_PER_SECOND`, `LINE_BURST`
//!   at once);
//! * it is a `hello` and a reply is owed: the hello changes the stream's format,
//!   so it waits until every reply before it is out.
//!
//! So one client has at most `COMMAND_WINDOW` commands in the daemon's command
//! queue, and cannot fill it for the others. The limits are the session's
//! (`session.rs`), shared with the WebSocket transport.

use super::hub::Hub;
use super::lines::{LineBuf, Next};
use super::queue::ClientShared;
use super::session::{Acted, Session};
use super::stats::PublisherStats;
use super::wire::Frame;
use crate::publish::protocol;
use crate::vocab::Micros;
use nix::sys::epoll::EpollFlags;
use std::io::ErrorKind;
use std::os::unix::net::UnixStream;
use std::sync::Arc;
use std::time::Instant;

/// Bytes read from one client per round of the I/O loop, so a client that sends a
/// lot does not delay the others.
const READ_BUDGET_BYTES: usize = 16 * 1024;

/// What the I/O thread should do with a connection after serving it.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Fate {
    /// Keep it.
    Keep,
    /// Remove it now: it is gone, or closed and written out.
    Remove,
}

/// How the last write went.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Write {
    /// Everything queued is written.
    Idle,
    /// The socket's buffer is full; wait until it is writable.
    Blocked,
}

/// One connected client, owned by the I/O thread.
#[derive(Debug)]
pub(crate) struct Conn {
    /// What the publisher shares about this client.
    pub shared: Arc<ClientShared>,
    /// The socket (non-blocking).
    pub stream: UnixStream,
    frame: Frame,
    lines: LineBuf,
    /// The client's limits and its held `hello`.
    session: Session,
    /// The client shut its side (half-close) or its input was refused: read no more.
    input_done: bool,
    /// Lines wait (window, rate or a held hello): do not poll for input.
    pub paused: bool,
    /// The last write found the socket full.
    pub write: Write,
    /// Since when the socket has taken no bytes while some were waiting.
    pub stalled_since: Option<Instant>,
    /// The events its socket is registered for.
    pub interest: EpollFlags,
}

impl Conn {
    /// Whether it sent a `touch` command (its contacts are lifted when it leaves).
    pub fn touched(&self) -> bool {
        self.session.touched
    }

    /// A connection for `shared` on `stream` (already non-blocking).
    pub fn new(shared: Arc<ClientShared>, stream: UnixStream, now: Micros) -> Conn {
        Conn {
            session: Session::new(Arc::clone(&shared), now),
            shared,
            stream,
            frame: Frame::default(),
            lines: LineBuf::default(),
            input_done: false,
            paused: false,
            write: Write::Idle,
            stalled_since: None,
            interest: EpollFlags::empty(),
        }
    }

    /// The client's id.
    pub fn id(&self) -> u64 {
        self.shared.id
    }

    /// Whether to poll the socket for input.
    pub fn wants_input(&self) -> bool {
        !self.input_done && !self.paused
    }

    /// Writes queued messages until the queue is empty or the socket is full.
    pub fn flush(&mut self, stats: &PublisherStats, now: Instant) -> Fate {
        loop {
            if !self.frame.active() {
                let mut q = self.shared.lock();
                if q.dead {
                    return Fate::Remove;
                }
                let Some((item, unnotified, total)) = q.pop() else {
                    self.write = Write::Idle;
                    self.stalled_since = None;
                    // A closing client is done once its last message is out.
                    return if q.closing_since.is_some() {
                        Fate::Remove
                    } else {
                        Fate::Keep
                    };
                };
                drop(q);
                self.frame.load(item, unnotified, total);
            }
            match self.frame.send(&self.stream) {
                Ok(_) => {
                    self.stalled_since = None;
                    if !self.frame.active() {
                        let (len, snapshot) = self.frame.finish();
                        stats.record_write(len, snapshot.is_some(), snapshot.flatten());
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.write = Write::Blocked;
                    self.stalled_since.get_or_insert(now);
                    return Fate::Keep;
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    log::debug!("client {}: gone ({e})", self.id());
                    return Fate::Remove;
                }
            }
        }
    }

    /// Reads what the client sent and acts on its complete lines, as far as its
    /// window, its line budget and the read budget allow.
    pub fn input(&mut self, hub: &Hub, now: Micros) -> Fate {
        self.paused = false;
        let mut budget = READ_BUDGET_BYTES;
        loop {
            if !self.session.release_held(hub) {
                self.paused = true;
                return Fate::Keep;
            }
            if !self.take_lines(hub, now) {
                return Fate::Keep;
            }
            if self.input_done || budget == 0 {
                return Fate::Keep;
            }
            match self.lines.fill(&self.stream, budget) {
                Ok(0) => {
                    // The client shut its side: the session goes on until it hangs up
                    // (a half-close is not a hang-up). A partial last line is dropped.
                    log::debug!("client {}: end of its stream", self.id());
                    self.input_done = true;
                }
                Ok(n) => budget -= n,
                Err(e) if e.kind() == ErrorKind::WouldBlock => return Fate::Keep,
                Err(e) => {
                    log::debug!("client {}: read failed: {e}", self.id());
                    return Fate::Remove;
                }
            }
        }
    }

    /// Acts on complete lines; false when the rest must wait (or input is over).
    fn take_lines(&mut self, hub: &Hub, now: Micros) -> bool {
        loop {
            if self.input_done {
                return false;
            }
            let range = match self.lines.peek(protocol::MAX_LINE_BYTES) {
                Next::Partial => return true,
                Next::TooLong(len) => {
                    let e = protocol::ProtocolError::LineTooLong {
                        len,
                        max: protocol::MAX_LINE_BYTES,
                    };
                    self.session.fatal(hub, &e.to_string());
                    self.input_done = true;
                    return false;
                }
                Next::Line(r) => r,
            };
            let line = &self.lines.bytes()[range];
            if line.iter().all(u8::is_ascii_whitespace) {
                // Blank lines (someone typing in socat) are harmless and free.
                self.lines.consume();
                continue;
            }
            if !self.session.may_take(now) {
                self.paused = true;
                return false;
            }
            let acted = self.session.act(hub, line);
            self.lines.consume();
            match acted {
                Acted::Done => {}
                Acted::Held => {
                    self.paused = true;
                    return false;
                }
                Acted::Fatal => {
                    self.input_done = true;
                    return false;
                }
            }
        }
    }
}
