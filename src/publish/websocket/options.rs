//! A WebSocket output's settings.

use std::net::SocketAddr;

/// A WebSocket output's settings: the config's `WebSocket(...)` entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WebSocketOptions {
    /// Address to listen on.
    pub listen: SocketAddr,
    /// The token clients must present; `None`: anyone who can connect.
    pub token: Option<String>,
    /// Whether its clients are privileged (raw touches, commands).
    pub privileged: bool,
    /// Most WebSocket clients at once.
    pub max_clients: u32,
    /// Largest message a client may send (bytes).
    pub max_message_bytes: u32,
    /// Serve the viewer page at `/`.
    pub viewer: bool,
    /// Serve the newest `stats` as Prometheus text at `/metrics`.
    pub metrics: bool,
    /// Other web origins whose pages may connect, read-only: `scheme://host[:port]`,
    /// lowercase, without the scheme's default port (as browsers send `Origin`).
    pub origins: Vec<String>,
    /// Other web origins whose pages are privileged (same form as `origins`).
    pub privileged_origins: Vec<String>,
    /// Host names a request's `Host` may name besides the address it reached:
    /// lowercase `name` (on the listen port) or `name:port`.
    pub hosts: Vec<String>,
}

impl WebSocketOptions {
    /// Settings for `listen` with no token, no other origin or host name, the
    /// viewer on: what tools and benches start from.
    pub fn on(listen: SocketAddr, privileged: bool, max_clients: u32) -> WebSocketOptions {
        WebSocketOptions {
            listen,
            token: None,
            privileged,
            max_clients,
            max_message_bytes: 64 * 1024,
            viewer: true,
            metrics: false,
            origins: Vec::new(),
            privileged_origins: Vec::new(),
            hosts: Vec::new(),
        }
    }
}
