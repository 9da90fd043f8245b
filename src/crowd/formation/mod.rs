//! Formation shapes the crowd switches between (mesh-formation-control section 7.3):
//! the shipped ones and the config's, validated, and meshed for a crowd where it
//! stands. Switching to one is [`crate::crowd::control`]'s job.

mod sample;
mod shapes;

pub use sample::{SampleError, SampleParams};

pub use shapes::{
    Formation, FormationDef, FormationError, FormationLibrary, Placement, DEFAULT_LAMBDA,
    MAX_FORMATIONS, MAX_MESH_VERTICES, MAX_OUTLINE_VERTICES, SHIPPED, START,
};
