//! Formation transforms: `transform` and `transform compare`, their scenarios and
//! pictures.

pub mod shared;
pub mod transform;
pub mod transform_compare;
pub mod transform_compare_rows;
pub mod transform_scenario;
pub mod transform_setup;
pub mod transform_svg;
pub mod variant;
