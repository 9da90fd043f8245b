//! `crowdtouch edit`: crowd motion editing (crowd-motion-editing, Zhang et al. 2020)
//! on track files: collisions (`edit check`), scripted edits (`edit apply`) and
//! pictures (`edit render`); tracks of a group walking through a scene (`edit path`,
//! in `edit_path.rs`).

use super::{edit_apply, edit_check, edit_render};

use super::track_file::{load_flat, TrackFileArgs};
use anyhow::Result;
use clap::Subcommand;

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
