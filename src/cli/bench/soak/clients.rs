//! The soak's socket clients: readers that keep reading, one that reconnects every
//! second, one that handshakes and never reads, optionally one that connects and
//! closes over and over (churn), and the one-shot command client that resizes the
//! crowd. Each adds what it saw to a shared tally the driver takes once per report
//! period.
//!
//! The soak's process holds the daemon too, so its clients are kept light: the first
//! reader (the one whose latency the report gives) has a thread of its own; every
//! other reader is served by one thread polling their sockets, which keeps only the
//! first 256 bytes of each line (the fields it checks); client threads run on small
//! stacks. Under `mlockall` every stack is resident in full.

use anyhow::{bail, Context, Result};
use crowdtouch::rt::monotonic_now;
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::os::fd::AsFd;
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long the reconnecting client stays connected before it closes and connects
/// again.
pub const RECONNECT_EVERY: Duration = Duration::from_secs(1);

/// What a reading client saw since the driver last took its tally.
#[derive(Clone, Debug, Default)]
pub struct ReadTally {
    /// Connections made.
    pub connections: u64,
    /// Snapshots read.
    pub read: u64,
    /// Snapshots missing between two consecutive snapshots of one connection:
    /// `seq` rose by more than 1 (the client gets every tick: no `max_rate_hz`).
    pub missed: u64,
    /// The part of `missed` the daemon did not announce: the gap is larger than the
    /// rise of the snapshot's cumulative `dropped` (a protocol violation).
    pub silent: u64,
    /// Snapshots the daemon dropped for this client (rise of `dropped`).
    pub dropped: u64,
    /// Snapshots whose `seq` did not rise (out of order or repeated).
    pub reordered: u64,
    /// Input → read latencies (µs): the client's CLOCK_MONOTONIC when it has read the
    /// line minus the snapshot's `input_t_us`, for snapshots that carry one.
    pub latency_us: Vec<u64>,
    /// The connection ended while the soak was still running (not by `bye`).
    pub lost_connection: u64,
}

/// What the stalled client saw since the driver last took its tally.
#[derive(Clone, Debug, Default)]
pub struct StallTally {
    /// Connections made (each handshakes, then never reads).
    pub connections: u64,
    /// Connections the daemon closed.
    pub disconnected: u64,
    /// How long each closed connection lasted (s).
    pub lasted_s: Vec<f64>,
}

/// What the churning client saw since the driver last took its tally.
#[derive(Clone, Debug, Default)]
pub struct ChurnTally {
    /// Connections that got the server's `hello` and were closed.
    pub cycles: u64,
    /// Connections that failed or were refused (no `hello`).
    pub failed: u64,
}

/// Stack of each soak client thread (bytes): they hold a few small buffers.
const CLIENT_STACK_BYTES: usize = 256 * 1024;
/// Bytes of a line the polled readers keep: the fields they read come first.
const HEAD_BYTES: usize = 256;

/// A tally shared between a client thread and the driver.
pub struct Shared<T>(Arc<Mutex<T>>);

impl<T: Default> Shared<T> {
    fn new() -> Shared<T> {
        Shared(Arc::new(Mutex::new(T::default())))
    }

    fn lock(&self) -> MutexGuard<'_, T> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Takes the tally and starts a new one.
    pub fn take(&self) -> T {
        std::mem::take(&mut *self.lock())
    }
}

impl<T> Clone for Shared<T> {
    fn clone(&self) -> Self {
        Shared(Arc::clone(&self.0))
    }
}

/// The running clients.
pub struct Clients {
    /// One tally per continuously reading client; the first has a thread of its own.
    pub readers: Vec<Shared<ReadTally>>,
    /// The client that reconnects every second.
    pub reconnecting: Shared<ReadTally>,
    /// The client that never reads.
    pub stalled: Shared<StallTally>,
    /// The client that connects and closes over and over (`--churn`).
    pub churn: Option<Shared<ChurnTally>>,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl Clients {
    /// Starts `count` clients (at least 3): one stalled, one reconnecting, the rest
    /// reading continuously; with `churn` one more that connects and closes.
    ///
    /// # Errors
    /// Thread creation, or a reader that cannot connect.
    pub fn start(socket: &Path, count: u32, churn: bool) -> Result<Clients> {
        anyhow::ensure!(
            count >= 3,
            "--clients must be at least 3 (one stalled, one reconnecting, one reading)"
        );
        let stop = Arc::new(AtomicBool::new(false));
        let mut c = Clients {
            readers: Vec::new(),
            reconnecting: Shared::new(),
            stalled: Shared::new(),
            churn: churn.then(Shared::new),
            stop: Arc::clone(&stop),
            threads: Vec::new(),
        };
        let mut polled = Vec::new();
        for i in 0..count - 2 {
            let tally = Shared::new();
            let stream = UnixStream::connect(socket).context("connecting a soak reader")?;
            if i == 0 {
                let (t, s) = (tally.clone(), Arc::clone(&stop));
                c.threads.push(spawn("soak-read0", move || {
                    read_connection(stream, &t, &s, None)
                })?);
            } else {
                polled.push((stream, tally.clone()));
            }
            c.readers.push(tally);
        }
        if !polled.is_empty() {
            let s = Arc::clone(&stop);
            c.threads
                .push(spawn("soak-readers", move || read_polled(polled, &s))?);
        }
        let (path, t, s) = (
            socket.to_path_buf(),
            c.reconnecting.clone(),
            Arc::clone(&stop),
        );
        c.threads.push(spawn("soak-reconnect", move || {
            reconnecting(&path, &t, &s)
        })?);
        let (path, t, s) = (socket.to_path_buf(), c.stalled.clone(), Arc::clone(&stop));
        c.threads
            .push(spawn("soak-stalled", move || stalled(&path, &t, &s))?);
        if let Some(tally) = &c.churn {
            let (path, t, s) = (socket.to_path_buf(), tally.clone(), Arc::clone(&stop));
            c.threads
                .push(spawn("soak-churn", move || churning(&path, &t, &s))?);
        }
        Ok(c)
    }

    /// Tells every client to stop (call before the daemon shuts down, so a closed
    /// connection is not counted as lost).
    pub fn stopping(&self) {
        self.stop.store(true, Ordering::SeqCst);
    }

    /// Waits for every client thread.
    pub fn join(self) {
        self.stop.store(true, Ordering::SeqCst);
        for t in self.threads {
            let _ = t.join();
        }
    }
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) -> Result<JoinHandle<()>> {
    std::thread::Builder::new()
        .name(name.into())
        .stack_size(CLIENT_STACK_BYTES)
        .spawn(f)
        .with_context(|| format!("starting the {name} thread"))
}

/// The number after `key` in a JSON line (`None` when absent or `null`). The keys
/// the soak reads come before the arrays, so only the line's head is searched.
fn number_after(line: &[u8], key: &[u8]) -> Option<u64> {
    let head = &line[..line.len().min(256)];
    let at = head.windows(key.len()).position(|w| w == key)? + key.len();
    let digits = head[at..].iter().take_while(|b| b.is_ascii_digit()).count();
    std::str::from_utf8(&head[at..at + digits])
        .ok()?
        .parse()
        .ok()
}

/// Continuity of one connection's snapshot stream.
#[derive(Default)]
struct Stream {
    last_seq: Option<u64>,
    last_dropped: u64,
}

impl Stream {
    /// Accounts one snapshot line (read at `now_us`) into `t`.
    fn snapshot(&mut self, line: &[u8], now_us: u64, t: &mut ReadTally) {
        let (Some(seq), Some(dropped)) = (
            number_after(line, b"\"seq\":"),
            number_after(line, b"\"dropped\":"),
        ) else {
            return;
        };
        t.read += 1;
        let announced = dropped.saturating_sub(self.last_dropped);
        t.dropped += announced;
        if let Some(prev) = self.last_seq {
            if seq <= prev {
                t.reordered += 1;
            } else {
                let gap = seq - prev - 1;
                t.missed += gap;
                t.silent += gap.saturating_sub(announced);
            }
        }
        self.last_seq = Some(self.last_seq.map_or(seq, |p| p.max(seq)));
        self.last_dropped = dropped;
        if let Some(input) = number_after(line, b"\"input_t_us\":") {
            t.latency_us.push(now_us.saturating_sub(input));
        }
    }
}

/// Reads one connection until `bye`, end of stream, `stop`, or `until`; an end
/// before `stop` is counted as a lost connection.
fn read_connection(
    stream: UnixStream,
    tally: &Shared<ReadTally>,
    stop: &AtomicBool,
    until: Option<Instant>,
) {
    tally.lock().connections += 1;
    // A timeout only so that `stop` and `until` are looked at; bytes read before
    // a timeout stay in `line` and the next read_until appends to them.
    let _ = stream.set_read_timeout(Some(Duration::from_millis(100)));
    let mut r = BufReader::with_capacity(1 << 16, stream);
    let mut line = Vec::with_capacity(1 << 16);
    let mut s = Stream::default();
    loop {
        if until.is_some_and(|u| Instant::now() >= u) {
            return;
        }
        match r.read_until(b'\n', &mut line) {
            Ok(0) => break,
            Ok(_) if line.last() == Some(&b'\n') => {
                let now_us = monotonic_now().0;
                if line.starts_with(b"{\"type\":\"snapshot\"") {
                    s.snapshot(&line, now_us, &mut tally.lock());
                } else if line.starts_with(b"{\"type\":\"bye\"") {
                    return;
                }
                line.clear();
            }
            Ok(_) => break,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if stop.load(Ordering::Relaxed) && until.is_none() {
                    return;
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => break,
        }
    }
    if !stop.load(Ordering::Relaxed) {
        tally.lock().lost_connection += 1;
    }
}

/// One reader served by [`read_polled`]: the head of the line being read.
struct Polled {
    stream: UnixStream,
    tally: Shared<ReadTally>,
    s: Stream,
    head: Vec<u8>,
    open: bool,
}

impl Polled {
    /// Accounts `bytes` read from the socket at `now_us`; false at `bye`.
    fn take(&mut self, mut bytes: &[u8], now_us: u64) -> bool {
        while !bytes.is_empty() {
            let (part, end) = match bytes.iter().position(|&b| b == b'\n') {
                Some(i) => (&bytes[..i], true),
                None => (bytes, false),
            };
            let room = HEAD_BYTES.saturating_sub(self.head.len());
            self.head.extend_from_slice(&part[..part.len().min(room)]);
            bytes = &bytes[part.len() + usize::from(end)..];
            if end {
                if self.head.starts_with(b"{\"type\":\"snapshot\"") {
                    self.s.snapshot(&self.head, now_us, &mut self.tally.lock());
                } else if self.head.starts_with(b"{\"type\":\"bye\"") {
                    return false;
                }
                self.head.clear();
            }
        }
        true
    }
}

/// Reads every reader of `conns` from one thread until `bye`, end of stream or
/// `stop`; an end before `stop` is counted as a lost connection.
fn read_polled(conns: Vec<(UnixStream, Shared<ReadTally>)>, stop: &AtomicBool) {
    use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
    let mut conns: Vec<Polled> = conns
        .into_iter()
        .filter_map(|(stream, tally)| {
            stream.set_nonblocking(true).ok()?;
            tally.lock().connections += 1;
            Some(Polled {
                stream,
                tally,
                s: Stream::default(),
                head: Vec::with_capacity(HEAD_BYTES),
                open: true,
            })
        })
        .collect();
    let mut buf = vec![0u8; 1 << 16];
    while !stop.load(Ordering::Relaxed) && conns.iter().any(|c| c.open) {
        let ready: Vec<bool> = {
            let mut fds: Vec<PollFd> = conns
                .iter()
                .map(|c| {
                    let events = if c.open {
                        PollFlags::POLLIN
                    } else {
                        PollFlags::empty()
                    };
                    PollFd::new(c.stream.as_fd(), events)
                })
                .collect();
            if poll(&mut fds, PollTimeout::from(100u8)).is_err() {
                continue;
            }
            fds.iter()
                .map(|f| f.revents().is_some_and(|r| !r.is_empty()))
                .collect()
        };
        for (c, ready) in conns.iter_mut().zip(ready) {
            if !ready || !c.open {
                continue;
            }
            // A few reads per round, so one busy socket does not starve the others.
            for _ in 0..4 {
                match (&c.stream).read(&mut buf) {
                    Ok(0) => {
                        c.open = false;
                        if !stop.load(Ordering::Relaxed) {
                            c.tally.lock().lost_connection += 1;
                        }
                        break;
                    }
                    Ok(n) => {
                        if !c.take(&buf[..n], monotonic_now().0) {
                            c.open = false;
                            break;
                        }
                    }
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(_) => {
                        c.open = false;
                        if !stop.load(Ordering::Relaxed) {
                            c.tally.lock().lost_connection += 1;
                        }
                        break;
                    }
                }
            }
        }
    }
}

/// Connects, reads the server's `hello` line, closes; again, as fast as the daemon
/// answers.
fn churning(path: &Path, tally: &Shared<ChurnTally>, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        let hello = UnixStream::connect(path).and_then(|s| {
            s.set_read_timeout(Some(Duration::from_secs(5)))?;
            let mut line = Vec::new();
            BufReader::with_capacity(1024, s).read_until(b'\n', &mut line)?;
            Ok(line)
        });
        match hello {
            Ok(line) if line.starts_with(b"{\"type\":\"hello\"") => tally.lock().cycles += 1,
            _ => {
                tally.lock().failed += 1;
                std::thread::sleep(Duration::from_millis(10));
            }
        }
    }
}

/// Connects, reads for [`RECONNECT_EVERY`], closes, connects again.
fn reconnecting(path: &Path, tally: &Shared<ReadTally>, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        let until = Instant::now() + RECONNECT_EVERY;
        match UnixStream::connect(path) {
            Ok(stream) => read_connection(stream, tally, stop, Some(until)),
            Err(_) => {
                tally.lock().lost_connection += 1;
                std::thread::sleep(Duration::from_millis(100));
            }
        }
    }
}

/// Connects, reads the server's `hello` and answers with its own, then never reads
/// again; when the daemon closes the connection (a socket that takes no bytes for
/// 10 s is disconnected, docs/protocol.md "Slow clients and drops") it connects and
/// stalls again.
fn stalled(path: &Path, tally: &Shared<StallTally>, stop: &AtomicBool) {
    use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
    while !stop.load(Ordering::Relaxed) {
        let Ok(mut stream) = UnixStream::connect(path) else {
            std::thread::sleep(Duration::from_millis(100));
            continue;
        };
        let since = Instant::now();
        if handshake(&mut stream).is_err() {
            continue;
        }
        tally.lock().connections += 1;
        loop {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            let mut fds = [PollFd::new(stream.as_fd(), PollFlags::empty())];
            let hung_up = match poll(&mut fds, PollTimeout::from(200u8)) {
                Ok(_) => fds[0]
                    .revents()
                    .is_some_and(|r| r.intersects(PollFlags::POLLHUP | PollFlags::POLLERR)),
                Err(_) => false,
            };
            if hung_up {
                let mut t = tally.lock();
                t.disconnected += 1;
                t.lasted_s.push(since.elapsed().as_secs_f64());
                break;
            }
        }
    }
}

/// Reads the server's `hello` line one byte at a time (nothing after it) and sends
/// a client `hello` asking for the default stream.
fn handshake(stream: &mut UnixStream) -> Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(5)))?;
    let mut b = [0u8; 1];
    let mut line = Vec::new();
    while b[0] != b'\n' {
        if stream.read(&mut b)? == 0 {
            bail!("closed during the handshake");
        }
        line.push(b[0]);
    }
    if !line.starts_with(b"{\"type\":\"hello\"") {
        bail!("the server did not start with hello");
    }
    stream.write_all(b"{\"type\":\"hello\",\"protocol\":1}\n")?;
    Ok(())
}

/// Sends one command on a connection of its own that subscribes to nothing, and
/// waits for its `ack` (an `error` reply is returned as the error).
///
/// # Errors
/// The daemon's refusal, or no answer within 5 s.
pub fn command(socket: &PathBuf, id: u64, body: &str) -> Result<()> {
    let stream = UnixStream::connect(socket).context("connecting the command client")?;
    stream.set_read_timeout(Some(Duration::from_secs(5)))?;
    let mut w = stream.try_clone()?;
    writeln!(w, "{{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[]}}")?;
    writeln!(w, "{{\"type\":\"command\",\"id\":{id},{body}}}")?;
    let ack = format!("{{\"type\":\"ack\",\"id\":{id}}}");
    let mut r = BufReader::new(stream);
    let mut line = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(5);
    while Instant::now() < deadline {
        line.clear();
        if r.read_until(b'\n', &mut line)? == 0 {
            bail!("the daemon closed the command connection");
        }
        if line.starts_with(ack.as_bytes()) {
            return Ok(());
        }
        if line.starts_with(b"{\"type\":\"error\"") {
            bail!(
                "command refused: {}",
                String::from_utf8_lossy(&line).trim_end()
            );
        }
    }
    bail!("no answer to command {id} within 5 s")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(seq: u64, dropped: u64) -> Vec<u8> {
        format!("{{\"type\":\"snapshot\",\"seq\":{seq},\"t_us\":5,\"latency_us\":3,\"input_t_us\":100,\"dropped\":{dropped},\"agents\":1,\"assignment_seq\":{}}}\n", seq + 7).into_bytes()
    }

    #[test]
    fn gaps_are_missed_and_silent_unless_dropped_rises() {
        let mut s = Stream::default();
        let mut t = ReadTally::default();
        for (seq, dropped) in [(10, 0), (11, 0), (14, 2), (15, 2), (17, 2), (16, 2)] {
            s.snapshot(&line(seq, dropped), 150, &mut t);
        }
        assert_eq!(t.read, 6);
        // 11 → 14: 2 missing, announced by `dropped` 0 → 2; 15 → 17: 1 missing, silent.
        assert_eq!((t.missed, t.dropped, t.silent, t.reordered), (3, 2, 1, 1));
        assert_eq!(t.latency_us, vec![50; 6]);
    }

    #[test]
    fn null_input_time_gives_no_latency_sample() {
        let l = b"{\"type\":\"snapshot\",\"seq\":3,\"t_us\":5,\"latency_us\":null,\"input_t_us\":null,\"dropped\":0}\n";
        let mut t = ReadTally::default();
        Stream::default().snapshot(l, 150, &mut t);
        assert_eq!((t.read, t.latency_us.len()), (1, 0));
        assert_eq!(number_after(l, b"\"seq\":"), Some(3));
    }
}
