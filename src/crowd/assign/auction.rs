//! Price initialisers of the sparse strategy (step 2): a forward auction with
//! ε-scaling (Bertsekas) on the candidate lists, and on warm starts an augmenting row
//! reduction (Jonker–Volgenant 1987).
//!
//! The auction brings the prices close to optimal cheaply; a row whose list went stale
//! (its best entry rose above `theta`) rebuilds it with one streaming pass. It is only a
//! price initialiser; exactness comes from the exact searches. After it each assigned
//! column's price is raised by its row's slack (at most the last ε) so the pairs become
//! tight, and the list bounds are lowered by as much. A warm start runs the auction
//! (its first ε sized by how far the broken pairs are off) only if more than three quarters
//! of the rows lost their pair; otherwise the row reduction: a free row takes its
//! cheapest listed column at the price that leaves it tight, bumping the previous row;
//! prices only fall, every pair stays tight.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::cancel::Cancel;
use super::candidates::{key, key_floor};
use super::costs::CostSource;
use super::solver::{Solver, NONE};

/// Candidate slots over which the local cost spread is measured for the auction.
const AUCTION_SPREAD_SLOTS: usize = 8;
/// First auction ε as a fraction of the mean local cost spread.
const AUCTION_START: f64 = 0.5;
/// Smallest first auction ε of a warm start (prices already near optimal), as
/// [`AUCTION_START`].
const AUCTION_START_WARM: f64 = 0.1;
/// First auction ε of a warm start as a fraction of the mean slack of the pairs the
/// new costs broke (clamped between the warm and the cold start).
const AUCTION_WARM_SLACK: f64 = 0.25;
/// Factor by which ε shrinks between auction phases.
const AUCTION_FACTOR: f64 = 0.1;
/// Last auction ε relative to the first.
const AUCTION_END: f64 = 1e-4;
/// Last auction ε relative to the first when the solve started from given prices
/// ([`Solver::solve_from_prices`]): they are near optimal already, and the exact
/// searches after the auction are short from there (1,000 agents against the
/// starts of a synthesised motion: 7.6–8.0 ms CPU p50 against 8.4 with
/// [`AUCTION_END`]).
const AUCTION_END_SEEDED: f64 = 1e-2;
/// Largest auction bid, in units of the first ε (rows with one finite entry).
const AUCTION_CAP: f64 = 1e6;

/// Auction bid budget per row and phase (beyond it the exact finish takes over).
const AUCTION_BIDS_PER_ROW: usize = 200;
/// Auction budget of list rebuilds (full-row passes) per row over all phases.
const AUCTION_REBUILDS_PER_ROW: u64 = 64;

/// Whether auction bids use the exact second-best value (else a lower bound).
const AUCTION_EXACT_SECOND: bool = true;

/// Bid budget of the augmenting row reduction of a warm start, per free row
/// ([`Solver::reduce_rows`]).
const ROW_REDUCTION_BIDS_PER_FREE: usize = 4;

impl Solver {
    /// Forward auction with ε-scaling over the candidate lists (Bertsekas; prices
    /// only fall, so every list threshold stays valid). It only brings the prices
    /// close to optimal; exactness comes from the finish that follows.
    pub(super) fn auction<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        let Some(spread) = self.local_spread() else {
            return;
        };
        let eps0 = if self.stats.warm {
            // Sized by how far the prices are off: the mean slack of the broken pairs.
            let freed = self.free_rows.len().max(1) as f64;
            (AUCTION_WARM_SLACK * self.freed_slack / freed)
                .clamp(AUCTION_START_WARM * spread, AUCTION_START * spread)
        } else {
            AUCTION_START * spread
        };
        if !(eps0 > 0.0 && eps0 < f64::INFINITY) {
            return;
        }
        let eps_end = eps0
            * if self.stats.seeded {
                AUCTION_END_SEEDED
            } else {
                AUCTION_END
            };
        // Bid cap for rows with a single finite candidate.
        let cap = AUCTION_CAP * eps0;
        let budget = AUCTION_BIDS_PER_ROW * self.rows + 64;
        let rebuild_budget =
            self.stats.rows_priced + AUCTION_REBUILDS_PER_ROW * self.rows as u64 + 64;
        let mut eps = eps0;
        loop {
            self.stats.auction_phases += 1;
            self.free_rows.clear();
            for i in 0..self.rows {
                if self.poll(cancel) {
                    return;
                }
                let xi = self.x[i];
                if xi != NONE {
                    let (w1, _, _) = self.best2(costs, i, false);
                    if costs.get(i, xi) - self.v[xi] <= w1 + eps {
                        continue;
                    }
                    self.x[i] = NONE;
                    self.y[xi] = NONE;
                }
                self.free_rows.push(i as u32);
            }
            let mut bids = 0;
            while let Some(i) = self.free_rows.pop() {
                if self.poll(cancel) {
                    self.stats.bids += bids as u64;
                    return;
                }
                let i = i as usize;
                bids += 1;
                let (w1, j1, w2) = self.best2(costs, i, AUCTION_EXACT_SECOND);
                if bids > budget || j1 == NONE || self.stats.rows_priced > rebuild_budget {
                    self.free_rows.push(i as u32);
                    self.stats.bids += bids as u64;
                    return;
                }
                let w2 = w2.min(w1 + cap);
                self.v[j1] -= (w2 - w1) + eps;
                let prev = self.y[j1];
                self.y[j1] = i;
                self.x[i] = j1;
                if prev != NONE {
                    self.x[prev] = NONE;
                    self.free_rows.push(prev as u32);
                }
            }
            self.stats.bids += bids as u64;
            if eps <= eps_end {
                break;
            }
            eps = (eps * AUCTION_FACTOR).max(eps_end);
        }
    }

    /// The mean spread of the rows' cheapest few reduced costs (over the first
    /// `AUCTION_SPREAD_SLOTS` list entries): the local scale of the costs. `None`
    /// when no list holds two entries.
    pub(super) fn local_spread(&self) -> Option<f64> {
        let k = self.k;
        let (mut spread, mut count) = (0.0, 0usize);
        for i in 0..self.rows {
            let len = (self.cand_len[i] as usize).min(AUCTION_SPREAD_SLOTS);
            if len >= 2 {
                spread += self.cand_wb[i * k + len - 1] - self.cand_wb[i * k];
                count += 1;
            }
        }
        (count > 0).then(|| spread / count as f64)
    }

    /// Augmenting row reduction (Jonker–Volgenant 1987) over the candidate lists: a
    /// free row takes its cheapest column `j1` and lowers its price by the gap to its
    /// second cheapest, so the new pair is tight and the row dual-feasible; the
    /// column's previous row becomes free and bids in turn. Prices only fall (every
    /// list bound stays valid) and every assigned pair stays tight, so the exact
    /// searches can follow directly. A row tied between a taken cheapest column and
    /// another, and every row beyond the bid budget, is left to the searches.
    pub(super) fn reduce_rows<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        let budget = ROW_REDUCTION_BIDS_PER_FREE * self.free_rows.len();
        let mut bids = 0usize;
        self.deferred.clear();
        while let Some(i) = self.free_rows.pop() {
            if self.poll(cancel) {
                break;
            }
            let i = i as usize;
            if bids >= budget {
                self.deferred.push(i as u32);
                continue;
            }
            bids += 1;
            let (w1, j1, w2) = self.best2(costs, i, true);
            if j1 == NONE {
                self.deferred.push(i as u32);
                continue;
            }
            let prev = self.y[j1];
            if prev != NONE && !(w1 < w2) {
                self.deferred.push(i as u32);
                continue;
            }
            if w2 < f64::INFINITY {
                self.v[j1] -= w2 - w1;
            }
            self.x[i] = j1;
            self.y[j1] = i;
            if prev != NONE {
                self.x[prev] = NONE;
                self.free_rows.push(prev as u32);
            }
        }
        self.stats.bids += bids as u64;
        self.free_rows.extend_from_slice(&self.deferred);
        self.deferred.clear();
    }

    /// After the auction: raises each assigned column's price by its row's slack so
    /// that the pair becomes tight (the pricing pass that follows frees the few rows
    /// this makes violated, and rebuilds every list).
    pub(super) fn tighten<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        let rect = self.rows < self.cols;
        let mut max_raise = 0.0f64;
        for i in 0..self.rows {
            if self.poll(cancel) {
                return;
            }
            let xi = self.x[i];
            if xi == NONE {
                continue;
            }
            let (w1, _, _) = self.best2(costs, i, false);
            let slack = costs.get(i, xi) - self.v[xi] - w1;
            if slack > 0.0 {
                let old = self.v[xi];
                self.v[xi] += slack;
                if rect && self.v[xi] > 0.0 {
                    self.v[xi] = 0.0;
                }
                self.v_hi = self.v_hi.max(self.v[xi]);
                max_raise = max_raise.max(self.v[xi] - old);
            }
        }
        // Every price rose by at most `max_raise`: lowering the list bounds and the
        // thresholds by as much keeps them valid, so the lists stay usable.
        if max_raise > 0.0 {
            let mask = self.mask;
            for wb in &mut self.cand_wb {
                *wb -= max_raise;
            }
            for (t, tk) in self.theta.iter_mut().zip(&mut self.theta_key) {
                if *t < f64::INFINITY {
                    let kk = key(*t - max_raise, 0, mask);
                    *t = key_floor(kk, mask);
                    *tk = kk;
                }
            }
        }
    }
}
