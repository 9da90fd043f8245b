//! The WebSocket listener and its I/O thread (`ct-ws-io`): every connection on one
//! `epoll`, non-blocking, with the publisher's wake-up.

use super::conn::{self, Fate, WsConn};
use super::error::Error;
use super::options::WebSocketOptions;
use crate::publish::protocol;
use crate::publish::socket::{Budget, ClientShared, Hub};
use crate::publish::socket::{
    ACCEPTS_PER_SECOND, ACCEPT_BURST, CLIENT_SNDBUF_BYTES, SHUTDOWN_GRACE, WRITE_STALL_TIMEOUT,
};
use crate::rt::monotonic_now;
use nix::sys::epoll::{Epoll, EpollCreateFlags, EpollEvent, EpollFlags, EpollTimeout};
use std::io::ErrorKind;
use std::net::{SocketAddr, TcpListener};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The viewer page, embedded in the binary.
pub const VIEWER_PAGE: &str = include_str!("viewer.html");
/// A connection must send its request head and take the answer within this.
pub const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(10);
/// How often (ms) the loop looks at every connection without being woken.
const HOUSEKEEPING_MS: u16 = 50;
const HOUSEKEEPING_INTERVAL: Duration = Duration::from_millis(HOUSEKEEPING_MS as u64);
/// Connections still in their handshake beyond the client limit.
const HANDSHAKE_SLOTS: usize = 64;
/// Least time between two log lines about refused connections (the others are
/// counted and summed in the next line).
const REFUSAL_LOG_INTERVAL: Duration = Duration::from_secs(10);
/// Connections accepted per round.
const ACCEPTS_PER_ROUND: usize = 16;

const LISTENER: u64 = u64::MAX;
const WAKE: u64 = u64::MAX - 1;

fn token(slot: usize, serial: u64) -> u64 {
    ((slot as u64) << 32) | (serial & 0xffff_ffff)
}

/// A bound WebSocket listener, ready to be served by the publisher
/// ([`Server::with_websocket`](crate::publish::Server::with_websocket)).
#[derive(Debug)]
pub struct WebSocketListener {
    pub(crate) listener: TcpListener,
    pub(crate) epoll: Epoll,
    pub(crate) opts: WebSocketOptions,
    addr: SocketAddr,
}

impl WebSocketListener {
    /// Binds `opts.listen` (non-blocking) and makes the I/O thread's epoll.
    ///
    /// # Errors
    /// [`Error::Bind`], [`Error::Io`].
    pub fn bind(opts: WebSocketOptions) -> Result<WebSocketListener, Error> {
        let addr = opts.listen;
        let listener = TcpListener::bind(addr).map_err(|source| Error::Bind { addr, source })?;
        let io = |op: &'static str| move |source: std::io::Error| Error::Io { addr, op, source };
        listener
            .set_nonblocking(true)
            .map_err(io("make the listener non-blocking"))?;
        let addr = listener
            .local_addr()
            .map_err(io("read the bound address"))?;
        let epoll = Epoll::new(EpollCreateFlags::EPOLL_CLOEXEC)
            .map_err(|e| io("create the epoll instance")(e.into()))?;
        Ok(WebSocketListener {
            listener,
            epoll,
            opts,
            addr,
        })
    }

    /// The bound address (the port chosen when the config said 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The viewer's URL (`http://ADDR/`), or the stream's when there is no viewer.
    pub fn url(&self) -> String {
        if self.opts.viewer {
            format!("http://{}/", self.addr)
        } else {
            format!("ws://{}/ws", self.addr)
        }
    }

    /// Whether it serves its clients as privileged.
    pub fn privileged(&self) -> bool {
        self.opts.privileged
    }
}

/// The WebSocket I/O thread's state.
pub(crate) struct WsLoop {
    hub: Arc<Hub>,
    listener: TcpListener,
    epoll: Epoll,
    /// Which of the hub's extra wake-ups is ours.
    wake_index: usize,
    opts: WebSocketOptions,
    addr: SocketAddr,
    conns: Vec<Option<(u64, WsConn)>>,
    free: Vec<usize>,
    serial: u64,
    accepts: Budget,
    listener_polled: bool,
    last_housekeeping: Instant,
    shutdown_since: Option<Instant>,
    last_refusal_log: Option<Instant>,
    refusals_unlogged: u64,
}

impl WsLoop {
    /// The loop of `l`, registered with its epoll; `wake_index` is its wake-up's
    /// index among the hub's extra wake-ups.
    ///
    /// # Errors
    /// `epoll_ctl`'s.
    pub fn new(hub: Arc<Hub>, l: WebSocketListener, wake_index: usize) -> nix::Result<WsLoop> {
        let WebSocketListener {
            listener,
            epoll,
            opts,
            addr,
        } = l;
        epoll.add(&listener, EpollEvent::new(EpollFlags::EPOLLIN, LISTENER))?;
        if let Some(w) = hub.extra_wake_source(wake_index) {
            epoll.add(w, EpollEvent::new(EpollFlags::EPOLLIN, WAKE))?;
        }
        Ok(WsLoop {
            hub,
            listener,
            epoll,
            wake_index,
            opts,
            addr,
            conns: Vec::new(),
            free: Vec::new(),
            serial: 0,
            accepts: Budget::new(ACCEPTS_PER_SECOND, ACCEPT_BURST, monotonic_now()),
            listener_polled: true,
            last_housekeeping: Instant::now(),
            shutdown_since: None,
            last_refusal_log: None,
            refusals_unlogged: 0,
        })
    }

    /// Thread body: serves connections until the hub is closing and every client
    /// has taken its `bye` (or [`SHUTDOWN_GRACE`] has passed).
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
                    log::error!("WebSocket {}: epoll_wait failed: {e}", self.addr);
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
            if woken {
                if let Some(w) = self.hub.extra_wake_source(self.wake_index) {
                    let _ = w.read();
                }
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

    /// Open clients now.
    fn open_clients(&self) -> usize {
        self.conns
            .iter()
            .flatten()
            .filter(|(_, c)| c.is_open())
            .count()
    }

    fn event(&mut self, token: u64, ev: EpollFlags) {
        let slot = (token >> 32) as usize;
        match self.conns.get(slot).and_then(Option::as_ref) {
            Some((serial, _)) if serial & 0xffff_ffff == token & 0xffff_ffff => {}
            _ => return,
        }
        let mut fate = Fate::Keep;
        if ev.intersects(EpollFlags::EPOLLIN | EpollFlags::EPOLLRDHUP | EpollFlags::EPOLLHUP) {
            fate = self.input(slot);
        }
        if fate == Fate::Keep {
            fate = self.output(slot);
        }
        if ev.intersects(EpollFlags::EPOLLHUP | EpollFlags::EPOLLERR) {
            fate = Fate::Remove;
        }
        self.settle(slot, fate);
    }

    /// Reads from the connection in `slot`: its request head, or its messages.
    fn input(&mut self, slot: usize) -> Fate {
        let clients = self.open_clients();
        let Some((_, c)) = self.conns[slot].as_mut() else {
            return Fate::Keep;
        };
        if c.is_open() {
            return c.input(&self.hub, monotonic_now());
        }
        let opts = &self.opts;
        let hub = &self.hub;
        let metrics = || crate::publish::metrics::render(hub.latest_stats().as_deref());
        let local = c.local;
        let mut refused: Option<String> = None;
        let fate = c.head_input(
            |buf| conn::answer(buf, opts, VIEWER_PAGE, clients, local, &metrics),
            |why| refused = Some(why.to_string()),
        );
        if let Some(why) = refused {
            let peer = c.peer;
            self.refused(peer, &why);
        }
        fate
    }

    /// Writes to the connection in `slot`: its response (then the upgrade), or
    /// what is queued for it.
    fn output(&mut self, slot: usize) -> Fate {
        let Some((_, c)) = self.conns[slot].as_mut() else {
            return Fate::Keep;
        };
        if c.is_open() {
            return c.flush(&self.hub.stats, Instant::now());
        }
        let (fate, upgrade) = c.respond(Instant::now());
        let Some(conn::Upgrade { rest, privileged }) = upgrade else {
            return fate;
        };
        // The 101 is out: the client joins the publisher's clients.
        let id = self.hub.next_client_id();
        let shared = Arc::new(ClientShared::with_privilege(id, privileged));
        {
            let mut clients = self.hub.lock_clients();
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
        let stats = &self.hub.stats;
        stats.count_client_connected();
        log::info!(
            "WebSocket client {id} ({}): connected ({})",
            c.peer,
            if privileged {
                "privileged"
            } else {
                "read-only"
            }
        );
        c.upgrade(
            shared,
            rest,
            self.opts.max_message_bytes as usize,
            monotonic_now(),
        );
        // Bytes the client sent after its head are already buffered: read them.
        let fate = c.input(&self.hub, monotonic_now());
        if fate == Fate::Remove {
            return fate;
        }
        c.flush(&self.hub.stats, Instant::now())
    }

    /// A refused connection: counted, logged now and then.
    fn refused(&mut self, peer: SocketAddr, why: &str) {
        self.hub.stats.count_ws_refused();
        if self
            .last_refusal_log
            .is_none_or(|t| t.elapsed() >= REFUSAL_LOG_INTERVAL)
        {
            let more = std::mem::take(&mut self.refusals_unlogged);
            let also = if more > 0 {
                format!(" ({more} more refused since the last such line)")
            } else {
                String::new()
            };
            log::warn!("WebSocket {}: refused {peer}: {why}{also}", self.addr);
            self.last_refusal_log = Some(Instant::now());
        } else {
            self.refusals_unlogged += 1;
        }
    }

    fn serve_all(&mut self, housekeeping: bool) {
        let now = Instant::now();
        for slot in 0..self.conns.len() {
            let Some((_, c)) = self.conns[slot].as_mut() else {
                continue;
            };
            if housekeeping {
                if !c.is_open() && now.saturating_duration_since(c.since) >= HANDSHAKE_TIMEOUT {
                    log::debug!("WebSocket {}: {} took too long to ask", self.addr, c.peer);
                    self.settle(slot, Fate::Remove);
                    continue;
                }
                if let Some(shared) = c.shared() {
                    let mut q = shared.lock();
                    let overdue = q.close_overdue();
                    if let Err(o) = q.expire_replies(now) {
                        q.fail(&o.to_string());
                    }
                    drop(q);
                    if overdue {
                        self.settle(slot, Fate::Remove);
                        continue;
                    }
                }
                if c.stalled_since
                    .is_some_and(|t| now.saturating_duration_since(t) >= WRITE_STALL_TIMEOUT)
                {
                    log::info!(
                        "WebSocket client {}: took no data for {:?}; disconnecting",
                        c.peer,
                        WRITE_STALL_TIMEOUT
                    );
                    self.settle(slot, Fate::Remove);
                    continue;
                }
            }
            let mut fate = Fate::Keep;
            if c.paused {
                fate = c.input(&self.hub, monotonic_now());
            }
            if fate == Fate::Keep && !c.blocked {
                fate = self.output(slot);
            }
            self.settle(slot, fate);
        }
    }

    fn settle(&mut self, slot: usize, fate: Fate) {
        let Some((serial, c)) = self.conns[slot].as_mut() else {
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
        if c.blocked {
            want |= EpollFlags::EPOLLOUT;
        }
        if want != c.interest {
            let mut ev = EpollEvent::new(want, token(slot, *serial));
            let ok = match c.stream() {
                Some(s) => self.epoll.modify(s, &mut ev).is_ok(),
                None => false,
            };
            if ok {
                c.interest = want;
            } else {
                self.remove(slot);
            }
        }
    }

    fn remove(&mut self, slot: usize) {
        let Some((_, c)) = self.conns[slot].take() else {
            return;
        };
        self.free.push(slot);
        if let Some(s) = c.stream() {
            let _ = self.epoll.delete(s);
        }
        c.shut_down();
        if let Some(shared) = c.shared() {
            if c.touched() {
                self.hub.lift_touches(shared.id);
            }
            shared.lock().dead = true;
            self.hub.lock_clients().retain(|s| !Arc::ptr_eq(s, shared));
            self.hub.stats.count_client_gone();
            log::info!("WebSocket client {} ({}): disconnected", shared.id, c.peer);
        }
    }

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
        if self.epoll.modify(&self.listener, &mut ev).is_ok() {
            self.listener_polled = on;
        }
    }

    fn accept_pending(&mut self) {
        if self.shutdown_since.is_some() {
            return;
        }
        for _ in 0..ACCEPTS_PER_ROUND {
            if !self.accepts.ready(monotonic_now()) {
                self.poll_listener(false);
                return;
            }
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    self.accepts.take(monotonic_now());
                    self.admit(stream, peer);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => {
                    log::warn!("WebSocket {}: accept failed: {e}", self.addr);
                    self.poll_listener(false);
                    return;
                }
            }
        }
    }

    fn admit(&mut self, stream: std::net::TcpStream, peer: SocketAddr) {
        if stream.set_nonblocking(true).is_err() {
            return;
        }
        let Ok(local) = stream.local_addr() else {
            return;
        };
        let _ = stream.set_nodelay(true);
        let connections = self.conns.iter().flatten().count();
        if connections >= self.opts.max_clients as usize + HANDSHAKE_SLOTS {
            self.refused(peer, "too many connections");
            let _ = stream.shutdown(std::net::Shutdown::Both);
            return;
        }
        let _ = nix::sys::socket::setsockopt(
            &stream,
            nix::sys::socket::sockopt::SndBuf,
            &CLIENT_SNDBUF_BYTES,
        );
        self.serial += 1;
        let serial = self.serial;
        let slot = self.free.pop().unwrap_or_else(|| {
            self.conns.push(None);
            self.conns.len() - 1
        });
        let want = EpollFlags::EPOLLIN | EpollFlags::EPOLLRDHUP;
        if self
            .epoll
            .add(&stream, EpollEvent::new(want, token(slot, serial)))
            .is_err()
        {
            self.free.push(slot);
            return;
        }
        let mut c = WsConn::new(stream, peer, local);
        c.interest = want;
        self.conns[slot] = Some((serial, c));
    }

    fn shut_down_step(&mut self) -> bool {
        let since = *self.shutdown_since.get_or_insert_with(|| {
            let _ = self.epoll.delete(&self.listener);
            let mut bye = Vec::new();
            protocol::encode_bye("shutdown", &mut bye);
            let bye: Arc<[u8]> = bye.into();
            for (_, c) in self.conns.iter().flatten() {
                if let Some(shared) = c.shared() {
                    let mut q = shared.lock();
                    if q.accepting() {
                        q.close_with(Arc::clone(&bye));
                    }
                }
            }
            Instant::now()
        });
        if since.elapsed() < SHUTDOWN_GRACE {
            self.serve_all(false);
        }
        let all_closing = self
            .conns
            .iter()
            .flatten()
            .all(|(_, c)| c.is_open() && c.closing());
        if all_closing
            || self.conns.iter().all(Option::is_none)
            || since.elapsed() >= SHUTDOWN_GRACE
        {
            for slot in 0..self.conns.len() {
                self.remove(slot);
            }
            return true;
        }
        false
    }
}
