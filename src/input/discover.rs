//! STUB until the discovery module lands.
#![allow(missing_docs, unused)]
use crate::input::{DeviceInfo, DeviceKind, Error};
use std::path::{Path, PathBuf};
pub trait Prober {
    fn probe(&self, kind: DeviceKind, node: &Path) -> Result<DeviceInfo, Error>;
}
pub struct Found {
    pub info: DeviceInfo,
    pub processed: bool,
    pub probe_error: Option<String>,
}
pub fn discover(root: &Path, prober: &dyn Prober) -> Vec<Found> {
    Vec::new()
}
#[derive(Clone, Debug, PartialEq)]
pub enum Selector {
    Auto,
    Name(String),
    VendorProduct(String),
    Path(PathBuf),
    Id(String),
}
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum InterfacePreference {
    Any,
    Evdev,
    Hidraw,
}
#[derive(Debug)]
pub struct SelectError(pub String);
impl std::fmt::Display for SelectError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}
pub fn select<'a>(
    found: &'a [Found],
    sel: &Selector,
    pref: InterfacePreference,
) -> Result<&'a Found, SelectError> {
    Err(SelectError("stub".into()))
}
pub fn matches(info: &DeviceInfo, sel: &Selector) -> bool {
    false
}
