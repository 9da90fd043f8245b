//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("in use {path}")]
    InUse { path: PathBuf },
}
#[derive(Clone, Debug)]
pub struct HelloInfo {
    pub world: crate::geom::Rect,
    pub agents: u32,
    pub agent_radius_m: f64,
}
pub struct PublisherStats {}
impl PublisherStats {
    pub fn clients(&self) -> u32 {
        0
    }
    pub fn snapshots_dropped(&self) -> u64 {
        0
    }
    pub fn take_end_to_end(&self) -> hdrhistogram::Histogram<u64> {
        unimplemented!()
    }
    pub fn take_encode(&self) -> hdrhistogram::Histogram<u64> {
        unimplemented!()
    }
}
pub struct Server {}
impl Server {
    pub fn bind(
        cfg: &crate::config::SocketConfig,
        path: &Path,
        hello: HelloInfo,
    ) -> Result<Server, Error> {
        unimplemented!()
    }
    pub fn path(&self) -> &Path {
        unimplemented!()
    }
    pub fn stats(&self) -> Arc<PublisherStats> {
        unimplemented!()
    }
    pub fn run(
        self,
        rx: crossbeam_channel::Receiver<crate::snapshot::Outgoing>,
        commands: crossbeam_channel::Sender<crate::snapshot::CommandRequest>,
        stop: Arc<AtomicBool>,
    ) {
        unimplemented!()
    }
}
pub mod protocol {
    #![allow(missing_docs, unused)]
    use crate::snapshot::*;
    pub struct FieldSet;
    impl FieldSet {
        pub const ALL: FieldSet = FieldSet;
    }
    pub fn encode_snapshot_json(
        s: &Snapshot,
        latency_us: Option<u64>,
        dropped: u64,
        fields: &FieldSet,
        out: &mut Vec<u8>,
    ) {
    }
    pub fn encode_mesh_json(m: &MeshView, with_triangles: bool, out: &mut Vec<u8>) {}
    pub fn encode_event(e: &Event, out: &mut Vec<u8>) {}
}
