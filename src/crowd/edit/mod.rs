//! Crowd motion editing (crowd-motion-editing, Zhang et al. 2020): a crowd's recorded
//! or authored tracks, edited in space by a concave-hull cage and as-rigid-as-possible
//! mesh deformation (section 3.2), in time (section 3.3), checked for collisions in
//! space-time and kept apart by retiming (section 4.1), and kept out of obstacles by
//! adjusting the cage (section 4.2).
//!
//! | file | what | paper |
//! |---|---|---|
//! | `tracks.rs` | [`TrackSet`]: per person a spatial and a temporal track, linked samples and gaps | 3.1 |
//! | `collide.rs` | [`detect`]: people closer than a threshold in space-time (and the all-pairs reference) | 4.1.1 |
//! | `avoid.rs` | [`avoid`]: retiming people apart, positions kept | 4.1.2 |
//! | [`io`] | readers and writers: the pedestrian datasets' raw format, … | |

mod avoid;
mod collide;
pub mod io;
mod tracks;

pub use avoid::{
    avoid, AvoidError, AvoidParams, AvoidReport, Remaining, Stuck, MIN_PACE_LENGTH_M,
    STILL_SPEED_M_S,
};
pub use collide::{
    collisions_all_pairs, detect, Approach, CollideError, CollisionEvent, Collisions, PairCollision,
};
pub use tracks::{Track, TrackError, TrackSet, MAX_SAMPLES};
