//! The socket output's counters, shared with the rest of the daemon.

use crate::publish::ClientLimit;
use crate::rt::monotonic_now;
use crate::vocab::Micros;
use hdrhistogram::Histogram;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// Largest latency a histogram records (µs); larger values are clamped to it.
const HISTOGRAM_MAX_US: u64 = 60_000_000;
/// Significant figures kept by the latency histograms.
const HISTOGRAM_SIGFIG: u8 = 3;

fn new_histogram() -> Histogram<u64> {
    // Constant bounds that hdrhistogram accepts (checked by a unit test): not input.
    #[allow(clippy::expect_used)]
    Histogram::new_with_bounds(1, HISTOGRAM_MAX_US, HISTOGRAM_SIGFIG)
        .expect("valid histogram bounds")
}

/// Counters shared with the rest of the daemon, and the one setting that changes
/// while the socket runs: the client limit.
///
/// Counts are atomics (read often, by the stats reporter). The two histograms are a
/// `Mutex<Histogram>` each: writers are the I/O thread and the publisher, and each
/// holds the lock for one `record` (tens of ns); readers take a copy and reset
/// ("interval" semantics).
#[derive(Debug)]
pub struct PublisherStats {
    /// Shared with the daemon, which changes it on a reload ([`Output::client_limit`](crate::publish::Output::client_limit)).
    pub(super) max_clients: ClientLimit,
    pub(super) clients: AtomicU32,
    pub(super) clients_accepted: AtomicU64,
    pub(super) clients_refused: AtomicU64,
    pub(super) snapshots_sent: AtomicU64,
    pub(super) snapshots_dropped: AtomicU64,
    pub(super) snapshots_rate_skipped: AtomicU64,
    pub(super) messages_sent: AtomicU64,
    pub(super) bytes_written: AtomicU64,
    pub(super) protocol_errors: AtomicU64,
    pub(super) commands_busy: AtomicU64,
    pub(super) read_only_refusals: AtomicU64,
    pub(super) ws_refused: AtomicU64,
    pub(super) ws_oversize: AtomicU64,
    pub(super) ws_bad_frames: AtomicU64,
    pub(super) end_to_end: Mutex<Histogram<u64>>,
    pub(super) encode: Mutex<Histogram<u64>>,
}

impl Default for PublisherStats {
    fn default() -> Self {
        PublisherStats {
            max_clients: ClientLimit::new(0),
            clients: AtomicU32::new(0),
            clients_accepted: AtomicU64::new(0),
            clients_refused: AtomicU64::new(0),
            snapshots_sent: AtomicU64::new(0),
            snapshots_dropped: AtomicU64::new(0),
            snapshots_rate_skipped: AtomicU64::new(0),
            messages_sent: AtomicU64::new(0),
            bytes_written: AtomicU64::new(0),
            protocol_errors: AtomicU64::new(0),
            commands_busy: AtomicU64::new(0),
            read_only_refusals: AtomicU64::new(0),
            ws_refused: AtomicU64::new(0),
            ws_oversize: AtomicU64::new(0),
            ws_bad_frames: AtomicU64::new(0),
            end_to_end: Mutex::new(new_histogram()),
            encode: Mutex::new(new_histogram()),
        }
    }
}

impl PublisherStats {
    /// Most clients served at once (config `socket.max_clients`).
    pub fn max_clients(&self) -> u32 {
        self.max_clients.get()
    }

    /// Changes the client limit while the socket runs (a reload): the next
    /// connection is admitted or refused by `n`. Clients already connected stay,
    /// also when there are more of them than `n`.
    pub fn set_max_clients(&self, n: u32) {
        self.max_clients.set(n);
    }

    /// Clients connected now.
    pub fn clients(&self) -> u32 {
        self.clients.load(Ordering::Relaxed)
    }
    /// Clients accepted since start.
    pub fn clients_accepted(&self) -> u64 {
        self.clients_accepted.load(Ordering::Relaxed)
    }
    /// Connections refused because `max_clients` were connected, since start.
    pub fn clients_refused(&self) -> u64 {
        self.clients_refused.load(Ordering::Relaxed)
    }
    /// Snapshots written to clients since start (all clients).
    pub fn snapshots_sent(&self) -> u64 {
        self.snapshots_sent.load(Ordering::Relaxed)
    }
    /// Snapshots dropped for slow clients since start (all clients).
    pub fn snapshots_dropped(&self) -> u64 {
        self.snapshots_dropped.load(Ordering::Relaxed)
    }
    /// Snapshots not sent because of a client's `max_rate_hz`, since start (not "dropped").
    pub fn snapshots_rate_skipped(&self) -> u64 {
        self.snapshots_rate_skipped.load(Ordering::Relaxed)
    }
    /// Messages of every kind written since start.
    pub fn messages_sent(&self) -> u64 {
        self.messages_sent.load(Ordering::Relaxed)
    }
    /// Bytes written to client sockets since start.
    pub fn bytes_written(&self) -> u64 {
        self.bytes_written.load(Ordering::Relaxed)
    }
    /// Invalid client messages since start (fatal or not).
    pub fn protocol_errors(&self) -> u64 {
        self.protocol_errors.load(Ordering::Relaxed)
    }
    /// Commands refused because the client is read-only, since start.
    pub fn read_only_refusals(&self) -> u64 {
        self.read_only_refusals.load(Ordering::Relaxed)
    }
    /// WebSocket connections refused before the upgrade (a wrong or missing token,
    /// a foreign `Origin` or `Host`, a handshake RFC 6455 refuses, an unknown path
    /// or method, an oversize request head, too many clients).
    pub fn websocket_refused(&self) -> u64 {
        self.ws_refused.load(Ordering::Relaxed)
    }
    /// WebSocket messages over the output's `max_message_bytes` (each closed its
    /// connection), since start.
    pub fn websocket_oversize(&self) -> u64 {
        self.ws_oversize.load(Ordering::Relaxed)
    }
    /// Bad WebSocket frames (text not UTF-8, protocol violations), since start.
    pub fn websocket_bad_frames(&self) -> u64 {
        self.ws_bad_frames.load(Ordering::Relaxed)
    }
    /// Commands refused "busy" because the command queue was full, since start.
    pub fn commands_busy(&self) -> u64 {
        self.commands_busy.load(Ordering::Relaxed)
    }

    /// End-to-end latency histogram (input timestamp → snapshot bytes written to a
    /// client socket, µs) over all clients since the last call; resets it.
    pub fn take_end_to_end(&self) -> Histogram<u64> {
        take(&self.end_to_end)
    }

    /// Serialisation time per snapshot encoding (µs) since the last call; resets it.
    pub fn take_encode(&self) -> Histogram<u64> {
        take(&self.encode)
    }

    /// Counts one message written (`bytes` long); a snapshot also records its
    /// end-to-end latency from `input_t`.
    pub(crate) fn record_write(&self, bytes: usize, snapshot: bool, input_t: Option<Micros>) {
        self.bytes_written
            .fetch_add(bytes as u64, Ordering::Relaxed);
        self.messages_sent.fetch_add(1, Ordering::Relaxed);
        if snapshot {
            self.snapshots_sent.fetch_add(1, Ordering::Relaxed);
            if let Some(t) = input_t {
                let us = end_to_end_us(t);
                lock(&self.end_to_end).saturating_record(us.max(1));
            }
        }
    }

    /// Records the time one snapshot encoding took (µs).
    pub(crate) fn record_encode(&self, us: u64) {
        lock(&self.encode).saturating_record(us.max(1));
    }

    pub(crate) fn count_protocol_error(&self) {
        self.protocol_errors.fetch_add(1, Ordering::Relaxed);
    }

    pub(crate) fn count_busy(&self) {
        self.commands_busy.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a client that connected (another transport's).
    pub(crate) fn count_client_connected(&self) {
        self.clients.fetch_add(1, Ordering::Relaxed);
        self.clients_accepted.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a client that left (another transport's).
    pub(crate) fn count_client_gone(&self) {
        self.clients.fetch_sub(1, Ordering::Relaxed);
    }

    pub(crate) fn count_read_only_refusal(&self) {
        self.read_only_refusals.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a refused WebSocket handshake (401, 404, 405, 431, 400, too many).
    pub(crate) fn count_ws_refused(&self) {
        self.ws_refused.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a WebSocket message over the output's `max_message_bytes`.
    pub(crate) fn count_ws_oversize(&self) {
        self.ws_oversize.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a bad WebSocket frame (not UTF-8, a protocol violation).
    pub(crate) fn count_ws_bad_frame(&self) {
        self.ws_bad_frames.fetch_add(1, Ordering::Relaxed);
    }
}

fn take(h: &Mutex<Histogram<u64>>) -> Histogram<u64> {
    let mut g = lock(h);
    let copy = g.clone();
    g.reset();
    copy
}

/// Locks, ignoring poisoning: every critical section leaves the data consistent.
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Time of a write, for end-to-end latency.
pub(crate) fn end_to_end_us(input_t: Micros) -> u64 {
    monotonic_now().saturating_since(input_t).0
}

impl crate::publish::output::OutputStats for PublisherStats {
    fn clients(&self) -> u32 {
        PublisherStats::clients(self)
    }
    fn snapshots_dropped(&self) -> u64 {
        PublisherStats::snapshots_dropped(self)
    }
    fn take_end_to_end(&self) -> Histogram<u64> {
        PublisherStats::take_end_to_end(self)
    }
    fn take_encode(&self) -> Histogram<u64> {
        PublisherStats::take_encode(self)
    }
    /// What went wrong with clients of either transport, since start: in `stats`
    /// as the output `socket`.
    fn counters(&self) -> Option<crate::vocab::OutputCounters> {
        let count = |k: &str, v: u64| (k.to_string(), v);
        Some(crate::vocab::OutputCounters {
            output: "socket".to_string(),
            address: String::new(),
            counts: vec![
                count("clients_accepted", self.clients_accepted()),
                count("clients_refused", self.clients_refused()),
                count("protocol_errors", self.protocol_errors()),
                count("read_only_refusals", self.read_only_refusals()),
                count("commands_busy", self.commands_busy()),
                count("websocket_refused", self.websocket_refused()),
                count("websocket_oversize", self.websocket_oversize()),
                count("websocket_bad_frames", self.websocket_bad_frames()),
            ],
        })
    }
}
