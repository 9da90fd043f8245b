//! System calls the safe crates do not wrap (in progress).
#![allow(unsafe_code)]
#![deny(clippy::undocumented_unsafe_blocks)]
