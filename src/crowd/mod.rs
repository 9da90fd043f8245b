//! The crowd: agents, the deformable mesh over them, assignment, the environment and
//! the controllers that move them.
//!
//! Pure geometry and numerics: nothing here knows about threads, sockets, devices,
//! the config or the clock (callers pass `now` and parameter structs). One folder per
//! job:
//!
//! | folder | what | paper |
//! |---|---|---|
//! | [`mesh`] | the triangle mesh, goal points on it, ARAP deformation, mean value coordinates | mesh-formation-control 4.1–4.2, 6.1 |
//! | [`assign`] | exact agent-to-goal assignment: cost sources, the solver, the least-effort cost | mesh-formation-control 6.1; formation-transform 3.2 |
//! | [`environment`] | scenes, the potential field, fast marching, the travel-cost planner | mesh-formation-control 5, 6.2 |
//! | [`formation`] | formation shapes the crowd switches between, meshed for a crowd | mesh-formation-control 7.3 |
//! | [`control`] | the controllers: direct manipulation by touch, formation switches | mesh-formation-control 4, 7.3 |
//! | [`motion`] | crowd motions from gestures: FPCA, Gaussian mixtures, blending, synthesis, following | gesture-driven 6, 7 |
//! | [`transform`] | formation transforms: sampling, least-effort pairing, affinity-propagation subgroups, social forces with mutual-information feedback, the paper's measures | formation-transform 3, 5 |
//! | [`edit`] | crowd motion editing: track sets, cage editing in space and time, space-time collisions and their avoidance by retiming | crowd-motion-editing 3, 4 |
//! | [`agents`] | agents following their goals (PD control, overlap resolution) | mesh-formation-control 6.2.1 |

pub mod agents;
pub mod assign;
pub mod control;
pub mod edit;
pub mod environment;
pub mod formation;
pub mod mesh;
pub mod motion;
pub mod transform;
