//! `crowdtouch edit render`: what `edit apply` does, drawn as an SVG. The tracks
//! before (thin, light grey) and after (coloured by time, with the time scale;
//! people the edit left as they were faded),
//! each drag's cage at rest (dashed) and deformed (solid) over its deformation mesh,
//! the dragged handle's arrow, the fixed places, collisions before (hollow red rings)
//! and after (filled red), the scene's obstacles, axes in metres, a title and a
//! one-line summary. Optionally everyone's position at given instants, before and
//! after. Coordinates are written in metres rounded to the millimetre.

use super::edit_apply::{run, EditArgs, Outcome};
use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use crowdtouch::crowd::edit::{Op, Track, TrackSet};
use crowdtouch::crowd::environment::Part;
use crowdtouch::geom::Vec2;
use std::fmt::Write;
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

/// Width of the plotting area (px).
const PLOT_WIDTH_PX: f64 = 880.0;
/// Bounds of the scale (px per metre).
const MIN_PX_PER_M: f64 = 6.0;
const MAX_PX_PER_M: f64 = 160.0;
/// Margin around what is drawn (m).
const MARGIN_M: f64 = 0.5;
/// Room for the title above and the axis labels left of the plot (px).
const TOP_PX: f64 = 40.0;
const LEFT_PX: f64 = 56.0;
const RIGHT_PX: f64 = 20.0;
/// Room under the plot for the axis, the legend and the summary (px).
const BOTTOM_PX: f64 = 118.0;
/// Most points drawn per track and per picture; longer tracks are thinned.
const MAX_TRACK_POINTS: usize = 400;
const MAX_POINTS: usize = 40_000;
/// Bands of the time colour scale.
const TIME_BANDS: usize = 12;
/// Viridis-like stops of the time colour scale (early → late).
const TIME_STOPS: [[f64; 3]; 5] = [
    [68.0, 1.0, 84.0],
    [59.0, 82.0, 139.0],
    [33.0, 145.0, 140.0],
    [94.0, 201.0, 98.0],
    [253.0, 231.0, 37.0],
];
const COLLISION_RED: &str = "#d62728";
const FIXED_BLUE: &str = "#1f4e9c";
const CAGE_COLOUR: &str = "#e07b00";
const OBSTACLE_FILL: &str = "#8c8c8c";

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

/// A length in metres, rounded to the millimetre, without trailing zeros.
fn mm(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    let s = format!("{:.3}", if r == 0.0 { 0.0 } else { r });
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn pt(p: Vec2) -> String {
    format!("{},{}", mm(p.x), mm(p.y))
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The time colour at `f` in [0, 1].
fn time_colour(f: f64) -> String {
    let f = f.clamp(0.0, 1.0) * (TIME_STOPS.len() - 1) as f64;
    let i = (f.floor() as usize).min(TIME_STOPS.len() - 2);
    let u = f - i as f64;
    let c: Vec<u8> = (0..3)
        .map(|k| (TIME_STOPS[i][k] * (1.0 - u) + TIME_STOPS[i + 1][k] * u).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// A tick step of 1, 2 or 5 × 10^n giving about `n` ticks over `span`.
fn nice_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|k| k * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

/// Every `stride`-th sample of `t` (and its last) as runs of linked samples.
fn runs(t: &Track, stride: usize) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut cur: Vec<usize> = Vec::new();
    for j in 0..t.len() {
        let linked_in = j > 0 && t.linked[j - 1];
        if !linked_in && !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
        let run_end = j + 1 == t.len() || !t.linked[j];
        if cur.is_empty() || run_end || j % stride == 0 {
            cur.push(j);
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

fn stride_for(set: &TrackSet) -> impl Fn(&Track) -> usize {
    let total = set.samples().max(1);
    let global = total.div_ceil(MAX_POINTS).max(1);
    move |t: &Track| global.max(t.len().div_ceil(MAX_TRACK_POINTS)).max(1)
}

/// Points of a run, dropping consecutive repeats at millimetre precision.
fn run_points(t: &Track, run: &[usize]) -> Vec<String> {
    let mut v: Vec<String> = Vec::with_capacity(run.len());
    for &j in run {
        let p = pt(t.points[j]);
        if v.last() != Some(&p) {
            v.push(p);
        }
    }
    v
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
    let (wm, hm) = (hi.x - lo.x, hi.y - lo.y);
    let k = (PLOT_WIDTH_PX / wm).clamp(MIN_PX_PER_M, MAX_PX_PER_M);
    let (pw, ph) = (wm * k, hm * k);
    let width = LEFT_PX + pw.max(PLOT_WIDTH_PX) + RIGHT_PX;
    let height = TOP_PX + ph + BOTTOM_PX;
    // A width of `px` pixels in metres.
    let w = |px: f64| mm((px / k).max(0.001));
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="13">"##
    );
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#fbfbf8"/>"##
    );
    let _ = writeln!(
        s,
        r##"<text x="{LEFT_PX:.0}" y="24" font-size="16" fill="#222">{}</text>"##,
        xml_escape(title)
    );
    // World metres → picture: y up.
    let _ = writeln!(
        s,
        r##"<defs><clipPath id="plot"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"##,
        mm(lo.x),
        mm(lo.y),
        mm(wm),
        mm(hm)
    );
    let _ = writeln!(
        s,
        r##"<g id="world" transform="matrix({k:.4},0,0,{:.4},{:.3},{:.3})" clip-path="url(#plot)" stroke-linejoin="round" stroke-linecap="round">"##,
        -k,
        LEFT_PX - lo.x * k,
        TOP_PX + hi.y * k
    );
    let _ = writeln!(
        s,
        r##"<rect x="{}" y="{}" width="{}" height="{}" fill="#ffffff" stroke="none"/>"##,
        mm(lo.x),
        mm(lo.y),
        mm(wm),
        mm(hm)
    );
    grid(&mut s, lo, hi, k);
    obstacles(&mut s, o, lo, hi, &w);
    tracks_before(&mut s, o, &w);
    cages(&mut s, o, &w);
    let (t0, t1) = time_range(&o.after);
    tracks_after(&mut s, o, t0, t1, &w);
    instants(&mut s, o, at_s, t0, t1, k);
    drags_and_fixes(&mut s, o, k, &w);
    collisions(&mut s, o, k, &w);
    s.push_str("</g>\n");
    axes(&mut s, lo, hi, k, ph);
    legend(&mut s, o, threshold_m, t0, t1, at_s, TOP_PX + ph + 44.0);
    s.push_str("</svg>\n");
    s
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

fn grid(s: &mut String, lo: Vec2, hi: Vec2, k: f64) {
    let step = nice_step((hi.x - lo.x).max(hi.y - lo.y), 10.0);
    let mut d = String::new();
    let mut x = (lo.x / step).ceil() * step;
    while x <= hi.x {
        let _ = write!(d, "M{} {}V{}", mm(x), mm(lo.y), mm(hi.y));
        x += step;
    }
    let mut y = (lo.y / step).ceil() * step;
    while y <= hi.y {
        let _ = write!(d, "M{} {}H{}", mm(lo.x), mm(y), mm(hi.x));
        y += step;
    }
    let _ = writeln!(
        s,
        r##"<path id="grid" d="{d}" fill="none" stroke="#e8e8e4" stroke-width="{}"/>"##,
        mm((0.8 / k).max(0.001))
    );
}

fn obstacles(s: &mut String, o: &Outcome, lo: Vec2, hi: Vec2, w: &impl Fn(f64) -> String) {
    let Some((scene, _, _)) = &o.obstacles else {
        return;
    };
    let _ = writeln!(
        s,
        r##"<g id="obstacles" fill="{OBSTACLE_FILL}" fill-opacity="0.55" stroke="#333" stroke-width="{}">"##,
        w(0.8)
    );
    for ob in scene.obstacles() {
        for part in &ob.parts {
            let bb = part.aabb();
            if bb.max[0] < lo.x || bb.min[0] > hi.x || bb.max[1] < lo.y || bb.min[1] > hi.y {
                continue;
            }
            match part {
                Part::Polygon(p) => {
                    let pts: Vec<String> = p.vertices().iter().map(|&v| pt(v)).collect();
                    let _ = writeln!(s, r##"<polygon points="{}"/>"##, pts.join(" "));
                }
                Part::Circle(c) => {
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{}" cy="{}" r="{}"/>"##,
                        mm(c.centre.x),
                        mm(c.centre.y),
                        mm(c.radius_m)
                    );
                }
            }
        }
    }
    s.push_str("</g>\n");
}

/// Tracks before, only where they differ in space from after.
fn tracks_before(s: &mut String, o: &Outcome, w: &impl Fn(f64) -> String) {
    let stride = stride_for(&o.before);
    let _ = writeln!(
        s,
        r##"<g id="before" fill="none" stroke="#b4b4b4" stroke-width="{}">"##,
        w(1.0)
    );
    for (i, t) in o.before.tracks.iter().enumerate() {
        if o.after.tracks.get(i).map(|a| &a.points) == Some(&t.points) {
            continue;
        }
        for r in runs(t, stride(t)) {
            let pts = run_points(t, &r);
            if pts.len() >= 2 {
                let _ = writeln!(s, r##"<polyline points="{}"/>"##, pts.join(" "));
            }
        }
    }
    s.push_str("</g>\n");
}

/// Tracks after, split into bands of the time scale; tracks the edit did not move
/// in space are faded.
fn tracks_after(s: &mut String, o: &Outcome, t0: f64, t1: f64, w: &impl Fn(f64) -> String) {
    let set = &o.after;
    let stride = stride_for(set);
    let band = |t: f64| (((t - t0) / (t1 - t0) * TIME_BANDS as f64) as usize).min(TIME_BANDS - 1);
    let mut moved: Vec<String> = vec![String::new(); TIME_BANDS];
    let mut still: Vec<String> = vec![String::new(); TIME_BANDS];
    for (i, t) in set.tracks.iter().enumerate() {
        let same = o.before.tracks.get(i).map(|b| &b.points) == Some(&t.points)
            && o.before.tracks[i].times_s == t.times_s;
        let by_band = if same { &mut still } else { &mut moved };
        for r in runs(t, stride(t)) {
            // Pieces of the run within one band; each starts where the last ended.
            let mut piece: Vec<usize> = Vec::new();
            let mut b = band(t.times_s[r[0]]);
            for &j in &r {
                piece.push(j);
                let bj = band(t.times_s[j]);
                if bj != b {
                    let pts = run_points(t, &piece);
                    if pts.len() >= 2 {
                        let _ = writeln!(by_band[b], r##"<polyline points="{}"/>"##, pts.join(" "));
                    }
                    piece = vec![j];
                    b = bj;
                }
            }
            let pts = run_points(t, &piece);
            if pts.len() >= 2 {
                let _ = writeln!(by_band[b], r##"<polyline points="{}"/>"##, pts.join(" "));
            }
        }
    }
    let _ = writeln!(
        s,
        r##"<g id="after" fill="none" stroke-width="{}">"##,
        w(1.6)
    );
    for (bands, attrs) in [(&still, r#" opacity="0.3""#), (&moved, "")] {
        if bands.iter().all(|b| b.is_empty()) {
            continue;
        }
        let _ = writeln!(s, "<g{attrs}>");
        for (b, body) in bands.iter().enumerate() {
            if body.is_empty() {
                continue;
            }
            let f = (b as f64 + 0.5) / TIME_BANDS as f64;
            let _ = writeln!(s, r##"<g stroke="{}">"##, time_colour(f));
            s.push_str(body);
            s.push_str("</g>\n");
        }
        s.push_str("</g>\n");
    }
    s.push_str("</g>\n");
}

fn cages(s: &mut String, o: &Outcome, w: &impl Fn(f64) -> String) {
    if o.report.drags.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        r##"<g id="mesh" fill="none" stroke="#9aa9c4" stroke-width="{}">"##,
        w(0.4)
    );
    for d in &o.report.drags {
        let mut edges: Vec<(u32, u32)> = d
            .mesh_triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut path = String::new();
        for (a, b) in edges {
            let (Some(&p), Some(&q)) = (
                d.mesh_vertices.get(a as usize),
                d.mesh_vertices.get(b as usize),
            ) else {
                continue;
            };
            let _ = write!(path, "M{} {}L{} {}", mm(p.x), mm(p.y), mm(q.x), mm(q.y));
        }
        let _ = writeln!(s, r##"<path d="{path}"/>"##);
    }
    s.push_str("</g>\n");
    let _ = writeln!(
        s,
        r##"<g id="cage-rest" fill="none" stroke="{CAGE_COLOUR}" stroke-width="{}" stroke-dasharray="{} {}">"##,
        w(1.4),
        w(6.0),
        w(4.0)
    );
    for d in &o.report.drags {
        let pts: Vec<String> = d.hull_rest.iter().map(|&p| pt(p)).collect();
        let _ = writeln!(s, r##"<polygon points="{}"/>"##, pts.join(" "));
    }
    s.push_str("</g>\n");
    let _ = writeln!(
        s,
        r##"<g id="cage-deformed" fill="none" stroke="{CAGE_COLOUR}" stroke-width="{}">"##,
        w(1.8)
    );
    for d in &o.report.drags {
        let pts: Vec<String> = d.hull.iter().map(|&p| pt(p)).collect();
        let _ = writeln!(s, r##"<polygon points="{}"/>"##, pts.join(" "));
    }
    s.push_str("</g>\n");
}

fn instants(s: &mut String, o: &Outcome, at_s: &[f64], t0: f64, t1: f64, k: f64) {
    if at_s.is_empty() {
        return;
    }
    let r = mm(3.5 / k);
    let _ = writeln!(
        s,
        r##"<g id="instants" stroke-width="{}">"##,
        mm((1.0 / k).max(0.001))
    );
    for &t in at_s {
        let c = time_colour((t - t0) / (t1 - t0));
        for (b, a) in o.before.tracks.iter().zip(&o.after.tracks) {
            let pb = b.position_at(t);
            let pa = a.position_at(t);
            if let (Some(p), Some(q)) = (pb, pa) {
                if (p - q).norm() > 0.01 {
                    let _ = writeln!(
                        s,
                        r##"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="#555"/>"##,
                        mm(p.x),
                        mm(p.y),
                        mm(q.x),
                        mm(q.y)
                    );
                }
            }
            if let Some(p) = pb {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{}" cy="{}" r="{r}" fill="#ffffff" stroke="#777"/>"##,
                    mm(p.x),
                    mm(p.y)
                );
            }
            if let Some(q) = pa {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{}" cy="{}" r="{r}" fill="{c}" stroke="#222"/>"##,
                    mm(q.x),
                    mm(q.y)
                );
            }
        }
    }
    s.push_str("</g>\n");
}

fn drags_and_fixes(s: &mut String, o: &Outcome, k: f64, w: &impl Fn(f64) -> String) {
    let mut arrows = String::new();
    let mut fixed = String::new();
    let head = 10.0 / k;
    for (op, _) in &o.script.ops {
        match op {
            Op::Drag { from, to, .. } => {
                let d = *to - *from;
                let len = d.norm();
                let _ = writeln!(
                    arrows,
                    r##"<circle cx="{}" cy="{}" r="{}" fill="#111"/>"##,
                    mm(from.x),
                    mm(from.y),
                    mm(3.0 / k)
                );
                if len < 1e-6 {
                    continue;
                }
                let u = d / len;
                let n = Vec2::new(-u.y, u.x);
                let back = *to - u * head.min(len);
                let _ = writeln!(
                    arrows,
                    r##"<line x1="{}" y1="{}" x2="{}" y2="{}"/>"##,
                    mm(from.x),
                    mm(from.y),
                    mm(back.x),
                    mm(back.y)
                );
                let (l, r) = (back + n * head * 0.45, back - n * head * 0.45);
                let _ = writeln!(
                    arrows,
                    r##"<polygon points="{} {} {}" fill="#111"/>"##,
                    pt(*to),
                    pt(l),
                    pt(r)
                );
            }
            Op::Fix(v) => {
                let h = 5.0 / k;
                for p in v {
                    let _ = writeln!(
                        fixed,
                        r##"<rect x="{}" y="{}" width="{}" height="{}"/>"##,
                        mm(p.x - h),
                        mm(p.y - h),
                        mm(2.0 * h),
                        mm(2.0 * h)
                    );
                }
            }
            _ => {}
        }
    }
    if !arrows.is_empty() {
        let _ = writeln!(
            s,
            r##"<g id="drags" stroke="#111" stroke-width="{}">"##,
            w(2.2)
        );
        s.push_str(&arrows);
        s.push_str("</g>\n");
    }
    if !fixed.is_empty() {
        let _ = writeln!(
            s,
            r##"<g id="fixed" fill="{FIXED_BLUE}" fill-opacity="0.25" stroke="{FIXED_BLUE}" stroke-width="{}">"##,
            w(2.0)
        );
        s.push_str(&fixed);
        s.push_str("</g>\n");
    }
}

fn collisions(s: &mut String, o: &Outcome, k: f64, w: &impl Fn(f64) -> String) {
    let r = mm(6.0 / k);
    let _ = writeln!(
        s,
        r##"<g id="collisions-before" fill="none" stroke="{COLLISION_RED}" stroke-width="{}">"##,
        w(1.6)
    );
    for e in &o.collisions_before.events {
        let p = e.closest.place();
        let _ = writeln!(
            s,
            r##"<circle cx="{}" cy="{}" r="{r}"/>"##,
            mm(p.x),
            mm(p.y)
        );
    }
    s.push_str("</g>\n");
    let _ = writeln!(
        s,
        r##"<g id="collisions-after" fill="{COLLISION_RED}" stroke="#7a0000" stroke-width="{}">"##,
        w(0.8)
    );
    let r = mm(4.0 / k);
    for e in &o.collisions_after.events {
        let p = e.closest.place();
        let _ = writeln!(
            s,
            r##"<circle cx="{}" cy="{}" r="{r}"/>"##,
            mm(p.x),
            mm(p.y)
        );
    }
    s.push_str("</g>\n");
}

fn axes(s: &mut String, lo: Vec2, hi: Vec2, k: f64, ph: f64) {
    let px = |x: f64| LEFT_PX + (x - lo.x) * k;
    let py = |y: f64| TOP_PX + (hi.y - y) * k;
    let step = nice_step((hi.x - lo.x).max(hi.y - lo.y), 10.0);
    let label = |v: f64| {
        let v = if v.abs() < step * 1e-6 { 0.0 } else { v };
        if step >= 1.0 {
            format!("{v:.0}")
        } else {
            format!("{v:.1}")
        }
    };
    let _ = writeln!(s, r##"<g id="axes" fill="#333" stroke="#333">"##);
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT_PX:.1}" y="{TOP_PX:.1}" width="{:.1}" height="{ph:.1}" fill="none" stroke-width="1"/>"##,
        (hi.x - lo.x) * k
    );
    let mut x = (lo.x / step).ceil() * step;
    while x <= hi.x {
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><text x="{:.1}" y="{:.1}" stroke="none" text-anchor="middle">{}</text>"##,
            px(x),
            TOP_PX + ph,
            px(x),
            TOP_PX + ph + 5.0,
            px(x),
            TOP_PX + ph + 19.0,
            label(x)
        );
        x += step;
    }
    let mut y = (lo.y / step).ceil() * step;
    while y <= hi.y {
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><text x="{:.1}" y="{:.1}" stroke="none" text-anchor="end">{}</text>"##,
            LEFT_PX - 5.0,
            py(y),
            LEFT_PX,
            py(y),
            LEFT_PX - 8.0,
            py(y) + 4.0,
            label(y)
        );
        y += step;
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" stroke="none" text-anchor="middle">x (m)</text><text x="14" y="{:.1}" stroke="none" transform="rotate(-90 14 {:.1})" text-anchor="middle">y (m)</text>"##,
        LEFT_PX + (hi.x - lo.x) * k / 2.0,
        TOP_PX + ph + 34.0,
        TOP_PX + ph / 2.0,
        TOP_PX + ph / 2.0
    );
    s.push_str("</g>\n");
}

fn legend(s: &mut String, o: &Outcome, threshold_m: f64, t0: f64, t1: f64, at_s: &[f64], top: f64) {
    let _ = writeln!(s, r##"<g id="legend" fill="#333">"##);
    // The time scale.
    let (x0, bw, bh) = (LEFT_PX, 240.0, 10.0);
    let _ = writeln!(
        s,
        r##"<defs><linearGradient id="time-scale">{}</linearGradient></defs>"##,
        (0..TIME_STOPS.len())
            .map(|i| {
                let f = i as f64 / (TIME_STOPS.len() - 1) as f64;
                format!(
                    r##"<stop offset="{:.2}" stop-color="{}"/>"##,
                    f,
                    time_colour(f)
                )
            })
            .collect::<String>()
    );
    let _ = writeln!(
        s,
        r##"<text x="{x0:.1}" y="{:.1}">time after the edit (s)</text>"##,
        top + 6.0
    );
    let _ = writeln!(
        s,
        r##"<rect x="{x0:.1}" y="{:.1}" width="{bw:.0}" height="{bh:.0}" fill="url(#time-scale)"/>"##,
        top + 12.0
    );
    for f in [0.0, 0.5, 1.0] {
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">{:.1}</text>"##,
            x0 + f * bw,
            top + 12.0 + bh + 13.0,
            t0 + f * (t1 - t0)
        );
    }
    // Symbols.
    // Each key is drawn at x = 0 and moved into place.
    let mut at = x0 + bw + 30.0;
    let (x, y) = (0.0_f64, top + 17.0);
    let mut key = |s: &mut String, symbol: String, text: &str| {
        let _ = writeln!(
            s,
            r##"<g transform="translate({at:.1} 0)">{symbol}<text x="24" y="{:.1}" font-size="12">{text}</text></g>"##,
            y + 4.0
        );
        at += 32.0 + 6.7 * text.chars().count() as f64;
    };
    let line = |x: f64, attrs: &str| {
        format!(
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" {attrs}/>"##,
            x,
            x + 20.0
        )
    };
    key(
        s,
        line(x, r##"stroke="#b4b4b4" stroke-width="1.5""##),
        "before",
    );
    if !o.report.drags.is_empty() {
        key(
            s,
            line(
                x,
                &format!(r##"stroke="{CAGE_COLOUR}" stroke-width="1.4" stroke-dasharray="6 4""##),
            ),
            "cage at rest",
        );
        key(
            s,
            line(
                x,
                &format!(r##"stroke="{CAGE_COLOUR}" stroke-width="1.8""##),
            ),
            "deformed",
        );
        key(s, line(x, r##"stroke="#111" stroke-width="2.2""##), "drag");
    }
    if o.script.ops.iter().any(|(op, _)| matches!(op, Op::Fix(_))) {
        key(
            s,
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="{FIXED_BLUE}" fill-opacity="0.25" stroke="{FIXED_BLUE}" stroke-width="2"/>"##,
                x + 5.0,
                y - 5.0
            ),
            "fixed",
        );
    }
    key(
        s,
        format!(
            r##"<circle cx="{:.1}" cy="{y:.1}" r="6" fill="none" stroke="{COLLISION_RED}" stroke-width="1.6"/>"##,
            x + 10.0
        ),
        "collision before",
    );
    key(
        s,
        format!(
            r##"<circle cx="{:.1}" cy="{y:.1}" r="4" fill="{COLLISION_RED}" stroke="#7a0000" stroke-width="0.8"/>"##,
            x + 10.0
        ),
        "after",
    );
    if !at_s.is_empty() {
        key(
            s,
            format!(
                r##"<circle cx="{:.1}" cy="{y:.1}" r="3.5" fill="#ffffff" stroke="#777"/><circle cx="{:.1}" cy="{y:.1}" r="3.5" fill="{}" stroke="#222"/>"##,
                x + 4.0,
                x + 15.0,
                time_colour(0.5)
            ),
            &format!(
                "at {} s: before, after",
                at_s.iter()
                    .map(|t| format!("{t}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    let retimed = if o.report.retimes > 0 {
        format!("; {} retime(s)", o.report.retimes)
    } else {
        String::new()
    };
    let inside = o
        .obstacles
        .as_ref()
        .map(|(_, r, _)| {
            format!(
                "; samples in obstacles: {} before, {} after",
                r.samples_inside_before, r.samples_inside_after
            )
        })
        .unwrap_or_default();
    let _ = writeln!(
        s,
        r##"<text id="summary" x="{x0:.1}" y="{:.1}" font-size="12">{} people, {} drag(s){retimed}; pairs closer than {} m: {} before, {} after; speeds {:.0}–{:.0} % of the input{inside}</text>"##,
        top + 56.0,
        o.after.tracks.len(),
        o.report.drags.len(),
        threshold_m,
        o.collisions_before.pair_count(),
        o.collisions_after.pair_count(),
        100.0 * o.speed.0,
        100.0 * o.speed.1
    );
    s.push_str("</g>\n");
}
