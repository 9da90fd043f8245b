//! The error every track reader returns.

use thiserror::Error;

/// A track file that cannot be read: the line (1-based; 0 when the problem is the
/// file as a whole) and what is wrong there.
#[derive(Debug, Error, PartialEq)]
#[error("line {line}: {what}")]
pub struct ReadError {
    /// 1-based line number, 0 for the whole file.
    pub line: usize,
    /// What is wrong, for a person.
    pub what: String,
}

impl ReadError {
    pub(crate) fn at(line: usize, what: impl Into<String>) -> ReadError {
        ReadError {
            line,
            what: what.into(),
        }
    }
}
