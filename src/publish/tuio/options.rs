//! What a TUIO output is built from, and why it could not start.

use crate::geom::Rect;

/// The TUIO version an output speaks.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Version {
    /// TUIO 1.1: `/tuio/2Dcur`, `/tuio/2Dobj`, `/tuio/2Dblb`.
    V1_1,
    /// TUIO 2.0: `/tuio2/frm`, `ptr`, `tok`, `bnd`, `alv`.
    V2_0,
}

/// A TUIO output's settings (the pipeline builds them from the config's
/// `outputs` entry).
#[derive(Clone, Debug)]
pub struct TuioOptions {
    /// `host:port` the datagrams go to; resolved once, at start.
    pub target: String,
    /// Protocol version.
    pub version: Version,
    /// Send the touches (raw contacts: only to a privileged target).
    pub cursors: bool,
    /// Send the agents.
    pub objects: bool,
    /// Send the controls' boxes.
    pub blobs: bool,
    /// Most frames per second.
    pub rate_hz: f64,
    /// Largest datagram (bytes).
    pub max_datagram_bytes: usize,
    /// The `source` name frames carry.
    pub source: String,
    /// The world rectangle (m), mapped to TUIO's unit square.
    pub world: Rect,
}

/// Why a TUIO output could not start.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The target's host name did not resolve.
    #[error("TUIO output: cannot resolve the target {target}: {source}")]
    Resolve {
        /// The configured target.
        target: String,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The target resolved to no address.
    #[error("TUIO output: the target {target} resolves to no address")]
    NoAddress {
        /// The configured target.
        target: String,
    },
    /// No local UDP socket could be opened.
    #[error("TUIO output to {target}: cannot open a UDP socket: {source}")]
    Socket {
        /// The configured target.
        target: String,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}
