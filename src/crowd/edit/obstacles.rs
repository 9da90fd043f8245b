//! Keeping a crowd out of obstacles by adjusting its cage (crowd-motion-editing
//! section 4.2, eq. 29, Figs. 10–12).
//!
//! The cage encloses the crowd, so a cage that touches no obstacle keeps the people
//! out of them (Fig. 10). [`avoid_obstacles`] finds the deformed hull vertices inside
//! an obstacle part (Fig. 11 a), maps each to the part's nearest boundary point,
//! pushed out by a clearance along the outward normal, the nearest exit direction
//! (Fig. 11 b–c), and drags the cage with those targets by eq. 1 (Fig. 11 d). A hull
//! edge that crosses a part with both ends outside (an obstacle corner poking into the
//! cage) is handled the same way: its deepest sampled point inside the part gives an
//! exit displacement applied to both ends. Since the deformation can carry other
//! vertices into obstacles, this repeats for a few rounds, keeping the targets found
//! so far.

use super::cage::{Cage, Handle};
use super::error::EditError;
use super::tracks::TrackSet;
use crate::crowd::environment::Obstacle;
use crate::geom::{cross, Vec2};

/// Points sampled along a hull edge to find its deepest point inside a part.
const EDGE_SAMPLES: usize = 16;

/// Parameters of [`avoid_obstacles`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ObstacleParams {
    /// Distance kept from the obstacle boundary (m).
    pub clearance_m: f64,
    /// Detection and drag rounds at most.
    pub max_rounds: usize,
}

impl Default for ObstacleParams {
    fn default() -> Self {
        ObstacleParams {
            clearance_m: 0.1,
            max_rounds: 6,
        }
    }
}

/// What [`avoid_obstacles`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct ObstacleReport {
    /// The hull vertices dragged out of obstacles, with their targets (m).
    pub targets: Vec<(usize, Vec2)>,
    /// Rounds run.
    pub rounds: usize,
    /// Hull vertices inside an obstacle, or hull edges crossing one, after the last
    /// round (0 on success).
    pub hull_violations: usize,
    /// Selected samples inside an obstacle before the adjustment.
    pub samples_inside_before: usize,
    /// Selected samples inside an obstacle after it.
    pub samples_inside_after: usize,
}

/// The signed distance of `p` to the obstacles (m, negative inside) with the exit
/// point (nearest boundary point pushed out by `clearance_m`) of the deepest part.
fn deepest(obstacles: &[Obstacle], p: Vec2, clearance_m: f64) -> Option<(f64, Vec2)> {
    let mut best: Option<(f64, Vec2)> = None;
    for part in obstacles.iter().flat_map(|o| &o.parts) {
        let b = part.boundary_point(p);
        if b.signed_distance_m < clearance_m && best.is_none_or(|(d, _)| b.signed_distance_m < d) {
            best = Some((b.signed_distance_m, b.point + b.normal * clearance_m));
        }
    }
    best
}

fn samples_inside(cage: &Cage, obstacles: &[Obstacle]) -> usize {
    (0..cage.selection().len())
        .filter(|&i| {
            let p = cage.deformed_sample(i);
            obstacles
                .iter()
                .flat_map(|o| &o.parts)
                .any(|part| part.contains(p))
        })
        .count()
}

/// Drags the cage's hull out of the obstacles (see the module documentation),
/// keeping the drags in `keep` (e.g. the user's) as well.
///
/// # Errors
/// The errors of [`Cage::drag`].
pub fn avoid_obstacles(
    cage: &mut Cage,
    obstacles: &[Obstacle],
    keep: &[(Handle, Vec2)],
    params: &ObstacleParams,
) -> Result<ObstacleReport, EditError> {
    let mut rep = ObstacleReport {
        targets: Vec::new(),
        rounds: 0,
        hull_violations: 0,
        samples_inside_before: samples_inside(cage, obstacles),
        samples_inside_after: 0,
    };
    // A vertex is "in" when it is closer to a part than half the clearance, so that
    // vertices already placed at the clearance are not counted again.
    let inside_tol = 0.5 * params.clearance_m;
    let mut drags: Vec<(Handle, Vec2)> = keep.to_vec();
    for round in 0..=params.max_rounds {
        // Hull indices run over every time window's hull (`Cage::hull_range`);
        // edges close each window's polygon.
        let hull = cage.deformed_hull();
        let mut found: Vec<(usize, Vec2)> = Vec::new();
        for (i, v) in hull.iter().enumerate() {
            if let Some((d, exit)) = deepest(obstacles, *v, params.clearance_m) {
                if d < inside_tol {
                    found.push((i, exit));
                }
            }
        }
        let edges = (0..cage.window_count()).flat_map(|w| {
            let r = cage.hull_range(w);
            r.clone()
                .map(move |i| (i, if i + 1 == r.end { r.start } else { i + 1 }))
        });
        for (i, j) in edges {
            let (a, b) = (hull[i], hull[j]);
            let mut worst: Option<(f64, Vec2)> = None;
            for s in 1..EDGE_SAMPLES {
                let q = a + (b - a) * (s as f64 / EDGE_SAMPLES as f64);
                if let Some((d, exit)) = deepest(obstacles, q, params.clearance_m) {
                    if d < 0.0 && worst.is_none_or(|(w, _)| d < w) {
                        worst = Some((d, exit - q));
                    }
                }
            }
            if let Some((_, shift)) = worst {
                for k in [i, j] {
                    if !found.iter().any(|f| f.0 == k) {
                        found.push((k, hull[k] + shift));
                    }
                }
            }
        }
        rep.hull_violations = found.len();
        if found.is_empty() || round == params.max_rounds {
            break;
        }
        rep.rounds = round + 1;
        for (i, t) in found {
            match drags.iter_mut().find(|d| d.0 == Handle::Hull(i)) {
                Some(d) => d.1 = t,
                None => drags.push((Handle::Hull(i), t)),
            }
        }
        cage.drag(&drags, &[])?;
    }
    rep.targets = drags
        .iter()
        .filter_map(|d| match d.0 {
            Handle::Hull(i) if !keep.iter().any(|k| k.0 == d.0) => Some((i, d.1)),
            _ => None,
        })
        .collect();
    rep.samples_inside_after = samples_inside(cage, obstacles);
    Ok(rep)
}

/// How many samples of `tracks` (indices into `set`) lie inside each obstacle,
/// one count per obstacle of `obstacles`.
pub fn samples_in_obstacles(
    set: &TrackSet,
    tracks: &[usize],
    obstacles: &[Obstacle],
) -> Vec<usize> {
    let mut out = vec![0; obstacles.len()];
    for &k in tracks {
        for &p in &set.tracks[k].points {
            for (o, count) in obstacles.iter().zip(out.iter_mut()) {
                if o.parts.iter().any(|part| part.contains(p)) {
                    *count += 1;
                }
            }
        }
    }
    out
}

/// Moves each sample of `tracks` that is inside an obstacle (or nearer its
/// boundary than half the clearance) to its exit: the nearest boundary point of
/// the deepest part, pushed out by `clearance_m` along the outward normal (the
/// targets of section 4.2's hull vertices, applied to one person's sample when the
/// cage could not carry it out: a cage encloses its group, not each person).
/// Repeats while a moved sample lands in another part, at most `rounds` times.
/// Returns how many samples were moved.
pub fn push_samples_out(
    set: &mut TrackSet,
    tracks: &[usize],
    obstacles: &[Obstacle],
    clearance_m: f64,
    rounds: usize,
) -> usize {
    let mut moved = 0;
    for &k in tracks {
        for p in &mut set.tracks[k].points {
            let mut changed = false;
            for _ in 0..rounds.max(1) {
                match deepest(obstacles, *p, clearance_m) {
                    Some((d, exit)) if d < 0.5 * clearance_m => {
                        *p = exit;
                        changed = true;
                    }
                    _ => break,
                }
            }
            moved += usize::from(changed);
        }
    }
    moved
}

/// The crowd's width across its moving direction (eq. 29).
///
/// # Formula
/// `D = max_{p, q ∈ G} ‖p − q‖ sin θ_pq`, `θ_pq` the angle between `p − q` and the
/// moving direction `u`: `‖p − q‖ sin θ = |(p − q) × û|`, so `D` is the extent of `G`
/// along the normal of `u`, `max_p (p × û) − min_p (p × û)`, computed in O(|G|).
///
/// # Units
/// Metres; `direction` any non-zero length. Returns 0 for fewer than two points or a
/// zero direction.
pub fn crowd_width(points: &[Vec2], direction: Vec2) -> f64 {
    let len = direction.norm();
    if points.len() < 2 || len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return 0.0;
    }
    let u = direction / len;
    let (lo, hi) = points
        .iter()
        .map(|p| cross(*p, u))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| {
            (l.min(c), h.max(c))
        });
    hi - lo
}

/// Eq. 29 for the given tracks at time `t_s`: the positions of the people present,
/// across their mean velocity (taken over `t_s ± step_s / 2`). `None` when fewer than
/// two are present or they do not move.
pub fn crowd_width_at(set: &TrackSet, tracks: &[usize], t_s: f64) -> Option<f64> {
    let h = 0.5 * set.step_s;
    let mut pts = Vec::new();
    let mut dir = Vec2::zeros();
    for &ti in tracks {
        let t = set.tracks.get(ti)?;
        if let Some(p) = t.position_at(t_s) {
            pts.push(p);
            if let (Some(a), Some(b)) = (t.position_at(t_s - h), t.position_at(t_s + h)) {
                dir += b - a;
            }
        }
    }
    if pts.len() < 2 || dir.norm_squared() == 0.0 {
        return None;
    }
    Some(crowd_width(&pts, dir))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::cage::CageParams;
    use crate::crowd::edit::select::{Selection, SelectionQuery};
    use crate::crowd::edit::tracks::Track;
    use crate::crowd::environment::{Circle, ConvexPolygon, Part};

    /// 8 people side by side 0.8 m apart (5.6 m wide) walking along +x, 40 samples.
    fn band() -> TrackSet {
        let tracks = (0..8)
            .map(|i| {
                let pts = (0..40)
                    .map(|j| Vec2::new(0.6 * j as f64, 0.8 * i as f64))
                    .collect();
                let ts = (0..40).map(|j| 0.5 * j as f64).collect();
                Track::linked(i as u64, pts, ts)
            })
            .collect();
        TrackSet {
            tracks,
            step_s: 0.5,
        }
    }

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Part {
        Part::Polygon(
            ConvexPolygon::new(vec![
                Vec2::new(x0, y0),
                Vec2::new(x1, y0),
                Vec2::new(x1, y1),
                Vec2::new(x0, y1),
            ])
            .unwrap(),
        )
    }

    #[test]
    fn crowd_squeezes_through_a_narrowing_gap() {
        let set = band();
        // A gap 4.4 m wide (y from 0.6 to 5.0) at x in [10, 14]; the crowd is 5.6 m wide.
        let obstacles = vec![
            Obstacle {
                name: "top".into(),
                parts: vec![rect(10.0, 5.0, 14.0, 9.0)],
            },
            Obstacle {
                name: "bottom".into(),
                parts: vec![
                    rect(10.0, -4.0, 14.0, 0.6),
                    Part::Circle(Circle {
                        centre: Vec2::new(8.0, -1.2),
                        radius_m: 1.5,
                    }),
                ],
            },
        ];
        let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
        let mut cage = Cage::new(&set, &sel, &CageParams::default()).unwrap();
        let rep = avoid_obstacles(&mut cage, &obstacles, &[], &ObstacleParams::default()).unwrap();
        assert!(rep.samples_inside_before > 0, "{rep:?}");
        assert_eq!(rep.hull_violations, 0, "{rep:?}");
        assert_eq!(rep.samples_inside_after, 0, "{rep:?}");
        let mut out = set.clone();
        cage.apply(&mut out).unwrap();
        let all: Vec<usize> = (0..8).collect();
        // At x = 12 m (sample 20, t = 10 s) the crowd now fits the gap.
        let w_before = crowd_width_at(&set, &all, 10.0).unwrap();
        let w_after = crowd_width_at(&out, &all, 10.0).unwrap();
        assert!((w_before - 5.6).abs() < 1e-9);
        assert!(w_after < 4.4, "{w_after}");
        // Far from the gap the crowd keeps most of its width.
        let w_far = crowd_width_at(&out, &all, 1.0).unwrap();
        assert!(w_far > 5.0, "{w_far}");
    }

    #[test]
    fn width_is_the_extent_across_the_motion() {
        let pts = [
            Vec2::new(0.0, 0.0),
            Vec2::new(3.0, 1.0),
            Vec2::new(1.0, -2.0),
        ];
        assert!((crowd_width(&pts, Vec2::new(1.0, 0.0)) - 3.0).abs() < 1e-12);
        assert!((crowd_width(&pts, Vec2::new(0.0, 2.0)) - 3.0).abs() < 1e-12);
        assert_eq!(crowd_width(&pts[..1], Vec2::x()), 0.0);
    }
}
