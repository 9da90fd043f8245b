//! The gesture-motion controller's own costs: the follower's per-tick targets, the
//! mesh rebuilt around the crowd when a motion ends, and one library motion simulated.
//!
//! Run: `cargo bench --bench motion_follow -- --warm-up-time 1 --measurement-time 3`.
//! Inputs are generated deterministically outside the measured closures.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::crowd::agents::AgentParams;
use crowdtouch::crowd::mesh::mesh_around;
use crowdtouch::crowd::motion::{library_specs, simulate, FollowParams, Follower};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::{MotionClass, S_H};
use crowdtouch::rng::SplitMix64;

/// `n` agents on a jittered grid at 0.5 m spacing.
fn crowd(n: usize, seed: u64) -> Vec<Vec2> {
    let mut rng = SplitMix64::new(seed);
    let cols = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|k| {
            Vec2::new((k % cols) as f64 * 0.5, (k / cols) as f64 * 0.5)
                + Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1))
        })
        .collect()
}

fn bench_targets(c: &mut Criterion) {
    let mut g = c.benchmark_group("follower_targets");
    for n in [100, 1000, 10_000] {
        let pos = crowd(n, 1);
        let trajs: Vec<[Vec2; S_H]> = pos
            .iter()
            .map(|&p| std::array::from_fn(|j| p + Vec2::new(0.05 * j as f64, 0.0)))
            .collect();
        let mut f = Follower::new(trajs, 10.0, FollowParams::default()).unwrap();
        // Everyone at the start: following from t = 0.
        let _ = f.targets(&pos, 0.0);
        let mut t = 0.0;
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                t = (t + 1e-4) % 10.0;
                black_box(f.targets(black_box(&pos), t).len())
            })
        });
    }
    g.finish();
}

fn bench_mesh_around(c: &mut Criterion) {
    let mut g = c.benchmark_group("mesh_around");
    for n in [100, 1000, 10_000] {
        let pos = crowd(n, 2);
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| black_box(mesh_around(black_box(&pos), 0.15).unwrap().1.len()))
        });
    }
    g.finish();
}

fn bench_simulate(c: &mut Criterion) {
    let params = AgentParams {
        radius_m: 0.15,
        max_speed_m_s: 1.5,
        max_accel_m_s2: 6.0,
        kp_per_s2: 16.0,
        kd_per_s: 8.0,
        push_stiffness_per_s2: 200.0,
    };
    let spec = library_specs(MotionClass::TwistWhileContracting, 1, 3).remove(0);
    c.bench_function("simulate/twist_while_contracting", |b| {
        b.iter(|| black_box(simulate(&spec, &params, 1.0 / 30.0).unwrap().duration_s))
    });
}

criterion_group!(benches, bench_targets, bench_mesh_around, bench_simulate);
criterion_main!(benches);
