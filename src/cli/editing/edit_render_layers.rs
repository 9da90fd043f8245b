//! The edit picture's layers, drawn through the world frame: the grid, the scene's obstacles, the
//! tracks before and after (thinned, the after ones banded by time), the cages and
//! their meshes, the positions at given instants, the drags and fixed places, and
//! the collisions before and after.

use super::edit_apply::Outcome;
use super::edit_render_svg::{
    BEFORE_GREY, COLLISION_DARK, MAX_POINTS, MAX_TRACK_POINTS, MESH_EDGE, TIME_BANDS,
};
use crowdtouch::crowd::edit::{Op, Track, TrackSet};
use crowdtouch::crowd::environment::Part;
use crowdtouch::geom::Vec2;
use crowdtouch::picture::scale::{nice_step, ticks, time};
use crowdtouch::picture::{elements, style, Canvas, Frame, Paint, PathData};

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

/// Page points of a run, dropping consecutive repeats at millimetre precision.
fn run_points(f: &Frame, t: &Track, run: &[usize]) -> Vec<(f64, f64)> {
    let mm = |p: Vec2| ((p.x * 1000.0).round() as i64, (p.y * 1000.0).round() as i64);
    let mut v: Vec<(f64, f64)> = Vec::with_capacity(run.len());
    let mut last = None;
    for &j in run {
        let p = t.points[j];
        if last != Some(mm(p)) {
            last = Some(mm(p));
            v.push(f.pt(p));
        }
    }
    v
}

/// Grid lines every 1–2–5 step of the longer side (about ten of them).
pub fn grid(c: &mut Canvas, f: &Frame) {
    let w = f.world;
    let step = nice_step(w.width().max(w.height()), 10);
    let mut d = PathData::new();
    for x in ticks(w.min[0], w.max[0], step) {
        d.move_to(f.pt(Vec2::new(x, w.min[1])));
        d.line_to(f.pt(Vec2::new(x, w.max[1])));
    }
    for y in ticks(w.min[1], w.max[1], step) {
        d.move_to(f.pt(Vec2::new(w.min[0], y)));
        d.line_to(f.pt(Vec2::new(w.max[0], y)));
    }
    c.path(&d, &Paint::stroke(style::GRID, 0.8).class("grid"));
}

/// The scene's obstacles that reach into the frame.
pub fn obstacles(c: &mut Canvas, f: &Frame, o: &Outcome) {
    let Some((scene, _, _)) = &o.obstacles else {
        return;
    };
    let w = f.world;
    let paint = Paint::fill_stroke(style::OBSTACLE, style::INK, 0.8)
        .fill_opacity(0.45)
        .class("obstacle");
    c.open_group(r#"class="obstacles""#);
    for ob in scene.obstacles() {
        for part in &ob.parts {
            let bb = part.aabb();
            if bb.max[0] < w.min[0]
                || bb.min[0] > w.max[0]
                || bb.max[1] < w.min[1]
                || bb.min[1] > w.max[1]
            {
                continue;
            }
            match part {
                Part::Polygon(p) => elements::hull(c, f, p.vertices(), &paint),
                Part::Circle(d) => elements::disc(c, f, d.centre, d.radius_m, &paint),
            }
        }
    }
    c.close_group();
}

/// Tracks before, only where they differ in space from after.
pub fn tracks_before(c: &mut Canvas, f: &Frame, o: &Outcome) {
    let stride = stride_for(&o.before);
    let paint = Paint::stroke(BEFORE_GREY, 1.0).class("before");
    c.open_group(r#"class="before""#);
    for (i, t) in o.before.tracks.iter().enumerate() {
        if o.after.tracks.get(i).map(|a| &a.points) == Some(&t.points) {
            continue;
        }
        for r in runs(t, stride(t)) {
            c.polyline(run_points(f, t, &r), &paint);
        }
    }
    c.close_group();
}

/// Tracks after, split into bands of the time scale; tracks the edit did not move
/// in space are faded.
pub fn tracks_after(c: &mut Canvas, f: &Frame, o: &Outcome, t0: f64, t1: f64) {
    let set = &o.after;
    let stride = stride_for(set);
    let band = |t: f64| (((t - t0) / (t1 - t0) * TIME_BANDS as f64) as usize).min(TIME_BANDS - 1);
    // Per band, the pieces of moved and of still tracks.
    type Pieces = Vec<Vec<(f64, f64)>>;
    let mut moved: Vec<Pieces> = vec![Vec::new(); TIME_BANDS];
    let mut still: Vec<Pieces> = vec![Vec::new(); TIME_BANDS];
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
                    let pts = run_points(f, t, &piece);
                    if pts.len() >= 2 {
                        by_band[b].push(pts);
                    }
                    piece = vec![j];
                    b = bj;
                }
            }
            let pts = run_points(f, t, &piece);
            if pts.len() >= 2 {
                by_band[b].push(pts);
            }
        }
    }
    for (bands, class, opacity) in [(&still, "after-unmoved", 0.3), (&moved, "after", 1.0)] {
        for (b, pieces) in bands.iter().enumerate() {
            let colour = time((b as f64 + 0.5) / TIME_BANDS as f64);
            let paint = Paint::stroke(&colour, 1.6)
                .stroke_opacity(opacity)
                .class(class);
            for p in pieces {
                c.polyline(p.iter().copied(), &paint);
            }
        }
    }
}

/// Each drag's deformation mesh (its edges once each), its cage at rest (dashed)
/// and deformed.
pub fn cages(c: &mut Canvas, f: &Frame, o: &Outcome) {
    if o.report.drags.is_empty() {
        return;
    }
    for d in &o.report.drags {
        let mut edges: Vec<(u32, u32)> = d
            .mesh_triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut path = PathData::new();
        for (a, b) in edges {
            let (Some(&p), Some(&q)) = (
                d.mesh_vertices.get(a as usize),
                d.mesh_vertices.get(b as usize),
            ) else {
                continue;
            };
            path.move_to(f.pt(p)).line_to(f.pt(q));
        }
        c.path(&path, &Paint::stroke(MESH_EDGE, 0.4).class("cage-mesh"));
    }
    let rest = Paint::stroke(style::CAGE, 1.4)
        .dash("6 4")
        .class("cage-rest");
    for d in &o.report.drags {
        elements::hull(c, f, &d.hull_rest, &rest);
    }
    let deformed = Paint::stroke(style::CAGE, 1.8).class("cage-deformed");
    for d in &o.report.drags {
        elements::hull(c, f, &d.hull, &deformed);
    }
}

/// Everyone's position at each of `at_s`, before (white dots) and after (dots in
/// the time colour), joined where they differ.
pub fn instants(c: &mut Canvas, f: &Frame, o: &Outcome, at_s: &[f64], t0: f64, t1: f64) {
    if at_s.is_empty() {
        return;
    }
    let joint = Paint::stroke(style::PATH, 1.0).class("moved-by");
    let before = Paint::fill_stroke(style::PLOT, style::AGENT_START, 1.0).class("before-at");
    for &t in at_s {
        let after =
            Paint::fill_stroke(&time((t - t0) / (t1 - t0)), style::INK, 1.0).class("after-at");
        for (b, a) in o.before.tracks.iter().zip(&o.after.tracks) {
            let pb = b.position_at(t);
            let pa = a.position_at(t);
            if let (Some(p), Some(q)) = (pb, pa) {
                if (p - q).norm() > 0.01 {
                    c.line(f.pt(p), f.pt(q), &joint);
                }
            }
            if let Some(p) = pb {
                c.circle(f.pt(p), 3.5, &before);
            }
            if let Some(q) = pa {
                c.circle(f.pt(q), 3.5, &after);
            }
        }
    }
}

/// Each drag as a handle dot and an arrow to where it went; fixed places as squares.
pub fn drags_and_fixes(c: &mut Canvas, f: &Frame, o: &Outcome) {
    const HEAD_PX: f64 = 10.0;
    let ink = "#111111";
    let handle = Paint::fill(ink).class("handle");
    let shaft = Paint::stroke(ink, 2.2).class("drag");
    let head = Paint::fill_stroke(ink, ink, 2.2).class("drag");
    let fixed = Paint::fill_stroke(style::FIXED, style::FIXED, 2.0)
        .fill_opacity(0.25)
        .class("fixed");
    for (op, _) in &o.script.ops {
        if let Op::Drag { from, to, .. } = op {
            let (a, b) = (f.pt(*from), f.pt(*to));
            c.circle(a, 3.0, &handle);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len = dx.hypot(dy);
            if len < 1e-6 * f.px_per_m {
                continue;
            }
            let (ux, uy) = (dx / len, dy / len);
            let back_len = HEAD_PX.min(len);
            let back = (b.0 - ux * back_len, b.1 - uy * back_len);
            c.line(a, back, &shaft);
            let (nx, ny) = (-uy * HEAD_PX * 0.45, ux * HEAD_PX * 0.45);
            c.polygon(
                [b, (back.0 + nx, back.1 + ny), (back.0 - nx, back.1 - ny)],
                &head,
            );
        }
    }
    for (op, _) in &o.script.ops {
        if let Op::Fix(v) = op {
            for p in v {
                let (x, y) = f.pt(*p);
                c.rect(x - 5.0, y - 5.0, 10.0, 10.0, &fixed);
            }
        }
    }
}

/// The closest places of the collisions before (hollow rings) and after (filled).
pub fn collisions(c: &mut Canvas, f: &Frame, o: &Outcome) {
    let before = Paint::stroke(style::ALERT, 1.6).class("collision-before");
    for e in &o.collisions_before.events {
        c.circle(f.pt(e.closest.place()), 6.0, &before);
    }
    let after = Paint::fill_stroke(style::ALERT, COLLISION_DARK, 0.8).class("collision-after");
    for e in &o.collisions_after.events {
        c.circle(f.pt(e.closest.place()), 4.0, &after);
    }
}
