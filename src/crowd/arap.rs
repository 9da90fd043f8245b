//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use super::mesh::TriMesh;
use crate::geom::Vec2;
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Constraint {
    pub vertex: u32,
    pub weight: f64,
}
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum ArapError {
    #[error("x")]
    Degenerate,
}
pub struct Arap {
    c: Vec<Constraint>,
}
impl Arap {
    pub fn new(mesh: &TriMesh) -> Arap {
        unimplemented!()
    }
    pub fn set_constraints(&mut self, constraints: &[Constraint]) -> Result<(), ArapError> {
        unimplemented!()
    }
    pub fn constraints(&self) -> &[Constraint] {
        &self.c
    }
    pub fn solve(
        &mut self,
        targets: &[Vec2],
        anchor: &[Vec2],
        out: &mut [Vec2],
    ) -> Result<(), ArapError> {
        unimplemented!()
    }
}
