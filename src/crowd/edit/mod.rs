//! Crowd motion editing (crowd-motion-editing, Zhang et al. 2020): a crowd's recorded
//! or authored tracks, edited in space by a concave-hull cage and as-rigid-as-possible
//! mesh deformation (section 3.2), in time (section 3.3), checked for collisions in
//! space-time and kept apart by retiming (section 4.1), and kept out of obstacles by
//! adjusting the cage (section 4.2).
//!
//! | file | what | paper |
//! |---|---|---|
//! | `tracks.rs` | [`TrackSet`]: per person a spatial and a temporal track, linked samples and gaps | 3.1 |
//! | `script.rs` | edit scripts (`edit apply --ops`): selections, fixed points, drags, retimes, with their lines | 3.2, 3.3 |
//! | `collide.rs` | [`detect`]: people closer than a threshold in space-time (and the all-pairs reference) | 4.1.1 |
//! | [`io`] | readers and writers: our JSON Lines, CSV `t,id,x,y`, the pedestrian datasets' raw format | 3.1 |

mod collide;
pub mod io;
mod script;
mod tracks;

pub use collide::{
    collisions_all_pairs, detect, Approach, CollideError, CollisionEvent, Collisions, PairCollision,
};
pub use script::{parse_script, Op, OpDef, Script, ScriptError, SelectSpec, MAX_LIST, MAX_OPS};
pub use tracks::{Track, TrackError, TrackSet, MAX_SAMPLES};
