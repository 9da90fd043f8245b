//! The hand-written JSON snapshot and mesh encoders.

use super::fixtures::{arb_snapshot, close, flat, snap, FIXED3_TOLERANCE};
use crate::geom::Vec2;
use crate::publish::protocol::{
    encode_mesh_json, encode_snapshot_json, encode_snapshot_json_shared, splice_dropped_json,
    FieldSet,
};
use crate::vocab::MeshView;
use proptest::prelude::*;
use serde_json::Value;
use std::sync::Arc;

#[test]
fn json_snapshot_has_every_field() {
    let s = snap(3);
    let mut out = Vec::new();
    encode_snapshot_json(&s, Some(17), 5, &FieldSet::ALL, &mut out);
    assert_eq!(out.last(), Some(&b'\n'));
    assert_eq!(out.iter().filter(|&&c| c == b'\n').count(), 1);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["type"], "snapshot");
    assert_eq!(v["seq"], 42);
    assert_eq!(v["t_us"], 1_000_123);
    assert_eq!(v["latency_us"], 17);
    assert_eq!(v["input_t_us"], 999_000);
    assert_eq!(v["dropped"], 5);
    assert_eq!(v["agents"], 3);
    assert_eq!(v["paused"], false);
    assert_eq!(v["assignment_seq"], 40);
    assert_eq!(v["assignment"], serde_json::json!([2, 1, 0]));
    assert_eq!(flat(&v["velocities"]), vec![0.5, 0.0, 0.5, 0.0, 0.5, 0.0]);
    assert_eq!(flat(&v["goals"])[1], 1.001);
    assert_eq!(
        v["touches"],
        serde_json::json!([{"id":7,"x":0.25,"y":0.75,"control":3},
                           {"id":8,"x":-1.0,"y":2.0,"control":null}])
    );
}

#[test]
fn json_snapshot_respects_fields_and_null_latency() {
    let s = snap(2);
    let mut out = Vec::new();
    let fields = FieldSet {
        positions: true,
        ..FieldSet::NONE
    };
    encode_snapshot_json(&s, None, 0, &fields, &mut out);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert!(v["latency_us"].is_null());
    let mut no_input = s.clone();
    no_input.input_t = None;
    let mut out2 = Vec::new();
    encode_snapshot_json(&no_input, None, 0, &fields, &mut out2);
    let v2: Value = serde_json::from_slice(&out2).unwrap();
    assert!(v2["input_t_us"].is_null());
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    for absent in [
        "velocities",
        "goals",
        "assignment",
        "assignment_seq",
        "touches",
    ] {
        assert!(!keys.contains(&absent), "{absent} in {keys:?}");
    }
    assert_eq!(flat(&v["positions"]).len(), 4);
}

#[test]
fn shared_json_splices_to_the_same_bytes() {
    let s = snap(4);
    let mut direct = Vec::new();
    encode_snapshot_json(&s, Some(3), 123_456, &FieldSet::ALL, &mut direct);
    let mut shared = Vec::new();
    let at = encode_snapshot_json_shared(&s, Some(3), &FieldSet::ALL, &mut shared);
    let mut spliced = Vec::new();
    splice_dropped_json(&shared, at, 123_456, &mut spliced);
    assert_eq!(direct, spliced);
}

#[test]
fn a_mesh_of_several_pieces_lists_every_outline() {
    let m = MeshView {
        seq: 1,
        vertices: vec![Vec2::new(0.0, 0.0); 6],
        triangles: Arc::new(vec![[0, 1, 2], [3, 4, 5]]),
        outline: Arc::new(vec![0, 1, 2]),
        outlines: Arc::new(vec![vec![0, 1, 2], vec![3, 4, 5]]),
        topology: 2,
    };
    let mut out = Vec::new();
    encode_mesh_json(&m, false, &mut out);
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["outline"], serde_json::json!([0, 1, 2]));
    assert_eq!(v["outlines"], serde_json::json!([[0, 1, 2], [3, 4, 5]]));
}

#[test]
fn mesh_triangles_only_when_asked() {
    let m = MeshView {
        seq: 3,
        vertices: vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ],
        triangles: Arc::new(vec![[0, 1, 2]]),
        outline: Arc::new(vec![0, 1, 2]),
        outlines: Arc::default(),
        topology: 9,
    };
    let mut a = Vec::new();
    encode_mesh_json(&m, true, &mut a);
    let v: Value = serde_json::from_slice(&a).unwrap();
    assert_eq!(v["triangles"], serde_json::json!([0, 1, 2]));
    assert_eq!(v["topology"], 9);
    assert_eq!(flat(&v["vertices"]), vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    let mut b = Vec::new();
    encode_mesh_json(&m, false, &mut b);
    let v: Value = serde_json::from_slice(&b).unwrap();
    assert!(v.get("triangles").is_none());
    assert_eq!(v["outline"], serde_json::json!([0, 1, 2]));
}

#[test]
fn json_snapshot_carries_motions_only_with_a_scene() {
    use crate::vocab::MotionType;
    let mut s = snap(3);
    let mut out = Vec::new();
    encode_snapshot_json(&s, None, 0, &FieldSet::ALL, &mut out);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert!(v.get("motions").is_none(), "no scene, no motions key");
    s.motions = vec![MotionType::Run, MotionType::Swim, MotionType::ClimbUp];
    out.clear();
    encode_snapshot_json(&s, None, 0, &FieldSet::ALL, &mut out);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["motions"], serde_json::json!(["run", "swim", "climb_up"]));
    let only_positions = FieldSet {
        positions: true,
        ..FieldSet::NONE
    };
    out.clear();
    encode_snapshot_json(&s, None, 0, &only_positions, &mut out);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert!(v.get("motions").is_none(), "not subscribed");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed), ..ProptestConfig::default() })]

    #[test]
    fn json_snapshot_matches(s in arb_snapshot(), latency in proptest::option::of(any::<u64>()), dropped in any::<u64>()) {
        let mut out = Vec::new();
        encode_snapshot_json(&s, latency, dropped, &FieldSet::ALL, &mut out);
        let v: Value = serde_json::from_slice(&out).unwrap();
        prop_assert_eq!(v["seq"].as_u64(), Some(s.seq));
        prop_assert_eq!(v["t_us"].as_u64(), Some(s.t.0));
        prop_assert_eq!(v["latency_us"].as_u64(), latency);
        prop_assert_eq!(v["dropped"].as_u64(), Some(dropped));
        prop_assert_eq!(v["agents"].as_u64(), Some(s.agents.len() as u64));
        prop_assert_eq!(v["paused"].as_bool(), Some(s.paused));
        prop_assert!(close(&flat(&v["positions"]), s.agents.iter().flat_map(|a| [a.pos.x, a.pos.y])));
        prop_assert!(close(&flat(&v["velocities"]), s.agents.iter().flat_map(|a| [a.vel.x, a.vel.y])));
        prop_assert!(close(&flat(&v["goals"]), s.goals.iter().flat_map(|g| [g.x, g.y])));
        let asg: Vec<u64> = v["assignment"].as_array().unwrap().iter().map(|x| x.as_u64().unwrap()).collect();
        prop_assert_eq!(asg, s.agents.iter().map(|a| u64::from(a.goal)).collect::<Vec<_>>());
        let touches = v["touches"].as_array().unwrap();
        prop_assert_eq!(touches.len(), s.touches.len());
        for (jt, t) in touches.iter().zip(&s.touches) {
            prop_assert_eq!(jt["id"].as_u64(), Some(u64::from(t.id)));
            prop_assert_eq!(jt["control"].as_u64(), t.control.map(u64::from));
            prop_assert!((jt["x"].as_f64().unwrap() - t.pos.x).abs() <= FIXED3_TOLERANCE);
            prop_assert!((jt["y"].as_f64().unwrap() - t.pos.y).abs() <= FIXED3_TOLERANCE);
        }
    }
}
