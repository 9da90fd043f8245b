//! The TUIO output: the crowd as TUIO 1.1 or 2.0 over OSC/UDP, for renderers
//! that speak the tabletop ecosystem's common protocol (Unity, TouchDesigner,
//! Processing, openFrameworks, Max/MSP, vvvv).
//!
//! * [`frame`](TuioFrame): a snapshot in TUIO's terms: touches as cursors, agents
//!   as objects, controls as blobs, in the unit square (units and orientation
//!   there);
//! * session ids, stable per agent, fresh per touch and control;
//! * the TUIO 1.1 and 2.0 encoders (messages by `rosc`), and the packing of a
//!   frame into datagrams of a bounded size;
//! * [`TuioOutput`]: the [`Output`](crate::publish::Output) with its thread, rate
//!   limit and counters.
//!
//! The message reference for renderer authors is `docs/renderers.md`, "TUIO".

mod encode11;
mod encode20;
mod frame;
mod options;
mod output;
mod session;
mod split;

pub use encode11::{Encoder11, Profiles};
pub use encode20::{dimension, Encoder20};
pub use frame::{Blob, Cursor, Framer, Object, TuioFrame};
pub use options::{Error, TuioOptions, Version};
pub use output::{TuioOutput, TuioStats, QUEUE_CAPACITY};
pub use split::{alive_element_bytes, Datagrams, MIN_ITEMS_PER_BUNDLE};

#[cfg(test)]
mod tests;
