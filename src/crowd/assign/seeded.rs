//! Solves started from column prices the caller supplies (e.g. the prices of a
//! coarser instance of the same problem, [`super::CoarseToFine`]), and the duals of
//! the last solve.
//!
//! Any finite prices are a valid start for the shortest-augmenting-path solver:
//! the first pricing pass sets each row dual to its row's least reduced cost, which
//! makes the duals feasible, and the exact searches do the rest, so the answer is
//! the optimum whatever the prices. Near-optimal prices only make it quick: most
//! rows take their cheapest column in that first pass, and the searches that
//! repair the rest stay short.

use super::cancel::Cancel;
use super::costs::CostSource;
use super::error::AssignError;
use super::solver::{SolveStats, Solver, NONE};

impl Solver {
    /// Exact solve of a square problem starting from the column prices `prices`
    /// (one per column, finite) instead of a column reduction; otherwise (a
    /// rectangular problem, a wrong length or a non-finite price) a cold
    /// [`Solver::solve_with`]. The result is the optimum either way; the prices
    /// only decide how much work it takes. [`SolveStats::seeded`] says which ran.
    ///
    /// # Formula
    /// As [`Solver::solve`]: the initial duals are `v = prices` (shifted so that
    /// the largest is 0, which changes no reduced-cost difference) and
    /// `u[i] = min_j c[i][j] - v[j]`.
    ///
    /// # Complexity
    /// One streaming pricing pass over the costs, an auction that ends at 1 % of
    /// its first ε, and the exact searches of the rows still free; no allocation
    /// when the dimensions equal those of the previous call.
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_from_prices<S: CostSource>(
        &mut self,
        costs: &S,
        prices: &[f64],
    ) -> Result<&[usize], AssignError> {
        self.solve_from_prices_with_cancel(costs, prices, Cancel::NEVER)
    }

    /// [`Solver::solve_from_prices`] that gives up when `cancel` says so (as
    /// [`Solver::solve_with_cancel`]).
    ///
    /// # Errors
    /// As [`Solver::solve`], and [`AssignError::Cancelled`].
    pub fn solve_from_prices_with_cancel<S: CostSource>(
        &mut self,
        costs: &S,
        prices: &[f64],
        cancel: Cancel<'_>,
    ) -> Result<&[usize], AssignError> {
        self.check_dims(costs)?;
        let (rows, cols) = (costs.rows(), costs.cols());
        let vmax = prices.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let usable = rows == cols
            && prices.len() == cols
            && vmax.is_finite()
            && prices.iter().all(|p| p.is_finite());
        if !usable {
            return self.solve_with_cancel(costs, cancel);
        }
        self.size_for(rows, cols);
        self.start_polls();
        self.clear_row_sets();
        for (v, &p) in self.v.iter_mut().zip(prices) {
            *v = p - vmax;
        }
        self.x.fill(NONE);
        self.y.fill(NONE);
        // The warm path of the driver: the first pass keeps no pair (there are
        // none), so no restart; a short auction and the exact searches follow.
        self.stats = SolveStats {
            warm: true,
            seeded: true,
            ..SolveStats::default()
        };
        self.freed_slack = 0.0;
        self.k_eff = self.k;
        self.finish(costs, cancel)
    }

    /// The row duals `u` of the last successful solve (`c[i][j] - u[i] - v[j] >= 0`,
    /// zero on the assigned pairs); empty after an error or before the first solve.
    pub fn row_duals(&self) -> &[f64] {
        if self.solved {
            &self.u
        } else {
            &[]
        }
    }

    /// The column prices `v` of the last successful solve; empty after an error or
    /// before the first solve.
    pub fn column_prices(&self) -> &[f64] {
        if self.solved {
            &self.v
        } else {
            &[]
        }
    }
}
