//! STUB until the hotplug module lands.
#![allow(missing_docs, unused)]
use std::path::{Path, PathBuf};
use std::time::Duration;
pub enum HotplugEvent {
    Added(PathBuf),
    Changed(PathBuf),
    Removed(PathBuf),
    UdevProcessed(PathBuf),
}
pub struct Watcher;
impl Watcher {
    pub fn new(root: &Path) -> std::io::Result<Watcher> {
        Ok(Watcher)
    }
    pub fn next(&mut self, timeout: Duration) -> std::io::Result<Option<HotplugEvent>> {
        std::thread::sleep(timeout);
        Ok(None)
    }
    pub fn wait_ready(
        &mut self,
        node: &Path,
        udev: &super::udev::UdevDb,
        timeout: Duration,
    ) -> std::io::Result<()> {
        Ok(())
    }
}
