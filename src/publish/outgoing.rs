//! What the control thread hands to the outputs.

use crate::vocab::{ClientId, Event, MeshView, Snapshot, StatsReport};
use std::sync::Arc;

/// What the control thread sends to the publisher thread.
#[derive(Clone, Debug)]
pub enum Outgoing {
    /// A new snapshot (every tick).
    Snapshot(Arc<Snapshot>),
    /// The mesh changed.
    Mesh(Arc<MeshView>),
    /// Something happened.
    Event(Arc<Event>),
    /// Periodic stats.
    Stats(Arc<StatsReport>),
    /// The answer to a command: `Ok` becomes `ack`, `Err` becomes `error`.
    Reply {
        /// The client that asked.
        client: ClientId,
        /// Its id for the command.
        id: serde_json::Value,
        /// Outcome.
        result: Result<(), String>,
    },
}
