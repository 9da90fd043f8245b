//! The assignment cost provider: travel costs between agents and goals read from
//! fast-marching fields (mesh-formation-control section 6.2, eq. 6), with early stop
//! and a field cache.
//!
//! **The choice for the assignment.** 100 full-resolution fields per frame cannot
//! reach 30 Hz at 256² however they are scheduled (timings in `docs/benchmarks.md`):
//! in the bench scene (walls between crowd and formation, agents over 60 % of the
//! height) the marches cover most of the grid, so the early stop saves little, and
//! the cache only helps a drifting frame. The provider therefore runs on the scene
//! grid coarsened to about 16 cm cells ([`coarsen`](super::coarsen), factor 4 from
//! 4 cm), with the cache. Its entries are 5.9 % (median, 11 % max) above the 256²
//! costs — thicker walls and sources snapped to coarse cell centres, mostly a common
//! offset — and the assignment it gives costs 0.05 % more than the 256² optimum
//! (0.008 % at 128²). Routing (descent) keeps the fine grid. A discomfort term that
//! follows the crowd density changes the cost grid every frame and defeats the
//! cache; refresh it at a lower rate than the assignment. For hundreds of goals or
//! more, one field per goal is still too slow (0.9 s for 1,000): the planner marches
//! one field per cluster of goals instead ([`ClusterCosts`](super::ClusterCosts)),
//! reading them through [`EikonalCosts::fields`].
//!
//! **Not used.** Fields from the smaller side ([`FieldSources::Auto`]) are
//! implemented but gain nothing at 100 × 100 (the assignment always has at least as
//! many goals as agents), and swapping sides changes entries by up to 1.2 % (test
//! `field_direction_agrees_within_discretisation_error`). A visibility shortcut
//! (straight-line cost when the segment crosses only cells at the grid's minimum
//! cost) would give the exact continuous geodesic but not the FMM's discrete value
//! (0.5–1.4 % above it, more on a coarse grid), so mixing both would bias the
//! assignment towards visible pairs; in the bench scene no pair is visible.

use std::cell::RefCell;

use super::error::EikonalError;
use super::grid::{validate_cost, Grid};
use super::march::{Fmm, Order, Sources, Targets};
use super::reads::{descent_direction, sample};
use crate::crowd::assign::{Cancel, CostMatrix, CostProvider};
use crate::geom::Vec2;

/// Which side of the assignment the fields are computed from.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum FieldSources {
    /// One field per goal, read at the agents (mesh-formation-control eq. 6).
    Goals,
    /// One field per agent, read at the goals (travel cost is symmetric for an
    /// isotropic cost, up to the discretisation error).
    Agents,
    /// Whichever side has fewer points; goals on a tie (the default).
    #[default]
    Auto,
}

/// Options of [`EikonalCosts`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct EikonalOptions {
    /// Which side the fields start from.
    pub sources: FieldSources,
    /// Fields kept between fills, keyed by source cell (0 disables the cache). Each
    /// costs one `f64` and one `u32` per touched cell (0.5–0.75 MB at 256²).
    pub cache_fields: usize,
    /// Stencil order of the solver.
    pub order: Order,
}

impl Default for EikonalOptions {
    fn default() -> EikonalOptions {
        EikonalOptions {
            sources: FieldSources::Auto,
            cache_fields: DEFAULT_CACHE_FIELDS,
            order: Order::Second,
        }
    }
}

/// How far, in cells, a source standing in a blocked cell (an agent pushed into an
/// obstacle, or a coarse cell covering a wall) is moved to the nearest free cell.
pub const SNAP_RADIUS_CELLS: usize = 2;

/// Default number of cached fields: enough for 128 sources per fill.
pub const DEFAULT_CACHE_FIELDS: usize = 128;

/// Work counters of [`EikonalCosts`], cumulative since creation.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct EikonalStats {
    /// Matrices filled.
    pub fills: u64,
    /// Fields marched.
    pub fields: u64,
    /// Fields reused from the cache.
    pub cache_hits: u64,
    /// Cells frozen by the solver.
    pub cells_marched: u64,
}

/// One field from the centre of a source cell. `phi` holds final values on frozen
/// cells and `+inf` elsewhere; `touched` lists the cells to reset before reuse.
#[derive(Clone, Debug)]
struct Field {
    cell: u32,
    valid: bool,
    complete: bool,
    used: u64,
    phi: Vec<f64>,
    touched: Vec<u32>,
}

impl Field {
    fn new(n: usize) -> Field {
        Field {
            cell: 0,
            valid: false,
            complete: false,
            used: 0,
            phi: vec![f64::INFINITY; n],
            touched: Vec::new(),
        }
    }
}

#[derive(Clone, Debug)]
struct Inner {
    fmm: Fmm,
    fields: Vec<Field>,
    scratch: Option<Field>,
    mark: Vec<u32>,
    stamp: u32,
    targets: Vec<u32>,
    clock: u64,
    stats: EikonalStats,
    last_error: Option<EikonalError>,
}

/// Environment-aware assignment costs: entry `(i, j)` is the travel cost `Φ` between
/// agent `i` and goal `j` on a fixed cost grid (mesh-formation-control section 6.2).
///
/// # Formula
/// mesh-formation-control eq. 6, `c_ij = Φ_j(a_i)`, with `Φ_j` the solution of eq. 5
/// that is zero at the centre of the cell containing goal `j` ("Φi = 0 in the cell
/// containing vi"), read bilinearly ([`sample`]). With [`FieldSources::Agents`] the
/// roles swap: `c_ij = Φ_i(g_j)` from the centre of agent `i`'s cell.
///
/// # Speed-ups (all exact: the same numbers as one full field per source)
/// * **Early stop**: a march stops once every free cell of the bilinear stencils of
///   the points it is read at is frozen; frozen values are final, so the reads are
///   the full field's.
/// * **Cache**: a field is kept, keyed by its source cell, until the cost grid
///   changes ([`EikonalCosts::set_cost`]); it is reused while it covers the stencils
///   of the points read (else it is marched again, further).
/// * **Fewer sources**: [`FieldSources::Auto`] marches from the smaller side. This
///   one is not exact against per-goal fields: FMM is symmetric only up to its
///   discretisation error (measured in the tests below the second-order bound).
///
/// The benches (`cargo bench --bench fmm`) measure each (figures in
/// `docs/benchmarks.md`).
///
/// # Errors
/// [`CostProvider::fill`] cannot fail: on invalid points it writes `+inf` everywhere
/// (the assignment then reports infeasible) and records the error, readable with
/// [`EikonalCosts::last_error`]; [`EikonalCosts::try_fill`] returns it.
#[derive(Clone, Debug)]
pub struct EikonalCosts {
    grid: Grid,
    cost: Vec<f64>,
    options: EikonalOptions,
    inner: RefCell<Inner>,
}

impl EikonalCosts {
    /// A provider over `grid` with per-cell unit `cost` (see [`cost_field_into`](super::cost_field_into)).
    ///
    /// # Errors
    /// [`validate_cost`]'s errors.
    pub fn new(
        grid: Grid,
        cost: &[f64],
        options: EikonalOptions,
    ) -> Result<EikonalCosts, EikonalError> {
        validate_cost(&grid, cost)?;
        let mut fmm = Fmm::with_order(options.order);
        fmm.load(&grid, cost);
        Ok(EikonalCosts {
            grid,
            cost: cost.to_vec(),
            options,
            inner: RefCell::new(Inner {
                fmm,
                fields: Vec::new(),
                scratch: None,
                mark: vec![0; grid.len()],
                stamp: 0,
                targets: Vec::new(),
                clock: 0,
                stats: EikonalStats::default(),
                last_error: None,
            }),
        })
    }

    /// Replaces the cost grid. Cached fields are dropped only if it changed; returns
    /// whether it did.
    ///
    /// # Errors
    /// [`validate_cost`]'s errors (the previous cost stays in force).
    pub fn set_cost(&mut self, cost: &[f64]) -> Result<bool, EikonalError> {
        validate_cost(&self.grid, cost)?;
        if cost == self.cost.as_slice() {
            return Ok(false);
        }
        self.cost.copy_from_slice(cost);
        let inner = self.inner.get_mut();
        inner.fmm.load(&self.grid, cost);
        for f in &mut inner.fields {
            f.valid = false;
        }
        Ok(true)
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The cost grid in use.
    pub fn cost(&self) -> &[f64] {
        &self.cost
    }

    /// The options.
    pub fn options(&self) -> EikonalOptions {
        self.options
    }

    /// Work counters.
    pub fn stats(&self) -> EikonalStats {
        self.inner.borrow().stats
    }

    /// The error of the last [`CostProvider::fill`], if it failed.
    pub fn last_error(&self) -> Option<EikonalError> {
        self.inner.borrow().last_error
    }

    /// Whether the fields of one fill start from the goals (else from the agents).
    pub fn from_goals(&self, agents: usize, goals: usize) -> bool {
        match self.options.sources {
            FieldSources::Goals => true,
            FieldSources::Agents => false,
            FieldSources::Auto => goals <= agents,
        }
    }

    /// Fills `out` (resized to `agents × goals`) with travel costs.
    ///
    /// # Errors
    /// [`EikonalError::PointNotFinite`], [`EikonalError::SourceOutside`] or
    /// [`EikonalError::SourceBlocked`] for the first agent or goal (numbered agents
    /// first, then goals: goal `j` is point `agents.len() + j`) that is not finite,
    /// lies outside the grid, or in a blocked cell with no free cell within
    /// [`SNAP_RADIUS_CELLS`] (a source in a blocked cell marches from the nearest
    /// free one). `out` is unspecified then.
    ///
    /// # Complexity
    /// At most one march per distinct source cell, `O(N log N)` each, stopped early.
    pub fn try_fill(
        &self,
        agents: &[Vec2],
        goals: &[Vec2],
        out: &mut CostMatrix,
    ) -> Result<(), EikonalError> {
        self.try_fill_cancellable(agents, goals, out, Cancel::NEVER)
    }

    /// [`Self::try_fill`] that gives up when `cancel` says so, checked before each
    /// march.
    ///
    /// # Errors
    /// As [`Self::try_fill`], and [`EikonalError::Cancelled`] (`out` unspecified).
    pub fn try_fill_cancellable(
        &self,
        agents: &[Vec2],
        goals: &[Vec2],
        out: &mut CostMatrix,
        cancel: Cancel<'_>,
    ) -> Result<(), EikonalError> {
        out.resize(agents.len(), goals.len());
        self.validate_points(agents, goals)?;
        let from_goals = self.from_goals(agents.len(), goals.len());
        let (sources, readers) = if from_goals {
            (goals, agents)
        } else {
            (agents, goals)
        };
        self.with_fields(
            sources,
            readers,
            |k, phi| {
                for (m, &p) in readers.iter().enumerate() {
                    let v = sample(&self.grid, phi, p);
                    if from_goals {
                        out.set(m, k, v);
                    } else {
                        out.row_mut(k)[m] = v;
                    }
                }
            },
            cancel,
        )
    }

    /// Calls `f(k, Φ_k)` for each source `k` with its field (one `f64` per cell,
    /// `+inf` where not reached), marched far enough to be final on the bilinear
    /// stencils of every point of `readers` and on every cell whose `Φ` is below
    /// theirs (from the cache when it already covers them). The fields of one call
    /// stay cached (up to [`EikonalOptions::cache_fields`]) for [`Self::descent`].
    ///
    /// # Errors
    /// As [`Self::try_fill`], with `readers` numbered first, then `sources`.
    pub fn fields(
        &self,
        sources: &[Vec2],
        readers: &[Vec2],
        f: impl FnMut(usize, &[f64]),
    ) -> Result<(), EikonalError> {
        self.fields_cancellable(sources, readers, f, Cancel::NEVER)
    }

    /// [`Self::fields`] that gives up when `cancel` says so, checked before each
    /// source's field (one march at most between two checks).
    ///
    /// # Errors
    /// As [`Self::fields`], and [`EikonalError::Cancelled`] (`f` was called for
    /// the sources before then).
    pub fn fields_cancellable(
        &self,
        sources: &[Vec2],
        readers: &[Vec2],
        f: impl FnMut(usize, &[f64]),
        cancel: Cancel<'_>,
    ) -> Result<(), EikonalError> {
        self.validate_points(readers, sources)?;
        self.with_fields(sources, readers, f, cancel)
    }

    /// Checks that every point is finite, inside the grid and in (or near) a free
    /// cell, numbered `first` then `second`.
    ///
    /// # Errors
    /// As [`Self::try_fill`].
    pub fn validate_points(&self, first: &[Vec2], second: &[Vec2]) -> Result<(), EikonalError> {
        for (point, &p) in first.iter().chain(second).enumerate() {
            if !(p.x.is_finite() && p.y.is_finite()) {
                return Err(EikonalError::PointNotFinite { point });
            }
            let cell = self
                .grid
                .cell_of(p)
                .ok_or(EikonalError::SourceOutside { index: point })?;
            if self.source_cell(cell, p).is_none() {
                return Err(EikonalError::SourceBlocked { index: point });
            }
        }
        Ok(())
    }

    /// The loop of [`Self::fields`] over validated points; `Err(Cancelled)` when
    /// `cancel` says so before a field.
    fn with_fields(
        &self,
        sources: &[Vec2],
        readers: &[Vec2],
        mut f: impl FnMut(usize, &[f64]),
        cancel: Cancel<'_>,
    ) -> Result<(), EikonalError> {
        let mut inner = self.inner.borrow_mut();
        let inner = &mut *inner;
        inner.stats.fills += 1;
        inner.clock += 1;
        // Free stencil cells of every point read: where the marches may stop.
        inner.stamp = inner.stamp.wrapping_add(1);
        if inner.stamp == 0 {
            inner.mark.fill(0);
            inner.stamp = 1;
        }
        let stamp = inner.stamp;
        inner.targets.clear();
        for &p in readers {
            let (cells, _, _) = self.grid.stencil_cells(p);
            for c in cells {
                if inner.mark[c] != stamp && self.cost[c] != f64::INFINITY {
                    inner.mark[c] = stamp;
                    inner.targets.push(c as u32);
                }
            }
        }
        for (k, &s) in sources.iter().enumerate() {
            if cancel.cancelled() {
                return Err(EikonalError::Cancelled);
            }
            let cell = self.grid.cell_of(s).expect("validated");
            let cell = self.source_cell(cell, s).expect("validated");
            let field = self.field_in(inner, cell);
            f(k, &field.phi);
        }
        Ok(())
    }

    /// The cell a source at `p` marches from (see [`Self::try_fill`] on snapping):
    /// `None` outside the grid or with no free cell within [`SNAP_RADIUS_CELLS`].
    pub fn source_cell_of(&self, p: Vec2) -> Option<usize> {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return None;
        }
        self.source_cell(self.grid.cell_of(p)?, p)
    }

    /// The descent direction at `at` on the cached field of the source at `source`
    /// ([`descent_direction`]): the way towards `source` for an agent routed by
    /// gradient descent (mesh-formation-control section 6.2.1). `None` when that
    /// field is not cached (never marched, evicted, or the cost grid changed since),
    /// at the source, or where the field is not reachable.
    pub fn descent(&self, source: Vec2, at: Vec2) -> Option<Vec2> {
        if !(source.x.is_finite() && source.y.is_finite() && at.x.is_finite() && at.y.is_finite()) {
            return None;
        }
        let cell = self.source_cell(self.grid.cell_of(source)?, source)?;
        let inner = self.inner.borrow();
        let f = inner
            .fields
            .iter()
            .find(|f| f.valid && f.cell as usize == cell)?;
        descent_direction(&self.grid, &f.phi, at)
    }

    /// The cell a source at `p` (in `cell`) marches from: `cell` if free, else the
    /// free cell within [`SNAP_RADIUS_CELLS`] whose centre is nearest `p` (first in
    /// index order on a tie), else `None`.
    fn source_cell(&self, cell: usize, p: Vec2) -> Option<usize> {
        if self.cost[cell] != f64::INFINITY {
            return Some(cell);
        }
        let g = &self.grid;
        let (c, r) = (cell % g.cols, cell / g.cols);
        let k = SNAP_RADIUS_CELLS;
        let mut best: Option<(f64, usize)> = None;
        for rr in r.saturating_sub(k)..=(r + k).min(g.rows - 1) {
            for cc in c.saturating_sub(k)..=(c + k).min(g.cols - 1) {
                let i = g.index(cc, rr);
                if self.cost[i] == f64::INFINITY {
                    continue;
                }
                let d = (g.center(i) - p).norm_squared();
                if best.is_none_or(|(bd, _)| d < bd) {
                    best = Some((d, i));
                }
            }
        }
        best.map(|(_, i)| i)
    }

    /// The field from the centre of `cell`, covering the marked targets: from the
    /// cache, or marched (into a cache slot or the scratch field).
    fn field_in<'a>(&self, inner: &'a mut Inner, cell: usize) -> &'a Field {
        let clock = inner.clock;
        let covers = |f: &Field, targets: &[u32]| {
            f.complete || targets.iter().all(|&t| f.phi[t as usize].is_finite())
        };
        let hit = inner
            .fields
            .iter()
            .position(|f| f.valid && f.cell as usize == cell);
        if let Some(k) = hit {
            if covers(&inner.fields[k], &inner.targets) {
                inner.stats.cache_hits += 1;
                inner.fields[k].used = clock;
                return &inner.fields[k];
            }
        }
        // Choose a slot: the stale entry for this cell, a free or least recently used
        // one not read in this fill, a new one, or the scratch field.
        let cap = self.options.cache_fields;
        let slot = hit.or_else(|| {
            let lru = inner
                .fields
                .iter()
                .enumerate()
                .filter(|(_, f)| !f.valid || f.used < clock)
                .min_by_key(|(_, f)| (f.valid, f.used))
                .map(|(k, _)| k);
            match lru {
                Some(k) if inner.fields.len() >= cap || !inner.fields[k].valid => Some(k),
                _ if inner.fields.len() < cap => {
                    inner.fields.push(Field::new(self.grid.len()));
                    Some(inner.fields.len() - 1)
                }
                _ => None,
            }
        });
        let Inner {
            fmm,
            fields,
            scratch,
            mark,
            stamp,
            targets,
            stats,
            ..
        } = inner;
        let field = match slot {
            Some(k) => &mut fields[k],
            None => scratch.get_or_insert_with(|| Field::new(self.grid.len())),
        };
        for &i in &field.touched {
            field.phi[i as usize] = f64::INFINITY;
        }
        field.touched.clear();
        let before = fmm.marched;
        let src = [self.grid.center(cell)];
        let t = Targets {
            mark,
            stamp: *stamp,
            count: targets.len(),
        };
        let complete = fmm.march(&self.grid, &self.cost, Sources::Points(&src), Some(t));
        field.touched.extend(fmm.touched.iter().map(|&(_, i)| i));
        fmm.finish(&mut field.phi);
        stats.fields += 1;
        stats.cells_marched += fmm.marched - before;
        field.cell = cell as u32;
        field.valid = slot.is_some();
        field.complete = complete;
        field.used = clock;
        field
    }
}

impl CostProvider for EikonalCosts {
    fn fill(&self, agents: &[Vec2], goals: &[Vec2], out: &mut CostMatrix) {
        let r = self.try_fill(agents, goals, out);
        let mut inner = self.inner.borrow_mut();
        inner.last_error = r.err();
        if r.is_err() {
            out.resize(agents.len(), goals.len());
            for k in 0..out.rows() {
                out.row_mut(k).fill(f64::INFINITY);
            }
        }
    }
}
