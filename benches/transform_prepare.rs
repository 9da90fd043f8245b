//! Preparing a formation transform (formation-transform sections 3.2 and 3.4), one
//! core: the exact pairing by each cost (`transform_pair/<cost>/{1000,2000,5000}`),
//! the affinity-propagation subgroups at 2,000 agents (`transform_subgroups/local/2000`
//! with the default local similarity, `transform_subgroups/paper/2000` with eq. 20 as
//! written) and the whole plan at 2,000 (`transform_plan/2000`: least-effort
//! pairing, then subgroups with the default parameters). Each subgroup bench prints
//! the subgroup count, the iterations and whether the messages converged. The budget: the whole
//! preparation (sampling + triangulations + pairing + subgroups) ≤ 300 ms at 2,000
//! agents; the sampling is `Formation::sample`'s and is not in these figures.
//!
//! `cargo bench --bench transform_prepare -- --warm-up-time 1 --measurement-time 5`
//!
//! The crowd stands on a jittered square grid 5 cm apart; the targets are a jittered
//! hexagonal lattice filling a ring of the same area around the same centre (the
//! crowd turns into a ring: every agent moves, the local spacing changes).

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::transform::{
    pair, subgroups, ApParams, PairCost, Similarity, TransformPlan,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;

/// Crowd sizes of the pairing benches; a debug build (`cargo test --benches`, the
/// CI smoke run) takes small ones.
const PAIR_SIZES: &[usize] = if cfg!(debug_assertions) {
    &[200]
} else {
    &[1000, 2000, 5000]
};

/// Crowd size of the subgroup and plan benches (small in a debug build).
const PLAN_SIZE: usize = if cfg!(debug_assertions) { 400 } else { 2000 };

/// Spacing of the crowd's grid (m).
const SPACING_M: f64 = 0.05;

/// `n` agents on a jittered square grid (spacing [`SPACING_M`], centred on 0) and
/// `n` targets on a jittered hexagonal lattice in a ring of the same area.
fn instance(n: usize) -> (Vec<Vec2>, Vec<Vec2>) {
    let mut rng = SplitMix64::new(0x7A5F_0000 ^ n as u64);
    let side = (n as f64).sqrt().ceil() as usize;
    let half = side as f64 * SPACING_M / 2.0;
    let jit = |rng: &mut SplitMix64| 0.2 * SPACING_M * (rng.unit() - 0.5);
    let sources: Vec<Vec2> = (0..n)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            Vec2::new(
                i as f64 * SPACING_M - half + jit(&mut rng),
                j as f64 * SPACING_M - half + jit(&mut rng),
            )
        })
        .collect();
    // A ring with inner radius r0 and the crowd's area (n spacings²).
    let area = n as f64 * SPACING_M * SPACING_M;
    let r0 = 0.5 * (area / std::f64::consts::PI).sqrt();
    let r1 = (r0 * r0 + area / std::f64::consts::PI).sqrt();
    // Hexagonal lattice of `n` sites per `area`: lattice constant from the density,
    // grown a little until the ring holds at least `n` sites, then the first `n`.
    let mut a = (2.0 * area / (3f64.sqrt() * n as f64)).sqrt();
    let targets = loop {
        let mut t = Vec::new();
        let rows = (2.0 * r1 / (a * 3f64.sqrt() / 2.0)).ceil() as i64 + 1;
        let cols = (2.0 * r1 / a).ceil() as i64 + 1;
        for r in -rows..=rows {
            for c in -cols..=cols {
                let x = (c as f64 + 0.5 * (r & 1) as f64) * a;
                let y = r as f64 * a * 3f64.sqrt() / 2.0;
                let d = (x * x + y * y).sqrt();
                if d >= r0 && d <= r1 {
                    t.push(Vec2::new(x + jit(&mut rng), y + jit(&mut rng)));
                }
            }
        }
        if t.len() >= n {
            // Every k-th site, so the kept ones still fill the whole ring.
            let step = t.len() as f64 / n as f64;
            break (0..n)
                .map(|k| t[(k as f64 * step) as usize])
                .collect::<Vec<_>>();
        }
        a *= 0.98;
    };
    (sources, targets)
}

fn costs() -> [PairCost; 3] {
    [
        PairCost::LeastEffort { lambda: 0.5 },
        PairCost::Euclidean,
        PairCost::Manhattan,
    ]
}

fn transform_pair(c: &mut Criterion) {
    let mut g = c.benchmark_group("transform_pair");
    g.sample_size(10);
    for &n in PAIR_SIZES {
        let (s, t) = instance(n);
        for cost in costs() {
            g.bench_with_input(BenchmarkId::new(cost.name(), n), &n, |b, _| {
                b.iter(|| black_box(pair(&s, &t, cost, Cancel::NEVER).unwrap()))
            });
        }
    }
    g.finish();
}

fn transform_subgroups(c: &mut Criterion) {
    let mut g = c.benchmark_group("transform_subgroups");
    g.sample_size(10);
    let n = PLAN_SIZE;
    let (s, t) = instance(n);
    let to = pair(&s, &t, PairCost::LeastEffort { lambda: 0.5 }, Cancel::NEVER).unwrap();
    let paired: Vec<Vec2> = to.iter().map(|&j| t[j as usize]).collect();
    for (name, similarity) in [("local", Similarity::Local), ("paper", Similarity::Paper)] {
        let p = ApParams {
            similarity,
            ..ApParams::default()
        };
        let once = subgroups(&s, &paired, &p, Cancel::NEVER).unwrap();
        println!(
            "transform_subgroups/{name}/{n}: {} subgroups, {} iterations, converged {}",
            once.count(),
            once.iterations,
            once.converged
        );
        g.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
            b.iter(|| black_box(subgroups(&s, &paired, &p, Cancel::NEVER).unwrap()))
        });
    }
    g.finish();
}

fn transform_plan(c: &mut Criterion) {
    let mut g = c.benchmark_group("transform_plan");
    g.sample_size(10);
    let n = PLAN_SIZE;
    let (s, t) = instance(n);
    let p = ApParams::default();
    g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
        b.iter(|| {
            black_box(
                TransformPlan::new(
                    &s,
                    &t,
                    PairCost::LeastEffort { lambda: 0.5 },
                    Some(&p),
                    Cancel::NEVER,
                )
                .unwrap()
                .unwrap(),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, transform_pair, transform_subgroups, transform_plan);
criterion_main!(benches);
