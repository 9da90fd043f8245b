//! Unit tests of the spatial editor (`cage.rs`, `cage_solve.rs`, `cage_mvc.rs`).

use super::cage::{correct_speeds, Cage, Handle};
use super::cage_mvc::HullMvc;
use super::cage_solve::CageParams;
use super::error::EditError;
use super::select::{SampleRef, Selection, SelectionQuery};
use super::tracks::{Track, TrackSet};
use crate::geom::{Rect, Vec2};

/// `rows` people side by side 0.8 m apart walking along +x at 1.2 m/s, sampled
/// every 0.5 s for `samples` samples.
fn band(rows: usize, samples: usize) -> TrackSet {
    let tracks = (0..rows)
        .map(|i| {
            let pts = (0..samples)
                .map(|j| Vec2::new(0.6 * j as f64, 0.8 * i as f64))
                .collect();
            let ts = (0..samples).map(|j| 0.5 * j as f64).collect();
            Track::linked(i as u64, pts, ts)
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.5,
    }
}

fn cage(set: &TrackSet) -> Cage {
    let sel = Selection::select(set, &SelectionQuery::default()).unwrap();
    Cage::new(set, &sel, &CageParams::default()).unwrap()
}

#[test]
fn mvc_rows_sum_to_one_and_reproduce_the_rest_points() {
    let set = band(8, 25);
    let c = cage(&set);
    let t = c.window(0).sample_matrix();
    for i in 0..t.nrows() {
        let s: f64 = t.row(i).iter().sum();
        assert!((s - 1.0).abs() < 1e-9, "row {i} sums to {s}");
        let q: Vec2 = (0..t.ncols()).map(|j| c.hull()[j] * t[(i, j)]).sum();
        assert!((q - c.rest_sample(i)).norm() < 1e-9);
        assert!((c.deformed_sample(i) - c.rest_sample(i)).norm() < 1e-9);
    }
    let tm = c.window(0).mesh_matrix();
    for i in 0..c.hull().len() {
        assert_eq!(tm[(i, i)], 1.0);
    }
}

#[test]
fn sample_matrix_equals_mean_value_coordinates() {
    let set = band(8, 25);
    let c = cage(&set);
    let t = c.window(0).sample_matrix();
    let mut row = vec![0.0; c.hull().len()];
    for i in 0..t.nrows() {
        crate::crowd::mesh::mean_value_coordinates(c.hull(), c.rest_sample(i), &mut row).unwrap();
        for (j, w) in row.iter().enumerate() {
            // The block path multiplies by reciprocals: a few ulps, not the bits.
            assert!(
                (t[(i, j)] - w).abs() <= 1e-13,
                "row {i} column {j}: {} {w}",
                t[(i, j)]
            );
        }
    }
    // On a vertex, on an edge, and outside.
    let mvc = HullMvc::new(c.hull()).unwrap();
    let (v0, v1) = (c.hull()[0], c.hull()[1]);
    let mut fast = vec![0.0; c.hull().len()];
    for p in [v0, (v0 + v1) / 2.0, v0 + (v0 - v1) * 3.0] {
        let a = crate::crowd::mesh::mean_value_coordinates(c.hull(), p, &mut row);
        let b = mvc.coordinates(p, &mut fast);
        assert_eq!(a.is_ok(), b.is_some());
        for (x, y) in row.iter().zip(&fast) {
            assert_eq!(x.to_bits(), y.to_bits());
        }
    }
}

#[test]
fn dragging_to_the_rest_position_leaves_the_rest_pose() {
    let set = band(6, 20);
    let mut c = cage(&set);
    let v = c.hull()[2];
    c.drag(&[(Handle::Hull(2), v)], &[Handle::Hull(7)]).unwrap();
    for i in 0..c.selection().len() {
        assert!((c.deformed_sample(i) - c.rest_sample(i)).norm() < 1e-9);
    }
    c.drag(&[(Handle::Hull(2), v)], &[]).unwrap();
    for i in 0..c.hull().len() {
        assert!((c.deformed_vertex(i) - c.hull()[i]).norm() < 1e-9);
    }
}

#[test]
fn dragged_hull_vertex_and_sample_land_exactly() {
    let set = band(8, 25);
    let mut c = cage(&set);
    let target = c.hull()[0] + Vec2::new(0.7, -0.4);
    c.drag(&[(Handle::Hull(0), target)], &[]).unwrap();
    assert!((c.deformed_vertex(0) - target).norm() <= 1e-9);
    let r = SampleRef {
        track: 3,
        sample: 12,
    };
    let i = c.selection().binary_search(&r).unwrap();
    let t2 = c.rest_sample(i) + Vec2::new(0.5, 0.5);
    c.drag(&[(Handle::Sample(r), t2)], &[]).unwrap();
    assert!((c.handle_position(Handle::Sample(r)).unwrap() - t2).norm() <= 1e-9);
    let mut out = set.clone();
    c.apply(&mut out).unwrap();
    assert!((out.tracks[3].points[12] - t2).norm() <= 1e-9);
}

#[test]
fn far_points_move_less_than_near_ones() {
    let set = band(8, 40);
    let mut c = cage(&set);
    // Drag the hull vertex nearest the far right end outwards by 1 m.
    let right = (0..c.hull().len())
        .max_by(|&a, &b| c.hull()[a].x.total_cmp(&c.hull()[b].x))
        .unwrap();
    let v = c.hull()[right];
    c.drag(&[(Handle::Hull(right), v + Vec2::new(1.0, 0.5))], &[])
        .unwrap();
    let (mut near, mut nn, mut far, mut nf) = (0.0, 0, 0.0, 0);
    for i in 0..c.selection().len() {
        let p = c.rest_sample(i);
        let moved = (c.deformed_sample(i) - p).norm();
        let d = (p - v).norm();
        if d < 3.0 {
            near += moved;
            nn += 1;
        } else if d > 15.0 {
            far += moved;
            nf += 1;
        }
    }
    let (near, far) = (near / nn as f64, far / nf as f64);
    assert!(near > 0.25, "near points moved {near} m");
    assert!(far < 0.01 * near, "far {far} m vs near {near} m");
}

#[test]
fn moderate_drag_keeps_the_hull_shape() {
    let set = band(8, 40);
    let mut c = cage(&set);
    let v = c.hull()[0];
    c.drag(&[(Handle::Hull(0), v + Vec2::new(0.5, 0.5))], &[])
        .unwrap();
    let e = c.hull_shape_error();
    // A 0.7 m drag of a corner of a 24 m × 6 m cage, bent within the locality
    // radius (the rest of the hull stays).
    assert!(e.edge_length_rms < 0.1, "{e:?}");
    assert!(e.angle_rms_rad < 0.15, "{e:?}");
    c.reset();
    let e = c.hull_shape_error();
    assert!(e.edge_length_rms < 1e-12 && e.angle_rms_rad < 1e-12);
}

#[test]
fn fixed_handles_stay_and_drag_lands() {
    let set = band(8, 40);
    let mut c = cage(&set);
    let n = c.hull().len();
    let (a, b) = (0, n / 2);
    let target = c.hull()[a] + Vec2::new(0.0, -1.0);
    c.drag(&[(Handle::Hull(a), target)], &[Handle::Hull(b)])
        .unwrap();
    assert!((c.deformed_vertex(a) - target).norm() <= 1e-9);
    assert!((c.deformed_vertex(b) - c.hull()[b]).norm() <= 1e-9);
    assert!(matches!(
        c.drag(&[(Handle::Hull(a), target)], &[Handle::Hull(a)]),
        Err(EditError::ConflictingHandles { .. })
    ));
}

#[test]
fn bad_targets_are_refused() {
    let set = band(4, 10);
    let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
    let params = CageParams {
        world: Some(Rect {
            min: [-5.0, -5.0],
            max: [20.0, 20.0],
        }),
        ..CageParams::default()
    };
    let mut c = Cage::new(&set, &sel, &params).unwrap();
    assert!(matches!(
        c.drag(&[(Handle::Hull(0), Vec2::new(f64::NAN, 0.0))], &[]),
        Err(EditError::DragNotFinite { .. })
    ));
    assert!(matches!(
        c.drag(&[(Handle::Hull(0), Vec2::new(50.0, 0.0))], &[]),
        Err(EditError::DragOutsideWorld { .. })
    ));
    assert!(matches!(
        c.drag(&[(Handle::Hull(999), Vec2::new(1.0, 0.0))], &[]),
        Err(EditError::UnknownHandle { .. })
    ));
}

#[test]
fn speed_correction_restores_speeds() {
    let before = band(8, 40);
    let mut c = cage(&before);
    let v = c.hull()[0];
    c.drag(&[(Handle::Hull(0), v + Vec2::new(-2.0, -1.5))], &[])
        .unwrap();
    let mut after = before.clone();
    c.apply(&mut after).unwrap();
    let touched: Vec<usize> = (0..8).collect();
    let rep = correct_speeds(&before, &mut after, &touched).unwrap();
    assert!(
        rep.edited_ratio.0 < 0.99 || rep.edited_ratio.1 > 1.01,
        "{rep:?}"
    );
    assert!(
        rep.corrected_ratio.0 > 0.99 && rep.corrected_ratio.1 < 1.01,
        "{rep:?}"
    );
    for (tb, ta) in before.tracks.iter().zip(&after.tracks) {
        assert_eq!(ta.times_s[0], tb.times_s[0]);
        ta.validate().unwrap();
        for j in 0..tb.len() - 1 {
            let r = ta.segment_speed(j) / tb.segment_speed(j);
            assert!((r - 1.0).abs() < 0.01, "speed ratio {r}");
        }
    }
}

/// Rotates `p` by `deg` degrees about `c`.
fn rotate(p: Vec2, c: Vec2, deg: f64) -> Vec2 {
    let (s, co) = deg.to_radians().sin_cos();
    let d = p - c;
    c + Vec2::new(co * d.x - s * d.y, s * d.x + co * d.y)
}

fn handle_of(c: &Cage, track: usize, sample: usize) -> (Handle, Vec2) {
    let r = SampleRef { track, sample };
    let i = c.selection().binary_search(&r).unwrap();
    (Handle::Sample(r), c.rest_sample(i))
}

#[test]
fn a_rigid_turn_costs_nothing_and_is_found() {
    // Eq. 6 with eq. 7 made rotation invariant: a fixed sample and a dragged one
    // whose targets are a rigid turn of the rest pose give that turn exactly, from
    // the rest cage (no rigid start: a reset cage with another handle set first).
    let set = band(3, 30);
    for deg in [90.0, -135.0, 30.0] {
        let mut c = cage(&set);
        let (fixed, centre) = handle_of(&c, 1, 0);
        let (dragged, end) = handle_of(&c, 1, 29);
        c.drag(&[(dragged, rotate(end, centre, deg))], &[fixed])
            .unwrap();
        let stats = c.last_solve();
        assert!(stats.converged, "{deg}°: {stats:?}");
        for i in 0..c.selection().len() {
            let want = rotate(c.rest_sample(i), centre, deg);
            assert!(
                (c.deformed_sample(i) - want).norm() < 1e-3,
                "{deg}°: sample {i} at {:?}, a turn puts it at {want:?}",
                c.deformed_sample(i)
            );
        }
        let e = c.hull_shape_error();
        assert!(
            e.edge_length_rms < 1e-4 && e.angle_rms_rad < 1e-4,
            "{deg}°: {e:?}"
        );
    }
}

#[test]
fn the_iteration_stops_at_the_tolerance_or_the_cap() {
    let set = band(3, 30);
    let mut c = cage(&set);
    let (fixed, centre) = handle_of(&c, 1, 0);
    let (dragged, end) = handle_of(&c, 1, 29);
    let first_iterations = {
        c.reset();
        // A handle set of its own first, so that the turn below starts from rest
        // without the rigid start of a fresh cage.
        c.drag(&[(dragged, end)], &[fixed]).unwrap();
        c.drag(&[(dragged, rotate(end, centre, 60.0))], &[fixed])
            .unwrap();
        c.last_solve()
    };
    assert!(first_iterations.converged && first_iterations.iterations > 1);
    assert!(first_iterations.iterations <= c_params().max_iterations);
    // A continuing drag by 1 cm converges in a few iterations.
    c.drag(
        &[(dragged, rotate(end, centre, 60.0) + Vec2::new(0.01, 0.0))],
        &[fixed],
    )
    .unwrap();
    assert!(c.last_solve().converged && c.last_solve().iterations < first_iterations.iterations);
    // Capped at one iteration: not converged.
    let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
    let params = CageParams {
        max_iterations: 1,
        ..CageParams::default()
    };
    let mut one = Cage::new(&set, &sel, &params).unwrap();
    one.drag(&[(dragged, end)], &[fixed]).unwrap();
    one.drag(&[(dragged, rotate(end, centre, 60.0))], &[fixed])
        .unwrap();
    assert_eq!(
        one.last_solve(),
        super::cage::SolveStats {
            iterations: 1,
            converged: false
        }
    );
}

fn c_params() -> CageParams {
    CageParams::default()
}

#[test]
fn cotangent_weights_of_known_triangles() {
    // A right isosceles triangle: ½ cot 45° = 0.5 on the legs' opposite edges, and
    // the hypotenuse opposite the right angle gets the floor.
    let set = band(2, 4);
    let c = cage(&set);
    for (t, w) in c.mesh_triangles().iter().zip(c.window(0).edge_weights()) {
        let p = t.map(|i| c.mesh_vertices()[i as usize]);
        for e in 0..3 {
            let (a, b, o) = (p[e], p[(e + 1) % 3], p[(e + 2) % 3]);
            let (u, v) = (a - o, b - o);
            let want = (0.5 * u.dot(&v) / crate::geom::cross(u, v).abs()).clamp(
                super::cage_solve::MIN_EDGE_WEIGHT,
                super::cage_solve::MAX_EDGE_WEIGHT,
            );
            assert!((w[e] - want).abs() < 1e-12, "{w:?}");
            assert!(w[e] >= super::cage_solve::MIN_EDGE_WEIGHT);
        }
    }
}

#[test]
fn the_paper_locality_slides_the_cage_and_the_default_does_not() {
    // Eq. 5 with k = 300 layers: e^{c - k} vanishes on a cage of a few dozen layers and
    // a drag in the middle of a 12 m band moves its ends; with k at 5 m they stay.
    let set = band(3, 20);
    let sel = Selection::select(&set, &SelectionQuery::default()).unwrap();
    let mut ends = Vec::new();
    for params in [CageParams::paper(), CageParams::default()] {
        let mut c = Cage::new(&set, &sel, &params).unwrap();
        let (h, p) = handle_of(&c, 1, 10);
        c.drag(&[(h, p + Vec2::new(0.0, 1.5))], &[]).unwrap();
        let mut end: f64 = 0.0;
        for i in 0..c.selection().len() {
            let q = c.rest_sample(i);
            if (q - p).norm() > 5.5 {
                end = end.max((c.deformed_sample(i) - q).norm());
            }
        }
        ends.push(end);
    }
    assert!(ends[0] > 0.3, "paper: ends moved {} m", ends[0]);
    assert!(ends[1] < 0.15, "default: ends moved {} m", ends[1]);
    let c = cage(&set);
    let coef = c.window(0).locality_coefficients(&[Handle::Hull(0)]);
    assert_eq!(coef[0], 0.0, "the dragged vertex is free");
    let k = c.window(0).locality_k_layers();
    assert!(k > 5.0 && k < 40.0, "k = {k} layers");
}
