//! Formation shapes the crowd switches between (mesh-formation-control section 7.3,
//! formation-transform section 3.1): polygons with holes and several pieces, or
//! images whose pixels in a colour range are the shape; the shipped ones and the
//! config's, validated, meshed for a crowd where it stands and sampled into target
//! points. Switching to one is [`crate::crowd::control`]'s and
//! [`crate::crowd::transform`]'s job.

mod bitmap;
mod library;
mod region;
mod sample;
mod seam;
mod shapes;

pub use bitmap::{
    decode as decode_image, select as select_pixels, selected as pixel_selected, BitmapDef, Image,
    ImageError, MAX_IMAGE_SIDE, MAX_PIECES, MAX_TRACED_VERTICES,
};
pub use library::{heart_pixels, shipped_formations, FormationLibrary, SHIPPED, SHIPPED_IMAGES};
pub use region::{Piece, Ring};
pub use sample::{hex_fit, SampleError, SampleParams};
pub use shapes::{
    FileReader, Formation, FormationDef, FormationError, PieceDef, Placement, DEFAULT_LAMBDA,
    MAX_FORMATIONS, MAX_MESH_VERTICES, MAX_OUTLINE_VERTICES, MAX_RINGS, START,
};
