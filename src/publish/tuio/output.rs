//! The TUIO output: its thread, the rate limit, sending, and its counters.
//!
//! It runs on a thread of its own (`ct-tuio`) behind a queue of
//! [`QUEUE_CAPACITY`] messages that drops the oldest when full (only the newest
//! crowd matters). It sends at most `rate_hz` frames a second: a snapshot that
//! arrives before the next frame is due waits, replaced by any newer one, and the
//! newest always goes out when it is due, so a lifted touch or a removed agent
//! leaves the alive lists at the next frame even when snapshots stop.
//!
//! The target is resolved once, at start ([`TuioOutput::new`] fails with the
//! target named when it does not resolve: a typo shows at once rather than as
//! silence). Sending never blocks: the socket is non-blocking and connected to the
//! target, so a refused or unreachable target (ICMP) shows as an error on a later
//! send, which is counted and logged at most every [`LOG_EVERY_US`] with the
//! target, never fatal; datagrams keep going out in case the renderer starts.
//! On stop, one last frame with empty alive lists tells the renderer everything
//! is gone.

use super::encode11::{Encoder11, Profiles};
use super::encode20::Encoder20;
use super::frame::Framer;
use super::options::{Error, TuioOptions, Version};
use super::split::Datagrams;
use crate::publish::{Outgoing, Output, OutputContext, OutputStats, Overflow, QueuePolicy};
use crate::rt::monotonic_now;
use crate::vocab::{Micros, OutputCounters, Snapshot};
use crossbeam_channel::RecvTimeoutError;
use hdrhistogram::Histogram;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, SystemTime};

/// Messages the output's queue holds (drop-oldest).
pub const QUEUE_CAPACITY: usize = 4;
/// Shortest time between two log lines about one kind of trouble (µs).
pub const LOG_EVERY_US: u64 = 10_000_000;
/// How long the thread waits for a message before it checks `stop` (ms).
const POLL_MS: u64 = 100;

/// A TUIO output's counters, read by `stats` and the tests.
#[derive(Debug, Default)]
pub struct TuioStats {
    /// The configured target, as `stats` names it.
    target: String,
    frames: AtomicU64,
    datagrams: AtomicU64,
    bytes: AtomicU64,
    send_errors: AtomicU64,
    skipped: AtomicU64,
    dropped: AtomicU64,
    truncated: AtomicU64,
    reachable: AtomicU32,
}

impl TuioStats {
    /// Frames sent.
    pub fn frames(&self) -> u64 {
        self.frames.load(Ordering::Relaxed)
    }
    /// Datagrams sent.
    pub fn datagrams(&self) -> u64 {
        self.datagrams.load(Ordering::Relaxed)
    }
    /// Bytes sent (UDP payload).
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }
    /// Datagrams that could not be sent (refused, unreachable, no buffer room).
    pub fn send_errors(&self) -> u64 {
        self.send_errors.load(Ordering::Relaxed)
    }
    /// Snapshots replaced by a newer one before their frame was due (the rate
    /// limit).
    pub fn skipped(&self) -> u64 {
        self.skipped.load(Ordering::Relaxed)
    }
    /// Entities left out of frames because their alive list would not fit a
    /// datagram (raise `max_datagram_bytes`).
    pub fn truncated(&self) -> u64 {
        self.truncated.load(Ordering::Relaxed)
    }
}

impl OutputStats for TuioStats {
    /// 1 while the target takes the datagrams (the last send succeeded), else 0.
    fn clients(&self) -> u32 {
        self.reachable.load(Ordering::Relaxed)
    }
    /// Snapshots the full queue dropped before this thread saw them (gaps in
    /// the snapshots' sequence numbers); the rate limit's skips are not drops.
    fn snapshots_dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }
    /// Not reported: the daemon's end-to-end figure is touch-to-socket, and a
    /// rate-limited UDP stream would only blur it.
    fn take_end_to_end(&self) -> Histogram<u64> {
        empty_histogram()
    }
    /// Not reported, for the same reason.
    fn take_encode(&self) -> Histogram<u64> {
        empty_histogram()
    }
    /// Frames, datagrams and bytes sent, send errors, snapshots skipped by the
    /// rate limit and entities left out for room.
    fn counters(&self) -> Option<OutputCounters> {
        let count = |k: &str, v: u64| (k.to_string(), v);
        Some(OutputCounters {
            output: "tuio".to_string(),
            address: self.target.clone(),
            counts: vec![
                count("frames", self.frames()),
                count("datagrams", self.datagrams()),
                count("bytes", self.bytes()),
                count("send_errors", self.send_errors()),
                count("skipped", self.skipped()),
                count("left_out", self.truncated()),
            ],
        })
    }
}

fn empty_histogram() -> Histogram<u64> {
    // Constant bounds hdrhistogram accepts (the socket's): not input.
    #[allow(clippy::expect_used)]
    Histogram::new_with_bounds(1, 60_000_000, 3).expect("valid histogram bounds")
}

/// Sends the crowd as TUIO over UDP to one target.
pub struct TuioOutput {
    opts: TuioOptions,
    target: SocketAddr,
    socket: UdpSocket,
    stats: Arc<TuioStats>,
}

impl TuioOutput {
    /// Resolves the target and opens a non-blocking UDP socket connected to it.
    ///
    /// # Errors
    /// [`Error::Resolve`] or [`Error::NoAddress`] when the target does not resolve,
    /// [`Error::Socket`] when no UDP socket can be opened.
    pub fn new(opts: TuioOptions) -> Result<TuioOutput, Error> {
        let target = opts
            .target
            .to_socket_addrs()
            .map_err(|source| Error::Resolve {
                target: opts.target.clone(),
                source,
            })?
            .next()
            .ok_or_else(|| Error::NoAddress {
                target: opts.target.clone(),
            })?;
        let local: SocketAddr = if target.is_ipv4() {
            (std::net::Ipv4Addr::UNSPECIFIED, 0).into()
        } else {
            (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
        };
        let socket_err = |source| Error::Socket {
            target: opts.target.clone(),
            source,
        };
        let socket = UdpSocket::bind(local).map_err(socket_err)?;
        socket.set_nonblocking(true).map_err(socket_err)?;
        socket.connect(target).map_err(socket_err)?;
        let stats = Arc::new(TuioStats {
            target: opts.target.clone(),
            ..TuioStats::default()
        });
        Ok(TuioOutput {
            opts,
            target,
            socket,
            stats,
        })
    }

    /// The address the datagrams go to.
    pub fn target(&self) -> SocketAddr {
        self.target
    }

    /// The output's counters.
    pub fn tuio_stats(&self) -> Arc<TuioStats> {
        Arc::clone(&self.stats)
    }
}

/// The sending side: framer, encoders, buffers and the rate-limited logs.
struct Sender {
    opts: TuioOptions,
    socket: UdpSocket,
    stats: Arc<TuioStats>,
    framer: Framer,
    enc11: Encoder11,
    enc20: Encoder20,
    datagrams: Datagrams,
    fseq: i32,
    error_log: RateLimitedLog,
    cut_log: RateLimitedLog,
}

/// A log line at most every [`LOG_EVERY_US`], saying how often it happened since.
struct RateLimitedLog {
    last: Option<Micros>,
    since: u64,
}

impl RateLimitedLog {
    fn new() -> Self {
        RateLimitedLog {
            last: None,
            since: 0,
        }
    }

    /// Counts one occurrence; returns how many to report when a line is due.
    fn due(&mut self, now: Micros) -> Option<u64> {
        self.since += 1;
        if self
            .last
            .is_some_and(|t| now.saturating_since(t).0 < LOG_EVERY_US)
        {
            return None;
        }
        self.last = Some(now);
        Some(std::mem::take(&mut self.since))
    }
}

impl Sender {
    fn send(&mut self, snap: &Snapshot) {
        let o = &self.opts;
        let frame = self.framer.build(snap, o.cursors, o.objects, o.blobs);
        self.datagrams.clear();
        let cut = match o.version {
            Version::V1_1 => self.enc11.encode(
                frame,
                Profiles {
                    cursors: o.cursors,
                    objects: o.objects,
                    blobs: o.blobs,
                },
                self.fseq,
                o.max_datagram_bytes,
                &mut self.datagrams,
            ),
            Version::V2_0 => {
                let ttag = frame_time(snap.t);
                self.enc20.encode(
                    frame,
                    self.fseq,
                    ttag,
                    o.max_datagram_bytes,
                    &mut self.datagrams,
                )
            }
        };
        self.fseq = if self.fseq == i32::MAX {
            1
        } else {
            self.fseq + 1
        };
        let now = monotonic_now();
        if cut > 0 {
            self.stats
                .truncated
                .fetch_add(cut as u64, Ordering::Relaxed);
            if let Some(n) = self.cut_log.due(now) {
                log::warn!(
                    "TUIO output to {}: {cut} entities left out of a frame ({n} such frames since the last line): \
                     their alive list does not fit a datagram of {} bytes; raise max_datagram_bytes",
                    o.target,
                    o.max_datagram_bytes
                );
            }
        }
        let mut ok = true;
        for d in self.datagrams.iter() {
            match self.socket.send(d) {
                Ok(_) => {
                    self.stats.datagrams.fetch_add(1, Ordering::Relaxed);
                    self.stats
                        .bytes
                        .fetch_add(d.len() as u64, Ordering::Relaxed);
                }
                Err(e) => {
                    ok = false;
                    self.stats.send_errors.fetch_add(1, Ordering::Relaxed);
                    if let Some(n) = self.error_log.due(now) {
                        log::warn!(
                            "TUIO output to {}: cannot send ({e}); {n} datagrams lost since the last line; still trying",
                            o.target
                        );
                    }
                }
            }
        }
        self.stats.frames.fetch_add(1, Ordering::Relaxed);
        self.stats.reachable.store(u32::from(ok), Ordering::Relaxed);
    }
}

/// The OSC time tag of a snapshot taken at `t` (CLOCK_MONOTONIC): the wall clock
/// now, less the snapshot's age.
fn frame_time(t: Micros) -> rosc::OscTime {
    let age = Duration::from_micros(monotonic_now().saturating_since(t).0);
    let wall = SystemTime::now()
        .checked_sub(age)
        .unwrap_or(SystemTime::UNIX_EPOCH);
    rosc::OscTime::try_from(wall).unwrap_or(rosc::OscTime {
        seconds: 0,
        fractional: 1,
    })
}

impl Output for TuioOutput {
    fn name(&self) -> &'static str {
        "tuio"
    }

    fn queue(&self) -> QueuePolicy {
        QueuePolicy {
            capacity: QUEUE_CAPACITY,
            overflow: Overflow::DropOldest,
        }
    }

    /// Snapshots only: events, replies, transforms and the scene's poses would take
    /// room in the drop-oldest queue and push snapshots out.
    fn wants(&self) -> fn(&Outgoing) -> bool {
        |m| matches!(m, Outgoing::Snapshot(_))
    }

    fn stats(&self) -> Arc<dyn OutputStats> {
        self.stats.clone()
    }

    fn run(self: Box<Self>, ctx: OutputContext) {
        let TuioOutput {
            opts,
            target,
            socket,
            stats,
        } = *self;
        log::info!(
            "TUIO {} output to {target} ({}), at most {} Hz, datagrams of at most {} bytes",
            match opts.version {
                Version::V1_1 => "1.1",
                Version::V2_0 => "2.0",
            },
            opts.target,
            opts.rate_hz,
            opts.max_datagram_bytes
        );
        let period_us = (1e6 / opts.rate_hz.max(1e-3)) as u64;
        let mut s = Sender {
            framer: Framer::new(opts.world),
            enc11: Encoder11::new(&opts.source),
            enc20: Encoder20::new(&opts.source, opts.world),
            datagrams: Datagrams::default(),
            fseq: 1,
            error_log: RateLimitedLog::new(),
            cut_log: RateLimitedLog::new(),
            opts,
            socket,
            stats,
        };
        let mut pending: Option<Arc<Snapshot>> = None;
        let mut last_seq: Option<u64> = None;
        let mut last_sent: Option<Micros> = None;
        let mut last_t = Micros::ZERO;
        let mut take = |m: Outgoing, pending: &mut Option<Arc<Snapshot>>, stats: &TuioStats| {
            if let Outgoing::Snapshot(snap) = m {
                if let Some(prev) = last_seq {
                    let gap = snap.seq.saturating_sub(prev).saturating_sub(1);
                    stats.dropped.fetch_add(gap, Ordering::Relaxed);
                }
                last_seq = Some(snap.seq);
                if pending.replace(snap).is_some() {
                    stats.skipped.fetch_add(1, Ordering::Relaxed);
                }
            }
        };
        loop {
            if ctx.stop.load(Ordering::Relaxed) {
                break;
            }
            let now = monotonic_now();
            let due = last_sent.map_or(now, |t| t + Micros(period_us));
            let wait_us = match pending {
                Some(_) => due.saturating_since(now).0,
                None => POLL_MS * 1000,
            }
            .min(POLL_MS * 1000);
            match ctx.messages.recv_timeout(Duration::from_micros(wait_us)) {
                Ok(m) => {
                    take(m, &mut pending, &s.stats);
                    while let Ok(m) = ctx.messages.try_recv() {
                        take(m, &mut pending, &s.stats);
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            let now = monotonic_now();
            if pending.is_some() && last_sent.is_none_or(|t| now.saturating_since(t).0 >= period_us)
            {
                if let Some(snap) = pending.take() {
                    last_t = snap.t;
                    s.send(&snap);
                    last_sent = Some(now);
                }
            }
        }
        // Goodbye: nothing alive.
        s.send(&Snapshot {
            t: last_t,
            ..Snapshot::default()
        });
    }
}
