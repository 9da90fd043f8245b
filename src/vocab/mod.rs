//! The shared vocabulary: the plain data types every layer speaks.
//!
//! Time ([`Micros`] on CLOCK_MONOTONIC), touch frames as sources produce them, motion
//! types, and what the control thread publishes (snapshots, meshes, events, stats) or
//! takes from clients (commands), and what a recognised gesture makes the crowd do
//! (recognitions, planned trajectories), and a formation transform's progress and
//! summary, and the edit mode's tracks and state, and the scene and where its moving
//! things are. Nothing here does work: `input` fills touch frames,
//! `gesture` and `crowd` read them, `engine` fills snapshots, `publish` encodes them.
//! It depends on [`geom`](crate::geom) only, so every other module may use it.

mod command;
mod device;
mod edit;
mod event;
mod motion;
mod plan;
mod scene;
mod snapshot;
mod stats;
mod time;
mod touch;
mod transform;

pub use command::{
    ClientContact, ClientId, Command, CommandRequest, FormationMethod, MAX_CLIENT_CONTACTS,
    MAX_CLIENT_CONTACT_ID, MAX_LASSO_VERTICES, MAX_SELECT_IDS,
};
pub use device::parse_vendor_product;
pub use edit::{CollisionView, EditView, PreviewView, SelectionView, TrackView, TracksView};
pub use event::{CollectState, CollectView, ControlKind, DeviceState, Event};
pub use motion::MotionType;
pub use plan::{MotionPhase, NeighbourView, PlanOrigin, PlanView, Recognition};
pub use scene::{CheckpointView, SceneItemView, ScenePoses, SceneView, ShapeView, TerrainView};
pub use snapshot::{AgentView, MeshView, Snapshot, TouchView};
pub use stats::{
    DeviceStatus, OutputCounters, RestartPending, StageHistogram, StageStats, StatsReport,
};
pub use time::Micros;
pub use touch::{
    Contact, ContactFlags, ContactId, FrameFull, TouchFrame, CLIENT_DEVICE, MAX_CONTACTS,
};
pub use transform::{TransformMeasures, TransformOutcome, TransformSummary, TransformView};
