//! The binary snapshot encoder and decoder, JSON frames, and the documented example
//! frames and motion codes.

use super::fixtures::{arb_snapshot, snap, with_motions};
use crate::geom::Vec2;
use crate::publish::protocol::binary::{rd_u32, rd_u64};
use crate::publish::protocol::{
    decode_snapshot_binary, encode_snapshot_binary, frame_json, motion_code, motion_from_code,
    DecodeError, FieldSet, BINARY_DROPPED_OFFSET, BINARY_HEADER_BYTES, BINARY_TOUCH_BYTES,
    FLAG_MOTIONS, FRAME_KIND_JSON, MOTION_CODES,
};
use crate::vocab::Micros;
use crate::vocab::MotionType;
use crate::vocab::{AgentView, Snapshot, TouchView};
use proptest::prelude::*;

#[test]
fn binary_round_trips() {
    let mut s = snap(5);
    s.paused = true;
    let mut out = vec![0xAA]; // appends, never overwrites what is there
    encode_snapshot_binary(&s, Some(99), 7, &FieldSet::ALL, &mut out);
    let frame = &out[1..];
    assert_eq!(rd_u32(frame, 0) as usize, frame.len() - 4);
    let d = decode_snapshot_binary(frame).unwrap();
    assert_eq!(
        (d.seq, d.t_us, d.latency_us, d.dropped),
        (42, 1_000_123, Some(99), 7)
    );
    assert_eq!(
        (d.agents, d.goal_count, d.assignment_seq, d.paused),
        (5, 5, 40, true)
    );
    let pos = d.positions.unwrap();
    for (a, p) in s.agents.iter().zip(&pos) {
        assert!((a.pos.x - f64::from(p[0])).abs() < 1e-5);
        assert!((a.pos.y - f64::from(p[1])).abs() < 1e-5);
    }
    assert_eq!(d.assignment.unwrap(), vec![4, 3, 2, 1, 0]);
    let t = d.touches.unwrap();
    assert_eq!(t[0].control, Some(3));
    assert_eq!(t[1].control, None);
    assert_eq!(rd_u64(frame, BINARY_DROPPED_OFFSET), 7);
}

#[test]
fn binary_without_arrays_is_just_the_header() {
    let s = snap(5);
    let mut out = Vec::new();
    encode_snapshot_binary(&s, None, 0, &FieldSet::NONE, &mut out);
    assert_eq!(out.len(), BINARY_HEADER_BYTES);
    let d = decode_snapshot_binary(&out).unwrap();
    assert_eq!(d.latency_us, None);
    assert!(d.positions.is_none() && d.touches.is_none());
    assert_eq!(
        decode_snapshot_binary(&out[..10]),
        Err(DecodeError::Truncated { need: 64, have: 10 })
    );
    let mut j = Vec::new();
    frame_json(b"{\"type\":\"bye\"}\n", &mut j);
    j.resize(64, 0);
    assert_eq!(
        decode_snapshot_binary(&j),
        Err(DecodeError::NotASnapshot {
            kind: FRAME_KIND_JSON
        })
    );
}

#[test]
fn frame_json_strips_newline() {
    let mut out = Vec::new();
    frame_json(b"{}\n", &mut out);
    assert_eq!(out, vec![3, 0, 0, 0, FRAME_KIND_JSON, b'{', b'}']);
}

#[test]
fn binary_snapshot_carries_motions_when_named_and_in_a_scene() {
    use crate::vocab::MotionType;
    // 5 agents: 5 motion bytes, padded to 8 after the touches.
    let s = with_motions(snap(5));
    let mut out = Vec::new();
    encode_snapshot_binary(&s, Some(3), 0, &FieldSet::ALL, &mut out);
    let flags = u16::from_le_bytes([out[6], out[7]]);
    assert_ne!(flags & FLAG_MOTIONS, 0);
    let touches_end = BINARY_HEADER_BYTES + 8 * 5 + 8 * 5 + 8 * 5 + 4 * 5 + 2 * BINARY_TOUCH_BYTES;
    assert_eq!(out.len(), touches_end + 8, "5 codes and 3 bytes of padding");
    assert_eq!(&out[touches_end..], &[0, 1, 2, 3, 4, 0, 0, 0]);
    let d = decode_snapshot_binary(&out).unwrap();
    let codes = d.motions.clone().expect("motions decoded");
    let types: Vec<MotionType> = codes
        .iter()
        .map(|&c| motion_from_code(c).unwrap())
        .collect();
    assert_eq!(types, s.motions);
    // The arrays before it are where they always were.
    assert_eq!(d.touches.unwrap()[0].id, 7);
    assert_eq!(d.assignment.unwrap(), vec![4, 3, 2, 1, 0]);
    // Every type has its documented code and comes back.
    for m in MotionType::ALL {
        assert_eq!(motion_from_code(motion_code(m)), Some(m));
    }
    assert_eq!(motion_from_code(7), None);
    assert_eq!(motion_from_code(255), None);
    // A multiple of 4 agents needs no padding; alignment holds for any count.
    for n in 1..=9 {
        let s = with_motions(snap(n));
        let only = FieldSet {
            positions: true,
            motions: true,
            ..FieldSet::NONE
        };
        let mut out = Vec::new();
        encode_snapshot_binary(&s, None, 0, &only, &mut out);
        assert_eq!(out.len() % 4, 0, "n = {n}");
        assert_eq!(out.len(), BINARY_HEADER_BYTES + 8 * n + n.div_ceil(4) * 4);
        let d = decode_snapshot_binary(&out).unwrap();
        assert_eq!(d.motions.unwrap().len(), n);
        // A truncated motions array is reported, not read past.
        assert!(matches!(
            decode_snapshot_binary(&out[..out.len() - 1]),
            Err(DecodeError::Truncated { .. })
        ));
    }
}

#[test]
fn binary_snapshot_without_motions_keeps_the_previous_layout_exactly() {
    let plain = snap(5);
    let scene = with_motions(snap(5));
    for fields in [
        FieldSet::BINARY_DEFAULT,
        FieldSet::NONE,
        FieldSet {
            positions: true,
            touches: true,
            ..FieldSet::NONE
        },
    ] {
        // Not asked for: a scene changes nothing, byte for byte.
        let (mut a, mut b) = (Vec::new(), Vec::new());
        encode_snapshot_binary(&plain, Some(9), 2, &fields, &mut a);
        encode_snapshot_binary(&scene, Some(9), 2, &fields, &mut b);
        assert_eq!(a, b, "{fields:?}");
        let flags = u16::from_le_bytes([b[6], b[7]]);
        assert_eq!(flags & FLAG_MOTIONS, 0);
        assert!(decode_snapshot_binary(&b).unwrap().motions.is_none());
    }
    // Asked for but no scene: no flag, no bytes.
    let (mut a, mut b) = (Vec::new(), Vec::new());
    encode_snapshot_binary(&plain, None, 0, &FieldSet::BINARY_DEFAULT, &mut a);
    encode_snapshot_binary(&plain, None, 0, &FieldSet::ALL, &mut b);
    assert_eq!(a, b);
    // The documented example frame (docs/protocol.md, "Binary format") is unchanged.
    let example = example_frame_snapshot();
    let only = FieldSet {
        positions: true,
        touches: true,
        ..FieldSet::NONE
    };
    let mut out = Vec::new();
    encode_snapshot_binary(&example, Some(2248), 0, &only, &mut out);
    assert_eq!(out, documented_frame("Here is a real frame"));
    let mut out = Vec::new();
    encode_snapshot_binary(
        &with_motions(example.clone()),
        Some(2248),
        0,
        &only,
        &mut out,
    );
    assert_eq!(
        out,
        documented_frame("Here is a real frame"),
        "motions not named"
    );
    let with = FieldSet {
        motions: true,
        ..only
    };
    let mut s = example;
    s.motions = vec![MotionType::Run, MotionType::Swim, MotionType::Crawl];
    let mut out = Vec::new();
    encode_snapshot_binary(&s, Some(2248), 0, &with, &mut out);
    assert_eq!(out, documented_frame("The same frame with motions"));
}

/// The snapshot of the example frames in docs/protocol.md.
fn example_frame_snapshot() -> Snapshot {
    Snapshot {
        seq: 4812,
        t: Micros(73_911_402_118),
        input_t: None,
        agents: [(1.2504, 0.8), (1.75, 0.8124), (1.5, 1.2331)]
            .iter()
            .map(|&(x, y)| AgentView {
                pos: Vec2::new(x, y),
                vel: Vec2::zeros(),
                goal: 0,
            })
            .collect(),
        goals: vec![Vec2::zeros(); 3],
        assignment_seq: 4810,
        touches: vec![TouchView {
            id: 17,
            pos: Vec2::new(1.41, 1.02),
            control: Some(5),
        }],
        paused: false,
        motions: Vec::new(),
    }
}

/// The bytes of the hex dump that follows the paragraph starting with `intro` in
/// docs/protocol.md.
fn documented_frame(intro: &str) -> Vec<u8> {
    let doc = include_str!("../../../../docs/protocol.md");
    let at = doc
        .find(intro)
        .unwrap_or_else(|| panic!("no {intro:?} in the doc"));
    let block = doc[at..].split("```").nth(1).expect("a code block");
    block
        .lines()
        .filter(|l| l.len() > 6 && l.as_bytes()[..4].iter().all(u8::is_ascii_hexdigit))
        .flat_map(|l| {
            l[6..]
                .split_whitespace()
                .take_while(|w| w.len() == 2 && w.bytes().all(|b| b.is_ascii_hexdigit()))
                .map(|w| u8::from_str_radix(w, 16).unwrap())
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn motion_codes_match_the_documented_table() {
    let doc = include_str!("../../../../docs/protocol.md");
    let mut rows = 0;
    for (code, m) in MOTION_CODES {
        let row = format!("| {code} | `{}` |", m.as_str());
        assert!(doc.contains(&row), "docs/protocol.md lacks the row {row:?}");
        assert_eq!(motion_code(m), code);
        rows += 1;
    }
    assert_eq!(rows, MotionType::ALL.len(), "every motion type has a code");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed), ..ProptestConfig::default() })]

    #[test]
    fn binary_snapshot_matches(s in arb_snapshot(), dropped in any::<u64>()) {
        let mut out = Vec::new();
        encode_snapshot_binary(&s, None, dropped, &FieldSet::ALL, &mut out);
        let d = decode_snapshot_binary(&out).unwrap();
        prop_assert_eq!(d.seq, s.seq);
        prop_assert_eq!(d.dropped, dropped);
        let pos = d.positions.unwrap();
        prop_assert_eq!(pos.len(), s.agents.len());
        for (p, a) in pos.iter().zip(&s.agents) {
            // f32 keeps ~7 significant digits: 1e-3 m at 1e4 m.
            prop_assert!((f64::from(p[0]) - a.pos.x).abs() <= 1e-3);
        }
        prop_assert_eq!(d.touches.unwrap().len(), s.touches.len());
        let motions: Option<Vec<_>> = d
            .motions
            .map(|m| m.iter().map(|&c| motion_from_code(c).unwrap()).collect());
        let sent = (!s.motions.is_empty()).then(|| s.motions.clone());
        prop_assert_eq!(motions, sent);
        prop_assert_eq!(out.len() % 4, 0);
        // Without motions in the fields, the frame is what it was without a scene.
        let mut a = Vec::new();
        let mut b = Vec::new();
        let mut plain = s.clone();
        plain.motions.clear();
        encode_snapshot_binary(&s, None, dropped, &FieldSet::BINARY_DEFAULT, &mut a);
        encode_snapshot_binary(&plain, None, dropped, &FieldSet::ALL, &mut b);
        prop_assert_eq!(a, b);
    }
}
