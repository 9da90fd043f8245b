//! crowdtouch: a multi-touch table daemon that drives a crowd.
//!
//! Touches come in (`input`), are segmented into controls and gestures (`gesture`),
//! deform a mesh over the crowd and move its agents (`crowd`), and leave as snapshots
//! over a Unix socket (`publish`). `pipeline` wires the threads and queues between
//! them. See `docs/` and the README for the architecture.
// `unsafe` is denied everywhere except `sys` (ioctls), where every block has a
// `// SAFETY:` comment.
#![deny(unsafe_code)]
#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]

pub mod config;
pub mod crowd;
pub mod engine;
pub mod geom;
pub mod gesture;
pub mod input;
pub mod located;
pub mod picture;
pub mod pipeline;
pub mod publish;
pub mod rng;
pub mod rt;
pub mod sys;
pub mod vocab;
