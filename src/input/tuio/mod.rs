//! TUIO input: cursors sent over OSC/UDP by camera tables (reacTIVision), TUIO
//! simulators and phone apps, turned into touch frames.
//!
//! `osc.rs` reads OSC packets in place (no allocation); `decode.rs` keeps every
//! sender's cursor sessions (TUIO 1.1 `/tuio/2Dcur`, TUIO 2.0 `/tuio2/frm`, `ptr`,
//! `alv`) and emits a [`TouchFrame`](crate::vocab::TouchFrame) per complete frame;
//! `source.rs` is the thread shell: a UDP socket read with a timeout.

mod decode;
mod osc;
mod source;

pub use decode::{TuioCounters, TuioDecoder, MAX_SENDERS, REORDER_WINDOW};
pub use osc::{walk, Arg, Message, OscError, OscErrorKind, MAX_DEPTH};
pub use source::{Error, TuioSettings, TuioSource, MAX_PACKETS_PER_S};
