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
}
