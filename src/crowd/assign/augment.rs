//! Exact shortest augmenting paths over the candidate lists (step 4 of the sparse
//! strategy).
//!
//! Dijkstra from each free row over the sorted lists, with lazy relaxation: a scanned
//! row relaxes its list a few slots at a time, in order of the bound
//! `offset + w_listed`; past the list, `offset + theta` guards the rest of the row,
//! fetched `k` columns at a time by a streaming pass only if the search gets that far.
//! A row whose dual outgrew its `theta` is repriced on the spot (and released if no
//! longer tight). The searches are therefore exact on the full matrix, not just on the
//! lists. A final check reprices the rows whose dual outgrew their threshold
//! (`pricing.rs`).

// NaN-aware comparisons (`!(a > b)` is true for NaN) are deliberate throughout.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::cancel::Cancel;
use super::candidates::{key_col, key_floor, select_k};
use super::costs::CostSource;
use super::heaps::{Mark, Pending, BEYOND};
use super::solver::{tol, Solver, NONE};

/// Candidate list slots relaxed at once when a scanned row's list is advanced.
const RELAX_BATCH: usize = 8;

impl Solver {
    fn next_epoch(&mut self) -> u32 {
        if self.epoch == u32::MAX {
            self.mark.fill(Mark::default());
            self.epoch = 0;
        }
        self.epoch += 1;
        self.epoch
    }

    #[inline]
    fn mark_dirty(&mut self, i: usize) {
        if !self.dirty[i] {
            self.dirty[i] = true;
            self.dirty_rows.push(i as u32);
        }
    }

    /// Dijkstra from free row `i0` over the sorted candidate lists, exact on the full
    /// matrix:
    ///
    /// * a scanned row relaxes its list lazily, a few slots at a time, in order of
    ///   the bound `off + wb[slot]` (prices only fall, so `wb` bounds the current
    ///   reduced cost from below); past the list, the bound `off + theta` guards the
    ///   rest of the row, which is fetched `k` columns at a time by a streaming pass;
    /// * a row whose dual rose above its threshold since its list was built is
    ///   repriced first; if its pair is no longer tight the row is released and its
    ///   column ends the augmenting path (the row goes back on the free list).
    ///
    /// On success updates the prices of the settled columns and flips the path.
    /// Returns false if no augmenting path exists in the whole matrix, or when a
    /// poll of `cancel` found the solve cancelled (nothing changed then but the
    /// prices of nothing: the search is dropped).
    pub(super) fn sparse_augment<S: CostSource>(
        &mut self,
        costs: &S,
        i0: usize,
        cancel: Cancel<'_>,
    ) -> bool {
        if self.poll(cancel) {
            return false;
        }
        let ep = self.next_epoch();
        self.stats.augmentations += 1;
        self.heap.clear();
        self.pending.clear();
        self.scanned.clear();
        self.early = NONE;
        // Every reduced cost of the row is at least its first list bound.
        self.cur_min = if self.cand_len[i0] > 0 {
            self.cand_wb[i0 * self.k]
        } else {
            self.theta[i0]
        };
        self.advance_list(i0, 0.0, 0, ep);
        let (dstar, sink) = loop {
            self.work += 1;
            if self.poll(cancel) {
                return false;
            }
            if self.early != NONE {
                let j = self.early;
                self.mark[j].done = ep;
                self.scanned.push(j as u32);
                break (self.mark[j].dist, j);
            }
            let hmin = self.heap.key.first().copied().unwrap_or(f64::INFINITY);
            if self.pending.min_bound() < hmin {
                if let Some(p) = self.pending.pop() {
                    if p.slot == BEYOND {
                        self.expand_row(costs, p, ep);
                    } else {
                        self.advance_list(p.row as usize, p.off, p.slot as usize, ep);
                    }
                    continue;
                }
            }
            let Some((dk, j)) = self.heap.pop() else {
                return false;
            };
            let j = j as usize;
            self.mark[j].done = ep;
            self.scanned.push(j as u32);
            self.cur_min = dk;
            let i = self.y[j];
            if i == NONE {
                break (dk, j);
            }
            self.stats.rows_scanned += 1;
            self.mark_dirty(i);
            let (cij, vj) = (costs.get(i, j), self.v[j]);
            let ui = cij - vj;
            if !(ui <= self.theta[i] + tol(cij, vj, 0.0, 0.0)) {
                self.stats.rows_priced += 1;
                let (min_w, arg, _) = self.build_row(costs, i, false);
                let t = if arg == NONE {
                    0.0
                } else {
                    tol(cij, vj, costs.get(i, arg), self.v[arg])
                };
                if !(ui <= min_w + t) {
                    self.x[i] = NONE;
                    self.y[j] = NONE;
                    self.free_rows.push(i as u32);
                    break (dk, j);
                }
            }
            self.advance_list(i, dk - ui, 0, ep);
        };
        for &k in &self.scanned {
            let k = k as usize;
            self.v[k] += self.mark[k].dist - dstar;
        }
        self.flip_path(sink, i0);
        self.mark_dirty(i0);
        true
    }

    /// Relaxes column `k` from row `i` with tentative distance `nd`.
    #[inline]
    fn relax_to(&mut self, i: u32, k: usize, nd: f64, ep: u32) {
        let m = &mut self.mark[k];
        if m.done != ep && (m.seen != ep || nd < m.dist) {
            m.seen = ep;
            m.dist = nd;
            self.pred[k] = i;
            self.heap.push_or_decrease(k as u32, nd);
            // A free column at the least possible distance ends the search at once
            // (what LAPJV does with zero reduced costs; decisive with many ties).
            if nd <= self.cur_min && self.y[k] == NONE && self.early == NONE {
                self.early = k;
            }
        }
    }

    /// Relaxes list slots `t0..t0 + RELAX_BATCH` of row `i` (distance offset `off`)
    /// and queues what is left of the row.
    fn advance_list(&mut self, i: usize, off: f64, t0: usize, ep: u32) {
        let base = i * self.k;
        let len = self.cand_len[i] as usize;
        let t1 = len.min(t0 + RELAX_BATCH);
        self.work += (t1 - t0.min(t1)) as u64;
        for s in base + t0..base + t1 {
            let k = self.cand_col[s] as usize;
            let nd = off + (self.cand_cost[s] - self.v[k]);
            self.relax_to(i as u32, k, nd, ep);
        }
        let p = if t1 < len {
            Pending {
                bound: off + self.cand_wb[base + t1],
                off,
                lo: 0,
                row: i as u32,
                slot: t1 as u32,
            }
        } else {
            Pending {
                bound: off + self.theta[i],
                off,
                lo: self.theta_key[i],
                row: i as u32,
                slot: BEYOND,
            }
        };
        if p.bound < f64::INFINITY {
            self.pending.push(p);
        }
    }

    /// Relaxes the next `k` cheapest columns of a row beyond its list (one streaming
    /// pass) and queues the row again with the raised bound.
    fn expand_row<S: CostSource>(&mut self, costs: &S, p: Pending, ep: u32) {
        self.stats.expansions += 1;
        let k = self.k;
        self.work += match costs.points() {
            Some(_) => 4 * k as u64,
            None => self.cols as u64,
        };
        let mask = self.mask;
        let salt = self.salt(p.row as usize);
        let i = p.row as usize;
        let n = match costs.points() {
            Some(pc) => pc.select_near(
                i,
                &self.v,
                self.v_hi,
                k,
                mask,
                p.lo,
                f64::INFINITY,
                salt,
                &mut self.buf,
            ),
            None => {
                let row = costs.row(i, &mut self.rowbuf);
                let (n, _) = select_k::<true>(
                    row,
                    &self.v,
                    k,
                    mask,
                    p.lo,
                    f64::INFINITY,
                    false,
                    salt,
                    &mut self.buf,
                );
                n
            }
        };
        for t in 0..n {
            let c = (key_col(self.buf[t], mask) ^ salt) as usize;
            let nd = p.off + (costs.get(i, c) - self.v[c]);
            self.relax_to(p.row, c, nd, ep);
        }
        if n == k {
            let lo = self.buf[k - 1] + 1;
            let bound = p.off + key_floor(lo, mask);
            if bound < f64::INFINITY {
                self.pending.push(Pending { bound, lo, ..p });
            }
        }
    }

    /// Flips the alternating path ending at free column `sink` back to row `i0`.
    pub(super) fn flip_path(&mut self, sink: usize, i0: usize) {
        let mut j = sink;
        loop {
            let i = self.pred[j] as usize;
            let prev = self.x[i];
            self.y[j] = i;
            self.x[i] = j;
            if i == i0 {
                break;
            }
            j = prev;
        }
    }
}
