//! The socket's I/O thread: every client's socket on one `epoll`, non-blocking.
//!
//! It accepts clients, writes what the publisher queued for them (resuming partial
//! writes when the socket is writable again), reads their lines, and closes them.
//! The publisher wakes it through an eventfd after queueing; every
//! [`HOUSEKEEPING_INTERVAL`] it also looks for stalled, overdue and throttled
//! clients. However many clients connect, this is one thread.

use super::budget::{Budget, ACCEPTS_PER_SECOND, ACCEPT_BURST};
use super::conn::{Conn, Fate, Write};
use super::hub::Hub;
use super::queue::ClientShared;
use super::stats::lock;
use crate::publish::protocol;
use crate::rt::monotonic_now;
use nix::sys::epoll::{Epoll, EpollEvent, EpollFlags, EpollTimeout};
use std::io::ErrorKind;
use std::net::Shutdown;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often (ms) the I/O thread looks at every client without being woken: write
/// stalls, closing clients past their grace, unanswered commands, line budgets.
const HOUSEKEEPING_MS: u16 = 50;
const HOUSEKEEPING_INTERVAL: Duration = Duration::from_millis(HOUSEKEEPING_MS as u64);
/// Least time between two log lines about a failing `accept`.
const ACCEPT_LOG_INTERVAL: Duration = Duration::from_secs(10);
/// Connections accepted per round, so a connect storm does not starve the clients.
const ACCEPTS_PER_ROUND: usize = 16;
/// Send buffer requested for each client socket (bytes): room for several
/// 1,000-agent snapshots, so a reader that is briefly late never fills it.
pub const CLIENT_SNDBUF_BYTES: usize = 1 << 20;
/// A client whose socket takes no bytes for this long is disconnected.
pub const WRITE_STALL_TIMEOUT: Duration = Duration::from_secs(10);
/// At shutdown, how long clients get to read their `bye` before every socket closes.
pub const SHUTDOWN_GRACE: Duration = Duration::from_millis(250);

/// The epoll token of the listener and of the wake-up eventfd; a client's token is
/// its slot and the low 32 bits of its id (a reused slot never takes a stale event).
const LISTENER: u64 = u64::MAX;
const WAKE: u64 = u64::MAX - 1;

fn token(slot: usize, id: u64) -> u64 {
    ((slot as u64) << 32) | (id & 0xffff_ffff)
}

/// The I/O thread's state.
pub(crate) struct IoLoop {
    hub: Arc<Hub>,
    listener: UnixListener,
    path: PathBuf,
    epoll: Epoll,
    conns: Vec<Option<Conn>>,
    free: Vec<usize>,
    last_accept_log: Option<Instant>,
    last_housekeeping: Instant,
    shutdown_since: Option<Instant>,
    /// Connections per second ([`ACCEPTS_PER_SECOND`]); when spent, the listener
    /// is not polled until the next housekeeping round.
    accepts: Budget,
    listener_polled: bool,
}

impl IoLoop {
    /// The loop for `listener` (non-blocking), registered with `epoll` with the
    /// hub's wake-up.
    ///
    /// # Errors
    /// `epoll_ctl`'s.
    pub fn new(
        hub: Arc<Hub>,
        listener: UnixListener,
        path: PathBuf,
        epoll: Epoll,
    ) -> nix::Result<IoLoop> {
        epoll.add(&listener, EpollEvent::new(EpollFlags::EPOLLIN, LISTENER))?;
        epoll.add(
            hub.wake_source(),
            EpollEvent::new(EpollFlags::EPOLLIN, WAKE),
        )?;
        Ok(IoLoop {
            hub,
            listener,
            path,
            epoll,
            conns: Vec::new(),
            free: Vec::new(),
            last_accept_log: None,
            last_housekeeping: Instant::now(),
            shutdown_since: None,
            accepts: Budget::new(ACCEPTS_PER_SECOND, ACCEPT_BURST, monotonic_now()),
            listener_polled: true,
        })
    }

    /// Thread body: serves clients until the hub is closing and every client has
    /// taken its `bye` (or [`SHUTDOWN_GRACE`] has passed).
    pub fn run(mut self) {
        let mut events = [EpollEvent::empty(); 64];
        loop {
            let n = match self
                .epoll
                .wait(&mut events, EpollTimeout::from(HOUSEKEEPING_MS))
            {
                Ok(n) => n,
                Err(nix::errno::Errno::EINTR) => 0,
                Err(e) => {
                    log::error!("{}: epoll_wait failed: {e}", self.path.display());
                    std::thread::sleep(HOUSEKEEPING_INTERVAL);
                    0
                }
            };
            let (mut woken, mut connecting) = (false, false);
            for ev in &events[..n] {
                match ev.data() {
                    LISTENER => connecting = true,
                    WAKE => woken = true,
                    t => self.event(t, ev.events()),
                }
            }
            // The clients first: what is queued for them, then new connections.
            if woken {
                self.hub.take_wake();
                self.serve_all(false);
            }
            if connecting {
                self.accept_pending();
            }
            if self.last_housekeeping.elapsed() >= HOUSEKEEPING_INTERVAL {
                self.last_housekeeping = Instant::now();
                self.serve_all(true);
                self.poll_listener(true);
            }
            if self.hub.is_closing() && self.shut_down_step() {
                return;
            }
        }
    }

    /// A readiness event for a client.
    fn event(&mut self, token: u64, ev: EpollFlags) {
        let slot = (token >> 32) as usize;
        let Some(c) = self.conns.get_mut(slot).and_then(Option::as_mut) else {
            return;
        };
        if c.id() & 0xffff_ffff != token & 0xffff_ffff {
            return; // a removed client's event; the slot has a new client
        }
        let hub = &self.hub;
        let mut fate = Fate::Keep;
        if ev.intersects(EpollFlags::EPOLLIN | EpollFlags::EPOLLRDHUP | EpollFlags::EPOLLHUP) {
            fate = c.input(hub, monotonic_now());
        }
        // Writable again, or idle with replies the input may just have queued.
        if fate == Fate::Keep
            && (c.write == Write::Idle
                || ev.intersects(EpollFlags::EPOLLOUT | EpollFlags::EPOLLERR))
        {
            fate = c.flush(&hub.stats, Instant::now());
        }
        if ev.intersects(EpollFlags::EPOLLHUP | EpollFlags::EPOLLERR) {
            // Hung up (a half-close is not a hang-up): what it sent is acted on
            // above; what it has not been sent no longer matters.
            log::debug!("client {}: hung up", c.id());
            fate = Fate::Remove;
        }
        self.settle(slot, fate);
    }

    /// Writes what is queued for every client; with `housekeeping`, also drops
    /// clients stalled or closing for too long, times out unanswered commands and
    /// resumes input that waited.
    fn serve_all(&mut self, housekeeping: bool) {
        let now = Instant::now();
        for slot in 0..self.conns.len() {
            let Some(c) = self.conns[slot].as_mut() else {
                continue;
            };
            let hub = &self.hub;
            if housekeeping {
                let mut q = c.shared.lock();
                let overdue = q.close_overdue();
                if let Err(o) = q.expire_replies(now) {
                    q.fail(&o.to_string());
                }
                drop(q);
                if overdue {
                    log::debug!("client {}: did not take its last messages in time", c.id());
                    self.settle(slot, Fate::Remove);
                    continue;
                }
                if c.stalled_since
                    .is_some_and(|t| now.saturating_duration_since(t) >= WRITE_STALL_TIMEOUT)
                {
                    log::info!(
                        "client {}: took no data for {:?}; disconnecting",
                        c.id(),
                        WRITE_STALL_TIMEOUT
                    );
                    self.settle(slot, Fate::Remove);
                    continue;
                }
            }
            let mut fate = Fate::Keep;
            if c.paused {
                fate = c.input(hub, monotonic_now());
            }
            if fate == Fate::Keep && c.write == Write::Idle {
                fate = c.flush(&hub.stats, now);
            }
            self.settle(slot, fate);
        }
    }

    /// Removes the client in `slot`, or brings its epoll interest up to date.
    fn settle(&mut self, slot: usize, fate: Fate) {
        let Some(c) = self.conns[slot].as_mut() else {
            return;
        };
        if fate == Fate::Remove {
            self.remove(slot);
            return;
        }
        let mut want = EpollFlags::empty();
        if c.wants_input() {
            want |= EpollFlags::EPOLLIN | EpollFlags::EPOLLRDHUP;
        }
        if c.write == Write::Blocked {
            want |= EpollFlags::EPOLLOUT;
        }
        if want != c.interest {
            let mut ev = EpollEvent::new(want, token(slot, c.id()));
            match self.epoll.modify(&c.stream, &mut ev) {
                Ok(()) => c.interest = want,
                Err(e) => {
                    log::warn!("client {}: cannot poll its socket: {e}", c.id());
                    self.remove(slot);
                }
            }
        }
    }

    fn remove(&mut self, slot: usize) {
        let Some(c) = self.conns[slot].take() else {
            return;
        };
        self.free.push(slot);
        if c.touched() {
            self.hub.lift_touches(c.id());
        }
        c.shared.lock().dead = true;
        let _ = self.epoll.delete(&c.stream);
        let _ = c.stream.shutdown(Shutdown::Both);
        lock(&self.hub.clients).retain(|s| !Arc::ptr_eq(s, &c.shared));
        self.hub.stats.clients.fetch_sub(1, Ordering::Relaxed);
        log::debug!("client {}: disconnected", c.id());
    }

    /// Polls the listener for connections, or stops polling it.
    fn poll_listener(&mut self, on: bool) {
        if on == self.listener_polled || self.shutdown_since.is_some() {
            return;
        }
        let flags = if on {
            EpollFlags::EPOLLIN
        } else {
            EpollFlags::empty()
        };
        let mut ev = EpollEvent::new(flags, LISTENER);
        match self.epoll.modify(&self.listener, &mut ev) {
            Ok(()) => self.listener_polled = on,
            Err(e) => log::warn!("{}: cannot poll the listener: {e}", self.path.display()),
        }
    }

    fn accept_pending(&mut self) {
        if self.shutdown_since.is_some() {
            return;
        }
        for _ in 0..ACCEPTS_PER_ROUND {
            if !self.accepts.ready(monotonic_now()) {
                // The rest wait in the listen backlog until the next round.
                self.poll_listener(false);
                return;
            }
            match self.listener.accept() {
                Ok((stream, _)) => {
                    self.accepts.take(monotonic_now());
                    self.admit(stream);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    // EMFILE and friends: try again next round, say so now and then.
                    if self
                        .last_accept_log
                        .is_none_or(|t| t.elapsed() >= ACCEPT_LOG_INTERVAL)
                    {
                        log::warn!("{}: accept failed: {e}", self.path.display());
                        self.last_accept_log = Some(Instant::now());
                    }
                    return;
                }
            }
        }
    }

    fn admit(&mut self, stream: UnixStream) {
        let stats = &self.hub.stats;
        // A fresh socket's buffer is empty; never block on it anyway.
        if let Err(e) = stream.set_nonblocking(true) {
            log::warn!("a client: cannot set up the connection: {e}");
            return;
        }
        // This socket's clients (WebSocket clients have their own limit).
        let connected = self.conns.iter().flatten().count();
        let max = stats.max_clients() as usize;
        if connected >= max {
            stats.clients_refused.fetch_add(1, Ordering::Relaxed);
            log::warn!(
                "refusing a client: {connected} clients connected (config socket.max_clients)"
            );
            let mut json = Vec::new();
            let msg = format!("too many clients: {connected} connected (socket.max_clients)");
            protocol::encode_error(None, &msg, true, &mut json);
            let _ = nix::sys::socket::send(
                std::os::fd::AsRawFd::as_raw_fd(&stream),
                &json,
                nix::sys::socket::MsgFlags::MSG_NOSIGNAL | nix::sys::socket::MsgFlags::MSG_DONTWAIT,
            );
            let _ = stream.shutdown(Shutdown::Both);
            return;
        }
        let id = self.hub.next_client_id();
        let privileged = super::privilege::peer_credentials(&stream)
            .is_some_and(|peer| self.hub.peers.privileged(&peer, self.hub.own_uid));
        // A kernel buffer that holds several large snapshots, so a client that reads a
        // little late does not fill it (the kernel caps this at wmem_max).
        let _ = nix::sys::socket::setsockopt(
            &stream,
            nix::sys::socket::sockopt::SndBuf,
            &CLIENT_SNDBUF_BYTES,
        );
        let slot = self.free.pop().unwrap_or_else(|| {
            self.conns.push(None);
            self.conns.len() - 1
        });
        let want = EpollFlags::EPOLLIN | EpollFlags::EPOLLRDHUP;
        if let Err(e) = self
            .epoll
            .add(&stream, EpollEvent::new(want, token(slot, id)))
        {
            log::warn!("client {id}: cannot poll its socket: {e}");
            self.free.push(slot);
            return;
        }
        let shared = Arc::new(ClientShared::with_privilege(id, privileged));
        {
            // Under the list's lock: a mesh the publisher sends next finds this
            // client in the list; one it sent before is the latest mesh read here.
            let mut clients = lock(&self.hub.clients);
            let mut q = shared.lock();
            let hello = self.hub.hello(&shared, &q.settings);
            let _ = q.push_message(hello, protocol::Format::Json);
            if let Some((json, topology)) = self.hub.latest_mesh_json() {
                q.mesh_topology = Some(topology);
                let _ = q.push_mesh(json, true);
            }
            drop(q);
            clients.push(Arc::clone(&shared));
        }
        stats.clients.fetch_add(1, Ordering::Relaxed);
        stats.clients_accepted.fetch_add(1, Ordering::Relaxed);
        log::debug!(
            "client {id}: connected ({})",
            if privileged {
                "privileged"
            } else {
                "read-only"
            }
        );
        let mut c = Conn::new(shared, stream, monotonic_now());
        c.interest = want;
        let fate = c.flush(&self.hub.stats, Instant::now());
        self.conns[slot] = Some(c);
        self.settle(slot, fate);
    }

    /// One step of shutting down: the first time, stops accepting and queues `bye`
    /// for every client. True once every client is gone or [`SHUTDOWN_GRACE`] is up
    /// (then every socket is closed).
    fn shut_down_step(&mut self) -> bool {
        let since = *self.shutdown_since.get_or_insert_with(|| {
            let _ = self.epoll.delete(&self.listener);
            let mut bye = Vec::new();
            protocol::encode_bye("shutdown", &mut bye);
            let bye: Arc<[u8]> = bye.into();
            for c in self.conns.iter().flatten() {
                let mut q = c.shared.lock();
                if q.accepting() {
                    q.close_with(Arc::clone(&bye));
                }
            }
            Instant::now()
        });
        if since.elapsed() < SHUTDOWN_GRACE {
            self.serve_all(false);
        }
        if self.conns.iter().all(Option::is_none) || since.elapsed() >= SHUTDOWN_GRACE {
            for slot in 0..self.conns.len() {
                self.remove(slot);
            }
            return true;
        }
        false
    }
}
