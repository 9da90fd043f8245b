//! `crowdtouch edit`: crowd motion editing (crowd-motion-editing, Zhang et al. 2020)
//! on track files: collisions (`edit check`), scripted edits (`edit apply`) and
//! pictures (`edit render`); tracks of a group walking through a scene (`edit path`,
//! in `edit_path.rs`).

#[path = "edit_apply.rs"]
mod edit_apply;
#[path = "edit_check.rs"]
mod edit_check;
#[path = "edit_render.rs"]
mod edit_render;

use anyhow::{anyhow, Result};
use clap::{Subcommand, ValueEnum};
use crowdtouch::crowd::edit::io::{self, EthOptions, Format, ReadOptions};
use crowdtouch::crowd::edit::{FlatTracks, TrackSet};
use std::path::PathBuf;

/// Subcommands of `edit`.
#[derive(Subcommand, Debug)]
pub enum EditCmd {
    /// Collisions between people (space-time closest approach below a threshold).
    Check(CheckArgs),
    /// Run an edit script (`--ops EDIT.ron`: select, fix, drag, retime) on a track
    /// file, optionally keep the crowd out of a scene's obstacles and people apart
    /// by retiming; write the result to `-o` and report collisions before and
    /// after, the speed change and each drag's hull-shape error.
    Apply(edit_apply::ApplyArgs),
    /// Draw what `edit apply` does as an SVG: the tracks before and after (coloured
    /// by time), each drag's cage at rest and deformed with its mesh, the drag
    /// arrows, fixed places, collisions before and after, the scene's obstacles.
    Render(edit_render::RenderArgs),
    /// Tracks of a group walking a path through a scene in rows (the paper's test
    /// crowd, section 5.2).
    Path(super::edit_path::PathArgs),
}

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

/// `edit check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// The tracks.
    #[command(flatten)]
    pub tracks: TrackFileArgs,
    /// Two people closer than this collide (metres). Collisions are reported, not an
    /// error: the exit status is 0 either way.
    #[arg(long, default_value_t = 0.3)]
    pub threshold: f64,
    /// Pairs, events and clusters listed (the closest pairs, the earliest events,
    /// the largest clusters; all are counted). Default 1000.
    #[arg(long)]
    pub keep: Option<usize>,
    /// One JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs an `edit` subcommand.
pub fn edit(cmd: EditCmd) -> Result<()> {
    match cmd {
        EditCmd::Check(a) => check(a),
        EditCmd::Apply(a) => edit_apply::apply(a),
        EditCmd::Render(a) => edit_render::render(a),
        EditCmd::Path(a) => super::edit_path::path(a),
    }
}

/// `edit check`: exits 0 whether or not people collide (`edit_check`).
fn check(a: CheckArgs) -> Result<()> {
    let (set, _) = load_flat(&a.tracks)?;
    edit_check::run(
        &set,
        &a.tracks.file.display().to_string(),
        a.threshold,
        a.keep,
        a.json,
    )
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
