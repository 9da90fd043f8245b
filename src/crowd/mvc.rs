//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::geom::Vec2;
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum MvcError {
    #[error("x")]
    Degenerate,
}
pub fn mean_value_coordinates(poly: &[Vec2], p: Vec2, out: &mut [f64]) -> Result<(), MvcError> {
    unimplemented!()
}
pub fn convex_hull(points: &[Vec2]) -> Vec<usize> {
    unimplemented!()
}
pub fn point_in_convex_polygon(poly: &[Vec2], p: Vec2) -> bool {
    unimplemented!()
}
