//! `crowdtouch scene …`: tools for scene files.

use crate::cli::common::output::{self, outln};
use anyhow::Result;
use crowdtouch::config::Config;
use crowdtouch::crowd::environment::{DynamicKind, Scene};
use std::path::{Path, PathBuf};

/// `crowdtouch scene` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum SceneCmd {
    /// Validate a scene file: prints its bounds and counts, or every error as
    /// `file:line:col: field: what` (exit code 1).
    ///
    /// Obstacles must be at least one agent diameter apart; the agent radius is the
    /// config's `crowd.agent_radius_m` unless given. Checkpoints must name a
    /// formation of the config (the shipped shapes and its `formations.shapes`).
    Check {
        /// Scene file (RON).
        file: PathBuf,
        /// Agent radius (m) for the gap check.
        #[arg(long)]
        agent_radius_m: Option<f64>,
        /// Config whose agent radius and formations to check against (default:
        /// the embedded default config).
        #[arg(long)]
        config: Option<PathBuf>,
    },
    /// Draw a scene as SVG: bounds, obstacles, travel-speed patches by motion type,
    /// moving things at `--t` with their paths, checkpoints with their formations;
    /// the travel-time field of one goal as a heat map with contours (seconds at the
    /// default config's `crowd.max_speed_m_s`); agents in the default crowd start
    /// and their routes down the field.
    ///
    /// Exit code 1 for a bad scene file or an output that cannot be written, 2 for
    /// a bad argument (a goal outside the bounds or inside an obstacle).
    Render(super::scene_render::RenderArgs),
}

/// Runs a `scene` subcommand; returns the exit code, or why its output could not
/// be written.
pub fn scene(cmd: SceneCmd) -> Result<i32> {
    match cmd {
        SceneCmd::Check {
            file,
            agent_radius_m,
            config,
        } => check(&file, agent_radius_m, config.as_deref()),
        SceneCmd::Render(a) => super::scene_render::render(a),
    }
}

fn check(file: &Path, agent_radius_m: Option<f64>, config: Option<&Path>) -> Result<i32> {
    let cfg = match config {
        Some(p) => match Config::load(p) {
            Ok(c) => c,
            Err(e) => return Ok(output::fail_with(1, format_args!("{e}"))),
        },
        None => Config::embedded_default(),
    };
    let radius = agent_radius_m.unwrap_or(cfg.crowd.agent_radius_m);
    if !(radius.is_finite() && radius > 0.0) {
        return Ok(output::fail_with(
            2,
            format_args!(
                "crowdtouch: error: --agent-radius-m must be a positive number of metres, got {radius}"
            ),
        ));
    }
    match Scene::load(file, radius).and_then(|s| {
        s.check_formations(file, &cfg.formation_library().known_names())
            .map(|()| s)
    }) {
        Ok(s) => {
            let b = s.bounds();
            let moving_obstacles = s
                .dynamic()
                .iter()
                .filter(|d| d.kind == DynamicKind::Obstacle)
                .count();
            let parts: usize = s.obstacles().iter().map(|o| o.parts.len()).sum();
            outln!(
                "{}: ok: {:?} {} x {} m from ({}, {}); {} obstacle{} ({} convex part{}), {} patch{}, {} dynamic ({} obstacle{}, {} patch{}), {} checkpoint{}; gaps checked for agent radius {} m",
                file.display(),
                s.name(),
                b.width(),
                b.height(),
                b.min[0],
                b.min[1],
                s.obstacles().len(),
                plural(s.obstacles().len(), "", "s"),
                parts,
                plural(parts, "", "s"),
                s.patches().len(),
                plural(s.patches().len(), "", "es"),
                s.dynamic().len(),
                moving_obstacles,
                plural(moving_obstacles, "", "s"),
                s.dynamic().len() - moving_obstacles,
                plural(s.dynamic().len() - moving_obstacles, "", "es"),
                s.checkpoints().len(),
                plural(s.checkpoints().len(), "", "s"),
                radius,
            )?;
            Ok(0)
        }
        Err(e) => Ok(output::fail_with(1, format_args!("{e}"))),
    }
}

fn plural(n: usize, one: &'static str, many: &'static str) -> &'static str {
    if n == 1 {
        one
    } else {
        many
    }
}
