//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::input::{SurfaceInfo, TouchFrame};
use std::path::{Path, PathBuf};
pub struct Recording {
    pub surface: SurfaceInfo,
    pub frames: Vec<TouchFrame>,
    pub warnings: Vec<RecordingIssue>,
}
pub struct RecordingIssue {
    pub line: usize,
    pub message: String,
}
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum OnBadFrame {
    #[default]
    Stop,
    Skip,
}
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("x")]
    Empty { path: PathBuf },
}
pub fn read_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    unimplemented!()
}
pub fn parse_recording(
    text: &str,
    name: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    unimplemented!()
}
pub fn write_jsonl(
    rec_surface: &SurfaceInfo,
    frames: &[TouchFrame],
    w: &mut impl std::io::Write,
) -> std::io::Result<()> {
    unimplemented!()
}
