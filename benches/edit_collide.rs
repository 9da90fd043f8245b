//! Space-time collision detection and avoidance by retiming (crowd-motion-editing
//! section 4.1; `crowd::edit::{detect, avoid}`). One core.
//!
//! `cargo bench --bench edit_collide -- --warm-up-time 1 --measurement-time 3`
//!
//! - `detect/walkers_1000x200`: 1,000 random walkers (1.3 m/s, heading drifting,
//!   60 × 60 m, 200 samples at 0.1 s), threshold 0.3 m. Target ≤ 200 ms.
//! - `detect/{zara01,students001}` and `all_pairs/…`: the UCY fixtures (25 fps,
//!   step 10), threshold 0.3 m; grid sweep against the all-pairs reference.
//!   Target ≤ 50 ms each.
//! - `avoid/crossing_200`: two groups of 100 (rows of 10, 2.5 m apart) crossing at
//!   right angles at 1.3 m/s, 201 samples at 0.1 s, default parameters (a fresh
//!   copy per iteration). Target ≤ 200 ms.

use criterion::{black_box, criterion_group, criterion_main, BatchSize, Criterion};
use crowdtouch::crowd::edit::io::{read_eth, EthOptions};
use crowdtouch::crowd::edit::{avoid, collisions_all_pairs, detect, AvoidParams, Track, TrackSet};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;

fn walkers(n: usize, samples: usize) -> TrackSet {
    let mut rng = SplitMix64::new(0xED17);
    let step = 0.1;
    let tracks = (0..n)
        .map(|id| {
            let mut p = Vec2::new(rng.uniform(0.0, 60.0), rng.uniform(0.0, 60.0));
            let mut heading = rng.uniform(0.0, std::f64::consts::TAU);
            let mut points = Vec::with_capacity(samples);
            for _ in 0..samples {
                points.push(p);
                heading += rng.uniform(-0.3, 0.3);
                p += Vec2::new(heading.cos(), heading.sin()) * (1.3 * step);
            }
            Track::linked(
                id as u64,
                points,
                (0..samples).map(|k| k as f64 * step).collect(),
            )
        })
        .collect();
    TrackSet {
        tracks,
        step_s: step,
    }
}

fn crossing(per_group: usize, spacing: f64) -> TrackSet {
    let mut rng = SplitMix64::new(0xC805);
    let (step, samples, cols) = (0.1, 201, 10);
    let mut tracks = Vec::new();
    for g in 0..2 {
        let dir = if g == 0 {
            Vec2::new(1.0, 0.0)
        } else {
            Vec2::new(0.0, 1.0)
        };
        let side = Vec2::new(-dir.y, dir.x);
        let rows = per_group.div_ceil(cols) as f64;
        for k in 0..per_group {
            let (r, c) = ((k / cols) as f64, (k % cols) as f64);
            let jitter = Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1));
            let from = dir * (-13.0 - c * spacing) + side * ((r - rows / 2.0) * spacing) + jitter;
            tracks.push(Track::linked(
                (g * 1000 + k) as u64,
                (0..samples)
                    .map(|s| from + dir * (1.3 * step * s as f64))
                    .collect(),
                (0..samples).map(|s| s as f64 * step).collect(),
            ));
        }
    }
    TrackSet {
        tracks,
        step_s: step,
    }
}

fn fixture(name: &str) -> TrackSet {
    let path = format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"));
    read_eth(
        &std::fs::read_to_string(path).unwrap(),
        EthOptions::default(),
    )
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("detect");
    let set = walkers(1000, 200);
    g.bench_function("walkers_1000x200", |b| {
        b.iter(|| detect(black_box(&set), 0.3).unwrap())
    });
    for name in ["crowds_zara01.txt", "students001.txt"] {
        let set = fixture(name);
        let label = name.trim_end_matches(".txt");
        g.bench_function(label, |b| b.iter(|| detect(black_box(&set), 0.3).unwrap()));
    }
    g.finish();

    let mut g = c.benchmark_group("all_pairs");
    g.sample_size(10);
    for name in ["crowds_zara01.txt", "students001.txt"] {
        let set = fixture(name);
        let label = name.trim_end_matches(".txt");
        g.bench_function(label, |b| {
            b.iter(|| collisions_all_pairs(black_box(&set), 0.3).unwrap())
        });
    }
    g.finish();

    let mut g = c.benchmark_group("avoid");
    g.sample_size(10);
    let set = crossing(100, 2.5);
    // The outcome once, when timing (`cargo test --benches` runs each body once).
    if std::env::args().any(|a| a == "--bench") {
        let mut once = set.clone();
        let r = avoid(&mut once, &AvoidParams::default()).unwrap();
        eprintln!(
            "avoid/crossing_200: {} rounds, pairs {} -> {}, {} retimings, {} corrections, max speed change {:.1} %",
            r.iterations, r.pairs_before, r.pairs_after, r.retimings, r.corrections, r.max_speed_change_pct
        );
    }
    g.bench_function("crossing_200", |b| {
        b.iter_batched(
            || set.clone(),
            |mut s| avoid(&mut s, &AvoidParams::default()).unwrap(),
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
