//! Gesture recognition benchmarks: the K = 10 nearest-neighbour query of
//! gesture-driven eq. 12 over 150 and 1,500 library gestures (default parameters:
//! unbanded DTW, the paper's weights), and the features of one gesture (validation,
//! Hermite resampling, eq. 2 and the four features of section 5.2).
//!
//! `cargo bench --bench gesture_knn`
//!
//! The gestures come from a small seeded generator here (not the library's): 1–5
//! fingers about a centre, each moved by a random mix of translation, turning and
//! scaling over 0.3–2 s at 60–240 Hz, with jitter.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::knn::{GestureIndex, SearchParams, Searcher};
use crowdtouch::gesture::resample::prepare;
use crowdtouch::gesture::track::{GestureTracks, TouchTrack, TrackSample};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::Micros;

/// A random gesture: fingers around a centre, moved by a random translation, turn
/// and scale (each of which may be absent), with jitter.
fn gesture(rng: &mut SplitMix64) -> GestureTracks {
    let fingers = 1 + (rng.next_u64() % 5) as usize;
    let centre = Vec2::new(rng.uniform(50.0, 250.0), rng.uniform(50.0, 150.0));
    let shift = if rng.unit() < 0.5 {
        Vec2::new(rng.uniform(-80.0, 80.0), rng.uniform(-80.0, 80.0))
    } else {
        Vec2::zeros()
    };
    let turn = if rng.unit() < 0.5 {
        rng.uniform(-3.0, 3.0)
    } else {
        0.0
    };
    let scale = if rng.unit() < 0.5 {
        rng.uniform(0.3, 2.5)
    } else {
        1.0
    };
    let duration_s = rng.uniform(0.3, 2.0);
    let hz = rng.uniform(60.0, 240.0);
    let samples = (duration_s * hz) as usize + 2;
    let tracks = (0..fingers)
        .map(|_| {
            let r = rng.uniform(10.0, 40.0);
            let a0 = rng.uniform(0.0, std::f64::consts::TAU);
            TouchTrack {
                samples: (0..samples)
                    .map(|i| {
                        let s = i as f64 / (samples - 1) as f64;
                        let a = a0 + turn * s;
                        let rad = r * (1.0 + (scale - 1.0) * s);
                        let p = centre + shift * s + Vec2::new(a.cos(), a.sin()) * rad;
                        let jitter = Vec2::new(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3));
                        TrackSample {
                            t: Micros((i as f64 / hz * 1e6) as u64),
                            mm: p + jitter,
                        }
                    })
                    .collect(),
            }
        })
        .collect();
    GestureTracks { fingers: tracks }
}

fn features(rng: &mut SplitMix64) -> GestureFeatures {
    loop {
        if let Ok(r) = prepare(&gesture(rng)) {
            return GestureFeatures::of(&r);
        }
    }
}

fn knn(c: &mut Criterion) {
    let mut group = c.benchmark_group("gesture_knn");
    for n in [150usize, 1500] {
        let mut rng = SplitMix64::new(0x6E57 ^ n as u64);
        let index = GestureIndex::new((0..n).map(|_| features(&mut rng)).collect());
        let queries: Vec<GestureFeatures> = (0..16).map(|_| features(&mut rng)).collect();
        let p = SearchParams::default();
        let mut searcher = Searcher::new();
        let mut q = 0usize;
        group.bench_with_input(BenchmarkId::new("query", n), &n, |b, _| {
            b.iter(|| {
                q = (q + 1) % queries.len();
                black_box(searcher.search(&index, black_box(&queries[q]), &p).len())
            })
        });
        let (mut computed, mut abandoned, mut pruned) = (0, 0, 0);
        for query in &queries {
            searcher.search(&index, query, &p);
            let s = searcher.stats();
            (computed, abandoned, pruned) = (
                computed + s.computed,
                abandoned + s.abandoned,
                pruned + s.pruned,
            );
        }
        let k = queries.len();
        println!(
            "gesture_knn/query/{n}: per query {} computed, {} abandoned, {} pruned",
            computed / k,
            abandoned / k,
            pruned / k
        );
    }
    group.finish();
}

fn extract(c: &mut Criterion) {
    let mut rng = SplitMix64::new(0xFEA7);
    let gestures: Vec<GestureTracks> = (0..32).map(|_| gesture(&mut rng)).collect();
    let mut i = 0usize;
    c.bench_function("gesture_features/prepare_and_features", |b| {
        b.iter(|| {
            i = (i + 1) % gestures.len();
            black_box(
                prepare(black_box(&gestures[i]))
                    .map(|r| GestureFeatures::of(&r))
                    .is_ok(),
            )
        })
    });
}

criterion_group!(benches, knn, extract);
criterion_main!(benches);
