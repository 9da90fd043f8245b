//! Turning touch frames into controls (touches on the crowd) and gestures (in open
//! space), and recognising gestures (gesture-driven-crowd-motion sections 5 and 7.1).

pub mod capture;
pub mod continuous;
pub mod dtw;
pub mod error;
pub mod eval;
pub mod features;
pub mod find;
pub mod generator;
pub mod knn;
pub mod library;
pub mod mobb;
pub mod physical;
pub mod recognise;
pub mod reject;
pub mod resample;
pub mod segment;
pub mod style2;
pub mod synth;
pub mod track;
