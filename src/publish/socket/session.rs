//! What a client may ask, whatever carries its messages: one client message (a
//! Unix-socket line, a WebSocket text message) acted on under the client's limits.
//!
//! Both transports go through here, so the limits are the same for every client:
//! * at most [`COMMAND_WINDOW`] replies owed at once, and a budget of
//!   [`LINES_PER_SECOND`] messages ([`LINE_BURST`] at once) — a transport asks
//!   [`Session::may_take`] before it takes the next message, and leaves it unread
//!   (in its socket) while the answer is no;
//! * a `hello` waits until every reply before it is out (it changes the stream's
//!   format);
//! * a read-only client (not privileged) may negotiate its stream, but every
//!   command is refused with an `error` ("read-only client: …"), and it never
//!   receives the raw touches (`queue.rs`, `restrict`).

use super::budget::{Budget, LINES_PER_SECOND, LINE_BURST};
use super::hub::Hub;
use super::queue::{restrict, ClientShared};
use crate::publish::protocol::{self, ClientMessage, ClientSettings};
use crate::vocab::{Command, CommandRequest, Micros};
use crossbeam_channel::TrySendError;
use serde_json::Value;
use std::sync::Arc;
use std::time::Instant;

/// Replies one client may be owed at once (commands sent to the control thread and
/// not answered, and replies waiting behind them); further messages wait.
pub const COMMAND_WINDOW: usize = 8;

/// The error a read-only client gets for a command.
pub const READ_ONLY_COMMAND: &str =
    "read-only client: commands need a privileged connection (Unix socket: a user or \
     group in socket.privileged; WebSocket: an output with privileged: true)";

/// What became of one message.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) enum Acted {
    /// Acted on (or answered with a non-fatal `error`).
    Done,
    /// A `hello` held until the replies before it are out ([`Session::release_held`]).
    Held,
    /// A fatal protocol error: the client is told and closing; read no more.
    Fatal,
}

/// One client's message limits and its held `hello`.
#[derive(Debug)]
pub(crate) struct Session {
    /// What the publisher shares about this client.
    pub shared: Arc<ClientShared>,
    rate: Budget,
    /// A `hello` waiting for the replies before it to go out.
    held: Option<ClientSettings>,
    /// It sent a `touch` command: its contacts are lifted when it leaves
    /// ([`Hub::lift_touches`]).
    pub touched: bool,
}

impl Session {
    /// A session for `shared`, its budget full at `now`.
    pub fn new(shared: Arc<ClientShared>, now: Micros) -> Session {
        Session {
            shared,
            rate: Budget::new(LINES_PER_SECOND, LINE_BURST, now),
            touched: false,
            held: None,
        }
    }

    /// The client's id.
    pub fn id(&self) -> u64 {
        self.shared.id
    }

    /// Applies a held `hello` once no reply is owed before it; false while it
    /// still waits (take no message meanwhile).
    pub fn release_held(&mut self, hub: &Hub) -> bool {
        let Some(settings) = self.held else {
            return true;
        };
        if self.shared.lock().replies_waiting() > 0 {
            return false;
        }
        self.held = None;
        self.hello(hub, settings);
        true
    }

    /// Whether the next message may be taken now (the window has room and the
    /// budget has one, which this takes); false: leave it unread.
    pub fn may_take(&mut self, now: Micros) -> bool {
        self.shared.lock().replies_waiting() < COMMAND_WINDOW && self.rate.take(now)
    }

    /// Acts on one message (after [`Session::may_take`]).
    pub fn act(&mut self, hub: &Hub, message: &[u8]) -> Acted {
        match protocol::parse_client_message(message) {
            Ok(ClientMessage::Hello(settings)) => {
                if self.shared.lock().replies_waiting() > 0 {
                    self.held = Some(settings);
                    return Acted::Held;
                }
                self.hello(hub, settings);
            }
            Ok(ClientMessage::Command { id, command }) => {
                if self.shared.privileged {
                    self.command(hub, id, command);
                } else {
                    hub.stats.count_read_only_refusal();
                    self.answer(Some(&id), READ_ONLY_COMMAND);
                }
            }
            Err(e) if !e.is_fatal() => {
                hub.stats.count_protocol_error();
                self.answer(e.command_id(), &e.to_string());
            }
            Err(e) => {
                self.fatal(hub, &e.to_string());
                return Acted::Fatal;
            }
        }
        Acted::Done
    }

    /// A non-fatal `error` answered on the spot, in the order of the replies.
    pub fn answer(&self, id: Option<&Value>, message: &str) {
        let mut json = Vec::new();
        protocol::encode_error(id, message, false, &mut json);
        let mut q = self.shared.lock();
        if q.accepting() {
            if let Err(o) = q.reply(json.into()) {
                q.fail(&o.to_string());
            }
        }
    }

    /// A fatal error: the client is told and closed; its input is over.
    pub fn fatal(&self, hub: &Hub, message: &str) {
        hub.stats.count_protocol_error();
        log::info!(
            "client {}: protocol error: {message}; disconnecting",
            self.id()
        );
        self.shared.lock().fail(message);
    }

    /// A client `hello`: the reply in the old format, then the new settings.
    fn hello(&mut self, hub: &Hub, settings: ClientSettings) {
        let settings = restrict(settings, self.shared.privileged);
        let reply = hub.hello(&self.shared, &settings);
        let mut q = self.shared.lock();
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
            // Read under the queue's lock: a newer mesh the publisher queues after
            // this sees the subscription and replaces this one.
            if let Some((json, topology)) = hub.latest_mesh_json() {
                q.take_queued_mesh();
                q.mesh_topology = Some(topology);
                result = result.and(q.push_mesh(json, true));
            }
        }
        if settings.subscriptions.scene && !old.subscriptions.scene {
            if let Some(json) = hub.latest_scene_json() {
                result = result.and(q.push_message(json, settings.format));
            }
        }
        if settings.subscriptions.edit && !old.subscriptions.edit {
            // The edit mode as it is: every person's tracks, then its state.
            let latest = hub.latest_edit_json();
            for json in [latest.tracks, latest.state].into_iter().flatten() {
                result = result.and(q.push_message(json, settings.format));
            }
        }
        if let Err(o) = result {
            q.fail(&o.to_string());
        }
    }

    /// A command: to the control thread (its answer comes back through the
    /// publisher), or refused on the spot when the command queue is full.
    fn command(&mut self, hub: &Hub, id: Value, command: Command) {
        {
            let mut q = self.shared.lock();
            if !q.accepting() {
                return;
            }
            // The slot is taken before the control thread can answer.
            q.expect_reply(id.clone(), Instant::now());
        }
        self.touched |= matches!(command, Command::Touch { .. });
        let request = CommandRequest {
            client: self.id(),
            id,
            command,
        };
        let (id, message) = match hub.commands.try_send(request) {
            Ok(()) => return,
            Err(TrySendError::Full(r)) => {
                hub.stats.count_busy();
                (r.id, "busy: the daemon's command queue is full; try again")
            }
            Err(TrySendError::Disconnected(r)) => (r.id, "the daemon is shutting down"),
        };
        let mut json = Vec::new();
        protocol::encode_error(Some(&id), message, false, &mut json);
        let mut q = self.shared.lock();
        if let Err(o) = q.refuse_newest(json.into()) {
            q.fail(&o.to_string());
        }
    }
}
