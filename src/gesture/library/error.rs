//! What is wrong with a library file or a library in memory: one error type for the
//! library's boundary, naming the file, the byte offset (when read from bytes), the
//! item (`gesture 17: finger 3: sample 12`) and the problem (`x is NaN`).

use super::class::ClassNameError;
use crate::located::Escaped;
use std::fmt;

/// The part of a library a problem is in.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    /// The file header (magic, version, counts).
    Header,
    /// A class of the class table.
    Class(usize),
    /// A crowd motion's record.
    Motion(usize),
    /// One eigenvector of a motion's basis.
    Basis {
        /// Index of the motion.
        motion: usize,
        /// Index of the eigenvector.
        vector: usize,
    },
    /// One Gaussian of a motion's mixture.
    Component {
        /// Index of the motion.
        motion: usize,
        /// Index of the component.
        component: usize,
    },
    /// A gesture's record.
    Gesture(usize),
    /// One sample of one finger of a gesture.
    Sample {
        /// Index of the gesture.
        gesture: usize,
        /// Index of the finger.
        finger: usize,
        /// Index of the sample (0..T_H).
        sample: usize,
    },
    /// The trailing checksum.
    Checksum,
    /// The library as a whole.
    Library,
}

impl fmt::Display for Item {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Item::Header => f.write_str("header"),
            Item::Class(c) => write!(f, "class {c}"),
            Item::Motion(m) => write!(f, "motion {m}"),
            Item::Basis { motion, vector } => write!(f, "motion {motion}: eigenvector {vector}"),
            Item::Component { motion, component } => {
                write!(f, "motion {motion}: gmm component {component}")
            }
            Item::Gesture(g) => write!(f, "gesture {g}"),
            Item::Sample {
                gesture,
                finger,
                sample,
            } => write!(f, "gesture {gesture}: finger {finger}: sample {sample}"),
            Item::Checksum => f.write_str("checksum"),
            Item::Library => f.write_str("library"),
        }
    }
}

/// What is wrong.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// The file does not start with `CTGL`.
    #[error("not a gesture library: starts with {found:02x?}, expected the magic `CTGL`")]
    BadMagic {
        /// The first bytes found (up to 4).
        found: Vec<u8>,
    },
    /// A format version this reader does not read.
    #[error("format version {found}; this reader reads versions 1 to {supported} (a newer crowdtouch wrote it, or it is damaged)")]
    UnsupportedVersion {
        /// The file's version.
        found: u32,
        /// The version this build writes, the newest it reads.
        supported: u32,
    },
    /// A gesture's scale (eq. 2's extent, mm) is negative.
    #[error("scale_mm is {0}, negative")]
    NegativeScale(f64),
    /// The file ends inside a record, or a count promises more than the file holds.
    #[error("{what}: needs {needed} bytes, the file has {remaining} left")]
    Truncated {
        /// What was being read.
        what: &'static str,
        /// Bytes it needs.
        needed: u64,
        /// Bytes left in the file from here.
        remaining: u64,
    },
    /// Bytes after the checksum.
    #[error("{count} trailing bytes after the checksum")]
    TrailingBytes {
        /// How many.
        count: usize,
    },
    /// The checksum does not match the content.
    #[error("CRC-32 stored {stored:#010x}, content gives {computed:#010x}: the file is corrupt")]
    ChecksumMismatch {
        /// The stored value.
        stored: u32,
        /// The value computed over the content.
        computed: u32,
    },
    /// A reserved byte that must be zero is not.
    #[error("reserved byte is {0}, must be 0")]
    Reserved(u8),
    /// A value is NaN or infinite.
    #[error("{field} is {value}")]
    NotFinite {
        /// The field (`x`, `duration_s`, `mean[3]`, …).
        field: String,
        /// The value (NaN or ±inf).
        value: f64,
    },
    /// A value outside its range.
    #[error("{field} = {value} is outside {range}")]
    OutOfRange {
        /// The field.
        field: String,
        /// The value.
        value: f64,
        /// The allowed range, written out (`(0, 600] s`).
        range: &'static str,
    },
    /// A class number beyond the class table.
    #[error("class index {index} is out of range ({count} classes)")]
    BadClass {
        /// The index.
        index: u64,
        /// How many classes the library has.
        count: usize,
    },
    /// A class name that is not one.
    #[error("{0}")]
    BadClassName(Box<ClassNameError>),
    /// A class name given twice.
    #[error("class `{}` is named twice (also class {first})", Escaped(.name))]
    DuplicateClass {
        /// The name.
        name: String,
        /// The class that has it first.
        first: usize,
    },
    /// A library without classes.
    #[error("the library has no class")]
    NoClasses,
    /// A gesture of a class that has no crowd motion to play.
    #[error("class `{}` has gestures but no motions (import one with `library import-motion --class {}`)", Escaped(.class), Escaped(.class))]
    ClassWithoutMotions {
        /// The class's name.
        class: String,
    },
    /// A gesture names a motion that does not exist.
    #[error("motion index {index} is out of range ({count} motions)")]
    BadMotionIndex {
        /// The index.
        index: u64,
        /// How many motions the library has.
        count: usize,
    },
    /// A gesture's class differs from its motion's.
    #[error("class `{}` differs from its motion {motion}'s class `{}`", Escaped(.gesture), Escaped(.motion_class))]
    ClassMismatch {
        /// The gesture's class name.
        gesture: Box<str>,
        /// The motion's index.
        motion: usize,
        /// The motion's class name.
        motion_class: Box<str>,
    },
    /// A count outside its range (fingers, eigenvectors, components, origin bytes).
    #[error("{what} count {count} is outside {min}..={max}")]
    BadCount {
        /// What is counted.
        what: &'static str,
        /// The count.
        count: u64,
        /// Least allowed.
        min: u64,
        /// Most allowed.
        max: u64,
    },
    /// A vector or matrix of the wrong length.
    #[error("{what} has {found} values, expected {expected}")]
    DimensionMismatch {
        /// Which vector.
        what: &'static str,
        /// Its length.
        found: usize,
        /// The length it must have.
        expected: usize,
    },
    /// The eigenvectors are not orthonormal.
    #[error("eigenvectors {i} and {j}: dot product {dot:.3e}, expected {expected} (tolerance {tolerance:e})")]
    NotOrthonormal {
        /// First vector.
        i: usize,
        /// Second vector.
        j: usize,
        /// Their dot product.
        dot: f64,
        /// 1 when `i == j`, else 0.
        expected: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// Mixture weights that do not sum to 1.
    #[error("gmm weights sum to {sum}, expected 1 (tolerance {tolerance:e})")]
    WeightsDoNotSum {
        /// Their sum.
        sum: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// A covariance that is not symmetric.
    #[error("covariance is not symmetric: [{i}][{j}] = {a}, [{j}][{i}] = {b}")]
    NotSymmetric {
        /// Row.
        i: usize,
        /// Column.
        j: usize,
        /// `cov[i][j]`.
        a: f64,
        /// `cov[j][i]`.
        b: f64,
    },
    /// A covariance that is not positive definite (its Cholesky factorisation fails).
    #[error("covariance is not positive definite")]
    NotPositiveDefinite,
    /// The origin text is not UTF-8.
    #[error("{what} is not UTF-8 (at its byte {at})")]
    NotUtf8 {
        /// Which text (`origin`, `class name`, `participant`, `device`).
        what: &'static str,
        /// The byte of the text where it stops being UTF-8.
        at: usize,
    },
    /// A library with no motion or no gesture.
    #[error("the library has nothing to recognise: {motions} motions, {gestures} gestures (it needs at least one of each)")]
    Empty {
        /// Motions.
        motions: usize,
        /// Gestures.
        gestures: usize,
    },
}

/// A library that cannot be read or is not consistent.
///
/// Displays as `library.ctgl: offset 1234: gesture 17: finger 3: sample 0: x is NaN`
/// (no offset for a library checked in memory).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{}: {item}: {problem}", crate::located::Escaped(.file), match .offset { Some(o) => format!(": offset {o}"), None => String::new() })]
pub struct LibraryError {
    /// The file's name, as given to the reader (`(in memory)` for [`validate`](fn@super::validate));
    /// the message escapes its control characters. The problems quote no byte of
    /// the file but as hex (the magic) and numbers.
    pub file: String,
    /// The byte offset of the value or record at fault, when read from bytes.
    pub offset: Option<usize>,
    /// Where in the library.
    pub item: Item,
    /// What is wrong.
    pub problem: Problem,
}
