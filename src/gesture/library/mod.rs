//! The gesture library: gestures paired with the crowd motions they ask for
//! (gesture-driven section 4), its file format and the shipped library.

mod class;
mod error;
mod format;
mod model;
mod random;
mod shipped;
mod validate;

pub use class::{
    check_class_name, ClassId, ClassNameError, MotionClass, UnknownClass, MAX_CLASSES,
    MAX_CLASS_NAME_BYTES,
};
pub use error::{Item, LibraryError, Problem};
pub use format::{
    crc32, read_library, read_library_with, reseal, write_library, FORMAT_VERSION, MAGIC,
    MAX_LIBRARY_BYTES, OLDEST_VERSION,
};
pub use model::{
    ClassCounts, GmmComponent, Library, LibraryGesture, MotionFeatures, Resampled, MAX_COMPONENTS,
    MAX_DEVICE_BYTES, MAX_PARTICIPANT_BYTES, S_H, TRAJ_DIM, T_H,
};
pub use random::{random_library, RandomLibrarySpec};
pub use shipped::{shipped, shipped_from, SHIPPED_BYTES, SHIPPED_NAME};
pub use validate::{
    validate, validate_with, LoadPolicy, IN_MEMORY, MAX_GMM_COMPONENTS, MAX_MOTION_DURATION_S,
    MAX_ORIGIN_BYTES, ORTHONORMAL_TOLERANCE, POINT_SLACK, SYMMETRY_TOLERANCE, WEIGHT_SUM_TOLERANCE,
};
