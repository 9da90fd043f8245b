//! The edit picture's layers in world metres: the grid, the scene's obstacles, the
//! tracks before and after (thinned, the after ones banded by time), the cages and
//! their meshes, the positions at given instants, the drags and fixed places, and
//! the collisions before and after.

use super::edit_apply::Outcome;
use super::edit_render_svg::{
    mm, nice_step, pt, time_colour, CAGE_COLOUR, COLLISION_RED, FIXED_BLUE, MAX_POINTS,
    MAX_TRACK_POINTS, OBSTACLE_FILL, TIME_BANDS,
};
use crowdtouch::crowd::edit::{Op, Track, TrackSet};
use crowdtouch::crowd::environment::Part;
use crowdtouch::geom::Vec2;
use std::fmt::Write;

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

pub fn grid(s: &mut String, lo: Vec2, hi: Vec2, k: f64) {
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

pub fn obstacles(s: &mut String, o: &Outcome, lo: Vec2, hi: Vec2, w: &impl Fn(f64) -> String) {
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
pub fn tracks_before(s: &mut String, o: &Outcome, w: &impl Fn(f64) -> String) {
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
pub fn tracks_after(s: &mut String, o: &Outcome, t0: f64, t1: f64, w: &impl Fn(f64) -> String) {
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

pub fn cages(s: &mut String, o: &Outcome, w: &impl Fn(f64) -> String) {
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

pub fn instants(s: &mut String, o: &Outcome, at_s: &[f64], t0: f64, t1: f64, k: f64) {
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

pub fn drags_and_fixes(s: &mut String, o: &Outcome, k: f64, w: &impl Fn(f64) -> String) {
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

pub fn collisions(s: &mut String, o: &Outcome, k: f64, w: &impl Fn(f64) -> String) {
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
