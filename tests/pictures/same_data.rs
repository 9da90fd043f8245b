//! Whether two pictures show the same data: the same shapes of each kind, each
//! within a tolerance of one of the other, whatever their order, grouping or style.
//!
//! Shapes are matched as multisets. Two shapes can match when they are of one kind
//! with the same number of points, both rings or both open, with the same text,
//! and every point of one is within the tolerance (in x and in y) of the
//! corresponding point of the other. A line may be written in either direction and
//! a ring may start at any vertex; circles, rects and texts compare point by point.
//! Candidates are found through a grid over the shapes' key points
//! ([`Shape::key`], which moves no more than the points do), and a maximum matching
//! (augmenting paths from a greedy start) pairs them, so close duplicates cannot
//! steal each other's partners.

use super::svg_shapes::{Kind, Point, Shape};
use std::collections::HashMap;

/// The default tolerance: coordinates rounded to a tenth of a pixel on one side
/// and to a millimetre at 100 px/m on the other differ by at most 0.1 px.
pub const TOLERANCE_PX: f64 = 0.15;

/// Side of the grid cells candidates are looked up in; at least twice the
/// tolerance, so the 3 × 3 cells around a key hold every candidate.
const CELL_PX: f64 = 1.0;

/// How many unmatched shapes of each kind and side a report lists.
const SHOWN: usize = 5;

/// The shapes of one kind that found no partner.
#[derive(Debug)]
pub struct KindDifference {
    pub kind: Kind,
    pub reference_count: usize,
    pub now_count: usize,
    /// Indices into the reference's shapes.
    pub only_reference: Vec<usize>,
    /// Indices into the new picture's shapes.
    pub only_now: Vec<usize>,
}

/// What sets two shapes apart before any coordinate is read.
#[derive(Clone, PartialEq, Eq, Hash)]
struct Group {
    kind: Kind,
    closed: bool,
    points: usize,
    text: String,
}

fn group(s: &Shape) -> Group {
    Group {
        kind: s.kind,
        closed: s.closed,
        points: s.points.len(),
        text: s.text.clone(),
    }
}

fn cell((x, y): Point) -> (i64, i64) {
    ((x / CELL_PX).floor() as i64, (y / CELL_PX).floor() as i64)
}

fn off((ax, ay): Point, (bx, by): Point) -> f64 {
    (ax - bx).abs().max((ay - by).abs())
}

/// How far apart two shapes of one group are: the largest coordinate difference of
/// corresponding points, under the best correspondence (either direction of a
/// line, any start and direction of a ring). Ring alignments whose first points
/// are farther apart than `bound` are not tried (`f64::INFINITY` tries all).
pub fn deviation(a: &Shape, b: &Shape, bound: f64) -> f64 {
    let (p, q) = (&a.points, &b.points);
    if p.len() != q.len() {
        return f64::INFINITY;
    }
    let n = p.len();
    let along = |map: &dyn Fn(usize) -> usize| -> f64 {
        let mut worst = 0.0f64;
        for (i, &pi) in p.iter().enumerate() {
            worst = worst.max(off(pi, q[map(i)]));
            if worst > bound {
                return worst;
            }
        }
        worst
    };
    match (a.kind, a.closed) {
        (Kind::Line, false) => along(&|i| i).min(along(&|i| n - 1 - i)),
        (Kind::Line, true) => {
            let mut best = f64::INFINITY;
            for (k, &qk) in q.iter().enumerate() {
                if off(p[0], qk) > bound.min(best) {
                    continue;
                }
                best = best
                    .min(along(&|i| (k + i) % n))
                    .min(along(&|i| (k + n - i % n) % n));
            }
            best
        }
        _ => along(&|i| i),
    }
}

/// The shapes of each kind without a partner in the other picture; empty when the
/// two pictures show the same data within `tolerance` px.
pub fn differences(reference: &[Shape], now: &[Shape], tolerance: f64) -> Vec<KindDifference> {
    assert!(
        tolerance * 2.0 <= CELL_PX,
        "tolerance above the grid's reach"
    );
    // Candidates per group: the new shapes filed by cell.
    let mut grids: HashMap<Group, HashMap<(i64, i64), Vec<usize>>> = HashMap::new();
    for (j, s) in now.iter().enumerate() {
        grids
            .entry(group(s))
            .or_default()
            .entry(cell(s.key()))
            .or_default()
            .push(j);
    }
    // Edges: every reference shape to every new shape within the tolerance.
    let mut edges: Vec<Vec<usize>> = vec![Vec::new(); reference.len()];
    for (i, s) in reference.iter().enumerate() {
        let Some(grid) = grids.get(&group(s)) else {
            continue;
        };
        let (cx, cy) = cell(s.key());
        let mut found: Vec<(f64, usize)> = Vec::new();
        for gx in cx - 1..=cx + 1 {
            for gy in cy - 1..=cy + 1 {
                for &j in grid.get(&(gx, gy)).map_or(&[][..], Vec::as_slice) {
                    let d = deviation(s, &now[j], tolerance);
                    if d <= tolerance {
                        found.push((d, j));
                    }
                }
            }
        }
        // Nearest first: the greedy start then pairs the obvious partners.
        found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        edges[i] = found.into_iter().map(|(_, j)| j).collect();
    }
    let partner_of_now = maximum_matching(&edges, now.len());
    let mut matched_reference = vec![false; reference.len()];
    for i in partner_of_now.iter().flatten() {
        matched_reference[*i] = true;
    }
    let mut out = Vec::new();
    for kind in Kind::ALL {
        let only_reference: Vec<usize> = (0..reference.len())
            .filter(|&i| reference[i].kind == kind && !matched_reference[i])
            .collect();
        let only_now: Vec<usize> = (0..now.len())
            .filter(|&j| now[j].kind == kind && partner_of_now[j].is_none())
            .collect();
        if only_reference.is_empty() && only_now.is_empty() {
            continue;
        }
        out.push(KindDifference {
            kind,
            reference_count: reference.iter().filter(|s| s.kind == kind).count(),
            now_count: now.iter().filter(|s| s.kind == kind).count(),
            only_reference,
            only_now,
        });
    }
    out
}

/// A maximum matching of the bipartite graph `edges` (left `i` to right
/// `edges[i][..]`): greedy, then an augmenting path from every left vertex left
/// over (Kuhn's algorithm, with an explicit stack). Returns each right vertex's
/// partner.
fn maximum_matching(edges: &[Vec<usize>], right: usize) -> Vec<Option<usize>> {
    let mut partner_of_right: Vec<Option<usize>> = vec![None; right];
    let mut partner_of_left: Vec<Option<usize>> = vec![None; edges.len()];
    for (i, e) in edges.iter().enumerate() {
        if let Some(&j) = e.iter().find(|&&j| partner_of_right[j].is_none()) {
            partner_of_right[j] = Some(i);
            partner_of_left[i] = Some(j);
        }
    }
    let mut seen = vec![usize::MAX; right];
    for root in 0..edges.len() {
        if partner_of_left[root].is_some() || edges[root].is_empty() {
            continue;
        }
        // Depth-first search for an augmenting path: stack of (left vertex, next edge).
        let mut stack: Vec<(usize, usize)> = vec![(root, 0)];
        let mut via: Vec<usize> = Vec::new();
        let mut found = None;
        while let Some(top) = stack.len().checked_sub(1) {
            let (i, next) = stack[top];
            if next >= edges[i].len() {
                stack.pop();
                via.pop();
                continue;
            }
            stack[top].1 += 1;
            let j = edges[i][next];
            if seen[j] == root {
                continue;
            }
            seen[j] = root;
            match partner_of_right[j] {
                None => {
                    found = Some(j);
                    break;
                }
                Some(k) => {
                    via.push(j);
                    stack.push((k, 0));
                }
            }
        }
        if let Some(mut j) = found {
            // Flip the path: every left vertex on the stack takes the right vertex
            // after it.
            for depth in (0..stack.len()).rev() {
                let i = stack[depth].0;
                partner_of_right[j] = Some(i);
                let previous = partner_of_left[i].replace(j);
                if depth > 0 {
                    j = via[depth - 1];
                    debug_assert_eq!(previous, Some(j));
                }
            }
        }
    }
    partner_of_right
}

/// `Ok` when the two pictures show the same data within `tolerance` px; otherwise
/// a message naming the picture, each kind that differs, how many of its shapes
/// found no partner on each side, and the first few of them with the nearest
/// shape of the other side.
pub fn same_data(
    name: &str,
    reference: &[Shape],
    now: &[Shape],
    tolerance: f64,
) -> Result<(), String> {
    let diffs = differences(reference, now, tolerance);
    if diffs.is_empty() {
        return Ok(());
    }
    let mut m =
        format!("{name} does not show what its reference shows (tolerance {tolerance} px):\n");
    for d in &diffs {
        let kind = d.kind.as_str();
        m += &format!(
            "  {kind}: {} in the reference, {} now; {} of the reference's without a match now, {} of the new without a match in the reference\n",
            d.reference_count,
            d.now_count,
            d.only_reference.len(),
            d.only_now.len()
        );
        for &i in d.only_reference.iter().take(SHOWN) {
            m += &format!(
                "    only in the reference: {}{}\n",
                reference[i].describe(),
                nearest(&reference[i], now)
            );
        }
        if d.only_reference.len() > SHOWN {
            m += &format!("    … and {} more\n", d.only_reference.len() - SHOWN);
        }
        for &j in d.only_now.iter().take(SHOWN) {
            m += &format!(
                "    only now: {}{}\n",
                now[j].describe(),
                nearest(&now[j], reference)
            );
        }
        if d.only_now.len() > SHOWN {
            m += &format!("    … and {} more\n", d.only_now.len() - SHOWN);
        }
    }
    Err(m)
}

/// How near `o` is to `s`, to pick the shape a message shows beside an unmatched
/// one: for lines, how near `s`'s two ends come to any vertex of `o` (a line that
/// grew or shrank keeps its ends' neighbourhood, not its mean); otherwise the
/// distance of the key points.
fn proximity(s: &Shape, o: &Shape) -> f64 {
    match (s.kind, s.points.first(), s.points.last()) {
        (Kind::Line, Some(&a), Some(&b)) => {
            let to = |p: Point| {
                o.points
                    .iter()
                    .map(|&q| off(p, q))
                    .fold(f64::INFINITY, f64::min)
            };
            to(a) + to(b)
        }
        _ => off(s.key(), o.key()),
    }
}

/// "nearest on the other side: …, off by … px" for a message.
fn nearest(s: &Shape, other: &[Shape]) -> String {
    let best = other
        .iter()
        .filter(|o| o.kind == s.kind)
        .map(|o| (proximity(s, o), o))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, o)| o);
    match best {
        None => String::from("; none of its kind on the other side"),
        Some(o) => {
            let d = if group(o) == group(s) {
                format!(", off by {:.2} px", deviation(s, o, f64::INFINITY))
            } else {
                String::new()
            };
            format!("\n        nearest on the other side: {}{d}", o.describe())
        }
    }
}
