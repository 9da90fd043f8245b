//! The Unix-socket publisher: snapshots in, bytes out to every client.
//!
//! The control thread sends [`Outgoing`] messages to the
//! publisher thread ([`Server::run`]). The publisher serialises each snapshot once per
//! wire encoding in use (format × field set), shares the bytes (`Arc`) with every
//! client, and never blocks on a client. The wire format is in [`protocol`] and, for
//! renderer authors, `docs/protocol.md`.
//!
//! # Threads
//! * **Publisher thread** ([`Server::run`]): receives from the control thread with a
//!   short timeout, accepts clients (non-blocking listener), encodes, and pushes onto
//!   each client's queue. A push holds the client's queue mutex for well under a
//!   microsecond; the first client of each encoding also holds it while the snapshot
//!   is encoded (tens of µs; that only delays that client's own writer). Nobody holds
//!   the mutex across I/O, so a stalled client can never stall the publisher.
//! * **Per client, a writer thread and a reader thread.** Kiosks have a handful of
//!   clients (`socket.max_clients`, default 32), so plain blocking I/O on two threads
//!   per client is the simplest thing that keeps one client's socket from touching
//!   another's: the writer blocks in `write` on its own socket only, the reader blocks
//!   in `read`. A poll loop would save the threads but would need non-blocking partial
//!   writes, per-client write cursors and a wake-up path from the crossbeam channel
//!   (which cannot be polled); it buys nothing at this client count.
//!
//! # Queues and what is dropped
//! * Control → publisher: the caller's crossbeam channel (its policy is `pipeline`'s).
//! * Publisher → client: one queue per client (`VecDeque` under a mutex + condvar),
//!   holding at most `socket.client_queue` snapshots. When a new snapshot finds it
//!   full, the **oldest queued snapshot** is removed and counted; the client sees the
//!   cumulative count in every snapshot's `dropped` field and gets a `dropped` notice
//!   before the next message written. Events, replies and `stats` are never dropped;
//!   a `mesh` not yet written is replaced by a newer one (the newer supersedes it;
//!   `triangles` are still sent when the topology changed). If the non-snapshot
//!   backlog passes [`MAX_BACKLOG_MESSAGES`] or [`MAX_BACKLOG_BYTES`] the client is
//!   sent a fatal `error` and disconnected.
//! * Client → control: commands go through the caller's bounded channel with
//!   `try_send`; when it is full the client gets an immediate `error` "busy".
//! * A client whose socket accepts nothing for [`WRITE_STALL_TIMEOUT`] is
//!   disconnected; a closing client (fatal error, shutdown) gets [`CLOSE_GRACE`] to
//!   take its last messages before its socket is shut down.
//!
//! # Latency accounting
//! `latency_us` in a snapshot is encode time − `input_t`. Each writer records
//! (CLOCK_MONOTONIC after the last byte of a snapshot is sent) − `input_t` into
//! [`PublisherStats::take_end_to_end`]'s histogram.

mod client;
mod outgoing;
pub mod protocol;
mod server;

pub use outgoing::Outgoing;
pub use server::{PublisherStats, Server};

use std::path::PathBuf;
use std::time::Duration;

/// Send buffer requested for each client socket (bytes): room for several
/// 1,000-agent snapshots, so a reader that is briefly late never blocks the write.
pub const CLIENT_SNDBUF_BYTES: usize = 1 << 20;

/// Most non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_MESSAGES: usize = 4096;
/// Most bytes of non-snapshot messages queued for one client before it is disconnected.
pub const MAX_BACKLOG_BYTES: usize = 16 << 20;
/// A client whose socket takes no bytes for this long is disconnected.
pub const WRITE_STALL_TIMEOUT: Duration = Duration::from_secs(10);
/// Time a closing client gets to read its last messages (`error`, `bye`).
pub const CLOSE_GRACE: Duration = Duration::from_secs(1);

/// Static facts sent in the server hello.
#[derive(Clone, Debug)]
pub struct HelloInfo {
    /// The world rectangle (m).
    pub world: crate::geom::Rect,
    /// Agent count at start (the hello reports the current count once snapshots flow).
    pub agents: u32,
    /// Agent radius (m).
    pub agent_radius_m: f64,
}

/// Why the socket could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Another process (probably another crowdtouch) is listening on the path.
    #[error("{path}: another process is already listening on this socket (is crowdtouch already running?)")]
    InUse {
        /// Socket path.
        path: PathBuf,
    },
    /// Something other than a socket is at the path; it is left alone.
    #[error("{path}: exists and is not a socket; refusing to replace it")]
    NotASocket {
        /// The path.
        path: PathBuf,
    },
    /// `bind` failed.
    #[error("{path}: cannot bind the socket: {source}")]
    Bind {
        /// Socket path.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The socket's mode could not be set.
    #[error("{path}: cannot set socket mode {mode:04o}: {source}")]
    Permissions {
        /// Socket path.
        path: PathBuf,
        /// Mode asked for.
        mode: u32,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The configured group does not exist.
    #[error("socket group `{group}` does not exist (config socket.group)")]
    UnknownGroup {
        /// Group name.
        group: String,
    },
    /// The socket could not be given to the configured group.
    #[error("{path}: cannot give the socket to group `{group}`: {source}")]
    Group {
        /// Socket path.
        path: PathBuf,
        /// Group name.
        group: String,
        /// Cause (`EPERM` when the daemon is not a member of the group).
        #[source]
        source: nix::errno::Errno,
    },
    /// Another I/O step failed.
    #[error("{path}: cannot {op}: {source}")]
    Io {
        /// Path involved.
        path: PathBuf,
        /// What was being done (`remove the stale socket`, ...).
        op: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}
