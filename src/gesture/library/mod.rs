//! The gesture library: gestures paired with the crowd motions they ask for
//! (gesture-driven section 4), its file format and the shipped library.

mod class;
mod model;

pub use class::{MotionClass, UnknownClass};
pub use model::{
    GmmComponent, Library, LibraryGesture, MotionFeatures, Resampled, MAX_COMPONENTS, S_H,
    TRAJ_DIM, T_H,
};
