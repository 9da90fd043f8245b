//! Dense shortest augmenting paths ([`Strategy::Dense`], and the safety net of the
//! sparse strategy): each free row runs a Dijkstra search over the full reduced-cost
//! matrix, scanning whole contiguous rows (settled columns are masked with
//! `d = +inf`, price `-inf`, so the relaxation loop is branch-free). `O(cols)` per
//! scanned row.
//!
//! [`Strategy::Dense`]: super::Strategy::Dense

use super::cancel::Cancel;
use super::costs::CostSource;
use super::error::AssignError;
use super::solver::{Solver, NONE};

impl Solver {
    /// Dense augmentation of every free row, in index order.
    pub(super) fn dense_all<S: CostSource>(
        &mut self,
        costs: &S,
        cancel: Cancel<'_>,
    ) -> Result<(), AssignError> {
        self.free_rows.sort_unstable();
        for idx in 0..self.free_rows.len() {
            let i = self.free_rows[idx] as usize;
            if !self.dense_augment(costs, i, cancel) {
                self.halted()?;
                return Err(AssignError::Infeasible { row: i });
            }
        }
        self.free_rows.clear();
        Ok(())
    }

    /// Dijkstra over full rows from free row `i0` (requires dual feasibility on the
    /// whole matrix). Settled columns get `d = +inf` and a masked price of `-inf`, so
    /// the relaxation loop runs branch-free over all columns and never touches them.
    /// Returns false when no augmenting path exists or a poll of `cancel` found the
    /// solve cancelled (the search is dropped).
    fn dense_augment<S: CostSource>(&mut self, costs: &S, i0: usize, cancel: Cancel<'_>) -> bool {
        if self.poll(cancel) {
            return false;
        }
        self.stats.augmentations += 1;
        self.work += self.cols as u64;
        self.scanned.clear();
        let row0 = costs.row(i0, &mut self.rowbuf);
        for (((d, vm), p), (&c, &vj)) in self
            .dd
            .iter_mut()
            .zip(&mut self.vm)
            .zip(&mut self.pred)
            .zip(row0.iter().zip(&self.v))
        {
            *vm = vj;
            *d = c - vj;
            *p = i0 as u32;
        }
        let (dstar, sink) = loop {
            let mut best = f64::INFINITY;
            let mut bj = NONE;
            for (j, &d) in self.dd.iter().enumerate() {
                if d < best {
                    best = d;
                    bj = j;
                }
            }
            if bj == NONE {
                return false;
            }
            self.dist[bj] = best;
            self.dd[bj] = f64::INFINITY;
            self.vm[bj] = f64::NEG_INFINITY;
            self.scanned.push(bj as u32);
            let i = self.y[bj];
            if i == NONE {
                break (best, bj);
            }
            self.stats.rows_scanned += 1;
            self.work += 2 * self.cols as u64;
            if self.poll(cancel) {
                return false;
            }
            let row = costs.row(i, &mut self.rowbuf);
            let off = best - (row[bj] - self.v[bj]);
            let iu = i as u32;
            for ((d, p), (&c, &vm)) in self
                .dd
                .iter_mut()
                .zip(&mut self.pred)
                .zip(row.iter().zip(&self.vm))
            {
                let h = c - vm + off;
                if h < *d {
                    *d = h;
                    *p = iu;
                }
            }
        };
        for &k in &self.scanned {
            let k = k as usize;
            self.v[k] += self.dist[k] - dstar;
        }
        self.flip_path(sink, i0);
        true
    }
}
