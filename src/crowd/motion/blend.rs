//! Blending the crowd motions of a gesture's K nearest neighbours into the motion to
//! run (gesture-driven section 7.2).
//!
//! * Mean trajectory: `c̄ʳ = Σ_k w_k c̄ᵏ` (eq. 19).
//! * Eigenvectors: `E_Vʳ = Σ_k w_k E_Vᵏ` (eq. 20), then re-orthonormalised by modified
//!   Gram–Schmidt [CK08].
//! * Mixtures: displacement interpolation [BvdPPH11]: the components of two mixtures
//!   are matched by optimal assignment on their means ([`crate::crowd::assign`], the
//!   mass transport of [HSK12]), matched components are averaged (weights, means,
//!   covariances), and the K mixtures are combined one after the other ("we
//!   iteratively combine all the GMMs").
//!
//! Three choices the paper leaves open:
//! * **Signs.** An eigenvector is defined up to sign, so the same motion analysed
//!   twice may give `e` and `−e`, and eq. 20 would cancel them. Each neighbour's
//!   `k`-th eigenvector is flipped to agree with the first neighbour's (positive dot
//!   product), and score dimension `k` of its mixture with it (`μ_k → −μ_k`, row
//!   and column `k` of each covariance negated).
//! * **Differing numbers of eigenvectors.** Every neighbour is zero-padded to the
//!   largest count: a missing eigenvector contributes nothing to eq. 20 and its
//!   score dimension has mean 0 and variance 0, so its variation is blended towards
//!   none in proportion to the neighbour's weight. A blended eigenvector that
//!   vanishes (norm below [`GS_DROP_REL`] of its pre-projection norm, e.g. only
//!   padded zeros) is dropped with its score dimension (the mixture is
//!   marginalised).
//! * **Differing numbers of Gaussian components.** The smaller mixture's components
//!   are matched one-to-one by the assignment; each component of the larger one left
//!   over is paired with the smaller one's component nearest by mean, whose weight is
//!   split among its partners in proportion to theirs. The result has as many
//!   components as the larger mixture.
//!
//! Neighbours of weight 0 are ignored; the weights are normalised to sum 1. The
//! class is the class of the heaviest neighbour (the first among equals), the
//! duration the weighted mean.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::error::MotionError;
use super::features::validate_features;
use crate::crowd::assign::{CostMatrix, Solver};
use crate::gesture::library::{GmmComponent, MotionFeatures, TRAJ_DIM};

/// A blended eigenvector is dropped when modified Gram–Schmidt leaves less than this
/// share of its norm.
pub const GS_DROP_REL: f64 = 1e-8;

/// Blends neighbours' motions `(features, weight)` (section 7.2; see the module doc).
///
/// # Errors
/// [`MotionError::Empty`] without neighbours, [`MotionError::BadValue`] for a
/// negative or non-finite weight or weights summing to 0, [`validate_features`]'s,
/// [`MotionError::Assign`] if matching components fails.
pub fn blend(neighbours: &[(&MotionFeatures, f64)]) -> Result<MotionFeatures, MotionError> {
    if neighbours.is_empty() {
        return Err(MotionError::Empty("blend neighbours"));
    }
    let mut total = 0.0;
    for (f, w) in neighbours {
        if !(w.is_finite() && *w >= 0.0) {
            return Err(MotionError::BadValue {
                what: "blend weight",
                value: *w,
                why: "finite and >= 0",
            });
        }
        validate_features(f)?;
        total += w;
    }
    if !(total > 0.0) {
        return Err(MotionError::BadValue {
            what: "sum of blend weights",
            value: total,
            why: "> 0",
        });
    }
    let active: Vec<(&MotionFeatures, f64)> = neighbours
        .iter()
        .filter(|(_, w)| *w > 0.0)
        .map(|&(f, w)| (f, w / total))
        .collect();
    let d = active.iter().map(|(f, _)| f.basis.len()).max().unwrap_or(0);
    let reference = active[0].0;

    let mut mean = vec![0.0; TRAJ_DIM];
    let mut basis = vec![vec![0.0; TRAJ_DIM]; d];
    let mut duration_s = 0.0;
    let mut acc: Vec<GmmComponent> = Vec::new();
    let mut acc_w = 0.0;
    let mut solver = Solver::new();
    for (j, &(f, w)) in active.iter().enumerate() {
        // Signs agreeing with the reference (the first neighbour).
        let signs: Vec<f64> = (0..d)
            .map(|k| match (f.basis.get(k), reference.basis.get(k)) {
                (Some(e), Some(r)) if j > 0 && dot(e, r) < 0.0 => -1.0,
                _ => 1.0,
            })
            .collect();
        for (m, v) in mean.iter_mut().zip(&f.mean) {
            *m += w * v;
        }
        for (k, e) in f.basis.iter().enumerate() {
            for (b, v) in basis[k].iter_mut().zip(e) {
                *b += w * signs[k] * v;
            }
        }
        duration_s += w * f.duration_s;
        let g = aligned_mixture(&f.gmm, f.basis.len(), d, &signs);
        if j == 0 {
            acc = g;
        } else {
            acc = combine(&acc, acc_w, &g, w, &mut solver)?;
        }
        acc_w += w;
    }
    let kept = modified_gram_schmidt(&mut basis);
    let basis: Vec<Vec<f64>> = kept
        .iter()
        .map(|&k| std::mem::take(&mut basis[k]))
        .collect();
    let wsum: f64 = acc.iter().map(|c| c.weight).sum();
    let gmm = acc
        .iter()
        .map(|c| GmmComponent {
            weight: c.weight / wsum,
            mean: kept.iter().map(|&k| c.mean[k]).collect(),
            cov: kept
                .iter()
                .flat_map(|&a| kept.iter().map(move |&b| c.cov[a * d + b]))
                .collect(),
        })
        .collect();
    let class = active
        .iter()
        .fold((reference.class, -1.0), |best, (f, w)| {
            if *w > best.1 {
                (f.class, *w)
            } else {
                best
            }
        })
        .0;
    Ok(MotionFeatures {
        class,
        duration_s,
        mean,
        basis,
        gmm,
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// A mixture over `d0` dimensions with score dimensions flipped by `signs` and
/// zero-padded to `d` (mean 0, variance 0 in the padded dimensions).
fn aligned_mixture(g: &[GmmComponent], d0: usize, d: usize, signs: &[f64]) -> Vec<GmmComponent> {
    g.iter()
        .map(|c| {
            let mut mean = vec![0.0; d];
            let mut cov = vec![0.0; d * d];
            for a in 0..d0 {
                mean[a] = signs[a] * c.mean[a];
                for b in 0..d0 {
                    cov[a * d + b] = signs[a] * signs[b] * c.cov[a * d0 + b];
                }
            }
            GmmComponent {
                weight: c.weight,
                mean,
                cov,
            }
        })
        .collect()
}

/// Displacement interpolation of mixture `a` (blend weight `wa`) and `b` (`wb`):
/// components matched by optimal assignment on their means (squared distance),
/// then averaged with weights `wa / (wa + wb)` and `wb / (wa + wb)`.
///
/// # Errors
/// [`MotionError::Assign`] if the assignment fails (it cannot on finite means).
pub fn combine(
    a: &[GmmComponent],
    wa: f64,
    b: &[GmmComponent],
    wb: f64,
    solver: &mut Solver,
) -> Result<Vec<GmmComponent>, MotionError> {
    let t = wb / (wa + wb);
    let swap = a.len() > b.len();
    let (small, large) = if swap { (b, a) } else { (a, b) };
    let pairs = match_components(small, large, solver)?;
    Ok(pairs
        .iter()
        .map(|&(s, l, share)| {
            let (cs, cl) = (&small[s], &large[l]);
            let (ws, wl) = (cs.weight * share, cl.weight);
            let (ca, cb, wca, wcb) = if swap {
                (cl, cs, wl, ws)
            } else {
                (cs, cl, ws, wl)
            };
            GmmComponent {
                weight: (1.0 - t) * wca + t * wcb,
                mean: ca
                    .mean
                    .iter()
                    .zip(&cb.mean)
                    .map(|(x, y)| (1.0 - t) * x + t * y)
                    .collect(),
                cov: ca
                    .cov
                    .iter()
                    .zip(&cb.cov)
                    .map(|(x, y)| (1.0 - t) * x + t * y)
                    .collect(),
            }
        })
        .collect())
}

/// Pairs each component of `large` with one of `small` (`small.len() <=
/// large.len()`): the optimal one-to-one assignment of `small` into `large` on
/// squared distance between means, and every left-over `large` component with the
/// `small` component nearest by mean. Returns `(small, large, share)` with `share`
/// the fraction of the small component's weight that goes to this pair
/// (proportional to its partners' weights).
fn match_components(
    small: &[GmmComponent],
    large: &[GmmComponent],
    solver: &mut Solver,
) -> Result<Vec<(usize, usize, f64)>, MotionError> {
    let d2 = |p: &GmmComponent, q: &GmmComponent| -> f64 {
        p.mean
            .iter()
            .zip(&q.mean)
            .map(|(x, y)| (x - y) * (x - y))
            .sum()
    };
    let costs = CostMatrix::from_fn(small.len(), large.len(), |r, c| d2(&small[r], &large[c]));
    let assigned = solver.solve(&costs)?;
    let mut partner = vec![usize::MAX; large.len()];
    for (s, &l) in assigned.iter().enumerate() {
        partner[l] = s;
    }
    for (l, p) in partner.iter_mut().enumerate() {
        if *p == usize::MAX {
            *p = (0..small.len())
                .min_by(|&x, &y| d2(&small[x], &large[l]).total_cmp(&d2(&small[y], &large[l])))
                .unwrap_or(0);
        }
    }
    let mut partner_weight = vec![0.0; small.len()];
    let mut partner_count = vec![0usize; small.len()];
    for (l, &s) in partner.iter().enumerate() {
        partner_weight[s] += large[l].weight;
        partner_count[s] += 1;
    }
    Ok(partner
        .iter()
        .enumerate()
        .map(|(l, &s)| {
            let share = if partner_weight[s] > 0.0 {
                large[l].weight / partner_weight[s]
            } else {
                1.0 / partner_count[s] as f64
            };
            (s, l, share)
        })
        .collect())
}

/// Modified Gram–Schmidt \[CK08\] in place, in order; returns the indices of the
/// vectors kept (those keeping more than [`GS_DROP_REL`] of their norm), now
/// orthonormal. Dropped vectors are left as they are.
pub fn modified_gram_schmidt(vs: &mut [Vec<f64>]) -> Vec<usize> {
    let mut kept: Vec<usize> = Vec::with_capacity(vs.len());
    for k in 0..vs.len() {
        let before = dot(&vs[k], &vs[k]).sqrt();
        let (done, rest) = vs.split_at_mut(k);
        let v = &mut rest[0];
        for &q in &kept {
            let p = dot(&done[q], v);
            for (x, y) in v.iter_mut().zip(&done[q]) {
                *x -= p * y;
            }
        }
        let after = dot(v, v).sqrt();
        if before > 0.0 && after > GS_DROP_REL * before && after > f64::MIN_POSITIVE {
            v.iter_mut().for_each(|x| *x /= after);
            kept.push(k);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::motion::features::tests::split_motion;
    use crate::crowd::motion::{features, synthesise, FeatureParams, Placement};
    use crate::geom::Vec2;
    use crate::gesture::library::{MotionClass, S_H};

    fn split_features(seed: u64) -> MotionFeatures {
        features(
            MotionClass::Split.id(),
            &split_motion(40, 2.0, seed),
            &FeatureParams::default(),
        )
        .unwrap()
    }

    fn close(a: &MotionFeatures, b: &MotionFeatures, tol: f64) {
        let near = |x: &[f64], y: &[f64]| {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| (p - q).abs() < tol)
        };
        assert!(near(&a.mean, &b.mean));
        assert_eq!(a.basis.len(), b.basis.len());
        for (x, y) in a.basis.iter().zip(&b.basis) {
            assert!(near(x, y));
        }
        assert_eq!(a.gmm.len(), b.gmm.len());
        for (x, y) in a.gmm.iter().zip(&b.gmm) {
            assert!(
                (x.weight - y.weight).abs() < tol && near(&x.mean, &y.mean) && near(&x.cov, &y.cov),
                "{x:?} {y:?}"
            );
        }
        assert!((a.duration_s - b.duration_s).abs() < tol);
    }

    #[test]
    fn blending_copies_of_one_motion_returns_it() {
        let f = split_features(1);
        close(&blend(&[(&f, 0.3), (&f, 0.7)]).unwrap(), &f, 1e-12);
        close(
            &blend(&[(&f, 1.0), (&f, 1.0), (&f, 2.0)]).unwrap(),
            &f,
            1e-12,
        );
        // A copy with every eigenvector (and score) negated is the same motion.
        let mut g = f.clone();
        g.basis.iter_mut().flatten().for_each(|v| *v = -*v);
        g.gmm
            .iter_mut()
            .flat_map(|c| c.mean.iter_mut())
            .for_each(|v| *v = -*v);
        close(&blend(&[(&f, 0.5), (&g, 0.5)]).unwrap(), &f, 1e-12);
    }

    #[test]
    fn weights_one_and_zero_return_the_first() {
        let f = split_features(1);
        let g = split_features(2);
        close(&blend(&[(&f, 1.0), (&g, 0.0)]).unwrap(), &f, 1e-12);
        close(&blend(&[(&g, 0.0), (&f, 1.0)]).unwrap(), &f, 1e-12);
    }

    #[test]
    fn matched_components_do_not_cross_fade() {
        // Two splits whose mixtures list their groups in opposite orders: blending
        // index by index would average the left group with the right one (cross
        // fading: both components at the middle, nobody splits); matching by means
        // keeps a left and a right group.
        let f = split_features(1);
        let mut g = f.clone();
        g.gmm.reverse();
        for c in &mut g.gmm {
            c.mean.iter_mut().for_each(|v| *v *= 1.1);
        }
        let b = blend(&[(&f, 0.5), (&g, 0.5)]).unwrap();
        let mut naive = f.clone();
        for (c, (x, y)) in naive.gmm.iter_mut().zip(f.gmm.iter().zip(&g.gmm)) {
            c.mean = x
                .mean
                .iter()
                .zip(&y.mean)
                .map(|(p, q)| 0.5 * (p + q))
                .collect();
            c.cov = x
                .cov
                .iter()
                .zip(&y.cov)
                .map(|(p, q)| 0.5 * (p + q))
                .collect();
        }
        let gap = |h: &MotionFeatures| (h.gmm[0].mean[0] - h.gmm[1].mean[0]).abs();
        assert!(
            gap(&b) > 0.9 * 1.05 * gap(&f),
            "matched gap {} vs source {}",
            gap(&b),
            gap(&f)
        );
        assert!(gap(&naive) < 0.1 * gap(&f), "naive gap {}", gap(&naive));
        // In the world: the matched blend splits the crowd, the naive one does not.
        let agents: Vec<Vec2> = (0..100)
            .map(|i| Vec2::new((i % 10) as f64, (i / 10) as f64))
            .collect();
        let spread_x = |h: &MotionFeatures| {
            let s = synthesise(h, &agents, &Placement::for_crowd(&agents), 4).unwrap();
            let xs: Vec<f64> = s
                .trajectories
                .iter()
                .map(|t| t[S_H - 1].x - t[0].x)
                .collect();
            let m = xs.iter().sum::<f64>() / xs.len() as f64;
            (xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / xs.len() as f64).sqrt()
        };
        let (sm, sn, sf) = (spread_x(&b), spread_x(&naive), spread_x(&f));
        assert!(
            sm > 0.8 * sf && sn < 0.3 * sf,
            "x-displacement spread: matched {sm}, naive {sn}, source {sf}"
        );
    }

    #[test]
    fn differing_counts_of_eigenvectors_and_components_blend() {
        let f = split_features(1);
        let mut g = split_features(3);
        g.basis.truncate(2);
        for c in &mut g.gmm {
            let d0 = c.mean.len();
            c.mean.truncate(2);
            c.cov = (0..4).map(|i| c.cov[(i / 2) * d0 + i % 2]).collect();
        }
        let h = GmmComponent {
            weight: 0.2,
            mean: vec![9.0, 9.0],
            cov: vec![1.0, 0.0, 0.0, 1.0],
        };
        g.gmm.iter_mut().for_each(|c| c.weight *= 0.8);
        g.gmm.push(h);
        let b = blend(&[(&f, 0.6), (&g, 0.4)]).unwrap();
        validate_features(&b).unwrap();
        assert_eq!(b.basis.len(), f.basis.len());
        assert_eq!(b.gmm.len(), 3);
        assert!((b.gmm.iter().map(|c| c.weight).sum::<f64>() - 1.0).abs() < 1e-12);
        for i in 0..b.basis.len() {
            for j in 0..b.basis.len() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(&b.basis[i], &b.basis[j]) - want).abs() < 1e-10);
            }
        }
        // Only the padded motion: its zero eigenvectors are dropped.
        let only = blend(&[(&g, 1.0)]).unwrap();
        assert_eq!(only.basis.len(), 2);
    }

    #[test]
    fn gram_schmidt_orthonormalises_and_drops_dependent_vectors() {
        let mut vs = vec![
            vec![3.0, 0.0, 0.0],
            vec![1.0, 1.0, 0.0],
            vec![2.0, 2.0, 0.0],
            vec![1.0, 1.0, 1.0],
        ];
        let kept = modified_gram_schmidt(&mut vs);
        assert_eq!(kept, vec![0, 1, 3]);
        assert_eq!(vs[0], vec![1.0, 0.0, 0.0]);
        assert!((vs[1][1] - 1.0).abs() < 1e-15 && (vs[3][2] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn bad_blends_are_refused() {
        let f = split_features(1);
        assert_eq!(blend(&[]), Err(MotionError::Empty("blend neighbours")));
        assert!(matches!(
            blend(&[(&f, -1.0)]),
            Err(MotionError::BadValue { .. })
        ));
        assert!(matches!(
            blend(&[(&f, f64::NAN)]),
            Err(MotionError::BadValue { .. })
        ));
        assert!(matches!(
            blend(&[(&f, 0.0)]),
            Err(MotionError::BadValue { .. })
        ));
        let mut g = f.clone();
        g.mean.pop();
        assert!(matches!(
            blend(&[(&f, 1.0), (&g, 1.0)]),
            Err(MotionError::Dimension { .. })
        ));
    }
}
