//! Every JSON message but `snapshot` and `mesh`: events, `stats`, the replies
//! (`ack`, `error`, `dropped`, `bye`) and the server `hello`. They are rare, so serde
//! writes most of them.

use super::hello::{Format, ServerHello, MAX_LINE_BYTES, PROTOCOL_VERSION};
use super::numbers::push_uint;
use crate::vocab::{ClientId, Event, Recognition, StatsReport};
use serde_json::{Map, Value};

/// Appends `value` as one JSON line. Serialising these plain types cannot fail; if it
/// ever did, nothing is appended and the bug is logged.
fn push_json_line(out: &mut Vec<u8>, value: &impl serde::Serialize) {
    let start = out.len();
    match serde_json::to_writer(&mut *out, value) {
        Ok(()) => out.push(b'\n'),
        Err(e) => {
            out.truncate(start);
            log::error!("internal bug: cannot serialise a protocol message: {e}");
        }
    }
}

/// Every JSON message but `snapshot`, `mesh`, `stats` and `dropped` (written by
/// hand), in wire form: serde writes the `type` tag first, then fields in order.
#[derive(serde::Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
enum Wire<'a> {
    Control {
        phase: &'static str,
        id: u32,
        kind: crate::vocab::ControlKind,
        #[serde(skip_serializing_if = "Option::is_none")]
        fingers: Option<&'a [u32]>,
        #[serde(skip_serializing_if = "Option::is_none")]
        vertices: Option<&'a [u32]>,
        #[serde(skip_serializing_if = "Option::is_none")]
        cancelled: Option<bool>,
        t_us: u64,
    },
    Gesture {
        phase: &'static str,
        id: u32,
        #[serde(skip_serializing_if = "Option::is_none")]
        fingers: Option<u32>,
        #[serde(skip_serializing_if = "Option::is_none")]
        contacts: Option<u32>,
        #[serde(skip_serializing_if = "Option::is_none")]
        duration_us: Option<u64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        cancelled: Option<bool>,
        /// On `end` only: the recognition, or `null`.
        #[serde(skip_serializing_if = "Option::is_none")]
        recognition: Option<Option<RecognitionWire<'a>>>,
        /// On `end` only: why no motion was made, or `null`.
        #[serde(skip_serializing_if = "Option::is_none")]
        rejected: Option<Option<&'a str>>,
        t_us: u64,
    },
    GestureMotion {
        id: u32,
        class: &'a str,
        phase: crate::vocab::MotionPhase,
        t_us: u64,
    },
    Reset {
        agents: u32,
        hard: bool,
        t_us: u64,
    },
    Paused {
        paused: bool,
        t_us: u64,
    },
    Collect {
        state: crate::vocab::CollectState,
        item: u32,
        of: u32,
        class: &'a str,
        motion: u32,
        participant: &'a str,
        recorded: u32,
        detail: Option<&'a str>,
        t_us: u64,
    },
    Formation {
        name: &'a str,
        checkpoint: Option<&'a str>,
        vertices: u32,
        t_us: u64,
    },
    Device {
        input: u16,
        state: crate::vocab::DeviceState,
        name: &'a str,
        node: &'a str,
        stable_id: &'a str,
        #[serde(skip_serializing_if = "Option::is_none")]
        message: Option<&'a str>,
        t_us: u64,
    },
    Ack {
        id: &'a Value,
    },
    Error {
        id: Option<&'a Value>,
        message: &'a str,
        fatal: bool,
    },
    Bye {
        reason: &'a str,
    },
    Hello {
        protocol: u32,
        server: &'static str,
        client: ClientId,
        formats: [&'static str; 2],
        format: &'static str,
        subscriptions: Vec<&'static str>,
        fields: Vec<&'static str>,
        max_rate_hz: Option<f64>,
        world: &'a crate::geom::Rect,
        agents: u32,
        agent_radius_m: f64,
        client_queue: u32,
        max_line_bytes: usize,
        privileged: bool,
    },
}

/// A recognition in a `gesture` end event.
#[derive(serde::Serialize)]
struct RecognitionWire<'a> {
    class: &'a str,
    weight: f64,
    neighbours: Vec<NeighbourWire<'a>>,
    synth_us: u64,
    agents: u32,
}

/// One neighbour of a recognition.
#[derive(serde::Serialize)]
struct NeighbourWire<'a> {
    class: &'a str,
    distance: f64,
    weight: f64,
    origin: &'a str,
}

/// A finite number, else `0` (JSON has no NaN or infinity; serde_json would write
/// `null` where a client expects a number).
fn finite(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

fn recognition_wire(r: &Recognition) -> RecognitionWire<'_> {
    RecognitionWire {
        class: &r.class,
        weight: finite(r.weight),
        neighbours: r
            .neighbours
            .iter()
            .map(|n| NeighbourWire {
                class: &n.class,
                distance: finite(n.distance),
                weight: finite(n.weight),
                origin: &n.origin,
            })
            .collect(),
        synth_us: r.synth_us,
        agents: r.agents,
    }
}

/// Appends one event JSON line (`control`, `gesture`, `gesture_motion`, `reset`,
/// `formation`, `paused` or `device`).
pub fn encode_event(e: &Event, out: &mut Vec<u8>) {
    let w = match e {
        Event::ControlBegin {
            id,
            kind,
            fingers,
            vertices,
            t,
        }
        | Event::ControlUpdate {
            id,
            kind,
            fingers,
            vertices,
            t,
        } => Wire::Control {
            phase: if matches!(e, Event::ControlBegin { .. }) {
                "begin"
            } else {
                "update"
            },
            id: *id,
            kind: *kind,
            fingers: Some(fingers),
            vertices: Some(vertices),
            cancelled: None,
            t_us: t.0,
        },
        Event::ControlEnd {
            id,
            kind,
            cancelled,
            t,
        } => Wire::Control {
            phase: "end",
            id: *id,
            kind: *kind,
            fingers: None,
            vertices: None,
            cancelled: Some(*cancelled),
            t_us: t.0,
        },
        Event::GestureBegin { id, t } => Wire::Gesture {
            phase: "begin",
            id: *id,
            fingers: None,
            contacts: None,
            duration_us: None,
            cancelled: None,
            recognition: None,
            rejected: None,
            t_us: t.0,
        },
        Event::GestureEnd {
            id,
            fingers,
            contacts,
            duration_us,
            cancelled,
            recognition,
            rejected,
            t,
        } => Wire::Gesture {
            phase: "end",
            id: *id,
            fingers: Some(*fingers),
            contacts: Some(*contacts),
            duration_us: Some(*duration_us),
            cancelled: Some(*cancelled),
            recognition: Some(recognition.as_ref().map(recognition_wire)),
            rejected: Some(rejected.as_deref()),
            t_us: t.0,
        },
        Event::GestureMotion {
            id,
            class,
            phase,
            t,
        } => Wire::GestureMotion {
            id: *id,
            class,
            phase: *phase,
            t_us: t.0,
        },
        Event::Reset { agents, hard, t } => Wire::Reset {
            agents: *agents,
            hard: *hard,
            t_us: t.0,
        },
        Event::Paused { paused, t } => Wire::Paused {
            paused: *paused,
            t_us: t.0,
        },
        Event::Collect(c) => Wire::Collect {
            state: c.state,
            item: c.item,
            of: c.of,
            class: &c.class,
            motion: c.motion,
            participant: &c.participant,
            recorded: c.recorded,
            detail: c.detail.as_deref(),
            t_us: c.t.0,
        },
        Event::Formation {
            name,
            checkpoint,
            vertices,
            t,
        } => Wire::Formation {
            name,
            checkpoint: checkpoint.as_deref(),
            vertices: *vertices,
            t_us: t.0,
        },
        Event::Device {
            input,
            state,
            name,
            node,
            stable_id,
            message,
            t,
        } => Wire::Device {
            input: *input,
            state: *state,
            name,
            node,
            stable_id,
            message: message.as_deref(),
            t_us: t.0,
        },
    };
    push_json_line(out, &w);
}

/// Appends one `stats` JSON line: every field of [`StatsReport`], with its time `t`
/// written as `t_us` like every other time on the wire.
pub fn encode_stats(r: &StatsReport, out: &mut Vec<u8>) {
    let fields = match serde_json::to_value(r) {
        Ok(Value::Object(m)) => m,
        _ => Map::new(),
    };
    out.extend_from_slice(b"{\"type\":\"stats\"");
    for (k, v) in &fields {
        out.push(b',');
        let key = if k == "t" { "t_us" } else { k.as_str() };
        // Keys are plain identifiers and values plain JSON: writing them cannot fail.
        let _ = serde_json::to_writer(&mut *out, key);
        out.push(b':');
        let _ = serde_json::to_writer(&mut *out, v);
    }
    out.extend_from_slice(b"}\n");
}

/// Appends `{"type":"ack","id":…}`.
pub fn encode_ack(id: &Value, out: &mut Vec<u8>) {
    push_json_line(out, &Wire::Ack { id });
}

/// Appends `{"type":"error","id":…|null,"message":…,"fatal":…}`.
pub fn encode_error(id: Option<&Value>, message: &str, fatal: bool, out: &mut Vec<u8>) {
    push_json_line(out, &Wire::Error { id, message, fatal });
}

/// Appends `{"type":"dropped","count":…,"total":…}`: `count` snapshots were dropped
/// since the last notice, `total` since the client connected.
pub fn encode_dropped(count: u64, total: u64, out: &mut Vec<u8>) {
    let mut b = itoa::Buffer::new();
    out.extend_from_slice(b"{\"type\":\"dropped\",\"count\":");
    push_uint(out, count, &mut b);
    out.extend_from_slice(b",\"total\":");
    push_uint(out, total, &mut b);
    out.extend_from_slice(b"}\n");
}

/// Appends `{"type":"bye","reason":…}`.
pub fn encode_bye(reason: &str, out: &mut Vec<u8>) {
    push_json_line(out, &Wire::Bye { reason });
}

/// Appends one server `hello` line.
pub fn encode_server_hello(h: &ServerHello<'_>, out: &mut Vec<u8>) {
    let s = h.settings;
    let v = Wire::Hello {
        protocol: PROTOCOL_VERSION,
        server: concat!("crowdtouch ", env!("CARGO_PKG_VERSION")),
        client: h.client,
        formats: [Format::Json.as_str(), Format::Binary.as_str()],
        format: s.format.as_str(),
        subscriptions: s.subscriptions.names(),
        fields: s.fields.names(),
        max_rate_hz: s.max_rate_hz,
        world: &h.info.world,
        agents: h.agents,
        agent_radius_m: h.info.agent_radius_m,
        client_queue: h.client_queue,
        max_line_bytes: MAX_LINE_BYTES,
        privileged: h.privileged,
    };
    push_json_line(out, &v);
}
