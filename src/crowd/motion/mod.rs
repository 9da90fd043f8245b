//! Crowd motions driven by gestures (gesture-driven-crowd-motion sections 6 and 7):
//! a crowd motion's features (FPCA and a Gaussian mixture over eigenscores),
//! blending the motions of a gesture's neighbours, synthesising trajectories for the
//! crowd at hand, and the controller that walks agents along them.

mod build;
mod command;
mod follow;
mod import;
mod keep;
mod simulate;

pub use build::{build_library, library_agents, BuildError, BuildParams, SHIPPED_SEED};
pub use command::{
    alignment, play_duration, rotated, GestureCommandError, GestureJob, GestureMotion,
    GestureRequest, PreparedGesture, PreparedRemesh, PreparedWindow, RemeshRequest, WindowRequest,
    MOTION_DURATION_S,
};
pub use follow::{FollowError, FollowParams, FollowPhase, Follower};
pub use import::{
    busiest_window, import_motion, ImportError, ImportWindow, ImportedMotion, PersonSamples,
    DEFAULT_IMPORT_DURATION_S, MAX_IMPORT_SAMPLES, MIN_IMPORT_PEOPLE,
};
pub use keep::{
    is_split_class, keep_formation, parts_of, ApplyMode, KeepParams, Kept, Similarity,
    GROUP_GAP_FACTOR,
};
pub use simulate::{
    library_specs, measure, simulate, MotionMeasure, MotionSpec, SimulateError, SimulatedMotion,
    ARRIVE_TOLERANCE_M, LIBRARY_AGENTS, REST_SPEED_M_S, SETTLE_CAP_S, WAYPOINTS_PER_PHASE,
};
mod blend;
mod crowd_motion;
mod error;
mod features;
mod fpca;
mod gmm;
mod synth;

pub use blend::{blend, combine, modified_gram_schmidt, GS_DROP_REL};
pub use crowd_motion::{
    deserialise, resample_hermite, serialise, start_centroid_radius, CrowdMotion, SPREAD_FLOOR_REL,
};
pub use error::MotionError;
pub use features::{features, validate_features, FeatureParams};
pub use fpca::{fpca, reconstruct, Fpca, ReconstructionError};
pub use gmm::{
    fit, fit_auto, log_likelihood, standard_normal_pair, validate_mixture, GmmFit, GmmParams,
    GmmSampler, PRUNE_WEIGHT,
};
pub use synth::{start_costs, synthesise, Placement, Synthesis, Synthesiser, MIN_CROWD_SCALE_M};
