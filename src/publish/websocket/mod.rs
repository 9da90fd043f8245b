//! The WebSocket output: protocol v1 over WebSocket, and the live viewer page, on
//! one TCP address (`outputs: [WebSocket(listen: ...)]`).
//!
//! WebSocket clients are clients of the Unix socket's publisher
//! ([`Server::with_websocket`](crate::publish::Server::with_websocket)): a snapshot
//! is encoded once per encoding for every client of either transport, and every
//! client has the same bounded queue, drop policy, command window and budget. A
//! WebSocket I/O thread of its own (`ct-ws-io`, `server.rs`) serves the address:
//! `epoll` over the listener, the publisher's wake-up and every client, all
//! non-blocking; it parses each HTTP request head itself (`http.rs`, capped at
//! [`MAX_REQUEST_HEAD_BYTES`]), serves the page, refuses what it must (400, 401,
//! 403, 404, 405, 421, 426, 431, 503) and upgrades the rest, then frames and reads
//! messages with `tungstenite` resuming on `WouldBlock` (`conn.rs`, whose doc states
//! the Host and Origin rules, the handshake checks, close codes and ping policy).
//!
//! Privilege: a client that sends no `Origin` (not a browser) or the server's own
//! origin (the viewer page) is privileged iff its output says `privileged: true`; a
//! page of an origin in `privileged_origins` is privileged, one in `origins` is
//! read-only (no raw touches, no commands); any other origin is refused.

mod conn;
mod error;
mod http;
mod options;
mod server;

pub use error::Error;
pub use http::{
    parse_request_head, valid_websocket_key, HttpError, Request, MAX_REQUEST_HEAD_BYTES,
};
pub use options::WebSocketOptions;
pub(crate) use server::WsLoop;
pub use server::{WebSocketListener, HANDSHAKE_TIMEOUT, VIEWER_PAGE};
