//! After a gesture motion the direct-control mesh is rebuilt around where the crowd
//! stands (`crowd::mesh::mesh_around`, gesture-driven section 7.3 then
//! mesh-formation-control section 4.1): installing it moves nobody, and touch control
//! goes on deforming it, also for a crowd split in two far groups: each group is a
//! piece of its own, so a hand on one group leaves the other where it is.
//!
//! An integration test because `crowd::mesh` may not import the controller.

use crowdtouch::crowd::control::{DirectController, DirectParams};
use crowdtouch::crowd::mesh::{mesh_around, TriMesh};
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::gesture::segment::{Control, ControlState, Finger};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::{ContactId, Micros};

fn jittered(n: usize, centre: Vec2, seed: u64) -> Vec<Vec2> {
    let mut rng = SplitMix64::new(seed);
    let cols = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|k| {
            centre
                + Vec2::new((k % cols) as f64 * 0.5, (k / cols) as f64 * 0.5)
                + Vec2::new(rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1))
        })
        .collect()
}

fn params() -> DirectParams {
    DirectParams {
        handle_weight: 1000.0,
        soft_weight: 100.0,
        checkpoint_spacing_m: 0.05,
        max_constraint_speed_m_s: 3.0,
        opposing_gain_per_s: 2.0,
    }
}

fn finger(id: u32, down: Vec2, now: Vec2) -> Control {
    Control {
        id,
        state: ControlState::Held,
        t_begin: Micros(0),
        fingers: vec![Finger {
            id: ContactId(id),
            world: now,
            world_down: down,
            glass_mm: now * 100.0,
            down: true,
            cancelled: false,
        }],
    }
}

/// A controller over some formation mesh, switched to the mesh around `p`.
fn installed(p: &[Vec2]) -> DirectController {
    let (mesh, samples) = mesh_around(p, 0.15).unwrap();
    let grid = TriMesh::grid(
        Rect {
            min: [0.0, 0.0],
            max: [2.0, 2.0],
        },
        3,
        3,
    );
    let mut dc = DirectController::new(grid, p.len(), params());
    dc.set_mesh_sampled(mesh, samples);
    dc
}

#[test]
fn installing_the_mesh_around_the_crowd_moves_nobody() {
    for p in [
        jittered(40, Vec2::new(3.0, 2.0), 7),
        vec![Vec2::new(1.0, 1.0)],
        (0..5).map(|k| Vec2::new(k as f64, 0.0)).collect(),
    ] {
        let dc = installed(&p);
        for (g, q) in dc.goals().iter().zip(&p) {
            assert!((g - q).norm() < 1e-9, "goal {g:?} for agent at {q:?}");
        }
        assert!(dc.is_at_rest());
    }
}

#[test]
fn two_hands_on_one_group_of_a_split_crowd_stretch_it() {
    let mut p = jittered(25, Vec2::zeros(), 1);
    p.extend(jittered(25, Vec2::new(8.0, 0.5), 2));
    let mut dc = installed(&p);
    // Hold agent 0 (a corner of the left group) and drag agent 24 (its far corner)
    // 1 m further out: the left group stretches between the two hands.
    let (a, b) = (p[0], p[24]);
    let d = (b - a).normalize();
    let dt = 1.0 / 120.0;
    for k in 0..=360 {
        let s = (k as f64 / 120.0).min(1.0);
        let controls = [finger(1, a, a), finger(2, b, b + d * s)];
        dc.update(&controls, dt, 0.0).unwrap();
    }
    let g = dc.goals();
    assert!((g[0] - a).norm() < 0.05, "held agent moved to {:?}", g[0]);
    assert!(
        (g[24] - (b + d)).norm() < 0.05,
        "dragged agent at {:?}",
        g[24]
    );
    let (before, after) = ((p[12] - a).norm(), (g[12] - g[0]).norm());
    assert!(after > before + 0.2, "{before} -> {after}");
    assert!(g.iter().all(|q| q.x.is_finite() && q.y.is_finite()));
    // The other group is a piece of its own (no corridor joins them): it stays.
    let moved = p[25..]
        .iter()
        .zip(&g[25..])
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    eprintln!("other group moved {moved:.2e} m");
    assert!(moved < 0.01, "the other group moved {moved} m");
}

#[test]
fn dragging_one_group_of_a_split_crowd_leaves_the_other() {
    let mut p = jittered(25, Vec2::zeros(), 1);
    p.extend(jittered(25, Vec2::new(8.0, 0.5), 2));
    let mut dc = installed(&p);
    assert_eq!(dc.mesh().piece_count(), 2);
    // One finger drags the middle of the right group 1 m up.
    let a = p[37];
    let dt = 1.0 / 120.0;
    for k in 0..=360 {
        let s = (k as f64 / 120.0).min(1.0);
        dc.update(&[finger(1, a, a + Vec2::new(0.0, s))], dt, 0.0)
            .unwrap();
    }
    let g = dc.goals();
    for (q, r) in g[25..].iter().zip(&p[25..]) {
        assert!(
            (q - r - Vec2::new(0.0, 1.0)).norm() < 0.02,
            "{q:?} from {r:?}"
        );
    }
    let moved = p[..25]
        .iter()
        .zip(&g[..25])
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    eprintln!("left group moved {moved:.2e} m");
    assert!(moved < 0.01, "the left group moved {moved} m");
    // Both pieces are still there to grab.
    assert!(dc.hits(p[0], 1e-6) && dc.hits(g[37], 1e-6));
    assert!(
        !dc.hits(Vec2::new(4.5, 0.5), 0.3),
        "nothing between the groups"
    );
}
