//! `crowdtouch scene render`: a picture of a scene and of how agents cross it.
//!
//! Draws, in world metres (x right, y down, as `replay --svg`):
//! * the travel-time field `Φ` of one goal as a heat map with iso-time contours
//!   (mesh-formation-control section 6.2: the scene rasterised into a
//!   [`SceneGrid`], the unit cost of eq. 7 from [`cost_field_into`], fast marching
//!   from the goal with [`Fmm::solve_into`]); blocked and unreachable cells in their
//!   own colours;
//! * the world bounds, static obstacles (filled), travel-speed patches coloured by
//!   motion type, moving obstacles and patches where they are at `--t` with their
//!   paths dashed, checkpoints outlined with their formation names;
//! * agents sampled on a lattice in the default crowd start rectangle and each
//!   agent's route to the goal, traced by descending `Φ` ([`descent_direction`]);
//! * a legend (Table 1 motion types and speed factors), the colour scale, a title
//!   line and a scale bar.
//!
//! # Units of `Φ`
//! Seconds of travel at the agents' preferred speed `f` (the config's
//! `crowd.max_speed_m_s`): eq. 7 with `α = 0`, `β = 1 /s`, `γ = 0` gives the unit
//! cost `C = 1 / (f · TravelSpeed(x))` in seconds per metre. Without discomfort the
//! assignment's default weights (`α = β = 1`) give the same field scaled by
//! `(α f + β) / β`, so the routes are the same.
//!
//! The output depends only on the scene file and the arguments: no clock, no
//! randomness, numbers printed with fixed precision, so the same input gives the
//! same bytes.
//!
//! [`SceneGrid`]: crowdtouch::crowd::environment::SceneGrid
//! [`cost_field_into`]: crowdtouch::crowd::environment::eikonal::cost_field_into
//! [`Fmm::solve_into`]: crowdtouch::crowd::environment::eikonal::Fmm::solve_into
//! [`descent_direction`]: crowdtouch::crowd::environment::eikonal::descent_direction

mod args;
mod colours;
mod contours;
mod error;
mod heatmap;
mod legend;
mod picture;
mod routes;
mod svg;
mod view;

pub use args::{render, RenderArgs};
