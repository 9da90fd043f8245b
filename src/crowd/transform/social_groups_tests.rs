//! Tests of the subgroup terms in a running transform (`social_groups.rs` through
//! `run.rs`): eq. 21 as printed held by the acceleration clamp, and a subgroup
//! kept together by its Delaunay graph.

use super::run::{MoveParams, SubgroupAttraction, TransformRun};
use super::{PairCost, Subgroups, TransformPlan};
use crate::geom::Vec2;

const DT_S: f64 = 1.0 / 60.0;

fn plan(sources: &[Vec2], targets: &[Vec2], group_of: Vec<u32>) -> TransformPlan {
    let groups = group_of.iter().map(|&g| g as usize + 1).max().unwrap_or(1);
    TransformPlan {
        sources_m: sources.to_vec(),
        targets_m: targets.to_vec(),
        subgroups: Subgroups {
            group_of,
            exemplars: (0..groups as u32).collect(),
            iterations: 0,
            converged: true,
        },
        cost: PairCost::Euclidean,
    }
}

/// `n` points on a square lattice of `spacing_m` from `origin`.
fn lattice(n: usize, spacing_m: f64, origin: Vec2) -> Vec<Vec2> {
    let w = (n as f64).sqrt().ceil() as usize;
    (0..n)
        .map(|i| origin + Vec2::new((i % w) as f64, (i / w) as f64) * spacing_m)
        .collect()
}

#[test]
fn as_printed_drives_every_agent_at_the_clamp_towards_its_group() {
    // Nine agents 1.5 m apart, one group, targets 20 m to the right.
    let src = lattice(9, 1.5, Vec2::zeros());
    let tgt: Vec<Vec2> = src.iter().map(|s| s + Vec2::new(20.0, 0.0)).collect();
    let p = MoveParams {
        subgroup_attraction: SubgroupAttraction::AsPrinted,
        fluctuation_m_s2: 0.0,
        ..MoveParams::default()
    };
    let mut run = TransformRun::new(&plan(&src, &tgt, vec![0; 9]), &p, 1);
    let (mut pos, mut vel) = (src.clone(), vec![Vec2::zeros(); 9]);
    run.step(&mut pos, &mut vel, DT_S, None);
    let centroid = src.iter().sum::<Vec2>() / 9.0;
    let limit = p.max_accel_m_s2 * DT_S;
    for (i, v) in vel.iter().enumerate() {
        assert!(v.norm() <= limit * (1.0 + 1e-9), "agent {i}: {v:?}");
        if i == 4 {
            continue; // the centre: the pulls cancel, the driving force remains.
        }
        // Every other agent at the clamp, heading inwards more than to its target.
        assert!((v.norm() - limit).abs() < 1e-9 * limit, "agent {i}: {v:?}");
        let inwards = (centroid - src[i]).normalize();
        assert!(v.normalize().dot(&inwards) > 0.9, "agent {i}: {v:?}");
    }
    // Members 800 m apart: e^800 overflows f64, the held exponent does not.
    // Targets 10 m up; the pull along x all but hides the driving force.
    let far = [Vec2::zeros(), Vec2::new(800.0, 0.0)];
    let up: Vec<Vec2> = far.iter().map(|s| s + Vec2::new(0.0, 10.0)).collect();
    let mut run = TransformRun::new(&plan(&far, &up, vec![0, 0]), &p, 1);
    let (mut pos, mut vel) = (far.to_vec(), vec![Vec2::zeros(); 2]);
    run.step(&mut pos, &mut vel, DT_S, None);
    assert!(
        vel[0].x > 0.999 * limit && vel[1].x < -0.999 * limit,
        "{vel:?}"
    );
    assert!(
        pos.iter().all(|x| x.x.is_finite() && x.y.is_finite()),
        "{pos:?}"
    );
}

/// Largest change of a Delaunay edge's length from its source length over a walk
/// of a 16-agent group translated 12 m as a whole, with `attraction` (`None`: no
/// subgroup forces), and whether it arrived.
fn edge_drift_m(attraction: Option<SubgroupAttraction>) -> (f64, bool) {
    let src = lattice(16, 1.0, Vec2::zeros());
    let tgt: Vec<Vec2> = src.iter().map(|s| s + Vec2::new(12.0, 0.0)).collect();
    let p = MoveParams {
        subgroup_attraction: attraction.unwrap_or_default(),
        subgroup_forces: attraction.is_some(),
        ..MoveParams::default()
    };
    let pl = plan(&src, &tgt, vec![0; 16]);
    // The edges of the source layout, as the Delaunay variant builds them.
    let graph = super::social_groups::tests_edges(&src);
    let mut run = TransformRun::new(&pl, &p, 7);
    let (mut pos, mut vel) = (src.clone(), vec![Vec2::zeros(); 16]);
    let mut drift_m = 0.0f64;
    while !run.done() && run.elapsed_s() < 60.0 {
        run.step(&mut pos, &mut vel, DT_S, None);
        for &(a, b, len_m) in &graph {
            drift_m = drift_m.max(((pos[b] - pos[a]).norm() - len_m).abs());
        }
    }
    (drift_m, run.done())
}

#[test]
fn a_subgroup_translated_as_a_whole_keeps_its_delaunay_edges_where_the_plain_model_drifts() {
    let (dt_m, dt_done) = edge_drift_m(Some(SubgroupAttraction::DelaunayGraph));
    let (plain_m, plain_done) = edge_drift_m(None);
    let (place_m, _) = edge_drift_m(Some(SubgroupAttraction::Place));
    assert!(dt_done && plain_done, "both arrive");
    assert!(dt_m < 0.05, "Delaunay graph: edges drift {dt_m} m");
    assert!(plain_m > 3.0 * dt_m, "plain {plain_m} m vs graph {dt_m} m");
    assert!(place_m > dt_m, "place {place_m} m vs graph {dt_m} m");
    eprintln!("edge drift: graph {dt_m:.3} m, place {place_m:.3} m, plain {plain_m:.3} m");
}
