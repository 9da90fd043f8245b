//! Synthesising the trajectories of the crowd at hand from a motion's features
//! (gesture-driven section 7.3): sample one eigenscore vector per agent from the
//! mixture, rebuild trajectories by eq. 16, place them in the world, and match
//! agents to trajectory starts by optimal assignment ([HSK12]; here
//! [`crate::crowd::assign::CoarseToFine`], exact, on squared distance) so that no
//! agent walks far to its start.
//!
//! The number of agents is free: the mixture is sampled as often as there are
//! agents, whatever the size of the crowds the library's motions came from.

use super::crowd_motion::deserialise;
use super::error::MotionError;
use super::features::validate_features;
use super::fpca::reconstruct;
use super::gmm::GmmSampler;
use crate::crowd::assign::{AffineMap, CoarseStats, CoarseToFine, CostMatrix};
use crate::geom::Vec2;
use crate::gesture::library::{MotionFeatures, S_H, TRAJ_DIM};
use crate::rng::SplitMix64;

/// Where and how large a synthesised motion runs.
///
/// # Convention
/// A point `p` in crowd units (the motion's starting centroid at the origin, its
/// starting RMS radius 1) goes to the world point (metres)
///
/// ```text
///   world = centre + gesture_offset + R(rotation_rad) · (scale_m · p)
/// ```
///
/// with `R(θ)` the counter-clockwise rotation by `θ` (in the world's x-right, y-up
/// frame). So the motion's starting centroid lands on `centre + gesture_offset` and
/// its starting RMS radius is `scale_m`. [`Placement::for_crowd`] fits it to a crowd
/// (its centroid and RMS radius, no rotation, no offset); `gesture_offset` moves the
/// whole motion (e.g. towards where the gesture was drawn), `rotation_rad` turns it
/// (e.g. to the gesture's orientation).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placement {
    /// Where the motion's starting centroid goes, before the offset (m).
    pub centre: Vec2,
    /// The motion's starting RMS radius in the world (m, > 0).
    pub scale_m: f64,
    /// Rotation of the motion about its starting centroid (rad, counter-clockwise).
    pub rotation_rad: f64,
    /// Translation added to every point (m).
    pub gesture_offset: Vec2,
}

impl Default for Placement {
    fn default() -> Placement {
        Placement {
            centre: Vec2::zeros(),
            scale_m: 1.0,
            rotation_rad: 0.0,
            gesture_offset: Vec2::zeros(),
        }
    }
}

/// Smallest `scale_m` [`Placement::for_crowd`] gives (m): a crowd of one agent, or
/// of agents on one spot, still gets a motion of this size.
pub const MIN_CROWD_SCALE_M: f64 = 0.5;

impl Placement {
    /// The placement on a crowd: its centroid, its RMS radius about it (at least
    /// [`MIN_CROWD_SCALE_M`]), no rotation and no offset. The centre is the origin
    /// for no agents.
    pub fn for_crowd(agents: &[Vec2]) -> Placement {
        let n = agents.len().max(1) as f64;
        let centre = agents.iter().fold(Vec2::zeros(), |a, p| a + p) / n;
        let ms = agents
            .iter()
            .map(|p| (p - centre).norm_squared())
            .sum::<f64>()
            / n;
        Placement {
            centre,
            scale_m: ms.sqrt().max(MIN_CROWD_SCALE_M),
            ..Placement::default()
        }
    }

    /// A crowd-unit point in the world (see the convention above).
    pub fn apply(&self, p: Vec2) -> Vec2 {
        let (s, c) = self.rotation_rad.sin_cos();
        let q = p * self.scale_m;
        self.centre + self.gesture_offset + Vec2::new(c * q.x - s * q.y, s * q.x + c * q.y)
    }

    fn validate(&self) -> Result<(), MotionError> {
        let finite = [
            self.centre.x,
            self.centre.y,
            self.rotation_rad,
            self.gesture_offset.x,
            self.gesture_offset.y,
        ];
        if let Some(i) = finite.iter().position(|v| !v.is_finite()) {
            return Err(MotionError::NotFinite {
                what: "placement",
                index: 0,
                sample: i,
            });
        }
        if !(self.scale_m.is_finite() && self.scale_m > 0.0) {
            return Err(MotionError::BadValue {
                what: "placement scale_m",
                value: self.scale_m,
                why: "finite and > 0",
            });
        }
        Ok(())
    }
}

/// Trajectories for a crowd: `trajectories[i]` is agent `i`'s (world metres, [`S_H`]
/// samples evenly spaced over `duration_s`).
#[derive(Clone, Debug, PartialEq)]
pub struct Synthesis {
    /// One trajectory per agent, in the agents' order.
    pub trajectories: Vec<[Vec2; S_H]>,
    /// Time from the first sample to the last (s).
    pub duration_s: f64,
}

/// [`synthesise`] with its workspaces kept from call to call (the assignment's
/// solvers and cost matrices, the scores and the unassigned trajectories).
///
/// The assignment is [`CoarseToFine`]: the agents and the starts mapped to a common
/// centre and spread ([`AffineMap::equalising`]; the starts are sampled from a
/// mixture and the agents stand in a formation, two differently shaped clouds),
/// solved on nested random subsets of a quarter, a sixteenth, … of both, each level
/// started from the prices of the one below, the last on the full `M × M` matrix of
/// squared distances (8 MB at 1,000 agents, reused). The answer is the exact optimum
/// of the plain squared distances.
pub struct Synthesiser {
    assigner: CoarseToFine,
    scores: Vec<f64>,
    buf: Vec<f64>,
    raw: Vec<[Vec2; S_H]>,
    starts: Vec<Vec2>,
}

impl Default for Synthesiser {
    fn default() -> Synthesiser {
        Synthesiser::new()
    }
}

impl Synthesiser {
    /// Empty workspaces.
    pub fn new() -> Synthesiser {
        Synthesiser {
            assigner: CoarseToFine::new(),
            scores: Vec::new(),
            buf: vec![0.0; TRAJ_DIM],
            raw: Vec::new(),
            starts: Vec::new(),
        }
    }

    /// Work counters of the last synthesis's assignment.
    pub fn assign_stats(&self) -> CoarseStats {
        self.assigner.stats()
    }

    /// See [`synthesise`].
    ///
    /// # Errors
    /// As [`synthesise`].
    pub fn synthesise(
        &mut self,
        f: &MotionFeatures,
        agents: &[Vec2],
        placement: &Placement,
        seed: u64,
    ) -> Result<Synthesis, MotionError> {
        validate_features(f)?;
        placement.validate()?;
        if agents.is_empty() {
            return Err(MotionError::Empty("agents"));
        }
        if let Some(i) = agents
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(MotionError::NotFinite {
                what: "agent",
                index: i,
                sample: 0,
            });
        }
        let m = agents.len();
        let d = f.basis.len();
        let mut sampler = GmmSampler::new(&f.gmm)?;
        let mut rng = SplitMix64::new(seed);
        self.scores.resize(d, 0.0);
        self.raw.resize(m, [Vec2::zeros(); S_H]);
        self.starts.clear();
        for t in self.raw.iter_mut() {
            sampler.sample_into(&mut rng, &mut self.scores);
            reconstruct(&f.mean, &f.basis, &self.scores, &mut self.buf); // eq. 16
            deserialise(&self.buf, t);
            for p in t.iter_mut() {
                *p = placement.apply(*p);
            }
            self.starts.push(t[0]);
        }
        let goal_of = self.assigner.solve(agents, &self.starts)?;
        Ok(Synthesis {
            trajectories: goal_of.iter().map(|&g| self.raw[g]).collect(),
            duration_s: f.duration_s,
        })
    }
}

/// The cost matrix of the assignment of `agents` to trajectory `starts` (section
/// 7.3; as many of each): squared distances, not between the positions themselves
/// but between the agents mapped by `a ↦ A(a − μa)` and the starts by
/// `s ↦ A⁻¹(s − μs)` ([`AffineMap::equalising`]: both clouds centred and given
/// the same covariance). Every assignment's total changes by the same constant, so
/// the optimum is the same permutation; a row's cheapest starts are then its near
/// ones, and the solver's candidate lists hold from the first pass (1,000 agents
/// on a grid against the two clouds of a split: 9 ms instead of 13–27 ms).
/// `mapped` is a workspace; `costs` is resized. (The one-level instance: the
/// [`Synthesiser`] solves it coarse to fine, [`CoarseToFine`], on the same
/// coordinates.)
pub fn start_costs(
    agents: &[Vec2],
    starts: &[Vec2],
    mapped: &mut Vec<Vec2>,
    costs: &mut CostMatrix,
) {
    let map = AffineMap::equalising(agents, starts);
    mapped.clear();
    mapped.extend(
        starts
            .iter()
            .map(|&p| map.as_ref().map_or(p, |m| m.goal(p))),
    );
    costs.resize(agents.len(), starts.len());
    for (i, &a) in agents.iter().enumerate() {
        let a = map.as_ref().map_or(a, |m| m.agent(a));
        for (c, s) in costs.row_mut(i).iter_mut().zip(mapped.iter()) {
            *c = (a - s).norm_squared();
        }
    }
}

/// Trajectories for `agents` (world metres) from a motion's features (section 7.3):
/// `agents.len()` eigenscore vectors sampled from the mixture (seeded by `seed`),
/// trajectories `c̄ + E_V s` (eq. 16) placed by `placement`, and agent `i` given the
/// trajectory whose start the optimal assignment (least total squared distance from
/// agents to starts) gives it.
///
/// # Complexity
/// `O(M · d · TRAJ_DIM)` for the trajectories and one exact assignment of `M`
/// agents to `M` starts.
///
/// # Errors
/// [`validate_features`]'s, [`MotionError::Empty`] without agents,
/// [`MotionError::NotFinite`] for a NaN agent or placement,
/// [`MotionError::BadValue`] for a scale that is not finite and positive,
/// [`MotionError::NotPositiveDefinite`] for a bad covariance,
/// [`MotionError::Assign`] if the assignment fails.
pub fn synthesise(
    f: &MotionFeatures,
    agents: &[Vec2],
    placement: &Placement,
    seed: u64,
) -> Result<Synthesis, MotionError> {
    Synthesiser::new().synthesise(f, agents, placement, seed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::assign::Solver;
    use crate::crowd::motion::features::tests::split_motion;
    use crate::crowd::motion::{features, FeatureParams};
    use crate::gesture::library::{GmmComponent, MotionClass};
    use crate::rng::SplitMix64;

    fn total_sq(agents: &[Vec2], s: &Synthesis) -> f64 {
        agents
            .iter()
            .zip(&s.trajectories)
            .map(|(a, t)| (a - t[0]).norm_squared())
            .sum()
    }

    fn permutations(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for p in permutations(n - 1) {
            for i in 0..=p.len() {
                let mut q = p.clone();
                q.insert(i, n - 1);
                out.push(q);
            }
        }
        out
    }

    #[test]
    fn a_large_crowd_gets_the_optimum_of_the_plain_squared_distances() {
        // 400 agents on a grid against the starts of a split: the total of the
        // equalised instance's optimum is the plain matrix's optimum.
        let f = features(
            MotionClass::Split.id(),
            &split_motion(60, 3.0, 4),
            &FeatureParams::default(),
        )
        .unwrap();
        let agents: Vec<Vec2> = (0..400)
            .map(|i| Vec2::new((i % 20) as f64 * 0.4, (i / 20) as f64 * 0.35))
            .collect();
        let s = synthesise(&f, &agents, &Placement::for_crowd(&agents), 3).unwrap();
        let starts: Vec<Vec2> = s.trajectories.iter().map(|t| t[0]).collect();
        let mut plain = CostMatrix::new(400, 400);
        for (i, a) in agents.iter().enumerate() {
            for (c, st) in plain.row_mut(i).iter_mut().zip(&starts) {
                *c = (a - st).norm_squared();
            }
        }
        let best: f64 = Solver::new()
            .solve(&plain)
            .unwrap()
            .iter()
            .enumerate()
            .map(|(i, &j)| (agents[i] - starts[j]).norm_squared())
            .sum();
        let got = total_sq(&agents, &s);
        assert!((got - best).abs() <= 1e-9 * best, "{got} vs {best}");
    }

    #[test]
    fn the_coarse_to_fine_assignment_is_the_dense_optimum_at_1000_agents() {
        // The synthesis's assignment (three levels at 1,000 agents) against a cold
        // solve of the plain 1,000 × 1,000 matrix, for three splits and samplings,
        // the motion moved off the crowd's centre.
        let mut syn = Synthesiser::new();
        let agents: Vec<Vec2> = (0..1000)
            .map(|i| Vec2::new((i % 40) as f64 * 0.5, (i / 40) as f64 * 0.45))
            .collect();
        for seed in [1u64, 2, 3] {
            let f = features(
                MotionClass::Split.id(),
                &split_motion(50, 3.0, seed),
                &FeatureParams::default(),
            )
            .unwrap();
            let placement = Placement {
                gesture_offset: Vec2::new(4.0, -2.0),
                ..Placement::for_crowd(&agents)
            };
            let s = syn.synthesise(&f, &agents, &placement, seed).unwrap();
            assert_eq!(syn.assign_stats().levels, 3);
            let starts: Vec<Vec2> = s.trajectories.iter().map(|t| t[0]).collect();
            let mut plain = CostMatrix::new(1000, 1000);
            for (i, a) in agents.iter().enumerate() {
                for (c, st) in plain.row_mut(i).iter_mut().zip(&starts) {
                    *c = (a - st).norm_squared();
                }
            }
            let mut dense = Solver::new();
            dense.solve(&plain).unwrap();
            let best = dense.total_cost(&plain);
            let got = total_sq(&agents, &s);
            assert!(
                (got - best).abs() <= 1e-9 * best,
                "seed {seed}: {got} vs {best}"
            );
        }
    }

    #[test]
    fn agents_get_the_starts_of_least_total_squared_distance() {
        let f = features(
            MotionClass::Split.id(),
            &split_motion(30, 2.0, 2),
            &FeatureParams::default(),
        )
        .unwrap();
        let agents: Vec<Vec2> = (0..7)
            .map(|i| Vec2::new((i * 37 % 11) as f64 * 0.3, (i * 5 % 7) as f64 * 0.4))
            .collect();
        let s = synthesise(&f, &agents, &Placement::for_crowd(&agents), 9).unwrap();
        assert_eq!(s.trajectories.len(), 7);
        let starts: Vec<Vec2> = s.trajectories.iter().map(|t| t[0]).collect();
        let best = permutations(7)
            .iter()
            .map(|p| {
                agents
                    .iter()
                    .enumerate()
                    .map(|(i, a)| (a - starts[p[i]]).norm_squared())
                    .sum::<f64>()
            })
            .fold(f64::INFINITY, f64::min);
        assert!((total_sq(&agents, &s) - best).abs() < 1e-9 * best.max(1.0));
        // Same seed, same answer; another seed, other samples.
        assert_eq!(
            synthesise(&f, &agents, &Placement::for_crowd(&agents), 9).unwrap(),
            s
        );
        assert_ne!(
            synthesise(&f, &agents, &Placement::for_crowd(&agents), 10).unwrap(),
            s
        );
    }

    #[test]
    fn the_equalised_costs_give_the_plain_optimum() {
        // A filled rectangle of agents against the two blobs of a split, far
        // apart and differently shaped: the optimum of the mapped costs has the
        // least total plain squared distance.
        let mut rng = SplitMix64::new(5);
        let agents: Vec<Vec2> = (0..300)
            .map(|i| Vec2::new((i % 20) as f64 * 0.8, (i / 20) as f64 * 0.8))
            .collect();
        let starts: Vec<Vec2> = (0..300)
            .map(|i| {
                let c = if i % 2 == 0 { 4.0 } else { 30.0 };
                Vec2::new(c + rng.uniform(-2.0, 2.0), 20.0 + rng.uniform(-6.0, 6.0))
            })
            .collect();
        let (mut mapped, mut costs) = (Vec::new(), CostMatrix::new(0, 0));
        start_costs(&agents, &starts, &mut mapped, &mut costs);
        assert!(
            mapped
                .iter()
                .zip(&starts)
                .any(|(m, s)| (m - s).norm() > 1.0),
            "the map moves the starts"
        );
        let mut plain = CostMatrix::new(300, 300);
        for (i, a) in agents.iter().enumerate() {
            for (c, s) in plain.row_mut(i).iter_mut().zip(&starts) {
                *c = (a - s).norm_squared();
            }
        }
        let total = |goal_of: &[usize]| -> f64 {
            goal_of
                .iter()
                .enumerate()
                .map(|(i, &j)| (agents[i] - starts[j]).norm_squared())
                .sum()
        };
        let mapped_total = total(Solver::new().solve(&costs).unwrap());
        let plain_total = total(Solver::new().solve(&plain).unwrap());
        assert!(
            (mapped_total - plain_total).abs() <= 1e-9 * plain_total,
            "{mapped_total} vs {plain_total}"
        );
    }

    #[test]
    fn placement_scales_rotates_and_moves_the_motion() {
        // One Gaussian of zero variance: every agent gets the mean trajectory, a
        // straight walk from the origin to (1, 0) in crowd units.
        let mut mean = vec![0.0; TRAJ_DIM];
        for s in 0..S_H {
            mean[2 * s] = s as f64 / (S_H - 1) as f64;
        }
        let f = MotionFeatures {
            class: MotionClass::Translate.id(),
            duration_s: 2.0,
            mean,
            basis: vec![],
            gmm: vec![GmmComponent {
                weight: 1.0,
                mean: vec![],
                cov: vec![],
            }],
        };
        let p = Placement {
            centre: Vec2::new(10.0, 5.0),
            scale_m: 3.0,
            rotation_rad: std::f64::consts::FRAC_PI_2,
            gesture_offset: Vec2::new(1.0, 0.0),
        };
        let s = synthesise(&f, &[Vec2::zeros(), Vec2::new(1.0, 1.0)], &p, 0).unwrap();
        for t in &s.trajectories {
            assert!((t[0] - Vec2::new(11.0, 5.0)).norm() < 1e-12);
            assert!(
                (t[S_H - 1] - Vec2::new(11.0, 8.0)).norm() < 1e-12,
                "{:?}",
                t[S_H - 1]
            );
        }
        assert_eq!(s.duration_s, 2.0);
        let c = Placement::for_crowd(&[Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0)]);
        assert_eq!((c.centre, c.scale_m), (Vec2::new(1.0, 0.0), 1.0));
        assert_eq!(
            Placement::for_crowd(&[Vec2::new(4.0, 4.0)]).scale_m,
            MIN_CROWD_SCALE_M
        );
    }

    #[test]
    fn any_crowd_size_is_served_and_keeps_the_motion() {
        let f = features(
            MotionClass::Split.id(),
            &split_motion(40, 2.0, 5),
            &FeatureParams::default(),
        )
        .unwrap();
        let mut syn = Synthesiser::new();
        for m in [1usize, 2, 13, 1000] {
            let side = (m as f64).sqrt().ceil() as usize;
            let agents: Vec<Vec2> = (0..m)
                .map(|i| Vec2::new((i % side) as f64 * 0.8, (i / side) as f64 * 0.8))
                .collect();
            let s = syn
                .synthesise(&f, &agents, &Placement::for_crowd(&agents), 1)
                .unwrap();
            assert_eq!(s.trajectories.len(), m);
            assert!(s
                .trajectories
                .iter()
                .flatten()
                .all(|p| p.x.is_finite() && p.y.is_finite()));
            if m == 1000 {
                // A split: the mean x-displacement is near 0, and about half the
                // crowd moves each way.
                let dx: Vec<f64> = s
                    .trajectories
                    .iter()
                    .map(|t| t[S_H - 1].x - t[0].x)
                    .collect();
                let left = dx.iter().filter(|&&x| x < 0.0).count();
                assert!((350..650).contains(&left), "{left} of 1000 go left");
            }
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let f = features(
            MotionClass::Split.id(),
            &split_motion(20, 2.0, 5),
            &FeatureParams::default(),
        )
        .unwrap();
        let p = Placement::default();
        assert_eq!(
            synthesise(&f, &[], &p, 0),
            Err(MotionError::Empty("agents"))
        );
        let nan = [Vec2::new(0.0, f64::NAN)];
        assert!(matches!(
            synthesise(&f, &nan, &p, 0),
            Err(MotionError::NotFinite { what: "agent", .. })
        ));
        let bad = Placement { scale_m: 0.0, ..p };
        assert!(matches!(
            synthesise(&f, &[Vec2::zeros()], &bad, 0),
            Err(MotionError::BadValue { .. })
        ));
        let mut g = f.clone();
        g.gmm[0].cov[0] = -1.0;
        assert!(matches!(
            synthesise(&g, &[Vec2::zeros()], &p, 0),
            Err(MotionError::NotPositiveDefinite { .. })
        ));
    }
}
