//! Target points sampled inside a formation (formation-transform section 3.1):
//! "appropriate sampling densities den_x and den_y" give a grid of points in the
//! shape close to the asked count; "randomly deleting some sampled points or adding
//! some formation points according to the Roulette Wheel Selection strategy" makes
//! the count exact; a force-based relaxation then spreads the points evenly (the
//! paper calls the grid result "very rigid, lacking the aesthetic effect").
//!
//! Everything runs in the formation's normalised frame (area 1) and is laid out at
//! the placement at the end, so the region's cell index built with the formation
//! serves every inside test and boundary projection.

use super::shapes::{Formation, Placement};
use crate::geom::Vec2;
use crate::rng::SplitMix64;

/// How points are sampled in a shape.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SampleParams {
    /// Two points closer than this do not fit (m): usually two agent radii.
    pub min_spacing_m: f64,
    /// Iterations of the force-based relaxation (at least; more run, up to four
    /// times as many plus 100, while two points are closer than `min_spacing_m`).
    pub relax_iterations: u32,
}

impl Default for SampleParams {
    /// 0.5 m apart (two agents of radius 0.25 m), 60 relaxation steps.
    fn default() -> Self {
        SampleParams {
            min_spacing_m: 0.5,
            relax_iterations: 60,
        }
    }
}

/// Why a shape could not be sampled.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// More agents than fit at the minimum spacing.
    #[error("{agents} agents do not fit in formation `{name}` ({area_m2:.2} m²) at {spacing_m} m apart: at most {fit} do")]
    TooMany {
        /// The formation.
        name: String,
        /// Asked for.
        agents: usize,
        /// What fits.
        fit: usize,
        /// Its area (m²).
        area_m2: f64,
        /// The spacing (m).
        spacing_m: f64,
    },
}

/// How many points of a hexagonal packing at `spacing_m` the area holds: each takes
/// `√3/2 · spacing²`. `usize::MAX` for a spacing that is not finite and positive.
pub fn hex_fit(area_m2: f64, spacing_m: f64) -> usize {
    if !(spacing_m > 0.0 && spacing_m.is_finite()) {
        return usize::MAX;
    }
    let f = area_m2 / (0.5 * 3f64.sqrt() * spacing_m * spacing_m);
    if f.is_finite() && f >= 0.0 {
        f.floor().min(usize::MAX as f64 / 2.0) as usize
    } else {
        0
    }
}

/// Points bucketed into square cells (counting sort), rebuilt in place.
#[derive(Default)]
struct CellGrid {
    lo: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    fill: Vec<u32>,
    items: Vec<u32>,
}

impl CellGrid {
    fn build(&mut self, pts: &[Vec2], lo: Vec2, hi: Vec2, cell: f64) {
        self.lo = lo;
        self.cell = cell;
        let ext = hi - lo;
        // Cells beyond 1024 a side would only cost memory: points share them.
        self.nx = ((ext.x / cell).floor() as usize + 1).clamp(1, 1024);
        self.ny = ((ext.y / cell).floor() as usize + 1).clamp(1, 1024);
        self.start.clear();
        self.start.resize(self.nx * self.ny + 1, 0);
        for p in pts {
            let k = self.key(*p);
            self.start[k + 1] += 1;
        }
        for i in 1..self.start.len() {
            self.start[i] += self.start[i - 1];
        }
        self.items.clear();
        self.items.resize(pts.len(), 0);
        self.fill.clear();
        self.fill.extend_from_slice(&self.start);
        for (i, p) in pts.iter().enumerate() {
            let k = self.key(*p);
            self.items[self.fill[k] as usize] = i as u32;
            self.fill[k] += 1;
        }
    }

    fn xy(&self, p: Vec2) -> (usize, usize) {
        let x = ((p.x - self.lo.x) / self.cell).floor().max(0.0) as usize;
        let y = ((p.y - self.lo.y) / self.cell).floor().max(0.0) as usize;
        (x.min(self.nx - 1), y.min(self.ny - 1))
    }

    fn key(&self, p: Vec2) -> usize {
        let (x, y) = self.xy(p);
        y * self.nx + x
    }

    /// Calls `f` with every point index in the cells within `r` cells of `p`'s.
    fn near(&self, p: Vec2, r: usize, mut f: impl FnMut(usize)) {
        let (x, y) = self.xy(p);
        for cy in y.saturating_sub(r)..=(y + r).min(self.ny - 1) {
            for cx in x.saturating_sub(r)..=(x + r).min(self.nx - 1) {
                let k = cy * self.nx + cx;
                for &i in &self.items[self.start[k] as usize..self.start[k + 1] as usize] {
                    f(i as usize);
                }
            }
        }
    }
}

/// A unit direction for two points at the same place, opposite for `(i, j)` and
/// `(j, i)`.
fn split_direction(i: usize, j: usize) -> Vec2 {
    let (a, b) = (i.min(j) as u64, i.max(j) as u64);
    let h = SplitMix64::new(a.wrapping_mul(0x9e37_79b9) ^ b).unit() * std::f64::consts::TAU;
    let d = Vec2::new(h.cos(), h.sin());
    if i < j {
        d
    } else {
        -d
    }
}

impl Formation {
    /// Exactly `n` points inside the shape laid out by `place` (never in a hole):
    /// grid sampling, the count made exact by roulette-wheel removal or addition,
    /// then force-based relaxation (section 3.1). `Ok(None)` when `cancel` returned
    /// `true` (polled once per relaxation step and every 64 additions).
    /// Deterministic for a seed.
    ///
    /// # Method
    /// 1. Grid: `den_x = den_y = √(A / n)` (normalised area `A = 1`) at a random
    ///    offset; the grid points inside.
    /// 2. Too many: uniformly random ones are deleted (a roulette of equal
    ///    weights). Too few: a pool of random points inside is drawn, and each
    ///    addition is picked by roulette with weight its distance to the nearest
    ///    point already in (so gaps fill first).
    /// 3. Relaxation: every pair closer than `r = max(s_hex, 1.02 · min_spacing)`
    ///    (`s_hex = √(2A / (√3 n))`, the spacing of a hexagonal packing of the
    ///    area) is pushed apart by half the overlap each (neighbours through a cell
    ///    grid of side `r`); a point pushed out of the shape (or into a hole) is put
    ///    back just inside its nearest boundary point; a point closer than `r / 2`
    ///    to the boundary is pushed in by half the difference (during the asked
    ///    iterations only). After `relax_iterations`
    ///    steps it goes on while a pair is closer than `min_spacing_m`, up to
    ///    `4 · relax_iterations + 100` steps.
    ///
    /// When `n` is at most about 80 % of [`hex_fit`] the relaxation ends with every
    /// pair at least `min_spacing_m` apart (tested on the shipped shapes).
    ///
    /// # Complexity
    /// `O(n)` expected per relaxation step (a bounded number of neighbours, an
    /// inside test costing the edges of one index cell); the additions are
    /// `O(pool · added)`.
    ///
    /// # Errors
    /// [`SampleError::TooMany`] when `n` exceeds [`hex_fit`] of the laid-out area
    /// at `min_spacing_m`.
    pub fn sample(
        &self,
        place: &Placement,
        n: usize,
        p: &SampleParams,
        seed: u64,
        cancel: &dyn Fn() -> bool,
    ) -> Result<Option<Vec<Vec2>>, SampleError> {
        let frame = self.frame(place);
        let k = frame.2;
        let area_m2 = k * k;
        let fit = hex_fit(area_m2, p.min_spacing_m);
        if n > fit {
            return Err(SampleError::TooMany {
                name: self.name().to_string(),
                agents: n,
                fit,
                area_m2,
                spacing_m: p.min_spacing_m,
            });
        }
        if n == 0 {
            return Ok(Some(Vec::new()));
        }
        let d = if p.min_spacing_m > 0.0 && p.min_spacing_m.is_finite() {
            p.min_spacing_m / k
        } else {
            0.0
        };
        let mut rng = SplitMix64::new(seed);
        let Some(mut pts) = self.grid_sample(n, &mut rng, cancel) else {
            return Ok(None);
        };
        if !self.relax(&mut pts, d, p.relax_iterations, cancel) {
            return Ok(None);
        }
        Ok(Some(
            pts.into_iter()
                .map(|q| self.to_world(place, frame, q))
                .collect(),
        ))
    }

    /// Steps 1 and 2: exactly `n` points inside (normalised frame). `None` when
    /// cancelled.
    fn grid_sample(
        &self,
        n: usize,
        rng: &mut SplitMix64,
        cancel: &dyn Fn() -> bool,
    ) -> Option<Vec<Vec2>> {
        let (lo, hi) = self.index.bounds();
        let g = (1.0 / n as f64).sqrt();
        let off = Vec2::new(rng.unit() * g, rng.unit() * g);
        let mut pts = Vec::with_capacity(n);
        let (nx, ny) = (
            ((hi.x - lo.x) / g).ceil() as usize + 1,
            ((hi.y - lo.y) / g).ceil() as usize + 1,
        );
        for j in 0..ny {
            for i in 0..nx {
                let q = lo + off + Vec2::new(i as f64 * g, j as f64 * g);
                if self.index.inside(q) {
                    pts.push(q);
                }
            }
        }
        // Deletion: a roulette wheel of equal weights.
        while pts.len() > n {
            let i = ((rng.unit() * pts.len() as f64) as usize).min(pts.len() - 1);
            pts.swap_remove(i);
        }
        let need = n - pts.len();
        if need == 0 {
            return Some(pts);
        }
        // Addition: a pool of random points inside, weighted by their distance to
        // the nearest point in (capped at 2 g).
        let pool_size = (4 * need).clamp(256, 20_000);
        let mut pool = Vec::with_capacity(pool_size);
        let mut tries = 0usize;
        while pool.len() < pool_size && tries < 10_000 * pool_size {
            tries += 1;
            let q = Vec2::new(rng.uniform(lo.x, hi.x), rng.uniform(lo.y, hi.y));
            if self.index.inside(q) {
                pool.push(q);
            }
        }
        let mut grid = CellGrid::default();
        grid.build(&pts, lo, hi, g);
        let cap = 2.0 * g;
        let mut weight: Vec<f64> = pool
            .iter()
            .map(|&c| {
                let mut best = cap;
                if !pts.is_empty() {
                    grid.near(c, 2, |i| best = best.min((pts[i] - c).norm()));
                }
                best
            })
            .collect();
        for added in 0..need {
            if added % 64 == 63 && cancel() {
                return None;
            }
            let total: f64 = weight.iter().sum();
            let pick = if total > 0.0 {
                let mut r = rng.unit() * total;
                let mut pick = weight.len() - 1;
                for (i, &w) in weight.iter().enumerate() {
                    if r < w {
                        pick = i;
                        break;
                    }
                    r -= w;
                }
                Some(pick)
            } else {
                None
            };
            let q = match pick {
                Some(i) if !pool.is_empty() => pool[i],
                // The pool is used up (every candidate taken): a random point in.
                _ => {
                    pts[((rng.unit() * pts.len() as f64) as usize).min(pts.len() - 1)]
                        + Vec2::new(rng.uniform(-1e-6, 1e-6), rng.uniform(-1e-6, 1e-6))
                }
            };
            for (w, &c) in weight.iter_mut().zip(&pool) {
                *w = w.min((c - q).norm());
            }
            pts.push(q);
        }
        Some(pts)
    }

    /// Step 3: the relaxation, in place (normalised frame; `d` the minimum spacing
    /// in normalised units). `false` when cancelled.
    fn relax(&self, pts: &mut [Vec2], d: f64, iterations: u32, cancel: &dyn Fn() -> bool) -> bool {
        let n = pts.len();
        let s_hex = (2.0 / (3f64.sqrt() * n as f64)).sqrt();
        let r = s_hex.max(1.02 * d);
        let (lo, hi) = self.index.bounds();
        let (lo, hi) = (lo - Vec2::repeat(r), hi + Vec2::repeat(r));
        let mut grid = CellGrid::default();
        let mut disp = vec![Vec2::zeros(); n];
        let max_iter = 4 * iterations as usize + 100;
        let eps = 1e-6 * r;
        for step in 0.. {
            if cancel() {
                return false;
            }
            grid.build(pts, lo, hi, r);
            // The boundary's push stops after the asked iterations, so the ones that
            // follow only separate pairs closer than the minimum spacing.
            let wall = step < iterations as usize;
            let mut min_d = f64::INFINITY;
            for i in 0..n {
                let p = pts[i];
                let mut f = Vec2::zeros();
                grid.near(p, 1, |j| {
                    if j == i {
                        return;
                    }
                    let dv = p - pts[j];
                    let dist = dv.norm();
                    if dist < r {
                        min_d = min_d.min(dist);
                        let dir = if dist > 1e-12 * r {
                            dv / dist
                        } else {
                            split_direction(i, j)
                        };
                        f += dir * (0.5 * (r - dist));
                    }
                });
                // The boundary pushes like a neighbour outside at distance r: a
                // point closer than r / 2 is pushed in, so points do not pile up
                // against the boundary.
                let (b, bd) = if wall {
                    self.index.nearest_boundary(p)
                } else {
                    (p, 0.0)
                };
                if bd < 0.5 * r && bd > 0.0 {
                    f += (p - b) / bd * (0.5 * (0.5 * r - bd));
                }
                let len = f.norm();
                disp[i] = if len > 0.5 * r {
                    f * (0.5 * r / len)
                } else {
                    f
                };
            }
            let done = step >= iterations as usize && min_d >= d;
            if done || step >= max_iter {
                break;
            }
            for i in 0..n {
                let q = pts[i] + disp[i];
                if self.index.inside(q) {
                    pts[i] = q;
                    continue;
                }
                // Back just inside, past the nearest boundary point.
                let (b, dist) = self.index.nearest_boundary(q);
                let inward = if dist > 0.0 {
                    (b - q) / dist
                } else {
                    Vec2::zeros()
                };
                let back = b + inward * eps;
                if self.index.inside(back) {
                    pts[i] = back;
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::library::FormationLibrary;
    use super::*;

    fn place(area: f64) -> Placement {
        Placement {
            centre_m: Vec2::new(3.0, -2.0),
            heading: Vec2::new(0.6, 0.8),
            area_m2: area,
        }
    }

    /// Per point, the distance to its nearest other (brute force).
    fn nn(pts: &[Vec2]) -> Vec<f64> {
        (0..pts.len())
            .map(|i| {
                (0..pts.len())
                    .filter(|&j| j != i)
                    .map(|j| (pts[i] - pts[j]).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    fn sigma(v: &[f64]) -> f64 {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
    }

    /// Inside test on the laid-out shape, brute force over every ring.
    fn inside_world(f: &Formation, pl: &Placement, q: Vec2) -> bool {
        f.placed_pieces(pl).iter().any(|k| {
            super::super::region::inside_ring(&k.outline, q)
                && !k
                    .holes
                    .iter()
                    .any(|h| super::super::region::inside_ring(h, q))
        })
    }

    #[test]
    fn every_shipped_shape_gets_exactly_n_points_inside_and_apart() {
        let lib = FormationLibrary::shipped();
        let p = SampleParams {
            min_spacing_m: 0.5,
            relax_iterations: 40,
        };
        for name in lib.names() {
            let f = lib.get(name).unwrap();
            let pl = place(60.0);
            let fit = hex_fit(60.0, 0.5);
            for n in [1, 7, 100, fit * 8 / 10] {
                let pts = f.sample(&pl, n, &p, 11, &|| false).unwrap().unwrap();
                assert_eq!(pts.len(), n, "{name}");
                for q in &pts {
                    assert!(
                        inside_world(f, &pl, *q),
                        "{name}: {q:?} outside or in a hole"
                    );
                }
                let closest = nn(&pts).into_iter().fold(f64::INFINITY, f64::min);
                if n > 1 {
                    assert!(
                        closest >= 0.5 - 1e-9,
                        "{name} n={n}: closest pair {closest}"
                    );
                }
            }
        }
    }

    #[test]
    fn relaxation_evens_the_spacing_and_the_seed_decides() {
        // Where the roulette had to add points (σ of the nearest-neighbour distance
        // above 0; a thinned square grid keeps equal nearest distances), the
        // relaxation leaves that σ smaller.
        let lib = FormationLibrary::shipped();
        let raw = SampleParams {
            min_spacing_m: 0.0,
            relax_iterations: 0,
        };
        let relaxed = SampleParams {
            min_spacing_m: 0.0,
            relax_iterations: 60,
        };
        let pl = place(50.0);
        let mut compared = 0;
        for name in lib.names() {
            let f = lib.get(name).unwrap();
            for n in [40, 150] {
                let a = f.sample(&pl, n, &raw, 5, &|| false).unwrap().unwrap();
                let b = f.sample(&pl, n, &relaxed, 5, &|| false).unwrap().unwrap();
                let (na, nb) = (sigma(&nn(&a)), sigma(&nn(&b)));
                if na > 1e-9 {
                    compared += 1;
                    assert!(
                        nb < na,
                        "{name} n={n}: σ of nearest-neighbour distance {na} before, {nb} after"
                    );
                }
            }
        }
        assert!(compared >= 4, "only {compared} samples had points added");
        let f = lib.get("ring").unwrap();
        let b = f.sample(&pl, 150, &relaxed, 5, &|| false).unwrap().unwrap();
        assert_eq!(
            f.sample(&pl, 150, &relaxed, 5, &|| false).unwrap().unwrap(),
            b
        );
        assert_ne!(
            f.sample(&pl, 150, &relaxed, 6, &|| false).unwrap().unwrap(),
            b
        );
    }

    #[test]
    fn too_many_agents_and_cancel_are_answered() {
        let lib = FormationLibrary::shipped();
        let f = lib.get("square").unwrap();
        let p = SampleParams {
            min_spacing_m: 1.0,
            relax_iterations: 10,
        };
        // 10 m²: 10 / (√3/2) = 11.5, so 11 fit.
        assert_eq!(hex_fit(10.0, 1.0), 11);
        let e = f.sample(&place(10.0), 12, &p, 1, &|| false).unwrap_err();
        assert!(
            matches!(
                e,
                SampleError::TooMany {
                    fit: 11,
                    agents: 12,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("at most 11"));
        assert_eq!(
            f.sample(&place(10.0), 11, &p, 1, &|| false)
                .unwrap()
                .map(|v| v.len()),
            Some(11)
        );
        assert_eq!(f.sample(&place(10.0), 5, &p, 1, &|| true), Ok(None));
        assert_eq!(
            f.sample(&place(10.0), 0, &p, 1, &|| false),
            Ok(Some(vec![]))
        );
    }
}
