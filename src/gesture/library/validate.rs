//! The invariants of a library, checked item by item by the file reader (which adds
//! the byte offset) and as a whole by [`validate`] for a library built in memory.
//!
//! The class table: at most [`MAX_CLASSES`] names, each a valid class name
//! ([`check_class_name`]) given once. A motion: a class in the table; a duration
//! in `(0, MAX_MOTION_DURATION_S]`; a mean of [`TRAJ_DIM`] values; at most
//! [`MAX_COMPONENTS`] eigenvectors of [`TRAJ_DIM`] values, orthonormal within
//! [`ORTHONORMAL_TOLERANCE`]; 1 to [`MAX_GMM_COMPONENTS`] Gaussians over as many
//! dimensions as eigenvectors, with weights in `[0, 1]` summing to 1 within
//! [`WEIGHT_SUM_TOLERANCE`] and symmetric positive definite covariances. A gesture:
//! a class that has a motion, a motion index in range of the same class, 1 to
//! [`MAX_GESTURE_FINGERS`] fingers, every point finite and inside
//! `[-POINT_SLACK, 1 + POINT_SLACK]²`, an origin of at most [`MAX_ORIGIN_BYTES`], a
//! participant and a device of at most [`MAX_PARTICIPANT_BYTES`] and
//! [`MAX_DEVICE_BYTES`]. Every number finite. The whole, under
//! [`LoadPolicy::Complete`]: at least one class, one motion and one gesture.

use super::class::{check_class_name, ClassId, MAX_CLASSES};
use super::error::{Item, LibraryError, Problem};
use super::model::{
    Library, LibraryGesture, MotionFeatures, MAX_COMPONENTS, MAX_DEVICE_BYTES,
    MAX_PARTICIPANT_BYTES, TRAJ_DIM,
};
use crate::gesture::track::MAX_GESTURE_FINGERS;

/// Largest `|e_i · e_j − δ_ij|` accepted between two eigenvectors of a motion.
///
/// Eigenvectors from an SVD in f64 are orthonormal to about 1e-14; blending
/// re-orthonormalises. 1e-6 accepts either and refuses a basis that was not.
pub const ORTHONORMAL_TOLERANCE: f64 = 1e-6;

/// Largest `|Σ w − 1|` accepted for a mixture's weights.
pub const WEIGHT_SUM_TOLERANCE: f64 = 1e-6;

/// Largest `|c_ij − c_ji|`, relative to `max(1, |c_ij|)`, accepted in a covariance.
pub const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// How far outside the unit square a resampled point may lie: a Hermite spline
/// through normalised samples overshoots a little between them.
pub const POINT_SLACK: f64 = 0.25;

/// Most Gaussians in one motion's mixture (two by default; more when chosen by
/// likelihood).
pub const MAX_GMM_COMPONENTS: usize = 32;

/// Longest crowd motion, s.
pub const MAX_MOTION_DURATION_S: f64 = 600.0;

/// Longest origin text, bytes of UTF-8.
pub const MAX_ORIGIN_BYTES: usize = 1024;

/// Whether a library must be usable for recognition.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum LoadPolicy {
    /// At least one class, one motion and one gesture: what the daemon loads.
    #[default]
    Complete,
    /// Anything consistent, even no class: a library being built (`library new`,
    /// `add`, `import-motion`, `remove`).
    Partial,
}

/// The name used in errors of a library checked in memory.
pub const IN_MEMORY: &str = "(in memory)";

/// Checks a whole library in memory under [`LoadPolicy::Complete`].
///
/// # Errors
/// The first problem found, as a [`LibraryError`] naming the item (no offset).
pub fn validate(lib: &Library) -> Result<(), LibraryError> {
    validate_with(lib, LoadPolicy::Complete)
}

/// Checks a whole library in memory under `policy`.
///
/// # Errors
/// The first problem found, as a [`LibraryError`] naming the item (no offset).
pub fn validate_with(lib: &Library, policy: LoadPolicy) -> Result<(), LibraryError> {
    let fail = |(item, problem)| LibraryError {
        file: IN_MEMORY.to_string(),
        offset: None,
        item,
        problem,
    };
    count("class", lib.classes.len(), 0, MAX_CLASSES)
        .map_err(|p| (Item::Library, p))
        .map_err(fail)?;
    for (i, name) in lib.classes.iter().enumerate() {
        check_class(name, &lib.classes[..i])
            .map_err(|p| (Item::Class(i), p))
            .map_err(fail)?;
    }
    for (i, m) in lib.motions.iter().enumerate() {
        check_motion_class(m.class, lib.classes.len())
            .map_err(|p| (Item::Motion(i), p))
            .map_err(fail)?;
        check_motion(i, m).map_err(fail)?;
    }
    for (i, g) in lib.gestures.iter().enumerate() {
        check_gesture(i, g, &lib.classes, &lib.motions).map_err(fail)?;
    }
    check_whole(lib, policy).map_err(fail)
}

/// A value that must be finite.
pub(crate) fn finite(field: impl FnOnce() -> String, value: f64) -> Result<(), Problem> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Problem::NotFinite {
            field: field(),
            value,
        })
    }
}

pub(crate) fn count(what: &'static str, n: usize, min: usize, max: usize) -> Result<(), Problem> {
    if (min..=max).contains(&n) {
        Ok(())
    } else {
        Err(Problem::BadCount {
            what,
            count: n as u64,
            min: min as u64,
            max: max as u64,
        })
    }
}

fn dims(what: &'static str, found: usize, expected: usize) -> Result<(), Problem> {
    if found == expected {
        Ok(())
    } else {
        Err(Problem::DimensionMismatch {
            what,
            found,
            expected,
        })
    }
}

/// Checks a class name, and that none of the `earlier` classes has it.
pub(crate) fn check_class(name: &str, earlier: &[String]) -> Result<(), Problem> {
    check_class_name(name).map_err(|e| Problem::BadClassName(Box::new(e)))?;
    match earlier.iter().position(|e| e == name) {
        Some(first) => Err(Problem::DuplicateClass {
            name: name.to_string(),
            first,
        }),
        None => Ok(()),
    }
}

/// Checks that a motion's class is in a table of `classes`.
pub(crate) fn check_motion_class(class: ClassId, classes: usize) -> Result<(), Problem> {
    if class.index() < classes {
        Ok(())
    } else {
        Err(Problem::BadClass {
            index: u64::from(class.0),
            count: classes,
        })
    }
}

/// Checks one motion (index `i`), but for its class (see [`check_motion_class`]).
pub(crate) fn check_motion(i: usize, m: &MotionFeatures) -> Result<(), (Item, Problem)> {
    let at = |p| (Item::Motion(i), p);
    finite(|| "duration_s".into(), m.duration_s).map_err(at)?;
    if !(m.duration_s > 0.0 && m.duration_s <= MAX_MOTION_DURATION_S) {
        return Err(at(Problem::OutOfRange {
            field: "duration_s".into(),
            value: m.duration_s,
            range: "(0, 600] s",
        }));
    }
    dims("mean", m.mean.len(), TRAJ_DIM).map_err(at)?;
    for (k, &v) in m.mean.iter().enumerate() {
        finite(|| format!("mean[{k}]"), v).map_err(at)?;
    }
    count("eigenvector", m.basis.len(), 0, MAX_COMPONENTS).map_err(at)?;
    for (a, e) in m.basis.iter().enumerate() {
        let at = |p| {
            (
                Item::Basis {
                    motion: i,
                    vector: a,
                },
                p,
            )
        };
        dims("eigenvector", e.len(), TRAJ_DIM).map_err(at)?;
        for (k, &v) in e.iter().enumerate() {
            finite(|| format!("value {k}"), v).map_err(at)?;
        }
    }
    check_orthonormal(&m.basis).map_err(at)?;
    let d = m.basis.len();
    count("gmm component", m.gmm.len(), 1, MAX_GMM_COMPONENTS).map_err(at)?;
    let mut sum = 0.0;
    for (c, g) in m.gmm.iter().enumerate() {
        let at = |p| {
            (
                Item::Component {
                    motion: i,
                    component: c,
                },
                p,
            )
        };
        finite(|| "weight".into(), g.weight).map_err(at)?;
        if !(0.0..=1.0).contains(&g.weight) {
            return Err(at(Problem::OutOfRange {
                field: "weight".into(),
                value: g.weight,
                range: "[0, 1]",
            }));
        }
        sum += g.weight;
        dims("gmm mean", g.mean.len(), d).map_err(at)?;
        for (k, &v) in g.mean.iter().enumerate() {
            finite(|| format!("mean[{k}]"), v).map_err(at)?;
        }
        dims("covariance", g.cov.len(), d * d).map_err(at)?;
        for (k, &v) in g.cov.iter().enumerate() {
            finite(|| format!("cov[{}][{}]", k / d.max(1), k % d.max(1)), v).map_err(at)?;
        }
        check_covariance(&g.cov, d).map_err(at)?;
    }
    if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
        return Err(at(Problem::WeightsDoNotSum {
            sum,
            tolerance: WEIGHT_SUM_TOLERANCE,
        }));
    }
    Ok(())
}

fn check_orthonormal(basis: &[Vec<f64>]) -> Result<(), Problem> {
    for (i, a) in basis.iter().enumerate() {
        for (j, b) in basis.iter().enumerate().take(i + 1) {
            let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            let expected = if i == j { 1.0 } else { 0.0 };
            // A NaN dot product (of huge finite values) is refused too.
            let off = (dot - expected).abs();
            if off.is_nan() || off > ORTHONORMAL_TOLERANCE {
                return Err(Problem::NotOrthonormal {
                    i: j,
                    j: i,
                    dot,
                    expected,
                    tolerance: ORTHONORMAL_TOLERANCE,
                });
            }
        }
    }
    Ok(())
}

fn check_covariance(cov: &[f64], d: usize) -> Result<(), Problem> {
    for i in 0..d {
        for j in 0..i {
            let (a, b) = (cov[i * d + j], cov[j * d + i]);
            if (a - b).abs() > SYMMETRY_TOLERANCE * a.abs().max(1.0) {
                return Err(Problem::NotSymmetric { i, j, a, b });
            }
        }
    }
    if d == 0 {
        return Ok(());
    }
    let m = nalgebra::DMatrix::from_row_slice(d, d, cov);
    match nalgebra::Cholesky::new(m) {
        Some(ch) if ch.l_dirty().iter().all(|v| v.is_finite()) => Ok(()),
        _ => Err(Problem::NotPositiveDefinite),
    }
}

/// Checks one gesture's class and counts against the classes and motions (before
/// its points).
pub(crate) fn check_gesture_head(
    class: ClassId,
    motion: u64,
    fingers: usize,
    classes: &[String],
    motions: &[MotionFeatures],
) -> Result<(), Problem> {
    check_motion_class(class, classes.len())?;
    let name = |c: ClassId| classes[c.index()].clone();
    let m = usize::try_from(motion).ok().and_then(|i| motions.get(i));
    if m.is_none_or(|m| m.class != class) && !motions.iter().any(|m| m.class == class) {
        return Err(Problem::ClassWithoutMotions { class: name(class) });
    }
    let Some(m) = m else {
        return Err(Problem::BadMotionIndex {
            index: motion,
            count: motions.len(),
        });
    };
    if m.class != class {
        return Err(Problem::ClassMismatch {
            gesture: name(class).into(),
            motion: motion as usize,
            motion_class: classes
                .get(m.class.index())
                .map_or("?", String::as_str)
                .into(),
        });
    }
    count("finger", fingers, 1, MAX_GESTURE_FINGERS)
}

/// Checks one coordinate of a gesture's point.
pub(crate) fn check_coordinate(axis: &'static str, v: f64) -> Result<(), Problem> {
    finite(|| axis.to_string(), v)?;
    if !(-POINT_SLACK..=1.0 + POINT_SLACK).contains(&v) {
        return Err(Problem::OutOfRange {
            field: axis.to_string(),
            value: v,
            range: "[-0.25, 1.25] (normalised gesture)",
        });
    }
    Ok(())
}

/// Checks one gesture (index `i`).
pub(crate) fn check_gesture(
    i: usize,
    g: &LibraryGesture,
    classes: &[String],
    motions: &[MotionFeatures],
) -> Result<(), (Item, Problem)> {
    let at = |p| (Item::Gesture(i), p);
    check_gesture_head(
        g.class,
        u64::from(g.motion),
        g.gesture.fingers.len(),
        classes,
        motions,
    )
    .map_err(at)?;
    count("origin byte", g.origin.len(), 0, MAX_ORIGIN_BYTES).map_err(at)?;
    count(
        "participant byte",
        g.participant.len(),
        0,
        MAX_PARTICIPANT_BYTES,
    )
    .map_err(at)?;
    count("device byte", g.device.len(), 0, MAX_DEVICE_BYTES).map_err(at)?;
    for (f, finger) in g.gesture.fingers.iter().enumerate() {
        for (s, p) in finger.iter().enumerate() {
            let at = |pr| {
                (
                    Item::Sample {
                        gesture: i,
                        finger: f,
                        sample: s,
                    },
                    pr,
                )
            };
            check_coordinate("x", p.x).map_err(at)?;
            check_coordinate("y", p.y).map_err(at)?;
        }
    }
    Ok(())
}

/// Checks the library as a whole: under [`LoadPolicy::Complete`], at least one
/// class, one motion and one gesture.
pub(crate) fn check_whole(lib: &Library, policy: LoadPolicy) -> Result<(), (Item, Problem)> {
    if policy == LoadPolicy::Partial {
        return Ok(());
    }
    if lib.classes.is_empty() {
        return Err((Item::Library, Problem::NoClasses));
    }
    if lib.motions.is_empty() || lib.gestures.is_empty() {
        return Err((
            Item::Library,
            Problem::Empty {
                motions: lib.motions.len(),
                gestures: lib.gestures.len(),
            },
        ));
    }
    Ok(())
}
