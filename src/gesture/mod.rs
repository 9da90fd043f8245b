//! Turning touch frames into controls (touches on the crowd) and gestures (in open space).

pub mod segment;
