//! Direct manipulation: fingers on the crowd deform its mesh
//! (mesh-formation-control sections 4.1–4.2).
//!
//! Each control from the segmenter becomes a *rig* (`rig.rs`): one handle per
//! finger (`handle.rs`: the nearest vertex of the mesh the user sees when the
//! finger landed, kept at its offset from the finger) plus supplementary soft
//! constraints — for a line control the vertices between its two handles, moved by
//! linear interpolation of the handles; for an area control the vertices inside the
//! convex hull of its fingers and points sampled on and inside it (`area.rs`, held
//! through the triangles they lie in), moved by their mean value coordinates in
//! that hull. All rigs' constraints go to one ARAP solve (`controller.rs`), so
//! several controls (two hands, two people) act on the mesh together.
//!
//! The mesh is as rigid as possible relative to its pose when the constraint set
//! last changed (a finger landed or lifted, a drag ended): a deformation persists
//! until another control changes it, and `reset` returns to the formation.
//!
//! Handles follow their finger through check points spaced along its trajectory
//! (section 4.1), at the constraint speed less the opposing force proportional to
//! the agents' lag. When the fingers lift, the handles go on through the check
//! points still ahead of them, until they reach the last one, a new control lands
//! on the crowd, or a reset.

mod area;
mod controller;
mod handle;
mod rig;

pub use controller::{DirectController, DirectError, DirectParams};
