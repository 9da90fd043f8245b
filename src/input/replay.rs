//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::input::{FrameSink, TouchFrame};
use crate::time::Micros;
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Pacing {
    RealTime,
    Virtual,
}
pub struct ReplayItem {
    pub name: String,
    pub frames: Vec<TouchFrame>,
}
pub struct ReplaySource {}
impl ReplaySource {
    pub fn new(items: Vec<ReplayItem>, looped: bool, gap: Micros, pacing: Pacing) -> ReplaySource {
        unimplemented!()
    }
    pub fn run(
        &mut self,
        sink: &mut dyn FrameSink,
        stop: &std::sync::atomic::AtomicBool,
        on_item: &mut dyn FnMut(usize),
    ) {
        unimplemented!()
    }
}
