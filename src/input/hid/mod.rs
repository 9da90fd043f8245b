//! STUB until the HID module lands.
#![allow(missing_docs, unused)]
use crate::input::{DeviceInfo, DeviceReader, Error};
use std::path::Path;
pub struct HidOptions {}
pub fn probe(node: &Path) -> Result<DeviceInfo, Error> {
    Err(Error::NotFound { node: node.into() })
}
pub struct HidReader;
impl HidReader {
    pub fn open(node: &Path, opts: &HidOptions) -> Result<Box<dyn DeviceReader>, Error> {
        Err(Error::NotFound { node: node.into() })
    }
}
