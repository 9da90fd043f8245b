//! The environment's potential field, which pushes control-mesh vertices away from
//! obstacles (mesh-formation-control section 5, eq. 1), and the step that turns the
//! user mesh into the final mesh (section 6.1): displace every vertex by the summed
//! field, then project penetrating vertices out of the obstacles. Mesh edges may
//! still cross obstacles, as the paper allows.
//!
//! Each convex part of an obstacle is one field source, so a concave obstacle built
//! from several parts does not push the crowd out of its concave area (section 5).
//!
//! ```text
//!          ^ f(x) = 1 − d/r          direction: (x − c) / |x − c|
//!        1 |\                          c: the part's centre
//!          | \                         d: distance from the part's surface
//!          |  \
//!        0 +---+------> d
//!          0   r
//! ```

use crate::crowd::environment::{Part, Placement, Scene};
use crate::geom::Vec2;

/// A point this close to a part's centre gets no direction, hence no push (m).
pub const CENTRE_EPSILON_M: f64 = 1e-12;
/// Reach of the potential field pushing mesh vertices off obstacles (m; `r` of
/// mesh-formation-control eq. 1).
pub const MESH_FIELD_RANGE_M: f64 = 1.0;

/// Why field parameters were refused.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FieldError {
    /// The range is not finite and positive.
    #[error("field range must be finite and positive (m)")]
    BadRange,
    /// The step is not finite and ≥ 0.
    #[error("field step must be finite and zero or positive (m)")]
    BadStep,
    /// The margin is not finite and ≥ 0.
    #[error("projection margin must be finite and zero or positive (m)")]
    BadMargin,
}

/// How the field moves mesh vertices.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FieldParams {
    range_m: f64,
    step_m: f64,
    margin_m: f64,
}

impl FieldParams {
    /// `range_m`: the field reaches this far from an obstacle's surface (`r` of
    /// eq. 1). `step_m`: a vertex moves `step_m × F(x)` per application (F is
    /// dimensionless, at most the number of parts in range). `margin_m`: penetrating
    /// vertices end at least this far outside (an agent radius keeps agents off the
    /// obstacle).
    ///
    /// # Errors
    /// [`FieldError`] for a non-finite or out-of-range value.
    pub fn new(range_m: f64, step_m: f64, margin_m: f64) -> Result<FieldParams, FieldError> {
        if !(range_m.is_finite() && range_m > 0.0) {
            return Err(FieldError::BadRange);
        }
        if !(step_m.is_finite() && step_m >= 0.0) {
            return Err(FieldError::BadStep);
        }
        if !(margin_m.is_finite() && margin_m >= 0.0) {
            return Err(FieldError::BadMargin);
        }
        Ok(FieldParams {
            range_m,
            step_m,
            margin_m,
        })
    }

    /// Range `r` (m).
    pub fn range_m(&self) -> f64 {
        self.range_m
    }
    /// Displacement per unit field (m).
    pub fn step_m(&self) -> f64 {
        self.step_m
    }
    /// Projection margin (m).
    pub fn margin_m(&self) -> f64 {
        self.margin_m
    }
}

/// Magnitude of one source's field at distance `d_m` from its surface.
///
/// # Formula
/// mesh-formation-control eq. 1: `f = 1 − d/r` for `0 < d < r`, `0` for `d ≥ r`;
/// inside or on the surface (`d ≤ 0`) the limit value 1.
///
/// # Units
/// `d_m`, `range_m` in metres; the result is dimensionless in `[0, 1]`.
///
/// ```
/// use crowdtouch::crowd::environment::magnitude;
/// assert!((magnitude(0.25, 1.0) - 0.75).abs() < 1e-12);
/// assert_eq!(magnitude(1.5, 1.0), 0.0);
/// assert_eq!(magnitude(-0.1, 1.0), 1.0);
/// ```
pub fn magnitude(d_m: f64, range_m: f64) -> f64 {
    if d_m >= range_m {
        0.0
    } else if d_m <= 0.0 {
        1.0
    } else {
        1.0 - d_m / range_m
    }
}

/// The field of one convex part at `x` (world frame).
///
/// # Formula
/// mesh-formation-control eq. 1 and section 5: `f(d) · (x − c)/‖x − c‖`, `d` the
/// distance from the part's surface, `c` its centre (area centroid, or the disc's
/// centre).
///
/// # Units
/// Metres in; dimensionless vector out (length at most 1). Zero at the centre.
pub fn part_field(part: &Part, placement: &Placement, x: Vec2, range_m: f64) -> Vec2 {
    let local = placement.to_local(x);
    let f = magnitude(part.signed_distance(local), range_m);
    if f == 0.0 {
        return Vec2::zeros();
    }
    let away = local - part.centre();
    let n = away.norm();
    if n.is_nan() || n < CENTRE_EPSILON_M {
        return Vec2::zeros();
    }
    placement.rotate(away / n) * f
}

/// The summed field of every obstacle part at `x` and time `t_s` (dynamic obstacles
/// where their paths put them).
///
/// # Formula
/// `F(x) = Σ_parts f_i(x)` (section 6.1: the fields of all obstacles are summed at
/// each vertex).
///
/// # Units
/// Metres and seconds in, dimensionless vector out.
///
/// # Complexity
/// O(parts).
pub fn field_at(scene: &Scene, x: Vec2, t_s: f64, range_m: f64) -> Vec2 {
    let mut sum = Vec2::zeros();
    scene.for_each_obstacle_part(t_s, |_, _, part, pl| {
        sum += part_field(part, pl, x, range_m);
    });
    sum
}

/// The field sampled at cell centres (section 5: "we divide the floor into grid
/// cells ... and compute the potential field for each cell").
#[derive(Clone, Debug, PartialEq)]
pub struct FieldGrid {
    /// Cells along x.
    pub cols: usize,
    /// Cells along y.
    pub rows: usize,
    /// Cell side (m).
    pub cell_m: f64,
    /// World position of the minimum corner (m).
    pub origin: Vec2,
    /// Field at each cell centre, index `row · cols + col` (dimensionless).
    pub values: Vec<Vec2>,
}

impl FieldGrid {
    /// A zero field on `cols × rows` cells (no validation beyond what sampling
    /// needs: a zero-sized grid samples nothing).
    pub fn new(cols: usize, rows: usize, cell_m: f64, origin: Vec2) -> FieldGrid {
        FieldGrid {
            cols,
            rows,
            cell_m,
            origin,
            values: vec![Vec2::zeros(); cols.saturating_mul(rows)],
        }
    }

    /// Fills every cell with [`field_at`] its centre at `t_s`, reusing the buffer.
    pub fn sample(&mut self, scene: &Scene, t_s: f64, range_m: f64) {
        let n = self.cols.saturating_mul(self.rows);
        self.values.resize(n, Vec2::zeros());
        for row in 0..self.rows {
            for col in 0..self.cols {
                let c = self.origin + Vec2::new(col as f64 + 0.5, row as f64 + 0.5) * self.cell_m;
                self.values[row * self.cols + col] = field_at(scene, c, t_s, range_m);
            }
        }
    }
}

/// Turns user-mesh vertex positions into final-mesh positions, in place:
/// every vertex moves by `step_m × F(v)`, then any vertex within `margin_m` of an
/// obstacle (inside included) is projected to the nearest free point
/// ([`Scene::project_out`]). Edges are not checked: they may cross obstacles.
///
/// # Formula
/// mesh-formation-control sections 5 and 6.1: `v_f = project(v_u + step · F(v_u))`.
///
/// # Units
/// Metres; `t_s` in seconds.
///
/// # Complexity
/// O(vertices × parts) when nothing penetrates.
pub fn displace_vertices(scene: &Scene, t_s: f64, params: &FieldParams, vertices: &mut [Vec2]) {
    for v in vertices.iter_mut() {
        if !(v.x.is_finite() && v.y.is_finite()) {
            continue;
        }
        let moved = *v + field_at(scene, *v, t_s, params.range_m) * params.step_m;
        *v = scene.project_out(moved, params.margin_m, t_s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn scene(obstacles: &str) -> Scene {
        let text = format!(
            "(version: 1, bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)), obstacles: [{obstacles}])"
        );
        Scene::from_str(&text, Path::new("f"), 0.15).unwrap()
    }

    const DISC: &str = "(parts: [Circle(centre_m: (5.0, 4.0), radius_m: 1.0)])";
    const SQUARE: &str =
        "(parts: [Polygon(vertices_m: [(9.0, 3.0), (11.0, 3.0), (11.0, 5.0), (9.0, 5.0)])])";

    #[test]
    fn single_circle_matches_the_closed_form() {
        let s = scene(DISC);
        let r = 2.0;
        // At distance D from the centre along a direction u: (1 − (D − R)/r) u.
        for (angle, dist) in [(0.0f64, 1.5f64), (1.0, 2.0), (2.5, 2.9), (4.0, 1.0)] {
            let u = Vec2::new(angle.cos(), angle.sin());
            let f = field_at(&s, Vec2::new(5.0, 4.0) + u * dist, 0.0, r);
            let expect = u * (1.0 - (dist - 1.0) / r);
            assert!(
                (f - expect).norm() < 1e-12,
                "{angle} {dist}: {f:?} vs {expect:?}"
            );
        }
        // At and beyond the range: nothing.
        assert_eq!(field_at(&s, Vec2::new(8.0, 4.0), 0.0, r), Vec2::zeros());
        assert_eq!(field_at(&s, Vec2::new(9.0, 4.0), 0.0, r), Vec2::zeros());
    }

    #[test]
    fn single_square_points_away_from_its_centre() {
        let s = scene(SQUARE);
        let r = 1.0;
        // Facing the right edge: straight out, 1 − d/r.
        let f = field_at(&s, Vec2::new(11.25, 4.0), 0.0, r);
        assert!((f - Vec2::new(0.75, 0.0)).norm() < 1e-12, "{f:?}");
        // Beside the top edge but off-centre: magnitude from the edge distance,
        // direction from the centre (10, 4) — it has a tangential part, which is why
        // the paper uses the centre.
        let x = Vec2::new(10.8, 5.5);
        let f = field_at(&s, x, 0.0, r);
        let u = (x - Vec2::new(10.0, 4.0)).normalize();
        assert!((f - u * 0.5).norm() < 1e-12, "{f:?}");
        assert!(f.x > 0.0);
        // Past the corner: distance to the corner.
        let x = Vec2::new(11.3, 5.4);
        let d = (x - Vec2::new(11.0, 5.0)).norm();
        let f = field_at(&s, x, 0.0, r);
        assert!((f.norm() - (1.0 - d / r)).abs() < 1e-12);
    }

    #[test]
    fn fields_of_two_obstacles_add() {
        let s = scene(&format!("{DISC}, {SQUARE}"));
        let x = Vec2::new(7.0, 4.0); // 1 m from the disc, 2 m from the square
        let f = field_at(&s, x, 0.0, 2.5);
        let expect = Vec2::new(1.0 - 1.0 / 2.5, 0.0) + Vec2::new(-(1.0 - 2.0 / 2.5), 0.0);
        assert!((f - expect).norm() < 1e-12, "{f:?}");
    }

    #[test]
    fn grid_samples_cell_centres() {
        let s = scene(DISC);
        let mut g = FieldGrid::new(16, 9, 1.0, Vec2::zeros());
        g.sample(&s, 0.0, 2.0);
        // Cell (6, 4) has centre (6.5, 4.5).
        let c = Vec2::new(6.5, 4.5);
        assert_eq!(g.values[4 * 16 + 6], field_at(&s, c, 0.0, 2.0));
        assert!(g.values[4 * 16 + 6].x > 0.0);
        assert_eq!(g.values[0], Vec2::zeros());
    }

    #[test]
    fn vertices_are_pushed_then_projected_out() {
        let s = scene(&format!("{DISC}, {SQUARE}"));
        let p = FieldParams::new(1.0, 0.2, 0.15).unwrap();
        let mut v = vec![
            Vec2::new(6.5, 4.0),  // 0.5 m right of the disc: pushed 0.1 m right
            Vec2::new(10.0, 3.2), // inside the square: out through the bottom
            Vec2::new(1.0, 1.0),  // far: unchanged
        ];
        displace_vertices(&s, 0.0, &p, &mut v);
        assert!((v[0] - Vec2::new(6.6, 4.0)).norm() < 1e-12, "{:?}", v[0]);
        assert!((v[1] - Vec2::new(10.0, 2.85)).norm() < 1e-12, "{:?}", v[1]);
        assert_eq!(v[2], Vec2::new(1.0, 1.0));
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert_eq!(FieldParams::new(0.0, 0.1, 0.1), Err(FieldError::BadRange));
        assert_eq!(
            FieldParams::new(1.0, f64::NAN, 0.1),
            Err(FieldError::BadStep)
        );
        assert_eq!(FieldParams::new(1.0, 0.1, -1.0), Err(FieldError::BadMargin));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 128, ..Default::default() })]

        /// After displacement no vertex is inside an obstacle, whatever the field
        /// step (big steps can throw vertices into another obstacle).
        #[test]
        fn displaced_vertices_are_never_inside(
            pts in proptest::collection::vec((0.0f64..16.0, 0.0f64..9.0), 1..20),
            step in 0.0f64..3.0, margin in 0.0f64..0.15,
        ) {
            let s = scene(&format!("{DISC}, {SQUARE}, (parts: [Circle(centre_m: (7.2, 4.0), radius_m: 0.3)])"));
            let p = FieldParams::new(1.0, step, margin).unwrap();
            let mut v: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
            displace_vertices(&s, 0.0, &p, &mut v);
            for q in v {
                proptest::prop_assert!(s.obstacle_at(q, 0.0).is_none(), "{q:?}");
                proptest::prop_assert!(s.signed_distance(q, 0.0) >= margin - 1e-9);
            }
        }
    }
}
