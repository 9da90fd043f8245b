//! The invariants a validated scene keeps, checked (tests, the scene fuzz target).

use super::limits::MAX_SPEED_FACTOR;
use super::model::Scene;
use super::shape::{self, Part};

impl Scene {
    /// Invariant checker for tests: every part is valid, every polygon convex and
    /// counter-clockwise, every speed factor in range.
    ///
    /// # Errors
    /// A description of the first broken invariant.
    pub fn sanity_check(&self) -> Result<(), String> {
        let all_parts = self
            .obstacles
            .iter()
            .flat_map(|o| o.parts.iter())
            .chain(self.patches.iter().flat_map(|p| p.parts.iter()))
            .chain(self.dynamic.iter().flat_map(|d| d.parts.iter()))
            .chain(self.checkpoints.iter().map(|c| &c.region));
        for part in all_parts {
            match part {
                Part::Polygon(p) => {
                    if shape::signed_twice_area(p.vertices()) <= 0.0 {
                        return Err("polygon not counter-clockwise".into());
                    }
                    if shape::non_convex_vertex(p.vertices()).is_some() {
                        return Err("polygon not convex".into());
                    }
                }
                Part::Circle(c) => {
                    if c.radius_m.is_nan() || c.radius_m <= 0.0 {
                        return Err("circle radius not positive".into());
                    }
                }
            }
        }
        for p in &self.patches {
            let s = p.terrain.speed_factor;
            if !(s > 0.0 && s <= MAX_SPEED_FACTOR) {
                return Err(format!("patch speed factor {s} out of range"));
            }
        }
        Ok(())
    }
}
