//! The supplementary control points of an area control (mesh-formation-control
//! section 4.2: "supplementary control points are sampled along the edges and
//! inside its convex hull. They act as soft constraints on the mesh in the same way
//! as in the line control. The mean value coordinates of these supplementary
//! control points are computed and are subsequently used to update their positions
//! throughout the lifetime of the area control").
//!
//! A hand's hull may hold few mesh vertices or none (the default mesh spacing is
//! about 0.43 m), so the samples are points anywhere in the mesh: each is held
//! through the corners of the triangle it lies in (barycentric coordinates, an ARAP
//! point constraint), and moved by its mean value coordinates in the hull.

use crate::geom::{cross, Vec2};

/// Most supplementary points one area control samples (edges and inside); a larger
/// hull gets a wider spacing instead of more points.
pub(super) const MAX_AREA_SAMPLES: usize = 192;

/// Samples are at most this fraction of the mesh's mean edge length apart, so every
/// triangle under the hand holds some.
const SAMPLES_PER_EDGE: f64 = 2.0;

/// ...and at most this fraction of the hull's smaller extent apart, so a small hand
/// on a coarse mesh still holds a few rows of them.
const SAMPLES_ACROSS_HULL: f64 = 4.0;

/// The spacing of an area control's samples (m): the finer of half a mesh edge and
/// a quarter of the hull's smaller extent, widened until the count estimate fits
/// [`MAX_AREA_SAMPLES`].
pub(super) fn sample_spacing(hull: &[Vec2], mesh_spacing_m: f64) -> f64 {
    let (lo, hi) = bounds(hull);
    let extent = (hi - lo).min();
    let mut h = (mesh_spacing_m / SAMPLES_PER_EDGE).min(extent / SAMPLES_ACROSS_HULL);
    if !(h.is_finite() && h > 0.0) {
        h = mesh_spacing_m.max(1e-3);
    }
    let (area, perimeter) = area_perimeter(hull);
    while area / (h * h) + perimeter / h > MAX_AREA_SAMPLES as f64 {
        h *= 1.25;
    }
    h
}

/// Samples the convex polygon `hull` every `h` metres: its vertices, points along
/// its edges, and a square lattice inside it; at most [`MAX_AREA_SAMPLES`], into
/// `out` (cleared first; no allocation once it has the capacity).
pub(super) fn sample_hull(hull: &[Vec2], h: f64, out: &mut Vec<Vec2>) {
    out.clear();
    let n = hull.len();
    for i in 0..n {
        let (a, b) = (hull[i], hull[(i + 1) % n]);
        // (Less a hair, so an edge of a whole number of steps is not cut once more.)
        let steps = ((b - a).norm() / h - 1e-9).ceil().max(1.0) as usize;
        for j in 0..steps {
            if out.len() < MAX_AREA_SAMPLES {
                out.push(a + (b - a) * (j as f64 / steps as f64));
            }
        }
    }
    let (lo, hi) = bounds(hull);
    let (nx, ny) = (
        ((hi.x - lo.x) / h + 1e-9).floor() as usize,
        ((hi.y - lo.y) / h + 1e-9).floor() as usize,
    );
    // Centre the lattice in the bounding box.
    let start = lo + Vec2::new(hi.x - lo.x - nx as f64 * h, hi.y - lo.y - ny as f64 * h) * 0.5;
    for iy in 0..=ny {
        for ix in 0..=nx {
            let p = start + Vec2::new(ix as f64, iy as f64) * h;
            if out.len() < MAX_AREA_SAMPLES && strictly_inside(hull, p, 0.25 * h) {
                out.push(p);
            }
        }
    }
}

/// The mesh triangles (indices into `tris`) whose bounding box meets the box of
/// `hull` on the pose `verts`, into `out` (cleared first).
pub(super) fn candidate_triangles(
    tris: &[[u32; 3]],
    verts: &[Vec2],
    hull: &[Vec2],
    out: &mut Vec<u32>,
) {
    out.clear();
    let (lo, hi) = bounds(hull);
    for (k, t) in tris.iter().enumerate() {
        let (a, b, c) = (
            verts[t[0] as usize],
            verts[t[1] as usize],
            verts[t[2] as usize],
        );
        let tlo = a.inf(&b).inf(&c);
        let thi = a.sup(&b).sup(&c);
        if tlo.x <= hi.x && tlo.y <= hi.y && thi.x >= lo.x && thi.y >= lo.y {
            out.push(k as u32);
        }
    }
}

/// The triangle among `candidates` that holds `p` on the pose `verts`, and `p`'s
/// barycentric coordinates in it; `None` off the mesh or in degenerate triangles
/// only.
pub(super) fn locate(
    tris: &[[u32; 3]],
    candidates: &[u32],
    verts: &[Vec2],
    p: Vec2,
) -> Option<([u32; 3], [f64; 3])> {
    const EDGE_TOLERANCE: f64 = 1e-9;
    for &k in candidates {
        let t = tris[k as usize];
        let (a, b, c) = (
            verts[t[0] as usize],
            verts[t[1] as usize],
            verts[t[2] as usize],
        );
        let area2 = cross(b - a, c - a);
        if area2.abs() < 1e-15 {
            continue;
        }
        let la = cross(b - p, c - p) / area2;
        let lb = cross(c - p, a - p) / area2;
        let lc = 1.0 - la - lb;
        if la >= -EDGE_TOLERANCE && lb >= -EDGE_TOLERANCE && lc >= -EDGE_TOLERANCE {
            return Some((t, [la, lb, lc]));
        }
    }
    None
}

fn bounds(pts: &[Vec2]) -> (Vec2, Vec2) {
    pts.iter().fold(
        (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    )
}

fn area_perimeter(poly: &[Vec2]) -> (f64, f64) {
    let n = poly.len();
    let (mut a2, mut per) = (0.0, 0.0);
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        a2 += cross(p, q);
        per += (q - p).norm();
    }
    (0.5 * a2.abs(), per)
}

/// Whether `p` is inside the convex polygon and at least `margin` from its edges.
fn strictly_inside(poly: &[Vec2], p: Vec2, margin: f64) -> bool {
    let n = poly.len();
    let orientation = {
        let mut a2 = 0.0;
        for i in 0..n {
            a2 += cross(poly[i], poly[(i + 1) % n]);
        }
        a2.signum()
    };
    (0..n).all(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let e = b - a;
        let len = e.norm();
        len > 0.0 && orientation * cross(e, p - a) / len >= margin
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(c: Vec2, r: f64) -> Vec<Vec2> {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .iter()
            .map(|&(x, y)| c + Vec2::new(x, y) * r)
            .collect()
    }

    #[test]
    fn a_small_hull_on_a_coarse_mesh_gets_rows_of_samples_on_and_inside_it() {
        let hull = square(Vec2::new(2.0, 1.0), 0.1);
        let h = sample_spacing(&hull, 0.43);
        assert!((h - 0.05).abs() < 1e-12, "{h}");
        let mut out = Vec::new();
        sample_hull(&hull, h, &mut out);
        let inside = out
            .iter()
            .filter(|p| strictly_inside(&hull, **p, 1e-9))
            .count();
        assert_eq!(out.len() - inside, 16, "4 edges of 4 steps");
        assert!(inside >= 9, "{inside} inside");
        for p in &out {
            assert!(crate::crowd::mesh::point_in_convex_polygon(&hull, *p));
        }
    }

    #[test]
    fn a_large_hull_is_capped() {
        let hull = square(Vec2::new(0.0, 0.0), 5.0);
        let h = sample_spacing(&hull, 0.43);
        let mut out = Vec::new();
        sample_hull(&hull, h, &mut out);
        assert!(out.len() <= MAX_AREA_SAMPLES && out.len() > MAX_AREA_SAMPLES / 2);
    }

    #[test]
    fn locate_finds_the_triangle_and_its_coordinates() {
        let verts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
        ];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let mut cand = Vec::new();
        candidate_triangles(&tris, &verts, &square(Vec2::new(0.8, 0.8), 0.05), &mut cand);
        assert_eq!(cand, vec![0, 1]);
        let p = Vec2::new(0.8, 0.7);
        let (t, b) = locate(&tris, &cand, &verts, p).expect("on the mesh");
        assert_eq!(t, [1, 3, 2]);
        let q = verts[1] * b[0] + verts[3] * b[1] + verts[2] * b[2];
        assert!((q - p).norm() < 1e-12);
        assert!(locate(&tris, &cand, &verts, Vec2::new(1.5, 0.5)).is_none());
    }
}
