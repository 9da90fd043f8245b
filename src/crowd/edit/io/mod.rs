//! Reading and writing track sets. Every reader parses text it is given (the caller
//! reads the file, capped) and names the line and what is wrong; none panics.
//!
//! | format | file | what |
//! |---|---|---|
//! | [`Format::Eth`] | `eth.rs` | the public pedestrian datasets (ETH/UCY as redistributed by trajectory-prediction projects): `frame id x y` per line, whitespace-separated, metres |

mod eth;

pub use eth::{read_eth, write_eth, EthOptions};

use thiserror::Error;

/// The formats a track set is read from and written to.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Format {
    /// `frame id x y` per line (ETH/UCY raw files).
    Eth,
}

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
