//! The input tools: `devices`, `calibrate`, `record`, `hid`, `replay`, `watch` and
//! `synth-recordings`.

pub mod calibrate;
pub mod devices;
pub mod hid;
pub mod record;
pub mod replay;
pub mod replay_svg;
pub mod watch;
