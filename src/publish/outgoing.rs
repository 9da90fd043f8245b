//! What the control thread hands to the outputs.

use crate::vocab::{
    ClientId, EditView, Event, MeshView, PlanView, ScenePoses, SceneView, Snapshot, StatsReport,
    TracksView, TransformSummary, TransformView,
};
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
    /// Every agent's planned trajectory (a gesture's motion, or a library motion
    /// shown by `library collect`): to clients subscribed to `plan` only.
    Plan(Arc<PlanView>),
    /// A running formation transform's progress (every tick): to clients
    /// subscribed to `transform` only.
    Transform(Arc<TransformView>),
    /// A formation transform ended, summarised: to clients subscribed to
    /// `transform` only.
    TransformEnd(Arc<TransformSummary>),
    /// The edit mode's tracks changed: to clients subscribed to `edit` only.
    Tracks(Arc<TracksView>),
    /// The edit mode's state changed: to clients subscribed to `edit` only.
    Edit(Arc<EditView>),
    /// The scene changed (or the daemon started): to clients subscribed to
    /// `scene` only, and to each such client when it subscribes.
    Scene(Arc<SceneView>),
    /// Where the scene's moving things are this tick: to clients subscribed to
    /// `scene` only.
    ScenePoses(Arc<ScenePoses>),
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
