//! Crowd motion editing (crowd-motion-editing, Zhang et al. 2020): a crowd's recorded
//! or authored tracks, edited in space by a concave-hull cage and as-rigid-as-possible
//! mesh deformation (section 3.2), in time (section 3.3), checked for collisions in
//! space-time and kept apart by retiming (section 4.1), and kept out of obstacles by
//! adjusting the cage (section 4.2).
//!
//! | file | what | paper |
//! |---|---|---|
//! | `tracks.rs` | [`TrackSet`]: per person a spatial and a temporal track, linked samples and gaps | 3.1 |
//! | `paths.rs` | [`group_tracks`]: a group walking the standard path through a scene (fast-marching route around obstacles), in rows | 5.2 |
//! | `record.rs` | [`TrackRecorder`]: a running crowd's positions, tick by tick, into tracks on a time grid | 3.1 |
//! | [`io`] | readers and writers: our JSON Lines, CSV `t,id,x,y`, the pedestrian datasets' raw format | 3.1 |

pub mod io;
mod paths;
mod record;
mod tracks;

pub use paths::{group_tracks, standard_path, GroupPath, PathError, DIRECTION_SPAN_M};
pub use record::{RecordError, TrackRecorder};
pub use tracks::{Track, TrackError, TrackSet, MAX_SAMPLES};
