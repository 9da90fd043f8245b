//! `crowdtouch edit render`: what `edit apply` does, drawn as an SVG. The tracks
//! before (thin, light grey) and after (coloured by time, with the time scale;
//! people the edit left as they were faded),
//! each drag's cage at rest (dashed) and deformed (solid) over its deformation mesh,
//! the dragged handle's arrow, the fixed places, collisions before (hollow red rings)
//! and after (filled red), the scene's obstacles, axes in metres, a title and a
//! one-line summary. Optionally everyone's position at given instants, before and
//! after. Drawn through `crowdtouch::picture` with world y up.

use super::edit_apply::{run, EditArgs, Outcome};
use super::edit_render_layers::{
    cages, collisions, drags_and_fixes, grid, instants, obstacles, tracks_after, tracks_before,
};
use super::edit_render_legend::legend;
use super::edit_render_svg::{
    BOTTOM_PX, LEFT_PX, MARGIN_M, MAX_PX_PER_M, MIN_PX_PER_M, PLOT_WIDTH_PX, RIGHT_PX, TOP_PX,
};
use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use crowdtouch::crowd::edit::{Op, TrackSet};
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::picture::text::px;
use crowdtouch::picture::{elements, style, Canvas, Frame, Paint};
use std::path::PathBuf;

/// `edit render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// The tracks, the script and the avoidance steps (as `edit apply`).
    #[command(flatten)]
    pub edit: EditArgs,
    /// The SVG to write.
    #[arg(long, short)]
    pub output: PathBuf,
    /// Replace `-o` if it exists.
    #[arg(long)]
    pub force: bool,
    /// The picture's title (default: the track file and the script).
    #[arg(long)]
    pub title: Option<String>,
    /// Also mark everyone's position at this time (s), before (grey rings) and after
    /// (filled); may be given more than once.
    #[arg(long = "at", value_name = "SECONDS")]
    pub at_s: Vec<f64>,
}

/// Runs `edit render`.
pub fn render(a: RenderArgs) -> Result<()> {
    if a.output.exists() && !a.force {
        bail!("{} exists; give --force to replace it", a.output.display());
    }
    if let Some(t) = a.at_s.iter().find(|t| !t.is_finite()) {
        bail!("--at must be a number of seconds, not {t}");
    }
    let o = run(&a.edit)?;
    let title = a.title.clone().unwrap_or_else(|| match &a.edit.ops {
        Some(ops) => format!(
            "{} edited by {}",
            a.edit.tracks.file.display(),
            ops.display()
        ),
        None => a.edit.tracks.file.display().to_string(),
    });
    let svg = picture(&o, a.edit.threshold, &a.at_s, &title);
    std::fs::write(&a.output, &svg).with_context(|| format!("writing {}", a.output.display()))?;
    outln!(
        "{}: {} people; pairs closer than {} m: {} before, {} after ({} bytes)",
        a.output.display(),
        o.after.tracks.len(),
        a.edit.threshold,
        o.collisions_before.pair_count(),
        o.collisions_after.pair_count(),
        svg.len()
    )?;
    Ok(())
}

/// The SVG of an outcome.
pub fn picture(o: &Outcome, threshold_m: f64, at_s: &[f64], title: &str) -> String {
    // What is drawn decides the extent; obstacles are clipped to it.
    let mut lo = Vec2::repeat(f64::INFINITY);
    let mut hi = Vec2::repeat(f64::NEG_INFINITY);
    let mut grow = |p: Vec2| {
        lo = lo.inf(&p);
        hi = hi.sup(&p);
    };
    for t in o.before.tracks.iter().chain(&o.after.tracks) {
        t.points.iter().for_each(|&p| grow(p));
    }
    for d in &o.report.drags {
        d.hull.iter().chain(&d.hull_rest).for_each(|&p| grow(p));
    }
    for (op, _) in &o.script.ops {
        match op {
            Op::Drag { from, to, .. } => {
                grow(*from);
                grow(*to);
            }
            Op::Fix(v) => v.iter().for_each(|&p| grow(p)),
            _ => {}
        }
    }
    if !(lo.x.is_finite() && hi.x.is_finite()) {
        lo = Vec2::zeros();
        hi = Vec2::new(1.0, 1.0);
    }
    lo -= Vec2::repeat(MARGIN_M);
    hi += Vec2::repeat(MARGIN_M);
    let k = (PLOT_WIDTH_PX / (hi.x - lo.x)).clamp(MIN_PX_PER_M, MAX_PX_PER_M);
    let f = Frame {
        world: Rect {
            min: [lo.x, lo.y],
            max: [hi.x, hi.y],
        },
        px_per_m: k,
        left_px: LEFT_PX,
        top_px: TOP_PX,
        y_up: true,
    };
    let (pw, ph) = (f.width_px(), f.height_px());
    let mut c = Canvas::new(
        LEFT_PX + pw.max(PLOT_WIDTH_PX) + RIGHT_PX,
        TOP_PX + ph + BOTTOM_PX,
    );
    c.title((LEFT_PX, 24.0), title);
    c.raw(&format!(
        r#"<defs><clipPath id="plot"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"#,
        px(LEFT_PX),
        px(TOP_PX),
        px(pw),
        px(ph)
    ));
    c.open_group(
        r#"class="world" clip-path="url(#plot)" stroke-linejoin="round" stroke-linecap="round""#,
    );
    c.rect(LEFT_PX, TOP_PX, pw, ph, &Paint::fill(style::PLOT));
    grid(&mut c, &f);
    obstacles(&mut c, &f, o);
    tracks_before(&mut c, &f, o);
    cages(&mut c, &f, o);
    let (t0, t1) = time_range(&o.after);
    tracks_after(&mut c, &f, o, t0, t1);
    instants(&mut c, &f, o, at_s, t0, t1);
    drags_and_fixes(&mut c, &f, o);
    collisions(&mut c, &f, o);
    c.close_group();
    elements::metre_axes(&mut c, &f, 10);
    legend(&mut c, o, threshold_m, t0, t1, at_s, TOP_PX + ph + 44.0);
    c.finish()
}

fn time_range(set: &TrackSet) -> (f64, f64) {
    let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
    for t in &set.tracks {
        if let (Some(x), Some(y)) = (t.times_s.first(), t.times_s.last()) {
            a = a.min(*x);
            b = b.max(*y);
        }
    }
    if a.is_finite() && b > a {
        (a, b)
    } else if a.is_finite() {
        (a, a + 1.0)
    } else {
        (0.0, 1.0)
    }
}
