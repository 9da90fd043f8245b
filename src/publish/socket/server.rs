//! The listening socket and the output's two threads: the publisher (this output's
//! thread, [`Server::run`]) and the I/O thread it starts.

use super::error::Error;
use super::hub::Hub;
use super::io::IoLoop;
use super::preflight::{self, PathState};
use super::privilege::PeerPolicy;
use super::publisher::Publisher;
use super::stats::PublisherStats;
use crate::publish::output::{
    ClientLimit, Output, OutputContext, OutputStats, Overflow, QueuePolicy,
};
use crate::publish::protocol::HelloInfo;
use crate::publish::websocket::{WebSocketListener, WsLoop};
use crate::publish::Outgoing;
use crate::vocab::CommandRequest;
use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use nix::sys::epoll::{Epoll, EpollCreateFlags};
use nix::sys::eventfd::EventFd;
use std::io::ErrorKind;
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::os::unix::net::UnixListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the publisher waits for a message before looking at the stop flag again.
const POLL_INTERVAL: Duration = Duration::from_millis(10);
/// Once the daemon stops, how long the publisher still takes messages (the control
/// thread's last tick publishes the final state) unless its queue closes first.
pub const FINAL_MESSAGES_WAIT: Duration = Duration::from_millis(100);
/// Messages the publisher takes in a row before it looks at the stop flag again.
const DRAIN_MESSAGES: usize = 256;
/// Messages the control thread may have in flight to the publisher thread.
pub const QUEUE_CAPACITY: usize = 1024;
/// Stack of the I/O thread (bytes). Under `mlockall` a thread's whole stack is
/// resident. A deepest-nesting client line, parsed on the I/O thread, needs between
/// 256 and 512 KiB in a debug build (`tests/publish.rs` sends one); this leaves twice
/// that.
pub const IO_THREAD_STACK_BYTES: usize = 1024 * 1024;

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
    /// The listener, and the I/O thread's epoll and wake-up (made at bind, so that
    /// failing is a setup error); taken by [`Server::run`].
    io: Option<IoParts>,
    path: PathBuf,
    /// (device, inode) of the socket file we created, so drop removes only ours.
    ident: Option<(u64, u64)>,
    client_queue: u32,
    hello: HelloInfo,
    stats: Arc<PublisherStats>,
    /// SCHED_FIFO priority for the I/O thread (`None`: normal scheduling).
    realtime: Option<u8>,
    /// Which peers are privileged.
    peers: PeerPolicy,
    /// WebSocket listeners whose clients this publisher also serves.
    websockets: Vec<WebSocketListener>,
}

#[derive(Debug)]
struct IoParts {
    listener: UnixListener,
    epoll: Epoll,
    wake: EventFd,
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
        let io_setup = |op: &'static str, e: nix::errno::Errno| {
            cleanup(Error::Io {
                path: path.clone(),
                op,
                source: e.into(),
            })
        };
        let epoll = Epoll::new(EpollCreateFlags::EPOLL_CLOEXEC)
            .map_err(|e| io_setup("create the epoll instance", e))?;
        let wake = Hub::wake_fd().map_err(|e| io_setup("create the eventfd", e))?;
        let ident = std::fs::symlink_metadata(&path)
            .ok()
            .map(|m| (m.dev(), m.ino()));
        let stats = PublisherStats::default();
        stats.set_max_clients(opts.max_clients);
        Ok(Server {
            io: Some(IoParts {
                listener,
                epoll,
                wake,
            }),
            path,
            ident,
            client_queue: opts.client_queue,
            realtime: None,
            peers: PeerPolicy::default(),
            websockets: Vec::new(),
            hello,
            stats: Arc::new(stats),
        })
    }

    /// The socket path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The counters, shared with the rest of the daemon; also the live client
    /// limit ([`PublisherStats::set_max_clients`]).
    pub fn stats(&self) -> Arc<PublisherStats> {
        Arc::clone(&self.stats)
    }

    /// Makes the peers `peers` lists privileged, besides root and the daemon's
    /// own user (`socket.privileged`).
    pub fn with_privileged(mut self, peers: PeerPolicy) -> Server {
        self.peers = peers;
        self
    }

    /// Also serves the WebSocket clients of `listener` (an I/O thread of its own,
    /// `ct-ws-io`, on this publisher's clients: one encoding per format for both
    /// transports).
    pub fn with_websocket(mut self, listener: WebSocketListener) -> Server {
        self.websockets.push(listener);
        self
    }

    /// Runs the I/O thread under SCHED_FIFO at `priority` (it writes the snapshots:
    /// its `sendmsg` is what the end-to-end figure ends with).
    pub fn with_realtime(mut self, priority: Option<u8>) -> Server {
        self.realtime = priority;
        self
    }

    /// Publisher thread body: starts the I/O thread (which accepts, writes and reads
    /// every client), then queues each message for the clients that want it, until
    /// `rx` disconnects or [`FINAL_MESSAGES_WAIT`] after `stop` is set (messages sent
    /// before the stop, such as the final state, still go out); then the I/O thread
    /// sends every client a final `{"type":"bye"}`, gives them
    /// [`SHUTDOWN_GRACE`](super::SHUTDOWN_GRACE) to read it, and closes.
    ///
    /// Commands from clients go to `commands` with `try_send` (full → the client gets
    /// an `error` "busy"); answers come back as [`Outgoing::Reply`].
    pub fn run(
        mut self,
        rx: Receiver<Outgoing>,
        commands: Sender<CommandRequest>,
        stop: Arc<AtomicBool>,
    ) {
        // `self` lives until the run ends; dropping it removes the socket file.
        let path = self.path.clone();
        let Some(IoParts {
            listener,
            epoll,
            wake,
        }) = self.io.take()
        else {
            return;
        };
        let websockets = std::mem::take(&mut self.websockets);
        let mut extra_wakes = Vec::with_capacity(websockets.len());
        let mut ws_parts = Vec::with_capacity(websockets.len());
        for l in websockets {
            match Hub::wake_fd() {
                Ok(w) => {
                    extra_wakes.push(w);
                    ws_parts.push(l);
                }
                Err(e) => log::error!(
                    "WebSocket {}: cannot create its wake-up ({e}); no client can connect",
                    l.local_addr()
                ),
            }
        }
        let hub = Arc::new(
            Hub::new(
                self.hello.clone(),
                self.client_queue,
                commands,
                Arc::clone(&self.stats),
                wake,
                self.peers.clone(),
            )
            .with_extra_wakes(extra_wakes),
        );
        let mut ws_threads = Vec::new();
        for (i, l) in ws_parts.into_iter().enumerate() {
            let addr = l.local_addr();
            let ws = match WsLoop::new(Arc::clone(&hub), l, i) {
                Ok(ws) => ws,
                Err(e) => {
                    log::error!("WebSocket {addr}: cannot poll ({e}); no client can connect");
                    continue;
                }
            };
            let realtime = self.realtime;
            let spawned = std::thread::Builder::new()
                .name("ct-ws-io".into())
                .stack_size(IO_THREAD_STACK_BYTES)
                .spawn(move || {
                    if let Some(p) = realtime {
                        crate::rt::make_realtime(p, "WebSocket I/O");
                    }
                    ws.run()
                });
            match spawned {
                Ok(t) => ws_threads.push(t),
                Err(e) => log::error!(
                    "WebSocket {addr}: cannot start its I/O thread ({e}); no client can connect"
                ),
            }
        }
        let realtime = self.realtime;
        let io = match IoLoop::new(Arc::clone(&hub), listener, path.clone(), epoll) {
            Ok(io) => io,
            Err(e) => {
                log::error!(
                    "{}: cannot poll the socket ({e}); no client can connect",
                    path.display()
                );
                return;
            }
        };
        let spawned = std::thread::Builder::new()
            .name("ct-socket-io".into())
            .stack_size(IO_THREAD_STACK_BYTES)
            .spawn(move || {
                if let Some(p) = realtime {
                    crate::rt::make_realtime(p, "socket I/O");
                }
                io.run()
            });
        let io_thread = match spawned {
            Ok(t) => t,
            Err(e) => {
                log::error!(
                    "{}: cannot start the socket's I/O thread ({e}); no client can connect",
                    path.display()
                );
                return;
            }
        };
        log::info!("{}: listening", path.display());
        let mut publisher = Publisher::new(Arc::clone(&hub));
        let mut stopping: Option<Instant> = None;
        loop {
            if stopping.is_none() && stop.load(Ordering::Relaxed) {
                stopping = Some(Instant::now());
            }
            if stopping.is_some_and(|t| t.elapsed() >= FINAL_MESSAGES_WAIT) {
                break;
            }
            match rx.recv_timeout(POLL_INTERVAL) {
                Ok(msg) => {
                    // A tick's events and mesh go out with its snapshot (one wake-up);
                    // a backlog of ticks is written as it is queued, not in one burst
                    // that would overrun the clients' snapshot queues.
                    let mut next = Some(msg);
                    let mut left = DRAIN_MESSAGES;
                    while let Some(msg) = next {
                        let snapshot = matches!(msg, Outgoing::Snapshot(_));
                        publisher.dispatch(msg);
                        left -= 1;
                        next = if left > 0 { rx.try_recv().ok() } else { None };
                        if snapshot || next.is_none() {
                            hub.wake();
                        }
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
        }
        hub.closing.store(true, Ordering::Release);
        hub.wake();
        let _ = io_thread.join();
        for t in ws_threads {
            let _ = t.join();
        }
        log::info!("{}: closed", path.display());
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
        Some(self.stats.max_clients.clone())
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
