//! Unit and property tests of the wire protocol (encoders, decoder, parser).

use super::*;
use crate::geom::Rect;
use crate::vocab::Micros;
use crate::vocab::{AgentView, ControlKind, TouchView};
use proptest::prelude::*;
use std::sync::Arc;

/// Worst-case error of a 3-decimal coordinate (m): half the last digit plus float slack.
const FIXED3_TOLERANCE: f64 = 0.0005 + 1e-9;

fn snap(n: usize) -> Snapshot {
    Snapshot {
        seq: 42,
        t: Micros(1_000_123),
        input_t: Some(Micros(999_000)),
        agents: (0..n)
            .map(|i| AgentView {
                pos: Vec2::new(i as f64 * 0.123_456 - 3.0, -(i as f64) * 0.01),
                vel: Vec2::new(0.5, -0.000_4),
                goal: (n - 1 - i) as u32,
            })
            .collect(),
        goals: (0..n).map(|i| Vec2::new(i as f64, 1.0005)).collect(),
        assignment_seq: 40,
        touches: vec![
            TouchView {
                id: 7,
                pos: Vec2::new(0.25, 0.75),
                control: Some(3),
            },
            TouchView {
                id: 8,
                pos: Vec2::new(-1.0, 2.0),
                control: None,
            },
        ],
        paused: false,
        motions: Vec::new(),
    }
}

fn flat(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn fixed3_formats_exactly() {
    let cases = [
        (0.0, "0.000"),
        (-0.0004, "0.000"),
        (-0.0006, "-0.001"),
        (1.2345, "1.235"),
        (-12.3454, "-12.345"),
        (1e12, "1000000000.000"),
        (f64::NEG_INFINITY, "-1000000000.000"),
        (f64::NAN, "0.000"),
        (0.999_9, "1.000"),
        (5.05, "5.050"),
        (99.999_6, "100.000"),
        (123_456.789_1, "123456.789"),
        (-7.0, "-7.000"),
        (10.0, "10.000"),
    ];
    for (v, want) in cases {
        let mut out = Vec::new();
        push_fixed3(&mut out, v);
        assert_eq!(String::from_utf8(out).unwrap(), want, "{v}");
    }
}

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
fn events_and_replies_are_json_lines() {
    let evs = [
        Event::ControlBegin {
            id: 1,
            kind: ControlKind::Line,
            fingers: vec![4, 5],
            vertices: vec![10, 11],
            t: Micros(5),
        },
        Event::ControlEnd {
            id: 1,
            kind: ControlKind::Line,
            cancelled: true,
            t: Micros(6),
        },
        Event::GestureEnd {
            id: 2,
            fingers: 3,
            contacts: 4,
            duration_us: 900,
            cancelled: false,
            t: Micros(7),
        },
        Event::Reset {
            agents: 50,
            hard: true,
            t: Micros(8),
        },
        Event::Paused {
            paused: true,
            t: Micros(9),
        },
        Event::Formation {
            name: "arrow".into(),
            checkpoint: Some("gate".into()),
            vertices: 36,
            t: Micros(10),
        },
    ];
    let mut out = Vec::new();
    for e in &evs {
        encode_event(e, &mut out);
    }
    assert!(out
        .split(|&c| c == b'\n')
        .filter(|l| !l.is_empty())
        .all(|l| l.starts_with(b"{\"type\":")));
    let lines: Vec<Value> = out
        .split(|&c| c == b'\n')
        .filter(|l| !l.is_empty())
        .map(|l| serde_json::from_slice(l).unwrap())
        .collect();
    assert_eq!(lines[0]["type"], "control");
    assert_eq!(lines[0]["phase"], "begin");
    assert_eq!(lines[0]["kind"], "line");
    assert_eq!(lines[1]["cancelled"], true);
    assert_eq!(lines[2]["type"], "gesture");
    assert_eq!(lines[2]["duration_us"], 900);
    assert_eq!(lines[3]["type"], "reset");
    assert_eq!(lines[4]["paused"], true);
    assert_eq!(lines[4]["t_us"], 9);
    assert_eq!(
        lines[5],
        serde_json::json!({"type":"formation","name":"arrow","checkpoint":"gate","vertices":36,"t_us":10})
    );

    let mut r = Vec::new();
    encode_ack(&Value::from("x"), &mut r);
    encode_error(None, "busy", false, &mut r);
    encode_dropped(3, 10, &mut r);
    encode_bye("shutdown", &mut r);
    let text = String::from_utf8(r).unwrap();
    assert!(text.lines().all(|l| l.starts_with("{\"type\":")), "{text}");
    let v: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(v[0], serde_json::json!({"type":"ack","id":"x"}));
    assert_eq!(v[1]["id"], Value::Null);
    assert_eq!(v[1]["fatal"], false);
    assert_eq!(
        v[2],
        serde_json::json!({"type":"dropped","count":3,"total":10})
    );
    assert_eq!(v[3]["type"], "bye");
}

#[test]
fn stats_carry_every_report_field_with_t_us() {
    let r = StatsReport {
        t: Micros(77),
        rss_bytes: Some(1),
        ..Default::default()
    };
    let mut out = Vec::new();
    encode_stats(&r, &mut out);
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["type"], "stats");
    assert_eq!(v["t_us"], 77);
    let report = serde_json::to_value(&r).unwrap();
    for k in report.as_object().unwrap().keys() {
        let k = if k == "t" { "t_us" } else { k.as_str() };
        assert!(v.get(k).is_some(), "stats lacks {k}");
    }
}

#[test]
fn server_hello_echoes_settings() {
    let info = crate::publish::HelloInfo {
        world: Rect {
            min: [0.0, 0.0],
            max: [4.0, 3.0],
        },
        agents: 10,
        agent_radius_m: 0.2,
    };
    let settings = ClientSettings {
        format: Format::Binary,
        subscriptions: Subscriptions {
            mesh: false,
            ..Subscriptions::ALL
        },
        max_rate_hz: Some(30.0),
        fields: FieldSet::NONE,
    };
    let mut out = Vec::new();
    encode_server_hello(
        &ServerHello {
            info: &info,
            client: 4,
            agents: 12,
            settings: &settings,
            client_queue: 8,
        },
        &mut out,
    );
    assert!(out.starts_with(b"{\"type\":\"hello\",\"protocol\":1,"));
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["protocol"], 1);
    assert_eq!(v["format"], "binary");
    assert_eq!(
        v["subscriptions"],
        serde_json::json!(["snapshot", "events", "stats"])
    );
    assert_eq!(v["fields"], serde_json::json!([]));
    assert_eq!(v["max_rate_hz"], 30.0);
    assert_eq!(v["world"]["max"], serde_json::json!([4.0, 3.0]));
    assert_eq!(v["agents"], 12);
    assert!(v["server"].as_str().unwrap().starts_with("crowdtouch "));
}

fn err(line: &str) -> ProtocolError {
    parse_client_message(line.as_bytes()).unwrap_err()
}

#[test]
fn hello_parses_with_defaults() {
    let m = parse_client_message(br#"{"type":"hello","protocol":1}"#).unwrap();
    assert_eq!(m, ClientMessage::Hello(ClientSettings::default()));
    let m = parse_client_message(
        br#"{"type":"hello","protocol":1,"format":"binary","subscribe":["events"],"max_rate_hz":30,"fields":["positions","touches"]}"#,
    )
    .unwrap();
    let ClientMessage::Hello(s) = m else {
        panic!("not a hello")
    };
    assert_eq!(s.format, Format::Binary);
    assert_eq!(s.subscriptions.names(), vec!["events"]);
    assert_eq!(s.max_rate_hz, Some(30.0));
    assert_eq!(s.min_interval_us(), Some(33_333));
    assert_eq!(s.fields.names(), vec!["positions", "touches"]);
}

#[test]
fn commands_parse() {
    let m =
        parse_client_message(br#"{"type":"command","id":3,"name":"reset","hard":true}"#).unwrap();
    assert_eq!(
        m,
        ClientMessage::Command {
            id: Value::from(3),
            command: Command::Reset { hard: true }
        }
    );
    assert_eq!(
        parse_client_message(
            b"{\"type\":\"command\",\"id\":4,\"name\":\"set_formation\",\"formation\":\"arrow\"}"
        )
        .unwrap(),
        ClientMessage::Command {
            id: Value::from(4),
            command: Command::SetFormation {
                formation: "arrow".into()
            }
        }
    );
    let m = parse_client_message(
        b"{\"type\":\"command\",\"id\":\"a\",\"name\":\"set_agent_count\",\"count\":50}\r",
    )
    .unwrap();
    assert_eq!(
        m,
        ClientMessage::Command {
            id: Value::from("a"),
            command: Command::SetAgentCount { count: 50 }
        }
    );
}

#[test]
fn errors_say_what_and_where() {
    let cases = [
        (
            "{\"type\":\"hello\",   x}",
            "line is not JSON at column 20: key must be a string",
            true,
        ),
        ("[1,2]", "message is an array, not a JSON object", true),
        ("{\"id\":1}", "missing `type` in message", true),
        (
            "{\"type\":\"snapshot\"}",
            "unknown message type \"snapshot\"",
            true,
        ),
        (
            "{\"type\":\"hello\",\"protocol\":1,\"foo\":1}",
            "unknown field `foo` in hello",
            true,
        ),
        ("{\"type\":\"hello\"}", "missing `protocol` in hello", true),
        (
            "{\"type\":\"hello\",\"protocol\":2}",
            "protocol version 2 is not supported",
            true,
        ),
        (
            "{\"type\":\"hello\",\"protocol\":1,\"format\":\"xml\"}",
            "`format` in hello must be \"json\" or \"binary\", got \"xml\"",
            true,
        ),
        (
            "{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[\"snapshot\",\"nope\"]}",
            "`subscribe` in hello must be a list of",
            true,
        ),
        (
            "{\"type\":\"hello\",\"protocol\":1,\"max_rate_hz\":0}",
            "`max_rate_hz` in hello must be a positive number or null, got 0",
            true,
        ),
        (
            "{\"type\":\"command\",\"name\":\"pause\"}",
            "missing `id` in command",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":[1],\"name\":\"pause\"}",
            "`id` in command must be a number or a string",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":1}",
            "missing `name` in command",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":1,\"name\":\"explode\"}",
            "unknown command `explode`",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":1,\"name\":\"set_agent_count\"}",
            "invalid arguments for command `set_agent_count`: missing field `count`",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":1,\"name\":\"set_formation\",\"formation\":3}",
            "invalid arguments for command `set_formation`",
            false,
        ),
        (
            "{\"type\":\"command\",\"id\":1,\"name\":\"pause\",\"x\":1}",
            "invalid arguments for command `pause`",
            false,
        ),
    ];
    for (line, want, fatal) in cases {
        let e = err(line);
        assert!(
            e.to_string().contains(want),
            "{line}: got `{e}`, want `{want}`"
        );
        assert_eq!(e.is_fatal(), fatal, "{line}");
    }
    assert_eq!(
        err("{\"type\":\"command\",\"id\":9,\"name\":\"explode\"}").command_id(),
        Some(&Value::from(9))
    );
    assert_eq!(
        err("{\"type\":\"command\",\"name\":\"pause\"}").command_id(),
        None
    );
    let long = vec![b' '; MAX_LINE_BYTES + 1];
    assert!(matches!(
        parse_client_message(&long),
        Err(ProtocolError::LineTooLong { .. })
    ));
}

fn arb_snapshot() -> impl Strategy<Value = Snapshot> {
    let coord = -1.0e4..1.0e4f64;
    let agent = (
        coord.clone(),
        coord.clone(),
        coord.clone(),
        coord.clone(),
        0..1000u32,
    )
        .prop_map(|(x, y, vx, vy, goal)| AgentView {
            pos: Vec2::new(x, y),
            vel: Vec2::new(vx, vy),
            goal,
        });
    let touch = (
        any::<u32>(),
        coord.clone(),
        coord.clone(),
        proptest::option::of(0..u32::MAX),
    )
        .prop_map(|(id, x, y, control)| TouchView {
            id,
            pos: Vec2::new(x, y),
            control,
        });
    (
        any::<u64>(),
        any::<u64>(),
        proptest::collection::vec(agent, 0..40),
        proptest::collection::vec(
            (coord.clone(), coord).prop_map(|(x, y)| Vec2::new(x, y)),
            0..40,
        ),
        proptest::collection::vec(touch, 0..5),
        any::<bool>(),
        any::<u64>(),
        // A scene (one motion per agent) or none.
        proptest::option::of(proptest::collection::vec(
            0..crate::vocab::MotionType::ALL.len(),
            40,
        )),
    )
        .prop_map(
            |(seq, t, agents, goals, touches, paused, aseq, scene)| Snapshot {
                seq,
                t: Micros(t),
                input_t: None,
                motions: scene
                    .map(|m| {
                        m.iter()
                            .take(agents.len())
                            .map(|&i| crate::vocab::MotionType::ALL[i])
                            .collect()
                    })
                    .unwrap_or_default(),
                agents,
                goals,
                assignment_seq: aseq,
                touches,
                paused,
            },
        )
}

fn close(a: &[f64], b: impl Iterator<Item = f64>) -> bool {
    let b: Vec<f64> = b.collect();
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| (x - y).abs() <= FIXED3_TOLERANCE)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed), ..ProptestConfig::default() })]

    #[test]
    fn parse_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = parse_client_message(&bytes);
    }

    #[test]
    fn parse_never_panics_on_jsonish(s in "\\{(\"(type|id|name|protocol|format|subscribe|fields|max_rate_hz|count|hard)\":(1|-1|2.5|null|true|\"hello\"|\"command\"|\"pause\"|\"binary\"|\\[\"events\"\\]|\\{\\}),?){0,6}\\}") {
        let _ = parse_client_message(s.as_bytes());
    }

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

#[test]
fn device_event_encodes_as_documented() {
    let mut out = Vec::new();
    encode_event(
        &Event::Device {
            input: 0,
            state: crate::vocab::DeviceState::Unplugged,
            name: "Dell Canvas".into(),
            node: "/dev/input/event5".into(),
            stable_id: "pci-0000:00:14.0-usb-0:2:1.0".into(),
            message: Some("device unplugged".into()),
            t: Micros(7),
        },
        &mut out,
    );
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["type"], "device");
    assert_eq!(v["state"], "unplugged");
    assert_eq!(v["node"], "/dev/input/event5");
    assert_eq!(v["message"], "device unplugged");
    assert_eq!(v["t_us"], 7);
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

/// One motion per agent, cycling through every type.
fn with_motions(mut s: Snapshot) -> Snapshot {
    use crate::vocab::MotionType;
    s.motions = (0..s.agents.len())
        .map(|i| MotionType::ALL[i % MotionType::ALL.len()])
        .collect();
    s
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

use crate::vocab::MotionType;

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
    let doc = include_str!("../../../docs/protocol.md");
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
    let doc = include_str!("../../../docs/protocol.md");
    let mut rows = 0;
    for (code, m) in MOTION_CODES {
        let row = format!("| {code} | `{}` |", m.as_str());
        assert!(doc.contains(&row), "docs/protocol.md lacks the row {row:?}");
        assert_eq!(motion_code(m), code);
        rows += 1;
    }
    assert_eq!(rows, MotionType::ALL.len(), "every motion type has a code");
}

#[test]
fn a_binary_hello_without_fields_does_not_get_motions() {
    let hello = |line: &str| match parse_client_message(line.as_bytes()).unwrap() {
        ClientMessage::Hello(s) => s,
        other => panic!("not a hello: {other:?}"),
    };
    let s = hello(r#"{"type":"hello","protocol":1,"format":"binary"}"#);
    assert_eq!(s.fields, FieldSet::BINARY_DEFAULT);
    assert!(!s.fields.names().contains(&"motions"));
    let s = hello(r#"{"type":"hello","protocol":1,"format":"json"}"#);
    assert_eq!(s.fields, FieldSet::ALL);
    let s = hello(
        r#"{"type":"hello","protocol":1,"format":"binary","fields":["positions","motions"]}"#,
    );
    assert_eq!(s.fields.names(), vec!["positions", "motions"]);
    assert_eq!(
        err(r#"{"type":"hello","protocol":1,"fields":["motion"]}"#).to_string(),
        "`fields` in hello must be a list of \"positions\", \"velocities\", \"goals\", \"assignment\", \"touches\", \"motions\", got \"motion\""
    );
}
