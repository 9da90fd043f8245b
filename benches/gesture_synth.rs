//! Crowd motion from a recognised gesture (gesture-driven section 7.2–7.3): blending
//! the motions of K = 10 neighbours, synthesising trajectories for 1,000 agents and
//! matching the agents to their starts — what the synthesis worker runs per gesture
//! (target: at most 20 ms on one core); the assignment alone, coarse to fine (as the
//! synthesis runs it) and in one level (as it ran before); and the features (FPCA + mixture) of one
//! 60-agent motion, what building the library costs per motion.
//!
//! `cargo bench --bench gesture_synth`
//!
//! The motions are generated here (seeded): splits and translations of a 60-agent
//! crowd on a jittered grid along eased paths with per-agent wobble.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use crowdtouch::crowd::assign::{CoarseToFine, CostMatrix, Solver};
use crowdtouch::crowd::motion::{
    blend, features, start_costs, CrowdMotion, FeatureParams, Placement, Synthesiser,
};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::library::{MotionClass, MotionFeatures};
use crowdtouch::rng::SplitMix64;

/// A 60-agent motion: `split` moves the halves apart, otherwise everyone translates.
fn motion(split: bool, seed: u64) -> CrowdMotion {
    let mut rng = SplitMix64::new(seed);
    let (m, side) = (60usize, 8usize);
    let heading = rng.uniform(-0.3, 0.3);
    let tracks: Vec<Vec<Vec2>> = (0..m)
        .map(|i| {
            let start = Vec2::new(
                (i % side) as f64 + rng.uniform(-0.2, 0.2),
                (i / side) as f64 + rng.uniform(-0.2, 0.2),
            );
            let dir = if !split || (i % side) * 2 >= side {
                1.0
            } else {
                -1.0
            };
            let (a, ph, speed) = (
                rng.uniform(0.0, 0.2),
                rng.uniform(0.0, 6.0),
                rng.uniform(0.9, 1.1),
            );
            (0..120)
                .map(|s| {
                    let t = s as f64 / 119.0;
                    let ease = t * t * (3.0 - 2.0 * t);
                    let d = dir * 6.0 * speed * ease;
                    start
                        + Vec2::new(d * heading.cos(), d * heading.sin())
                        + Vec2::new(0.0, a * (5.0 * t + ph).sin() * t)
                })
                .collect()
        })
        .collect();
    CrowdMotion::from_world(&tracks, 6.0).expect("valid motion")
}

fn neighbours() -> Vec<MotionFeatures> {
    (0..10)
        .map(|k| {
            let class = if k % 2 == 0 {
                MotionClass::Split
            } else {
                MotionClass::Translate
            };
            features(
                class.id(),
                &motion(k % 2 == 0, 100 + k),
                &FeatureParams::default(),
            )
            .expect("features")
        })
        .collect()
}

fn crowd(n: usize) -> Vec<Vec2> {
    let side = (n as f64).sqrt().ceil() as usize;
    let mut rng = SplitMix64::new(7);
    (0..n)
        .map(|i| {
            Vec2::new(
                (i % side) as f64 * 0.8 + rng.uniform(-0.1, 0.1),
                (i / side) as f64 * 0.8,
            )
        })
        .collect()
}

fn blend_and_synthesise(c: &mut Criterion) {
    let nb = neighbours();
    let weights = [0.2, 0.15, 0.12, 0.1, 0.1, 0.09, 0.08, 0.06, 0.05, 0.05];
    let pairs: Vec<(&MotionFeatures, f64)> = nb.iter().zip(weights).collect();
    let agents = crowd(1000);
    let placement = Placement::for_crowd(&agents);
    let mut syn = Synthesiser::new();
    let mut g = c.benchmark_group("gesture_synth");
    g.sample_size(30);
    g.bench_function("blend_k10", |b| {
        b.iter(|| blend(black_box(&pairs)).expect("blend"))
    });
    let blended = blend(&pairs).expect("blend");
    g.bench_function("synthesise_1000", |b| {
        b.iter(|| {
            syn.synthesise(black_box(&blended), &agents, &placement, 3)
                .expect("synthesis")
        })
    });
    g.bench_function("blend_k10_synthesise_assign_1000", |b| {
        b.iter(|| {
            let f = blend(black_box(&pairs)).expect("blend");
            syn.synthesise(&f, &agents, &placement, 3)
                .expect("synthesis")
        })
    });
    // The assignment alone, on the starts the synthesis sampled: coarse to fine
    // (what it runs) and the one-level solve of the equalised matrix.
    let starts: Vec<Vec2> = syn
        .synthesise(&blended, &agents, &placement, 3)
        .expect("synthesis")
        .trajectories
        .iter()
        .map(|t| t[0])
        .collect();
    let mut c2f = CoarseToFine::new();
    g.bench_function("assign_1000_coarse_to_fine", |b| {
        b.iter(|| {
            c2f.solve(black_box(&agents), black_box(&starts))
                .expect("assignment")
                .len()
        })
    });
    let (mut mapped, mut costs, mut solver) = (Vec::new(), CostMatrix::new(0, 0), Solver::new());
    g.bench_function("assign_1000_one_level", |b| {
        b.iter(|| {
            start_costs(
                black_box(&agents),
                black_box(&starts),
                &mut mapped,
                &mut costs,
            );
            solver.solve(&costs).expect("assignment").len()
        })
    });
    let m = motion(true, 5);
    g.bench_function("features_60_agents", |b| {
        b.iter(|| {
            features(
                MotionClass::Split.id(),
                black_box(&m),
                &FeatureParams::default(),
            )
            .expect("features")
        })
    });
    g.finish();
}

criterion_group!(benches, blend_and_synthesise);
criterion_main!(benches);
