//! Gaussian mixtures over eigenscores (gesture-driven section 6.2: "we propose to use
//! GMM to model the distribution of the eigenscores", fitted by EM [Bis96]): fitting
//! with a fixed number of components or choosing it by BIC, the log-likelihood, and
//! sampling.
//!
//! # The fit
//! * Initialisation: k-means++ seeds drawn from [`SplitMix64`] with the caller's
//!   seed, a few Lloyd iterations, then one M-step from the hard clusters; the best
//!   of `n_init` such starts (seeds `seed`, `seed + 1`, …) is kept.
//! * EM with log-sum-exp responsibilities and Cholesky factors (nalgebra).
//! * Covariance floor: each M-step sets `Σ_k = (S_k + ρ I) / N_k` (`S_k` the
//!   component's weighted scatter, `N_k` its weight), `ρ = reg · v̄` with `v̄` the
//!   data's mean per-dimension variance (1 when the data has none). This is the exact
//!   M-step of the *penalised* log-likelihood `L(θ) − (ρ/2) Σ_k tr(Σ_k⁻¹)`, so EM
//!   never decreases that objective (tested), and no covariance can collapse onto a
//!   point even when a component holds fewer samples than dimensions (a 20-agent
//!   crowd with 15 eigenscores). With `reg = 1e-6` the penalty is far below the
//!   likelihood's rounding on ordinary data.
//! * Stop when the objective rises by less than `tol` per sample, or after
//!   `max_iter` iterations.
//! * Degenerate inputs: more components than samples fit `min(k, M)` components;
//!   identical samples fit tight components about them; zero dimensions give the one
//!   empty component; components whose weight falls below [`PRUNE_WEIGHT`] are
//!   dropped at the end.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::error::MotionError;
use crate::gesture::library::GmmComponent;
use crate::rng::SplitMix64;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Parameters of [`fit`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct GmmParams {
    /// Most EM iterations.
    pub max_iter: usize,
    /// Convergence: the objective's rise per sample below which EM stops (nats).
    pub tol: f64,
    /// Covariance floor relative to the data's mean variance (see the module doc).
    pub reg: f64,
    /// Lloyd iterations after the k-means++ seeding.
    pub kmeans_iter: usize,
    /// Initialisations tried (seeds `seed`, `seed + 1`, …); the fit of highest
    /// objective is kept. At least one is run.
    pub n_init: usize,
}

impl Default for GmmParams {
    fn default() -> GmmParams {
        GmmParams {
            max_iter: 300,
            tol: 1e-7,
            reg: 1e-6,
            kmeans_iter: 10,
            n_init: 4,
        }
    }
}

/// Components whose weight ends below this are dropped (and the rest renormalised).
pub const PRUNE_WEIGHT: f64 = 1e-12;

/// A fitted mixture and how the fit went.
#[derive(Clone, Debug, PartialEq)]
pub struct GmmFit {
    /// The mixture (weights sum to 1; covariances `d × d` row-major).
    pub components: Vec<GmmComponent>,
    /// Total log-likelihood of the samples `Σ_i ln p(x_i)` (nats).
    pub log_likelihood: f64,
    /// The penalised objective EM ascends, one value per iteration (non-decreasing).
    pub objective_history: Vec<f64>,
    /// The log-likelihood at each iteration.
    pub log_likelihood_history: Vec<f64>,
    /// Whether EM stopped on `tol` rather than `max_iter`.
    pub converged: bool,
    /// Bayesian information criterion `−2 L + p ln M`, `p = (k−1) + k d + k d(d+1)/2`.
    pub bic: f64,
}

/// Fits a `k`-component mixture with full covariances to `scores` (one row per
/// sample, all of one length `d`) by EM (see the module doc).
///
/// # Errors
/// [`MotionError::NoComponents`] for `k == 0`, [`MotionError::Empty`] without
/// samples, [`MotionError::Dimension`] for rows of different lengths,
/// [`MotionError::NotFinite`] for a NaN or infinite score, [`MotionError::BadValue`]
/// for a negative or non-finite `reg` or `tol`.
pub fn fit(scores: &[Vec<f64>], k: usize, seed: u64, p: &GmmParams) -> Result<GmmFit, MotionError> {
    let data = Data::new(scores)?;
    if k == 0 {
        return Err(MotionError::NoComponents);
    }
    for (what, v) in [("reg", p.reg), ("tol", p.tol)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(MotionError::BadValue {
                what,
                value: v,
                why: "finite and >= 0",
            });
        }
    }
    let mut best = data.fit(k, seed, p);
    for i in 1..p.n_init as u64 {
        let f = data.fit(k, seed.wrapping_add(i), p);
        if f.objective_history.last() > best.objective_history.last() {
            best = f;
        }
    }
    Ok(best)
}

/// Fits mixtures of `1..=min(k_max, M)` components and returns the one of least BIC
/// (the smallest count among ties).
///
/// Section 6.2 suggests "iterating from one and choos\[ing\] the smallest value that
/// reaches the required data likelihood"; BIC makes "required" precise by charging
/// each component its parameters.
///
/// # Errors
/// As [`fit`].
pub fn fit_auto(
    scores: &[Vec<f64>],
    k_max: usize,
    seed: u64,
    p: &GmmParams,
) -> Result<GmmFit, MotionError> {
    if k_max == 0 {
        return Err(MotionError::NoComponents);
    }
    let mut best = fit(scores, 1, seed, p)?;
    for k in 2..=k_max.min(scores.len()) {
        let f = fit(scores, k, seed, p)?;
        if f.bic < best.bic {
            best = f;
        }
    }
    Ok(best)
}

/// Total log-likelihood `Σ_i ln Σ_k w_k N(x_i; μ_k, Σ_k)` of `scores` under a mixture.
///
/// # Errors
/// [`validate_mixture`]'s, and [`MotionError::Dimension`] / [`MotionError::NotFinite`]
/// for bad scores.
pub fn log_likelihood(
    components: &[GmmComponent],
    scores: &[Vec<f64>],
) -> Result<f64, MotionError> {
    let d = components.first().map_or(0, |c| c.mean.len());
    validate_mixture(components, d)?;
    let data = Data::new(scores)?;
    if data.d != d && data.n > 0 {
        return Err(MotionError::Dimension {
            what: "scores",
            expected: d,
            found: data.d,
        });
    }
    let comps = components
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let cov = DMatrix::from_row_slice(d, d, &c.cov);
            let l = cov
                .cholesky()
                .ok_or(MotionError::NotPositiveDefinite { component: i })?
                .l();
            Ok(Comp {
                weight: c.weight,
                mean: DVector::from_column_slice(&c.mean),
                cov: DMatrix::zeros(0, 0),
                l,
            })
        })
        .collect::<Result<Vec<_>, MotionError>>()?;
    let mut logp = DMatrix::zeros(data.n, comps.len());
    Ok(data.e_step(&comps, &mut logp).0)
}

/// Checks a mixture over `d` dimensions: at least one component, weights finite,
/// non-negative, summing to a positive total, means `d` long, covariances `d²` long,
/// everything finite.
///
/// # Errors
/// [`MotionError::NoComponents`], [`MotionError::Dimension`],
/// [`MotionError::NotFinite`], [`MotionError::BadValue`].
pub fn validate_mixture(components: &[GmmComponent], d: usize) -> Result<(), MotionError> {
    if components.is_empty() {
        return Err(MotionError::NoComponents);
    }
    let mut total = 0.0;
    for (i, c) in components.iter().enumerate() {
        if c.mean.len() != d {
            return Err(MotionError::Dimension {
                what: "mixture mean",
                expected: d,
                found: c.mean.len(),
            });
        }
        if c.cov.len() != d * d {
            return Err(MotionError::Dimension {
                what: "mixture covariance",
                expected: d * d,
                found: c.cov.len(),
            });
        }
        if let Some(j) = c.mean.iter().chain(&c.cov).position(|v| !v.is_finite()) {
            return Err(MotionError::NotFinite {
                what: "mixture component",
                index: i,
                sample: j,
            });
        }
        if !(c.weight.is_finite() && c.weight >= 0.0) {
            return Err(MotionError::BadValue {
                what: "mixture weight",
                value: c.weight,
                why: "finite and >= 0",
            });
        }
        total += c.weight;
    }
    if !(total > 0.0) {
        return Err(MotionError::BadValue {
            what: "sum of mixture weights",
            value: total,
            why: "> 0",
        });
    }
    Ok(())
}

/// A standard normal draw pair by the Box–Muller transform.
pub fn standard_normal_pair(rng: &mut SplitMix64) -> (f64, f64) {
    let u1 = 1.0 - rng.unit(); // (0, 1]
    let u2 = rng.unit();
    let r = (-2.0 * u1.ln()).sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    (r * c, r * s)
}

/// Draws from a mixture: a component by its weight, then `μ + L z` with `L` the
/// Cholesky factor of its covariance and `z` standard normal ([`standard_normal_pair`]).
#[derive(Clone, Debug)]
pub struct GmmSampler {
    d: usize,
    /// Cumulative normalised weights.
    cum: Vec<f64>,
    means: Vec<Vec<f64>>,
    /// Lower Cholesky factors, `d × d` row-major.
    chol: Vec<Vec<f64>>,
    z: Vec<f64>,
}

/// Jitter tried on a covariance that is only positive semi-definite (a blend with a
/// motion of fewer components pads with zero variance), relative to its largest
/// diagonal entry.
const SAMPLER_JITTER_REL: [f64; 5] = [1e-14, 1e-12, 1e-10, 1e-8, 1e-6];

impl GmmSampler {
    /// A sampler for a mixture ([`validate_mixture`]). A covariance that is only
    /// semi-definite is factored with the smallest jitter of `SAMPLER_JITTER_REL`
    /// that works; an all-zero one samples its mean.
    ///
    /// # Errors
    /// [`validate_mixture`]'s; [`MotionError::NotPositiveDefinite`] when even the
    /// largest jitter does not help (an indefinite or asymmetric covariance).
    pub fn new(components: &[GmmComponent]) -> Result<GmmSampler, MotionError> {
        let d = components.first().map_or(0, |c| c.mean.len());
        validate_mixture(components, d)?;
        let total: f64 = components.iter().map(|c| c.weight).sum();
        let mut acc = 0.0;
        let mut cum = Vec::with_capacity(components.len());
        let mut chol = Vec::with_capacity(components.len());
        for (i, c) in components.iter().enumerate() {
            acc += c.weight / total;
            cum.push(acc);
            let cov = DMatrix::from_row_slice(d, d, &c.cov);
            let asym = (0..d)
                .flat_map(|r| (0..d).map(move |s| (r, s)))
                .any(|(r, s)| {
                    (cov[(r, s)] - cov[(s, r)]).abs()
                        > 1e-9 * (cov[(r, r)].abs() + cov[(s, s)].abs() + 1e-300)
                });
            if asym {
                return Err(MotionError::NotPositiveDefinite { component: i });
            }
            let scale = (0..d).map(|r| cov[(r, r)]).fold(0.0, f64::max);
            let l = if scale == 0.0 && cov.iter().all(|&v| v == 0.0) {
                Some(DMatrix::zeros(d, d))
            } else {
                std::iter::once(0.0)
                    .chain(SAMPLER_JITTER_REL.iter().map(|j| j * scale))
                    .find_map(|j| {
                        (&cov + DMatrix::identity(d, d) * j)
                            .cholesky()
                            .map(|c| c.l())
                    })
            };
            let l = l.ok_or(MotionError::NotPositiveDefinite { component: i })?;
            chol.push((0..d * d).map(|k| l[(k / d, k % d)]).collect());
        }
        if let Some(last) = cum.last_mut() {
            *last = 1.0;
        }
        Ok(GmmSampler {
            d,
            cum,
            means: components.iter().map(|c| c.mean.clone()).collect(),
            chol,
            z: vec![0.0; d + 1],
        })
    }

    /// The dimension `d`.
    pub fn dim(&self) -> usize {
        self.d
    }

    /// One draw into `out` (`d` long).
    pub fn sample_into(&mut self, rng: &mut SplitMix64, out: &mut [f64]) {
        let u = rng.unit();
        let k = self
            .cum
            .iter()
            .position(|&c| u < c)
            .unwrap_or(self.cum.len() - 1);
        let d = self.d;
        let mut i = 0;
        while i < d {
            let (a, b) = standard_normal_pair(rng);
            self.z[i] = a;
            self.z[i + 1] = b;
            i += 2;
        }
        let (mean, l) = (&self.means[k], &self.chol[k]);
        for r in 0..d {
            let row = &l[r * d..r * d + r + 1];
            out[r] = mean[r] + row.iter().zip(&self.z).map(|(a, b)| a * b).sum::<f64>();
        }
    }
}

/// Samples as a matrix and their statistics.
struct Data {
    n: usize,
    d: usize,
    x: DMatrix<f64>,
}

/// A component during the fit.
struct Comp {
    weight: f64,
    mean: DVector<f64>,
    cov: DMatrix<f64>,
    /// Lower Cholesky factor of `cov`.
    l: DMatrix<f64>,
}

impl Data {
    fn new(scores: &[Vec<f64>]) -> Result<Data, MotionError> {
        let n = scores.len();
        if n == 0 {
            return Err(MotionError::Empty("eigenscores"));
        }
        let d = scores[0].len();
        for (i, s) in scores.iter().enumerate() {
            if s.len() != d {
                return Err(MotionError::Dimension {
                    what: "eigenscore row",
                    expected: d,
                    found: s.len(),
                });
            }
            if let Some(j) = s.iter().position(|v| !v.is_finite()) {
                return Err(MotionError::NotFinite {
                    what: "eigenscore row",
                    index: i,
                    sample: j,
                });
            }
        }
        Ok(Data {
            n,
            d,
            x: DMatrix::from_fn(n, d, |i, j| scores[i][j]),
        })
    }

    /// The covariance floor `ρ` (module doc).
    fn floor(&self, reg: f64) -> f64 {
        let n = self.n as f64;
        let mut v = 0.0;
        for j in 0..self.d {
            let col = self.x.column(j);
            let m = col.sum() / n;
            v += col.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n;
        }
        let v = if self.d > 0 { v / self.d as f64 } else { 0.0 };
        reg * if v > 0.0 { v } else { 1.0 }
    }

    fn fit(&self, k: usize, seed: u64, p: &GmmParams) -> GmmFit {
        let (n, d) = (self.n, self.d);
        let k = if d == 0 { 1 } else { k.min(n) };
        let rho = self.floor(p.reg);
        // Responsibilities (n × k): hard k-means clusters first.
        let mut resp = self.kmeans(k, seed, p.kmeans_iter);
        let mut comps: Vec<Comp> = Vec::with_capacity(k);
        let mut logp = DMatrix::zeros(n, k);
        let mut obj_hist = Vec::new();
        let mut ll_hist = Vec::new();
        let mut converged = false;
        self.m_step(&resp, rho, &mut comps);
        let mut ll = 0.0;
        for it in 0..=p.max_iter {
            let (l, r) = self.e_step(&comps, &mut logp);
            ll = l;
            resp = r;
            let penalty: f64 = comps
                .iter()
                .map(|c| {
                    let inv =
                        c.l.clone()
                            .solve_lower_triangular(&DMatrix::identity(d, d))
                            .unwrap_or_else(|| DMatrix::zeros(d, d));
                    0.5 * rho * inv.norm_squared()
                })
                .sum();
            let obj = ll - penalty;
            let rise = obj_hist.last().map(|&prev: &f64| obj - prev);
            obj_hist.push(obj);
            ll_hist.push(ll);
            if rise.is_some_and(|r| r <= p.tol * n as f64) {
                converged = true;
                break;
            }
            if it == p.max_iter {
                break;
            }
            self.m_step(&resp, rho, &mut comps);
        }
        // Drop empty components.
        let kept: f64 = comps
            .iter()
            .filter(|c| c.weight >= PRUNE_WEIGHT)
            .map(|c| c.weight)
            .sum();
        let components: Vec<GmmComponent> = comps
            .iter()
            .filter(|c| c.weight >= PRUNE_WEIGHT)
            .map(|c| GmmComponent {
                weight: c.weight / kept,
                mean: c.mean.iter().copied().collect(),
                cov: (0..d * d).map(|i| c.cov[(i / d, i % d)]).collect(),
            })
            .collect();
        let kk = components.len() as f64;
        let df = (kk - 1.0) + kk * d as f64 + kk * (d * (d + 1) / 2) as f64;
        GmmFit {
            bic: -2.0 * ll + df * (n as f64).ln(),
            components,
            log_likelihood: ll,
            objective_history: obj_hist,
            log_likelihood_history: ll_hist,
            converged,
        }
    }

    /// k-means++ seeding and Lloyd iterations; returns hard responsibilities (n × k).
    fn kmeans(&self, k: usize, seed: u64, iters: usize) -> DMatrix<f64> {
        let n = self.n;
        let mut rng = SplitMix64::new(seed);
        let dist2 = |i: usize, c: &DVector<f64>| -> f64 {
            self.x
                .row(i)
                .iter()
                .zip(c.iter())
                .map(|(a, b)| (a - b) * (a - b))
                .sum()
        };
        let first = ((rng.unit() * n as f64) as usize).min(n - 1);
        let mut centres: Vec<DVector<f64>> = vec![self.x.row(first).transpose()];
        let mut near: Vec<f64> = (0..n).map(|i| dist2(i, &centres[0])).collect();
        while centres.len() < k {
            let total: f64 = near.iter().sum();
            let pick = if total > 0.0 {
                let u = rng.unit() * total;
                let mut acc = 0.0;
                near.iter()
                    .position(|&w| {
                        acc += w;
                        u < acc
                    })
                    .unwrap_or(n - 1)
            } else {
                ((rng.unit() * n as f64) as usize).min(n - 1)
            };
            let c = self.x.row(pick).transpose();
            for (i, v) in near.iter_mut().enumerate() {
                *v = v.min(dist2(i, &c));
            }
            centres.push(c);
        }
        let mut label = vec![0usize; n];
        for it in 0..=iters {
            for (i, l) in label.iter_mut().enumerate() {
                *l = (0..k)
                    .min_by(|&a, &b| dist2(i, &centres[a]).total_cmp(&dist2(i, &centres[b])))
                    .unwrap_or(0);
            }
            if it == iters {
                break;
            }
            for (j, c) in centres.iter_mut().enumerate() {
                let members: Vec<usize> = (0..n).filter(|&i| label[i] == j).collect();
                if !members.is_empty() {
                    *c = members.iter().fold(DVector::zeros(self.d), |a, &i| {
                        a + self.x.row(i).transpose()
                    }) / members.len() as f64;
                }
            }
        }
        DMatrix::from_fn(n, k, |i, j| if label[i] == j { 1.0 } else { 0.0 })
    }

    /// Weights, means and covariances from responsibilities (the penalised M-step).
    fn m_step(&self, resp: &DMatrix<f64>, rho: f64, comps: &mut Vec<Comp>) {
        let (n, d, k) = (self.n, self.d, resp.ncols());
        comps.clear();
        for j in 0..k {
            let r = resp.column(j);
            let nk: f64 = r.sum();
            let nk_div = nk.max(f64::EPSILON);
            let mean: DVector<f64> = self.x.tr_mul(&r) / nk_div;
            let mut cov = DMatrix::<f64>::identity(d, d) * rho;
            let mut dx = vec![0.0; d];
            for i in 0..n {
                if r[i] == 0.0 {
                    continue;
                }
                for (t, v) in dx.iter_mut().enumerate() {
                    *v = self.x[(i, t)] - mean[t];
                }
                for a in 0..d {
                    let ra = r[i] * dx[a];
                    for b in 0..=a {
                        cov[(a, b)] += ra * dx[b];
                    }
                }
            }
            for a in 0..d {
                for b in 0..a {
                    cov[(b, a)] = cov[(a, b)];
                }
            }
            cov /= nk_div;
            // Symmetric by construction; Cholesky holds since ρ > 0 or the scatter is
            // positive definite; otherwise grow the diagonal until it does.
            let mut jitter = 0.0;
            let l = loop {
                if let Some(c) = (&cov + DMatrix::identity(d, d) * jitter).cholesky() {
                    cov += DMatrix::identity(d, d) * jitter;
                    break c.l();
                }
                jitter = if jitter == 0.0 {
                    1e-300_f64.max(f64::EPSILON * cov.diagonal().max().abs())
                } else {
                    jitter * 10.0
                };
            };
            comps.push(Comp {
                weight: nk / n as f64,
                mean,
                cov,
                l,
            });
        }
    }

    /// Log densities, the total log-likelihood and the responsibilities
    /// (log-sum-exp per sample).
    fn e_step(&self, comps: &[Comp], logp: &mut DMatrix<f64>) -> (f64, DMatrix<f64>) {
        let (n, d, k) = (self.n, self.d, comps.len());
        let c0 = 0.5 * d as f64 * (2.0 * PI).ln();
        let mut dx = vec![0.0; d];
        for (j, c) in comps.iter().enumerate() {
            let logdet: f64 = (0..d).map(|i| c.l[(i, i)].ln()).sum();
            let lw = c.weight.ln();
            // L⁻¹ once per component; the Mahalanobis term is |L⁻¹ (x − μ)|².
            let inv = c.l.clone().solve_lower_triangular(&DMatrix::identity(d, d));
            let Some(inv) = inv else {
                (0..n).for_each(|i| logp[(i, j)] = f64::NEG_INFINITY);
                continue;
            };
            for i in 0..n {
                for (t, v) in dx.iter_mut().enumerate() {
                    *v = self.x[(i, t)] - c.mean[t];
                }
                let mut maha = 0.0;
                for r in 0..d {
                    let z: f64 = (0..=r).map(|t| inv[(r, t)] * dx[t]).sum();
                    maha += z * z;
                }
                logp[(i, j)] = lw - c0 - logdet - 0.5 * maha;
            }
        }
        let mut ll = 0.0;
        let mut resp = DMatrix::zeros(n, k);
        for i in 0..n {
            let m = (0..k)
                .map(|j| logp[(i, j)])
                .fold(f64::NEG_INFINITY, f64::max);
            if !m.is_finite() {
                // Every component rules the sample out (cannot happen with ρ > 0).
                for j in 0..k {
                    resp[(i, j)] = 1.0 / k as f64;
                }
                ll += m;
                continue;
            }
            let s: f64 = (0..k).map(|j| (logp[(i, j)] - m).exp()).sum();
            let lse = m + s.ln();
            ll += lse;
            for j in 0..k {
                resp[(i, j)] = (logp[(i, j)] - lse).exp();
            }
        }
        (ll, resp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` draws from `N(mean, L Lᵀ)`.
    fn gaussian(rng: &mut SplitMix64, n: usize, mean: &[f64], l: &[f64]) -> Vec<Vec<f64>> {
        let c = GmmComponent {
            weight: 1.0,
            mean: mean.to_vec(),
            cov: llt(l, mean.len()),
        };
        let mut s = GmmSampler::new(&[c]).unwrap();
        (0..n)
            .map(|_| {
                let mut out = vec![0.0; mean.len()];
                s.sample_into(rng, &mut out);
                out
            })
            .collect()
    }

    fn llt(l: &[f64], d: usize) -> Vec<f64> {
        let m = DMatrix::from_row_slice(d, d, l);
        let c = &m * m.transpose();
        (0..d * d).map(|i| c[(i / d, i % d)]).collect()
    }

    fn two_clusters(seed: u64) -> Vec<Vec<f64>> {
        let mut rng = SplitMix64::new(seed);
        let mut x = gaussian(&mut rng, 120, &[-6.0, 0.0], &[1.0, 0.0, 0.3, 0.5]);
        x.extend(gaussian(&mut rng, 280, &[5.0, 2.0], &[0.7, 0.0, -0.2, 1.2]));
        x
    }

    #[test]
    fn recovers_two_well_separated_gaussians() {
        let x = two_clusters(1);
        for seed in [0, 1, 2, 99] {
            let f = fit(&x, 2, seed, &GmmParams::default()).unwrap();
            assert!(f.converged);
            let mut c = f.components.clone();
            c.sort_by(|a, b| a.mean[0].total_cmp(&b.mean[0]));
            assert!(
                (c[0].weight - 0.3).abs() < 0.01 && (c[1].weight - 0.7).abs() < 0.01,
                "{c:?}"
            );
            assert!(
                (c[0].mean[0] + 6.0).abs() < 0.25 && c[0].mean[1].abs() < 0.25,
                "{c:?}"
            );
            assert!(
                (c[1].mean[0] - 5.0).abs() < 0.25 && (c[1].mean[1] - 2.0).abs() < 0.25,
                "{c:?}"
            );
            let want0 = llt(&[1.0, 0.0, 0.3, 0.5], 2);
            let want1 = llt(&[0.7, 0.0, -0.2, 1.2], 2);
            for (got, want) in [(&c[0].cov, &want0), (&c[1].cov, &want1)] {
                for (g, w) in got.iter().zip(want.iter()) {
                    assert!((g - w).abs() < 0.3, "{got:?} vs {want:?}");
                }
            }
            let ll = log_likelihood(&f.components, &x).unwrap();
            assert!((ll - f.log_likelihood).abs() < 1e-9 * ll.abs());
        }
    }

    #[test]
    fn em_never_decreases_its_objective_or_the_likelihood() {
        let x = two_clusters(3);
        // Overlapping clusters and more components than clusters make EM work
        // for many iterations.
        let mut rng = SplitMix64::new(8);
        let mut y = gaussian(
            &mut rng,
            150,
            &[0.0, 0.0, 0.0],
            &[1.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.2, 0.1, 0.6],
        );
        y.extend(gaussian(
            &mut rng,
            150,
            &[1.0, 0.5, 0.0],
            &[0.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.4],
        ));
        let mut longest = 0;
        for (data, k) in [(&x, 2), (&x, 4), (&y, 2), (&y, 3), (&y, 5)] {
            let p = GmmParams {
                tol: 0.0,
                max_iter: 80,
                n_init: 1,
                ..GmmParams::default()
            };
            let f = fit(data, k, 5, &p).unwrap();
            longest = longest.max(f.objective_history.len());
            for w in f.objective_history.windows(2) {
                assert!(w[1] >= w[0] - 1e-9 * w[0].abs(), "objective fell: {w:?}");
            }
            for w in f.log_likelihood_history.windows(2) {
                assert!(w[1] >= w[0] - 1e-6 * w[0].abs(), "likelihood fell: {w:?}");
            }
        }
        assert!(
            longest > 30,
            "EM should have had work to do: {longest} iterations"
        );
    }

    #[test]
    fn one_component_is_the_sample_mean_and_covariance_in_closed_form() {
        let mut rng = SplitMix64::new(4);
        let x = gaussian(
            &mut rng,
            50,
            &[1.0, -1.0, 2.0],
            &[1.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.2, 0.1, 0.6],
        );
        let p = GmmParams::default();
        let f = fit(&x, 1, 0, &p).unwrap();
        let n = x.len() as f64;
        let mean: Vec<f64> = (0..3)
            .map(|j| x.iter().map(|r| r[j]).sum::<f64>() / n)
            .collect();
        let mut var = 0.0;
        for j in 0..3 {
            var += x.iter().map(|r| (r[j] - mean[j]).powi(2)).sum::<f64>() / n / 3.0;
        }
        let rho = p.reg * var;
        for a in 0..3 {
            assert!((f.components[0].mean[a] - mean[a]).abs() < 1e-12);
            for b in 0..3 {
                let s: f64 = x.iter().map(|r| (r[a] - mean[a]) * (r[b] - mean[b])).sum();
                let want = (s + if a == b { rho } else { 0.0 }) / n;
                assert!((f.components[0].cov[3 * a + b] - want).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn samples_have_the_mixtures_mean_and_covariance() {
        let comps = vec![
            GmmComponent {
                weight: 0.25,
                mean: vec![-2.0, 1.0],
                cov: vec![1.0, 0.3, 0.3, 0.5],
            },
            GmmComponent {
                weight: 0.75,
                mean: vec![3.0, 0.0],
                cov: vec![0.4, -0.1, -0.1, 2.0],
            },
        ];
        // Mixture mean Σ w μ; covariance Σ w (Σ + μμᵀ) − m mᵀ.
        let m = [0.25 * -2.0 + 0.75 * 3.0, 0.25 * 1.0];
        let mut cov = [0.0; 4];
        for c in &comps {
            for a in 0..2 {
                for b in 0..2 {
                    cov[2 * a + b] += c.weight * (c.cov[2 * a + b] + c.mean[a] * c.mean[b]);
                }
            }
        }
        for a in 0..2 {
            for b in 0..2 {
                cov[2 * a + b] -= m[a] * m[b];
            }
        }
        let mut s = GmmSampler::new(&comps).unwrap();
        let mut rng = SplitMix64::new(12);
        let n = 200_000;
        let mut xs = vec![[0.0; 2]; n];
        for x in xs.iter_mut() {
            s.sample_into(&mut rng, x);
        }
        let got_m: Vec<f64> = (0..2)
            .map(|j| xs.iter().map(|x| x[j]).sum::<f64>() / n as f64)
            .collect();
        for j in 0..2 {
            assert!((got_m[j] - m[j]).abs() < 0.02, "{got_m:?} vs {m:?}");
        }
        for a in 0..2 {
            for b in 0..2 {
                let c = xs
                    .iter()
                    .map(|x| (x[a] - got_m[a]) * (x[b] - got_m[b]))
                    .sum::<f64>()
                    / n as f64;
                assert!(
                    (c - cov[2 * a + b]).abs() < 0.05,
                    "({a},{b}): {c} vs {}",
                    cov[2 * a + b]
                );
            }
        }
        // Box–Muller: standard normal moments.
        let z: Vec<f64> = (0..100_000)
            .flat_map(|_| {
                let (a, b) = standard_normal_pair(&mut rng);
                [a, b]
            })
            .collect();
        let zm = z.iter().sum::<f64>() / z.len() as f64;
        let zv = z.iter().map(|v| (v - zm) * (v - zm)).sum::<f64>() / z.len() as f64;
        let k4 = z.iter().map(|v| v.powi(4)).sum::<f64>() / z.len() as f64;
        assert!(
            zm.abs() < 0.01 && (zv - 1.0).abs() < 0.01 && (k4 - 3.0).abs() < 0.05,
            "{zm} {zv} {k4}"
        );
    }

    #[test]
    fn bic_chooses_the_number_of_clusters() {
        let mut rng = SplitMix64::new(21);
        let l = [0.5, 0.0, 0.0, 0.5];
        let one = gaussian(&mut rng, 120, &[0.0, 0.0], &l);
        let mut three = gaussian(&mut rng, 50, &[-5.0, 0.0], &l);
        three.extend(gaussian(&mut rng, 50, &[5.0, 0.0], &l));
        three.extend(gaussian(&mut rng, 50, &[0.0, 6.0], &l));
        let p = GmmParams {
            n_init: 2,
            ..GmmParams::default()
        };
        assert_eq!(fit_auto(&one, 5, 1, &p).unwrap().components.len(), 1);
        assert_eq!(fit_auto(&three, 5, 1, &p).unwrap().components.len(), 3);
    }

    #[test]
    fn degenerate_inputs_fit_without_panicking() {
        let p = GmmParams::default();
        // Fewer samples than components.
        let few = vec![vec![0.0, 1.0], vec![2.0, 1.0], vec![5.0, -1.0]];
        let f = fit(&few, 5, 0, &p).unwrap();
        assert!(f.components.len() <= 3 && f.log_likelihood.is_finite());
        // Identical samples.
        let same = vec![vec![1.5, -2.0, 0.25]; 20];
        let f = fit(&same, 2, 0, &p).unwrap();
        assert!(f.log_likelihood.is_finite());
        for c in &f.components {
            assert!((c.mean[0] - 1.5).abs() < 1e-12 && c.cov[0] > 0.0 && c.cov[0] < 1e-6);
        }
        GmmSampler::new(&f.components).unwrap();
        // Fewer samples than dimensions (a 20-agent crowd, 15 eigenscores).
        let mut rng = SplitMix64::new(2);
        let thin: Vec<Vec<f64>> = (0..20)
            .map(|_| (0..15).map(|_| rng.uniform(-1.0, 1.0)).collect())
            .collect();
        let f = fit(&thin, 2, 0, &p).unwrap();
        assert!(f.log_likelihood.is_finite());
        assert!(fit_auto(&thin, 4, 0, &p).is_ok());
        // Zero dimensions: the one empty component.
        let f = fit(&vec![vec![]; 4], 2, 0, &p).unwrap();
        assert_eq!(
            f.components,
            vec![GmmComponent {
                weight: 1.0,
                mean: vec![],
                cov: vec![]
            }]
        );
        // Errors.
        assert_eq!(fit(&few, 0, 0, &p), Err(MotionError::NoComponents));
        assert_eq!(fit(&[], 2, 0, &p), Err(MotionError::Empty("eigenscores")));
        assert!(matches!(
            fit(&[vec![1.0], vec![1.0, 2.0]], 1, 0, &p),
            Err(MotionError::Dimension { .. })
        ));
        assert!(matches!(
            fit(&[vec![f64::NAN]], 1, 0, &p),
            Err(MotionError::NotFinite { .. })
        ));
        let bad = GmmParams { reg: -1.0, ..p };
        assert!(matches!(
            fit(&few, 1, 0, &bad),
            Err(MotionError::BadValue { .. })
        ));
        let indefinite = GmmComponent {
            weight: 1.0,
            mean: vec![0.0, 0.0],
            cov: vec![1.0, 0.0, 0.0, -1.0],
        };
        assert!(matches!(
            GmmSampler::new(&[indefinite]),
            Err(MotionError::NotPositiveDefinite { component: 0 })
        ));
        assert_eq!(GmmSampler::new(&[]).err(), Some(MotionError::NoComponents));
    }

    /// Writes the cross-check dataset and this fit's log-likelihood per sample for
    /// `benches/gmm_crosscheck.py` (scikit-learn's `GaussianMixture` on the same data)
    /// into `target/gmm_crosscheck/`.
    #[test]
    #[ignore = "writes files for benches/gmm_crosscheck.py"]
    fn gmm_crosscheck_dataset() {
        let mut rng = SplitMix64::new(2024);
        let mut x = gaussian(
            &mut rng,
            180,
            &[0.0, 0.0, 0.0],
            &[1.0, 0.0, 0.0, 0.4, 0.8, 0.0, -0.3, 0.2, 0.5],
        );
        x.extend(gaussian(
            &mut rng,
            120,
            &[3.0, 1.0, -1.0],
            &[0.6, 0.0, 0.0, 0.1, 1.1, 0.0, 0.0, 0.3, 0.7],
        ));
        let p = GmmParams {
            reg: 1e-9,
            tol: 1e-13,
            max_iter: 2000,
            n_init: 8,
            ..GmmParams::default()
        };
        let f = fit(&x, 2, 0, &p).unwrap();
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/gmm_crosscheck");
        std::fs::create_dir_all(&dir).unwrap();
        let csv: String = x
            .iter()
            .map(|r| format!("{:.17e},{:.17e},{:.17e}\n", r[0], r[1], r[2]))
            .collect();
        std::fs::write(dir.join("data.csv"), csv).unwrap();
        let json = format!(
            "{{\"k\": 2, \"ll_per_sample\": {:.17e}, \"converged\": {}, \"weights\": [{:.6}, {:.6}]}}\n",
            f.log_likelihood / x.len() as f64,
            f.converged,
            f.components[0].weight,
            f.components[1].weight
        );
        std::fs::write(dir.join("rust.json"), json).unwrap();
    }
}
