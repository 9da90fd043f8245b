//! The track formats by name, extension or first line, and the reader or writer
//! for each.

use super::csv::{read_csv, write_csv};
use super::error::ReadError;
use super::eth::{read_eth, write_eth, EthOptions};
use super::jsonl::{read_jsonl, write_jsonl};
use crate::crowd::edit::tracks::TrackSet;

/// The formats a track set is read from and written to.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Format {
    /// Ours: a header line, then one sample per line (`jsonl.rs`).
    Jsonl,
    /// `t,id,x,y` per line, an optional header (`csv.rs`).
    Csv,
    /// `frame id x y` per line (ETH/UCY raw files).
    Eth,
}

/// What a reader needs beyond the text.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct ReadOptions {
    /// Frames of the ETH/UCY format.
    pub eth: EthOptions,
    /// The frame step of a CSV file (seconds); `None` takes the median of the
    /// people's consecutive time differences.
    pub csv_step_s: Option<f64>,
}

/// The format of a file, from its extension (`.jsonl`, `.csv`, `.txt`/`.eth`), else
/// from its first non-empty line.
pub fn detect(path: &std::path::Path, text: &str) -> Format {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("jsonl") | Some("json") => return Format::Jsonl,
        Some("csv") => return Format::Csv,
        Some("txt") | Some("eth") => return Format::Eth,
        _ => {}
    }
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    if first.starts_with('{') {
        Format::Jsonl
    } else if first.contains(',') {
        Format::Csv
    } else {
        Format::Eth
    }
}

/// Reads a track set in `format`.
///
/// # Errors
/// [`ReadError`] naming the line and what is wrong there.
pub fn read(text: &str, format: Format, opts: &ReadOptions) -> Result<TrackSet, ReadError> {
    match format {
        Format::Jsonl => read_jsonl(text),
        Format::Csv => read_csv(text, opts.csv_step_s),
        Format::Eth => read_eth(text, opts.eth),
    }
}

/// Writes a track set in `format` (ETH frames at `opts.eth`; JSON Lines without a
/// `source`).
pub fn write(set: &TrackSet, format: Format, opts: &ReadOptions) -> String {
    match format {
        Format::Jsonl => write_jsonl(set, None),
        Format::Csv => write_csv(set),
        Format::Eth => write_eth(set, opts.eth),
    }
}
