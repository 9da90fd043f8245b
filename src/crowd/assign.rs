//! STUB (uncommitted)
#![allow(missing_docs, unused)]
use crate::geom::Vec2;
pub struct CostMatrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}
impl CostMatrix {
    pub fn new(rows: usize, cols: usize) -> CostMatrix {
        unimplemented!()
    }
    pub fn resize(&mut self, rows: usize, cols: usize) {}
    pub fn rows(&self) -> usize {
        self.rows
    }
    pub fn cols(&self) -> usize {
        self.cols
    }
    pub fn get(&self, r: usize, c: usize) -> f64 {
        0.0
    }
    pub fn set(&mut self, r: usize, c: usize, v: f64) {}
    pub fn row(&self, r: usize) -> &[f64] {
        &self.data
    }
    pub fn row_mut(&mut self, r: usize) -> &mut [f64] {
        &mut self.data
    }
}
pub trait CostProvider {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix);
}
pub struct SquaredDistance;
pub struct Distance;
impl CostProvider for SquaredDistance {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {}
}
impl CostProvider for Distance {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {}
}
#[derive(Copy, Clone, Debug, PartialEq, thiserror::Error)]
pub enum AssignError {
    #[error("e")]
    Empty,
    #[error("m")]
    MoreRowsThanCols { rows: usize, cols: usize },
    #[error("n")]
    NotFinite { row: usize, col: usize },
    #[error("i")]
    Infeasible { row: usize },
}
pub struct Solver {
    a: Vec<usize>,
}
impl Solver {
    pub fn new() -> Solver {
        unimplemented!()
    }
    pub fn solve(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        unimplemented!()
    }
    pub fn solve_warm(&mut self, costs: &CostMatrix) -> Result<&[usize], AssignError> {
        unimplemented!()
    }
    pub fn assignment(&self) -> &[usize] {
        &self.a
    }
    pub fn total_cost(&self, costs: &CostMatrix) -> f64 {
        0.0
    }
    pub fn verify_optimal(&self, costs: &CostMatrix, tol: f64) -> bool {
        true
    }
}
