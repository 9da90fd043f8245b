//! The outputs the daemon runs, built from the config: the one place an output is
//! registered (ARCHITECTURE.md, "Adding an output").

use super::error::Error;
use crate::config::{Config, SocketConfig};
use crate::publish::{HelloInfo, OutputSet, PublisherStats, Server, SocketOptions};
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
/// [`Error::Publish`] when the socket cannot be set up.
pub(super) fn register_outputs(
    cfg: &Config,
    socket_path: &Path,
    hello: HelloInfo,
) -> Result<Registered, Error> {
    let server = Server::bind(&socket_options(&cfg.socket), socket_path, hello)?;
    let socket_path = server.path().to_path_buf();
    let publisher = server.stats();
    let mut outputs = OutputSet::default();
    // One line per output: the Unix socket (config `socket`) is always there.
    outputs.add(Box::new(
        server.with_realtime(cfg.pipeline.realtime.priority),
    ));
    Ok(Registered {
        outputs,
        socket_path,
        publisher,
    })
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
