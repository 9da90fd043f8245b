//! A synthesised crowd motion applied to the crowd as it stands.
//!
//! Gesture-driven section 7.3 matches the agents to trajectory starts sampled from
//! the motion's mixture and walks them there first, so every gesture first
//! rearranges the crowd into the library crowd's shape. On a table the formation a
//! visitor shaped (or a switch or transform made) should survive a gesture. Here
//! the synthesis is decomposed into what it means for the group and a residual:
//!
//! 1. *Groups.* The crowd is cut into its parts: agents closer than
//!    [`GROUP_GAP_FACTOR`] spacings (single linkage) are one part, and a part with
//!    fewer than `min_part_agents` agents joins the nearest part. A split class
//!    (`split`, `split_then_translate`) instead cuts the whole crowd in two across
//!    the gesture's axis: the synthesised ends are clustered in two (2-means), the
//!    axis runs from one cluster's centroid to the other's, and the agents are
//!    ordered along it and divided in the clusters' proportion, so each part keeps
//!    its side of the formation.
//! 2. *The group part.* For each group and each sample `k`, the similarity (turn
//!    `R_k`, scale `s_k`) that best maps the group's trajectories at their start
//!    onto them at `k` (2-D Umeyama/Procrustes, least squares), and the
//!    displacement `d_k` of their centroid. Agent `i` of the group, standing at
//!    `p_i`, is sent along `y_i(k) = p_i + d_k + (s_k R_k − I)(p_i − c)`, with `c`
//!    the group's centroid: the formation translated, turned about its centre and
//!    scaled about it. A split part takes the motion of the trajectories that end
//!    in its cluster. The scale is kept at or above the one that would bring the
//!    group's nearest neighbours closer than two body radii (a contract never
//!    squeezes agents into each other).
//! 3. *The residual* `r_i(k) = x_i(k) − T_k(x_i(0))` of each agent's own
//!    trajectory (not for split parts, whose agents' trajectories belong to
//!    either cluster) is added bounded — at most `residual_fraction` of the group's
//!    RMS radius — and faded in and out by `sin(π k / (S_H − 1))`, so the motion
//!    keeps some of the library's liveliness and ends exactly on the moved
//!    formation.
//!
//! Sample 0 of every kept trajectory is the agent itself, so the follower's approach
//! ends at once. The planned ends, one per agent, and the parts are kept for the
//! mesh rebuilt afterwards.

use super::synth::Synthesis;
use crate::geom::Vec2;
use crate::gesture::library::S_H;

/// Agents closer than this many spacings (the median nearest-neighbour distance,
/// at least two body radii) are one part of the crowd.
pub const GROUP_GAP_FACTOR: f64 = 3.0;

/// How a synthesised motion is applied to the crowd (`gestures.apply`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum ApplyMode {
    /// As the paper does it: agents walk to trajectory starts sampled from the
    /// motion's mixture, then along the trajectories.
    AsSampled,
    /// The motion's group part (translation, turn, scale; per part for a split or
    /// a crowd in several parts) applied to the formation as it stands, plus a
    /// bounded residual.
    #[default]
    KeepFormation,
}

/// Tunables of [`keep_formation`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct KeepParams {
    /// Largest residual added to an agent's path, as a fraction of its group's RMS
    /// radius.
    pub residual_fraction: f64,
    /// A part with fewer agents joins the nearest part (at least 1).
    pub min_part_agents: usize,
    /// The agents' body radius (m).
    pub radius_m: f64,
}

impl Default for KeepParams {
    fn default() -> Self {
        KeepParams {
            residual_fraction: 0.1,
            min_part_agents: 5,
            radius_m: 0.15,
        }
    }
}

/// A similarity of the plane: `x ↦ s R(θ) x + t`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Similarity {
    /// Turn (rad, x towards y).
    pub theta_rad: f64,
    /// Scale.
    pub scale: f64,
    /// Translation (m).
    pub t_m: Vec2,
}

impl Similarity {
    /// The identity.
    pub const IDENTITY: Similarity = Similarity {
        theta_rad: 0.0,
        scale: 1.0,
        t_m: Vec2::new(0.0, 0.0),
    };

    /// `s R x + t`.
    pub fn apply(&self, x: Vec2) -> Vec2 {
        let (s, c) = self.theta_rad.sin_cos();
        self.scale * Vec2::new(c * x.x - s * x.y, s * x.x + c * x.y) + self.t_m
    }

    /// The least-squares similarity mapping `from[j]` onto `to[j]` (Umeyama 1991,
    /// eqs. 40–42, in 2-D): the turn from the cross and dot sums of the centred
    /// points, the scale from their projections over the source's spread. The
    /// identity for fewer than one pair; scale 1 when the source has no spread.
    pub fn fit(from: &[Vec2], to: &[Vec2]) -> Similarity {
        let n = from.len().min(to.len());
        if n == 0 {
            return Similarity::IDENTITY;
        }
        let ca = from[..n].iter().sum::<Vec2>() / n as f64;
        let cb = to[..n].iter().sum::<Vec2>() / n as f64;
        let (mut dot, mut cross, mut var) = (0.0, 0.0, 0.0);
        for (a, b) in from[..n].iter().zip(&to[..n]) {
            let (a, b) = (a - ca, b - cb);
            dot += a.dot(&b);
            cross += a.x * b.y - a.y * b.x;
            var += a.norm_squared();
        }
        let theta = cross.atan2(dot);
        let scale = if var > 1e-18 {
            (dot * dot + cross * cross).sqrt() / var
        } else {
            1.0
        };
        let rot = Similarity {
            theta_rad: theta,
            scale,
            t_m: Vec2::zeros(),
        };
        Similarity {
            t_m: cb - rot.apply(ca),
            ..rot
        }
    }
}

/// A motion applied to the crowd as it stands.
#[derive(Clone, Debug)]
pub struct Kept {
    /// One trajectory per agent (m), sample 0 where the agent stands.
    pub synthesis: Synthesis,
    /// The agents of each part (each agent in exactly one).
    pub parts: Vec<Vec<usize>>,
    /// Each part's group motion from start to end, about the part's centroid:
    /// `x ↦ end.apply(x)` maps where an agent stood to its planned end (before the
    /// residual, which ends at zero).
    pub ends: Vec<Similarity>,
}

/// The median nearest-neighbour distance of `pts` (at least `floor_m`); O(n²) for
/// n ≤ 2,000 points, a strided sample of 2,000 beyond.
fn spacing(pts: &[Vec2], floor_m: f64) -> f64 {
    if pts.len() < 2 {
        return floor_m;
    }
    let stride = pts.len().div_ceil(2000).max(1);
    let mut nn: Vec<f64> = pts
        .iter()
        .step_by(stride)
        .map(|p| {
            pts.iter()
                .filter(|q| !std::ptr::eq(*q, p))
                .map(|q| (q - p).norm_squared())
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .filter(|d| d.is_finite())
        .collect();
    if nn.is_empty() {
        return floor_m;
    }
    nn.sort_by(f64::total_cmp);
    nn[nn.len() / 2].max(floor_m)
}

/// The parts of the crowd: single linkage at `gap_m` (through a grid of cells of
/// that size), then parts smaller than `min` joined to the part of their nearest
/// agent outside them. Parts are listed by their smallest agent index.
pub fn parts_of(pts: &[Vec2], gap_m: f64, min: usize) -> Vec<Vec<usize>> {
    let n = pts.len();
    if n == 0 {
        return Vec::new();
    }
    let gap = gap_m.max(1e-9);
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let cell = |p: &Vec2| ((p.x / gap).floor() as i64, (p.y / gap).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<usize>> = Default::default();
    for (i, p) in pts.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i);
    }
    for (i, p) in pts.iter().enumerate() {
        let (cx, cy) = cell(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(js) = grid.get(&(cx + dx, cy + dy)) {
                    for &j in js {
                        if j > i && (pts[j] - p).norm_squared() <= gap * gap {
                            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                            if a != b {
                                parent[a.max(b)] = a.min(b);
                            }
                        }
                    }
                }
            }
        }
    }
    let mut roots: Vec<usize> = (0..n).map(|i| find(&mut parent, i)).collect();
    // Small parts join the part of the nearest agent outside them, smallest first,
    // until every part is big enough or one part is left.
    loop {
        let mut size = std::collections::BTreeMap::<usize, usize>::new();
        for &r in &roots {
            *size.entry(r).or_default() += 1;
        }
        if size.len() <= 1 {
            break;
        }
        let Some((&small, _)) = size
            .iter()
            .filter(|(_, &s)| s < min.max(1))
            .min_by_key(|(&r, &s)| (s, r))
        else {
            break;
        };
        let mut best = (f64::INFINITY, small);
        for i in (0..n).filter(|&i| roots[i] == small) {
            for j in (0..n).filter(|&j| roots[j] != small) {
                let d = (pts[i] - pts[j]).norm_squared();
                if d < best.0 {
                    best = (d, roots[j]);
                }
            }
        }
        for r in roots.iter_mut() {
            if *r == small {
                *r = best.1;
            }
        }
    }
    let mut by_root = std::collections::BTreeMap::<usize, Vec<usize>>::new();
    for (i, &r) in roots.iter().enumerate() {
        by_root.entry(r).or_default().push(i);
    }
    let mut parts: Vec<Vec<usize>> = by_root.into_values().collect();
    parts.sort_by_key(|p| p[0]);
    parts
}

/// The two clusters of `pts` (2-means from the two ends of the principal axis, a
/// few Lloyd rounds): each point's cluster, 0 or 1. All in cluster 0 for fewer than
/// two distinct points.
fn two_means(pts: &[Vec2]) -> Vec<u8> {
    let n = pts.len();
    if n < 2 {
        return vec![0; n];
    }
    let c = pts.iter().sum::<Vec2>() / n as f64;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let d = p - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let axis = Vec2::new(angle.cos(), angle.sin());
    let mut label: Vec<u8> = pts
        .iter()
        .map(|p| u8::from((p - c).dot(&axis) > 0.0))
        .collect();
    for _ in 0..20 {
        let mut sum = [Vec2::zeros(); 2];
        let mut count = [0usize; 2];
        for (p, &l) in pts.iter().zip(&label) {
            sum[l as usize] += p;
            count[l as usize] += 1;
        }
        if count[0] == 0 || count[1] == 0 {
            break;
        }
        let m = [sum[0] / count[0] as f64, sum[1] / count[1] as f64];
        let next: Vec<u8> = pts
            .iter()
            .map(|p| u8::from((p - m[1]).norm_squared() < (p - m[0]).norm_squared()))
            .collect();
        if next == label {
            break;
        }
        label = next;
    }
    label
}

/// Whether a class (its name in the library) divides the crowd in two.
pub fn is_split_class(name: &str) -> bool {
    matches!(name, "split" | "split_then_translate")
}

/// Lists of agent (or trajectory) indices.
type Groups = Vec<Vec<usize>>;

/// The two parts of a split and the trajectories each takes its motion from: the
/// synthesised ends in two clusters (2-means), the agents ordered along the axis
/// from one cluster's centroid to the other's and divided in the clusters'
/// proportion. A crowd thinner along the axis than its spacing (a line across
/// it) is ordered along the line instead, so each part is one end of it rather
/// than every other agent. `None` when a cluster or a part would have fewer than
/// `min` agents.
fn split_parts(
    traj: &[[Vec2; S_H]],
    agents: &[Vec2],
    space: f64,
    min: usize,
) -> Option<(Groups, Groups)> {
    let n = agents.len();
    let ends: Vec<Vec2> = traj.iter().map(|t| t[S_H - 1]).collect();
    let label = two_means(&ends);
    let cluster = |l: u8| -> Vec<usize> { (0..n).filter(|&j| label[j] == l).collect() };
    let (a, b) = (cluster(0), cluster(1));
    let min = min.max(1);
    if a.len() < min || b.len() < min {
        return None;
    }
    let mean = |js: &[usize]| js.iter().map(|&j| ends[j]).sum::<Vec2>() / js.len() as f64;
    let axis = (mean(&b) - mean(&a)).try_normalize(1e-12)?;
    let across = Vec2::new(-axis.y, axis.x);
    let proj: Vec<f64> = agents.iter().map(|p| p.dot(&axis)).collect();
    let m = proj.iter().sum::<f64>() / n as f64;
    let spread = (proj.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n as f64).sqrt();
    let key = |i: usize| {
        if spread < space {
            agents[i].dot(&across)
        } else {
            proj[i]
        }
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| key(i).total_cmp(&key(j)).then(i.cmp(&j)));
    // As many on the first cluster's side as it has trajectories.
    let take = a.len().clamp(1, n - 1);
    let mut first = order[..take].to_vec();
    let mut second = order[take..].to_vec();
    first.sort_unstable();
    second.sort_unstable();
    Some((vec![first, second], vec![a, b]))
}

/// The least scale that keeps the nearest neighbours of `pts` `floor_m` apart.
fn least_scale(pts: &[Vec2], floor_m: f64) -> f64 {
    if pts.len() >= 2 && floor_m > 0.0 {
        (floor_m / spacing(pts, 1e-9)).min(1.0)
    } else {
        0.0
    }
}

/// The group motion of a set of trajectories: at each sample, the similarity of
/// their starts onto them and their centroid.
struct GroupMotion {
    fits: Vec<Similarity>,
    centres: Vec<Vec2>,
}

impl GroupMotion {
    fn of(traj: &[[Vec2; S_H]], set: &[usize]) -> GroupMotion {
        let from: Vec<Vec2> = set.iter().map(|&j| traj[j][0]).collect();
        let mut to: Vec<Vec2> = Vec::with_capacity(set.len());
        let (fits, centres) = (0..S_H)
            .map(|k| {
                to.clear();
                to.extend(set.iter().map(|&j| traj[j][k]));
                let centre = to.iter().sum::<Vec2>() / to.len().max(1) as f64;
                (Similarity::fit(&from, &to), centre)
            })
            .unzip();
        GroupMotion { fits, centres }
    }
}

/// How a part follows a [`GroupMotion`].
struct Follow<'a> {
    /// The point the part turns and scales about (m).
    pivot: Vec2,
    /// Whether it turns and scales at all (a split's part only translates).
    turn: bool,
    /// The least scale (two radii between nearest neighbours).
    min_scale: f64,
    /// Extra shift at each sample (m); empty: none.
    shift: &'a [Vec2],
    /// The bound of each agent's residual (m); `None`: no residual.
    residual: Option<f64>,
}

/// Moves `part` (agents) by `m`: at each sample its similarity about `how.pivot`,
/// the pivot moved as the trajectories' centroid moved, plus `how.shift[k]`; with
/// a residual bound, each agent's own trajectory's deviation from that, bounded
/// and faded in and out. Sample 0 is where the agent stands. Returns the motion
/// from start to end.
fn move_part(
    out: &mut [[Vec2; S_H]],
    agents: &[Vec2],
    traj: &[[Vec2; S_H]],
    part: &[usize],
    m: &GroupMotion,
    how: &Follow,
) -> Similarity {
    let mut end = Similarity::IDENTITY;
    for k in 0..S_H {
        let f = m.fits[k];
        let turn = if how.turn {
            Similarity {
                theta_rad: f.theta_rad,
                scale: f.scale.max(how.min_scale),
                t_m: Vec2::zeros(),
            }
        } else {
            Similarity::IDENTITY
        };
        let d = how.shift.get(k).copied().unwrap_or_else(Vec2::zeros);
        let about = Similarity {
            t_m: how.pivot + (m.centres[k] - m.centres[0]) + d - turn.apply(how.pivot),
            ..turn
        };
        let fade = (std::f64::consts::PI * k as f64 / (S_H - 1) as f64).sin();
        for &i in part {
            let mut y = about.apply(agents[i]);
            if let (Some(bound), true) = (how.residual, k > 0 && k < S_H - 1) {
                let r = traj[i][k] - f.apply(traj[i][0]) - d;
                let len = r.norm();
                let r = if len > bound && len > 0.0 {
                    r * (bound / len)
                } else {
                    r
                };
                y += r * fade;
            }
            out[i][k] = if k == 0 { agents[i] } else { y };
        }
        if k == S_H - 1 {
            end = about;
        }
    }
    end
}

/// A motion that does not split: the whole crowd's similarity (fitted on every
/// trajectory, about the crowd's centroid); a crowd in several parts also moves
/// each part by how its own trajectories' centroid moved beyond that similarity
/// (the parts of a join close in, those of a twist orbit with the whole).
fn whole(
    out: &mut [[Vec2; S_H]],
    agents: &[Vec2],
    traj: &[[Vec2; S_H]],
    space: f64,
    floor_m: f64,
    params: &KeepParams,
) -> (Vec<Vec<usize>>, Vec<Similarity>) {
    let n = agents.len();
    let parts = parts_of(agents, GROUP_GAP_FACTOR * space, params.min_part_agents);
    let all: Vec<usize> = (0..n).collect();
    let c = agents.iter().sum::<Vec2>() / n.max(1) as f64;
    let rms = (agents.iter().map(|p| (p - c).norm_squared()).sum::<f64>() / n.max(1) as f64).sqrt();
    let m = GroupMotion::of(traj, &all);
    let mut ends = Vec::with_capacity(parts.len());
    for part in &parts {
        // Each part's own shift beyond the whole's similarity (none for one part).
        let shift: Vec<Vec2> = if parts.len() > 1 {
            let centre =
                |k: usize| part.iter().map(|&j| traj[j][k]).sum::<Vec2>() / part.len() as f64;
            (0..S_H)
                .map(|k| centre(k) - m.fits[k].apply(centre(0)))
                .collect()
        } else {
            Vec::new()
        };
        let how = Follow {
            pivot: c,
            turn: true,
            min_scale: least_scale(agents, floor_m),
            shift: &shift,
            residual: Some(params.residual_fraction.max(0.0) * rms),
        };
        ends.push(move_part(out, agents, traj, part, &m, &how));
    }
    (parts, ends)
}

/// `s` applied to the crowd at `agents` as it stands (module doc). `split`: the
/// class divides the crowd in two. Trajectory `i` of `s` is agent `i`'s.
pub fn keep_formation(s: &Synthesis, agents: &[Vec2], split: bool, params: &KeepParams) -> Kept {
    let n = agents.len().min(s.trajectories.len());
    let agents = &agents[..n];
    let traj = &s.trajectories[..n];
    let floor = 2.0 * params.radius_m.max(0.0);
    let space = spacing(agents, floor.max(1e-3));
    let mut out: Vec<[Vec2; S_H]> = vec![[Vec2::zeros(); S_H]; n];
    let (parts, ends) = if split && n >= 2 {
        match split_parts(traj, agents, space, params.min_part_agents) {
            Some((parts, clusters)) => {
                let mut ends = Vec::with_capacity(2);
                for (part, cluster) in parts.iter().zip(&clusters) {
                    // A part moves as its cluster's centroid does: the turn and
                    // scale of a cluster fitted from the starts it was sampled at
                    // (spread over the library crowd's shape) to the compact group
                    // it ends in say nothing about the part's own formation.
                    let how = Follow {
                        pivot: part.iter().map(|&i| agents[i]).sum::<Vec2>() / part.len() as f64,
                        turn: false,
                        min_scale: 0.0,
                        shift: &[],
                        residual: None,
                    };
                    let m = GroupMotion::of(traj, cluster);
                    ends.push(move_part(&mut out, agents, traj, part, &m, &how));
                }
                (parts, ends)
            }
            None => whole(&mut out, agents, traj, space, floor, params),
        }
    } else {
        whole(&mut out, agents, traj, space, floor, params)
    };
    Kept {
        synthesis: Synthesis {
            trajectories: out,
            duration_s: s.duration_s,
        },
        parts,
        ends,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(nx: usize, ny: usize, step: f64, at: Vec2) -> Vec<Vec2> {
        (0..nx * ny)
            .map(|k| at + Vec2::new((k % nx) as f64 * step, (k / nx) as f64 * step))
            .collect()
    }

    /// A synthesis in which every trajectory is `motion` applied over time to a
    /// start cloud unlike the crowd (a ring), as the mixture's samples are.
    fn synth_of(n: usize, centre: Vec2, motion: impl Fn(f64, Vec2) -> Vec2) -> Synthesis {
        let starts: Vec<Vec2> = (0..n)
            .map(|i| {
                let a = i as f64 * 2.399;
                centre + Vec2::new(a.cos(), a.sin()) * (1.0 + 0.5 * (i % 3) as f64)
            })
            .collect();
        Synthesis {
            trajectories: starts
                .iter()
                .map(|&p| std::array::from_fn(|k| motion(k as f64 / (S_H - 1) as f64, p)))
                .collect(),
            duration_s: 3.0,
        }
    }

    /// RMS distance between `a` mapped by the best similarity and `b`, over `b`'s
    /// RMS radius.
    fn procrustes_residual(a: &[Vec2], b: &[Vec2]) -> f64 {
        let t = Similarity::fit(a, b);
        let cb = b.iter().sum::<Vec2>() / b.len() as f64;
        let rms_b =
            (b.iter().map(|p| (p - cb).norm_squared()).sum::<f64>() / b.len() as f64).sqrt();
        let err = (a
            .iter()
            .zip(b)
            .map(|(p, q)| (t.apply(*p) - q).norm_squared())
            .sum::<f64>()
            / a.len() as f64)
            .sqrt();
        err / rms_b
    }

    #[test]
    fn fit_recovers_a_similarity_exactly() {
        let t = Similarity {
            theta_rad: 0.7,
            scale: 1.3,
            t_m: Vec2::new(2.0, -1.0),
        };
        let a = grid(4, 3, 0.5, Vec2::new(1.0, 1.0));
        let b: Vec<Vec2> = a.iter().map(|p| t.apply(*p)).collect();
        let f = Similarity::fit(&a, &b);
        assert!((f.theta_rad - 0.7).abs() < 1e-12 && (f.scale - 1.3).abs() < 1e-12);
        assert!((f.t_m - t.t_m).norm() < 1e-12);
        assert_eq!(Similarity::fit(&[], &[]), Similarity::IDENTITY);
    }

    #[test]
    fn a_translate_keeps_a_rectangle_a_rectangle() {
        let crowd = grid(10, 5, 0.5, Vec2::new(2.0, 2.0));
        let s = synth_of(50, Vec2::new(4.0, 3.0), |u, p| {
            p + Vec2::new(3.0 * u, 0.0)
                + Vec2::new(0.0, 0.2 * (4.0 * std::f64::consts::PI * u).sin())
        });
        let k = keep_formation(&s, &crowd, false, &KeepParams::default());
        assert_eq!(k.parts.len(), 1);
        for (i, t) in k.synthesis.trajectories.iter().enumerate() {
            assert_eq!(t[0], crowd[i], "the motion starts where the agent stands");
            let moved = t[S_H - 1] - crowd[i];
            assert!((moved - Vec2::new(3.0, 0.0)).norm() < 1e-9, "{moved:?}");
        }
    }

    #[test]
    fn a_twist_turns_the_formation_about_its_centre_and_a_contract_shrinks_it() {
        let crowd = grid(6, 6, 0.6, Vec2::new(0.0, 0.0));
        let c = Vec2::new(1.5, 1.5);
        let turn = synth_of(36, c, |u, p| {
            Similarity {
                theta_rad: 1.0 * u,
                scale: 1.0,
                t_m: Vec2::zeros(),
            }
            .apply(p - c)
                + c
        });
        let k = keep_formation(&turn, &crowd, false, &KeepParams::default());
        let after: Vec<Vec2> = k
            .synthesis
            .trajectories
            .iter()
            .map(|t| t[S_H - 1])
            .collect();
        let f = Similarity::fit(&crowd, &after);
        assert!(
            (f.theta_rad - 1.0).abs() < 1e-9 && (f.scale - 1.0).abs() < 1e-9,
            "{f:?}"
        );
        assert!(procrustes_residual(&crowd, &after) < 1e-9);
        let shrink = synth_of(36, c, |u, p| (p - c) * (1.0 - 0.3 * u) + c);
        let k = keep_formation(
            &shrink,
            &crowd,
            false,
            &KeepParams {
                radius_m: 0.1,
                ..KeepParams::default()
            },
        );
        let after: Vec<Vec2> = k
            .synthesis
            .trajectories
            .iter()
            .map(|t| t[S_H - 1])
            .collect();
        let f = Similarity::fit(&crowd, &after);
        assert!((f.scale - 0.7).abs() < 1e-9, "{f:?}");
        // A contract that would squeeze agents into each other stops at two radii.
        let k = keep_formation(
            &shrink,
            &crowd,
            false,
            &KeepParams {
                radius_m: 0.25,
                ..KeepParams::default()
            },
        );
        let after: Vec<Vec2> = k
            .synthesis
            .trajectories
            .iter()
            .map(|t| t[S_H - 1])
            .collect();
        assert!((Similarity::fit(&crowd, &after).scale - 0.5 / 0.6).abs() < 1e-9);
    }

    #[test]
    fn a_split_divides_the_crowd_along_the_axis_into_two_parts_that_keep_their_shape() {
        let crowd = grid(10, 4, 0.5, Vec2::new(0.0, 0.0));
        let c = Vec2::new(2.25, 0.75);
        // Trajectories from a ring; those starting left go 2 m left, the others right.
        let s = synth_of(40, c, |u, p| {
            p + Vec2::new(if p.x < c.x { -2.0 } else { 2.0 } * u, 0.0)
        });
        let k = keep_formation(&s, &crowd, true, &KeepParams::default());
        assert_eq!(k.parts.len(), 2);
        let ends: Vec<Vec2> = k
            .synthesis
            .trajectories
            .iter()
            .map(|t| t[S_H - 1])
            .collect();
        for part in &k.parts {
            let xs: Vec<f64> = part.iter().map(|&i| crowd[i].x).collect();
            let left = xs.iter().all(|&x| x < c.x);
            let right = xs.iter().all(|&x| x > c.x);
            assert!(left || right, "a part keeps one side: {xs:?}");
            let before: Vec<Vec2> = part.iter().map(|&i| crowd[i]).collect();
            let after: Vec<Vec2> = part.iter().map(|&i| ends[i]).collect();
            assert!(procrustes_residual(&before, &after) < 1e-9);
            let dx = after[0].x - before[0].x;
            assert!((dx - if left { -2.0 } else { 2.0 }).abs() < 0.3, "{dx}");
        }
    }

    #[test]
    fn the_residual_is_bounded_and_gone_at_the_end() {
        let crowd = grid(8, 8, 0.5, Vec2::zeros());
        let wild = synth_of(64, Vec2::new(1.75, 1.75), |u, p| {
            p + Vec2::new(2.0 * u, 3.0 * (7.0 * u + p.x).sin() * (1.0 - u) * u)
        });
        let params = KeepParams::default();
        let k = keep_formation(&wild, &crowd, false, &params);
        let rms = (crowd
            .iter()
            .map(|p| (p - Vec2::new(1.75, 1.75)).norm_squared())
            .sum::<f64>()
            / 64.0)
            .sqrt();
        let bound = params.residual_fraction * rms;
        let mut largest: f64 = 0.0;
        for kk in 0..S_H {
            // Each agent's distance from the formation moved rigidly at sample kk.
            let now: Vec<Vec2> = k.synthesis.trajectories.iter().map(|t| t[kk]).collect();
            let f = Similarity::fit(&crowd, &now);
            for (p, y) in crowd.iter().zip(&now) {
                let off = (f.apply(*p) - y).norm();
                largest = largest.max(off);
                assert!(
                    off <= 2.0 * bound + 1e-9,
                    "sample {kk}: {off} m off the formation"
                );
            }
        }
        assert!(
            largest > 0.2 * bound,
            "the residual is there at all: {largest}"
        );
        for (i, t) in k.synthesis.trajectories.iter().enumerate() {
            assert!((t[S_H - 1] - (crowd[i] + Vec2::new(2.0, 0.0))).norm() < 1e-6);
        }
    }

    #[test]
    fn parts_are_single_linkage_groups_and_small_parts_join_the_nearest() {
        let mut pts = grid(3, 3, 0.5, Vec2::zeros());
        pts.extend(grid(3, 3, 0.5, Vec2::new(10.0, 0.0)));
        pts.push(Vec2::new(13.0, 0.0));
        let parts = parts_of(&pts, 1.5, 2);
        assert_eq!(parts.len(), 2);
        assert!(
            parts[1].contains(&18),
            "the straggler joins the near part: {parts:?}"
        );
        let alone = parts_of(&pts, 1.5, 1);
        assert_eq!(alone.len(), 3);
        assert!(parts_of(&[], 1.0, 3).is_empty());
    }
}
