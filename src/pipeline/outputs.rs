//! The outputs the daemon runs, built from the config: the one place an output is
//! registered (ARCHITECTURE.md, "Adding an output").

use super::error::Error;
use crate::config::{
    is_loopback, normalize_host, normalize_origin, Config, OutputConfig, SocketConfig, TuioProfile,
    TuioVersion,
};
use crate::geom::Rect;
use crate::publish::socket::preflight::resolve_peers;
use crate::publish::tuio::{TuioOptions, TuioOutput, Version};
use crate::publish::{
    HelloInfo, OutputSet, PublisherStats, Server, SocketOptions, WebSocketListener,
    WebSocketOptions,
};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The registered outputs, and what the daemon keeps of the socket.
pub(super) struct Registered {
    /// Every output, in the order their threads start.
    pub outputs: OutputSet,
    /// The socket path clients connect to.
    pub socket_path: PathBuf,
    /// The socket's counters (`Daemon::publisher_stats`).
    pub publisher: Arc<PublisherStats>,
}

/// Binds the Unix socket at `socket_path` and registers every output of `cfg`.
///
/// # Errors
/// [`Error::Publish`] when the socket cannot be set up, [`Error::WebSocket`] when a
/// WebSocket address cannot be bound, [`Error::TuioOutput`] when a TUIO target does
/// not resolve.
pub(super) fn register_outputs(
    cfg: &Config,
    socket_path: &Path,
    hello: HelloInfo,
) -> Result<Registered, Error> {
    let world = hello.world;
    let peers = &cfg.socket.privileged;
    let mut server = Server::bind(&socket_options(&cfg.socket), socket_path, hello)?
        .with_privileged(resolve_peers(&peers.users, &peers.groups)?);
    let socket_path = server.path().to_path_buf();
    let publisher = server.stats();
    let mut outputs = OutputSet::default();
    for entry in &cfg.outputs {
        // WebSocket clients are clients of the socket's publisher (one encoding
        // per format for both transports).
        if let Some(l) = websocket_listener(entry)? {
            server = server.with_websocket(l);
        }
    }
    // One line per output: the Unix socket (config `socket`) is always there.
    outputs.add(Box::new(
        server.with_realtime(cfg.pipeline.realtime.priority),
    ));
    for o in &cfg.outputs {
        match o {
            OutputConfig::Tuio { .. } => {
                if let Some(opts) = tuio_options(o, world) {
                    outputs.add(Box::new(TuioOutput::new(opts)?));
                }
            }
            // Served by the socket's publisher (above).
            OutputConfig::WebSocket { .. } => {}
        }
    }
    Ok(Registered {
        outputs,
        socket_path,
        publisher,
    })
}

/// A WebSocket entry's listener, bound (its URL logged); `None` for other entries.
///
/// # Errors
/// [`Error::WebSocket`] when the address cannot be bound.
fn websocket_listener(entry: &OutputConfig) -> Result<Option<WebSocketListener>, Error> {
    let OutputConfig::WebSocket {
        listen,
        token,
        privileged,
        max_clients,
        max_message_bytes,
        viewer,
        metrics,
        origins,
        privileged_origins,
        hosts,
    } = entry
    else {
        return Ok(None);
    };
    let addr = listen
        .parse()
        .map_err(|_| crate::publish::websocket::Error::Address {
            listen: listen.clone(),
        })?;
    let l = WebSocketListener::bind(WebSocketOptions {
        listen: addr,
        token: token.clone(),
        privileged: *privileged,
        max_clients: *max_clients,
        max_message_bytes: *max_message_bytes,
        viewer: *viewer,
        metrics: *metrics,
        // Validated with the config: what fails to normalise is not there.
        origins: origins
            .iter()
            .filter_map(|o| normalize_origin(o).ok())
            .collect(),
        privileged_origins: privileged_origins
            .iter()
            .filter_map(|o| normalize_origin(o).ok())
            .collect(),
        hosts: hosts
            .iter()
            .filter_map(|h| normalize_host(h).ok())
            .collect(),
    })?;
    let who = if *privileged {
        "privileged"
    } else {
        "read-only"
    };
    let access = match (is_loopback(addr.ip()), token.is_some()) {
        (_, true) => "clients must present the token (?token= or Authorization: Bearer)",
        (true, false) => "this machine only, no token",
        (false, false) => "reachable from other machines: a token is required",
    };
    log::info!(
        "WebSocket output: {} (stream at ws://{}/ws; {who} clients; {access})",
        l.url(),
        l.local_addr()
    );
    Ok(Some(l))
}

/// The socket output's options from the config's `socket` section.
pub fn socket_options(cfg: &SocketConfig) -> SocketOptions {
    SocketOptions {
        mode: cfg.mode_bits(),
        group: cfg.group.clone(),
        client_queue: cfg.client_queue,
        max_clients: cfg.max_clients,
    }
}

/// A TUIO output's options from its `outputs` entry (validated: an unknown
/// version cannot reach here, and falls back to 1.1 if it did); `None` for
/// another kind of output.
pub fn tuio_options(o: &OutputConfig, world: Rect) -> Option<TuioOptions> {
    let OutputConfig::Tuio {
        target,
        version,
        profiles,
        rate_hz,
        max_datagram_bytes,
        source,
        privileged,
    } = o
    else {
        return None;
    };
    Some(TuioOptions {
        target: target.clone(),
        version: match TuioVersion::parse(version) {
            Some(TuioVersion::V2_0) => Version::V2_0,
            _ => Version::V1_1,
        },
        // Validation refuses Cursors without privileged; checked again here.
        cursors: *privileged && profiles.contains(&TuioProfile::Cursors),
        objects: profiles.contains(&TuioProfile::Objects),
        blobs: profiles.contains(&TuioProfile::Blobs),
        rate_hz: *rate_hz,
        max_datagram_bytes: *max_datagram_bytes as usize,
        source: source.clone().unwrap_or_else(default_source),
        world,
    })
}

/// `crowdtouch@<hostname>`, the `source` a TUIO output names by default.
fn default_source() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "localhost".to_string());
    format!("crowdtouch@{host}")
}
