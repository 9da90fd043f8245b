//! The Unix-socket output: snapshots in, bytes out to every client.
//!
//! The control thread's messages reach the socket's thread ([`Server`], the
//! [`Output`](crate::publish::Output) named `publisher`) through its output queue.
//! The publisher serialises each snapshot once per wire encoding in use (format ×
//! field set), shares the bytes (`Arc`) with every client, and never blocks on a
//! client. The wire format is in [`protocol`](crate::publish::protocol) and, for
//! renderer authors, `docs/protocol.md`.
//!
//! # Threads
//! Two, however many clients connect:
//! * **Publisher thread** (`Server::run`, `publisher.rs`): receives from its output
//!   queue, encodes each snapshot once per encoding in use (outside every lock),
//!   pushes onto each client's queue, routes each command's answer to the client that
//!   asked, and wakes the I/O thread (an eventfd) after each snapshot (a tick's
//!   events and mesh go with it) and after other messages. It never
//!   touches a socket, so a stalled client can never stall it.
//! * **I/O thread** (`ct-socket-io`, `io.rs`): one `epoll` over the listener, the
//!   wake-up and every client socket, all non-blocking. It accepts, writes what is
//!   queued (a message the socket takes only in part is resumed where it stopped
//!   when the socket is writable again, without copying the shared encoding:
//!   `wire.rs`), reads client lines incrementally (`lines.rs`) and acts on them
//!   (`conn.rs`). A client's queue mutex is held for a push or a pop only, never
//!   across I/O.
//!
//! # Queues and what is dropped
//! * Control → publisher: the output queue, [`QUEUE_CAPACITY`] messages, drop-newest
//!   (it fills only when the publisher thread itself stalls).
//! * Publisher → client: one queue per client (`queue.rs`), holding at most
//!   `socket.client_queue` snapshots. When a new snapshot finds it full, the
//!   **oldest queued snapshot** is removed and counted; the client sees the
//!   cumulative count in every snapshot's `dropped` field and gets a `dropped` notice
//!   before the next message written. Events, replies and `stats` are never dropped;
//!   a `mesh` not yet written is replaced by a newer one (the newer supersedes it;
//!   `triangles` are still sent when the topology changed). If the non-snapshot
//!   backlog passes [`MAX_BACKLOG_MESSAGES`] or [`MAX_BACKLOG_BYTES`] the client is
//!   sent a fatal `error` and disconnected.
//! * Client → control: commands go through the daemon's bounded command channel with
//!   `try_send`; when it is full the client gets an immediate `error` "busy". One
//!   client has at most [`COMMAND_WINDOW`] replies owed at once and a budget of
//!   [`LINES_PER_SECOND`] lines ([`LINE_BURST`] at once); further lines wait in its
//!   socket, so one client's flood slows only that client and cannot fill the
//!   command channel for the others.
//! * Replies reach only the client that asked, in the order of its requests
//!   (`queue.rs`, "Replies in order").
//! * A client whose socket accepts nothing for [`WRITE_STALL_TIMEOUT`] is
//!   disconnected; a closing client (fatal error) gets [`CLOSE_GRACE`] to take its
//!   last messages before its socket is shut down, and at shutdown every client gets
//!   [`SHUTDOWN_GRACE`] to take its `bye`.
//!
//! # Latency accounting
//! `latency_us` in a snapshot is encode time − `input_t`. The I/O thread records
//! (CLOCK_MONOTONIC after the last byte of a snapshot is sent) − `input_t` into
//! [`PublisherStats::take_end_to_end`]'s histogram.

mod budget;
mod conn;
mod error;
mod hub;
mod io;
mod lines;
pub mod preflight;
mod privilege;
mod publisher;
mod queue;
mod server;
mod session;
mod stats;
mod wire;

pub use budget::{ACCEPTS_PER_SECOND, ACCEPT_BURST, LINES_PER_SECOND, LINE_BURST};
pub use error::Error;
pub use io::{CLIENT_SNDBUF_BYTES, SHUTDOWN_GRACE, WRITE_STALL_TIMEOUT};
pub use privilege::{peer_credentials, PeerCredentials, PeerPolicy};
pub use queue::{CLOSE_GRACE, MAX_BACKLOG_BYTES, MAX_BACKLOG_MESSAGES, REPLY_TIMEOUT};
pub use server::{
    Server, SocketOptions, FINAL_MESSAGES_WAIT, IO_THREAD_STACK_BYTES, QUEUE_CAPACITY,
};
pub use session::COMMAND_WINDOW;
pub use stats::PublisherStats;
// For the WebSocket transport (`publish::websocket`): its clients are this
// publisher's clients.
pub(crate) use budget::Budget;
pub(crate) use hub::Hub;
pub(crate) use queue::{ClientShared, Item};
pub(crate) use session::{Acted, Session};
