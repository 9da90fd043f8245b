//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::input::{SurfaceInfo, TouchFrame};
use std::path::{Path, PathBuf};
pub fn shipped() -> Vec<(String, SurfaceInfo, Vec<TouchFrame>)> {
    unimplemented!()
}
pub fn write_shipped(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    unimplemented!()
}
