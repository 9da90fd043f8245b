//! The crowd: agents, the deformable mesh, assignment, and the controllers.
//!
//! Pure geometry and numerics: nothing here knows about threads, sockets or devices.

pub mod agents;
pub mod arap;
pub mod assign;
pub mod assigner;
pub mod direct;
pub mod effort;
pub mod eikonal;
pub mod environment;
pub mod field;
pub mod formation;
pub mod mesh;
pub mod mvc;
pub mod scene;
