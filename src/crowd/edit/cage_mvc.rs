//! Mean value coordinates of many points w.r.t. one cage polygon (crowd-motion-editing
//! section 3.2, eq. 4's rows): the per-polygon checks done once and the rows written
//! into a matrix a block at a time.

use crate::crowd::mesh::{MVC_EDGE_EPS, MVC_VERTEX_EPS};
use crate::geom::Vec2;
use nalgebra::DMatrix;

/// Mean value coordinates w.r.t. one polygon, with the per-polygon checks (finite,
/// not degenerate, the vertex tolerance) done once for [`mvc_matrix`]; a point it
/// cannot do in a block gets [`crate::crowd::mesh::mean_value_coordinates`].
pub(super) struct HullMvc<'a> {
    poly: &'a [Vec2],
    /// `MVC_VERTEX_EPS` × the polygon's bounding-box diagonal.
    vertex_eps: f64,
}

impl<'a> HullMvc<'a> {
    /// `None` when `mean_value_coordinates` would fail for every point: fewer than
    /// three vertices, a non-finite vertex, or a degenerate bounding box.
    pub(super) fn new(poly: &'a [Vec2]) -> Option<HullMvc<'a>> {
        if poly.len() < 3 || !poly.iter().all(|v| finite(*v)) {
            return None;
        }
        let (mut lo, mut hi) = (poly[0], poly[0]);
        for v in poly {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        let scale = (hi - lo).norm();
        if scale.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        Some(HullMvc {
            poly,
            vertex_eps: MVC_VERTEX_EPS * scale,
        })
    }

    /// The coordinates of `p` into `out` (of the polygon's length): those of
    /// [`crate::crowd::mesh::mean_value_coordinates`] (one-hot on a vertex, linear on
    /// an edge); `None` where it returns an error.
    pub(super) fn coordinates(&self, p: Vec2, out: &mut [f64]) -> Option<()> {
        crate::crowd::mesh::mean_value_coordinates(self.poly, p, out).ok()
    }
}

pub(super) fn finite(p: Vec2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

/// Samples per block of [`mvc_matrix`]: the inner loops run over a block's samples,
/// which the compiler vectorises.
const BLOCK: usize = 16;

/// The MVC of every point of `points` w.r.t. `poly` (N × n), or the index of the first
/// point whose coordinates are undefined.
///
/// # Formula
/// [`HullMvc::coordinates`], computed for [`BLOCK`] samples at once, one hull vertex
/// at a time (structure of arrays), with each `1 / r_i` and `1 / Σw` computed once and
/// multiplied (one division per sample and vertex instead of three): the same
/// coordinates to within a few units in the last place (a test holds them to 1e-13
/// of the per-point formula). A sample on a vertex or an edge, or whose weights are
/// not finite, is redone by [`HullMvc::coordinates`].
///
/// # Complexity
/// O(N n).
pub(super) fn mvc_matrix(mvc: &HullMvc<'_>, points: &[Vec2]) -> Result<DMatrix<f64>, usize> {
    let poly = mvc.poly;
    let n = poly.len();
    let mut t = DMatrix::zeros(points.len(), n);
    // r[i * BLOCK + k] = ‖v_i − p_k‖, w[i * BLOCK + k] the unnormalised weight.
    let mut r = vec![0.0; n * BLOCK];
    // 1 / r: one division per sample and vertex instead of three.
    let mut inv_r = vec![0.0; n * BLOCK];
    let mut w = vec![0.0; n * BLOCK];
    let mut row = vec![0.0; n];
    for (b, block) in points.chunks(BLOCK).enumerate() {
        let i0 = b * BLOCK;
        let (mut px, mut py) = ([0.0; BLOCK], [0.0; BLOCK]);
        for k in 0..BLOCK {
            // The tail block repeats its last point; the extra rows are not written.
            let p = block[k.min(block.len() - 1)];
            px[k] = p.x;
            py[k] = p.y;
        }
        let mut redo = [false; BLOCK];
        for (i, v) in poly.iter().enumerate() {
            let ri = &mut r[i * BLOCK..(i + 1) * BLOCK];
            let inv = &mut inv_r[i * BLOCK..(i + 1) * BLOCK];
            for k in 0..BLOCK {
                let (dx, dy) = (v.x - px[k], v.y - py[k]);
                ri[k] = (dx * dx + dy * dy).sqrt();
                inv[k] = 1.0 / ri[k];
                redo[k] |= ri[k] <= mvc.vertex_eps;
            }
        }
        let mut tan_prev = [0.0; BLOCK];
        for i in 0..n {
            let j = if i + 1 == n { 0 } else { i + 1 };
            let (vi, vj) = (poly[i], poly[j]);
            for k in 0..BLOCK {
                let (dix, diy) = (vi.x - px[k], vi.y - py[k]);
                let (djx, djy) = (vj.x - px[k], vj.y - py[k]);
                let (ri, rj) = (r[i * BLOCK + k], r[j * BLOCK + k]);
                let a = dix * djy - diy * djx;
                let d = dix * djx + diy * djy;
                let rr = ri * rj;
                redo[k] |= a.abs() <= MVC_EDGE_EPS * rr && d < 0.0;
                let (num, den) = if d >= 0.0 { (a, rr + d) } else { (rr - d, a) };
                let tk = num / den;
                let prev = if i > 0 { tan_prev[k] } else { 0.0 };
                w[i * BLOCK + k] = (tk + prev) * inv_r[i * BLOCK + k];
                tan_prev[k] = tk;
            }
        }
        let mut sum = [0.0; BLOCK];
        for k in 0..BLOCK {
            w[k] += tan_prev[k] * inv_r[k];
        }
        for i in 0..n {
            for k in 0..BLOCK {
                sum[k] += w[i * BLOCK + k];
            }
        }
        let mut inv_sum = [0.0; BLOCK];
        for k in 0..BLOCK {
            redo[k] |= !(sum[k].is_finite() && sum[k] != 0.0);
            inv_sum[k] = 1.0 / sum[k];
        }
        for i in 0..n {
            let col = &mut t.column_mut(i);
            for k in 0..block.len() {
                let v = w[i * BLOCK + k] * inv_sum[k];
                redo[k] |= !v.is_finite();
                col[i0 + k] = v;
            }
        }
        for (k, p) in block.iter().enumerate() {
            if redo[k] {
                mvc.coordinates(*p, &mut row).ok_or(i0 + k)?;
                for (i, v) in row.iter().enumerate() {
                    t[(i0 + k, i)] = *v;
                }
            }
        }
    }
    Ok(t)
}
