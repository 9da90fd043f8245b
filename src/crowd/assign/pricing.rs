//! Pricing rows against the column prices `v` (steps 1 and 3 of the sparse strategy,
//! and the dense strategy's pricing pass).
//!
//! A full pricing pass over the matrix (which also validates it) keeps, per row, the
//! `k` columns of smallest reduced cost `w = c - v`, sorted, and a threshold `theta`
//! below which no other column of the row lies. Prices only ever fall during the solve
//! (except where noted in `auction.rs` and for the free columns of a rectangular
//! problem, which weaken the bounds they affect), so these stay lower bounds. After the
//! auction, every row is priced against its list: rows whose pair is not tight are
//! freed, and a row whose list went stale (its best entry rose above `theta`) rebuilds
//! it with one streaming pass.

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::cancel::Cancel;
use super::candidates::{key, key_col, key_floor, select_k};
use super::costs::CostSource;
use super::error::AssignError;
use super::solver::{tol, Solver, NONE};

impl Solver {
    /// Pricing pass over every row: frees rows that are not tight, greedily assigns
    /// free rows whose cheapest column is free, collects the free rows, and (when
    /// `build`) rebuilds every candidate list. With `check` (the first pass of a
    /// solve) it also validates the entries.
    ///
    /// # Errors
    /// With `check`: [`AssignError::NotFinite`] for the first NaN / `-inf` in
    /// row-major order, else [`AssignError::Infeasible`] for the first row without a
    /// finite entry. [`AssignError::Cancelled`] when a poll of `cancel` says so.
    pub(super) fn price_all<S: CostSource>(
        &mut self,
        costs: &S,
        build: bool,
        check: bool,
        cancel: Cancel<'_>,
    ) -> Result<(), AssignError> {
        self.free_rows.clear();
        let mut unservable = None;
        for i in 0..self.rows {
            if self.poll(cancel) {
                return Err(AssignError::Cancelled);
            }
            let finite = self.price_row(costs, i, build, check)?;
            if !finite && unservable.is_none() {
                unservable = Some(i);
            }
        }
        if let (true, Some(row)) = (check, unservable) {
            return Err(AssignError::Infeasible { row });
        }
        self.raise_free_columns(costs, cancel);
        self.halted()
    }

    /// End of a sparse round: reprices the rows whose dual rose above their
    /// candidate threshold (the only rows that can have become violated).
    pub(super) fn price_dirty<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        self.free_rows.clear();
        for idx in 0..self.dirty_rows.len() {
            if self.poll(cancel) {
                return;
            }
            let i = self.dirty_rows[idx] as usize;
            self.dirty[i] = false;
            let xi = self.x[i];
            if xi == NONE {
                continue;
            }
            let (c, vx) = (costs.get(i, xi), self.v[xi]);
            if c - vx <= self.theta[i] + tol(c, vx, 0.0, 0.0) {
                continue;
            }
            let _ = self.price_row(costs, i, true, false);
        }
        self.dirty_rows.clear();
        self.raise_free_columns(costs, cancel);
    }

    /// Prices row `i` against the full row: keeps it if its pair is tight, else frees
    /// it; a free row takes its cheapest column if that column is free. With `build`,
    /// the row's candidate list is rebuilt; with `check`, NaN and `-inf` are reported.
    /// Returns whether the row has a finite entry.
    fn price_row<S: CostSource>(
        &mut self,
        costs: &S,
        i: usize,
        build: bool,
        check: bool,
    ) -> Result<bool, AssignError> {
        self.stats.rows_priced += 1;
        let (min_w, arg, bad) = if build {
            self.build_row(costs, i, check)
        } else {
            self.work += self.cols as u64;
            let row = costs.row(i, &mut self.rowbuf);
            let mut best = f64::INFINITY;
            let mut arg = NONE;
            let mut ok = true;
            for (j, (c, vj)) in row.iter().zip(&self.v).enumerate() {
                let w = c - vj;
                ok &= w > f64::NEG_INFINITY;
                if w < best {
                    best = w;
                    arg = j;
                }
            }
            let bad = if ok {
                None
            } else {
                row.iter().position(|&c| !(c > f64::NEG_INFINITY))
            };
            (best, arg, bad)
        };
        if let (true, Some(col)) = (check, bad) {
            return Err(AssignError::NotFinite { row: i, col });
        }
        let arg = if build {
            self.free_tie(costs, i, min_w, arg)
        } else {
            arg
        };
        self.settle_row(costs, i, min_w, arg);
        Ok(arg != NONE)
    }

    /// Among the listed columns of row `i` tied with its minimum `min_w` (at `arg`),
    /// one that is free if `arg` is taken (so that greedy assignment survives ties).
    fn free_tie<S: CostSource>(&self, costs: &S, i: usize, min_w: f64, arg: usize) -> usize {
        if arg == NONE || self.y[arg] == NONE {
            return arg;
        }
        let base = i * self.k;
        let len = self.cand_len[i] as usize;
        for (&c, &wb) in self.cand_col[base..base + len]
            .iter()
            .zip(&self.cand_wb[base..base + len])
        {
            let c = c as usize;
            if wb > min_w {
                break;
            }
            if self.y[c] == NONE && costs.get(i, c) - self.v[c] <= min_w {
                return c;
            }
        }
        arg
    }

    /// Keeps row `i` if its pair is tight against the row minimum `min_w` (at column
    /// `arg`), else frees it; a free row takes `arg` if that column is free.
    fn settle_row<S: CostSource>(&mut self, costs: &S, i: usize, min_w: f64, arg: usize) {
        let xi = self.x[i];
        if xi != NONE {
            let (c, vx) = (costs.get(i, xi), self.v[xi]);
            let t = if arg == NONE {
                0.0
            } else {
                tol(c, vx, costs.get(i, arg), self.v[arg])
            };
            if c - vx <= min_w + t {
                return;
            }
            self.freed_slack += c - vx - min_w;
            self.x[i] = NONE;
            self.y[xi] = NONE;
            if self.rows < self.cols {
                self.raise.push(xi as u32);
            }
        }
        if arg != NONE && self.y[arg] == NONE {
            self.x[i] = arg;
            self.y[arg] = i;
        } else {
            self.free_rows.push(i as u32);
        }
    }

    /// Rebuilds the candidate list of row `i` (its `k` smallest `(c - v, col)`) and
    /// its threshold. Returns the row's minimum `c - v`, its column, and (with
    /// `check`) the first column holding NaN or `-inf`.
    pub(super) fn build_row<S: CostSource>(
        &mut self,
        costs: &S,
        i: usize,
        check: bool,
    ) -> (f64, usize, Option<usize>) {
        let k = self.k_eff;
        let base = i * self.k;
        let mask = self.mask;
        let salt = self.salt(i);
        // Any k distinct columns bound the k-th smallest reduced cost from above:
        // the row's own list, and in a solve's first pass also the previous row's
        // (rows given in a spatial order are near each other, so the pass starts
        // each row with a tight threshold and admits few columns into the
        // selection; 1,000 agents against synthesised starts, coarse to fine:
        // 6.8 ms CPU p50 against 7.8).
        let bound = |from: usize| -> f64 {
            if self.cand_len[from] as usize >= k {
                let b = from * self.k;
                self.cand_col[b..b + k]
                    .iter()
                    .map(|&c| costs.get(i, c as usize) - self.v[c as usize])
                    .fold(f64::NEG_INFINITY, f64::max)
            } else {
                f64::INFINITY
            }
        };
        let thr0 = if check && i > 0 {
            bound(i).min(bound(i - 1))
        } else {
            bound(i)
        };
        // A spatial selection reads a few buckets around the row's point; a row
        // pass reads every column.
        self.work += match costs.points() {
            Some(_) => 4 * k as u64,
            None => self.cols as u64,
        };
        let (n, bad) = match costs.points() {
            Some(p) => {
                let n = p.select_near(i, &self.v, self.v_hi, k, mask, 0, thr0, salt, &mut self.buf);
                (n, None)
            }
            None => {
                let row = costs.row(i, &mut self.rowbuf);
                select_k::<false>(row, &self.v, k, mask, 0, thr0, check, salt, &mut self.buf)
            }
        };
        for (t, &kk) in self.buf[..n].iter().enumerate() {
            let c = key_col(kk, mask) ^ salt;
            self.cand_col[base + t] = c;
            self.cand_cost[base + t] = costs.get(i, c as usize);
            self.cand_wb[base + t] = key_floor(kk, mask);
        }
        self.cand_len[i] = n as u32;
        if n == k {
            let kk = self.buf[k - 1] + 1;
            self.theta[i] = key_floor(kk, mask);
            self.theta_key[i] = kk;
        } else {
            self.theta[i] = f64::INFINITY;
            self.theta_key[i] = u64::MAX;
        }
        match self.buf[..n].first() {
            Some(&kk) => {
                let c = (key_col(kk, mask) ^ salt) as usize;
                (costs.get(i, c) - self.v[c], c, bad)
            }
            None => (f64::INFINITY, NONE, bad),
        }
    }

    /// Minimum reduced cost `c - v` of row `i`, its column, and a lower bound of the
    /// second smallest, from the candidate list and the threshold (the list is
    /// rebuilt when stale). The scan stops as soon as the sorted list bounds prove
    /// the minimum; with `exact_second` it goes on until the second is exact too.
    pub(super) fn best2<S: CostSource>(
        &mut self,
        costs: &S,
        i: usize,
        exact_second: bool,
    ) -> (f64, usize, f64) {
        let mut rebuilt = false;
        loop {
            let base = i * self.k;
            let len = self.cand_len[i] as usize;
            self.work += len as u64;
            let (mut w1, mut j1, mut w2) = (f64::INFINITY, NONE, f64::INFINITY);
            let mut rest = f64::INFINITY;
            for ((&c, &cost), &wb) in self.cand_col[base..base + len]
                .iter()
                .zip(&self.cand_cost[base..base + len])
                .zip(&self.cand_wb[base..base + len])
            {
                // The list is sorted by `wb` and current values are >= `wb`: nothing
                // further down goes below `wb`.
                if wb >= if exact_second { w2 } else { w1 } {
                    rest = wb;
                    break;
                }
                let w = cost - self.v[c as usize];
                if w < w1 {
                    w2 = w1;
                    w1 = w;
                    j1 = c as usize;
                } else if w < w2 {
                    w2 = w;
                }
            }
            let th = self.theta[i];
            if w1 <= th || rebuilt {
                return (w1, j1, w2.min(rest).min(th));
            }
            self.stats.rows_priced += 1;
            let _ = self.build_row(costs, i, false);
            rebuilt = true;
        }
    }

    /// Pricing pass over every row using the candidate lists (a row is scanned in
    /// full only when its list is stale): as [`Solver::price_all`] otherwise.
    pub(super) fn price_all_lists<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        self.free_rows.clear();
        for i in 0..self.rows {
            if self.poll(cancel) {
                return;
            }
            self.stats.rows_priced += 1;
            let (min_w, arg, _) = self.best2(costs, i, false);
            self.settle_row(costs, i, min_w, arg);
        }
        self.raise_free_columns(costs, cancel);
    }

    /// Rectangular problems only: raises the price of every freed column back to the
    /// maximum (0), frees the assigned rows this makes non-tight (transitively), and
    /// keeps every row's candidate threshold a valid lower bound.
    fn raise_free_columns<S: CostSource>(&mut self, costs: &S, cancel: Cancel<'_>) {
        let sparse = self.use_sparse();
        while let Some(j) = self.raise.pop() {
            if self.poll(cancel) {
                return;
            }
            let j = j as usize;
            if self.y[j] != NONE || self.v[j] >= 0.0 {
                continue;
            }
            self.work += self.rows as u64;
            self.v[j] = 0.0;
            self.v_hi = self.v_hi.max(0.0);
            for r in 0..self.rows {
                let c = costs.get(r, j);
                if !(c < f64::INFINITY) {
                    continue;
                }
                if sparse && c < self.theta[r] {
                    // Column j got cheaper for row r: weaken the threshold, and clamp
                    // the list bounds (j may be on the list; clamping keeps it sorted).
                    let kk = key(c, 0, self.mask);
                    let th = key_floor(kk, self.mask);
                    self.theta[r] = th;
                    self.theta_key[r] = kk;
                    let base = r * self.k;
                    let len = self.cand_len[r] as usize;
                    for wb in &mut self.cand_wb[base..base + len] {
                        if *wb > th {
                            *wb = th;
                        }
                    }
                }
                let xr = self.x[r];
                if xr != NONE && {
                    let (cx, vx) = (costs.get(r, xr), self.v[xr]);
                    c < cx - vx - tol(c, cx, vx, 0.0)
                } {
                    self.x[r] = NONE;
                    self.y[xr] = NONE;
                    self.raise.push(xr as u32);
                    self.free_rows.push(r as u32);
                }
            }
        }
    }

    /// Per-row tie-breaking salt of the candidate keys.
    #[inline]
    pub(super) fn salt(&self, i: usize) -> u32 {
        ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as u32 & self.mask as u32
    }
}
