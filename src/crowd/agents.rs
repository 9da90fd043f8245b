//! Agents: point masses that follow their goals with a PD controller and push each
//! other apart.
//!
//! mesh-formation-control section 6.2.1: "The characters then move to their
//! corresponding target locations with a simple PD controller. A maximum speed is
//! defined to avoid unnatural fast movement." Overlap is resolved as in
//! gesture-driven-crowd-motion section 7.3: each character is a cylinder and a
//! spring-mass model pushes penetrating characters apart with a force proportional
//! to the penetration depth, along the line between their centres.

use crate::geom::Vec2;

/// Tunables of agent motion.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct AgentParams {
    /// Body radius (m).
    pub radius_m: f64,
    /// Speed limit (m/s).
    pub max_speed_m_s: f64,
    /// Acceleration limit (m/s²).
    pub max_accel_m_s2: f64,
    /// PD proportional gain (1/s²).
    pub kp_per_s2: f64,
    /// PD derivative gain (1/s).
    pub kd_per_s: f64,
    /// Push-back stiffness per metre of penetration (1/s², unit mass).
    pub push_stiffness_per_s2: f64,
}

/// Longest time step integrated at once (s); longer ticks are split.
pub const MAX_SUBSTEP_S: f64 = 1.0 / 60.0;

/// The agents and the workspace their step reuses.
#[derive(Clone, Debug, Default)]
pub struct Agents {
    pos: Vec<Vec2>,
    vel: Vec<Vec2>,
    grid: NeighbourGrid,
    /// Positions in the grid's cell order (`sorted_pos[k] = pos[grid.items[k]]`),
    /// so the push-apart pass reads neighbours from contiguous memory.
    sorted_pos: Vec<Vec2>,
    /// Push-apart accelerations in the same order.
    sorted_push: Vec<Vec2>,
    /// The same accelerations in the agents' order (`push[grid.items[k]] =
    /// sorted_push[k]`), so the integration reads every per-agent array in order.
    push: Vec<Vec2>,
}

impl Agents {
    /// Agents at `positions`, at rest.
    pub fn new(positions: &[Vec2]) -> Agents {
        Agents {
            pos: positions.to_vec(),
            vel: vec![Vec2::zeros(); positions.len()],
            grid: NeighbourGrid::default(),
            sorted_pos: Vec::with_capacity(positions.len()),
            sorted_push: Vec::with_capacity(positions.len()),
            push: Vec::with_capacity(positions.len()),
        }
    }

    /// Number of agents.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Positions (m).
    pub fn positions(&self) -> &[Vec2] {
        &self.pos
    }

    /// Velocities (m/s).
    pub fn velocities(&self) -> &[Vec2] {
        &self.vel
    }

    /// Positions (m) and velocities (m/s) for a mover that integrates them itself
    /// (a formation transform, [`crate::crowd::transform::TransformRun::step`]).
    pub fn state_mut(&mut self) -> (&mut [Vec2], &mut [Vec2]) {
        (&mut self.pos, &mut self.vel)
    }

    /// Moves every agent to `positions` and stops it (hard reset).
    pub fn teleport(&mut self, positions: &[Vec2]) {
        self.pos.clear();
        self.pos.extend_from_slice(positions);
        self.vel.clear();
        self.vel.resize(positions.len(), Vec2::zeros());
    }

    /// Mean distance from each agent to its goal (m): the lag that drives the
    /// opposing force of mesh-formation-control section 4.1.
    pub fn mean_goal_distance(&self, goals: &[Vec2], goal_of: &[u32]) -> f64 {
        if self.pos.is_empty() {
            return 0.0;
        }
        let sum: f64 = self
            .pos
            .iter()
            .zip(goal_of)
            .map(|(p, &g)| (goals[g as usize] - p).norm())
            .sum();
        sum / self.pos.len() as f64
    }

    /// Advances the agents by `dt_s` towards `goals[goal_of[i]]`.
    ///
    /// # Formula
    /// Per agent, unit mass: `a = kp (g − x) − kd v + Σ_j k (2r − d_ij) n̂_ij` over
    /// neighbours closer than `2r` (gesture-driven section 7.3 push-back), `|a|`
    /// clamped to `max_accel`, semi-implicit Euler `v += a dt; |v| ≤ max_speed;
    /// x += v dt`, in substeps of at most [`MAX_SUBSTEP_S`].
    ///
    /// # Complexity
    /// O(n) expected with the uniform neighbour grid; no allocation once the grid
    /// has grown to the crowd's size.
    pub fn step(&mut self, goals: &[Vec2], goal_of: &[u32], dt_s: f64, p: &AgentParams) {
        if dt_s.is_nan() || dt_s <= 0.0 || self.pos.is_empty() {
            return;
        }
        let substeps = (dt_s / MAX_SUBSTEP_S).ceil().clamp(1.0, 64.0) as usize;
        let h = dt_s / substeps as f64;
        for _ in 0..substeps {
            self.substep(p, |i, x, v, push| {
                let g = goals[goal_of[i] as usize];
                integrate(x, v, g, push, (), |_| (), |()| 1.0, h, p);
            });
        }
    }

    /// Advances the agents by `dt_s` towards per-agent `targets` (a goal or a
    /// waypoint on the way to it), each agent's speed limit scaled by
    /// `speed_factor(x)`, the travel speed of the terrain at `x`
    /// (mesh-formation-control section 6.2.3: "the average travel speed determines
    /// the speed of the agent as it passes through the patch").
    ///
    /// The terrain is read in every substep, where the agent is and where the
    /// substep takes it: an agent entering a slower patch moves at the patch's
    /// speed from the substep it enters, not from the next tick.
    ///
    /// # Formula
    /// As [`step`](Self::step) with `|v| ≤ speed_factor(x) · max_speed` at the
    /// substep's start `x`; if the end `x + v h` is slower still, `v` is scaled to
    /// its limit (and the end moved back accordingly).
    ///
    /// # Panics
    /// If `targets` has fewer entries than there are agents.
    pub fn step_towards(
        &mut self,
        targets: &[Vec2],
        speed_factor: impl Fn(Vec2) -> f64,
        dt_s: f64,
        p: &AgentParams,
    ) {
        if dt_s.is_nan() || dt_s <= 0.0 || self.pos.is_empty() {
            return;
        }
        let substeps = (dt_s / MAX_SUBSTEP_S).ceil().clamp(1.0, 64.0) as usize;
        let h = dt_s / substeps as f64;
        for _ in 0..substeps {
            self.substep(p, |i, x, v, push| {
                let here = speed_factor(*x);
                integrate(x, v, targets[i], push, here, &speed_factor, |s| s, h, p);
            });
        }
    }

    /// [`step_towards`](Self::step_towards) on ground that `read(x)` describes
    /// (the terrain of a scene at this tick's time) and `speed_factor` turns into
    /// the speed factor, with each agent's ground kept in `ground` at the point it
    /// was read: the ground is read only at points not read before. Afterwards
    /// `ground` holds every agent's ground at its new position (see
    /// [`GroundCache::values_at`]).
    ///
    /// The motion is bit for bit that of `step_towards` with
    /// `|x| speed_factor(read(x))`, provided `read` answers a point as it did when
    /// `ground` kept it (call [`GroundCache::forget`] when the ground changes).
    ///
    /// # Complexity
    /// One read per agent and substep, where the substep ends (the start of a
    /// substep is where the last one ended, or where the last step left the agent),
    /// plus one where an agent slowed down for the ground ahead, or was moved
    /// since its ground was read. No allocation once `ground` has the crowd's
    /// size.
    ///
    /// # Panics
    /// If `targets` has fewer entries than there are agents.
    pub fn step_over<T: Copy>(
        &mut self,
        targets: &[Vec2],
        ground: &mut GroundCache<T>,
        read: impl Fn(Vec2) -> T,
        speed_factor: impl Fn(T) -> f64,
        dt_s: f64,
        p: &AgentParams,
    ) {
        if dt_s.is_nan() || dt_s <= 0.0 || self.pos.is_empty() {
            return;
        }
        ground.fit(&self.pos, &read);
        let substeps = (dt_s / MAX_SUBSTEP_S).ceil().clamp(1.0, 64.0) as usize;
        let h = dt_s / substeps as f64;
        for _ in 0..substeps {
            self.substep(p, |i, x, v, push| {
                let here = ground.get(i, *x, &read);
                let there = integrate(x, v, targets[i], push, here, &read, &speed_factor, h, p);
                if let Some(t) = there {
                    ground.put(i, *x, t);
                }
            });
        }
    }

    /// Moves agent `i` to `pos` keeping its velocity's component along the move
    /// (an obstacle stopped the rest).
    pub fn set_position(&mut self, i: usize, pos: Vec2) {
        let d = pos - self.pos[i];
        let n2 = d.norm_squared();
        if n2 > 0.0 {
            // Remove the velocity pointing back into the obstacle (against d).
            let into = self.vel[i].dot(&d);
            if into < 0.0 {
                self.vel[i] -= d * (into / n2);
            }
        }
        self.pos[i] = pos;
    }

    /// The push-back of every pair closer than `two_r`, `k (2r − d) n̂` on one agent
    /// and its opposite on the other (gesture-driven section 7.3), summed per agent
    /// into `sorted_push` in the order of the grid just built on `pos`.
    ///
    /// The positions are copied in the grid's cell order first. In that order a cell
    /// and its right-hand neighbour are one contiguous range, and so are the three
    /// cells below them, so each agent meets its forward neighbours in two runs of
    /// contiguous memory instead of five lists of indices.
    fn push_apart(&mut self, two_r: f64, stiffness: f64) {
        let grid = &self.grid;
        let (nx, ny) = (grid.nx, grid.ny);
        if nx == 0 {
            return;
        }
        let n = self.pos.len();
        self.sorted_pos.clear();
        self.sorted_pos
            .extend(grid.items.iter().map(|&i| self.pos[i as usize]));
        self.sorted_push.clear();
        self.sorted_push.resize(n, Vec2::zeros());
        let (sp, push, items) = (&self.sorted_pos, &mut self.sorted_push, &grid.items);
        let start = |c: usize| grid.cell_start[c] as usize;
        let r2 = two_r * two_r;
        // Agent `k` (at `pk`) against the run `m0..m1` after it: a plain loop over
        // contiguous slices that the compiler inlines and unrolls (a closure called
        // per pair was not inlined, and a call per candidate pair cost a third of
        // the push-apart).
        let mut run = |k: usize, pk: Vec2, m0: usize, m1: usize| {
            for m in m0..m1 {
                let d = pk - sp[m];
                let d2 = d.norm_squared();
                if d2 < r2 {
                    let dist = d2.sqrt();
                    let (i, j) = (items[k] as usize, items[m] as usize);
                    let f = unit_or_fixed(d, dist, i, j) * (stiffness * (two_r - dist));
                    push[k] += f;
                    push[m] -= f;
                }
            }
        };
        for cy in 0..ny {
            for cx in 0..nx {
                let c = cy * nx + cx;
                let (a0, a1) = (start(c), start(c + 1));
                if a0 == a1 {
                    continue;
                }
                // This cell and the one to its right.
                let same_end = if cx + 1 < nx { start(c + 2) } else { a1 };
                // The three cells below (left, under, right), clipped at the edges.
                let below = if cy + 1 < ny {
                    let lo = c + nx - usize::from(cx > 0);
                    let hi = c + nx + 1 + usize::from(cx + 1 < nx);
                    start(lo)..start(hi)
                } else {
                    0..0
                };
                for (k, &pk) in (a0..a1).zip(&sp[a0..a1]) {
                    run(k, pk, k + 1, same_end);
                    run(k, pk, below.start, below.end);
                }
            }
        }
    }

    /// One substep: the push-apart accelerations, then
    /// `one(i, x, v, push)` integrates agent `i`, in the agents' order.
    fn substep(&mut self, p: &AgentParams, mut one: impl FnMut(usize, &mut Vec2, &mut Vec2, Vec2)) {
        let n = self.pos.len();
        let two_r = 2.0 * p.radius_m;
        if p.push_stiffness_per_s2 > 0.0 && two_r > 0.0 {
            self.grid.build(&self.pos, two_r);
            self.push_apart(two_r, p.push_stiffness_per_s2);
            // A grid left empty (a non-finite position) pushes no one.
            if self.grid.items.len() == n {
                // Back to the agents' order: one scattered write per agent here
                // instead of scattered reads of position, velocity and target in
                // the integration (which is bound by memory latency at 10,000).
                // `items` is a permutation of the agents: every entry is written.
                self.push.resize(n, Vec2::zeros());
                for (&i, &f) in self.grid.items.iter().zip(&self.sorted_push) {
                    self.push[i as usize] = f;
                }
                for (i, ((x, v), &f)) in self
                    .pos
                    .iter_mut()
                    .zip(self.vel.iter_mut())
                    .zip(&self.push)
                    .enumerate()
                {
                    one(i, x, v, f);
                }
                return;
            }
        }
        for (i, (x, v)) in self.pos.iter_mut().zip(self.vel.iter_mut()).enumerate() {
            one(i, x, v, Vec2::zeros());
        }
    }
}

/// One agent's substep: PD acceleration towards `g` plus `push`, clamped, then
/// semi-implicit Euler with the speed limits of [`Agents::step_towards`]: the
/// limit at the start is `speed(here)` (`here` the ground at `x`), the one ahead
/// `speed(read(x + w h))`.
///
/// Returns the ground read ahead when the agent ends exactly there (it did not
/// slow down for it): the ground at the new `x`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn integrate<T: Copy>(
    x: &mut Vec2,
    v: &mut Vec2,
    g: Vec2,
    push: Vec2,
    here: T,
    read: impl Fn(Vec2) -> T,
    speed: impl Fn(T) -> f64,
    h: f64,
    p: &AgentParams,
) -> Option<T> {
    let mut a = (g - *x) * p.kp_per_s2 - *v * p.kd_per_s + push;
    // Squared norms first: most agents are under both limits and need no root
    // (the scaling is out of line, so the compiler does not compute it for every
    // agent and select).
    let amax = p.max_accel_m_s2;
    let an2 = a.norm_squared();
    if an2 > amax * amax {
        a = scaled_to(a, amax, an2);
    }
    let vmax = p.max_speed_m_s * speed(here);
    let mut w = *v + a * h;
    let wn2 = w.norm_squared();
    if wn2 > vmax * vmax {
        w = scaled_to(w, vmax, wn2);
    }
    // Entering a slower patch in this substep: its limit holds from here.
    let end = *x + w * h;
    let there = read(end);
    let vmax_there = p.max_speed_m_s * speed(there);
    if vmax_there < vmax {
        let wn2 = w.norm_squared();
        if wn2 > vmax_there * vmax_there {
            w *= vmax_there / wn2.sqrt();
        }
    }
    *v = w;
    *x += w * h;
    same_point(*x, end).then_some(there)
}

/// `u` scaled to length `len` (`n2 = |u|²`), as `u *= len / √n2`.
#[cold]
#[inline(never)]
fn scaled_to(mut u: Vec2, len: f64, n2: f64) -> Vec2 {
    u *= len / n2.sqrt();
    u
}

/// Whether `a` and `b` are the same point bit for bit.
#[inline(always)]
fn same_point(a: Vec2, b: Vec2) -> bool {
    a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()
}

/// What a step reads under each agent (in a scene, the terrain at one time),
/// kept per agent with the point it was read at, so that the ground is read
/// again only where the agent has moved since ([`Agents::step_over`]; the
/// engine's motion types, from the same values).
///
/// A kept value is used only for the very point it was read at (compared bit
/// for bit), however the agent got there, so agents moved by other means (an
/// obstacle pushing them out, a reset, a formation transform, edit mode) are
/// read again. What it cannot see is the ground itself changing: call
/// [`forget`](Self::forget) then (another scene; moving patches at a new time).
///
/// Entry `i` belongs to agent `i`; a crowd that grows adds entries (allocating
/// only beyond [`with_capacity`](Self::with_capacity)), one that shrinks drops
/// them.
#[derive(Clone, Debug)]
pub struct GroundCache<T> {
    entries: Vec<GroundEntry<T>>,
    /// Entries of another epoch are stale ([`forget`](Self::forget)).
    epoch: u64,
}

/// One agent's ground, read at `at` in `epoch`.
#[derive(Copy, Clone, Debug)]
struct GroundEntry<T> {
    at: Vec2,
    epoch: u64,
    value: T,
}

impl<T> Default for GroundCache<T> {
    fn default() -> Self {
        GroundCache {
            entries: Vec::new(),
            epoch: 0,
        }
    }
}

impl<T: Copy> GroundCache<T> {
    /// An empty cache with room for `n` agents.
    pub fn with_capacity(n: usize) -> GroundCache<T> {
        GroundCache {
            entries: Vec::with_capacity(n),
            epoch: 0,
        }
    }

    /// Room for `n` agents in all (a crowd about to grow).
    pub fn reserve(&mut self, n: usize) {
        self.entries.reserve(n.saturating_sub(self.entries.len()));
    }

    /// The ground changed: every value is read again when next asked for.
    pub fn forget(&mut self) {
        self.epoch += 1;
    }

    /// Each agent's ground at `positions` (the same agents, in order), read with
    /// `read` where it was not read at that very point since the last
    /// [`forget`](Self::forget), and kept. Lazy: agent `i` is looked at when the
    /// iterator reaches it.
    pub fn values_at<'a>(
        &'a mut self,
        positions: &'a [Vec2],
        read: impl Fn(Vec2) -> T + 'a,
    ) -> impl ExactSizeIterator<Item = T> + 'a {
        self.fit(positions, &read);
        let epoch = self.epoch;
        self.entries
            .iter_mut()
            .zip(positions)
            .map(move |(e, &p)| e.get(epoch, p, &read))
    }

    /// As many entries as `positions`: extra ones dropped, missing ones read.
    fn fit(&mut self, positions: &[Vec2], read: impl Fn(Vec2) -> T) {
        let epoch = self.epoch;
        self.entries.truncate(positions.len());
        let have = self.entries.len();
        self.entries
            .extend(positions[have..].iter().map(|&at| GroundEntry {
                at,
                epoch,
                value: read(at),
            }));
    }

    /// Agent `i`'s ground at `p`: the kept value if it was read at `p`, else read
    /// and kept.
    #[inline(always)]
    fn get(&mut self, i: usize, p: Vec2, read: impl Fn(Vec2) -> T) -> T {
        let epoch = self.epoch;
        self.entries[i].get(epoch, p, read)
    }

    /// Keeps `value` as agent `i`'s ground at `at`.
    #[inline(always)]
    fn put(&mut self, i: usize, at: Vec2, value: T) {
        self.entries[i] = GroundEntry {
            at,
            epoch: self.epoch,
            value,
        };
    }
}

impl<T: Copy> GroundEntry<T> {
    #[inline(always)]
    fn get(&mut self, epoch: u64, p: Vec2, read: impl Fn(Vec2) -> T) -> T {
        if self.epoch != epoch || !same_point(self.at, p) {
            *self = GroundEntry {
                at: p,
                epoch,
                value: read(p),
            };
        }
        self.value
    }
}

/// Most cells per agent; a sparse crowd gets coarser cells instead of more.
const MAX_CELLS_PER_AGENT: usize = 4;

/// A uniform grid over agents for neighbour queries: pairs within a radius (push-back
/// here; forces, overlap resolution and overlap counting in a formation transform) and
/// each agent's nearest neighbour by a ring search (`σ_min_dis`, formation-transform
/// eq. 24). Rebuilt in place each step by a counting sort; no allocation once its
/// buffers have the crowd's size (reserved by [`with_capacity`](Self::with_capacity),
/// or by the first [`build`](Self::build)).
#[derive(Clone, Debug, Default)]
pub struct NeighbourGrid {
    origin: Vec2,
    cell_m: f64,
    nx: usize,
    ny: usize,
    cell_start: Vec<u32>,
    items: Vec<u32>,
    cell_of: Vec<u32>,
}

impl NeighbourGrid {
    /// A grid for `n` agents with every buffer reserved.
    pub fn with_capacity(n: usize) -> NeighbourGrid {
        let cells = (MAX_CELLS_PER_AGENT * n).max(16) + 1;
        NeighbourGrid {
            cell_start: Vec::with_capacity(cells),
            items: Vec::with_capacity(n),
            cell_of: Vec::with_capacity(n),
            ..NeighbourGrid::default()
        }
    }

    /// Side of a cell (m), at least the `cell_m` asked of [`build`](Self::build).
    pub fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Buckets `pos` into cells of at least `cell_m` metres. Non-finite positions
    /// leave the grid empty.
    pub fn build(&mut self, pos: &[Vec2], cell_m: f64) {
        let n = pos.len();
        let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
        for p in pos {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        self.items.clear();
        self.cell_of.clear();
        self.cell_start.clear();
        if n == 0 || !(lo.x.is_finite() && lo.y.is_finite() && hi.x.is_finite() && hi.y.is_finite())
        {
            self.nx = 0;
            self.ny = 0;
            return;
        }
        let ext = hi - lo;
        let mut cell = cell_m.max(1e-6);
        let max_cells = (MAX_CELLS_PER_AGENT * n).max(16);
        while ((ext.x / cell) as usize + 1) * ((ext.y / cell) as usize + 1) > max_cells {
            cell *= 2.0;
        }
        self.origin = lo;
        self.cell_m = cell;
        self.nx = (ext.x / cell) as usize + 1;
        self.ny = (ext.y / cell) as usize + 1;
        let cells = self.nx * self.ny;
        // The most cells this crowd size can use, so a moving crowd never makes the
        // grid grow again (a no-op after `with_capacity`).
        self.cell_start.reserve(max_cells + 1);
        self.cell_start.resize(cells + 1, 0);
        // Cells first, then their counts: two tight loops (one pushing and counting
        // stored the vector's length and waited on the count's store every agent).
        self.cell_of.resize(n, 0);
        let (origin, cell_m, nx, ny) = (self.origin, self.cell_m, self.nx, self.ny);
        for (c, p) in self.cell_of.iter_mut().zip(pos) {
            *c = cell_index(origin, cell_m, nx, ny, *p) as u32;
        }
        // Counting sort with the cursors at the cells' ends: `cell_start[c]` counts
        // cell `c`, the running sum turns it into the cell's end, and filling from
        // the last agent backwards leaves it at the cell's start (agents ascending
        // within a cell) with no pass to shift the starts back.
        for &c in &self.cell_of {
            self.cell_start[c as usize] += 1;
        }
        for c in 1..cells {
            self.cell_start[c] += self.cell_start[c - 1];
        }
        self.cell_start[cells] = n as u32;
        self.items.resize(n, 0);
        for (i, &c) in self.cell_of.iter().enumerate().rev() {
            let slot = &mut self.cell_start[c as usize];
            *slot -= 1;
            self.items[*slot as usize] = i as u32;
        }
    }

    fn cell_xy(&self, p: Vec2) -> (usize, usize) {
        cell_xy(self.origin, self.cell_m, self.nx, self.ny, p)
    }

    #[cfg(test)]
    fn cell_index(&self, p: Vec2) -> usize {
        cell_index(self.origin, self.cell_m, self.nx, self.ny, p)
    }

    fn cell_items(&self, c: usize) -> &[u32] {
        &self.items[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }

    /// Calls `f(i, j, distance, unit vector from j to i)` once for every pair closer
    /// than `radius` (at most the cell side), `pos` being the positions the grid was
    /// built on. Coincident agents get a direction fixed by their indices.
    pub fn for_each_pair(
        &self,
        pos: &[Vec2],
        radius: f64,
        mut f: impl FnMut(usize, usize, f64, Vec2),
    ) {
        self.for_each_pair_d2(pos, radius, |i, j, d, d2| {
            let dist = d2.sqrt();
            f(i, j, dist, unit_or_fixed(d, dist, i, j));
        });
    }

    /// Calls `f(i, j, pos[i] − pos[j], squared distance)` once for every pair closer
    /// than `radius` (at most the cell side), in the order of
    /// [`for_each_pair`](Self::for_each_pair), without a square root: for callers
    /// that need only a cut-off test or the squared distance.
    #[inline]
    pub fn for_each_pair_d2(
        &self,
        pos: &[Vec2],
        radius: f64,
        mut f: impl FnMut(usize, usize, Vec2, f64),
    ) {
        if self.nx == 0 {
            return;
        }
        let r2 = radius * radius;
        for cy in 0..self.ny {
            for cx in 0..self.nx {
                let c = cy * self.nx + cx;
                let a = self.cell_items(c);
                if a.is_empty() {
                    continue;
                }
                // This cell and the four "forward" neighbours: each pair seen once.
                for (dx, dy) in [(0i64, 0i64), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                    let (ox, oy) = (cx as i64 + dx, cy as i64 + dy);
                    if ox < 0 || oy < 0 || ox >= self.nx as i64 || oy >= self.ny as i64 {
                        continue;
                    }
                    let o = oy as usize * self.nx + ox as usize;
                    let b = self.cell_items(o);
                    for (ai, &i) in a.iter().enumerate() {
                        let i = i as usize;
                        let pi = pos[i];
                        let rest = if o == c { &b[ai + 1..] } else { b };
                        for &j in rest {
                            let j = j as usize;
                            let d = pi - pos[j];
                            let d2 = d.norm_squared();
                            if d2 < r2 {
                                f(i, j, d, d2);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Distance from agent `i` to its nearest other agent (m), by rings of cells
    /// around its own until no closer agent can be farther out; `INFINITY` alone.
    pub fn nearest_distance(&self, pos: &[Vec2], i: usize) -> f64 {
        if self.nx == 0 {
            return f64::INFINITY;
        }
        let p = pos[i];
        let (cx, cy) = self.cell_xy(p);
        let (cx, cy) = (cx as i64, cy as i64);
        let mut best2 = f64::INFINITY;
        let max_ring = self.nx.max(self.ny) as i64;
        for k in 0..=max_ring {
            // Every agent in ring k is at least (k − 1)·cell away.
            let reach = (k - 1).max(0) as f64 * self.cell_m;
            if reach * reach > best2 {
                break;
            }
            for oy in (cy - k)..=(cy + k) {
                if oy < 0 || oy >= self.ny as i64 {
                    continue;
                }
                let on_edge_row = oy == cy - k || oy == cy + k;
                let mut ox = cx - k;
                while ox <= cx + k {
                    if ox >= 0 && ox < self.nx as i64 {
                        for &j in self.cell_items(oy as usize * self.nx + ox as usize) {
                            if j as usize != i {
                                best2 = best2.min((pos[j as usize] - p).norm_squared());
                            }
                        }
                    }
                    // Inner rows of the ring: only the two end cells.
                    ox += if on_edge_row || k == 0 { 1 } else { 2 * k };
                }
            }
        }
        best2.sqrt()
    }
}

/// The grid cell `(column, row)` of `p` in a grid of `nx × ny` cells of side
/// `cell_m` from `origin`, points outside clamped to the nearest cell.
#[inline(always)]
fn cell_xy(origin: Vec2, cell_m: f64, nx: usize, ny: usize, p: Vec2) -> (usize, usize) {
    let q = (p - origin) / cell_m;
    let cx = (q.x.max(0.0) as usize).min(nx - 1);
    let cy = (q.y.max(0.0) as usize).min(ny - 1);
    (cx, cy)
}

/// The row-major index of [`cell_xy`]'s cell.
#[inline(always)]
fn cell_index(origin: Vec2, cell_m: f64, nx: usize, ny: usize, p: Vec2) -> usize {
    let (cx, cy) = cell_xy(origin, cell_m, nx, ny, p);
    cy * nx + cx
}

/// `d / dist`, or for coincident agents (`dist ≤ 1e-12`) a unit vector fixed by
/// their indices, opposite for `(i, j)` and `(j, i)`.
#[inline]
pub(crate) fn unit_or_fixed(d: Vec2, dist: f64, i: usize, j: usize) -> Vec2 {
    if dist > 1e-12 {
        d / dist
    } else {
        let a = (i.min(j) as f64) * 2.399963;
        let s = if i < j { 1.0 } else { -1.0 };
        Vec2::new(a.cos(), a.sin()) * s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use proptest::prelude::*;

    fn params() -> AgentParams {
        AgentParams {
            radius_m: 0.15,
            max_speed_m_s: 1.5,
            max_accel_m_s2: 6.0,
            kp_per_s2: 16.0,
            kd_per_s: 8.0,
            push_stiffness_per_s2: 200.0,
        }
    }

    #[test]
    fn single_agent_reaches_goal_without_exceeding_max_speed() {
        let mut a = Agents::new(&[Vec2::new(0.0, 0.0)]);
        let goals = [Vec2::new(3.0, 4.0)];
        let mut vmax: f64 = 0.0;
        for _ in 0..(8 * 120) {
            a.step(&goals, &[0], 1.0 / 120.0, &params());
            vmax = vmax.max(a.velocities()[0].norm());
        }
        assert!(
            (a.positions()[0] - goals[0]).norm() < 1e-3,
            "{:?}",
            a.positions()[0]
        );
        assert!(vmax <= 1.5 + 1e-9);
        // 5 m at 1.5 m/s cannot take less than 3.33 s.
        let mut b = Agents::new(&[Vec2::new(0.0, 0.0)]);
        for _ in 0..(3 * 120) {
            b.step(&goals, &[0], 1.0 / 120.0, &params());
        }
        assert!((b.positions()[0] - goals[0]).norm() > 0.4);
    }

    #[test]
    fn an_agent_entering_a_slow_patch_slows_the_tick_it_enters() {
        // Open ground west of x = 1, a patch at 0.3 of the speed east of it.
        let speed = |x: Vec2| if x.x > 1.0 { 0.3 } else { 1.0 };
        let mut a = Agents::new(&[Vec2::new(0.0, 0.0)]);
        let target = [Vec2::new(10.0, 0.0)];
        let dt = 1.0 / 60.0;
        let (mut ticks_in, mut before) = (0, 0.0f64);
        for _ in 0..240 {
            a.step_towards(&target, speed, dt, &params());
            let (x, v) = (a.positions()[0], a.velocities()[0].norm());
            if x.x > 1.0 {
                assert!(
                    v <= 0.3 * 1.5 + 1e-9,
                    "at {x} in the patch at {v} m/s, tick {ticks_in} in"
                );
                ticks_in += 1;
            } else {
                before = before.max(v);
            }
        }
        assert!(
            before > 1.4,
            "reached full speed before the patch: {before}"
        );
        assert!(ticks_in > 100, "went into the patch");
    }

    /// Ground for the cache tests: open west of x = 2, a slow band to x = 4, mud
    /// beyond; read as `(speed factor, which)`.
    fn bands(x: Vec2) -> (f64, u8) {
        if x.x < 2.0 {
            (1.0, 0)
        } else if x.x < 4.0 {
            (0.3, 1)
        } else {
            (0.6, 2)
        }
    }

    fn same_bits(a: &[Vec2], b: &[Vec2]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| same_point(*p, *q))
    }

    /// With the ground kept between substeps and steps, a crowd walking over
    /// ground of three speeds moves bit for bit as when every point is read
    /// afresh, in ticks of one substep and of several, while reading the ground
    /// about once per agent and substep instead of twice; the values kept are the
    /// ground under every agent, also after agents are moved by other means.
    #[test]
    fn kept_ground_moves_agents_bit_for_bit_as_fresh_reads() {
        use std::cell::Cell;
        let start = cloud(300, 5, 1.5);
        let targets: Vec<Vec2> = (0..300)
            .map(|i| Vec2::new(6.0 + (i % 20) as f64 * 0.1, (i / 20) as f64 * 0.1))
            .collect();
        let (mut fresh, mut kept) = (Agents::new(&start), Agents::new(&start));
        let mut ground = GroundCache::with_capacity(300);
        let (fresh_reads, kept_reads) = (Cell::new(0usize), Cell::new(0usize));
        let substeps = Cell::new(0usize);
        for k in 0..800 {
            // Mostly one substep a tick, now and then three.
            let dt = if k % 7 == 3 { 0.04 } else { 1.0 / 120.0 };
            substeps.set(substeps.get() + if k % 7 == 3 { 3 } else { 1 });
            let speed = |x: Vec2| {
                fresh_reads.set(fresh_reads.get() + 1);
                bands(x).0
            };
            fresh.step_towards(&targets, speed, dt, &params());
            let read = |x: Vec2| {
                kept_reads.set(kept_reads.get() + 1);
                bands(x)
            };
            kept.step_over(&targets, &mut ground, read, |g| g.0, dt, &params());
            assert!(same_bits(fresh.positions(), kept.positions()), "tick {k}");
            assert!(same_bits(fresh.velocities(), kept.velocities()), "tick {k}");
            if k % 50 == 25 {
                // Moved some other way (an obstacle's push, say): read again.
                for i in (0..300).step_by(9) {
                    let q = fresh.positions()[i] + Vec2::new(0.7, 0.0);
                    fresh.set_position(i, q);
                    kept.set_position(i, q);
                }
            }
            let before = kept_reads.get();
            let under: Vec<(f64, u8)> = ground.values_at(kept.positions(), read).collect();
            let want: Vec<(f64, u8)> = kept.positions().iter().map(|&x| bands(x)).collect();
            assert_eq!(under, want, "tick {k}");
            if k % 50 != 25 {
                // Only agents that slowed down for the band ahead need a read.
                assert!(kept_reads.get() - before < 30, "tick {k}");
            }
        }
        let (f, c, n) = (fresh_reads.get(), kept_reads.get(), 300 * substeps.get());
        eprintln!("ground reads: {f} afresh, {c} kept, {n} agent-substeps");
        assert_eq!(f, 2 * n);
        assert!(c < n + n / 10, "{c} reads for {n} agent-substeps");
        assert!(
            kept.positions().iter().all(|p| p.x > 4.0),
            "crossed every band"
        );
    }

    /// A kept value is used only at the very point it was read, and not after
    /// [`GroundCache::forget`]; the cache follows the crowd's size.
    #[test]
    fn ground_cache_reads_only_points_it_has_not_read() {
        use std::cell::Cell;
        let reads = Cell::new(0usize);
        let read = |x: Vec2| {
            reads.set(reads.get() + 1);
            x.x
        };
        let mut pos = vec![
            Vec2::new(1.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(3.0, 0.0),
        ];
        let mut g = GroundCache::default();
        assert_eq!(g.values_at(&pos, read).collect::<Vec<_>>(), [1.0, 2.0, 3.0]);
        assert_eq!(reads.replace(0), 3);
        assert_eq!(g.values_at(&pos, read).count(), 3);
        assert_eq!(reads.replace(0), 0);
        // The next float up is another point; so is −0 against +0.
        pos[1].x = f64::from_bits(2.0f64.to_bits() + 1);
        pos[2].y = -0.0;
        let got: Vec<f64> = g.values_at(&pos, read).collect();
        assert_eq!(got, [1.0, pos[1].x, 3.0]);
        assert_eq!(reads.replace(0), 2);
        g.forget();
        assert_eq!(g.values_at(&pos, read).count(), 3);
        assert_eq!(reads.replace(0), 3);
        // Shrinks and grows with the crowd; new agents are read.
        assert_eq!(g.values_at(&pos[..1], read).count(), 1);
        assert_eq!(reads.replace(0), 0);
        pos.push(Vec2::new(7.0, 0.0));
        let all: Vec<f64> = g.values_at(&pos, read).collect();
        assert_eq!(all, [1.0, pos[1].x, 3.0, 7.0]);
        assert_eq!(reads.replace(0), 3);
    }

    #[test]
    fn overlapping_agents_separate_to_two_radii() {
        let mut a = Agents::new(&[Vec2::new(0.0, 0.0), Vec2::new(0.05, 0.0)]);
        let goals = [Vec2::new(0.0, 0.0)];
        let mut p = params();
        p.kp_per_s2 = 0.0;
        for _ in 0..600 {
            a.step(&goals, &[0, 0], 1.0 / 120.0, &p);
        }
        let d = (a.positions()[0] - a.positions()[1]).norm();
        assert!(d >= 0.3 - 1e-3, "{d}");
    }

    #[test]
    fn coincident_agents_still_separate() {
        let mut a = Agents::new(&[Vec2::new(1.0, 1.0); 3]);
        let mut p = params();
        p.kp_per_s2 = 0.0;
        for _ in 0..600 {
            a.step(&[Vec2::new(1.0, 1.0)], &[0, 0, 0], 1.0 / 120.0, &p);
        }
        for i in 0..3 {
            for j in i + 1..3 {
                assert!((a.positions()[i] - a.positions()[j]).norm() > 0.25);
            }
        }
    }

    fn cloud(n: usize, seed: u64, side: f64) -> Vec<Vec2> {
        let mut r = SplitMix64::new(seed);
        (0..n)
            .map(|_| Vec2::new(r.uniform(0.0, side), r.uniform(0.0, side)))
            .collect()
    }

    /// The pairs closer than `r` the grid built on `pos` finds, `(min, max)`, sorted.
    fn grid_pairs(g: &NeighbourGrid, pos: &[Vec2], r: f64) -> Vec<(usize, usize)> {
        let mut got = vec![];
        g.for_each_pair(pos, r, |i, j, _, _| got.push((i.min(j), i.max(j))));
        got.sort();
        got
    }

    /// The pairs closer than `r` by checking every pair, `(i, j)` with `i < j`, sorted.
    fn brute_pairs(pos: &[Vec2], r: f64) -> Vec<(usize, usize)> {
        let mut want = vec![];
        for i in 0..pos.len() {
            for j in i + 1..pos.len() {
                if (pos[i] - pos[j]).norm_squared() < r * r {
                    want.push((i, j));
                }
            }
        }
        want
    }

    #[test]
    fn pairs_and_nearest_match_brute_force() {
        for (seed, side, cell) in [(1, 10.0, 0.7), (2, 40.0, 0.5), (3, 3.0, 2.0)] {
            let pos = cloud(300, seed, side);
            let mut g = NeighbourGrid::with_capacity(pos.len());
            g.build(&pos, cell);
            let r = g.cell_m().min(cell);
            assert_eq!(grid_pairs(&g, &pos, r), brute_pairs(&pos, r));
            for i in 0..pos.len() {
                let brute = (0..pos.len())
                    .filter(|&j| j != i)
                    .map(|j| (pos[i] - pos[j]).norm())
                    .fold(f64::INFINITY, f64::min);
                assert_eq!(g.nearest_distance(&pos, i), brute, "agent {i}");
            }
        }
    }

    #[test]
    fn a_lone_agent_has_no_neighbour() {
        let pos = [Vec2::new(1.0, 2.0)];
        let mut g = NeighbourGrid::with_capacity(1);
        g.build(&pos, 1.0);
        assert_eq!(g.nearest_distance(&pos, 0), f64::INFINITY);
    }

    /// The push-back of one step equals the sum over every overlapping pair, checked
    /// pair by pair (gesture-driven section 7.3), in crowds sparse, dense and piled up.
    #[test]
    fn push_back_equals_the_brute_force_sum_over_pairs() {
        for (seed, n, side) in [(1, 400, 12.0), (2, 400, 2.0), (3, 60, 0.2), (4, 1, 1.0)] {
            let mut pos = cloud(n, seed, side);
            if n > 10 {
                pos[7] = pos[3]; // two coincident agents
            }
            let mut p = params();
            p.kp_per_s2 = 0.0;
            p.kd_per_s = 0.0;
            p.max_accel_m_s2 = 1e12;
            p.max_speed_m_s = 1e12;
            let h = 1e-3;
            let mut a = Agents::new(&pos);
            a.step(&[Vec2::zeros()], &vec![0; n], h, &p);
            let two_r = 2.0 * p.radius_m;
            let mut want = vec![Vec2::zeros(); n];
            for i in 0..n {
                for j in i + 1..n {
                    let d = pos[i] - pos[j];
                    let dist = d.norm();
                    if dist < two_r {
                        let f = unit_or_fixed(d, dist, i, j)
                            * (p.push_stiffness_per_s2 * (two_r - dist));
                        want[i] += f;
                        want[j] -= f;
                    }
                }
            }
            for (i, (v, w)) in a.velocities().iter().zip(&want).enumerate() {
                let got = v / h;
                assert!(
                    (got - w).norm() <= 1e-9 * (1.0 + w.norm()),
                    "seed {seed}, agent {i}: {got} vs {w}"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The grid finds exactly the pairs brute force finds.
        #[test]
        fn grid_pairs_equal_brute_force(pts in proptest::collection::vec((-5.0f64..5.0, -5.0f64..5.0), 0..80), r in 0.05f64..2.0) {
            let pos: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
            let mut g = NeighbourGrid::default();
            g.build(&pos, r);
            prop_assert_eq!(grid_pairs(&g, &pos, r), brute_pairs(&pos, r));
        }

        /// Each cell lists exactly the agents in it, in ascending order (the order
        /// the push-apart sums in), and the cells' starts bracket their lists.
        #[test]
        fn grid_cells_hold_their_agents_in_order(pts in proptest::collection::vec((-5.0f64..5.0, -5.0f64..5.0), 1..120), r in 0.05f64..2.0) {
            let pos: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
            let mut g = NeighbourGrid::default();
            g.build(&pos, r);
            let cells = g.nx * g.ny;
            prop_assert_eq!(g.cell_start.len(), cells + 1);
            prop_assert_eq!(g.cell_start[0], 0);
            prop_assert_eq!(g.cell_start[cells] as usize, pos.len());
            for c in 0..cells {
                let want: Vec<u32> = (0..pos.len() as u32)
                    .filter(|&i| g.cell_index(pos[i as usize]) == c)
                    .collect();
                prop_assert_eq!(g.cell_items(c), &want[..]);
            }
        }

        /// Push-back forces are antisymmetric: with no goal pull, momentum is conserved.
        #[test]
        fn push_back_conserves_momentum(pts in proptest::collection::vec((-0.5f64..0.5, -0.5f64..0.5), 2..30)) {
            let pos: Vec<Vec2> = pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
            let mut a = Agents::new(&pos);
            let mut p = params();
            p.kp_per_s2 = 0.0;
            p.kd_per_s = 0.0;
            p.max_accel_m_s2 = 1e9;
            p.max_speed_m_s = 1e9;
            let goal_of = vec![0u32; pos.len()];
            a.step(&[Vec2::zeros()], &goal_of, 1.0 / 240.0, &p);
            let m: Vec2 = a.velocities().iter().sum();
            prop_assert!(m.norm() < 1e-9);
        }
    }
}
