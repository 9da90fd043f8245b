//! STUB until the calibration module lands.
#![allow(missing_docs, unused)]
use crate::input::TouchFrame;
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Calibration {
    pub rotation: u16,
    pub flip_x: bool,
    pub flip_y: bool,
    pub matrix: Option<[f64; 6]>,
}
pub struct DeviceTransform;
impl DeviceTransform {
    pub fn apply(&self, frame: &mut TouchFrame) {}
}
pub fn solve_matrix(targets: &[(f64, f64)], touched: &[(f64, f64)]) -> Result<[f64; 6], String> {
    Err("stub".into())
}
