//! The scenarios of formation-transform section 4 for `transform compare
//! --scenario`: every row of the comparison runs in the one chosen.
//!
//! | scenario | what | paper |
//! |---|---|---|
//! | `direct` | the target laid where the source is (what compare always did) | 5 |
//! | `path` | the target's anchor walks a path with a left turn, [`TRAVEL_M`] long, at [`ANCHOR_SPEED_SHARE`] of the desired speed; the targets ride on it and the transform completes on the way | 4, Figs. 6–7 |
//! | `obstacles` | the target laid [`TRAVEL_M`] (or more) ahead, a disc obstacle half way; the pairing ignores it | 4, Fig. 8 |
//! | `crossing` | two groups: the source and its mirror image across the table, each transforming into the target (mirrored) on the other side, through each other | 4, Fig. 9 |
//!
//! Design choices, stated: "ahead" is `+x` (the placement's heading); the travel
//! is at least [`TRAVEL_M`] and more when the formations are wide, so that the
//! source and the target (and in `crossing` the two groups, in `obstacles` the
//! obstacle) are [`CLEARANCE_M`] apart. `path` pairs agents with the targets where
//! the anchor starts (the source's place: the pairing is `direct`'s) and then
//! moves the targets, so the pairing is that of the formation's own frame.
//! `crossing` pairs group A like `obstacles` and gives group B the mirror image of
//! A's pairing (every cost here is symmetric under the mirror, so it is an optimal
//! pairing of B too); `--agents` agents in each group, subgroups of B numbered
//! after A's.

use super::shared::{run, run_seed, Recorded, DT_S, MAX_STEP_US};
use anyhow::{anyhow, Result};
use clap::ValueEnum;
use crowdtouch::crowd::environment::{ObstacleDef, PartDef, Scene, SceneFile, SCENE_VERSION};
use crowdtouch::crowd::formation::Placement;
use crowdtouch::crowd::transform::{
    interval, Interval, MoveParams, TransformPlan, TransformRun, OVERLAP_TOLERANCE_M,
};
use crowdtouch::geom::{Rect, Vec2};
use hdrhistogram::Histogram;
use serde_json::{json, Value};
use std::time::Instant;

/// `--scenario`.
#[derive(ValueEnum, Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum Scenario {
    /// The target laid where the source is (section 5's comparisons).
    #[default]
    Direct,
    /// The target formation's anchor walks a path with a turn; the targets ride
    /// on it (section 4, Figs. 6–7).
    Path,
    /// A disc obstacle between the source and the target (Fig. 8).
    Obstacles,
    /// Two groups passing through each other to the opposite sides (Fig. 9).
    Crossing,
}

impl Scenario {
    /// Its name on the command line and in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Direct => "direct",
            Scenario::Path => "path",
            Scenario::Obstacles => "obstacles",
            Scenario::Crossing => "crossing",
        }
    }
}

/// How far the target formation is carried or laid ahead, at least (m): the
/// path's length, the distance to the target past the obstacle, the distance
/// each crossing group walks.
pub const TRAVEL_M: f64 = 20.0;
/// Share of the path walked straight ahead (`+x`) before its left turn of 90°
/// (12 m ahead, then 8 m).
pub const PATH_FIRST_LEG_SHARE: f64 = 0.6;
/// The path's anchor walks at this share of the agents' desired speed, so that
/// the agents can catch up while transforming.
pub const ANCHOR_SPEED_SHARE: f64 = 0.8;
/// Least gap between two formations, and between a formation and the obstacle
/// (m).
pub const CLEARANCE_M: f64 = 2.0;
/// The obstacle's radius, as a share of the wider of the two formations across
/// the way (`y` extent); at least [`MIN_OBSTACLE_RADIUS_M`].
pub const OBSTACLE_RADIUS_SHARE: f64 = 0.25;
/// Smallest obstacle radius (m).
pub const MIN_OBSTACLE_RADIUS_M: f64 = 0.5;
/// The scene's bounds reach this far beyond everything in it (m).
const SCENE_MARGIN_M: f64 = 10.0;

/// One seed's scenario, laid out around its source and targets.
#[derive(Clone, Debug)]
pub struct Stage {
    /// Which.
    pub scenario: Scenario,
    /// Where the target is laid, from where it was sampled (m).
    pub target_offset_m: Vec2,
    /// `path`: the anchor's waypoints, as offsets from its start (m).
    pub path_m: Vec<Vec2>,
    /// `path`: the anchor's speed (m/s).
    pub anchor_speed_m_s: f64,
    /// `obstacles`: the discs, centre and radius (m).
    pub discs: Vec<(Vec2, f64)>,
    /// `obstacles`: the scene the runs step in.
    pub scene: Option<Scene>,
    /// `crossing`: the mirror line `x = mirror_x_m` (group A's targets lie beyond
    /// it, group B's before it).
    pub mirror_x_m: Option<f64>,
}

/// `(min, max)` of `f` over `pts`.
fn range(pts: &[Vec2], f: impl Fn(&Vec2) -> f64) -> (f64, f64) {
    pts.iter()
        .map(f)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        })
}

impl Stage {
    /// The scenario around `sources` and `targets` (as sampled, both at `place`),
    /// for agents of `moves`.
    ///
    /// # Errors
    /// A scene the scene validation refuses (not expected: named in the message).
    pub fn new(
        scenario: Scenario,
        place: &Placement,
        sources: &[Vec2],
        targets: &[Vec2],
        moves: &MoveParams,
    ) -> Result<Stage> {
        let c = place.centre_m;
        let mut stage = Stage {
            scenario,
            target_offset_m: Vec2::zeros(),
            path_m: Vec::new(),
            anchor_speed_m_s: 0.0,
            discs: Vec::new(),
            scene: None,
            mirror_x_m: None,
        };
        // The wider of the two formations' half extents along the way, about the
        // placement's centre, and their extents across it.
        let (sx, tx) = (range(sources, |p| p.x), range(targets, |p| p.x));
        let half_x = [sx.0, sx.1, tx.0, tx.1]
            .iter()
            .map(|x| (x - c.x).abs())
            .fold(0.0, f64::max);
        let (sy, ty) = (range(sources, |p| p.y), range(targets, |p| p.y));
        let across_m = (sy.1 - sy.0).max(ty.1 - ty.0);
        match scenario {
            Scenario::Direct => {}
            Scenario::Path => {
                let first = TRAVEL_M * PATH_FIRST_LEG_SHARE;
                stage.path_m = vec![
                    Vec2::zeros(),
                    Vec2::new(first, 0.0),
                    Vec2::new(first, TRAVEL_M - first),
                ];
                stage.anchor_speed_m_s = ANCHOR_SPEED_SHARE * moves.desired_speed_m_s;
            }
            Scenario::Obstacles => {
                let r_m = (OBSTACLE_RADIUS_SHARE * across_m).max(MIN_OBSTACLE_RADIUS_M);
                let d = TRAVEL_M.max(2.0 * half_x + 2.0 * r_m + 2.0 * CLEARANCE_M);
                stage.target_offset_m = Vec2::new(d, 0.0);
                // Half way between the source's front and the target's back.
                let mid_x = 0.5 * (sx.1 + tx.0 + d);
                let centre = Vec2::new(mid_x, c.y);
                stage.discs.push((centre, r_m));
                stage.scene = Some(scene_of(&stage.discs, sources, targets, d, moves)?);
            }
            Scenario::Crossing => {
                let d = TRAVEL_M.max(2.0 * half_x + CLEARANCE_M);
                stage.target_offset_m = Vec2::new(d, 0.0);
                stage.mirror_x_m = Some(c.x + 0.5 * d);
            }
        }
        Ok(stage)
    }

    /// The sampled targets laid where this scenario puts them.
    pub fn targets(&self, sampled: &[Vec2]) -> Vec<Vec2> {
        sampled.iter().map(|t| t + self.target_offset_m).collect()
    }

    /// The plan of the run from the plan of the source's agents: in `crossing`
    /// with group B (the mirror image of everything) appended.
    pub fn complete(&self, plan: TransformPlan) -> TransformPlan {
        let Some(xm) = self.mirror_x_m else {
            return plan;
        };
        let mirror = |p: &Vec2| Vec2::new(2.0 * xm - p.x, p.y);
        let n = plan.sources_m.len() as u32;
        let groups = plan.subgroups.count() as u32;
        let mut out = plan.clone();
        out.sources_m.extend(plan.sources_m.iter().map(mirror));
        out.targets_m.extend(plan.targets_m.iter().map(mirror));
        let sg = &mut out.subgroups;
        sg.group_of
            .extend(plan.subgroups.group_of.iter().map(|g| g + groups));
        sg.exemplars
            .extend(plan.subgroups.exemplars.iter().map(|e| e + n));
        out
    }

    /// The anchor's offset from its start after `t_s` seconds (`path`; zero
    /// otherwise).
    pub fn anchor_at(&self, t_s: f64) -> Vec2 {
        let mut left_m = (self.anchor_speed_m_s * t_s).max(0.0);
        for w in self.path_m.windows(2) {
            let leg = w[1] - w[0];
            let len = leg.norm();
            if left_m <= len {
                return w[0] + leg * (left_m / len.max(1e-12));
            }
            left_m -= len;
        }
        self.path_m.last().copied().unwrap_or_else(Vec2::zeros)
    }

    /// Whether the anchor is still walking at `t_s`.
    fn anchor_walking(&self, t_s: f64) -> bool {
        let len: f64 = self.path_m.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        self.anchor_speed_m_s * t_s < len
    }

    /// One run of `plan` in this scenario: what [`run`] records, with the
    /// scenario's own facts. `direct` is exactly [`run`].
    pub fn run(&self, plan: &TransformPlan, params: &MoveParams, seed: u64) -> (Recorded, Facts) {
        if self.scenario == Scenario::Direct {
            return (run(plan, params, seed, false), Facts::default());
        }
        let n = plan.sources_m.len();
        let mut pos = plan.sources_m.clone();
        let mut vel = vec![Vec2::zeros(); n];
        let mut r = TransformRun::new(plan, params, run_seed(seed));
        let mut step_us = match Histogram::new_with_bounds(1, MAX_STEP_US, 3) {
            Ok(h) => h,
            Err(e) => unreachable!("constant histogram bounds: {e}"),
        };
        let mut series = Vec::new();
        let mut entered = vec![false; n];
        // An agent's disc overlaps an obstacle by more than the contacts leave.
        let inside = |s: &Scene, p: Vec2, t: f64| {
            s.signed_distance(p, t) < params.radius_m - OVERLAP_TOLERANCE_M
        };
        // The path's run lasts at least until its anchor stops.
        let max_steps = (params.timeout_s / DT_S).ceil() as u64 + 2;
        let mut steps = 0u64;
        loop {
            let t = r.elapsed_s();
            let walking = self.anchor_walking(t);
            if steps >= max_steps || t >= params.timeout_s || (!walking && r.done()) {
                break;
            }
            if walking {
                r.shift_targets(self.anchor_at(t + DT_S) - self.anchor_at(t));
            }
            let t0 = Instant::now();
            let report = r.step(
                &mut pos,
                &mut vel,
                DT_S,
                self.scene.as_ref().map(|s| (s, t)),
            );
            step_us.saturating_record(t0.elapsed().as_micros().max(1) as u64);
            steps += 1;
            series.push((r.elapsed_s(), report.measures, report.arrived_fraction));
            if let Some(s) = &self.scene {
                for (e, &p) in entered.iter_mut().zip(&pos) {
                    *e |= inside(s, p, r.elapsed_s());
                }
            }
        }
        let t_end = r.elapsed_s();
        let targets = r.targets();
        let arrived: Vec<bool> = (0..n)
            .map(|i| {
                (pos[i] - targets[i]).norm() <= params.arrive_m
                    && (!params.settling || r.settled(i))
            })
            .collect();
        let short = (0..n)
            .filter(|&i| !arrived[i])
            .map(|i| (i, (pos[i] - targets[i]).norm(), vel[i].norm()))
            .collect();
        let mut facts = Facts::default();
        if let Some(s) = &self.scene {
            facts.entered_obstacle = Some(entered.iter().filter(|&&e| e).count());
            facts.inside_obstacle_at_end =
                Some(pos.iter().filter(|&&p| inside(s, p, t_end)).count());
        }
        if let Some(xm) = self.mirror_x_m {
            let half = n / 2;
            for (g, agents) in [(0usize, 0..half), (1, half..n)] {
                let k = agents.len().max(1) as f64;
                let home = |x: f64| if g == 0 { x > xm } else { x < xm };
                let got = agents.clone().filter(|&i| arrived[i]).count();
                let changed = agents.filter(|&i| !home(targets[i].x)).count();
                facts.groups.push(GroupEnd {
                    arrived_fraction: got as f64 / k,
                    changed_group: changed,
                });
            }
        }
        let rec = Recorded {
            summary: r.summary(),
            step_us,
            series,
            paths: None,
            short,
        };
        (rec, facts)
    }

    /// The scenario's layout, for the JSON.
    pub fn json(&self) -> Value {
        let xy = |p: &Vec2| json!([p.x, p.y]);
        json!({
            "name": self.scenario.name(),
            "target_offset_m": xy(&self.target_offset_m),
            "path_m": self.path_m.iter().map(xy).collect::<Vec<_>>(),
            "anchor_speed_m_s": self.anchor_speed_m_s,
            "obstacles": self.discs.iter().map(|(c, r)| json!({"centre_m": xy(c), "radius_m": r})).collect::<Vec<_>>(),
            "mirror_x_m": self.mirror_x_m,
        })
    }

    /// One line saying how the scenario is laid out.
    pub fn text(&self) -> String {
        match self.scenario {
            Scenario::Direct => "scenario direct: the target where the source is".into(),
            Scenario::Path => format!(
                "scenario path: the target's anchor walks {:.1} m ahead, turns left and walks {:.1} m, at {:.2} m/s; the targets ride on it",
                (self.path_m[1] - self.path_m[0]).norm(),
                (self.path_m[2] - self.path_m[1]).norm(),
                self.anchor_speed_m_s
            ),
            Scenario::Obstacles => format!(
                "scenario obstacles: the target {:.1} m ahead, {} (pairing ignores them)",
                self.target_offset_m.x,
                self.discs
                    .iter()
                    .map(|(c, r)| format!("a disc of radius {r:.2} m at ({:.1}, {:.1})", c.x, c.y))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            Scenario::Crossing => format!(
                "scenario crossing: two groups (the source and its mirror image across x = {:.1} m), each walking {:.1} m into the target on the other side",
                self.mirror_x_m.unwrap_or(f64::NAN),
                self.target_offset_m.x
            ),
        }
    }
}

/// The scene of the discs, bounded around everything with a margin.
fn scene_of(
    discs: &[(Vec2, f64)],
    sources: &[Vec2],
    targets: &[Vec2],
    d_m: f64,
    moves: &MoveParams,
) -> Result<Scene> {
    let (sx, sy) = (range(sources, |p| p.x), range(sources, |p| p.y));
    let (tx, ty) = (range(targets, |p| p.x), range(targets, |p| p.y));
    let m = SCENE_MARGIN_M;
    let file = SceneFile {
        version: SCENE_VERSION,
        name: "transform obstacles".into(),
        bounds_m: Rect {
            min: [sx.0.min(tx.0) - m, sy.0.min(ty.0) - m],
            max: [sx.1.max(tx.1 + d_m) + m, sy.1.max(ty.1) + m],
        },
        obstacles: discs
            .iter()
            .enumerate()
            .map(|(k, (c, r))| ObstacleDef {
                name: format!("disc {k}"),
                parts: vec![PartDef::Circle {
                    centre_m: [c.x, c.y],
                    radius_m: *r,
                }],
            })
            .collect(),
        patches: Vec::new(),
        dynamic: Vec::new(),
        checkpoints: Vec::new(),
    };
    Scene::from_file(&file, moves.radius_m).map_err(|problems| {
        anyhow!(
            "the obstacles scenario's scene is not valid: {}",
            problems
                .iter()
                .map(|(f, p)| format!("{f}: {p}"))
                .collect::<Vec<_>>()
                .join("; ")
        )
    })
}

/// The crossing groups' names: the source's, then its mirror image's.
const GROUP_NAMES: [&str; 2] = ["a", "b"];

/// One group's end in `crossing`.
#[derive(Copy, Clone, Debug, Default)]
pub struct GroupEnd {
    /// Its agents at their targets (settled, with settling).
    pub arrived_fraction: f64,
    /// Its agents that ended with a target of the other group (an exchange of
    /// targets across the groups, step 6 of `run.rs`).
    pub changed_group: usize,
}

/// What one run showed of its scenario.
#[derive(Clone, Debug, Default)]
pub struct Facts {
    /// `obstacles`: agents whose disc overlapped an obstacle (by more than the
    /// contact tolerance) at the end of some step.
    pub entered_obstacle: Option<usize>,
    /// `obstacles`: such agents at the end.
    pub inside_obstacle_at_end: Option<usize>,
    /// `crossing`: group A, then group B.
    pub groups: Vec<GroupEnd>,
}

/// One row's scenario facts over its seeds, as JSON (`null` for `direct` and
/// `path`).
pub fn facts_json(runs: &[&Facts]) -> Value {
    let iv = |xs: Vec<f64>| {
        let i: Interval = interval(&xs);
        json!({"mean": i.mean, "ci95": i.ci95, "n": i.n})
    };
    let mut out = serde_json::Map::new();
    if runs.iter().all(|f| f.entered_obstacle.is_some()) && !runs.is_empty() {
        let get = |f: &dyn Fn(&Facts) -> Option<usize>| {
            runs.iter()
                .filter_map(|r| f(r))
                .map(|k| k as f64)
                .collect::<Vec<_>>()
        };
        out.insert(
            "agents_entered_obstacle".into(),
            iv(get(&|f| f.entered_obstacle)),
        );
        out.insert(
            "agents_inside_obstacle_at_end".into(),
            iv(get(&|f| f.inside_obstacle_at_end)),
        );
    }
    let n_groups = runs.iter().map(|f| f.groups.len()).min().unwrap_or(0);
    if n_groups > 0 {
        let groups: Vec<Value> = (0..n_groups)
            .map(|g| {
                let fr: Vec<f64> = runs.iter().map(|f| f.groups[g].arrived_fraction).collect();
                let name = GROUP_NAMES.get(g).copied().unwrap_or("?");
                json!({
                    "group": name,
                    "arrived_fraction": iv(fr.clone()),
                    "arrived_runs": fr.iter().filter(|&&x| x >= 1.0).count(),
                    "changed_group": iv(runs.iter().map(|f| f.groups[g].changed_group as f64).collect()),
                })
            })
            .collect();
        let both = runs
            .iter()
            .filter(|f| f.groups.iter().all(|g| g.arrived_fraction >= 1.0))
            .count();
        out.insert("groups".into(), Value::Array(groups));
        out.insert("both_arrived_runs".into(), json!(both));
        out.insert("both_arrived".into(), json!(both == runs.len()));
    }
    if out.is_empty() {
        Value::Null
    } else {
        Value::Object(out)
    }
}

/// One row's scenario facts over its seeds, as a short text (empty for
/// `direct` and `path`).
pub fn facts_text(runs: &[&Facts]) -> String {
    let mean = |xs: Vec<f64>| interval(&xs).mean;
    let mut parts = Vec::new();
    if runs.iter().all(|f| f.entered_obstacle.is_some()) && !runs.is_empty() {
        parts.push(format!(
            "agents into the obstacle {:.1} (at the end {:.1})",
            mean(
                runs.iter()
                    .filter_map(|f| f.entered_obstacle)
                    .map(|k| k as f64)
                    .collect()
            ),
            mean(
                runs.iter()
                    .filter_map(|f| f.inside_obstacle_at_end)
                    .map(|k| k as f64)
                    .collect()
            ),
        ));
    }
    let n_groups = runs.iter().map(|f| f.groups.len()).min().unwrap_or(0);
    for g in 0..n_groups {
        parts.push(format!(
            "group {}: {:.1} % arrived, all in {}/{} runs, {:.1} agents changed group",
            GROUP_NAMES.get(g).copied().unwrap_or("?"),
            100.0 * mean(runs.iter().map(|f| f.groups[g].arrived_fraction).collect()),
            runs.iter()
                .filter(|f| f.groups[g].arrived_fraction >= 1.0)
                .count(),
            runs.len(),
            mean(
                runs.iter()
                    .map(|f| f.groups[g].changed_group as f64)
                    .collect()
            ),
        ));
    }
    parts.join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moves() -> MoveParams {
        MoveParams {
            radius_m: 0.15,
            desired_speed_m_s: 1.25,
            ..MoveParams::default()
        }
    }

    fn square(c: Vec2, half_m: f64) -> Vec<Vec2> {
        (0..25)
            .map(|k| {
                c + Vec2::new((k % 5) as f64, (k / 5) as f64) * (half_m / 2.0)
                    - Vec2::new(half_m, half_m)
            })
            .collect()
    }

    #[test]
    fn the_path_anchor_walks_its_legs_at_its_speed() {
        let place = Placement {
            centre_m: Vec2::new(8.0, 4.5),
            heading: Vec2::new(1.0, 0.0),
            area_m2: 16.0,
        };
        let pts = square(place.centre_m, 2.0);
        let s = Stage::new(Scenario::Path, &place, &pts, &pts, &moves()).unwrap();
        assert_eq!(s.anchor_speed_m_s, ANCHOR_SPEED_SHARE * 1.25);
        let v = s.anchor_speed_m_s;
        assert!((s.anchor_at(6.0 / v) - Vec2::new(6.0, 0.0)).norm() < 1e-9);
        assert!((s.anchor_at(15.0 / v) - Vec2::new(12.0, 3.0)).norm() < 1e-9);
        assert_eq!(s.anchor_at(100.0), Vec2::new(12.0, 8.0));
        assert!(s.anchor_walking(19.0 / v) && !s.anchor_walking(20.0 / v));
    }

    #[test]
    fn obstacles_lie_between_and_crossing_mirrors_the_plan() {
        let place = Placement {
            centre_m: Vec2::new(8.0, 4.5),
            heading: Vec2::new(1.0, 0.0),
            area_m2: 16.0,
        };
        let pts = square(place.centre_m, 2.0);
        let s = Stage::new(Scenario::Obstacles, &place, &pts, &pts, &moves()).unwrap();
        let (c, r) = s.discs[0];
        assert_eq!(s.target_offset_m, Vec2::new(TRAVEL_M, 0.0));
        assert!((c - Vec2::new(8.0 + TRAVEL_M / 2.0, 4.5)).norm() < 1e-9);
        assert_eq!(r, OBSTACLE_RADIUS_SHARE * 4.0);
        let scene = s.scene.as_ref().unwrap();
        assert!(scene.signed_distance(c, 0.0) < 0.0);
        assert!(scene.signed_distance(place.centre_m, 0.0) > 5.0);

        let x = Stage::new(Scenario::Crossing, &place, &pts, &pts, &moves()).unwrap();
        let plan = TransformPlan {
            sources_m: pts.clone(),
            targets_m: x.targets(&pts),
            subgroups: crowdtouch::crowd::transform::Subgroups::single(pts.len()),
            cost: crowdtouch::crowd::transform::PairCost::Euclidean,
        };
        let both = x.complete(plan);
        assert_eq!(both.sources_m.len(), 50);
        // Group B starts where group A goes, and goes where A starts.
        assert!((both.sources_m[25 + 12] - both.targets_m[12]).norm() < 1e-9);
        assert!((both.targets_m[25 + 12] - both.sources_m[12]).norm() < 1e-9);
        assert_eq!(both.subgroups.count(), 2);
        assert_eq!(both.subgroups.group_of[30], 1);
    }
}
