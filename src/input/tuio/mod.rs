//! TUIO input: cursors sent over OSC/UDP by camera tables (reacTIVision), TUIO
//! simulators and phone apps, turned into touch frames.
//!
//! `osc.rs` reads OSC packets in place (no allocation); `decode.rs` keeps every
//! sender's cursor sessions (TUIO 1.1 `/tuio/2Dcur`, TUIO 2.0 `/tuio2/frm`, `ptr`,
//! `alv`) and emits a [`TouchFrame`](crate::vocab::TouchFrame) per complete frame,
//! within its [`TuioLimits`]; `flood.rs` caps the datagrams of each peer (a token
//! bucket each); `source.rs` is the thread shell: a UDP socket read with a timeout.

mod decode;
mod flood;
mod osc;
mod source;

pub use decode::{
    TuioCounters, TuioDecoder, TuioLimits, DEFAULT_MAX_SENDERS, MAX_ALIVE, MOST_SENDERS,
    REORDER_WINDOW,
};
pub use flood::{Admit, FloodGate, DEFAULT_MAX_PACKETS_PER_S, IDLE_US, PEERS_PER_SENDER};
pub use osc::{walk, Arg, Message, OscError, OscErrorKind, MAX_DEPTH};
pub use source::{Error, TuioSettings, TuioSource, BUFFER_BYTES};
