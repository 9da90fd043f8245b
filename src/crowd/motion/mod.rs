//! Crowd motions driven by gestures (gesture-driven-crowd-motion sections 6 and 7):
//! a crowd motion's features (FPCA and a Gaussian mixture over eigenscores),
//! blending the motions of a gesture's neighbours, synthesising trajectories for the
//! crowd at hand, and the controller that walks agents along them.

mod follow;
mod simulate;

pub use follow::{FollowError, FollowParams, FollowPhase, Follower};
pub use simulate::{
    library_specs, measure, simulate, MotionMeasure, MotionSpec, SimulateError, SimulatedMotion,
    ARRIVE_TOLERANCE_M, LIBRARY_AGENTS, REST_SPEED_M_S, SETTLE_CAP_S, WAYPOINTS_PER_PHASE,
};
