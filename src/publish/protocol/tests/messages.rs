//! Events, stats, replies and the server hello.

use crate::geom::Rect;
use crate::publish::protocol::{
    encode_ack, encode_bye, encode_dropped, encode_error, encode_event, encode_server_hello,
    encode_stats, ClientSettings, FieldSet, Format, ServerHello, Subscriptions,
};
use crate::vocab::Micros;
use crate::vocab::{ControlKind, Event, StatsReport};
use serde_json::Value;

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
            recognition: None,
            rejected: Some("tap".into()),
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
    assert_eq!(lines[2]["recognition"], Value::Null);
    assert_eq!(lines[2]["rejected"], "tap");
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
            ..Subscriptions::DEFAULT
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
            privileged: false,
        },
        &mut out,
    );
    assert!(out.starts_with(b"{\"type\":\"hello\",\"protocol\":1,"));
    let v: Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["protocol"], 1);
    assert_eq!(v["privileged"], false, "the client is told it is read-only");
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
