//! The TUIO encoders' datagrams decoded by `rosc`: addresses, argument types and
//! order as the TUIO 1.1 and 2.0 specifications list them, and the size bound.

use super::*;
use crate::geom::{Rect, Vec2};
use crate::vocab::{AgentView, Micros, MotionType, Snapshot, TouchView};
use proptest::prelude::*;
use rosc::{OscBundle, OscMessage, OscPacket, OscType};
use std::f32::consts::FRAC_PI_2;

const WORLD: Rect = Rect {
    min: [-2.0, 1.0],
    max: [2.0, 3.0],
};

fn snapshot(agents: usize) -> Snapshot {
    Snapshot {
        seq: 1,
        t: Micros(1_000_000),
        agents: (0..agents)
            .map(|i| AgentView {
                pos: Vec2::new(-2.0 + 4.0 * i as f64 / agents.max(1) as f64, 2.0),
                vel: Vec2::new(0.0, 0.5),
                goal: 0,
            })
            .collect(),
        touches: vec![
            TouchView {
                id: 3,
                pos: Vec2::new(0.0, 2.0),
                control: Some(9),
            },
            TouchView {
                id: 4,
                pos: Vec2::new(1.0, 2.5),
                control: Some(9),
            },
        ],
        motions: vec![MotionType::Swim; agents],
        ..Snapshot::default()
    }
}

fn bundles(d: &Datagrams) -> Vec<OscBundle> {
    d.iter()
        .map(|b| match rosc::decoder::decode_udp(b) {
            Ok((rest, OscPacket::Bundle(b))) => {
                assert!(rest.is_empty());
                b
            }
            other => panic!("not a bundle: {other:?}"),
        })
        .collect()
}

fn messages(b: &OscBundle) -> Vec<&OscMessage> {
    b.content
        .iter()
        .map(|p| match p {
            OscPacket::Message(m) => m,
            OscPacket::Bundle(_) => panic!("nested bundle"),
        })
        .collect()
}

/// The OSC type tags of a message (`s`, `i`, `f`, `t`).
fn tags(m: &OscMessage) -> String {
    m.args
        .iter()
        .map(|a| match a {
            OscType::Int(_) => 'i',
            OscType::Float(_) => 'f',
            OscType::String(_) => 's',
            OscType::Time(_) => 't',
            _ => '?',
        })
        .collect()
}

fn word(m: &OscMessage) -> &str {
    match m.args.first() {
        Some(OscType::String(s)) => s,
        _ => "",
    }
}

fn ints(m: &OscMessage) -> Vec<i32> {
    m.args.iter().filter_map(|a| a.clone().int()).collect()
}

fn float(m: &OscMessage, i: usize) -> f32 {
    m.args[i].clone().float().expect("a float")
}

#[test]
fn tuio11_profiles_are_bundles_of_source_alive_sets_fseq_with_the_spec_types() {
    let mut framer = Framer::new(WORLD);
    let frame = framer.build(&snapshot(3), true, true, true);
    let mut enc = Encoder11::new("crowdtouch@test");
    let mut out = Datagrams::default();
    let all = Profiles {
        cursors: true,
        objects: true,
        blobs: true,
    };
    assert_eq!(enc.encode(frame, all, 42, 1472, &mut out), 0);
    let b = bundles(&out);
    assert_eq!(b.len(), 3, "one bundle per profile");
    for (bundle, addr, set_tags, sets) in [
        (&b[0], "/tuio/2Dcur", "sifffff", 2),
        (&b[1], "/tuio/2Dobj", "siiffffffff", 3),
        (&b[2], "/tuio/2Dblb", "sifffffffffff", 1),
    ] {
        let m = messages(bundle);
        assert!(m.iter().all(|m| m.addr == addr));
        let words: Vec<&str> = m.iter().map(|m| word(m)).collect();
        let mut expected = vec!["source", "alive"];
        expected.extend(std::iter::repeat_n("set", sets));
        expected.push("fseq");
        assert_eq!(words, expected, "{addr}");
        assert_eq!(tags(m[0]), "ss");
        assert_eq!(m[0].args[1], OscType::String("crowdtouch@test".into()));
        assert_eq!(tags(m[1]), format!("s{}", "i".repeat(sets)));
        for s in &m[2..2 + sets] {
            assert_eq!(tags(s), set_tags, "{addr}");
        }
        assert_eq!(tags(m[m.len() - 1]), "si");
        assert_eq!(ints(m[m.len() - 1]), vec![42]);
        // alive names exactly the sets' sessions.
        let set_ids: Vec<i32> = m[2..2 + sets].iter().map(|s| ints(s)[0]).collect();
        assert_eq!(ints(m[1]), set_ids);
    }
    // An agent: class = swim (3), heading +y = π/2, position normalised.
    let obj = messages(&b[1])[2];
    assert_eq!(ints(obj)[1], MotionType::Swim as i32);
    assert_eq!((float(obj, 3), float(obj, 4)), (0.0, 0.5));
    assert!((float(obj, 5) - FRAC_PI_2).abs() < 1e-6);
    // Velocity 0.5 m/s down a 2 m high world: 0.25 per second.
    assert_eq!((float(obj, 6), float(obj, 7)), (0.0, 0.25));
    // The control's box: touches at (0.5, 0.5) and (0.75, 0.75).
    let blb = messages(&b[2])[2];
    let v: Vec<f32> = (2..8).map(|i| float(blb, i)).collect();
    assert_eq!(v, vec![0.625, 0.625, 0.0, 0.25, 0.25, 0.0625]);
}

#[test]
fn tuio20_frames_are_frm_components_alv_with_unique_sessions() {
    let mut framer = Framer::new(WORLD);
    let frame = framer.build(&snapshot(3), true, true, true);
    let mut enc = Encoder20::new("crowdtouch@test", WORLD);
    let mut out = Datagrams::default();
    let ttag = rosc::OscTime {
        seconds: 7,
        fractional: 9,
    };
    assert_eq!(enc.encode(frame, 5, ttag, 1472, &mut out), 0);
    let b = bundles(&out);
    assert_eq!(b.len(), 1);
    let m = messages(&b[0]);
    let addrs: Vec<&str> = m.iter().map(|m| m.addr.as_str()).collect();
    assert_eq!(
        addrs,
        vec![
            "/tuio2/frm",
            "/tuio2/ptr",
            "/tuio2/ptr",
            "/tuio2/bnd",
            "/tuio2/tok",
            "/tuio2/tok",
            "/tuio2/tok",
            "/tuio2/alv"
        ]
    );
    assert_eq!(tags(m[0]), "itis");
    assert_eq!(m[0].args[0], OscType::Int(5));
    assert_eq!(m[0].args[1], OscType::Time(ttag));
    // 4 m × 2 m: 4000 mm << 16 | 2000 mm.
    assert_eq!(m[0].args[2], OscType::Int(4000 << 16 | 2000));
    assert_eq!(tags(m[1]), "iiiffffffffff".to_string() + "f");
    assert_eq!(tags(m[3]), "ifffffffffff");
    assert_eq!(tags(m[4]), "iiiffffffff");
    assert_eq!(ints(m[4])[2], MotionType::Swim as i32);
    let ids: Vec<i32> = m[1..7].iter().map(|s| ints(s)[0]).collect();
    let mut unique = ids.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), ids.len(), "session ids unique across kinds");
    assert_eq!(ints(m[7]), ids);
}

#[test]
fn the_dimension_is_millimetres_capped() {
    let big = Rect {
        min: [0.0, 0.0],
        max: [100.0, 0.5],
    };
    assert_eq!(dimension(big) as u32, 65_535 << 16 | 500);
}

#[test]
fn alive_sizes_match_rosc() {
    for ids in 0..40 {
        for word in [None, Some("alive")] {
            let mut args: Vec<OscType> = word
                .map(|w| OscType::String(w.into()))
                .into_iter()
                .collect();
            args.extend((0..ids).map(OscType::Int));
            let p = OscPacket::Message(OscMessage {
                addr: "/tuio/2Dobj".into(),
                args,
            });
            let mut b = Vec::new();
            rosc::encoder::encode_into_tcp(&p, &mut b).unwrap();
            assert_eq!(
                alive_element_bytes("/tuio/2Dobj", word, ids as usize),
                b.len()
            );
        }
    }
}

#[test]
fn session_ids_follow_agents_and_touches_across_frames() {
    let mut framer = Framer::new(WORLD);
    let a = framer.build(&snapshot(3), true, true, false).clone();
    let mut next = snapshot(2);
    next.t = Micros(1_100_000);
    next.touches.remove(0);
    let b = framer.build(&next, true, true, false).clone();
    let sessions = |f: &TuioFrame| -> Vec<i32> { f.objects.iter().map(|o| o.session).collect() };
    assert_eq!(sessions(&b), sessions(&a)[..2].to_vec());
    assert_eq!(b.cursors.len(), 1);
    assert_eq!(b.cursors[0].session, a.cursors[1].session);
    // Touch 4 stood still: no velocity.
    assert_eq!((b.cursors[0].vx, b.cursors[0].vy), (0.0, 0.0));
}

fn check_frames(agents: usize, max: usize, v20: bool) {
    let snap = snapshot(agents);
    let mut framer = Framer::new(WORLD);
    let frame = framer.build(&snap, true, true, true);
    let mut out = Datagrams::default();
    let cut = if v20 {
        Encoder20::new("s", WORLD).encode(frame, 9, rosc::OscTime::from((0, 1)), max, &mut out)
    } else {
        let all = Profiles {
            cursors: true,
            objects: true,
            blobs: true,
        };
        Encoder11::new("s").encode(frame, all, 9, max, &mut out)
    };
    for d in out.iter() {
        assert!(d.len() <= max, "{} > {max}", d.len());
    }
    // Per alive address: every bundle has the same alive, the same frame number,
    // and the sets over all bundles are exactly alive.
    let alive_addr = if v20 { "/tuio2/alv" } else { "/tuio/2Dobj" };
    let mut alive: Option<Vec<i32>> = None;
    let mut seen = Vec::new();
    for b in bundles(&out) {
        let m = messages(&b);
        if v20 {
            assert_eq!(m[0].addr, "/tuio2/frm");
            assert_eq!(m[0].args[0], OscType::Int(9));
        }
        if m[0].addr != "/tuio2/frm" && m[0].addr != alive_addr {
            continue;
        }
        let a = m
            .iter()
            .find(|m| m.addr == alive_addr && (v20 || word(m) == "alive"))
            .map(|m| ints(m))
            .expect("every bundle has its alive list");
        if let Some(prev) = &alive {
            assert_eq!(&a, prev);
        }
        alive = Some(a);
        if !v20 {
            assert_eq!(word(m[m.len() - 1]), "fseq");
            assert_eq!(ints(m[m.len() - 1]), vec![9]);
        }
        seen.extend(
            m.iter()
                .filter(|m| {
                    m.addr != "/tuio2/frm" && m.addr != "/tuio2/alv" && (v20 || word(m) == "set")
                })
                .map(|m| ints(m)[0]),
        );
    }
    let alive = alive.expect("some bundle");
    seen.sort();
    let mut sorted = alive.clone();
    sorted.sort();
    assert_eq!(seen, sorted);
    let total = agents + if v20 { 3 } else { 0 };
    assert_eq!(alive.len() + cut, total);
}

#[test]
fn a_large_crowd_spreads_over_bundles_of_one_frame() {
    check_frames(200, 1472, false);
    check_frames(200, 1472, true);
}

#[test]
fn a_crowd_too_large_to_list_is_cut_and_says_so() {
    check_frames(2000, 1472, false);
    check_frames(2000, 1472, true);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn no_datagram_exceeds_the_bound(agents in 0usize..3000, max in 512usize..9000, v20: bool) {
        check_frames(agents, max, v20);
    }
}
