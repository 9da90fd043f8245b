//! The control core: one tick of segment → deform → assign → step → snapshot.
//!
//! The engine owns the world (segmenter, mesh controller, agents) and knows nothing
//! about threads or clocks: it is given frames and `now`. The control thread drives it
//! in real time (`pipeline`); [`replay_virtual`] drives it on a virtual clock, which
//! makes replays deterministic.
//!
//! | file | what |
//! |---|---|
//! | `state.rs` | the [`Engine`]: what it owns, built from the config, reconfigured, what it reports |
//! | `tick.rs` | one tick ([`Engine::tick`]) and touch frames in ([`Engine::push_frame`]) |
//! | `commands.rs` | client commands ([`Engine::command`]) |
//! | `resize.rs` | a new crowd size: goal sampling prepared off the tick ([`ResizeRequest`](crate::crowd::control::ResizeRequest)), installed between ticks |
//! | `switch.rs` | formation switches at checkpoints and on request |
//! | `transform.rs`, `transform_state.rs` | formation transforms (formation-transform): prepared off the tick, run every tick, direct control after |
//! | `edit.rs`, `edit_grab.rs`, `edit_jobs.rs`, `edit_state.rs` | the edit mode (crowd-motion-editing): tracks loaded and played, grabbed and dragged by fingers, retimed, undone, saved |
//! | `scene_view.rs`, `scene_state.rs` | the scene as published: its parts when it changes, its moving things' poses every tick |
//! | `params.rs` | the config turned into the crowd's and gesture's parameter structs |
//! | `replay.rs` | replays on a virtual clock |
//! | `error.rs` | why a command or switch was refused |

mod collect;
mod collect_jobs;
mod collect_state;
mod commands;
mod edit;
mod edit_grab;
mod edit_jobs;
mod edit_select;
mod edit_state;
mod error;
mod gesture;
mod gesture_state;
mod params;
mod pool;
mod replay;
mod resize;
mod scene_state;
mod scene_view;
mod state;
mod switch;
mod tick;
mod transform;
mod transform_state;

#[cfg(test)]
mod tests;

pub use collect_state::{CollectDone, CollectJob, CollectPlan};
pub use edit::{GESTURE_FASTER, GESTURE_RETIME_S, HELD_TRACKS_PERIOD_US};
pub use edit_state::{EditDone, EditFileJob, EditJob, EDIT_THRESHOLD_M, GROUP_LINK_M, MAX_UNDO};
pub use error::{CommandError, SwitchError};
pub use params::{
    ap_params, inline_planner, move_params, pair_cost, planner_for, planner_params, point_metric,
    same_scene, search_params, segment_params, tap_thresholds,
};
pub use replay::{replay_virtual, VirtualClock};
pub use state::{Engine, EngineCounters, MAX_TICK_S, RADIUS_FIT};
pub use tick::TickOutput;
pub use transform::{
    MAX_DURATION_S, MIN_DESIRED_SPEED_M_S, SAMPLE_RELAX_ITERATIONS, SAMPLE_SPACING_RADII,
    TOUCHED_FORMATION,
};
