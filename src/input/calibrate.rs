//! Calibration: from a device's unit square to its place on the table.
//!
//! Decoders hand out contacts in the device's own unit square (`x` right, `y` down,
//! `[0, 1]²`, straight from the axis ranges). The input thread then runs each frame
//! through a [`DeviceTransform`], which applies, in this order:
//!
//! ```text
//!   device unit square      1. calibration matrix         2. rotation, clockwise     3. flips
//!   (x right, y down)          [a b c]                       about the centre
//!                              [d e f]
//!   (0,0) ───── (1,0)       x' = a·x + b·y + c            90°: (x, y) ↦ (1−y, x)      flip_x: x ↦ 1−x
//!     │  A     B  │         y' = d·x + e·y + f           180°: (x, y) ↦ (1−x, 1−y)    flip_y: y ↦ 1−y
//!     │           │                                      270°: (x, y) ↦ (y, 1−x)
//!     │  D     C  │         (the `matrix` of the config        A ─ B       D ─ A
//!   (0,1) ───── (1,1)        overrides udev's                  │   │  90°  │   │
//!                            LIBINPUT_CALIBRATION_MATRIX;      D ─ C  ──►  C ─ B
//!                            neither = identity)
//!
//!   4. clamp to [0, 1]²   5. into the device's region of the table:  X = rx + x·rw,  Y = ry + y·rh
//! ```
//!
//! The matrix convention is exactly libinput's `LIBINPUT_CALIBRATION_MATRIX`: row-major
//! `[a, b, c, d, e, f]` applied to normalised coordinates, so a matrix copied from a
//! working libinput setup means the same thing here. Rotation by 90° is the same map as
//! libinput's documented matrix `0 -1 1 1 0 0`, 180° is `-1 0 1 0 -1 1`, 270° is
//! `0 1 0 -1 0 1`.
//!
//! Steps 1–3 are affine and are folded into one matrix when the transform is built, so
//! [`DeviceTransform::apply`] costs one 2×3 multiply, a clamp and a scale per contact and
//! never allocates.
//!
//! A four-point calibration screen shows targets, records where the device reported
//! each touch, and calls [`solve_matrix`]; the result goes into
//! [`Calibration::matrix`] (with `rotation: 0` and no flips, since the solved matrix
//! already contains them).

use crate::vocab::{ContactFlags, TouchFrame};
use serde::{Deserialize, Serialize};

/// A calibration matrix, row-major `[a, b, c, d, e, f]`: `x' = a·x + b·y + c`,
/// `y' = d·x + e·y + f` on unit-square coordinates.
pub type Matrix = [f64; 6];

/// The identity calibration matrix.
pub const IDENTITY: Matrix = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

/// Smallest `det(S) / trace(S)²` of the touched points' scatter matrix `S` that
/// [`solve_matrix`] accepts; below it the points are (nearly) collinear. Evenly spread
/// points give 0.25.
pub const MIN_SPREAD_RATIO: f64 = 1e-6;

/// Smallest total spread `trace(S)` (unit-square², summed over points) that
/// [`solve_matrix`] accepts; below it the touched points coincide.
pub const MIN_SPREAD_UNIT2: f64 = 1e-12;

/// Smallest `|a·e − b·d|` of a solved matrix; below it the matrix collapses the surface.
pub const MIN_MATRIX_DET: f64 = 1e-9;

/// Slack allowed when checking that a region lies inside the table's unit square.
pub const REGION_EPS: f64 = 1e-9;

/// What is wrong with a calibration, a region or calibration points.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    /// A matrix string did not hold exactly six numbers.
    #[error("calibration matrix needs 6 numbers \"a b c d e f\", found {found}")]
    MatrixLength {
        /// How many whitespace-separated values there were.
        found: usize,
    },
    /// A matrix value is not a number.
    #[error("calibration matrix value {index} ({text:?}) is not a number")]
    MatrixNotANumber {
        /// Position of the value (0 = `a`).
        index: usize,
        /// The text found there.
        text: String,
    },
    /// A matrix value is infinite or NaN.
    #[error("calibration.matrix[{index}] is not a finite number")]
    MatrixNotFinite {
        /// Position of the value (0 = `a`).
        index: usize,
    },
    /// The rotation is not a quarter turn.
    #[error("calibration.rotation must be 0, 90, 180 or 270 (degrees clockwise), not {rotation}")]
    Rotation {
        /// The rotation given.
        rotation: u16,
    },
    /// A region field is out of range.
    #[error("region.{field} = {value}: {problem}")]
    Region {
        /// `x`, `y`, `width` or `height`.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// The device's physical size is not a positive finite number.
    #[error("size_mm.{field} = {value}: must be a positive, finite number of millimetres")]
    SizeMm {
        /// `width` or `height`.
        field: &'static str,
        /// The value given.
        value: f64,
    },
    /// The palm threshold is not a positive finite number.
    #[error("palm_max_mm = {value}: must be a positive, finite number of millimetres")]
    PalmThreshold {
        /// The value given.
        value: f64,
    },
    /// Fewer than three calibration point pairs.
    #[error("calibration needs at least 3 point pairs (normally 4), got {found}")]
    TooFewPoints {
        /// Pairs given.
        found: usize,
    },
    /// Target and touched lists differ in length.
    #[error("{targets} target points but {touched} touched points")]
    PointCountMismatch {
        /// Targets given.
        targets: usize,
        /// Touches given.
        touched: usize,
    },
    /// A calibration point is infinite or NaN.
    #[error("calibration point {index} is not finite")]
    PointNotFinite {
        /// Index of the pair.
        index: usize,
    },
    /// The touched points are collinear or coincide, so no affine map is determined.
    #[error("the touched points are collinear or coincide; touch targets that span the surface")]
    Collinear,
    /// The solved matrix collapses the surface (targets collinear).
    #[error("the target points are collinear; the solved matrix would collapse the surface")]
    DegenerateTargets,
}

/// Per-device calibration from the config.
///
/// `Default` is the identity: no rotation, no flips, no matrix (udev's matrix, if
/// any, is then used).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Calibration {
    /// Clockwise rotation about the centre, in degrees: 0, 90, 180 or 270.
    pub rotation: u16,
    /// Mirror left-right (after the rotation).
    pub flip_x: bool,
    /// Mirror top-bottom (after the rotation).
    pub flip_y: bool,
    /// Calibration matrix `[a, b, c, d, e, f]` (libinput convention); overrides udev's
    /// `LIBINPUT_CALIBRATION_MATRIX`.
    pub matrix: Option<Matrix>,
}

impl Calibration {
    /// Checks the fields.
    ///
    /// # Errors
    /// [`CalibrationError::Rotation`] for a rotation other than 0/90/180/270,
    /// [`CalibrationError::MatrixNotFinite`] naming the first bad matrix entry.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        if !matches!(self.rotation, 0 | 90 | 180 | 270) {
            return Err(CalibrationError::Rotation {
                rotation: self.rotation,
            });
        }
        if let Some(m) = &self.matrix {
            check_matrix(m)?;
        }
        Ok(())
    }

    /// The matrix that maps device coordinates to calibrated ones: this calibration's
    /// `matrix` (else `udev_matrix`, else identity), then the rotation, then the flips.
    ///
    /// # Errors
    /// As [`Calibration::validate`]; also a non-finite `udev_matrix` when it is used.
    pub fn combined(&self, udev_matrix: Option<Matrix>) -> Result<Matrix, CalibrationError> {
        self.validate()?;
        let base = match (self.matrix, udev_matrix) {
            (Some(m), _) => m,
            (None, Some(m)) => {
                check_matrix(&m)?;
                m
            }
            (None, None) => IDENTITY,
        };
        let mut m = compose(&rotation_matrix(self.rotation), &base);
        if self.flip_x {
            m = compose(&[-1.0, 0.0, 1.0, 0.0, 1.0, 0.0], &m);
        }
        if self.flip_y {
            m = compose(&[1.0, 0.0, 0.0, 0.0, -1.0, 1.0], &m);
        }
        Ok(m)
    }
}

fn check_matrix(m: &Matrix) -> Result<(), CalibrationError> {
    match m.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(CalibrationError::MatrixNotFinite { index }),
        None => Ok(()),
    }
}

/// The libinput matrix of a clockwise rotation about the centre (`rotation` in
/// {0, 90, 180, 270}; anything else gives the identity).
pub fn rotation_matrix(rotation: u16) -> Matrix {
    match rotation {
        90 => [0.0, -1.0, 1.0, 1.0, 0.0, 0.0],
        180 => [-1.0, 0.0, 1.0, 0.0, -1.0, 1.0],
        270 => [0.0, 1.0, 0.0, -1.0, 0.0, 1.0],
        _ => IDENTITY,
    }
}

/// `outer ∘ inner`: first `inner`, then `outer`.
pub fn compose(outer: &Matrix, inner: &Matrix) -> Matrix {
    let [a2, b2, c2, d2, e2, f2] = *outer;
    let [a1, b1, c1, d1, e1, f1] = *inner;
    [
        a2 * a1 + b2 * d1,
        a2 * b1 + b2 * e1,
        a2 * c1 + b2 * f1 + c2,
        d2 * a1 + e2 * d1,
        d2 * b1 + e2 * e1,
        d2 * c1 + e2 * f1 + f2,
    ]
}

/// Applies a matrix to a point.
pub fn apply_matrix(m: &Matrix, x: f64, y: f64) -> (f64, f64) {
    (m[0] * x + m[1] * y + m[2], m[3] * x + m[4] * y + m[5])
}

/// Where a device's surface lies on the table, as a rectangle in the table's unit
/// square (`x` right, `y` down). Default: the whole table.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    /// Left edge.
    pub x: f64,
    /// Top edge.
    pub y: f64,
    /// Width.
    pub width: f64,
    /// Height.
    pub height: f64,
}

impl Default for Region {
    fn default() -> Self {
        Region::WHOLE
    }
}

impl Region {
    /// The whole table.
    pub const WHOLE: Region = Region {
        x: 0.0,
        y: 0.0,
        width: 1.0,
        height: 1.0,
    };

    /// Checks that the region is a non-empty rectangle inside the unit square.
    ///
    /// # Errors
    /// [`CalibrationError::Region`] naming the field.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        let bad = |field, value, problem| {
            Err(CalibrationError::Region {
                field,
                value,
                problem,
            })
        };
        for (field, v) in [
            ("x", self.x),
            ("y", self.y),
            ("width", self.width),
            ("height", self.height),
        ] {
            if !v.is_finite() {
                return bad(field, v, "not a finite number");
            }
        }
        if self.x < 0.0 || self.x >= 1.0 {
            return bad("x", self.x, "must be in [0, 1)");
        }
        if self.y < 0.0 || self.y >= 1.0 {
            return bad("y", self.y, "must be in [0, 1)");
        }
        if self.width <= 0.0 || self.x + self.width > 1.0 + REGION_EPS {
            return bad("width", self.width, "must be > 0 with x + width ≤ 1");
        }
        if self.height <= 0.0 || self.y + self.height > 1.0 + REGION_EPS {
            return bad("height", self.height, "must be > 0 with y + height ≤ 1");
        }
        Ok(())
    }
}

/// Everything the input thread applies to a device's frames: calibration, its region
/// on the table, and the palm size threshold.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceTransform {
    /// Matrix, rotation and flips folded into one map (device → calibrated unit square).
    cal: Matrix,
    region: Region,
    size_mm: Option<(f64, f64)>,
    palm_max_mm: Option<f32>,
}

impl Default for DeviceTransform {
    fn default() -> Self {
        DeviceTransform::identity()
    }
}

impl DeviceTransform {
    /// No calibration, the whole table, no palm threshold.
    pub fn identity() -> DeviceTransform {
        DeviceTransform {
            cal: IDENTITY,
            region: Region::WHOLE,
            size_mm: None,
            palm_max_mm: None,
        }
    }

    /// Builds the transform.
    ///
    /// * `calibration`: rotation, flips and the config's matrix (which overrides
    ///   `udev_matrix`, the device's `LIBINPUT_CALIBRATION_MATRIX`).
    /// * `region`: the device's rectangle in the table's unit square.
    /// * `size_mm`: the device's physical `(width, height)`, kept for callers that
    ///   convert between surface and physical units (contact sizes arrive in mm).
    /// * `palm_max_mm`: contacts whose major axis exceeds this are flagged
    ///   [`ContactFlags::PALM`] (libinput's palm-by-size threshold).
    ///
    /// # Errors
    /// A [`CalibrationError`] naming the field that is out of range.
    pub fn new(
        calibration: &Calibration,
        udev_matrix: Option<Matrix>,
        region: Region,
        size_mm: Option<(f64, f64)>,
        palm_max_mm: Option<f64>,
    ) -> Result<DeviceTransform, CalibrationError> {
        let cal = calibration.combined(udev_matrix)?;
        region.validate()?;
        if let Some((w, h)) = size_mm {
            for (field, value) in [("width", w), ("height", h)] {
                if !(value.is_finite() && value > 0.0) {
                    return Err(CalibrationError::SizeMm { field, value });
                }
            }
        }
        if let Some(value) = palm_max_mm {
            if !(value.is_finite() && value > 0.0) {
                return Err(CalibrationError::PalmThreshold { value });
            }
        }
        Ok(DeviceTransform {
            cal,
            region,
            size_mm,
            palm_max_mm: palm_max_mm.map(|v| v as f32),
        })
    }

    /// The combined calibration (matrix, rotation, flips) as one matrix.
    pub fn matrix(&self) -> Matrix {
        self.cal
    }

    /// The device's region on the table.
    pub fn region(&self) -> Region {
        self.region
    }

    /// The device's physical size in millimetres, when known.
    pub fn size_mm(&self) -> Option<(f64, f64)> {
        self.size_mm
    }

    /// The palm threshold in millimetres, when set.
    pub fn palm_max_mm(&self) -> Option<f64> {
        self.palm_max_mm.map(f64::from)
    }

    /// Maps one point from the device's unit square to the table's unit square:
    /// calibration, clamp to `[0, 1]²`, then into the region.
    ///
    /// # Complexity
    /// O(1), no allocation.
    pub fn map_point(&self, x: f64, y: f64) -> (f64, f64) {
        let (cx, cy) = apply_matrix(&self.cal, x, y);
        let (cx, cy) = (clamp_unit(cx), clamp_unit(cy));
        let r = &self.region;
        (
            (r.x + cx * r.width).clamp(0.0, 1.0),
            (r.y + cy * r.height).clamp(0.0, 1.0),
        )
    }

    /// Maps every contact of `frame` in place and flags palms by size.
    ///
    /// # Complexity
    /// O(contacts), no allocation (called by the input thread for every frame).
    pub fn apply(&self, frame: &mut TouchFrame) {
        for c in frame.contacts_mut() {
            let (x, y) = self.map_point(f64::from(c.x), f64::from(c.y));
            c.x = x as f32;
            c.y = y as f32;
            if let (Some(max), Some(major)) = (self.palm_max_mm, c.major_mm) {
                if major > max {
                    c.flags.insert(ContactFlags::PALM);
                }
            }
        }
    }
}

/// Clamps to `[0, 1]`; NaN (only from a NaN input) becomes 0.
fn clamp_unit(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0)
    }
}

/// Solves the calibration matrix that maps where the device reported touches onto
/// where the targets were shown (least squares, affine).
///
/// `targets[i]` is where target `i` was drawn and `touched[i]` where the device
/// reported the touch on it, both in unit-square coordinates; the result `M`
/// minimises `Σ |M·touched[i] − targets[i]|²`, so applying `M` to device coordinates
/// gives screen coordinates. Store it as [`Calibration::matrix`] with rotation 0.
///
/// # Formula
/// Ordinary least squares for each output row separately. With the touched points
/// centred (`x̃ = x − x̄`, `ỹ = y − ȳ`) and the scatter matrix
/// `S = [Σx̃² Σx̃ỹ; Σx̃ỹ Σỹ²]`:
/// `[a b]ᵀ = S⁻¹ [Σx̃X Σỹ X]ᵀ`, `c = X̄ − a·x̄ − b·ȳ`, and the same for `d e f` with
/// the targets' `Y`.
///
/// # Units
/// Unit-square coordinates in, a dimensionless matrix out.
///
/// # Complexity
/// O(n) time, O(1) memory.
///
/// # Errors
/// [`CalibrationError::TooFewPoints`] (< 3 pairs), [`CalibrationError::PointCountMismatch`],
/// [`CalibrationError::PointNotFinite`], [`CalibrationError::Collinear`] (touched points
/// on a line, by [`MIN_SPREAD_RATIO`]), [`CalibrationError::DegenerateTargets`].
///
/// ```
/// use crowdtouch::input::calibrate::{apply_matrix, solve_matrix};
/// // The device is mounted upside down: (x, y) is reported as (1−x, 1−y).
/// let targets = [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9)];
/// let touched: Vec<_> = targets.iter().map(|&(x, y)| (1.0 - x, 1.0 - y)).collect();
/// let m = solve_matrix(&targets, &touched).unwrap();
/// let (x, y) = apply_matrix(&m, 0.25, 0.75);
/// assert!((x - 0.75).abs() < 1e-12 && (y - 0.25).abs() < 1e-12);
/// ```
pub fn solve_matrix(
    targets: &[(f64, f64)],
    touched: &[(f64, f64)],
) -> Result<Matrix, CalibrationError> {
    if targets.len() != touched.len() {
        return Err(CalibrationError::PointCountMismatch {
            targets: targets.len(),
            touched: touched.len(),
        });
    }
    let n = touched.len();
    if n < 3 {
        return Err(CalibrationError::TooFewPoints { found: n });
    }
    for (index, (t, p)) in targets.iter().zip(touched).enumerate() {
        if ![t.0, t.1, p.0, p.1].iter().all(|v| v.is_finite()) {
            return Err(CalibrationError::PointNotFinite { index });
        }
    }
    let nf = n as f64;
    let mean = |pts: &[(f64, f64)]| {
        let (sx, sy) = pts
            .iter()
            .fold((0.0, 0.0), |(sx, sy), p| (sx + p.0, sy + p.1));
        (sx / nf, sy / nf)
    };
    let (mx, my) = mean(touched);
    let (tx, ty) = mean(targets);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    let (mut sx_x, mut sy_x, mut sx_y, mut sy_y) = (0.0, 0.0, 0.0, 0.0);
    for (t, p) in targets.iter().zip(touched) {
        let (dx, dy) = (p.0 - mx, p.1 - my);
        let (dtx, dty) = (t.0 - tx, t.1 - ty);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
        sx_x += dx * dtx;
        sy_x += dy * dtx;
        sx_y += dx * dty;
        sy_y += dy * dty;
    }
    let trace = sxx + syy;
    let det = sxx * syy - sxy * sxy;
    if trace < MIN_SPREAD_UNIT2 || det < MIN_SPREAD_RATIO * trace * trace {
        return Err(CalibrationError::Collinear);
    }
    // S⁻¹ = [syy −sxy; −sxy sxx] / det
    let a = (syy * sx_x - sxy * sy_x) / det;
    let b = (sxx * sy_x - sxy * sx_x) / det;
    let d = (syy * sx_y - sxy * sy_y) / det;
    let e = (sxx * sy_y - sxy * sx_y) / det;
    let c = tx - a * mx - b * my;
    let f = ty - d * mx - e * my;
    let m = [a, b, c, d, e, f];
    if !m.iter().all(|v| v.is_finite()) || (a * e - b * d).abs() < MIN_MATRIX_DET {
        return Err(CalibrationError::DegenerateTargets);
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::Micros;
    use crate::vocab::{Contact, ContactId};
    use proptest::prelude::*;

    /// Tolerance for exact maps computed in f64.
    const EPS: f64 = 1e-12;
    /// Tolerance after a round trip through the f32 contact coordinates.
    const EPS_F32: f64 = 1e-6;

    fn t(cal: Calibration) -> DeviceTransform {
        DeviceTransform::new(&cal, None, Region::WHOLE, None, None).unwrap()
    }

    fn close(a: (f64, f64), b: (f64, f64), eps: f64) -> bool {
        (a.0 - b.0).abs() <= eps && (a.1 - b.1).abs() <= eps
    }

    fn rot(rotation: u16) -> Calibration {
        Calibration {
            rotation,
            ..Calibration::default()
        }
    }

    #[test]
    fn identity_maps_points_to_themselves() {
        let d = DeviceTransform::identity();
        for p in [(0.0, 0.0), (0.3, 0.7), (1.0, 1.0)] {
            assert!(close(d.map_point(p.0, p.1), p, EPS));
        }
        assert_eq!(t(Calibration::default()), d);
    }

    #[test]
    fn rotations_move_the_top_left_corner_clockwise() {
        // A = top-left (0,0) goes to top-right, bottom-right, bottom-left.
        let cases = [
            (0, (0.0, 0.0)),
            (90, (1.0, 0.0)),
            (180, (1.0, 1.0)),
            (270, (0.0, 1.0)),
        ];
        for (r, want) in cases {
            assert!(close(t(rot(r)).map_point(0.0, 0.0), want, EPS), "{r}");
        }
        // 90°: a point right of the top edge's centre goes down the right edge.
        assert!(close(t(rot(90)).map_point(0.75, 0.0), (1.0, 0.75), EPS));
        // The centre never moves.
        for r in [0, 90, 180, 270] {
            assert!(close(t(rot(r)).map_point(0.5, 0.5), (0.5, 0.5), EPS));
        }
    }

    #[test]
    fn rotations_equal_libinputs_documented_matrices() {
        // libinput "Static device configuration via udev": 90°, 180°, 270° clockwise.
        let docs = [
            (90, [0.0, -1.0, 1.0, 1.0, 0.0, 0.0]),
            (180, [-1.0, 0.0, 1.0, 0.0, -1.0, 1.0]),
            (270, [0.0, 1.0, 0.0, -1.0, 0.0, 1.0]),
        ];
        for (r, m) in docs {
            assert_eq!(t(rot(r)).matrix(), m, "{r}");
            let via_matrix = t(Calibration {
                matrix: Some(m),
                ..Calibration::default()
            });
            for p in [(0.2, 0.1), (0.9, 0.4)] {
                assert!(close(
                    via_matrix.map_point(p.0, p.1),
                    t(rot(r)).map_point(p.0, p.1),
                    EPS
                ));
            }
        }
    }

    #[test]
    fn four_quarter_turns_are_the_identity() {
        let q = rotation_matrix(90);
        let m = compose(&q, &compose(&q, &compose(&q, &q)));
        assert_eq!(m, IDENTITY);
    }

    #[test]
    fn flips_mirror_after_rotation() {
        let fx = t(Calibration {
            flip_x: true,
            ..Calibration::default()
        });
        assert!(close(fx.map_point(0.2, 0.3), (0.8, 0.3), EPS));
        let fy = t(Calibration {
            flip_y: true,
            ..Calibration::default()
        });
        assert!(close(fy.map_point(0.2, 0.3), (0.2, 0.7), EPS));
        let both = t(Calibration {
            flip_x: true,
            flip_y: true,
            ..Calibration::default()
        });
        assert!(close(
            both.map_point(0.2, 0.3),
            t(rot(180)).map_point(0.2, 0.3),
            EPS
        ));
        // Rotation first, then the flip: 90° takes (0.75, 0) to (1, 0.75), flip_x to (0, 0.75).
        let r_fx = t(Calibration {
            rotation: 90,
            flip_x: true,
            ..Calibration::default()
        });
        assert!(close(r_fx.map_point(0.75, 0.0), (0.0, 0.75), EPS));
    }

    #[test]
    fn config_matrix_overrides_udev_and_udev_applies_alone() {
        let shift = [1.0, 0.0, 0.1, 0.0, 1.0, 0.0];
        let scale = [0.5, 0.0, 0.0, 0.0, 0.5, 0.0];
        let cal = Calibration {
            matrix: Some(scale),
            ..Calibration::default()
        };
        let d = DeviceTransform::new(&cal, Some(shift), Region::WHOLE, None, None).unwrap();
        assert!(close(d.map_point(0.5, 0.5), (0.25, 0.25), EPS));
        let d = DeviceTransform::new(
            &Calibration::default(),
            Some(shift),
            Region::WHOLE,
            None,
            None,
        )
        .unwrap();
        assert!(close(d.map_point(0.5, 0.5), (0.6, 0.5), EPS));
        // The matrix comes before the rotation.
        let cal = Calibration {
            rotation: 90,
            ..Calibration::default()
        };
        let d = DeviceTransform::new(&cal, Some(shift), Region::WHOLE, None, None).unwrap();
        // shift: (0.5, 0.2) -> (0.6, 0.2); 90°: (1 - 0.2, 0.6).
        assert!(close(d.map_point(0.5, 0.2), (0.8, 0.6), EPS));
    }

    #[test]
    fn region_maps_and_clamps() {
        let region = Region {
            x: 0.5,
            y: 0.25,
            width: 0.5,
            height: 0.5,
        };
        let shift = Calibration {
            matrix: Some([1.0, 0.0, 0.2, 0.0, 1.0, -0.2]),
            ..Calibration::default()
        };
        let d = DeviceTransform::new(&shift, None, region, Some((596.7, 335.7)), None).unwrap();
        // (0.5, 0.5) -> (0.7, 0.3) -> (0.85, 0.4)
        assert!(close(d.map_point(0.5, 0.5), (0.85, 0.4), EPS));
        // (0.9, 0.1) -> (1.1, -0.1) clamps to (1, 0) -> the region's top-right corner.
        assert!(close(d.map_point(0.9, 0.1), (1.0, 0.25), EPS));
        assert_eq!(d.size_mm(), Some((596.7, 335.7)));
        // A NaN from a broken decoder still lands inside the region.
        let (x, y) = d.map_point(f64::NAN, 0.5);
        assert!((0.5..=1.0).contains(&x) && (0.25..=0.75).contains(&y));
    }

    #[test]
    fn apply_maps_contacts_and_flags_palms() {
        let region = Region {
            x: 0.0,
            y: 0.5,
            width: 0.5,
            height: 0.5,
        };
        let d = DeviceTransform::new(&rot(180), None, region, None, Some(30.0)).unwrap();
        let mut f = TouchFrame::new(Micros(5));
        let finger = Contact {
            id: ContactId(1),
            x: 0.25,
            y: 0.5,
            major_mm: Some(9.0),
            flags: ContactFlags::DOWN,
            ..Contact::default()
        };
        let palm = Contact {
            id: ContactId(2),
            x: 1.0,
            y: 1.0,
            major_mm: Some(42.0),
            ..Contact::default()
        };
        let unknown = Contact {
            id: ContactId(3),
            x: 0.0,
            y: 0.0,
            ..Contact::default()
        };
        f.push(finger).unwrap();
        f.push(palm).unwrap();
        f.push(unknown).unwrap();
        d.apply(&mut f);
        let c = f.contacts();
        assert!(close(
            (c[0].x.into(), c[0].y.into()),
            (0.375, 0.75),
            EPS_F32
        ));
        assert_eq!(c[0].flags, ContactFlags::DOWN);
        assert!(close((c[1].x.into(), c[1].y.into()), (0.0, 0.5), EPS_F32));
        assert!(c[1].flags.contains(ContactFlags::PALM));
        assert!(close((c[2].x.into(), c[2].y.into()), (0.5, 1.0), EPS_F32));
        assert!(!c[2].flags.contains(ContactFlags::PALM));
        assert_eq!(f.t, Micros(5));
    }

    #[test]
    fn validation_names_the_field() {
        let e = rot(45).validate().unwrap_err();
        assert_eq!(e, CalibrationError::Rotation { rotation: 45 });
        assert!(e.to_string().contains("calibration.rotation"));
        let e = Calibration {
            matrix: Some([1.0, 0.0, f64::NAN, 0.0, 1.0, 0.0]),
            ..Calibration::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("calibration.matrix[2]"), "{e}");
        let bad_region = Region {
            x: 0.5,
            y: 0.0,
            width: 0.75,
            height: 1.0,
        };
        let e = DeviceTransform::new(&Calibration::default(), None, bad_region, None, None)
            .unwrap_err();
        assert!(e.to_string().starts_with("region.width"), "{e}");
        let e = DeviceTransform::new(
            &Calibration::default(),
            None,
            Region::WHOLE,
            Some((0.0, 10.0)),
            None,
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("size_mm.width"), "{e}");
        let e = DeviceTransform::new(
            &Calibration::default(),
            None,
            Region::WHOLE,
            None,
            Some(-1.0),
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("palm_max_mm"), "{e}");
    }

    #[test]
    fn calibration_deserialises_with_defaults() {
        let c: Calibration = ron::from_str("(rotation: 90)").unwrap();
        assert_eq!(c, rot(90));
        let c: Calibration =
            ron::from_str("(flip_y: true, matrix: Some((1.0, 0.0, 0.0, 0.0, 1.0, 0.0)))").unwrap();
        assert!(c.flip_y && c.matrix == Some(IDENTITY));
        assert!(ron::from_str::<Calibration>("(rotate: 90)").is_err());
    }

    /// A deterministic noise sequence in `[-amp, amp]` (xorshift).
    fn noise(seed: &mut u64, amp: f64) -> f64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0) * amp
    }

    #[test]
    fn solve_recovers_a_known_affine_with_noise() {
        // 10° rotation, 0.9/1.1 scale, shift; 1e-4 noise on the touched points.
        let (s, c) = 10f64.to_radians().sin_cos();
        let truth = [0.9 * c, -0.9 * s, 0.05, 1.1 * s, 1.1 * c, -0.03];
        let mut seed = 0x5eed_u64;
        let touched: Vec<(f64, f64)> =
            [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9), (0.5, 0.5)].to_vec();
        let targets: Vec<(f64, f64)> = touched
            .iter()
            .map(|&(x, y)| {
                let (tx, ty) = apply_matrix(&truth, x, y);
                (tx + noise(&mut seed, 1e-4), ty + noise(&mut seed, 1e-4))
            })
            .collect();
        let m = solve_matrix(&targets, &touched).unwrap();
        for (got, want) in m.iter().zip(truth) {
            assert!((got - want).abs() < 1e-3, "{m:?} vs {truth:?}");
        }
        // Exact data gives the exact matrix.
        let exact: Vec<_> = touched
            .iter()
            .map(|&(x, y)| apply_matrix(&truth, x, y))
            .collect();
        let m = solve_matrix(&exact, &touched).unwrap();
        for (got, want) in m.iter().zip(truth) {
            assert!((got - want).abs() < 1e-12);
        }
    }

    #[test]
    fn solve_rejects_degenerate_input() {
        let three = [(0.1, 0.1), (0.9, 0.1), (0.5, 0.9)];
        assert_eq!(
            solve_matrix(&three[..2], &three[..2]),
            Err(CalibrationError::TooFewPoints { found: 2 })
        );
        assert_eq!(
            solve_matrix(&three, &three[..2]),
            Err(CalibrationError::PointCountMismatch {
                targets: 3,
                touched: 2
            })
        );
        let line = [(0.1, 0.1), (0.5, 0.5), (0.9, 0.9), (0.3, 0.3)];
        assert_eq!(solve_matrix(&line, &line), Err(CalibrationError::Collinear));
        let same = [(0.5, 0.5); 4];
        assert_eq!(
            solve_matrix(
                &three.iter().chain(&three[..1]).copied().collect::<Vec<_>>(),
                &same
            ),
            Err(CalibrationError::Collinear)
        );
        let mut bad = three;
        bad[1].0 = f64::INFINITY;
        assert_eq!(
            solve_matrix(&three, &bad),
            Err(CalibrationError::PointNotFinite { index: 1 })
        );
        let squashed = [(0.5, 0.1), (0.5, 0.1), (0.5, 0.9)];
        assert_eq!(
            solve_matrix(&squashed, &three),
            Err(CalibrationError::DegenerateTargets)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]

        /// Any well-conditioned affine map is recovered from four corner touches.
        #[test]
        fn solve_inverts_random_affines(
            angle in 0.0f64..360.0,
            sx in 0.5f64..1.5,
            sy in 0.5f64..1.5,
            cx in -0.3f64..0.3,
            cy in -0.3f64..0.3,
            flip in any::<bool>(),
        ) {
            let (s, c) = angle.to_radians().sin_cos();
            let fx = if flip { -1.0 } else { 1.0 };
            let truth = [fx * sx * c, -sy * s, cx, fx * sx * s, sy * c, cy];
            let touched = [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9)];
            let targets: Vec<_> = touched.iter().map(|&(x, y)| apply_matrix(&truth, x, y)).collect();
            let m = solve_matrix(&targets, &touched).unwrap();
            for (got, want) in m.iter().zip(truth) {
                prop_assert!((got - want).abs() < 1e-9);
            }
        }

        /// Mapped points always land in the region.
        #[test]
        fn mapped_points_stay_in_region(
            x in -1.0f64..2.0, y in -1.0f64..2.0,
            rotation in prop::sample::select(vec![0u16, 90, 180, 270]),
            flip_x in any::<bool>(), flip_y in any::<bool>(),
        ) {
            let region = Region { x: 0.25, y: 0.1, width: 0.5, height: 0.3 };
            let cal = Calibration { rotation, flip_x, flip_y, matrix: Some([1.2, 0.1, -0.1, 0.0, 0.9, 0.05]) };
            let d = DeviceTransform::new(&cal, None, region, None, None).unwrap();
            let (mx, my) = d.map_point(x, y);
            prop_assert!((0.25 - EPS..=0.75 + EPS).contains(&mx));
            prop_assert!((0.1 - EPS..=0.4 + EPS).contains(&my));
        }
    }
}
