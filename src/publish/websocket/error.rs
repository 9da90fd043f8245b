//! Why the WebSocket output cannot start.

use std::net::SocketAddr;
use thiserror::Error;

/// Setting up the WebSocket listener failed.
#[derive(Debug, Error)]
pub enum Error {
    /// The listen address is not `ip:port`.
    #[error("WebSocket listen address {listen:?} is not ip:port")]
    Address {
        /// As configured.
        listen: String,
    },
    /// `bind` failed (in use, not an address of this machine, a privileged port).
    #[error("cannot listen on {addr} for WebSocket clients: {source}")]
    Bind {
        /// The address.
        addr: SocketAddr,
        /// The system's reason.
        source: std::io::Error,
    },
    /// Another setup step failed.
    #[error("WebSocket output on {addr}: cannot {op}: {source}")]
    Io {
        /// The address.
        addr: SocketAddr,
        /// What was being done.
        op: &'static str,
        /// The system's reason.
        source: std::io::Error,
    },
}
