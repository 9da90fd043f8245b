//! What gesture commands add to the protocol: the recognition in `gesture` end
//! events, `gesture_motion`, `plan` and `demo_motion`, and the `plan` subscription.

use crate::geom::Vec2;
use crate::publish::protocol::{
    encode_event, encode_plan_json, parse_client_message, ClientMessage, ClientSettings,
    ProtocolError, Subscriptions,
};
use crate::vocab::{Event, Micros, MotionPhase, NeighbourView, PlanOrigin, PlanView, Recognition};
use serde_json::{json, Value};

fn one_line(out: &[u8]) -> Value {
    assert_eq!(out.iter().filter(|&&c| c == b'\n').count(), 1);
    assert_eq!(out.last(), Some(&b'\n'));
    serde_json::from_slice(out).unwrap()
}

fn recognised() -> Event {
    Event::GestureEnd {
        id: 9,
        fingers: 2,
        contacts: 3,
        duration_us: 840_000,
        cancelled: false,
        recognition: Some(Recognition {
            class: "translate".into(),
            weight: 0.75,
            neighbours: vec![
                NeighbourView {
                    class: "translate".into(),
                    distance: 0.5,
                    weight: 0.75,
                    origin: "generated".into(),
                },
                NeighbourView {
                    class: "split".into(),
                    distance: f64::INFINITY,
                    weight: 0.25,
                    origin: "alice \"2\".jsonl".into(),
                },
            ],
            synth_us: 4200,
            agents: 100,
        }),
        rejected: None,
        t: Micros(73_921_090_000),
    }
}

#[test]
fn a_recognised_gesture_end_carries_its_class_weight_neighbours_and_synthesis_time() {
    let mut out = Vec::new();
    encode_event(&recognised(), &mut out);
    assert_eq!(
        one_line(&out),
        json!({
            "type": "gesture", "phase": "end", "id": 9, "fingers": 2, "contacts": 3,
            "duration_us": 840000, "cancelled": false,
            "recognition": {
                "class": "translate", "weight": 0.75,
                "neighbours": [
                    {"class": "translate", "distance": 0.5, "weight": 0.75, "origin": "generated"},
                    {"class": "split", "distance": 0.0, "weight": 0.25, "origin": "alice \"2\".jsonl"}
                ],
                "synth_us": 4200, "agents": 100
            },
            "rejected": null,
            "t_us": 73921090000u64
        })
    );
    // The keys a client written before recognition existed reads come first, as
    // they did.
    let text = String::from_utf8(out).unwrap();
    assert!(
        text.starts_with(
            "{\"type\":\"gesture\",\"phase\":\"end\",\"id\":9,\"fingers\":2,\"contacts\":3,\
             \"duration_us\":840000,\"cancelled\":false,"
        ),
        "{text}"
    );
}

#[test]
fn a_gesture_begin_has_no_recognition_keys() {
    let mut out = Vec::new();
    encode_event(
        &Event::GestureBegin {
            id: 9,
            t: Micros(5),
        },
        &mut out,
    );
    assert_eq!(
        one_line(&out),
        json!({"type":"gesture","phase":"begin","id":9,"t_us":5})
    );
}

#[test]
fn a_motion_phase_is_a_gesture_motion_message() {
    for (phase, name) in [
        (MotionPhase::Approach, "approach"),
        (MotionPhase::Follow, "follow"),
        (MotionPhase::Done, "done"),
        (MotionPhase::Cancelled, "cancelled"),
    ] {
        assert_eq!(phase.as_str(), name);
        let mut out = Vec::new();
        encode_event(
            &Event::GestureMotion {
                id: 9,
                class: "twist".into(),
                phase,
                t: Micros(11),
            },
            &mut out,
        );
        assert_eq!(
            one_line(&out),
            json!({"type":"gesture_motion","id":9,"class":"twist","phase":name,"t_us":11})
        );
    }
}

fn plan(origin: PlanOrigin, agents: usize, samples: u32) -> PlanView {
    let points = (0..agents * samples as usize)
        .map(|i| Vec2::new(i as f64 * 0.0015 - 1.0, 2.0 + (i % 7) as f64 / 3.0))
        .collect();
    PlanView {
        origin,
        class: "split_then_translate".into(),
        duration_s: 4.2,
        samples,
        points,
    }
}

/// The coordinates a client reads back, independently of the encoder: every
/// agent's array, parsed as JSON numbers.
fn read_agents(v: &Value) -> Vec<Vec<f64>> {
    v["agents"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| {
            a.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn a_plan_carries_every_agents_trajectory_to_the_millimetre() {
    let p = plan(PlanOrigin::Gesture { id: 9 }, 5, 64);
    let mut out = Vec::new();
    encode_plan_json(&p, &mut out);
    let v = one_line(&out);
    assert_eq!(v["type"], "plan");
    assert_eq!(v["gesture"], 9);
    assert_eq!(v["class"], "split_then_translate");
    assert_eq!(v["duration_s"], 4.2);
    assert_eq!(v["samples"], 64);
    assert!(v.get("motion").is_none());
    let agents = read_agents(&v);
    assert_eq!(agents.len(), 5);
    for (a, coords) in agents.iter().enumerate() {
        assert_eq!(coords.len(), 128);
        for (k, q) in p.trajectory(a).iter().enumerate() {
            assert!((coords[2 * k] - q.x).abs() <= 0.0005 + 1e-12);
            assert!((coords[2 * k + 1] - q.y).abs() <= 0.0005 + 1e-12);
        }
    }
    // The keys in the documented order.
    let text = String::from_utf8(out).unwrap();
    assert!(text.starts_with(
        "{\"type\":\"plan\",\"gesture\":9,\"class\":\"split_then_translate\",\"duration_s\":4.200,\"samples\":64,\"agents\":[["
    ));
}

#[test]
fn a_demo_motion_has_the_plans_shape_with_its_class_and_motion_index() {
    let p = plan(PlanOrigin::Demo { motion: 3 }, 2, 4);
    let mut out = Vec::new();
    encode_plan_json(&p, &mut out);
    let v = one_line(&out);
    assert_eq!(v["type"], "demo_motion");
    assert_eq!(v["class"], "split_then_translate");
    assert_eq!(v["motion"], 3);
    assert!(v.get("gesture").is_none());
    assert_eq!(read_agents(&v).len(), 2);
    assert!(read_agents(&v).iter().all(|a| a.len() == 8));
}

#[test]
fn a_plan_with_bad_numbers_or_a_partial_trajectory_is_still_valid_json() {
    let mut p = plan(PlanOrigin::Gesture { id: 1 }, 3, 4);
    p.points[0] = Vec2::new(f64::NAN, f64::INFINITY);
    p.points.push(Vec2::new(1.0, 1.0)); // a point past the last whole trajectory
    p.duration_s = f64::NAN;
    p.class = "quote\" and \\ backslash".into();
    let mut out = Vec::new();
    encode_plan_json(&p, &mut out);
    let v = one_line(&out);
    assert_eq!(v["class"], "quote\" and \\ backslash");
    assert_eq!(v["duration_s"], 0.0);
    let agents = read_agents(&v);
    assert_eq!(agents.len(), 3);
    assert_eq!(agents[0][0], 0.0);
    assert_eq!(agents[0][1], 1.0e9);
    // No samples: no agents.
    let empty = PlanView {
        samples: 0,
        ..plan(PlanOrigin::Gesture { id: 2 }, 1, 4)
    };
    assert_eq!(empty.agents(), 0);
    let mut out = Vec::new();
    encode_plan_json(&empty, &mut out);
    assert_eq!(one_line(&out)["agents"], json!([]));
}

#[test]
fn plan_is_a_subscription_a_client_must_name() {
    // No `subscribe`: every stream but `plan`, so an old client sees nothing new.
    let d = ClientSettings::default().subscriptions;
    assert_eq!(d, Subscriptions::DEFAULT);
    assert!(!d.plan);
    assert_eq!(d.names(), vec!["snapshot", "mesh", "events", "stats"]);
    let m = parse_client_message(br#"{"type":"hello","protocol":1}"#).unwrap();
    assert_eq!(m, ClientMessage::Hello(ClientSettings::default()));
    let m =
        parse_client_message(br#"{"type":"hello","protocol":1,"subscribe":["snapshot","plan"]}"#)
            .unwrap();
    let ClientMessage::Hello(s) = m else {
        panic!("not a hello")
    };
    assert!(s.subscriptions.plan && s.subscriptions.snapshot && !s.subscriptions.events);
    assert_eq!(s.subscriptions.names(), vec!["snapshot", "plan"]);
    assert_eq!(Subscriptions::ALL.names().len(), Subscriptions::NAMES.len());
    // A misspelt stream names the ones there are.
    match parse_client_message(br#"{"type":"hello","protocol":1,"subscribe":["plans"]}"#) {
        Err(ProtocolError::InvalidValue {
            field, expected, ..
        }) => {
            assert_eq!(field, "subscribe");
            assert!(expected.contains("\"plan\""), "{expected}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn the_documented_gesture_end_example_is_what_the_encoder_writes() {
    let doc = include_str!("../../../../docs/protocol.md");
    let line = doc
        .lines()
        .find(|l| l.starts_with("{\"type\":\"gesture\",\"phase\":\"end\",\"id\":9,"))
        .expect("docs/protocol.md shows a recognised gesture end");
    let n = |class: &str, distance: f64, weight: f64, origin: &str| NeighbourView {
        class: class.into(),
        distance,
        weight,
        origin: origin.into(),
    };
    let e = Event::GestureEnd {
        id: 9,
        fingers: 2,
        contacts: 2,
        duration_us: 840_000,
        cancelled: false,
        recognition: Some(Recognition {
            class: "translate".into(),
            weight: 0.82,
            neighbours: vec![
                n("translate", 0.113, 0.82, "generated"),
                n("split_then_translate", 0.514, 0.18, "alice-03.jsonl"),
            ],
            synth_us: 4100,
            agents: 200,
        }),
        rejected: None,
        t: Micros(73_921_090_000),
    };
    let mut out = Vec::new();
    encode_event(&e, &mut out);
    assert_eq!(std::str::from_utf8(&out).unwrap().trim_end(), line);
}

#[test]
fn a_collect_event_carries_the_session_state_in_the_documented_order() {
    use crate::vocab::{CollectState, CollectView};
    let e = Event::Collect(Box::new(CollectView {
        state: CollectState::Refused,
        item: 2,
        of: 12,
        class: "twist".into(),
        motion: 16,
        participant: "p\"07".into(),
        recorded: 3,
        detail: Some("tap".into()),
        t: Micros(73_960_000_000),
    }));
    let mut out = Vec::new();
    encode_event(&e, &mut out);
    assert_eq!(
        String::from_utf8(out).unwrap(),
        "{\"type\":\"collect\",\"state\":\"refused\",\"item\":2,\"of\":12,\"class\":\"twist\",\"motion\":16,\"participant\":\"p\\\"07\",\"recorded\":3,\"detail\":\"tap\",\"t_us\":73960000000}\n"
    );
    for s in [
        CollectState::Showing,
        CollectState::Recorded,
        CollectState::Skipped,
        CollectState::Undone,
        CollectState::Refused,
        CollectState::Failed,
        CollectState::Finished,
    ] {
        let e = Event::Collect(Box::new(CollectView {
            state: s,
            item: 0,
            of: 1,
            class: String::new(),
            motion: 0,
            participant: "p".into(),
            recorded: 0,
            detail: None,
            t: Micros(1),
        }));
        let mut out = Vec::new();
        encode_event(&e, &mut out);
        let v = one_line(&out);
        assert_eq!(v["state"], s.as_str());
        assert_eq!(v["detail"], Value::Null);
    }
}

#[test]
fn the_collect_commands_parse_and_refuse_arguments() {
    use crate::vocab::Command;
    for (name, cmd) in [
        ("collect.skip", Command::CollectSkip),
        ("collect.undo", Command::CollectUndo),
        ("collect.again", Command::CollectAgain),
        ("collect.status", Command::CollectStatus),
    ] {
        let line = format!("{{\"type\":\"command\",\"id\":4,\"name\":\"{name}\"}}");
        match parse_client_message(line.as_bytes()).unwrap() {
            ClientMessage::Command { id, command } => {
                assert_eq!(id, json!(4));
                assert_eq!(command, cmd);
                assert_eq!(command.name(), name);
            }
            other => panic!("{other:?}"),
        }
        let line = format!("{{\"type\":\"command\",\"id\":5,\"name\":\"{name}\",\"item\":3}}");
        let err = parse_client_message(line.as_bytes()).unwrap_err();
        assert!(err.to_string().contains("item"), "{err}");
    }
}
