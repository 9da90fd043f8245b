//! Crowd motion editing (crowd-motion-editing, Zhang et al. 2020): a crowd's recorded
//! or authored tracks, edited in space by a concave-hull cage and as-rigid-as-possible
//! mesh deformation (section 3.2), in time (section 3.3), checked for collisions in
//! space-time and kept apart by retiming (section 4.1), and kept out of obstacles by
//! adjusting the cage (section 4.2).
//!
//! | file | what | paper |
//! |---|---|---|
//! | `flat.rs` | the bounds every track keeps and [`TrackError`]; [`TrackRef`] (one person's track, borrowed), [`Tracks`] (what detection reads), [`FlatTracks`] (every person's samples in three arrays: a million people in 62 MB) | 3.1 |
//! | `tracks.rs` | [`TrackSet`]: per person a spatial and a temporal track, linked samples and gaps, editable; conversions to and from [`FlatTracks`] | 3.1 |
//! | [`io`] | readers and writers: our JSON Lines, CSV `t,id,x,y`, the pedestrian datasets' raw format; files read capped and written safely | 3.1 |
//! | `paths.rs` | [`group_tracks`]: a group walking the standard path through a scene (fast-marching route around obstacles), in rows | 5.2 |
//! | `record.rs` | [`TrackRecorder`]: a running crowd's positions, tick by tick, into tracks on a time grid | 3.1 |
//! | `script.rs` | edit scripts (`edit apply --ops`): selections, fixed points, drags, retimes, with their lines | 3.2, 3.3 |
//! | `apply.rs` | [`run_script`]: an edit script run on a track set, with what each drag did | 3.2, 3.3 |
//! | `error.rs` | [`EditError`]: why an edit was refused | |
//! | `select.rs` | [`Selection`]: samples by id, rectangle, lasso, time window | 3.2 |
//! | `hull.rs` | [`concave_hull`]: the cage polygon (geo's concave hull, grown by a margin; convex fallback) | 3.2 |
//! | `cage.rs` | [`Cage`]: the spatial editor: one cage per time window, chained by shared handles and blended across the overlaps | 3.2, eqs. 1–9 |
//! | `cage_window.rs` | [`CageWindow`]: one cage (concave hull, MVC, deformation mesh, exact handle constraints) | 3.2, eqs. 1–8 |
//! | `cage_split.rs` | [`WindowParams`]: where a person revisits a place, and the time windows cut so that none holds a revisit | 3.2 (ours) |
//! | `cage_speed.rs` | [`correct_speeds`]: segments re-timed to their pre-edit speeds | 3.2, eq. 9 |
//! | `cage_solve.rs` | [`CageParams`]; the deformation solve: cotangent-weighted ARAP, locality (eqs. 3, 5), the rotation-invariant hull-shape term (eqs. 7–8), the local/global iteration to convergence | 3.2, eqs. 1–8 |
//! | `cage_mvc.rs` | mean value coordinates of many samples w.r.t. one cage polygon | 3.2, eq. 4 |
//! | `temporal.rs` | [`retime`]: dragging time nodes, intervals kept, locality, times increasing | 3.3, eqs. 10–12 |
//! | `collide.rs` | [`detect`]: people closer than a threshold in space-time (and the all-pairs reference) | 4.1.1 |
//! | `clusters.rs` | [`Cluster`]s: identical tracks and people standing together, counted in closed form; the order detection visits people in | 4.1.1 |
//! | `slab_grid.rs` | the uniform grid detection lays over each time slab | 4.1.1 |
//! | `avoid.rs` | [`avoid`]: retiming people apart, positions kept | 4.1.2, eqs. 18–28 |
//! | `avoid_params.rs` | [`AvoidParams`], [`AvoidReport`], [`AvoidError`]: what avoidance takes and tells | 4.1.2 |
//! | `avoid_solve.rs` | one pair's pieces retimed, a person's track re-solved, a pair's retiming and its undo | 4.1.2, eqs. 18–28 |
//! | `avoid_shift.rs` | avoidance's first candidates: rigid time shifts of a group or one person, judged on the piece pairs near in space | 4.1.2 (ours) |
//! | `obstacles.rs` | [`avoid_obstacles`]: hull vertices mapped out of obstacles, then eq. 1; [`crowd_width`] | 4.2, eq. 29 |

mod apply;
mod avoid;
mod avoid_params;
mod avoid_shift;
mod avoid_solve;
mod cage;
mod cage_mvc;
mod cage_solve;
mod cage_speed;
mod cage_split;
#[cfg(test)]
mod cage_tests;
mod cage_window;
mod clusters;
mod collide;
mod error;
mod flat;
mod hull;
pub mod io;
mod obstacles;
mod paths;
mod record;
mod script;
mod select;
mod slab_grid;
mod temporal;
mod tracks;

pub use apply::{run_script, ApplyParams, ApplyReport, DragReport, HANDLE_RADIUS_M};
pub use avoid::{avoid, avoid_around, avoid_around_leaving};
pub use avoid_params::{
    AvoidError, AvoidParams, AvoidReport, Remaining, Stuck, MIN_PACE_LENGTH_M, STILL_SPEED_M_S,
};
pub use cage::{Cage, MAX_SHARED_HANDLES, SHARED_SPACING_CELLS};
pub use cage_solve::{
    CageParams, DEFAULT_ALPHA, DEFAULT_BETA, DEFAULT_LOCALITY_RADIUS_M, DEFAULT_MAX_ITERATIONS,
    DEFAULT_TOLERANCE_M, PAPER_ALPHA, PAPER_BETA, PAPER_K,
};
pub use cage_speed::{correct_speeds, SpeedReport, MIN_INTERVAL_FRACTION};
pub use cage_split::{TimeWindow, WindowParams, DEFAULT_REVISIT_GAP_S, DEFAULT_REVISIT_RADIUS_M};
pub use cage_window::{CageWindow, Handle, ShapeError, SolveStats};
pub use clusters::{Cluster, MIN_STANDING_CLUSTER};
pub use collide::{
    collisions_all_pairs, detect, detect_keeping, Approach, CollideError, CollisionEvent,
    Collisions, PairCollision, DEFAULT_KEEP,
};
pub use error::EditError;
pub use flat::{
    coordinate_problem, time_problem, FlatTracks, TrackError, TrackRef, Tracks, MAX_COORDINATE_M,
    MAX_SAMPLES, MAX_TIME_S, MIN_SAMPLE_STEP_S,
};
pub use hull::{
    concave_hull, grid_cell, grid_subsample, is_simple, Hull, HullParams, DEFAULT_CONCAVITY,
    DEFAULT_MAX_EDGE_CELLS, DEFAULT_MAX_POINTS, DEFAULT_MIN_CELL_M, DENSE_GRID_FACTOR,
};
pub use obstacles::{
    avoid_obstacles, crowd_width, crowd_width_at, push_samples_out, samples_in_obstacles,
    ObstacleParams, ObstacleReport,
};
pub use paths::{group_tracks, standard_path, GroupPath, PathError, DIRECTION_SPAN_M};
pub use record::{RecordError, TrackRecorder};
pub use script::{parse_script, Op, OpDef, Script, ScriptError, SelectSpec, MAX_LIST, MAX_OPS};
pub use select::{point_in_polygon, SampleRef, Selection, SelectionQuery};
pub use temporal::{retime, RetimeParams, RetimeReport, TimeDrag};
pub use tracks::{Track, TrackSet};
