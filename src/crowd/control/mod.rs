//! The controllers that move the crowd: direct manipulation, where fingers on the
//! crowd deform its mesh (mesh-formation-control sections 4.1–4.2).

mod direct;

pub use direct::{DirectController, DirectError, DirectParams};
