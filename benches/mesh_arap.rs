//! ARAP mesh deformation and goal sampling (crowd mesh stage).
//!
//! Run: `cargo bench --bench mesh_arap -- --warm-up-time 1 --measurement-time 3`.
//! Inputs are generated deterministically outside the measured closures.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use crowdtouch::crowd::mesh::{convex_hull, mean_value_coordinates, point_in_convex_polygon};
use crowdtouch::crowd::mesh::{goal_positions, sample_goals, TriMesh};
use crowdtouch::crowd::mesh::{Arap, Constraint};
use crowdtouch::geom::{Rect, Vec2};

/// Handle (hard) and supplementary (soft) weights of an area control.
const W_HANDLE: f64 = 1000.0;
const W_SUPPLEMENTARY: f64 = 100.0;

fn rotate_about(p: Vec2, c: Vec2, theta: f64) -> Vec2 {
    let d = p - c;
    let (s, co) = theta.sin_cos();
    c + Vec2::new(co * d.x - s * d.y, s * d.x + co * d.y)
}

/// A 20×20 grid over 10 m × 10 m with an area control: four handles, and every other
/// vertex on or inside their convex hull as a supplementary point whose target follows
/// the handles through mean value coordinates; the handles rotate by 0.05 rad.
struct AreaCase {
    mesh: TriMesh,
    constraints: Vec<Constraint>,
    targets: Vec<Vec2>,
}

fn area_case() -> AreaCase {
    let cols = 20;
    let mesh = TriMesh::grid(
        Rect {
            min: [0.0, 0.0],
            max: [10.0, 10.0],
        },
        cols,
        20,
    );
    let rest = mesh.rest();
    let handles: Vec<u32> = [(4, 4), (15, 5), (14, 15), (5, 14)]
        .iter()
        .map(|&(c, r)| (r * cols + c) as u32)
        .collect();
    let handle_pos: Vec<Vec2> = handles.iter().map(|&v| rest[v as usize]).collect();
    let hull: Vec<Vec2> = convex_hull(&handle_pos)
        .iter()
        .map(|&i| handle_pos[i])
        .collect();
    let centre = hull.iter().sum::<Vec2>() / hull.len() as f64;
    let moved: Vec<Vec2> = hull
        .iter()
        .map(|&p| rotate_about(p, centre, 0.05) + Vec2::new(0.05, -0.02))
        .collect();
    let mut constraints = Vec::new();
    let mut targets = Vec::new();
    for (&v, &p) in handles.iter().zip(&handle_pos) {
        constraints.push(Constraint {
            vertex: v,
            weight: W_HANDLE,
        });
        targets.push(rotate_about(p, centre, 0.05) + Vec2::new(0.05, -0.02));
    }
    let mut lambda = vec![0.0; hull.len()];
    for (v, &p) in rest.iter().enumerate() {
        if handles.contains(&(v as u32)) || !point_in_convex_polygon(&hull, p) {
            continue;
        }
        mean_value_coordinates(&hull, p, &mut lambda).expect("inside the hull");
        constraints.push(Constraint {
            vertex: v as u32,
            weight: W_SUPPLEMENTARY,
        });
        targets.push(moved.iter().zip(&lambda).map(|(q, l)| q * *l).sum());
    }
    AreaCase {
        mesh,
        constraints,
        targets,
    }
}

fn bench_arap(c: &mut Criterion) {
    let case = area_case();
    let n = case.mesh.vertex_count();
    let anchor = case.mesh.rest().to_vec();
    let mut arap = Arap::new(&case.mesh);
    arap.set_constraints(&case.constraints)
        .expect("valid constraints");
    let mut out = vec![Vec2::zeros(); n];
    c.bench_function("arap_step/20x20_area", |b| {
        b.iter(|| {
            arap.solve(black_box(&case.targets), black_box(&anchor), &mut out)
                .expect("solve");
            black_box(&out);
        })
    });

    // Alternate between two sets that differ in one weight, so every call refactors.
    let mut other = case.constraints.clone();
    other[0].weight *= 2.0;
    let sets = [case.constraints.clone(), other];
    let mut k = 0;
    c.bench_function("arap_factorize/20x20_area", |b| {
        b.iter(|| {
            k ^= 1;
            arap.set_constraints(black_box(&sets[k]))
                .expect("factorise");
        })
    });

    c.bench_function("arap_new/20x20", |b| {
        b.iter(|| black_box(Arap::new(black_box(&case.mesh))))
    });

    // A point control on a 10×8 grid: one handle dragged by 0.3 m.
    let small = TriMesh::grid(
        Rect {
            min: [0.0, 0.0],
            max: [4.5, 3.5],
        },
        10,
        8,
    );
    let mut arap_small = Arap::new(&small);
    let handle = 3 * 10 + 4;
    arap_small
        .set_constraints(&[Constraint {
            vertex: handle,
            weight: W_HANDLE,
        }])
        .expect("valid");
    let target = [small.rest()[handle as usize] + Vec2::new(0.3, 0.1)];
    let anchor_small = small.rest().to_vec();
    let mut out_small = vec![Vec2::zeros(); small.vertex_count()];
    c.bench_function("arap_step/10x8_point", |b| {
        b.iter(|| {
            arap_small
                .solve(black_box(&target), black_box(&anchor_small), &mut out_small)
                .expect("solve");
            black_box(&out_small);
        })
    });
}

fn bench_goals(c: &mut Criterion) {
    let case = area_case();
    c.bench_function("sample_goals/20x20_1000", |b| {
        b.iter(|| black_box(sample_goals(black_box(&case.mesh), 1000)))
    });
    let samples = sample_goals(&case.mesh, 1000);
    let mut out = Vec::with_capacity(samples.len());
    c.bench_function("goal_positions/20x20_1000", |b| {
        b.iter(|| {
            goal_positions(&case.mesh, black_box(&samples), case.mesh.rest(), &mut out);
            black_box(&out);
        })
    });
}

criterion_group!(benches, bench_arap, bench_goals);
criterion_main!(benches);
