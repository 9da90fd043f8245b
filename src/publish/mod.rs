//! The Unix-socket publisher (in progress).
