//! Outputs: what leaves the daemon. The control thread publishes each snapshot,
//! mesh, event and stats report once ([`Outgoing`]); every output consumes it on a
//! thread of its own, behind its own bounded queue and drop policy ([`output`]).
//!
//! * [`protocol`]: the wire format renderers read (JSON Lines or binary snapshots,
//!   the hello negotiation, client messages), documented in `docs/protocol.md`.
//! * [`socket`]: the Unix-socket output, the first [`Output`].
//! * [`tuio`]: TUIO 1.1 or 2.0 over OSC/UDP to a renderer.
//! * [`websocket`]: the same stream over WebSocket, served by the socket's
//!   publisher, and the viewer page.

pub mod metrics;
mod outgoing;
pub mod output;
pub mod protocol;
pub mod socket;
pub mod tuio;
pub mod websocket;

pub use outgoing::Outgoing;
pub use output::{
    every_message, ClientLimit, Output, OutputContext, OutputSet, OutputStats, Outputs, Overflow,
    QueuePolicy,
};
pub use protocol::HelloInfo;
pub use socket::{Error, PeerPolicy, PublisherStats, Server, SocketOptions};
pub use websocket::{WebSocketListener, WebSocketOptions};
