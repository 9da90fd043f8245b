//! `crowdtouch edit path`: tracks of a group walking a standard path through a
//! scene in rows (crowd-motion-editing section 5.2), written as JSON Lines tracks
//! (docs/tracks.md).

use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::crowd::edit::io::write_jsonl;
use crowdtouch::crowd::edit::{group_tracks, GroupPath};
use crowdtouch::crowd::environment::{load_scene, DEFAULT_AGENT_RADIUS_M, SCENES};
use crowdtouch::geom::Vec2;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// `edit path`.
#[derive(clap::Args, Debug)]
pub struct PathArgs {
    /// Scene file, or the name of a shipped scene (`single_block`, `corridor.ron`, …).
    #[arg(long)]
    pub scene: PathBuf,
    /// Start of the path, `X,Y` in metres.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub from: Vec2,
    /// Goal of the path, `X,Y` in metres.
    #[arg(long, value_parser = parse_point, allow_hyphen_values = true)]
    pub to: Vec2,
    /// People in the group.
    #[arg(long)]
    pub people: usize,
    /// Distance between neighbours across the path and between rows (m).
    #[arg(long, default_value_t = 0.6)]
    pub spacing: f64,
    /// Walking speed (m/s).
    #[arg(long, default_value_t = 1.3)]
    pub speed: f64,
    /// Time between samples (s).
    #[arg(long, default_value_t = 0.1)]
    pub step: f64,
    /// Output track file (JSON Lines).
    #[arg(long, short)]
    pub out: PathBuf,
    /// Overwrite the output file if it exists.
    #[arg(long)]
    pub force: bool,
}

/// Runs `edit path`.
pub fn path(a: PathArgs) -> Result<()> {
    if !a.force && a.out.exists() {
        bail!("{} exists: give --force to overwrite it", a.out.display());
    }
    let file = scene_file(&a.scene);
    let scene = load_scene(&file, DEFAULT_AGENT_RADIUS_M).map_err(|e| anyhow!("{e}"))?;
    let group = GroupPath {
        start: a.from,
        goal: a.to,
        people: a.people,
        spacing_m: a.spacing,
        speed_m_s: a.speed,
        step_s: a.step,
    };
    let set = group_tracks(&Arc::new(scene), &group)
        .with_context(|| format!("a path through {}", file.display()))?;
    let source = format!(
        "edit path --scene {} --from {},{} --to {},{} --people {} --spacing {} --speed {} --step {}",
        file.display(),
        a.from.x,
        a.from.y,
        a.to.x,
        a.to.y,
        a.people,
        a.spacing,
        a.speed,
        a.step
    );
    std::fs::write(&a.out, write_jsonl(&set, Some(&source)))
        .with_context(|| format!("writing {}", a.out.display()))?;
    Ok(())
}

/// The scene file: the path as given when it exists, else a shipped scene by its
/// name with or without `.ron`.
pub(super) fn scene_file(p: &Path) -> PathBuf {
    if p.exists() || p.extension().is_some() {
        return p.to_path_buf();
    }
    let named = p.with_extension("ron");
    let name = named.file_name().and_then(|n| n.to_str()).unwrap_or("");
    if SCENES.iter().any(|(n, _)| *n == name) {
        named
    } else {
        p.to_path_buf()
    }
}

fn parse_point(s: &str) -> Result<Vec2, String> {
    let mut it = s.split(',').map(str::trim);
    let (Some(x), Some(y), None) = (it.next(), it.next(), it.next()) else {
        return Err(format!("expected X,Y in metres, not `{s}`"));
    };
    let num = |v: &str| {
        v.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("`{v}` is not a finite number"))
    };
    Ok(Vec2::new(num(x)?, num(y)?))
}
