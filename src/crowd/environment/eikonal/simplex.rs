//! The primal network simplex for an uncapacitated transshipment problem: the
//! solver of [`GridTransport`](super::GridTransport).
//!
//! Minimise `Σ c_a f_a` over flows `f ≥ 0` with supply `b_v = out − in` at every
//! node (`Σ b = 0`), arcs uncapacitated. The method is the textbook one (Ahuja,
//! Magnanti and Orlin, *Network Flows*, ch. 11): a spanning-tree basis rooted at an
//! artificial node joined to every node by an arc of prohibitive cost, kept
//! strongly feasible (a zero-flow tree arc points towards the root) so that it
//! cannot cycle; entering arcs are priced block by block (the block search of
//! LEMON's implementation, blocks of `√m` arcs), the leaving arc is the last
//! blocking arc of the cycle, and the subtree cut off by the leaving arc is hung
//! again from the entering arc with its potentials shifted. Optimal when no arc
//! has a negative reduced cost `c_a + π_tail − π_head`; feasible when no
//! artificial arc carries flow.

/// No node.
const NONE: u32 = u32::MAX;

/// Why the simplex stopped without an optimum.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(super) enum SimplexError {
    /// Supplies do not sum to zero, or some supply cannot reach a demand.
    Infeasible,
    /// A cycle of negative cost with no arc to limit it (a negative arc cost).
    Unbounded,
    /// The caller's check asked to stop.
    Cancelled,
}

/// Workspaces and the solution of the last solve.
#[derive(Default)]
pub(super) struct Simplex {
    tail: Vec<u32>,
    head: Vec<u32>,
    cost: Vec<i64>,
    flow: Vec<i64>,
    in_tree: Vec<bool>,
    parent: Vec<u32>,
    pred: Vec<u32>,
    up: Vec<bool>,
    depth: Vec<u32>,
    pi: Vec<i64>,
    first_child: Vec<u32>,
    next_sib: Vec<u32>,
    prev_sib: Vec<u32>,
    stack: Vec<u32>,
    /// Pivots of the last solve.
    pub pivots: u64,
}

impl Simplex {
    /// Clears the arcs for a problem on `nodes` nodes.
    pub fn reset(&mut self, nodes: usize) {
        self.tail.clear();
        self.head.clear();
        self.cost.clear();
        let n1 = nodes + 1;
        for v in [
            &mut self.parent,
            &mut self.pred,
            &mut self.first_child,
            &mut self.next_sib,
            &mut self.prev_sib,
        ] {
            v.clear();
            v.resize(n1, NONE);
        }
        self.up.clear();
        self.up.resize(n1, false);
        self.depth.clear();
        self.depth.resize(n1, 0);
        self.pi.clear();
        self.pi.resize(n1, 0);
    }

    /// Adds the arc `tail → head` of cost `cost` (at least 0); returns its index.
    pub fn add_arc(&mut self, tail: u32, head: u32, cost: i64) -> usize {
        self.tail.push(tail);
        self.head.push(head);
        self.cost.push(cost);
        self.tail.len() - 1
    }

    /// The flow on arc `a` of the last solve.
    pub fn flow(&self, a: usize) -> i64 {
        self.flow[a]
    }

    #[inline]
    fn rc(&self, a: usize) -> i64 {
        self.cost[a] + self.pi[self.tail[a] as usize] - self.pi[self.head[a] as usize]
    }

    fn add_child(&mut self, p: u32, c: u32) {
        let f = self.first_child[p as usize];
        self.next_sib[c as usize] = f;
        self.prev_sib[c as usize] = NONE;
        if f != NONE {
            self.prev_sib[f as usize] = c;
        }
        self.first_child[p as usize] = c;
    }

    fn remove_child(&mut self, p: u32, c: u32) {
        let (pv, nx) = (self.prev_sib[c as usize], self.next_sib[c as usize]);
        if pv == NONE {
            self.first_child[p as usize] = nx;
        } else {
            self.next_sib[pv as usize] = nx;
        }
        if nx != NONE {
            self.prev_sib[nx as usize] = pv;
        }
    }

    /// Solves with supplies `supply` (one per node, summing to 0), polling
    /// `cancelled` every few hundred pivots.
    pub fn solve(
        &mut self,
        supply: &[i64],
        cancelled: impl Fn() -> bool,
    ) -> Result<(), SimplexError> {
        let n = supply.len();
        if supply.iter().sum::<i64>() != 0 || self.parent.len() != n + 1 {
            return Err(SimplexError::Infeasible);
        }
        let m = self.tail.len();
        let root = n as u32;
        let maxc = self.cost.iter().copied().max().unwrap_or(0).max(0);
        let art = (maxc + 1).saturating_mul(n as i64 + 1);
        self.flow.clear();
        self.flow.resize(m + n, 0);
        self.in_tree.clear();
        self.in_tree.resize(m + n, false);
        self.tail.truncate(m);
        self.head.truncate(m);
        self.cost.truncate(m);
        self.first_child[n] = NONE;
        for (v, &b) in supply.iter().enumerate() {
            let a = m + v;
            let (t, h) = if b >= 0 {
                (v as u32, root)
            } else {
                (root, v as u32)
            };
            self.tail.push(t);
            self.head.push(h);
            self.cost.push(art);
            self.flow[a] = b.abs();
            self.in_tree[a] = true;
            self.up[v] = b >= 0;
            self.pi[v] = if b >= 0 { -art } else { art };
            self.parent[v] = root;
            self.pred[v] = a as u32;
            self.depth[v] = 1;
            self.first_child[v] = NONE;
            self.add_child(root, v as u32);
        }
        let total = m + n;
        let block = ((total as f64).sqrt() as usize).max(10);
        let mut next = 0usize;
        self.pivots = 0;
        loop {
            if self.pivots % 256 == 255 && cancelled() {
                return Err(SimplexError::Cancelled);
            }
            let Some(enter) = self.price(block, &mut next) else {
                break;
            };
            self.pivot(enter)?;
            self.pivots += 1;
        }
        if self.flow[m..].iter().any(|&f| f > 0) {
            return Err(SimplexError::Infeasible);
        }
        self.tail.truncate(m);
        self.head.truncate(m);
        self.cost.truncate(m);
        Ok(())
    }

    /// Block search: the arc of most negative reduced cost in the first block
    /// (from `next`, cyclically) that has one.
    fn price(&self, block: usize, next: &mut usize) -> Option<usize> {
        let total = self.tail.len();
        let (mut best, mut enter, mut count) = (0i64, None, 0usize);
        for _ in 0..total {
            let a = *next;
            *next = if a + 1 == total { 0 } else { a + 1 };
            if !self.in_tree[a] {
                let r = self.rc(a);
                if r < best {
                    best = r;
                    enter = Some(a);
                }
            }
            count += 1;
            if count == block {
                if enter.is_some() {
                    return enter;
                }
                count = 0;
            }
        }
        enter
    }

    fn pivot(&mut self, enter: usize) -> Result<(), SimplexError> {
        let (u, w) = (self.tail[enter], self.head[enter]);
        let (mut x, mut y) = (u, w);
        while x != y {
            let (dx, dy) = (self.depth[x as usize], self.depth[y as usize]);
            if dx >= dy {
                x = self.parent[x as usize];
            }
            if dy >= dx {
                y = self.parent[y as usize];
            }
        }
        let join = x;
        // The leaving arc: the last blocking arc met going round the cycle from
        // the join along the entering arc's direction (u's side first).
        let (mut delta, mut out, mut u_side) = (i64::MAX, NONE, false);
        let mut v = u;
        while v != join {
            if self.up[v as usize] {
                let d = self.flow[self.pred[v as usize] as usize];
                if d < delta {
                    (delta, out, u_side) = (d, v, true);
                }
            }
            v = self.parent[v as usize];
        }
        let mut v = w;
        while v != join {
            if !self.up[v as usize] {
                let d = self.flow[self.pred[v as usize] as usize];
                if d <= delta {
                    (delta, out, u_side) = (d, v, false);
                }
            }
            v = self.parent[v as usize];
        }
        if out == NONE {
            return Err(SimplexError::Unbounded);
        }
        if delta > 0 {
            self.flow[enter] += delta;
            for (start, sign) in [(u, -1), (w, 1)] {
                let mut v = start;
                while v != join {
                    let e = self.pred[v as usize] as usize;
                    let s = if self.up[v as usize] { sign } else { -sign };
                    self.flow[e] += s * delta;
                    v = self.parent[v as usize];
                }
            }
        }
        let (x_in, y_in) = if u_side { (u, w) } else { (w, u) };
        self.in_tree[self.pred[out as usize] as usize] = false;
        self.in_tree[enter] = true;
        let r = self.rc(enter);
        let sigma = if x_in == w { r } else { -r };
        // Reverse the tree path x_in … out and hang it from y_in.
        let (mut v, mut new_parent, mut new_pred, mut new_up) =
            (x_in, y_in, enter as u32, x_in == u);
        loop {
            let (old_parent, old_pred, old_up) = (
                self.parent[v as usize],
                self.pred[v as usize],
                self.up[v as usize],
            );
            self.remove_child(old_parent, v);
            self.parent[v as usize] = new_parent;
            self.pred[v as usize] = new_pred;
            self.up[v as usize] = new_up;
            self.add_child(new_parent, v);
            if v == out {
                break;
            }
            (new_parent, new_pred, new_up) = (v, old_pred, !old_up);
            v = old_parent;
        }
        self.stack.clear();
        self.stack.push(x_in);
        while let Some(v) = self.stack.pop() {
            let p = self.parent[v as usize];
            self.depth[v as usize] = self.depth[p as usize] + 1;
            self.pi[v as usize] += sigma;
            let mut c = self.first_child[v as usize];
            while c != NONE {
                self.stack.push(c);
                c = self.next_sib[c as usize];
            }
        }
        Ok(())
    }
}
