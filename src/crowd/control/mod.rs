//! The controllers that move the crowd: direct manipulation, where fingers on the
//! crowd deform its mesh (mesh-formation-control sections 4.1–4.2), and formation
//! switches prepared off the control thread (section 7.3).

mod direct;
mod switch;

pub use direct::{DirectController, DirectError, DirectParams};
pub use switch::{BuiltSwitch, PreparedResize, PreparedSwitch, ResizeRequest, SwitchRequest};
