//! The `k` nearest neighbours of every agent within a range, for the baselines
//! that avoid a bounded number of neighbours (RVO in `rvo.rs`, the steering of
//! `steer.rs`), as the RVO library's and OpenSteer's proximity queries give them.
//! Buffers sized once; rebuilding the lists allocates nothing.

use crate::crowd::agents::NeighbourGrid;
use crate::geom::Vec2;

/// Up to `k` nearest neighbours of each agent within a range.
#[derive(Clone, Debug)]
pub(crate) struct NearestLists {
    grid: NeighbourGrid,
    k: usize,
    /// `k` (distance², index) slots per agent.
    near: Vec<(f64, u32)>,
    len: Vec<u32>,
}

impl NearestLists {
    /// Lists of at most `k` neighbours for `n` agents.
    pub(crate) fn new(n: usize, k: usize) -> NearestLists {
        NearestLists {
            grid: NeighbourGrid::with_capacity(n),
            k,
            near: vec![(0.0, 0); n * k],
            len: vec![0; n],
        }
    }

    /// Agent `i`'s list offered `j` at squared distance `d2`: kept while the list
    /// has room, else in place of its farthest if nearer.
    fn offer(&mut self, i: usize, j: usize, d2: f64) {
        let k = self.k;
        if k == 0 {
            return;
        }
        let slots = &mut self.near[i * k..(i + 1) * k];
        let len = self.len[i] as usize;
        if len < k {
            slots[len] = (d2, j as u32);
            self.len[i] += 1;
            return;
        }
        let mut far = 0;
        for s in 1..k {
            if slots[s].0 > slots[far].0 {
                far = s;
            }
        }
        if d2 < slots[far].0 {
            slots[far] = (d2, j as u32);
        }
    }

    /// Every agent's nearest neighbours within `range_m` of `pos`, sorted nearest
    /// first (ties by index, so the order does not depend on the grid's).
    pub(crate) fn build(&mut self, pos: &[Vec2], range_m: f64) {
        let n = pos.len();
        self.len[..n].fill(0);
        let range = range_m.max(1e-9);
        self.grid.build(pos, range);
        let grid = std::mem::take(&mut self.grid);
        grid.for_each_pair_d2(pos, range, |i, j, _, d2| {
            self.offer(i, j, d2);
            self.offer(j, i, d2);
        });
        self.grid = grid;
        let k = self.k;
        for i in 0..n {
            let len = self.len[i] as usize;
            self.near[i * k..i * k + len]
                .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        }
    }

    /// Agent `i`'s neighbours from the last [`build`](Self::build), nearest first.
    pub(crate) fn of(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let len = self.len[i] as usize;
        self.near[i * self.k..i * self.k + len]
            .iter()
            .map(|&(_, j)| j as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_k_nearest_within_range_nearest_first() {
        let pos: Vec<Vec2> = (0..6).map(|k| Vec2::new(k as f64, 0.0)).collect();
        let mut l = NearestLists::new(pos.len(), 2);
        l.build(&pos, 2.5);
        assert_eq!(l.of(0).collect::<Vec<_>>(), [1, 2]);
        assert_eq!(l.of(3).collect::<Vec<_>>(), [2, 4]);
        // Out of range: nothing.
        l.build(&pos, 0.5);
        assert_eq!(l.of(3).count(), 0);
    }
}
