//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::geom::{Rect, Vec2};
pub struct TriMesh {
    rest: Vec<Vec2>,
    triangles: Vec<[u32; 3]>,
    outline: Vec<u32>,
}
impl TriMesh {
    pub fn grid(rect: Rect, cols: usize, rows: usize) -> TriMesh {
        unimplemented!()
    }
    pub fn rest(&self) -> &[Vec2] {
        &self.rest
    }
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    pub fn outline(&self) -> &[u32] {
        &self.outline
    }
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }
}
pub fn nearest_vertex(positions: &[Vec2], p: Vec2) -> (usize, f64) {
    unimplemented!()
}
pub fn distance_to_mesh(mesh: &TriMesh, positions: &[Vec2], p: Vec2) -> f64 {
    unimplemented!()
}
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GoalSample {
    pub tri: u32,
    pub bary: [f64; 3],
}
pub fn sample_goals(mesh: &TriMesh, n: usize) -> Vec<GoalSample> {
    unimplemented!()
}
pub fn goal_positions(
    mesh: &TriMesh,
    samples: &[GoalSample],
    positions: &[Vec2],
    out: &mut Vec<Vec2>,
) {
    unimplemented!()
}
