//! What can be wrong with a scene: a problem per field, located in the file, and the
//! errors of loading one.

use super::file::SCENE_VERSION;
use super::limits::MAX_SPEED_FACTOR;
use crate::located::{format_issues, Located};
use std::fmt;
use std::path::PathBuf;

/// What is wrong with one field of a scene.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// The text does not parse as a scene (syntax, unknown or missing field, type).
    #[error("{message}")]
    Syntax {
        /// The parser's message.
        message: String,
    },
    /// Unsupported format version.
    #[error("version {found} is not supported (this build reads version {SCENE_VERSION})")]
    UnsupportedVersion {
        /// The version in the file.
        found: u32,
    },
    /// A NaN or infinite number.
    #[error("numbers must be finite")]
    NonFinite,
    /// Bounds with `min >= max` on an axis.
    #[error("bounds must have min < max on both axes")]
    EmptyBounds,
    /// Too few polygon vertices.
    #[error("a polygon needs at least 3 vertices, got {count}")]
    TooFewVertices {
        /// Vertices given.
        count: usize,
    },
    /// More than a limit of something.
    #[error("at most {max} {what}, got {count}")]
    TooMany {
        /// What is counted.
        what: &'static str,
        /// How many there are.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// A polygon with (near) zero area.
    #[error("polygon has zero area ({area_m2:e} m²); its vertices are collinear or repeated")]
    ZeroArea {
        /// Its area (m²).
        area_m2: f64,
    },
    /// A polygon that is not convex.
    #[error("polygon is not convex at vertex {vertex} (split a concave shape into convex parts)")]
    NonConvex {
        /// Index of the offending vertex (repeated, or outside an edge).
        vertex: usize,
    },
    /// A circle radius ≤ 0.
    #[error("radius must be positive, got {radius_m} m")]
    NonPositiveRadius {
        /// The radius (m).
        radius_m: f64,
    },
    /// A speed or speed factor ≤ 0.
    #[error("speed must be positive, got {value}")]
    NonPositiveSpeed {
        /// The value.
        value: f64,
    },
    /// A speed factor above [`MAX_SPEED_FACTOR`].
    #[error("speed factor must be at most {MAX_SPEED_FACTOR}, got {value}")]
    SpeedTooHigh {
        /// The value.
        value: f64,
    },
    /// An obstacle, patch or checkpoint with no parts.
    #[error("needs at least one part")]
    NoParts,
    /// Something not inside the world bounds.
    #[error("lies outside the world bounds")]
    OutsideBounds,
    /// Parts of two different obstacles overlap.
    #[error("overlaps {other} (parts of one obstacle may overlap; separate obstacles may not)")]
    Overlap {
        /// The other obstacle, `obstacles[i] "name"`.
        other: String,
    },
    /// Two obstacles closer than an agent diameter.
    #[error("is {gap_m:.3} m from {other}, less than one agent diameter ({min_gap_m:.3} m)")]
    GapTooSmall {
        /// The other obstacle.
        other: String,
        /// The gap (m).
        gap_m: f64,
        /// The smallest allowed gap (m).
        min_gap_m: f64,
    },
    /// A single-step motion without its motion length.
    #[error(
        "{motion} is a single-step motion: give motion_length_m, the length of its trajectory"
    )]
    MissingMotionLength {
        /// The motion.
        motion: &'static str,
    },
    /// A motion length on a cyclic motion.
    #[error("motion_length_m applies only to jump, climb_up and climb_down, not {motion}")]
    MotionLengthNotApplicable {
        /// The motion.
        motion: &'static str,
    },
    /// A motion length ≤ 0.
    #[error("motion length must be positive, got {value} m")]
    NonPositiveMotionLength {
        /// The value (m).
        value: f64,
    },
    /// A single-step patch longer than its motion.
    #[error("patch is {width_m:.3} m across at its narrowest, longer than its motion ({motion_length_m:.3} m): the motion would play more than once")]
    PatchLongerThanMotion {
        /// Smallest width of the part (m).
        width_m: f64,
        /// The motion length (m).
        motion_length_m: f64,
    },
    /// A path that does not go anywhere.
    #[error("a path needs at least 2 waypoints and a positive length")]
    PathTooShort,
    /// A checkpoint naming no formation.
    #[error("formation name is empty")]
    EmptyFormation,
    /// A checkpoint naming a formation the config does not define.
    #[error("no formation is called `{name}`; the config defines {known}")]
    UnknownFormation {
        /// The name.
        name: String,
        /// The names there are, comma-separated.
        known: String,
    },
}

/// One problem, located in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneIssue {
    /// Dotted field path (`obstacles[1].parts[0].vertices_m`), empty when unknown.
    pub field: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub column: usize,
    /// What is wrong.
    pub problem: Problem,
}

/// Why a scene could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read scene: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_SCENE_BYTES`](super::MAX_SCENE_BYTES).
    #[error("{path}: scene is {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// The file is not a regular file, grew past the cap, is not UTF-8 text, or its
    /// read was stopped.
    #[error("cannot read scene: {0}")]
    Unreadable(crate::located::ReadError),
    /// The scene is invalid; every problem found is listed, one per line, as
    /// `file:line:col: field: what`.
    #[error("{}", format_issues(.path, .issues))]
    Invalid {
        /// File (or `<text>`).
        path: PathBuf,
        /// Problems, in file order.
        issues: Vec<SceneIssue>,
    },
}

impl Located for SceneIssue {
    fn line(&self) -> usize {
        self.line
    }
    fn column(&self) -> usize {
        self.column
    }
    fn fmt_what(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl fmt::Display for SceneIssue {
    /// `field: what` (the place is added by [`SceneError`]).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}", self.problem)
        } else {
            write!(f, "{}: {}", self.field, self.problem)
        }
    }
}
