//! Turning touch frames into controls (touches on the crowd) and gestures (in open
//! space), and recognising gestures (gesture-driven-crowd-motion sections 5 and 7.1).

pub mod library;
pub mod segment;
pub mod synth;
pub mod track;
