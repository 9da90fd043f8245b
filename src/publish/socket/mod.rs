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
//! * **Publisher thread** (`Server::run`): receives from its output queue with a
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
//! * Control → publisher: the output queue, [`QUEUE_CAPACITY`] messages, drop-newest
//!   (it fills only when the publisher thread itself stalls).
//! * Publisher → client: one queue per client (`VecDeque` under a mutex + condvar),
//!   holding at most `socket.client_queue` snapshots. When a new snapshot finds it
//!   full, the **oldest queued snapshot** is removed and counted; the client sees the
//!   cumulative count in every snapshot's `dropped` field and gets a `dropped` notice
//!   before the next message written. Events, replies and `stats` are never dropped;
//!   a `mesh` not yet written is replaced by a newer one (the newer supersedes it;
//!   `triangles` are still sent when the topology changed). If the non-snapshot
//!   backlog passes [`MAX_BACKLOG_MESSAGES`] or [`MAX_BACKLOG_BYTES`] the client is
//!   sent a fatal `error` and disconnected.
//! * Client → control: commands go through the daemon's bounded command channel with
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
mod error;
pub mod preflight;
mod server;
mod stats;

pub use client::{CLOSE_GRACE, MAX_BACKLOG_BYTES, MAX_BACKLOG_MESSAGES};
pub use error::Error;
pub use server::{Server, SocketOptions, CLIENT_SNDBUF_BYTES, QUEUE_CAPACITY, WRITE_STALL_TIMEOUT};
pub use stats::PublisherStats;
