//! The outputs a config asks for, built for the daemon's [`OutputSet`](crate::publish::OutputSet).

use crate::config::SocketConfig;
use crate::publish::SocketOptions;

/// The socket output's options from the config's `socket` section.
pub fn socket_options(cfg: &SocketConfig) -> SocketOptions {
    SocketOptions {
        mode: cfg.mode_bits(),
        group: cfg.group.clone(),
        client_queue: cfg.client_queue,
        max_clients: cfg.max_clients,
    }
}
