//! Cutting a selection into time windows where its paths revisit a place
//! (crowd-motion-editing section 3.2, ours: the paper builds one cage per group).
//!
//! A cage ties every selected sample to the hull by its mean value coordinates, which
//! depend on the sample's position only. A path that comes back near where it was
//! earlier — a U-turn, a loop, a person pacing — then has its early and late samples
//! welded: they get (nearly) the same coordinates, so dragging the late part drags the
//! early part with it, and eq. 5's locality cannot tell them apart either, since the
//! mesh links them in space. §3.2's cage deforms *space*, where the editing means
//! *space at a time*.
//!
//! We therefore cut the selection's time span into windows such that no window holds
//! a revisit, and `cage.rs` builds one cage per window, chained at the borders. What
//! is a revisit: one person back within [`WindowParams::revisit_radius_m`] of a place
//! after being away from it for more than [`WindowParams::revisit_gap_s`]. It is
//! counted per person on purpose: people following one another along a path (a
//! queue, a parade's back ranks, a crowd crossing a square over minutes) walk the
//! same places at different times, and that is one path to bend as a whole, as the
//! paper does; only a person coming back is two visits of one place.
//!
//! # Finding revisits
//! Each sample is entered into the 2 × 2 block of grid cells (side the revisit
//! radius) nearest it, so two samples closer than one cell along both axes always
//! share a cell (and samples up to two cells apart may). A person's samples are
//! visited in time order; a cell last seen by the same person more than the gap ago
//! gives a *forbidden interval* `[t_then, t_now]`: no window may contain both ends,
//! i.e. cover the interval. O(N) for N samples, on a dense grid over the selection's
//! bounding box (at most [`MAX_REVISIT_CELLS`] cells; the cell grows past that).
//!
//! # Cutting
//! Greedily, from the first time: a window starting at `s` ends (exclusive) at the
//! earliest `hi` of the forbidden intervals starting at or after `s`, the longest
//! window that covers none; the next window starts half the gap
//! ([`WindowParams::overlap_s`]) before that end, so consecutive windows share the
//! samples of their overlap. Every forbidden interval is longer than the gap, so every
//! window but the last is too, and with the overlap half the gap no sample lies in
//! three windows.

use crate::geom::Vec2;

/// Default [`WindowParams::revisit_radius_m`] (m): about a stride and a half, wider
/// than the spacing of the samples of a walker (0.5 to 0.7 m at 1.2 m/s) so that a
/// pass through a place is one visit, narrower than two people side by side.
pub const DEFAULT_REVISIT_RADIUS_M: f64 = 1.0;
/// Default [`WindowParams::revisit_gap_s`] (s): four samples at the usual 0.5 s step,
/// so a pass through a place is one visit, and about 2.4 m of walking, so a U-turn's
/// legs are told apart from about 1 m past the 2 m blocks of the turn on.
pub const DEFAULT_REVISIT_GAP_S: f64 = 2.0;
/// Most cells of the revisit grid; a larger bounding box gets larger cells.
pub const MAX_REVISIT_CELLS: usize = 1 << 18;

/// How a selection is cut into time windows (see the module documentation).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct WindowParams {
    /// Samples of one person closer than this along both axes are at the same place
    /// (m; up to twice as far may be).
    pub revisit_radius_m: f64,
    /// A person back at a place after more than this away has revisited it (s);
    /// infinite: never, one cage for every selection ([`WindowParams::one_cage`]).
    pub revisit_gap_s: f64,
}

impl Default for WindowParams {
    fn default() -> Self {
        WindowParams {
            revisit_radius_m: DEFAULT_REVISIT_RADIUS_M,
            revisit_gap_s: DEFAULT_REVISIT_GAP_S,
        }
    }
}

impl WindowParams {
    /// No time windows: one cage whatever the paths do (the paper's §3.2).
    pub fn one_cage() -> WindowParams {
        WindowParams {
            revisit_gap_s: f64::INFINITY,
            ..WindowParams::default()
        }
    }

    /// The first parameter out of range: the radius must be finite and positive, the
    /// gap positive (infinite turns windows off).
    pub fn problem(&self) -> Option<&'static str> {
        if !(self.revisit_radius_m.is_finite() && self.revisit_radius_m > 0.0) {
            Some("revisit_radius_m")
        } else if self.revisit_gap_s.is_nan() || self.revisit_gap_s <= 0.0 {
            Some("revisit_gap_s")
        } else {
            None
        }
    }

    /// The time consecutive windows share (s): half the gap, so that no sample lies
    /// in three windows.
    pub fn overlap_s(&self) -> f64 {
        0.5 * self.revisit_gap_s
    }
}

/// One time window: the samples with `start_s <= t < end_s` (the last window also
/// holds `t == end_s`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TimeWindow {
    /// First time (s).
    pub start_s: f64,
    /// End time (s, exclusive except for the last window).
    pub end_s: f64,
}

impl TimeWindow {
    /// Whether a sample at `t_s` belongs to this window (`last`: the last window).
    pub fn holds(&self, t_s: f64, last: bool) -> bool {
        t_s >= self.start_s && (t_s < self.end_s || (last && t_s <= self.end_s))
    }
}

/// The forbidden intervals of the samples `points` at `times_s`, where `person[i]`
/// names sample `i`'s person and each person's samples are consecutive and in time
/// order (a selection's order). See the module documentation.
///
/// # Complexity
/// O(N + cells), one allocation of the grid.
pub(super) fn revisits(
    points: &[Vec2],
    times_s: &[f64],
    person: &[usize],
    params: &WindowParams,
) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    if points.is_empty() || params.revisit_gap_s == f64::INFINITY {
        return out;
    }
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let ext = hi - lo;
    let mut cell = params.revisit_radius_m;
    let cells = |c: f64| ((ext.x / c) as usize + 3) * ((ext.y / c) as usize + 3);
    if cells(cell) > MAX_REVISIT_CELLS {
        cell = (ext.x * ext.y / MAX_REVISIT_CELLS as f64).sqrt().max(cell) * 1.5;
    }
    let (nx, ny) = ((ext.x / cell) as usize + 3, (ext.y / cell) as usize + 3);
    // Per cell: the person that last saw it (+1, 0 none) and when.
    let mut owner = vec![0u32; nx * ny];
    let mut last_s = vec![0.0f64; nx * ny];
    for ((p, &t), &k) in points.iter().zip(times_s).zip(person) {
        // The 2 × 2 block of cells nearest p: cells (i, j) .. (i + 1, j + 1) with
        // i = floor(x / cell - 0.5), shifted by one so that it is never negative.
        let gx = ((p.x - lo.x) / cell + 0.5) as usize;
        let gy = ((p.y - lo.y) / cell + 0.5) as usize;
        let k1 = k as u32 + 1;
        for (i, j) in [(gx, gy), (gx + 1, gy), (gx, gy + 1), (gx + 1, gy + 1)] {
            let c = j.min(ny - 1) * nx + i.min(nx - 1);
            if owner[c] == k1 && t - last_s[c] > params.revisit_gap_s {
                out.push((last_s[c], t));
            }
            owner[c] = k1;
            last_s[c] = t;
        }
    }
    out
}

/// The time windows of a selection spanning `[t_min_s, t_max_s]` with the forbidden
/// intervals `forbidden` (sorted here); one window when there is none.
///
/// # Complexity
/// O(F log F) for F forbidden intervals.
pub(super) fn cut(
    forbidden: &mut [(f64, f64)],
    t_min_s: f64,
    t_max_s: f64,
    params: &WindowParams,
) -> Vec<TimeWindow> {
    forbidden.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    // suffix_min[i]: the earliest end among the intervals from i on.
    let mut suffix_min = vec![f64::INFINITY; forbidden.len() + 1];
    for i in (0..forbidden.len()).rev() {
        suffix_min[i] = suffix_min[i + 1].min(forbidden[i].1);
    }
    let overlap = params.overlap_s();
    let mut windows = Vec::new();
    let mut start = t_min_s;
    loop {
        let first = forbidden.partition_point(|f| f.0 < start);
        let end = suffix_min[first];
        if end > t_max_s {
            windows.push(TimeWindow {
                start_s: start,
                end_s: t_max_s,
            });
            return windows;
        }
        windows.push(TimeWindow {
            start_s: start,
            end_s: end,
        });
        // end > start + gap = start + 2 overlap: the next start is later.
        start = end - overlap;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One walker out 10 m along +x and back 0.5 m beside the way out, 1.2 m/s, a
    /// sample every 0.5 s.
    fn u_turn() -> (Vec<Vec2>, Vec<f64>) {
        let mut pts = Vec::new();
        let mut ts = Vec::new();
        let leg = (10.0f64 / 0.6).round() as usize;
        for k in 0..=leg {
            pts.push(Vec2::new(0.6 * k as f64, 0.0));
        }
        for k in 1..=leg {
            pts.push(Vec2::new(10.0 - 0.6 * k as f64 + 0.0, 0.5));
        }
        for (i, _) in pts.iter().enumerate() {
            ts.push(0.5 * i as f64);
        }
        (pts, ts)
    }

    #[test]
    fn a_straight_walk_has_no_revisit() {
        let pts: Vec<Vec2> = (0..100).map(|k| Vec2::new(0.6 * k as f64, 0.0)).collect();
        let ts: Vec<f64> = (0..100).map(|k| 0.5 * k as f64).collect();
        let f = revisits(&pts, &ts, &[0; 100], &WindowParams::default());
        assert!(f.is_empty(), "{f:?}");
    }

    #[test]
    fn standing_still_is_one_visit() {
        let pts = vec![Vec2::new(3.0, 4.0); 60];
        let ts: Vec<f64> = (0..60).map(|k| 0.5 * k as f64).collect();
        assert!(revisits(&pts, &ts, &[0; 60], &WindowParams::default()).is_empty());
    }

    #[test]
    fn two_people_on_one_path_are_not_a_revisit() {
        // The second walks the same line 20 s later.
        let mut pts = Vec::new();
        let mut ts = Vec::new();
        let mut who = Vec::new();
        for p in 0..2 {
            for k in 0..30 {
                pts.push(Vec2::new(0.6 * k as f64, 0.0));
                ts.push(20.0 * p as f64 + 0.5 * k as f64);
                who.push(p);
            }
        }
        assert!(revisits(&pts, &ts, &who, &WindowParams::default()).is_empty());
    }

    #[test]
    fn a_u_turn_is_cut_so_that_no_window_holds_both_legs_far_from_the_turn() {
        let (pts, ts) = u_turn();
        let p = WindowParams::default();
        let mut f = revisits(&pts, &ts, &vec![0; pts.len()], &p);
        assert!(!f.is_empty());
        // Every forbidden interval is longer than the gap and joins the two legs.
        let turn_s = ts[pts.len() / 2];
        for &(a, b) in &f {
            assert!(b - a > p.revisit_gap_s);
            assert!(a < turn_s && b > turn_s, "({a}, {b}) around {turn_s}");
        }
        let w = cut(&mut f, ts[0], *ts.last().unwrap(), &p);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(w[0].start_s, 0.0);
        assert_eq!(w[1].end_s, *ts.last().unwrap());
        assert!((w[0].end_s - w[1].start_s - p.overlap_s()).abs() < 1e-12);
        // No window holds a sample of the way out and its neighbour on the way back
        // unless both are within the gap of the turn.
        for win in &w {
            let last = win == w.last().unwrap();
            for (i, &ti) in ts.iter().enumerate() {
                for (j, &tj) in ts.iter().enumerate().skip(i + 1) {
                    let near = (pts[i] - pts[j]).norm() < p.revisit_radius_m;
                    if near && win.holds(ti, last) && win.holds(tj, last) {
                        assert!(tj - ti <= p.revisit_gap_s + 1.0, "{ti} and {tj} in {win:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn windows_cover_the_span_and_overlap_by_the_given_time() {
        let mut f = vec![(0.0, 5.0), (3.0, 9.0), (8.5, 13.0), (20.0, 30.0)];
        let p = WindowParams::default();
        let w = cut(&mut f, 0.0, 40.0, &p);
        assert_eq!(w[0].start_s, 0.0);
        assert_eq!(w.last().unwrap().end_s, 40.0);
        for pair in w.windows(2) {
            assert!((pair[0].end_s - pair[1].start_s - p.overlap_s()).abs() < 1e-12);
            assert!(pair[1].start_s > pair[0].start_s);
        }
        // No window covers a forbidden interval.
        for win in &w {
            for &(a, b) in &f {
                assert!(
                    !(win.start_s <= a && win.end_s > b),
                    "{win:?} covers ({a}, {b})"
                );
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let p = WindowParams {
            revisit_gap_s: f64::NAN,
            ..WindowParams::default()
        };
        assert_eq!(p.problem(), Some("revisit_gap_s"));
        assert_eq!(WindowParams::default().problem(), None);
        assert_eq!(WindowParams::one_cage().problem(), None);
    }
}
