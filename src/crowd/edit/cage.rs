//! The spatial editor (crowd-motion-editing section 3.2, eqs. 1–9): a selection's
//! cages, one per time window, deformed as rigidly as possible and chained at their
//! borders.
//!
//! A selection whose paths do not come back to a place gets one cage
//! ([`CageWindow`], `cage_window.rs`: the concave hull, the mean value coordinates,
//! the deformation mesh and the solve of eqs. 1–8), exactly as §3.2 builds it. A
//! selection where a person revisits a place — a U-turn, a loop, someone pacing — is
//! cut into time windows none of which holds a revisit (`cage_split.rs` says how and
//! why: one cage ties samples by position only, so it welds a path's early and late
//! visits of a place), and each window gets its own cage.
//!
//! # Chaining the windows
//! Consecutive windows share the samples of their overlap (half the revisit gap, by
//! default 1 s). Up to [`MAX_SHARED_HANDLES`] of them, spread over the overlap, are the
//! border's *shared handles*. A drag is solved first in the windows that hold a
//! dragged handle (the user's fixed handles are kept in the windows that hold
//! them), then outwards along the chain: a window takes the shared handles of its
//! neighbours solved before it as dragged handles with targets where those
//! neighbours put them, and is solved by eq. 1 (or eq. 6 with fixed handles), so the
//! drag spreads through the shared handles and eq. 5's locality fades it within the
//! window. A window whose shared handles did not move (within
//! [`CageParams::tolerance_m`]) stays at rest and the spreading stops there. A
//! sample of an overlap takes the blend of its two windows' positions, linear in
//! time across the overlap (all of the earlier window's at the overlap's start, all
//! of the later one's at its end), so tracks stay continuous across the borders;
//! at a shared handle both windows agree exactly.
//!
//! Hull handles ([`Handle::Hull`]) number the windows' hull vertices one window
//! after another ([`Cage::hull_range`]); [`Cage::hull`] and [`Cage::deformed_hull`]
//! are that concatenation (one polygon when there is one window; draw
//! [`Cage::window`]'s polygons otherwise).

use super::cage_mvc::finite;
pub use super::cage_solve::{CageParams, PAPER_ALPHA, PAPER_BETA, PAPER_K};
pub use super::cage_speed::correct_speeds;
use super::cage_split::{cut, revisits, TimeWindow};
pub use super::cage_window::{CageWindow, Handle, ShapeError, SolveStats};
use super::error::EditError;
use super::select::{SampleRef, Selection};
use super::tracks::TrackSet;
use crate::geom::Vec2;
use std::ops::Range;

/// Most shared handles at one border between time windows: enough to carry a
/// translation and a turn across it, few enough to leave a window's cage free.
pub const MAX_SHARED_HANDLES: usize = 3;

/// Shared handles of one border are at least this many hull cells apart (the larger
/// cell of the two windows), so that their constraint rows are independent.
pub const SHARED_SPACING_CELLS: f64 = 2.0;

/// The narrowest locality a drag keeps in a window it reaches through shared
/// handles, in hull cells of that window: the border's move fades within a few
/// mesh layers.
pub const MIN_REACHED_RADIUS_CELLS: f64 = 2.0;

/// Fewest samples a time window keeps; a window with fewer is merged into its
/// neighbour (a cage needs three distinct points).
const MIN_WINDOW_SAMPLES: usize = 3;

/// Where a selected sample lives in the windows: its first window and index there,
/// and for a sample of an overlap the second (later) window, index and blend weight.
#[derive(Copy, Clone, Debug)]
struct Member {
    first: (u32, u32),
    second: Option<(u32, u32, f64)>,
}

/// A shared handle of the border between windows `b` and `b + 1`: the sample and its
/// indices in the two windows' selections.
#[derive(Copy, Clone, Debug)]
struct Shared {
    sample: SampleRef,
    left: usize,
    right: usize,
}

/// The windows holding a handle, with the handle as each names it: the first, and
/// the second for a sample of an overlap.
type Homes = ((usize, Handle), Option<(usize, Handle)>);

/// How a window fared in the drag being solved.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Fate {
    Pending,
    Moved,
    Quiet,
}

/// The spatial editor of one selection (see the module documentation).
pub struct Cage {
    windows: Vec<CageWindow>,
    spans: Vec<TimeWindow>,
    selection: Vec<SampleRef>,
    /// Per selected sample (empty when there is one window: sample `i` is window 0's
    /// sample `i`).
    members: Vec<Member>,
    /// `borders[b]`: the shared handles between windows `b` and `b + 1`.
    borders: Vec<Vec<Shared>>,
    /// Window `w`'s hull vertices are `hull_offsets[w]..hull_offsets[w + 1]`.
    hull_offsets: Vec<usize>,
    /// Every window's rest hull, mesh and triangles one after another (empty when
    /// there is one window).
    hull_all: Vec<Vec2>,
    mesh_all: Vec<Vec2>,
    triangles_all: Vec<[u32; 3]>,
    /// The blended deformed samples (empty when there is one window).
    points: Vec<Vec2>,
    // A drag's scratch, kept between drags so a continuing drag does not allocate.
    drags: Vec<Vec<(Handle, Vec2)>>,
    fixed: Vec<Vec<Handle>>,
    order: Vec<(usize, usize)>,
    fate: Vec<Fate>,
    /// Per window, how far (m, at rest) the drag has travelled to reach it.
    reach_m: Vec<f64>,
    last: SolveStats,
    tolerance_m: f64,
    locality_radius_m: Option<f64>,
    world: Option<crate::geom::Rect>,
}

impl Cage {
    /// Builds the selection's cages: the time windows (when
    /// a path revisits a place, see [`CageParams::windows`]), then per window
    /// the hull, the mesh, the MVC of its samples and `Tᵀ L T`.
    ///
    /// # Complexity
    /// O(N) to find revisits; per window O(N_w n_w) for the MVC of its N_w samples
    /// and n_w hull vertices, O(m_w n_w²) for `Tᵀ L T` on m_w mesh vertices.
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] when `sel` was made on another set;
    /// [`EditError::BadCageParams`] for unusable window parameters; the errors of
    /// [`concave_hull`](super::concave_hull); [`EditError::DegenerateHull`] when a
    /// sample's MVC are undefined or a mesh has no triangle.
    pub fn new(set: &TrackSet, sel: &Selection, params: &CageParams) -> Result<Cage, EditError> {
        let rest_points = sel.points(set)?;
        let samples = sel.samples();
        let mut times_s = Vec::with_capacity(samples.len());
        for r in samples {
            let t = set.tracks[r.track].times_s.get(r.sample).copied().ok_or(
                EditError::SelectionMismatch {
                    track: r.track,
                    sample: r.sample,
                },
            )?;
            times_s.push(t);
        }
        let (t_min, t_max) = times_s
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
                (a.min(t), b.max(t))
            });
        let mut spans = vec![TimeWindow {
            start_s: t_min,
            end_s: t_max,
        }];
        let wp = &params.windows;
        if let Some(what) = wp.problem() {
            return Err(EditError::BadCageParams { what });
        }
        let person: Vec<usize> = samples.iter().map(|r| r.track).collect();
        let mut forbidden = revisits(&rest_points, &times_s, &person, wp);
        if !forbidden.is_empty() {
            spans = cut(&mut forbidden, t_min, t_max, wp);
            merge_small(&mut spans, &times_s);
        }
        if spans.len() == 1 {
            let w = CageWindow::new(rest_points, samples.to_vec(), params)?;
            return Ok(Cage::assemble(
                vec![w],
                spans,
                samples.to_vec(),
                Vec::new(),
                params,
            ));
        }
        // Per window: its samples (selection order) and each sample's homes.
        let mut windows = Vec::with_capacity(spans.len());
        let mut members = vec![
            Member {
                first: (u32::MAX, 0),
                second: None,
            };
            samples.len()
        ];
        for (w, span) in spans.iter().enumerate() {
            let last = w + 1 == spans.len();
            let mut pts = Vec::new();
            let mut refs = Vec::new();
            for (i, &t) in times_s.iter().enumerate() {
                if !span.holds(t, last) {
                    continue;
                }
                let home = (w as u32, refs.len() as u32);
                let m = &mut members[i];
                if m.first.0 == u32::MAX {
                    m.first = home;
                } else {
                    // The overlap with the previous window: blend linearly in time.
                    let overlap = spans[w - 1].end_s - span.start_s;
                    let weight = if overlap > 0.0 {
                        ((t - span.start_s) / overlap).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    m.second = Some((home.0, home.1, weight));
                }
                pts.push(rest_points[i]);
                refs.push(samples[i]);
            }
            windows.push(CageWindow::new(pts, refs, params)?);
        }
        let mut cage = Cage::assemble(windows, spans, samples.to_vec(), members, params);
        cage.borders = cage.shared_handles(&rest_points);
        Ok(cage)
    }

    fn assemble(
        windows: Vec<CageWindow>,
        spans: Vec<TimeWindow>,
        selection: Vec<SampleRef>,
        members: Vec<Member>,
        params: &CageParams,
    ) -> Cage {
        let count = windows.len();
        let mut hull_offsets = vec![0];
        let (mut hull_all, mut mesh_all, mut triangles_all) = (Vec::new(), Vec::new(), Vec::new());
        for w in &windows {
            hull_offsets.push(hull_offsets.last().copied().unwrap_or(0) + w.hull().len());
            if count > 1 {
                hull_all.extend_from_slice(w.hull());
                let base = mesh_all.len() as u32;
                mesh_all.extend_from_slice(w.mesh_vertices());
                triangles_all.extend(w.mesh_triangles().iter().map(|t| t.map(|v| v + base)));
            }
        }
        let points = if count > 1 {
            (0..selection.len())
                .map(|i| {
                    windows[members[i].first.0 as usize].rest_sample(members[i].first.1 as usize)
                })
                .collect()
        } else {
            Vec::new()
        };
        Cage {
            windows,
            spans,
            selection,
            members,
            borders: vec![Vec::new(); count.saturating_sub(1)],
            hull_offsets,
            hull_all,
            mesh_all,
            triangles_all,
            points,
            drags: vec![Vec::new(); count],
            fixed: vec![Vec::new(); count],
            order: Vec::with_capacity(count),
            fate: vec![Fate::Pending; count],
            reach_m: vec![0.0; count],
            last: SolveStats::default(),
            tolerance_m: params.tolerance_m,
            locality_radius_m: params.locality_radius_m,
            world: params.world,
        }
    }

    /// Each border's shared handles: farthest-point picks among the overlap's
    /// samples, at least [`SHARED_SPACING_CELLS`] cells apart.
    fn shared_handles(&self, rest: &[Vec2]) -> Vec<Vec<Shared>> {
        let mut borders = vec![Vec::new(); self.windows.len() - 1];
        for (b, border) in borders.iter_mut().enumerate() {
            let cand: Vec<(usize, usize, usize)> = self
                .members
                .iter()
                .enumerate()
                .filter_map(|(i, m)| match m.second {
                    Some((w2, j2, _)) if m.first.0 as usize == b && w2 as usize == b + 1 => {
                        Some((i, m.first.1 as usize, j2 as usize))
                    }
                    _ => None,
                })
                .collect();
            let Some(&first) = cand.get(cand.len() / 2) else {
                continue;
            };
            let spacing =
                SHARED_SPACING_CELLS * self.windows[b].cell_m().max(self.windows[b + 1].cell_m());
            let mut picked = vec![first];
            while picked.len() < MAX_SHARED_HANDLES {
                let far = cand
                    .iter()
                    .map(|c| {
                        let d = picked
                            .iter()
                            .map(|p| (rest[p.0] - rest[c.0]).norm())
                            .fold(f64::INFINITY, f64::min);
                        (d, *c)
                    })
                    .max_by(|a, b| a.0.total_cmp(&b.0));
                match far {
                    Some((d, c)) if d >= spacing => picked.push(c),
                    _ => break,
                }
            }
            picked.sort_unstable();
            *border = picked
                .into_iter()
                .map(|(i, left, right)| Shared {
                    sample: self.selection[i],
                    left,
                    right,
                })
                .collect();
        }
        borders
    }

    /// The number of time windows (1 when the selection revisits no place).
    pub fn window_count(&self) -> usize {
        self.windows.len()
    }

    /// Time window `w`'s cage.
    ///
    /// # Panics
    /// When `w >= window_count()`.
    pub fn window(&self, w: usize) -> &CageWindow {
        &self.windows[w]
    }

    /// Time window `w`'s span (s): its samples have `start_s <= t < end_s` (the last
    /// window's also `t == end_s`).
    ///
    /// # Panics
    /// When `w >= window_count()`.
    pub fn window_span(&self, w: usize) -> TimeWindow {
        self.spans[w]
    }

    /// The shared handles between windows `b` and `b + 1` (see the module doc).
    ///
    /// # Panics
    /// When `b + 1 >= window_count()`.
    pub fn shared_samples(&self, b: usize) -> impl Iterator<Item = SampleRef> + '_ {
        self.borders[b].iter().map(|s| s.sample)
    }

    /// The hull handles of window `w` ([`Handle::Hull`] indices).
    ///
    /// # Panics
    /// When `w >= window_count()`.
    pub fn hull_range(&self, w: usize) -> Range<usize> {
        self.hull_offsets[w]..self.hull_offsets[w + 1]
    }

    /// The first window holding a handle.
    pub fn window_of(&self, h: Handle) -> Option<usize> {
        self.homes(h).ok().map(|(a, _)| a.0)
    }

    /// The windows holding a handle and the handle there: one, or two for a sample
    /// of an overlap.
    fn homes(&self, h: Handle) -> Result<Homes, EditError> {
        let unknown = || EditError::UnknownHandle {
            handle: h.to_string(),
        };
        match h {
            Handle::Hull(g) => {
                let w = self.hull_offsets.partition_point(|&o| o <= g);
                if w == 0 || w > self.windows.len() {
                    return Err(unknown());
                }
                Ok(((w - 1, Handle::Hull(g - self.hull_offsets[w - 1])), None))
            }
            Handle::Sample(r) => {
                let i = self.selection.binary_search(&r).map_err(|_| unknown())?;
                if self.members.is_empty() {
                    return Ok(((0, h), None));
                }
                let m = self.members[i];
                Ok(((m.first.0 as usize, h), m.second.map(|s| (s.0 as usize, h))))
            }
        }
    }

    /// Every window's rest hull, one after another ([`Cage::hull_range`]; the hull
    /// polygon when there is one window) (m).
    pub fn hull(&self) -> &[Vec2] {
        if self.windows.len() == 1 {
            self.windows[0].hull()
        } else {
            &self.hull_all
        }
    }

    /// Whether a window's hull is the convex fallback (see `hull.rs`).
    pub fn hull_is_convex_fallback(&self) -> bool {
        self.windows.iter().any(|w| w.hull_is_convex_fallback())
    }

    /// The deformed hull vertex `i` ([`Handle::Hull`] numbering) (m).
    ///
    /// # Panics
    /// When `i >= hull().len()`.
    pub fn deformed_vertex(&self, i: usize) -> Vec2 {
        let w = self.hull_offsets.partition_point(|&o| o <= i) - 1;
        self.windows[w].deformed_vertex(i - self.hull_offsets[w])
    }

    /// Every window's deformed hull, one after another (m).
    pub fn deformed_hull(&self) -> Vec<Vec2> {
        self.windows
            .iter()
            .flat_map(|w| w.deformed_hull())
            .collect()
    }

    /// Every window's mesh vertices at rest, one after another (m).
    pub fn mesh_vertices(&self) -> &[Vec2] {
        if self.windows.len() == 1 {
            self.windows[0].mesh_vertices()
        } else {
            &self.mesh_all
        }
    }

    /// Every window's mesh triangles (indices into [`Cage::mesh_vertices`]).
    pub fn mesh_triangles(&self) -> &[[u32; 3]] {
        if self.windows.len() == 1 {
            self.windows[0].mesh_triangles()
        } else {
            &self.triangles_all
        }
    }

    /// The selected samples.
    pub fn selection(&self) -> &[SampleRef] {
        &self.selection
    }

    /// The deformed position of the `i`-th selected sample (m).
    ///
    /// # Panics
    /// When `i >= selection().len()`.
    pub fn deformed_sample(&self, i: usize) -> Vec2 {
        if self.members.is_empty() {
            self.windows[0].deformed_sample(i)
        } else {
            self.points[i]
        }
    }

    /// The rest position of the `i`-th selected sample (m).
    ///
    /// # Panics
    /// When `i >= selection().len()`.
    pub fn rest_sample(&self, i: usize) -> Vec2 {
        match self.members.get(i) {
            None => self.windows[0].rest_sample(i),
            Some(m) => self.windows[m.first.0 as usize].rest_sample(m.first.1 as usize),
        }
    }

    /// How the last drag's iteration went: the most iterations any window ran, and
    /// whether every window solved converged.
    pub fn last_solve(&self) -> SolveStats {
        self.last
    }

    /// The current (deformed) position of a handle.
    ///
    /// # Errors
    /// [`EditError::UnknownHandle`].
    pub fn handle_position(&self, h: Handle) -> Result<Vec2, EditError> {
        match h {
            Handle::Hull(i) if i < self.hull().len() => Ok(self.deformed_vertex(i)),
            Handle::Sample(r) => match self.selection.binary_search(&r) {
                Ok(i) => Ok(self.deformed_sample(i)),
                Err(_) => Err(EditError::UnknownHandle {
                    handle: h.to_string(),
                }),
            },
            _ => Err(EditError::UnknownHandle {
                handle: h.to_string(),
            }),
        }
    }

    /// The handle nearest to `p` within `radius_m` in the deformed state: a hull vertex
    /// when one is that close, else the nearest selected sample.
    pub fn handle_near(&self, p: Vec2, radius_m: f64) -> Option<Handle> {
        let r2 = radius_m * radius_m;
        let mut best: Option<(f64, Handle)> = None;
        for i in 0..self.hull().len() {
            let d2 = (self.deformed_vertex(i) - p).norm_squared();
            if d2 <= r2 && best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, Handle::Hull(i)));
            }
        }
        if best.is_some() {
            return best.map(|b| b.1);
        }
        for (i, r) in self.selection.iter().enumerate() {
            let d2 = (self.deformed_sample(i) - p).norm_squared();
            if d2 <= r2 && best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, Handle::Sample(*r)));
            }
        }
        best.map(|b| b.1)
    }

    /// Moves the dragged handles to their targets (exactly) and keeps the fixed
    /// handles at their rest positions, deforming from the rest cage by eq. 1 (no
    /// fixed handle) or eq. 6 (with fixed handles); then updates every selected
    /// sample's deformed position. With several time windows the drag is solved in
    /// the windows holding a dragged handle and spread through the shared handles
    /// (see the module documentation). The previous deformation is the starting
    /// guess, so a continuing drag converges across calls.
    ///
    /// # Complexity
    /// The first call for a handle set factorises each solved window's KKT system,
    /// O(m n² + (n + K)³); later calls with the same handles cost
    /// O(iterations · m n + N n) per solved window and do not allocate.
    ///
    /// # Errors
    /// [`EditError::DragNotFinite`], [`EditError::DragOutsideWorld`],
    /// [`EditError::UnknownHandle`], [`EditError::ConflictingHandles`] (a handle twice,
    /// more handles than a window's cage vertices, or dependent constraint rows). On
    /// error the cage keeps its previous deformation.
    pub fn drag(&mut self, drags: &[(Handle, Vec2)], fixed: &[Handle]) -> Result<(), EditError> {
        if self.windows.len() == 1 {
            let r = self.windows[0].drag(drags, fixed);
            self.last = self.windows[0].last_solve();
            return r;
        }
        for (_, t) in drags {
            if !finite(*t) {
                return Err(EditError::DragNotFinite { x: t.x, y: t.y });
            }
            if self.world.is_some_and(|w| !w.contains(*t)) {
                return Err(EditError::DragOutsideWorld { x: t.x, y: t.y });
            }
        }
        for list in &mut self.drags {
            list.clear();
        }
        for list in &mut self.fixed {
            list.clear();
        }
        for &(h, t) in drags {
            let (a, b) = self.homes(h)?;
            for (w, local) in std::iter::once(a).chain(b) {
                self.drags[w].push((local, t));
            }
        }
        for &h in fixed {
            let (a, b) = self.homes(h)?;
            for (w, local) in std::iter::once(a).chain(b) {
                self.fixed[w].push(local);
            }
        }
        if drags.is_empty() {
            // Fixed handles alone keep the rest pose.
            self.reset();
            return Ok(());
        }
        // Windows by chain distance to the nearest window holding a dragged handle.
        let count = self.windows.len();
        self.order.clear();
        for w in 0..count {
            let dist = (0..count)
                .filter(|&s| !self.drags[s].is_empty())
                .map(|s| s.abs_diff(w))
                .min()
                .unwrap_or(usize::MAX);
            self.order.push((dist, w));
        }
        self.order.sort_unstable();
        for w in &mut self.windows {
            w.save();
        }
        self.fate.fill(Fate::Pending);
        let mut stats = SolveStats {
            iterations: 0,
            converged: true,
        };
        for k in 0..count {
            let (dist, w) = self.order[k];
            let mut moved = dist == 0;
            let mut reach = if dist == 0 { 0.0 } else { f64::INFINITY };
            for u in [w.wrapping_sub(1), w + 1] {
                if u >= count || self.fate[u] == Fate::Pending {
                    continue;
                }
                let b = u.min(w);
                for s in &self.borders[b] {
                    let (iu, iw) = if u < w {
                        (s.left, s.right)
                    } else {
                        (s.right, s.left)
                    };
                    if self.fate[u] == Fate::Moved {
                        // How far the drag travelled: from what drove window u to
                        // this shared handle, at rest.
                        let at = self.windows[u].rest_sample(iu);
                        for (d, _) in &self.drags[u] {
                            if let Some(q) = self.windows[u].handle_rest(*d) {
                                reach = reach.min(self.reach_m[u] + (q - at).norm());
                            }
                        }
                    }
                    let h = Handle::Sample(s.sample);
                    if self.drags[w].iter().any(|d| d.0 == h) || self.fixed[w].contains(&h) {
                        continue;
                    }
                    let target = self.windows[u].deformed_sample(iu);
                    if (target - self.windows[w].rest_sample(iw)).norm() > self.tolerance_m {
                        moved = true;
                    }
                    self.drags[w].push((h, target));
                }
            }
            if !moved {
                self.windows[w].reset();
                self.fate[w] = Fate::Quiet;
                continue;
            }
            self.reach_m[w] = reach;
            // Eq. 5's radius in a reached window: what is left of the drag's.
            let radius = match self.locality_radius_m {
                Some(r) if dist > 0 => {
                    Some((r - reach).max(MIN_REACHED_RADIUS_CELLS * self.windows[w].cell_m()))
                }
                _ => None,
            };
            if let Err(e) = self.windows[w].drag_within(&self.drags[w], &self.fixed[w], radius) {
                for win in &mut self.windows {
                    win.restore();
                }
                self.blend();
                return Err(e);
            }
            let s = self.windows[w].last_solve();
            stats.iterations = stats.iterations.max(s.iterations);
            stats.converged &= s.converged;
            self.fate[w] = Fate::Moved;
        }
        self.last = stats;
        self.blend();
        Ok(())
    }

    /// Every selected sample's position from its windows (see the module doc).
    fn blend(&mut self) {
        for (p, m) in self.points.iter_mut().zip(&self.members) {
            let a = self.windows[m.first.0 as usize].deformed_sample(m.first.1 as usize);
            *p = match m.second {
                None => a,
                Some((w, i, t)) => {
                    a * (1.0 - t) + self.windows[w as usize].deformed_sample(i as usize) * t
                }
            };
        }
    }

    /// Returns to the rest cage.
    pub fn reset(&mut self) {
        for w in &mut self.windows {
            w.reset();
        }
        self.blend();
    }

    /// Writes the deformed positions into the selected samples of `set` (the set the
    /// selection was made on; times are left alone, see [`correct_speeds`]).
    ///
    /// # Errors
    /// [`EditError::SelectionMismatch`] when `set` lacks a selected sample (nothing is
    /// written then).
    pub fn apply(&self, set: &mut TrackSet) -> Result<(), EditError> {
        if self.members.is_empty() {
            return self.windows[0].apply(set);
        }
        for r in &self.selection {
            if set
                .tracks
                .get(r.track)
                .is_none_or(|t| r.sample >= t.points.len())
            {
                return Err(EditError::SelectionMismatch {
                    track: r.track,
                    sample: r.sample,
                });
            }
        }
        for (r, p) in self.selection.iter().zip(&self.points) {
            set.tracks[r.track].points[r.sample] = *p;
        }
        Ok(())
    }

    /// How much the hulls' shape changed (see [`ShapeError`], over every window's
    /// edges and turns): a rigid motion of each window gives 0.
    pub fn hull_shape_error(&self) -> ShapeError {
        let (mut el, mut an, mut n) = (0.0, 0.0, 0usize);
        for w in &self.windows {
            let e = w.hull_shape_error();
            let k = w.hull().len();
            el += e.edge_length_rms.powi(2) * k as f64;
            an += e.angle_rms_rad.powi(2) * k as f64;
            n += k;
        }
        ShapeError {
            edge_length_rms: (el / n as f64).sqrt(),
            angle_rms_rad: (an / n as f64).sqrt(),
        }
    }
}

/// Merges every window with fewer than [`MIN_WINDOW_SAMPLES`] samples into its
/// neighbour (the previous one, or the next for the first).
fn merge_small(spans: &mut Vec<TimeWindow>, times_s: &[f64]) {
    loop {
        let count = spans.len();
        let small = (0..count).find(|&w| {
            let last = w + 1 == count;
            times_s.iter().filter(|&&t| spans[w].holds(t, last)).count() < MIN_WINDOW_SAMPLES
        });
        let Some(w) = small.filter(|_| count > 1) else {
            return;
        };
        let (a, b) = if w == 0 { (0, 1) } else { (w - 1, w) };
        spans[a] = TimeWindow {
            start_s: spans[a].start_s,
            end_s: spans[b].end_s,
        };
        spans.remove(b);
    }
}
