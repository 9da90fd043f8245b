//! STUB until the evdev module lands.
#![allow(missing_docs, unused)]
use crate::input::{DeviceInfo, DeviceReader, Error};
use std::path::Path;
pub struct EvdevOptions {
    pub grab: bool,
}
pub fn probe(node: &Path) -> Result<DeviceInfo, Error> {
    Err(Error::NotFound { node: node.into() })
}
pub struct EvdevReader;
impl EvdevReader {
    pub fn open(node: &Path, opts: &EvdevOptions) -> Result<Box<dyn DeviceReader>, Error> {
        Err(Error::NotFound { node: node.into() })
    }
}
