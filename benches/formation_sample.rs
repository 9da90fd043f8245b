//! Sampling target points in a formation (formation-transform section 3.1: grid,
//! roulette-wheel add/remove, force-based relaxation), the first part of preparing
//! a transform.
//!
//! Run: `cargo bench --bench formation_sample -- --warm-up-time 1 --measurement-time 3`.
//!
//! * `formation_sample/{square,ring,heart}/{500,2000}`: the points for N agents in a
//!   shipped shape of N m² (0.5 m apart, 60 relaxation steps; the ring has a hole,
//!   the heart is a traced bitmap).
//! * `sample_goals/{1000,5000,10000}`: one goal sample per agent on a mesh
//!   (mesh-formation-control section 6.1: candidates, farthest-point picks, Lloyd
//!   relaxation), what a formation switch and a resize prepare: a 10 m square
//!   meshed 9 × 9.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use crowdtouch::crowd::formation::{FormationLibrary, Placement, SampleParams};
use crowdtouch::crowd::mesh::{sample_goals, TriMesh};
use crowdtouch::geom::{Rect, Vec2};

fn formation_sample(cr: &mut Criterion) {
    let lib = FormationLibrary::shipped();
    let mut g = cr.benchmark_group("formation_sample");
    g.sample_size(10);
    let p = SampleParams {
        min_spacing_m: 0.5,
        relax_iterations: 60,
    };
    for name in ["square", "ring", "heart"] {
        let f = lib.get(name).expect("shipped");
        for n in [500usize, 2000] {
            let place = Placement {
                centre_m: Vec2::new(0.0, 0.0),
                heading: Vec2::new(1.0, 0.0),
                area_m2: n as f64,
            };
            g.bench_function(format!("{name}/{n}"), |b| {
                b.iter(|| black_box(f.sample(&place, n, &p, 7, &|| false)))
            });
        }
    }
    g.finish();
}

fn goals(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("sample_goals");
    g.sample_size(10);
    let mesh = TriMesh::grid(
        Rect {
            min: [0.0, 0.0],
            max: [10.0, 10.0],
        },
        9,
        9,
    );
    for n in [1000usize, 5000, 10_000] {
        g.bench_function(n.to_string(), |b| {
            b.iter(|| black_box(sample_goals(&mesh, n).len()))
        });
    }
    g.finish();
}

criterion_group!(benches, formation_sample, goals);
criterion_main!(benches);
