//! Comparing transform variants over many seeds (formation-transform section 5):
//! a mean with its 95 % confidence interval, the measures averaged over a common
//! time window, and how local subgroups are.
//!
//! Each run's own mean (`RunSummary::mean`) averages over that run's steps, that
//! is over its *normalised progress* (time divided by its own arrival time): two
//! variants that arrive at different times are then averaged over different
//! stretches of the motion. [`window_mean`] averages every run over the same
//! first seconds instead, so that a variant that arrives early is not credited
//! with the calm of standing still while the other is still on its way.

use super::measures::Measures;
use crate::geom::Vec2;

/// A mean over runs and the half-width of its 95 % confidence interval
/// (Student's t with `n − 1` degrees of freedom; 0 for one run).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Interval {
    /// The sample mean.
    pub mean: f64,
    /// Half-width of the 95 % confidence interval of the mean.
    pub ci95: f64,
    /// Runs it is over.
    pub n: usize,
}

impl Interval {
    /// Whether this interval lies wholly below `other`'s (the difference is
    /// significant at about the 5 % level or better).
    pub fn below(&self, other: &Interval) -> bool {
        self.mean + self.ci95 < other.mean - other.ci95
    }
}

/// The two-sided 97.5 % quantile of Student's t with `df` degrees of freedom
/// (tabulated to 3 decimals for 1–30; the normal's 1.960 beyond).
pub fn t_975(df: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::INFINITY,
        1..=30 => T[df - 1],
        31..=60 => 2.042 - (2.042 - 2.000) * (df - 30) as f64 / 30.0,
        61..=120 => 2.000 - (2.000 - 1.980) * (df - 60) as f64 / 60.0,
        _ => 1.960,
    }
}

/// The mean of `xs` and its 95 % confidence interval. Non-finite values are left
/// out (`n` says how many were used); no value gives a NaN mean.
pub fn interval(xs: &[f64]) -> Interval {
    let v: Vec<f64> = xs.iter().copied().filter(|x| x.is_finite()).collect();
    let n = v.len();
    if n == 0 {
        return Interval {
            mean: f64::NAN,
            ci95: f64::NAN,
            n: 0,
        };
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Interval { mean, ci95: 0.0, n };
    }
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    Interval {
        mean,
        ci95: t_975(n - 1) * (var / n as f64).sqrt(),
        n,
    }
}

/// The measures averaged over the steps at simulated times `t ≤ until_s` of a run
/// (`(t, measures)` per step, in order); `None` when no step is that early.
pub fn window_mean(
    series: impl IntoIterator<Item = (f64, Measures)>,
    until_s: f64,
) -> Option<Measures> {
    let mut sum = Measures::default();
    let mut n = 0usize;
    for (t, m) in series {
        if t > until_s + 1e-9 {
            break;
        }
        sum.i_d += m.i_d;
        sum.i_v += m.i_v;
        sum.sigma_min_dis_m += m.sigma_min_dis_m;
        sum.sigma_curr_eft_m += m.sigma_curr_eft_m;
        sum.heading_change_rad_s += m.heading_change_rad_s;
        n += 1;
    }
    (n > 0).then(|| {
        let k = n as f64;
        Measures {
            i_d: sum.i_d / k,
            i_v: sum.i_v / k,
            sigma_min_dis_m: sum.sigma_min_dis_m / k,
            sigma_curr_eft_m: sum.sigma_curr_eft_m / k,
            heading_change_rad_s: sum.heading_change_rad_s / k,
        }
    })
}

/// The fraction of agents whose nearest other agent (at `positions`) is in their
/// own subgroup (`group_of`): 1 for spatially coherent subgroups, about `1 / k`
/// for `k` groups drawn at random. 1 for fewer than two agents. Brute force,
/// `O(n²)`.
pub fn locality(positions: &[Vec2], group_of: &[u32]) -> f64 {
    let n = positions.len().min(group_of.len());
    if n < 2 {
        return 1.0;
    }
    let mut own = 0usize;
    for i in 0..n {
        let mut best = (f64::INFINITY, i);
        for j in 0..n {
            if j != i {
                let d2 = (positions[j] - positions[i]).norm_squared();
                if d2 < best.0 {
                    best = (d2, j);
                }
            }
        }
        if group_of[best.1] == group_of[i] {
            own += 1;
        }
    }
    own as f64 / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_matches_a_hand_computed_t_interval() {
        // Mean 3, sample sd sqrt(2.5), n 5: half-width t(4) · sd / sqrt(5).
        let i = interval(&[1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!((i.mean - 3.0).abs() < 1e-12);
        let want = 2.776 * (2.5f64 / 5.0).sqrt();
        assert!((i.ci95 - want).abs() < 1e-12, "{i:?}");
        assert_eq!(i.n, 5);
        let one = interval(&[7.0, f64::NAN]);
        assert_eq!((one.mean, one.ci95, one.n), (7.0, 0.0, 1));
        assert!(interval(&[]).mean.is_nan());
    }

    #[test]
    fn t_quantiles_fall_towards_the_normal() {
        assert!(t_975(0).is_infinite());
        let mut last = f64::INFINITY;
        for df in 1..200 {
            let t = t_975(df);
            assert!(t <= last && t >= 1.96, "df {df}: {t}");
            last = t;
        }
        assert_eq!(t_975(1000), 1.96);
    }

    #[test]
    fn window_mean_takes_only_the_early_steps() {
        let m = |x: f64| Measures {
            i_d: x,
            i_v: 2.0 * x,
            sigma_min_dis_m: 3.0 * x,
            sigma_curr_eft_m: 4.0 * x,
            heading_change_rad_s: 5.0 * x,
        };
        let series = (1..=10).map(|k| (k as f64 * 0.5, m(k as f64)));
        let w = window_mean(series.clone(), 2.0).unwrap();
        assert!((w.i_d - 2.5).abs() < 1e-12 && (w.sigma_curr_eft_m - 10.0).abs() < 1e-12);
        assert!((w.heading_change_rad_s - 12.5).abs() < 1e-12);
        assert!(window_mean(series, 0.1).is_none());
    }

    #[test]
    fn locality_of_two_clusters_and_of_a_checkerboard() {
        let pts: Vec<Vec2> = (0..20)
            .map(|k| Vec2::new(if k < 10 { 0.0 } else { 100.0 } + (k % 10) as f64, 0.0))
            .collect();
        let by_cluster: Vec<u32> = (0..20).map(|k| u32::from(k >= 10)).collect();
        assert_eq!(locality(&pts, &by_cluster), 1.0);
        let alternating: Vec<u32> = (0..20).map(|k| k % 2).collect();
        assert_eq!(locality(&pts, &alternating), 0.0);
    }
}
