//! The daemon's configuration: RON, strict, validated, with errors that point.
//!
//! `config/crowdtouch.ron` is the documented default and is embedded in the binary
//! ([`Config::embedded_default`]). Unknown fields are errors; every range is checked;
//! every error names the file, the line and column, and the field. Reads are
//! size-capped ([`MAX_CONFIG_BYTES`]).
//!
//! # Search path (`run` without `--config`)
//! 1. `$CROWDTOUCH_CONFIG`
//! 2. `$XDG_CONFIG_HOME/crowdtouch/crowdtouch.ron` (or `~/.config/crowdtouch/crowdtouch.ron`)
//! 3. `/etc/crowdtouch/crowdtouch.ron`
//! 4. the embedded default.
//!
//! # Reloading
//! `live.rs` classifies every field: applied by a reload (SIGHUP) or kept until a
//! restart ([`FIELDS`], [`plan_reload`]).

mod edit;
mod error;
mod gestures;
mod inputs;
mod live;
mod load;
mod model;
mod outputs;
mod transform;
#[cfg(test)]
mod transform_tests;
mod validate;

pub use edit::set_calibration_matrix;
pub use error::{ConfigIssue, EditError, Error};
pub use gestures::{
    Collected, ContinuousConfig, GestureApply, GestureWeights, GesturesConfig,
    DEFAULT_APPROACH_TIMEOUT_S, DEFAULT_COLLECTED, DEFAULT_GMM_COMPONENTS, DEFAULT_K,
    DEFAULT_MAX_DURATION_S, DEFAULT_MIN_DURATION_MS, DEFAULT_MIN_PIECE_AGENTS,
    DEFAULT_MIN_TRAVEL_MM, DEFAULT_MOTION_SPEED_M_S, MAX_COLLECTED_WEIGHT, MAX_GMM_COMPONENTS,
    MAX_K,
};
pub use inputs::{
    CalibrationConfig, DeviceInterface, DeviceSelect, InputConfig, DEFAULT_PALM_MAX_MM,
    TUIO_MOST_SENDERS, TUIO_MOST_SESSIONS_PER_FRAME, TUIO_PACKETS_PER_S,
};
pub use live::{
    field_class, plan_reload, show_value, unclassified_fields, FieldChange, FieldClass,
    ReloadClass, ReloadPlan, FIELDS,
};
pub use load::{load_recogniser, locate_issues, search_path, DEFAULT_CONFIG_RON, MAX_CONFIG_BYTES};
pub use model::{
    AssignmentConfig, AssignmentCost, BudgetsConfig, Config, ControlsConfig, CrowdConfig,
    EditConfig, FormationsConfig, LogLevel, MeshConfig, PipelineConfig, PrivilegedPeers,
    RealtimeConfig, SocketConfig, SurfaceConfig, CONFIG_VERSION, DEFAULT_FIELD_STEP_M,
    EDIT_DIR_NAME,
};
pub use outputs::{
    is_loopback, normalize_host, normalize_origin, OutputConfig, TuioProfile, TuioVersion,
    MAX_TUIO_DATAGRAM_BYTES, MIN_TUIO_DATAGRAM_BYTES,
};
pub use transform::{
    GestureFormation, SubgroupSimilarity, SubgroupsConfig, TransformAttraction, TransformCost,
    TransformMoveConfig, DEFAULT_METHOD, MAX_DESIRED_SPEED_M_S,
};
pub use validate::{LARGE_CROWD_BUDGETS, MAX_AGENTS, MAX_AGENTS_LARGE};
