//! A track file on the command line: its path, format and reading options, and
//! loading it (every `edit` subcommand reads one).

use anyhow::{anyhow, Result};
use clap::ValueEnum;
use crowdtouch::crowd::edit::io::{self, EthOptions, Format, ReadOptions};
use crowdtouch::crowd::edit::{FlatTracks, TrackSet};
use std::path::PathBuf;

/// A track file's format on the command line.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// From the extension, else the first line.
    Auto,
    /// Our JSON Lines tracks.
    Jsonl,
    /// `t,id,x,y`.
    Csv,
    /// ETH/UCY raw `frame id x y`.
    Eth,
}

/// How a track file is read.
#[derive(clap::Args, Debug, Clone)]
pub struct TrackFileArgs {
    /// Track file (JSON Lines, CSV `t,id,x,y`, or ETH/UCY `frame id x y`).
    pub file: PathBuf,
    /// The file's format.
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// ETH/UCY: video frames per second.
    #[arg(long, default_value_t = 25.0)]
    pub frame_rate: f64,
    /// ETH/UCY: frames between a person's consecutive annotations.
    #[arg(long, default_value_t = 10)]
    pub frame_step: u32,
    /// CSV: the frame step (s); samples at most 1.5 steps apart are linked
    /// (default: the median of the people's consecutive time differences).
    #[arg(long)]
    pub step: Option<f64>,
}

/// Reads a track file as the arguments say; errors name `file:line`.
pub fn load(a: &TrackFileArgs) -> Result<(TrackSet, Format)> {
    let (format, opts) = read_options(a);
    io::read_tracks(&a.file, format, &opts).map_err(|e| anyhow!(e))
}

/// [`load`] into the compact store, for commands that only read the tracks.
pub fn load_flat(a: &TrackFileArgs) -> Result<(FlatTracks, Format)> {
    let (format, opts) = read_options(a);
    io::read_tracks_flat(&a.file, format, &opts).map_err(|e| anyhow!(e))
}

/// The format (`None`: detect it) and reading options the arguments give.
fn read_options(a: &TrackFileArgs) -> (Option<Format>, ReadOptions) {
    let format = match a.format {
        FormatArg::Auto => None,
        FormatArg::Jsonl => Some(Format::Jsonl),
        FormatArg::Csv => Some(Format::Csv),
        FormatArg::Eth => Some(Format::Eth),
    };
    let opts = ReadOptions {
        eth: EthOptions {
            frame_rate_hz: a.frame_rate,
            frame_step: a.frame_step,
        },
        csv_step_s: a.step,
    };
    (format, opts)
}
