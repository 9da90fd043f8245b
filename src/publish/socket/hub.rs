//! What the publisher thread and the I/O thread share: the connected clients, the
//! facts every hello carries, the newest mesh, the command channel and the wake-up.

use super::privilege::PeerPolicy;
use super::queue::ClientShared;
use super::stats::{lock, PublisherStats};
use crate::publish::protocol::{self, ClientSettings, HelloInfo, ServerHello};
use crate::vocab::{ClientId, CommandRequest, MeshView, StatsReport};
use crossbeam_channel::Sender;
use nix::sys::eventfd::{EfdFlags, EventFd};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// The newest mesh, and its JSON line with triangles once a client needed it.
#[derive(Debug, Default)]
struct LatestMesh {
    mesh: Option<Arc<MeshView>>,
    json: Option<Arc<[u8]>>,
}

/// Shared by the publisher thread and the I/O thread.
///
/// Lock order: `clients`, then a client's queue, then `latest_mesh`,
/// `latest_scene`, `latest_edit` or `latest_stats` (each held alone).
#[derive(Debug)]
pub(crate) struct Hub {
    /// Static hello facts.
    pub info: HelloInfo,
    /// Current agent count (from the newest snapshot).
    pub agents: AtomicU32,
    /// `socket.client_queue`.
    pub client_queue: u32,
    /// Newest mesh, sent to clients that connect or subscribe later.
    latest_mesh: Mutex<LatestMesh>,
    /// The newest `scene` line, sent to clients when they subscribe to `scene`.
    latest_scene: Mutex<Option<Arc<[u8]>>>,
    /// The edit mode's newest full `tracks` line and newest `edit` line, sent to
    /// clients when they subscribe to `edit` (none outside the edit mode).
    latest_edit: Mutex<LatestEdit>,
    /// The newest `stats` report (`/metrics`); the publisher replaces it once per
    /// interval, a WebSocket I/O thread reads it when `/metrics` is asked for.
    latest_stats: Mutex<Option<Arc<StatsReport>>>,
    /// Commands to the control thread (bounded; `try_send` only).
    pub commands: Sender<CommandRequest>,
    /// Counters, and the live client limit.
    pub stats: Arc<PublisherStats>,
    /// Every connected client. The I/O thread adds and removes; the publisher fans
    /// out to them.
    pub clients: Mutex<Vec<Arc<ClientShared>>>,
    /// Set by the publisher when the output stops: the I/O thread says `bye` to
    /// every client, closes them and ends.
    pub closing: AtomicBool,
    /// Wakes the I/O thread (it polls this eventfd with the sockets).
    wake: EventFd,
    /// Wakes the WebSocket I/O threads, one eventfd each.
    extra_wakes: Vec<EventFd>,
    /// The next client's id (shared by every transport: replies find their client
    /// by it).
    next_id: AtomicU64,
    /// Which Unix-socket peers are privileged.
    pub peers: PeerPolicy,
    /// The daemon's own user id (its clients are privileged).
    pub own_uid: u32,
}

impl Hub {
    /// A hub for a server with these facts.
    pub fn new(
        info: HelloInfo,
        client_queue: u32,
        commands: Sender<CommandRequest>,
        stats: Arc<PublisherStats>,
        wake: EventFd,
        peers: PeerPolicy,
    ) -> Hub {
        Hub {
            agents: AtomicU32::new(info.agents),
            info,
            client_queue,
            latest_mesh: Mutex::new(LatestMesh::default()),
            latest_scene: Mutex::new(None),
            latest_edit: Mutex::new(LatestEdit::default()),
            latest_stats: Mutex::new(None),
            commands,
            stats,
            clients: Mutex::new(Vec::new()),
            closing: AtomicBool::new(false),
            wake,
            extra_wakes: Vec::new(),
            next_id: AtomicU64::new(1),
            peers,
            own_uid: nix::unistd::getuid().as_raw(),
        }
    }

    /// The connected clients (the WebSocket transport adds and removes its own).
    pub fn lock_clients(&self) -> std::sync::MutexGuard<'_, Vec<Arc<ClientShared>>> {
        lock(&self.clients)
    }

    /// A new client's id, unique while the daemon runs.
    pub fn next_client_id(&self) -> ClientId {
        self.next_id.fetch_add(1, Ordering::Relaxed)
    }

    /// A non-blocking eventfd for [`Hub::new`].
    ///
    /// # Errors
    /// The system's (`EMFILE`, ...).
    pub fn wake_fd() -> nix::Result<EventFd> {
        EventFd::from_flags(EfdFlags::EFD_NONBLOCK | EfdFlags::EFD_CLOEXEC)
    }

    /// The eventfd the I/O thread polls.
    pub fn wake_source(&self) -> &EventFd {
        &self.wake
    }

    /// The hub with more I/O threads to wake (the WebSocket transports').
    pub fn with_extra_wakes(mut self, wakes: Vec<EventFd>) -> Hub {
        self.extra_wakes = wakes;
        self
    }

    /// The eventfd extra I/O thread `i` polls.
    pub fn extra_wake_source(&self, i: usize) -> Option<&EventFd> {
        self.extra_wakes.get(i)
    }

    /// Wakes the I/O threads: something was queued for a client, or an answer came.
    pub fn wake(&self) {
        // Only fails when the counter is near u64::MAX (then it is readable anyway).
        let _ = self.wake.write(1);
        for w in &self.extra_wakes {
            let _ = w.write(1);
        }
    }

    /// Clears the wake-up (the I/O thread, before it looks at every client).
    pub fn take_wake(&self) {
        let _ = self.wake.read();
    }

    /// Whether the output is stopping.
    pub fn is_closing(&self) -> bool {
        self.closing.load(Ordering::Acquire)
    }

    /// Lifts the contacts a leaving client sent with `touch`, now rather than at the
    /// touch timeout: an empty `touch` with a null id (no answer). A full command
    /// queue leaves it to the timeout.
    pub fn lift_touches(&self, client: ClientId) {
        let _ = self.commands.try_send(CommandRequest {
            client,
            id: serde_json::Value::Null,
            command: crate::vocab::Command::Touch {
                contacts: Vec::new(),
            },
        });
    }

    /// The server hello for a client with these settings.
    pub fn hello(&self, client: &ClientShared, settings: &ClientSettings) -> Arc<[u8]> {
        let mut out = Vec::with_capacity(512);
        protocol::encode_server_hello(
            &ServerHello {
                info: &self.info,
                client: client.id,
                privileged: client.privileged,
                agents: self.agents.load(Ordering::Relaxed),
                settings,
                client_queue: self.client_queue,
            },
            &mut out,
        );
        out.into()
    }

    /// Makes `mesh` the newest.
    pub fn set_latest_mesh(&self, mesh: Arc<MeshView>) {
        *lock(&self.latest_mesh) = LatestMesh {
            mesh: Some(mesh),
            json: None,
        };
    }

    /// The newest mesh as a JSON line with triangles, if there is one (encoded once
    /// per mesh, however many clients connect).
    pub fn latest_mesh_json(&self) -> Option<(Arc<[u8]>, u64)> {
        let mut latest = lock(&self.latest_mesh);
        let topology = latest.mesh.as_ref()?.topology;
        if latest.json.is_none() {
            let mut out = Vec::new();
            protocol::encode_mesh_json(latest.mesh.as_ref()?, true, &mut out);
            latest.json = Some(out.into());
        }
        Some((Arc::clone(latest.json.as_ref()?), topology))
    }

    /// Keeps the newest `stats` report.
    pub fn set_latest_stats(&self, report: Arc<StatsReport>) {
        *lock(&self.latest_stats) = Some(report);
    }

    /// The newest `stats` report, if one was made.
    pub fn latest_stats(&self) -> Option<Arc<StatsReport>> {
        lock(&self.latest_stats).clone()
    }

    /// Makes `json` (a `scene` line) the newest scene.
    pub fn set_latest_scene(&self, json: Arc<[u8]>) {
        *lock(&self.latest_scene) = Some(json);
    }

    /// The newest `scene` line, if the control thread sent one.
    pub fn latest_scene_json(&self) -> Option<Arc<[u8]>> {
        lock(&self.latest_scene).clone()
    }

    /// Makes `json` (a `tracks` line with every person) the newest tracks.
    pub fn set_latest_tracks(&self, json: Arc<[u8]>) {
        lock(&self.latest_edit).tracks = Some(json);
    }

    /// Makes `json` (an `edit` line) the newest edit state; with `off`, the edit
    /// mode ended and neither it nor the tracks are sent to newcomers.
    pub fn set_latest_edit(&self, json: Arc<[u8]>, off: bool) {
        let mut latest = lock(&self.latest_edit);
        if off {
            *latest = LatestEdit::default();
        } else {
            latest.state = Some(json);
        }
    }

    /// The newest full `tracks` line and `edit` line of the edit mode, if any.
    pub fn latest_edit_json(&self) -> LatestEdit {
        lock(&self.latest_edit).clone()
    }
}

/// What a client subscribing to `edit` is sent first: the tracks, then the state.
#[derive(Clone, Debug, Default)]
pub(crate) struct LatestEdit {
    /// The newest `tracks` line with every person (`full: true`).
    pub tracks: Option<Arc<[u8]>>,
    /// The newest `edit` line.
    pub state: Option<Arc<[u8]>>,
}
