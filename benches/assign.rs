//! Exact assignment benchmarks: uniform random points in the unit square,
//! squared-Euclidean cost, square N×N, one core.
//!
//! `cargo bench --bench assign -- --warm-up-time 1 --measurement-time 3`
//!
//! `assign_warm/1000` solves a clone of the solver after each cold solve (the clone's
//! workspaces start without spare capacity); `assign_warm/alternating/1000` is the
//! steady state: one solver warm-solving the two instances in turn.
//!
//! `assign_cold_points/*` and `assign_warm_points/alternating/1000` solve the same
//! instances from the positions (`PointCosts`: costs computed on demand, candidate
//! lists from the spatial index, no matrix); the answers are identical.
//!
//! `assign_layout_cold/<layout>/1000` and `assign_layout_warm/<layout>/1000` run the
//! controllers' `Assigner` on the hard layouts of `crowd::assign::Layout` (a crowd
//! pinched, stretched, in a corner, dragged off its formation).

use criterion::{black_box, criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};
use crowdtouch::crowd::assign::{
    Assigner, CostMatrix, CostProvider, Layout, PointCosts, PointMetric, Solver, SquaredDistance,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;
use pathfinding::kuhn_munkres::kuhn_munkres;
use pathfinding::matrix::Matrix;

fn points(rng: &mut SplitMix64, n: usize) -> Vec<Vec2> {
    (0..n).map(|_| Vec2::new(rng.unit(), rng.unit())).collect()
}

/// Agents, goals and their cost matrix for size `n`.
fn instance(n: usize) -> (Vec<Vec2>, Vec<Vec2>, CostMatrix) {
    let mut rng = SplitMix64::new(0xC0FFEE ^ n as u64);
    let agents = points(&mut rng, n);
    let goals = points(&mut rng, n);
    let mut c = CostMatrix::new(n, n);
    SquaredDistance.fill(&agents, &goals, &mut c);
    (agents, goals, c)
}

fn assign_cold(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("assign_cold");
    g.sample_size(10);
    for n in [1000usize, 2000, 5000] {
        let (_, _, c) = instance(n);
        let mut solver = Solver::new();
        solver.solve(&c).expect("feasible");
        g.bench_with_input(BenchmarkId::from_parameter(n), &c, |b, c| {
            b.iter(|| {
                let a = solver.solve(black_box(c)).expect("feasible");
                black_box(a.len())
            })
        });
    }
    g.finish();
}

fn assign_cold_points(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("assign_cold_points");
    g.sample_size(10);
    for n in [1000usize, 2000, 5000] {
        let (agents, goals, _) = instance(n);
        let mut pc = PointCosts::new(PointMetric::Squared);
        pc.set(&agents, &goals);
        let mut solver = Solver::new();
        solver.solve_with(&pc).expect("feasible");
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let a = solver.solve_with(black_box(&pc)).expect("feasible");
                black_box(a.len())
            })
        });
    }
    g.finish();
}

fn assign_warm_points(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("assign_warm_points");
    g.sample_size(20);
    let n = 1000;
    let (agents, mut goals, _) = instance(n);
    let mut p0 = PointCosts::new(PointMetric::Squared);
    p0.set(&agents, &goals);
    let mut rng = SplitMix64::new(0xBEEF);
    for p in &mut goals {
        p.x += 0.04 * (rng.unit() - 0.5);
        p.y += 0.04 * (rng.unit() - 0.5);
    }
    let mut p1 = PointCosts::new(PointMetric::Squared);
    p1.set(&agents, &goals);
    let mut s = Solver::new();
    s.solve_with(&p0).expect("feasible");
    s.solve_warm_with(&p1).expect("feasible");
    s.solve_warm_with(&p0).expect("feasible");
    let mut flip = false;
    g.bench_function(BenchmarkId::new("alternating", n), |b| {
        b.iter(|| {
            flip = !flip;
            let pc = if flip { &p1 } else { &p0 };
            let a = s.solve_warm_with(black_box(pc)).expect("feasible");
            black_box(a.len())
        })
    });
    g.finish();
}

fn assign_warm(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("assign_warm");
    g.sample_size(20);
    let n = 1000;
    let (agents, mut goals, c0) = instance(n);
    // Every goal moves by up to 2 % of the extent (unit square) in x and y.
    let mut rng = SplitMix64::new(0xBEEF);
    for p in &mut goals {
        p.x += 0.04 * (rng.unit() - 0.5);
        p.y += 0.04 * (rng.unit() - 0.5);
    }
    let mut c1 = CostMatrix::new(n, n);
    SquaredDistance.fill(&agents, &goals, &mut c1);
    let mut base = Solver::new();
    base.solve(&c0).expect("feasible");
    g.bench_with_input(BenchmarkId::from_parameter(n), &c1, |b, c1| {
        b.iter_batched_ref(
            || base.clone(),
            |s| {
                let a = s.solve_warm(black_box(c1)).expect("feasible");
                black_box(a.len())
            },
            BatchSize::LargeInput,
        )
    });
    // Steady state: one solver warm-solving the two instances in turn (every goal
    // moves by up to 2 % of the extent between consecutive solves), no clone, so the
    // workspaces are reused as in the daemon's assignment worker.
    let mut s = base.clone();
    s.solve_warm(&c1).expect("feasible");
    s.solve_warm(&c0).expect("feasible");
    let mut flip = false;
    g.bench_function(BenchmarkId::new("alternating", n), |b| {
        b.iter(|| {
            flip = !flip;
            let c = if flip { &c1 } else { &c0 };
            let a = s.solve_warm(black_box(c)).expect("feasible");
            black_box(a.len())
        })
    });
    g.finish();
}

/// What the controllers run (`Assigner`: the positions mapped to alike spreads, then
/// the geometric fast path) on every layout at N = 1,000: cold solves of one
/// instance, and warm solves alternating between it and a copy whose goals moved by
/// up to 2 % of their width and height.
fn assign_layouts(cr: &mut Criterion) {
    let n = 1000;
    let mut cold = cr.benchmark_group("assign_layout_cold");
    cold.sample_size(10);
    for layout in Layout::ALL {
        let (agents, goals) = layout.instance(&mut SplitMix64::new(0xC0FFEE ^ n as u64), n);
        let mut a = Assigner::new(PointMetric::Squared);
        let mut goal_of = Vec::with_capacity(n);
        cold.bench_function(BenchmarkId::new(layout.name(), n), |b| {
            b.iter(|| {
                a.forget();
                a.solve(black_box(&agents), black_box(&goals), &mut goal_of)
                    .expect("feasible");
                black_box(goal_of.len())
            })
        });
    }
    cold.finish();
    let mut warm = cr.benchmark_group("assign_layout_warm");
    warm.sample_size(20);
    for layout in Layout::ALL {
        let (agents, g0) = layout.instance(&mut SplitMix64::new(0xC0FFEE ^ n as u64), n);
        let step = 0.04 * layout.goal_extent();
        let mut rng = SplitMix64::new(0xBEEF);
        let g1: Vec<Vec2> = g0
            .iter()
            .map(|p| {
                let dx = step.x * (rng.unit() - 0.5);
                let dy = step.y * (rng.unit() - 0.5);
                Vec2::new(p.x + dx, p.y + dy)
            })
            .collect();
        let mut a = Assigner::new(PointMetric::Squared);
        let mut goal_of = Vec::with_capacity(n);
        a.solve(&agents, &g0, &mut goal_of).expect("feasible");
        let mut flip = false;
        warm.bench_function(BenchmarkId::new(layout.name(), n), |b| {
            b.iter(|| {
                flip = !flip;
                let goals = if flip { &g1 } else { &g0 };
                a.solve(black_box(&agents), black_box(goals), &mut goal_of)
                    .expect("feasible");
                black_box(goal_of.len())
            })
        });
    }
    warm.finish();
}

fn pathfinding_kuhn_munkres(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("pathfinding_kuhn_munkres");
    g.sample_size(10);
    for n in [1000usize, 2000] {
        let (_, _, c) = instance(n);
        // kuhn_munkres maximises integer weights: negate the cost scaled to 1e-6.
        let w = Matrix::from_vec(
            n,
            n,
            c.as_slice()
                .iter()
                .map(|&x| -(x * 1e6).round() as i64)
                .collect(),
        )
        .expect("n×n");
        g.bench_with_input(BenchmarkId::from_parameter(n), &w, |b, w| {
            b.iter(|| black_box(kuhn_munkres(black_box(w)).0))
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    assign_cold,
    assign_warm,
    assign_cold_points,
    assign_warm_points,
    assign_layouts,
    pathfinding_kuhn_munkres
);
criterion_main!(benches);
