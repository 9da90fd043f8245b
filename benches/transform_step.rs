//! One step of a running formation transform (formation-transform sections 3.3,
//! 3.5): social forces with subgroup terms and mutual-information feedback, overlap
//! resolution, arrival and the section 5.1 measures, at 2,000 and 10,000 agents;
//! the same at 2,000 with each subgroup moved as a whole on its Delaunay graph
//! (`SubgroupAttraction::DelaunayGraph`); the ORCA, RVO and steering baselines at
//! 2,000. One core.
//!
//! `cargo bench --bench transform_step -- --warm-up-time 1 --measurement-time 3`
//!
//! Sources and targets are two jittered lattices (0.7 m and 0.6 m spacing, different
//! aspect), paired in reading order; subgroups are the sources' 4 m grid cells. The
//! timed step starts from the state 1 s into the transform (agents walking), a
//! fresh copy of it per iteration.

use criterion::{black_box, criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};
use crowdtouch::crowd::transform::{
    MoveParams, Mover, PairCost, SubgroupAttraction, Subgroups, TransformPlan, TransformRun,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;

const DT_S: f64 = 1.0 / 60.0;

fn jittered(rng: &mut SplitMix64, n: usize, cols: usize, spacing: f64, origin: Vec2) -> Vec<Vec2> {
    (0..n)
        .map(|i| {
            let j = Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)) * spacing;
            origin + Vec2::new((i % cols) as f64, (i / cols) as f64) * spacing + j
        })
        .collect()
}

/// A transform of `n` agents 1 s in: the run, positions, velocities.
fn walking(
    n: usize,
    mover: Mover,
    attraction: SubgroupAttraction,
) -> (TransformRun, Vec<Vec2>, Vec<Vec2>) {
    let mut rng = SplitMix64::new(0x5EED ^ n as u64);
    let side = (n as f64).sqrt().ceil() as usize;
    let sources = jittered(&mut rng, n, side, 0.7, Vec2::zeros());
    let targets = jittered(&mut rng, n, 2 * side, 0.6, Vec2::new(5.0, 5.0));
    let cells = (side as f64 * 0.7 / 4.0).ceil() as u32 + 1;
    let group_of: Vec<u32> = sources
        .iter()
        .map(|s| (s.x / 4.0).max(0.0) as u32 + cells * (s.y / 4.0).max(0.0) as u32)
        .collect();
    let groups = group_of.iter().max().map_or(1, |&g| g + 1);
    let plan = TransformPlan {
        sources_m: sources.clone(),
        targets_m: targets,
        subgroups: Subgroups {
            group_of,
            exemplars: (0..groups).collect(),
            iterations: 0,
            converged: true,
        },
        cost: PairCost::Euclidean,
    };
    let p = MoveParams {
        mover,
        subgroup_attraction: attraction,
        ..MoveParams::default()
    };
    let mut run = TransformRun::new(&plan, &p, 1);
    let (mut pos, mut vel) = (sources, vec![Vec2::zeros(); n]);
    for _ in 0..60 {
        let _ = run.step(&mut pos, &mut vel, DT_S, None);
    }
    (run, pos, vel)
}

fn transform_step(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("transform_step");
    g.sample_size(20);
    use SubgroupAttraction::{DelaunayGraph, Place};
    let cases: &[(&str, usize, Mover, SubgroupAttraction)] = if cfg!(debug_assertions) {
        &[
            ("social_force", 200, Mover::SocialForce, Place),
            ("social_force_dt", 200, Mover::SocialForce, DelaunayGraph),
            ("orca", 200, Mover::Orca, Place),
            ("rvo", 200, Mover::Rvo, Place),
            ("steering", 200, Mover::Steering, Place),
        ]
    } else {
        &[
            ("social_force", 2000, Mover::SocialForce, Place),
            ("social_force", 10_000, Mover::SocialForce, Place),
            ("social_force_dt", 2000, Mover::SocialForce, DelaunayGraph),
            ("orca", 2000, Mover::Orca, Place),
            ("rvo", 2000, Mover::Rvo, Place),
            ("steering", 2000, Mover::Steering, Place),
        ]
    };
    for &(name, n, mover, attraction) in cases {
        let state = walking(n, mover, attraction);
        g.bench_with_input(BenchmarkId::new(name, n), &state, |b, state| {
            b.iter_batched(
                || state.clone(),
                |(mut run, mut pos, mut vel)| {
                    black_box(run.step(&mut pos, &mut vel, DT_S, None));
                    (run, pos, vel)
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, transform_step);
criterion_main!(benches);
