//! STUB until the udev module lands.
#![allow(missing_docs, unused)]
use std::path::PathBuf;
pub struct UdevDb {
    pub root: PathBuf,
}
