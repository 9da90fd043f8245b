//! The spatial crowd-motion editor (crowd::edit::cage): building a cage, and one drag
//! plus writing the deformed samples back, on 200 tracks × 100 samples.
//!
//! Run: `cargo bench --bench edit_cage -- --warm-up-time 1 --measurement-time 3`.
//! Inputs are generated deterministically outside the measured closures.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use crowdtouch::crowd::edit::{
    Cage, CageParams, Handle, Selection, SelectionQuery, Track, TrackSet,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;

/// 200 people in a 20 × 10 block, 0.8 m apart with 0.1 m of jitter, walking along a
/// gently curving path at 1.2 m/s, sampled every 0.5 s for 100 samples.
fn crowd() -> TrackSet {
    let mut rng = SplitMix64::new(17);
    let mut tracks = Vec::with_capacity(200);
    for i in 0..200u64 {
        let (row, col) = ((i / 20) as f64, (i % 20) as f64);
        let off = Vec2::new(
            -0.8 * row + rng.uniform(-0.1, 0.1),
            0.8 * col + rng.uniform(-0.1, 0.1),
        );
        let pts = (0..100)
            .map(|j| {
                let s = 0.6 * j as f64;
                Vec2::new(s, 4.0 * (s / 20.0).sin()) + off
            })
            .collect();
        let ts = (0..100).map(|j| 0.5 * j as f64).collect();
        tracks.push(Track::linked(i, pts, ts));
    }
    TrackSet {
        tracks,
        step_s: 0.5,
    }
}

fn bench(c: &mut Criterion) {
    let set = crowd();
    let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
    let params = CageParams::default();
    let mut g = c.benchmark_group("edit_cage");
    g.bench_function("new_200x100", |b| {
        b.iter(|| Cage::new(black_box(&set), black_box(&sel), &params).unwrap())
    });
    let mut cage = Cage::new(&set, &sel, &params).unwrap();
    eprintln!(
        "cage: {} hull vertices, {} mesh vertices, {} triangles, {} samples",
        cage.hull().len(),
        cage.mesh_vertices().len(),
        cage.mesh_triangles().len(),
        cage.selection().len()
    );
    let h = Handle::Hull(cage.hull().len() / 3);
    let v = cage.hull()[cage.hull().len() / 3];
    // The first drag of a handle set factorises its KKT system; a live drag then
    // repeats it with moving targets.
    cage.drag(&[(h, v + Vec2::new(0.5, 0.5))], &[]).unwrap();
    let mut out = set.clone();
    let mut k = 0u32;
    g.bench_function("drag_apply_200x100", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let a = 0.05 * (k % 40) as f64;
            let target = v + Vec2::new(0.5 + a, 0.5 - a);
            cage.drag(black_box(&[(h, target)]), &[]).unwrap();
            cage.apply(&mut out).unwrap();
        })
    });
    g.bench_function("drag_new_handle_200x100", |b| {
        let mut flip = false;
        b.iter(|| {
            flip = !flip;
            let i = if flip { 0 } else { 1 };
            let target = cage.hull()[i] + Vec2::new(0.3, 0.3);
            cage.drag(black_box(&[(Handle::Hull(i), target)]), &[])
                .unwrap();
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
