//! `crowdtouch bench assign`: exact assignment solves of the standard layouts, cold or
//! warm, from a cost matrix or from the positions (what the controllers run).

use super::rows::{row_from_samples, Row};
use anyhow::{Context, Result};
use crowdtouch::crowd::assign::{
    Assigner, CostMatrix, CostProvider, Layout, PointMetric, Solver, SquaredDistance,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;
use std::time::Instant;

/// Seed of instance `k` of size `n` in `layout` (`k = 0` of the uniform layout is the
/// instance of `benches/assign.rs`; `benches/scipy_lsa.py` derives the same points).
fn seed(layout: Layout, n: usize, k: usize) -> u64 {
    let index = Layout::ALL.iter().position(|&l| l == layout).unwrap_or(0) as u64;
    ((0xC0FFEE ^ n as u64).wrapping_add(k as u64)) ^ (index << 32)
}

/// Seed of the goal moves of the warm chain.
const MOVE_SEED: u64 = 0xBEEF;
/// Largest goal move per frame of the warm chain, per axis, as a fraction of the
/// goals' extent along that axis: moves are uniform in `[-0.02, 0.02)` times it.
const MOVE_FRACTION: f64 = 0.02;

/// What `bench assign` is asked to do.
pub struct AssignRun<'a> {
    pub layout: Layout,
    pub n: usize,
    pub warm: bool,
    pub points: bool,
    pub repeats: usize,
    pub dump: Option<&'a std::path::Path>,
}

/// The layouts named by `--layout`: comma-separated names, or `all`.
pub fn parse_layouts(arg: &str) -> Result<Vec<Layout>> {
    if arg == "all" {
        return Ok(Layout::ALL.to_vec());
    }
    arg.split(',')
        .map(|name| {
            Layout::from_name(name.trim()).with_context(|| {
                let names: Vec<&str> = Layout::ALL.iter().map(|l| l.name()).collect();
                format!(
                    "--layout: unknown layout `{name}` (expected `all` or a comma-separated list of {})",
                    names.join(", ")
                )
            })
        })
        .collect()
}

/// One solver of either kind, so both paths run the same chain of instances.
enum Path {
    Matrix(Box<Solver>),
    Points(Box<Assigner>),
}

/// The assignment workload: `repeats` timed solves; every result is checked against
/// its dual certificate outside the timing.
pub fn assign(run: &AssignRun) -> Result<Row> {
    let AssignRun {
        layout,
        n,
        warm,
        points,
        repeats,
        dump,
    } = *run;
    anyhow::ensure!(n >= 1, "--n must be at least 1");
    let name = format!(
        "assign_{}{} {} n={n}",
        if warm { "warm" } else { "cold" },
        if points { "_points" } else { "" },
        layout.name(),
    );
    let mut samples = Vec::with_capacity(repeats);
    let mut c = CostMatrix::new(n, n);
    let mut path = if points {
        Path::Points(Box::new(Assigner::new(PointMetric::Squared)))
    } else {
        Path::Matrix(Box::new(Solver::new()))
    };
    let mut goal_of: Vec<u32> = Vec::with_capacity(n);
    let mut certified = 0usize;
    let mut frames: Vec<(Vec<Vec2>, Vec<Vec2>, Vec<u32>)> = Vec::new();
    // One solve; the first of a warm chain is not timed.
    let mut solve = |path: &mut Path,
                     c: &mut CostMatrix,
                     agents: &[Vec2],
                     goals: &[Vec2],
                     warm: bool,
                     timed: bool|
     -> Result<()> {
        let fail = |e| anyhow::anyhow!("assignment failed: {e}");
        let dt = match path {
            Path::Matrix(solver) => {
                SquaredDistance.fill(agents, goals, c);
                let t0 = Instant::now();
                let a = if warm {
                    solver.solve_warm(c)
                } else {
                    solver.solve(c)
                }
                .map_err(fail)?;
                let dt = t0.elapsed();
                goal_of.clear();
                goal_of.extend(a.iter().map(|&j| j as u32));
                if timed && solver.verify_optimal(&*c, 1e-9) {
                    certified += 1;
                }
                dt
            }
            Path::Points(assigner) => {
                if !warm {
                    assigner.forget();
                }
                let t0 = Instant::now();
                assigner.solve(agents, goals, &mut goal_of).map_err(fail)?;
                let dt = t0.elapsed();
                if timed && assigner.verify_optimal(1e-9) {
                    certified += 1;
                }
                dt
            }
        };
        if timed {
            samples.push(dt.as_secs_f64() * 1e6);
        }
        if dump.is_some() {
            frames.push((agents.to_vec(), goals.to_vec(), goal_of.clone()));
        }
        Ok(())
    };
    if warm {
        let mut rng = SplitMix64::new(seed(layout, n, 0));
        let (agents, mut goals) = layout.instance(&mut rng, n);
        solve(&mut path, &mut c, &agents, &goals, false, false)?;
        let step = 2.0 * MOVE_FRACTION * layout.goal_extent();
        let mut moves = SplitMix64::new(MOVE_SEED);
        for _ in 0..repeats {
            for p in &mut goals {
                p.x += step.x * (moves.unit() - 0.5);
                p.y += step.y * (moves.unit() - 0.5);
            }
            solve(&mut path, &mut c, &agents, &goals, true, true)?;
        }
    } else {
        for k in 0..repeats {
            let mut rng = SplitMix64::new(seed(layout, n, k));
            let (agents, goals) = layout.instance(&mut rng, n);
            solve(&mut path, &mut c, &agents, &goals, false, true)?;
        }
    }
    if let Some(path) = dump {
        let xy = |v: &[Vec2]| v.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>();
        let json = serde_json::json!({
            "n": n,
            "warm": warm,
            "layout": layout.name(),
            "cost": "squared_euclidean",
            "frames": frames.iter().map(|(a, g, x)| serde_json::json!({
                "agents": xy(a), "goals": xy(g), "goal_of": x,
            })).collect::<Vec<_>>(),
        });
        std::fs::write(path, serde_json::to_vec(&json)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let timed = samples.len();
    Ok(row_from_samples(
        &name,
        samples,
        format!(
            "{} layout, squared-Euclidean cost, one thread; dual certificate held on {certified}/{timed}{}",
            layout.name(),
            if warm {
                "; every goal moves by up to 2 % of the goals' width and height per frame"
            } else {
                "; a fresh instance per solve"
            }
        ),
    ))
}
