//! Minimum-cost assignment (the Hungarian method), for type-A contact matching.

use crate::vocab::MAX_CONTACTS;

/// How many rows [`assign_min_cost`] solves at most: every anonymous packet
/// and every anonymous previous contact of a type-A frame.
pub const ASSIGN_MAX: usize = 2 * MAX_CONTACTS;

/// Minimum-cost perfect assignment of an `n × n` cost matrix given as a function.
///
/// Writes `col_of_row[r]` = the column assigned to row `r`, for `r < n`, such that
/// `Σ cost(r, col_of_row[r])` is minimal.
///
/// # Formula
/// The Hungarian method (Kuhn 1955; Munkres 1957) in its shortest augmenting
/// path form with row and column potentials `u`, `v`: each row is added by a
/// Dijkstra-like search over reduced costs `cost(r, c) − u[r] − v[c] ≥ 0`,
/// then the potentials are updated by the smallest slack. The kernel's
/// multi-touch documentation states type-A tracking as this Euclidean bipartite
/// matching problem.
///
/// # Units
/// Whatever `cost` returns; it must be finite (non-finite costs give an
/// arbitrary assignment, never a panic or an endless loop).
///
/// # Complexity
/// O(n³) time, O(`ASSIGN_MAX`) stack, no heap. `n` above [`ASSIGN_MAX`] is
/// clamped to it.
///
/// # Errors
/// None.
///
/// ```
/// use crowdtouch::input::evdev::{assign_min_cost, ASSIGN_MAX};
/// let c = [[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]];
/// let mut col = [0usize; ASSIGN_MAX];
/// assign_min_cost(3, |r, k| c[r][k], &mut col);
/// let total: f64 = (0..3).map(|r| c[r][col[r]]).sum();
/// assert!((total - 5.0).abs() < 1e-12);
/// ```
pub fn assign_min_cost(
    n: usize,
    cost: impl Fn(usize, usize) -> f64,
    col_of_row: &mut [usize; ASSIGN_MAX],
) {
    let n = n.min(ASSIGN_MAX);
    // 1-based arrays; index 0 is the virtual root column.
    let mut u = [0.0f64; ASSIGN_MAX + 1];
    let mut v = [0.0f64; ASSIGN_MAX + 1];
    let mut row_of_col = [0usize; ASSIGN_MAX + 1];
    let mut way = [0usize; ASSIGN_MAX + 1];
    for row in 1..=n {
        row_of_col[0] = row;
        let mut j0 = 0usize;
        let mut minv = [f64::INFINITY; ASSIGN_MAX + 1];
        let mut used = [false; ASSIGN_MAX + 1];
        loop {
            used[j0] = true;
            let i0 = row_of_col[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0usize;
            for j in 1..=n {
                if used[j] {
                    continue;
                }
                let cur = cost(i0 - 1, j - 1) - u[i0] - v[j];
                if cur < minv[j] {
                    minv[j] = cur;
                    way[j] = j0;
                }
                // `j1 == 0` takes the first free column even if every slack is
                // NaN or infinite, so the search always advances.
                if j1 == 0 || minv[j] < delta {
                    delta = minv[j];
                    j1 = j;
                }
            }
            if !delta.is_finite() {
                delta = 0.0;
            }
            for j in 0..=n {
                if used[j] {
                    u[row_of_col[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if j0 == 0 || row_of_col[j0] == 0 {
                break;
            }
        }
        // Augment along the alternating path back to the root.
        while j0 != 0 {
            let j1 = way[j0];
            row_of_col[j0] = row_of_col[j1];
            j0 = j1;
        }
    }
    for j in 1..=n {
        if row_of_col[j] > 0 {
            col_of_row[row_of_col[j] - 1] = j - 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Smallest total cost over all permutations.
    fn brute_force(n: usize, c: &[f64]) -> f64 {
        fn go(n: usize, row: usize, used: &mut Vec<bool>, c: &[f64]) -> f64 {
            if row == n {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for col in 0..n {
                if !used[col] {
                    used[col] = true;
                    best = best.min(c[row * n + col] + go(n, row + 1, used, c));
                    used[col] = false;
                }
            }
            best
        }
        go(n, 0, &mut vec![false; n], c)
    }

    #[test]
    fn assignment_is_optimal_against_brute_force() {
        // Seeded LCG: integer costs make ties common.
        let mut seed: u64 = 0x5eed;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 33) % 20
        };
        for n in 1..=7 {
            for _ in 0..30 {
                let c: Vec<f64> = (0..n * n).map(|_| rnd() as f64).collect();
                let mut col = [usize::MAX; ASSIGN_MAX];
                assign_min_cost(n, |r, k| c[r * n + k], &mut col);
                let mut seen = vec![false; n];
                for &k in &col[..n] {
                    assert!(k < n && !seen[k], "not a permutation: {:?}", &col[..n]);
                    seen[k] = true;
                }
                let got: f64 = (0..n).map(|r| c[r * n + col[r]]).sum();
                assert!((got - brute_force(n, &c)).abs() < 1e-9, "n={n}");
            }
        }
        // Non-finite costs still give a permutation.
        let mut col = [usize::MAX; ASSIGN_MAX];
        assign_min_cost(3, |_, _| f64::NAN, &mut col);
        let mut cols = col[..3].to_vec();
        cols.sort_unstable();
        assert_eq!(cols, vec![0, 1, 2]);
    }
}
