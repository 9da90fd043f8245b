//! The command: arguments, running it, its exit codes and summary line.

use super::error::RenderError;
use super::picture::{Options, Picture};
use crate::cli::common::output::{self, outln};
use crowdtouch::config::Config;
use crowdtouch::crowd::environment::Scene;
use crowdtouch::geom::Vec2;
use std::path::{Path, PathBuf};

/// Default cell size of the field grid (m).
pub const DEFAULT_CELL_M: f64 = 0.05;
/// Default number of agents.
pub const DEFAULT_AGENTS: usize = 40;

/// `crowdtouch scene render` arguments.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (RON).
    pub file: PathBuf,
    /// Output SVG file.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Goal of the field, `X,Y` in metres (default: 1 m in from the east edge at
    /// mid-height, or the nearest free cell to it).
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    pub goal: Option<[f64; 2]>,
    /// Number of agents, on a lattice in the config's crowd start rectangle
    /// (blocked cells skipped).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_AGENTS)]
    pub agents: usize,
    /// Scene time (s): where moving obstacles and patches are.
    #[arg(
        long = "t",
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub t_s: f64,
    /// Cell size of the field grid (m).
    #[arg(long, value_name = "M", default_value_t = DEFAULT_CELL_M)]
    pub cell_m: f64,
}

/// Parses `X,Y` (metres).
fn parse_point(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("expected X,Y in metres (e.g. 14.5,4.5), got {s:?}");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite()) {
        return Err(bad());
    }
    Ok([x, y])
}

/// Runs `scene render`; returns the exit code, or why the summary line could not
/// be written.
pub fn render(a: RenderArgs) -> anyhow::Result<i32> {
    match run(&a) {
        Ok(summary) => {
            outln!("{summary}")?;
            Ok(0)
        }
        Err(RenderError::Usage(m)) => {
            Ok(output::fail_with(2, format_args!("crowdtouch: error: {m}")))
        }
        Err(RenderError::Failed(m)) => Ok(output::fail_with(1, format_args!("{m}"))),
    }
}

fn run(a: &RenderArgs) -> Result<String, RenderError> {
    let cfg = Config::embedded_default();
    let opts = Options {
        goal: a.goal.map(|[x, y]| Vec2::new(x, y)),
        agents: a.agents,
        t_s: a.t_s,
        cell_m: a.cell_m,
        preferred_speed_m_s: cfg.crowd.max_speed_m_s,
        start: cfg.crowd.formation,
    };
    opts.check()?;
    let scene = Scene::load(&a.file, cfg.crowd.agent_radius_m)
        .map_err(|e| RenderError::Failed(e.to_string()))?;
    let pic = Picture::compute(&scene, &opts)?;
    let svg = pic.svg(&scene, &opts);
    std::fs::write(&a.out, &svg).map_err(|e| {
        RenderError::Failed(format!(
            "crowdtouch: error: writing {}: {e}",
            a.out.display()
        ))
    })?;
    Ok(format!(
        "{}: {:?}, goal ({:.2}, {:.2}), {} agents, {} of {} routes reach the goal, Φ up to {:.1} s; {} bytes",
        display(&a.out),
        scene.name(),
        pic.goal.x,
        pic.goal.y,
        pic.agents.len(),
        pic.routes.iter().filter(|r| r.reached).count(),
        pic.routes.len(),
        pic.phi_max,
        svg.len()
    ))
}

fn display(p: &Path) -> String {
    p.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_point_accepts_x_comma_y_and_rejects_the_rest() {
        assert_eq!(parse_point("14.5,4.5"), Ok([14.5, 4.5]));
        assert_eq!(parse_point(" -1 , 2 "), Ok([-1.0, 2.0]));
        for bad in ["", "1", "1,", "a,2", "1,2,3", "nan,1", "inf,0"] {
            assert!(parse_point(bad).is_err(), "{bad}");
        }
    }
}
