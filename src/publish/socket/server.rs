//! The listening socket and the publisher thread.

use super::client::{self, ClientShared, EncodedSnapshot, Hub, CLOSE_GRACE};
use super::error::Error;
use super::preflight::{self, PathState};
use super::stats::{lock, PublisherStats};
use crate::publish::output::{
    ClientLimit, Output, OutputContext, OutputStats, Overflow, QueuePolicy,
};
use crate::publish::protocol::{self, FieldSet, Format, HelloInfo};
use crate::publish::Outgoing;
use crate::rt::monotonic_now;
use crate::vocab::{ClientId, CommandRequest, Event, MeshView, Snapshot};
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use std::io::ErrorKind;
use std::net::Shutdown;
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long the publisher waits for a message before looking at the listener,
/// the stop flag and closing clients again.
const POLL_INTERVAL: Duration = Duration::from_millis(10);
/// Least time between two looks at the listener while messages flow.
const ACCEPT_INTERVAL: Duration = Duration::from_millis(5);
/// Least time between two log lines about a failing `accept`.
const ACCEPT_LOG_INTERVAL: Duration = Duration::from_secs(10);
/// Send buffer requested for each client socket (bytes): room for several
/// 1,000-agent snapshots, so a reader that is briefly late never blocks the write.
pub const CLIENT_SNDBUF_BYTES: usize = 1 << 20;
/// A client whose socket takes no bytes for this long is disconnected.
pub const WRITE_STALL_TIMEOUT: Duration = Duration::from_secs(10);
/// Messages the control thread may have in flight to the publisher thread.
pub const QUEUE_CAPACITY: usize = 1024;
/// Stack of each client's reader and writer thread (bytes). Under `mlockall` a
/// thread's whole stack is resident, and glibc keeps finished threads' stacks cached,
/// so each extra pair of client threads ever alive at once adds two stacks to the
/// daemon's resident memory (a 4 MiB step with the default 2 MiB, seen in the soak).
/// A deepest-nesting client line, parsed on the reader thread, needs between 256 and
/// 512 KiB in a debug build (`tests/publish.rs` sends one); this leaves twice that.
pub const CLIENT_THREAD_STACK_BYTES: usize = 1024 * 1024;

/// How the socket is set up and whom it serves: the config's `socket` section.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SocketOptions {
    /// File mode of the socket (`0o660`).
    pub mode: u32,
    /// Group to give the socket to, `None` to keep the process's group.
    pub group: Option<String>,
    /// Snapshots queued per client before the oldest are dropped.
    pub client_queue: u32,
    /// Most clients at once.
    pub max_clients: u32,
}

/// The bound socket, ready to [`run`](Server::run).
#[derive(Debug)]
pub struct Server {
    listener: UnixListener,
    path: PathBuf,
    /// (device, inode) of the socket file we created, so drop removes only ours.
    ident: Option<(u64, u64)>,
    client_queue: u32,
    /// `socket.max_clients`, changeable while running ([`Output::client_limit`]).
    max_clients: ClientLimit,
    hello: HelloInfo,
    stats: Arc<PublisherStats>,
    /// SCHED_FIFO priority for client writer threads (`None`: normal scheduling).
    realtime: Option<u8>,
}

impl Server {
    /// Binds the socket at `path`.
    ///
    /// First the checks `check-config` also makes ([`preflight`]): the path fits a
    /// socket address and its directory exists; if something exists there, a socket
    /// that accepts a connection belongs to a live daemon (`Err(InUse)`), a socket
    /// that refuses is stale and is replaced, anything that is not a socket is left
    /// alone (`Err(NotASocket)`). Then applies `opts.mode` and `opts.group`. The socket file is removed on drop (only if
    /// it is still the one this server created).
    ///
    /// # Errors
    /// [`Error::PathTooLong`], [`Error::NoDirectory`], [`Error::InUse`],
    /// [`Error::NotASocket`], [`Error::Bind`], [`Error::Permissions`],
    /// [`Error::UnknownGroup`], [`Error::GroupLookup`], [`Error::Group`],
    /// [`Error::Io`].
    pub fn bind(opts: &SocketOptions, path: &Path, hello: HelloInfo) -> Result<Server, Error> {
        let path = path.to_path_buf();
        if preflight::inspect_socket_path(&path)? == PathState::Stale {
            log::info!("{}: removing stale socket", path.display());
            std::fs::remove_file(&path).map_err(|source| Error::Io {
                path: path.clone(),
                op: "remove the stale socket",
                source,
            })?;
        }
        let listener = UnixListener::bind(&path).map_err(|source| {
            if source.kind() == ErrorKind::AddrInUse {
                Error::InUse { path: path.clone() }
            } else {
                Error::Bind {
                    path: path.clone(),
                    source,
                }
            }
        })?;
        // From here on, failing must not leave our socket file behind.
        let cleanup = |e: Error| {
            let _ = std::fs::remove_file(&path);
            e
        };
        let mode = opts.mode;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).map_err(
            |source| {
                cleanup(Error::Permissions {
                    path: path.clone(),
                    mode,
                    source,
                })
            },
        )?;
        if let Some(group) = &opts.group {
            let gid = preflight::lookup_group(group).map_err(cleanup)?;
            nix::unistd::chown(&path, None, Some(gid)).map_err(|source| {
                cleanup(Error::Group {
                    path: path.clone(),
                    group: group.clone(),
                    source,
                })
            })?;
        }
        listener.set_nonblocking(true).map_err(|source| {
            cleanup(Error::Io {
                path: path.clone(),
                op: "make the listener non-blocking",
                source,
            })
        })?;
        let ident = std::fs::symlink_metadata(&path)
            .ok()
            .map(|m| (m.dev(), m.ino()));
        Ok(Server {
            listener,
            path,
            ident,
            client_queue: opts.client_queue,
            max_clients: ClientLimit::new(opts.max_clients),
            realtime: None,
            hello,
            stats: Arc::new(PublisherStats::default()),
        })
    }

    /// The socket path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The counters, shared with the rest of the daemon.
    pub fn stats(&self) -> Arc<PublisherStats> {
        Arc::clone(&self.stats)
    }
    /// Runs each client's writer thread under SCHED_FIFO at `priority` (the writer
    /// is on the latency path: its `send` is what the end-to-end figure ends with).
    pub fn with_realtime(mut self, priority: Option<u8>) -> Server {
        self.realtime = priority;
        self
    }

    /// Publisher thread body: accepts clients, fans out messages, until `stop` is set
    /// or `rx` disconnects; then sends every client a final `{"type":"bye"}`, gives
    /// them [`CLOSE_GRACE`] to read it, and closes.
    ///
    /// Commands from clients go to `commands` with `try_send` (full → the client gets
    /// an `error` "busy"); answers come back as [`Outgoing::Reply`].
    pub fn run(
        self,
        rx: Receiver<Outgoing>,
        commands: Sender<CommandRequest>,
        stop: Arc<AtomicBool>,
    ) {
        let hub = Arc::new(Hub {
            info: self.hello.clone(),
            agents: AtomicU32::new(self.hello.agents),
            client_queue: self.client_queue,
            latest_mesh: Mutex::new(None),
            commands,
            stats: Arc::clone(&self.stats),
        });
        let mut p = Publisher {
            server: &self,
            hub,
            clients: Vec::new(),
            lingering: Vec::new(),
            next_id: 1,
            last_accept: None,
            last_accept_log: None,
        };
        log::info!("{}: listening", self.path.display());
        loop {
            if stop.load(Ordering::Relaxed) {
                break;
            }
            if p.last_accept.is_none_or(|t| t.elapsed() >= ACCEPT_INTERVAL) {
                p.accept_pending();
                p.reap();
                p.last_accept = Some(Instant::now());
            }
            match rx.recv_timeout(POLL_INTERVAL) {
                Ok(msg) => p.dispatch(msg),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
        }
        p.shutdown();
        log::info!("{}: closed", self.path.display());
    }
}

impl Output for Server {
    fn name(&self) -> &'static str {
        "publisher"
    }

    fn queue(&self) -> QueuePolicy {
        QueuePolicy {
            capacity: QUEUE_CAPACITY,
            overflow: Overflow::DropNewest,
        }
    }

    fn stats(&self) -> Arc<dyn OutputStats> {
        Arc::clone(&self.stats) as Arc<dyn OutputStats>
    }

    fn client_limit(&self) -> Option<ClientLimit> {
        Some(self.max_clients.clone())
    }

    fn run(self: Box<Self>, ctx: OutputContext) {
        (*self).run(ctx.messages, ctx.commands, ctx.stop)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let ours = std::fs::symlink_metadata(&self.path)
            .ok()
            .map(|m| (m.dev(), m.ino()));
        if ours.is_some() && ours == self.ident {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// The publisher's view of one client.
struct ClientHandle {
    shared: Arc<ClientShared>,
    stream: UnixStream,
    writer: JoinHandle<()>,
    reader: JoinHandle<()>,
}

/// Snapshot encodings made for the current message, by (format, fields).
type EncodeCache = Vec<((Format, FieldSet), Arc<EncodedSnapshot>)>;

struct Publisher<'a> {
    server: &'a Server,
    hub: Arc<Hub>,
    clients: Vec<ClientHandle>,
    /// Reader threads of removed clients that have not finished yet.
    lingering: Vec<JoinHandle<()>>,
    next_id: ClientId,
    last_accept: Option<Instant>,
    last_accept_log: Option<Instant>,
}

impl Publisher<'_> {
    fn accept_pending(&mut self) {
        loop {
            match self.server.listener.accept() {
                Ok((stream, _)) => self.admit(stream),
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) => {
                    // EMFILE and friends: try again next round, say so now and then.
                    if self
                        .last_accept_log
                        .is_none_or(|t| t.elapsed() >= ACCEPT_LOG_INTERVAL)
                    {
                        log::warn!("{}: accept failed: {e}", self.server.path.display());
                        self.last_accept_log = Some(Instant::now());
                    }
                    return;
                }
            }
        }
    }

    fn admit(&mut self, stream: UnixStream) {
        let stats = &self.hub.stats;
        if self.clients.len() >= self.server.max_clients.get() as usize {
            stats.clients_refused.fetch_add(1, Ordering::Relaxed);
            log::warn!(
                "refusing a client: {} clients connected (config socket.max_clients)",
                self.clients.len()
            );
            let mut json = Vec::new();
            let msg = format!(
                "too many clients: {} connected (socket.max_clients)",
                self.clients.len()
            );
            protocol::encode_error(None, &msg, true, &mut json);
            // A fresh socket's buffer is empty; never block on it anyway.
            let _ = stream.set_nonblocking(true);
            let _ = client::send_all(&stream, &json);
            let _ = stream.shutdown(Shutdown::Both);
            return;
        }
        let id = self.next_id;
        self.next_id += 1;
        // A kernel buffer that holds several large snapshots, so a client that reads a
        // little late does not block its writer (the kernel caps this at wmem_max).
        let _ = nix::sys::socket::setsockopt(
            &stream,
            nix::sys::socket::sockopt::SndBuf,
            &CLIENT_SNDBUF_BYTES,
        );
        let prepared = stream
            .set_nonblocking(false)
            .and_then(|()| stream.set_write_timeout(Some(WRITE_STALL_TIMEOUT)))
            .and_then(|()| Ok((stream.try_clone()?, stream.try_clone()?)));
        let (wstream, rstream) = match prepared {
            Ok(s) => s,
            Err(e) => {
                log::warn!("client {id}: cannot set up the connection: {e}");
                return;
            }
        };
        let shared = Arc::new(ClientShared::new(id));
        // Counted before its hello can reach it, so a client that has read its hello
        // is always in the count; uncounted again if it cannot be started.
        stats.clients.fetch_add(1, Ordering::Relaxed);
        {
            let mut q = shared.lock();
            let hello = self.hub.hello(id, &q.settings);
            let _ = q.push_message(hello, Format::Json);
            if let Some((json, topology)) = self.hub.latest_mesh_json() {
                q.mesh_topology = Some(topology);
                let _ = q.push_mesh(json, true);
            }
        }
        let w = {
            let (shared, stats) = (Arc::clone(&shared), Arc::clone(stats));
            let realtime = self.server.realtime;
            std::thread::Builder::new()
                .name(format!("ct-client{id}-w"))
                .stack_size(CLIENT_THREAD_STACK_BYTES)
                .spawn(move || {
                    if let Some(p) = realtime {
                        crate::rt::make_realtime(p, "client writer");
                    }
                    client::writer_loop(shared, wstream, stats)
                })
        };
        let writer = match w {
            Ok(h) => h,
            Err(e) => {
                log::warn!("client {id}: cannot start its writer thread: {e}");
                stats.clients.fetch_sub(1, Ordering::Relaxed);
                return;
            }
        };
        let r = {
            let (shared, hub) = (Arc::clone(&shared), Arc::clone(&self.hub));
            std::thread::Builder::new()
                .name(format!("ct-client{id}-r"))
                .stack_size(CLIENT_THREAD_STACK_BYTES)
                .spawn(move || client::reader_loop(shared, rstream, hub))
        };
        let reader = match r {
            Ok(h) => h,
            Err(e) => {
                log::warn!("client {id}: cannot start its reader thread: {e}");
                shared.kill();
                let _ = stream.shutdown(Shutdown::Both);
                let _ = writer.join();
                stats.clients.fetch_sub(1, Ordering::Relaxed);
                return;
            }
        };
        stats.clients_accepted.fetch_add(1, Ordering::Relaxed);
        log::debug!("client {id}: connected");
        self.clients.push(ClientHandle {
            shared,
            stream,
            writer,
            reader,
        });
    }

    /// Removes clients whose writer has ended; shuts the socket of clients that have
    /// been closing for longer than [`CLOSE_GRACE`].
    fn reap(&mut self) {
        let mut i = 0;
        while i < self.clients.len() {
            let c = &self.clients[i];
            if c.writer.is_finished() {
                let c = self.clients.swap_remove(i);
                let _ = c.stream.shutdown(Shutdown::Both);
                let _ = c.writer.join();
                self.lingering.push(c.reader);
                self.hub.stats.clients.fetch_sub(1, Ordering::Relaxed);
                log::debug!("client {}: disconnected", c.shared.id);
                continue;
            }
            if c.shared.lock().close_overdue() {
                // Unblocks a writer stuck in `write`; it then finds the socket dead.
                let _ = c.stream.shutdown(Shutdown::Both);
                c.shared.kill();
            }
            i += 1;
        }
        let (done, pending): (Vec<_>, Vec<_>) = std::mem::take(&mut self.lingering)
            .into_iter()
            .partition(|h| h.is_finished());
        for h in done {
            let _ = h.join();
        }
        self.lingering = pending;
    }

    fn dispatch(&mut self, msg: Outgoing) {
        match msg {
            Outgoing::Snapshot(s) => self.snapshot(&s),
            Outgoing::Mesh(m) => self.mesh(m),
            Outgoing::Event(e) => {
                if let Event::Reset { agents, .. } = *e {
                    self.hub.agents.store(agents, Ordering::Relaxed);
                }
                self.broadcast(|s| s.events, |out| protocol::encode_event(&e, out));
            }
            Outgoing::Stats(r) => {
                self.broadcast(|s| s.stats, |out| protocol::encode_stats(&r, out))
            }
            Outgoing::Reply { client, id, result } => {
                let Some(c) = self.clients.iter().find(|c| c.shared.id == client) else {
                    return; // the client left before its answer came
                };
                let mut json = Vec::new();
                match result {
                    Ok(()) => protocol::encode_ack(&id, &mut json),
                    Err(message) => protocol::encode_error(Some(&id), &message, false, &mut json),
                }
                let mut q = c.shared.lock();
                if q.accepting() {
                    let framing = q.settings.format;
                    if let Err(o) = q.push_message(json.into(), framing) {
                        log::info!("client {}: {o}", c.shared.id);
                        q.fail(&o.to_string());
                    }
                }
                drop(q);
                c.shared.notify();
            }
        }
    }

    fn snapshot(&mut self, s: &Snapshot) {
        self.hub.agents.store(
            u32::try_from(s.agents.len()).unwrap_or(u32::MAX),
            Ordering::Relaxed,
        );
        if self.clients.is_empty() {
            return;
        }
        let now = monotonic_now();
        let latency_us = s.input_t.map(|t| now.saturating_since(t).0);
        let capacity = self.server.client_queue as usize;
        let stats = &self.hub.stats;
        let mut cache: EncodeCache = Vec::new();
        for c in &self.clients {
            let mut q = c.shared.lock();
            if !q.accepting() || !q.settings.subscriptions.snapshot {
                continue;
            }
            if let Some(period) = q.settings.min_interval_us() {
                if now.0 < q.rate_next_due_us {
                    stats.snapshots_rate_skipped.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                // Carry up to one period of lateness so jitter does not lower the rate.
                q.rate_next_due_us = q
                    .rate_next_due_us
                    .max(now.0.saturating_sub(period))
                    .saturating_add(period);
            }
            let key = (q.settings.format, q.settings.fields);
            let enc = match cache.iter().find(|(k, _)| *k == key) {
                Some((_, e)) => Arc::clone(e),
                None => {
                    let e = Arc::new(encode(s, latency_us, key, stats));
                    cache.push((key, Arc::clone(&e)));
                    e
                }
            };
            let dropped = q.push_snapshot(enc, capacity);
            drop(q);
            if dropped > 0 {
                stats
                    .snapshots_dropped
                    .fetch_add(dropped, Ordering::Relaxed);
            }
            c.shared.notify();
        }
    }

    fn mesh(&mut self, m: Arc<MeshView>) {
        *lock(&self.hub.latest_mesh) = Some(Arc::clone(&m));
        let mut with: Option<Arc<[u8]>> = None;
        let mut without: Option<Arc<[u8]>> = None;
        for c in &self.clients {
            let mut q = c.shared.lock();
            if !q.accepting() || !q.settings.subscriptions.mesh {
                continue;
            }
            let replaced_had_triangles = q.take_queued_mesh().unwrap_or(false);
            let tri = replaced_had_triangles || q.mesh_topology != Some(m.topology);
            q.mesh_topology = Some(m.topology);
            let slot = if tri { &mut with } else { &mut without };
            let json = Arc::clone(slot.get_or_insert_with(|| {
                let mut out = Vec::new();
                protocol::encode_mesh_json(&m, tri, &mut out);
                out.into()
            }));
            if let Err(o) = q.push_mesh(json, tri) {
                log::info!("client {}: {o}", c.shared.id);
                q.fail(&o.to_string());
            }
            drop(q);
            c.shared.notify();
        }
    }

    /// Queues one JSON message, encoded at most once, for every client `wants` it.
    fn broadcast(
        &mut self,
        wants: impl Fn(&protocol::Subscriptions) -> bool,
        encode: impl FnOnce(&mut Vec<u8>),
    ) {
        let mut encode = Some(encode);
        let mut json: Option<Arc<[u8]>> = None;
        for c in &self.clients {
            let mut q = c.shared.lock();
            if !q.accepting() || !wants(&q.settings.subscriptions) {
                continue;
            }
            let bytes = match (&json, encode.take()) {
                (Some(j), _) => Arc::clone(j),
                (None, Some(f)) => {
                    let mut out = Vec::new();
                    f(&mut out);
                    let j: Arc<[u8]> = out.into();
                    json = Some(Arc::clone(&j));
                    j
                }
                (None, None) => continue,
            };
            let framing = q.settings.format;
            if let Err(o) = q.push_message(bytes, framing) {
                log::info!("client {}: {o}", c.shared.id);
                q.fail(&o.to_string());
            }
            drop(q);
            c.shared.notify();
        }
    }

    /// Says `bye` to every client, waits up to [`CLOSE_GRACE`] for them to take it,
    /// then closes every socket and joins every client thread.
    fn shutdown(&mut self) {
        let mut bye = Vec::new();
        protocol::encode_bye("shutdown", &mut bye);
        let bye: Arc<[u8]> = bye.into();
        for c in &self.clients {
            let mut q = c.shared.lock();
            if q.accepting() {
                q.close_with(Arc::clone(&bye));
            }
            drop(q);
            c.shared.notify();
        }
        let deadline = Instant::now() + CLOSE_GRACE;
        while Instant::now() < deadline && self.clients.iter().any(|c| !c.writer.is_finished()) {
            std::thread::sleep(Duration::from_millis(2));
        }
        for c in self.clients.drain(..) {
            let _ = c.stream.shutdown(Shutdown::Both);
            c.shared.kill();
            let _ = c.writer.join();
            let _ = c.reader.join();
            self.hub.stats.clients.fetch_sub(1, Ordering::Relaxed);
        }
        for h in self.lingering.drain(..) {
            let _ = h.join();
        }
    }
}

/// Encodes one snapshot for one (format, fields), timing it.
fn encode(
    s: &Snapshot,
    latency_us: Option<u64>,
    (format, fields): (Format, FieldSet),
    stats: &PublisherStats,
) -> EncodedSnapshot {
    let t0 = Instant::now();
    let mut bytes = Vec::new();
    let dropped_at = match format {
        Format::Json => protocol::encode_snapshot_json_shared(s, latency_us, &fields, &mut bytes),
        Format::Binary => {
            protocol::encode_snapshot_binary(s, latency_us, 0, &fields, &mut bytes);
            protocol::BINARY_DROPPED_OFFSET
        }
    };
    let us = u64::try_from(t0.elapsed().as_micros()).unwrap_or(u64::MAX);
    stats.record_encode(us);
    EncodedSnapshot {
        format,
        bytes,
        dropped_at,
        input_t: s.input_t,
    }
}
