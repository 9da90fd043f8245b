//! Mutual-information feedback (formation-transform section 3.3, eqs. 11–19): the
//! mutual information between where agents are (bins of `R × R` metres) and where
//! they head (`K` sectors) or how fast they go (`K` speed bins), and the per-bin
//! adjustment of each agent's heading and desired speed towards its bin's.
//!
//! # Interpretation of eqs. 18–19
//! As printed, eq. 18 adds the scalar mean `|e_a − e_a'|` to the vector `e_a` and
//! eq. 19 only ever raises `v⁰_a`. Both are read here as what the text says they
//! are for ("the direction for the agent a will keep its step with its
//! neighbours"): a pull towards the bin's others with strength `I`,
//! `e_a ← normalise(e_a + g_d Σ_{a'≠a} (e_a' − e_a) / num(i, j))` and
//! `v⁰_a ← v⁰_a + g_v Σ_{a'≠a} (v⁰_a' − v⁰_a) / num(i, j)`, with gains
//! `g_d = min(I_d, 1)` and `g_v = min(I_v, 1)` so that a pull never overshoots the
//! bin's mean.
//!
//! Agents flagged as settled (arrived, at rest) take no part: they have no heading.

use crate::geom::Vec2;

/// Largest number of bins along one axis; a crowd spread wider shares the last bin.
pub(crate) const MAX_AXIS_BINS: usize = 1024;

/// `I(G, H)` in bits (eq. 11 with `n = 2`, as eqs. 15–16) of the paired labels
/// `g[k] ∈ 0..ng`, `h[k] ∈ 0..nh`; entries with `skip[k]` do not count. `joint`
/// holds at least `ng · nh`, `pg` at least `ng`, `ph` at least `nh` counters
/// (cleared here). Zero when fewer than one entry counts.
#[allow(clippy::too_many_arguments)]
pub(crate) fn mutual_information(
    g: &[u32],
    ng: usize,
    h: &[u32],
    nh: usize,
    skip: &[bool],
    joint: &mut [u32],
    pg: &mut [u32],
    ph: &mut [u32],
) -> f64 {
    joint[..ng * nh].fill(0);
    pg[..ng].fill(0);
    ph[..nh].fill(0);
    let mut n = 0u32;
    for k in 0..g.len() {
        if skip[k] {
            continue;
        }
        let (a, b) = (g[k] as usize, h[k] as usize);
        joint[a * nh + b] += 1;
        pg[a] += 1;
        ph[b] += 1;
        n += 1;
    }
    if n == 0 {
        return 0.0;
    }
    let nf = n as f64;
    let mut i = 0.0;
    for a in 0..ng {
        if pg[a] == 0 {
            continue;
        }
        for b in 0..nh {
            let c = joint[a * nh + b];
            if c == 0 {
                continue;
            }
            // p(a,b) log2 (p(a,b) / (p(a) p(b))) with counts: (c/n) log2(c n / (ca cb)).
            let ratio = (c as f64 * nf) / (pg[a] as f64 * ph[b] as f64);
            i += (c as f64 / nf) * ratio.log2();
        }
    }
    i.max(0.0)
}

/// The sector `0..k` of heading `v` (eq. 14: sector `i` covers angles
/// `[i 2π/K, (i + 1) 2π/K)`, angles in `[0, 2π)`).
pub(crate) fn sector(v: Vec2, k: usize) -> u32 {
    let mut a = v.y.atan2(v.x);
    if a < 0.0 {
        a += std::f64::consts::TAU;
    }
    ((a / std::f64::consts::TAU * k as f64) as usize).min(k - 1) as u32
}

/// Buffers of the feedback and of the `I_d`, `I_v` measures, sized for `n` agents
/// and `k` sectors once.
#[derive(Clone, Debug)]
pub(crate) struct Feedback {
    k: usize,
    bin_m: f64,
    bx: Vec<u32>,
    by: Vec<u32>,
    dir: Vec<u32>,
    spd: Vec<u32>,
    joint: Vec<u32>,
    pg: Vec<u32>,
    ph: Vec<u32>,
    cell: Vec<u32>,
    cell_count: Vec<u32>,
    cell_e: Vec<Vec2>,
    cell_v0: Vec<f64>,
}

/// What [`Feedback::measure`] found.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub(crate) struct Information {
    /// `I_d` (eq. 17, bits).
    pub i_d: f64,
    /// `I_v` (bits).
    pub i_v: f64,
}

impl Feedback {
    /// For `n` agents, bins of `bin_m` metres, `k ≥ 1` sectors and speed bins.
    pub(crate) fn new(n: usize, bin_m: f64, k: usize) -> Feedback {
        let k = k.max(1);
        let cells = 4 * n + 64;
        Feedback {
            k,
            bin_m: if bin_m.is_finite() && bin_m > 0.0 {
                bin_m
            } else {
                1.0
            },
            bx: vec![0; n],
            by: vec![0; n],
            dir: vec![0; n],
            spd: vec![0; n],
            joint: vec![0; MAX_AXIS_BINS * k],
            pg: vec![0; MAX_AXIS_BINS],
            ph: vec![0; k],
            cell: vec![0; n],
            cell_count: vec![0; cells],
            cell_e: vec![Vec2::zeros(); cells],
            cell_v0: vec![0.0; cells],
        }
    }

    /// Bins the agents by position and labels them by heading sector and speed bin
    /// (speeds over `[0, max_speed_m_s]`); returns the bins along x and y.
    fn label(
        &mut self,
        pos: &[Vec2],
        vel: &[Vec2],
        max_speed_m_s: f64,
        skip: &[bool],
    ) -> (usize, usize) {
        let r = self.bin_m;
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        for (p, &s) in pos.iter().zip(skip) {
            if !s {
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        if !(lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite()) {
            return (1, 1);
        }
        // Bins at multiples of R as in eqs. 12–13, counted from the first one used.
        let (x0, y0) = ((lo.x / r).floor(), (lo.y / r).floor());
        let nx = (((hi.x / r).floor() - x0) as usize + 1).min(MAX_AXIS_BINS);
        let ny = (((hi.y / r).floor() - y0) as usize + 1).min(MAX_AXIS_BINS);
        let k = self.k;
        for i in 0..pos.len() {
            if skip[i] {
                continue;
            }
            let p = pos[i];
            self.bx[i] = (((p.x / r).floor() - x0).max(0.0) as usize).min(nx - 1) as u32;
            self.by[i] = (((p.y / r).floor() - y0).max(0.0) as usize).min(ny - 1) as u32;
            self.dir[i] = sector(vel[i], k);
            let s = vel[i].norm() / max_speed_m_s.max(1e-9);
            self.spd[i] = ((s * k as f64) as usize).min(k - 1) as u32;
        }
        (nx, ny)
    }

    /// `I_d` (eq. 17) and `I_v` of agents at `pos` moving at `vel`, the agents with
    /// `skip` left out.
    pub(crate) fn measure(
        &mut self,
        pos: &[Vec2],
        vel: &[Vec2],
        max_speed_m_s: f64,
        skip: &[bool],
    ) -> Information {
        let (nx, ny) = self.label(pos, vel, max_speed_m_s, skip);
        let k = self.k;
        let (j, pg, ph) = (&mut self.joint, &mut self.pg, &mut self.ph);
        let ixd = mutual_information(&self.bx, nx, &self.dir, k, skip, j, pg, ph);
        let iyd = mutual_information(&self.by, ny, &self.dir, k, skip, j, pg, ph);
        let ixv = mutual_information(&self.bx, nx, &self.spd, k, skip, j, pg, ph);
        let iyv = mutual_information(&self.by, ny, &self.spd, k, skip, j, pg, ph);
        Information {
            i_d: 0.5 * (ixd + iyd),
            i_v: 0.5 * (ixv + iyv),
        }
    }

    /// Eqs. 18–19 as interpreted in the module docs: pulls each agent's unit
    /// heading `e[i]` and desired speed `v0[i]` towards the others' in its `R × R`
    /// bin with gains `min(info.i_d, 1)` and `min(info.i_v, 1)`, the heading's gain
    /// times `weight[i]` (the transform fades it out near the target, where an
    /// agent's heading is its own). Uses the bins of the
    /// last [`measure`](Self::measure) (same `pos` and `skip`). When the crowd spans
    /// more bins than the buffers hold, bins are merged in blocks (coarser bins).
    pub(crate) fn adjust(
        &mut self,
        e: &mut [Vec2],
        v0: &mut [f64],
        skip: &[bool],
        weight: &[f64],
        info: Information,
    ) {
        let gd = info.i_d.clamp(0.0, 1.0);
        let gv = info.i_v.clamp(0.0, 1.0);
        if gd == 0.0 && gv == 0.0 {
            return;
        }
        let (mut nx, mut ny) = (1u32, 1u32);
        for ((&s, &x), &y) in skip.iter().zip(&self.bx).zip(&self.by).take(e.len()) {
            if !s {
                nx = nx.max(x + 1);
                ny = ny.max(y + 1);
            }
        }
        let cap = self.cell_count.len();
        let mut block = 1u32;
        while (nx.div_ceil(block) as usize) * (ny.div_ceil(block) as usize) > cap {
            block *= 2;
        }
        let wx = nx.div_ceil(block);
        let cells = (wx * ny.div_ceil(block)) as usize;
        self.cell_count[..cells].fill(0);
        self.cell_e[..cells].fill(Vec2::zeros());
        self.cell_v0[..cells].fill(0.0);
        for i in 0..e.len() {
            if skip[i] {
                continue;
            }
            let c = ((self.by[i] / block) * wx + self.bx[i] / block) as usize;
            self.cell[i] = c as u32;
            self.cell_count[c] += 1;
            self.cell_e[c] += e[i];
            self.cell_v0[c] += v0[i];
        }
        for i in 0..e.len() {
            if skip[i] {
                continue;
            }
            let c = self.cell[i] as usize;
            let num = self.cell_count[c] as f64;
            if num < 2.0 {
                continue;
            }
            // Σ_{a'≠a} (e_a' − e_a) / num = (Σ e − num e_a) / num.
            let de = (self.cell_e[c] - e[i] * num) / num;
            let adj = e[i] + de * (gd * weight[i]);
            let n = adj.norm();
            if n > 1e-9 {
                e[i] = adj / n;
            }
            v0[i] += gv * (self.cell_v0[c] - v0[i] * num) / num;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mi(g: &[u32], ng: usize, h: &[u32], nh: usize) -> f64 {
        let skip = vec![false; g.len()];
        let (mut j, mut a, mut b) = (vec![0; ng * nh], vec![0; ng], vec![0; nh]);
        mutual_information(g, ng, h, nh, &skip, &mut j, &mut a, &mut b)
    }

    /// Entropy in bits of labels, by hand.
    fn entropy(h: &[u32], nh: usize) -> f64 {
        let n = h.len() as f64;
        (0..nh)
            .map(|b| h.iter().filter(|&&x| x as usize == b).count() as f64 / n)
            .filter(|&p| p > 0.0)
            .map(|p| -p * p.log2())
            .sum()
    }

    #[test]
    fn one_heading_carries_no_information() {
        let g = [0, 1, 2, 3, 0, 1, 2, 3];
        assert_eq!(mi(&g, 4, &[5; 8], 8), 0.0);
    }

    #[test]
    fn heading_a_function_of_x_carries_its_entropy() {
        // Four x bins; heading sector = 2 · bin (so D is a function of X).
        let g = [0, 0, 1, 2, 2, 2, 3, 1, 0, 3];
        let h: Vec<u32> = g.iter().map(|&x| 2 * x).collect();
        let i = mi(&g, 4, &h, 8);
        assert!((i - entropy(&h, 8)).abs() < 1e-12, "{i}");
    }

    #[test]
    fn independent_labels_carry_none_and_a_hand_case_matches() {
        // X and D independent by construction (every pair once).
        let mut g = vec![];
        let mut h = vec![];
        for a in 0..3 {
            for b in 0..4 {
                g.push(a);
                h.push(b);
            }
        }
        assert!(mi(&g, 3, &h, 4).abs() < 1e-12);
        // p(0,0)=1/2, p(1,1)=1/4, p(1,0)=1/4: brute force of eq. 15.
        let (g, h) = ([0, 0, 1, 1], [0, 0, 1, 0]);
        let want = 0.5 * (0.5f64 / (0.5 * 0.75)).log2()
            + 0.25 * (0.25f64 / (0.5 * 0.25)).log2()
            + 0.25 * (0.25f64 / (0.5 * 0.75)).log2();
        assert!((mi(&g, 2, &h, 2) - want).abs() < 1e-12);
    }

    #[test]
    fn sectors_follow_eq_14() {
        assert_eq!(sector(Vec2::new(1.0, 0.0), 8), 0);
        assert_eq!(sector(Vec2::new(0.0, 1.0), 8), 2);
        assert_eq!(sector(Vec2::new(-1.0, 0.0), 8), 4);
        assert_eq!(sector(Vec2::new(0.0, -1.0), 8), 6);
        assert_eq!(sector(Vec2::new(1.0, -1e-9), 8), 7);
    }

    #[test]
    fn adjustment_pulls_headings_in_a_bin_together() {
        // Two bins of four agents each, headings spread in each.
        let pos: Vec<Vec2> = (0..8)
            .map(|i| Vec2::new(if i < 4 { 0.5 } else { 2.5 }, 0.1 * i as f64))
            .collect();
        let e0: Vec<Vec2> = (0..8)
            .map(|i| {
                let a = 0.4 * (i % 4) as f64 + if i < 4 { 0.0 } else { 2.0 };
                Vec2::new(a.cos(), a.sin())
            })
            .collect();
        let skip = vec![false; 8];
        let mut f = Feedback::new(8, 2.0, 8);
        let info = f.measure(&pos, &e0, 1.0, &skip);
        // X separates the two bins' sectors (I(X,D) = 1), one y bin (I(Y,D) = 0).
        assert!((info.i_d - 0.5).abs() < 1e-12, "{info:?}");
        let spread = |e: &[Vec2]| -> f64 {
            let mut s = 0.0;
            for b in [0..4, 4..8] {
                let m: Vec2 = e[b.clone()].iter().sum::<Vec2>() / 4.0;
                s += e[b].iter().map(|x| (x - m).norm_squared()).sum::<f64>();
            }
            s
        };
        let mut e = e0.clone();
        let mut v0 = vec![1.0, 1.2, 1.4, 1.6, 1.0, 1.0, 1.0, 1.0];
        let info = Information { i_v: 0.5, ..info };
        f.adjust(&mut e, &mut v0, &skip, &[1.0; 8], info);
        assert!(
            spread(&e) < 0.5 * spread(&e0),
            "{} vs {}",
            spread(&e),
            spread(&e0)
        );
        assert!(e.iter().all(|x| (x.norm() - 1.0).abs() < 1e-12));
        let range = v0[..4].iter().cloned().fold(f64::MIN, f64::max)
            - v0[..4].iter().cloned().fold(f64::MAX, f64::min);
        assert!(range < 0.6, "{v0:?}");
        // The mean desired speed of the bin is kept.
        assert!((v0[..4].iter().sum::<f64>() - 5.2).abs() < 1e-9);
    }
}
