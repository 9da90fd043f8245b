//! Parsing client lines: hellos, commands and the errors for everything else.

use crate::publish::protocol::{
    parse_client_message, ClientMessage, ClientSettings, FieldSet, Format, ProtocolError,
    MAX_LINE_BYTES,
};
use crate::vocab::Command;
use proptest::prelude::*;
use serde_json::Value;

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
                formation: "arrow".into(),
                method: None,
                duration: None,
            }
        }
    );
    assert_eq!(
        parse_client_message(
            br#"{"type":"command","id":5,"name":"set_formation","formation":"ring","method":"mesh","duration":4.5}"#
        )
        .unwrap(),
        ClientMessage::Command {
            id: Value::from(5),
            command: Command::SetFormation {
                formation: "ring".into(),
                method: Some(crate::vocab::FormationMethod::Mesh),
                duration: Some(4.5),
            }
        }
    );
    // An unknown method is an `error` reply naming the methods.
    match parse_client_message(
        br#"{"type":"command","id":6,"name":"set_formation","formation":"ring","method":"teleport"}"#,
    ) {
        Err(e) => {
            assert!(!e.is_fatal());
            let m = e.to_string();
            assert!(
                m.contains("teleport") && m.contains("transform") && m.contains("mesh"),
                "{m}"
            );
        }
        other => panic!("expected an error, got {other:?}"),
    }
    match parse_client_message(
        br#"{"type":"command","id":7,"name":"set_formation","formation":"ring","duration":"soon"}"#,
    ) {
        Err(e) => assert!(e.to_string().contains("duration"), "{e}"),
        other => panic!("expected an error, got {other:?}"),
    }
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
}

#[test]
fn a_key_twice_is_refused_and_named() {
    // In a touch's contact: answered with the command's id, the client stays.
    let e = err(
        r#"{"type":"command","id":7,"name":"touch","contacts":[{"id":1,"x":0.5,"x":0.9,"y":0.5}]}"#,
    );
    assert_eq!(e.command_id(), Some(&Value::from(7)));
    assert!(!e.is_fatal());
    let ProtocolError::InCommand { detail, .. } = &e else {
        panic!("{e:?}")
    };
    assert!(
        matches!(&**detail, ProtocolError::DuplicateKey { key, .. } if key == "x"),
        "{e:?}"
    );
    assert!(
        e.to_string().starts_with("duplicate key `x` at column "),
        "{e}"
    );
    // At the top of a command, and in a hello (fatal: no command to answer).
    let e = err(
        r#"{"type":"command","id":"a","name":"set_formation","formation":"arrow","formation":"ring"}"#,
    );
    assert_eq!(e.command_id(), Some(&Value::from("a")));
    assert!(e.to_string().contains("`formation`"), "{e}");
    let e = err(r#"{"type":"hello","protocol":1,"protocol":2}"#);
    assert!(e.is_fatal());
    assert!(
        matches!(&e, ProtocolError::DuplicateKey { key, .. } if key == "protocol"),
        "{e:?}"
    );
    // A repeated `type`: which message is it? Fatal.
    let e = err(r#"{"type":"command","id":1,"type":"hello","protocol":1}"#);
    assert!(e.is_fatal(), "{e:?}");
    // The same key in two contacts is not a duplicate.
    assert!(parse_client_message(
        br#"{"type":"command","id":1,"name":"touch","contacts":[{"id":1,"x":0.5,"y":0.5},{"id":2,"x":0.1,"y":0.5}]}"#
    )
    .is_ok());
}

#[test]
fn control_characters_sent_are_escaped_in_every_error() {
    use crate::located::needs_escape;
    let nasty = r"\u001b[2J\u009b31m\u202e\u007f";
    let lines = [
        format!(r#"{{"type":"command","id":1,"name":"pa{nasty}use"}}"#),
        format!(r#"{{"type":"command","id":1,"name":"reset","hard":"{nasty}"}}"#),
        format!(r#"{{"type":"command","id":1,"name":"reset","{nasty}":true}}"#),
        format!(r#"{{"type":"command","id":1,"name":"pause","{nasty}":true}}"#),
        format!(
            r#"{{"type":"command","id":1,"name":"touch","contacts":[{{"id":1,"x":"{nasty}","y":0}}]}}"#
        ),
        format!(r#"{{"type":"hello","protocol":1,"format":"{nasty}"}}"#),
        format!(r#"{{"type":"{nasty}"}}"#),
        format!(r#"{{"type":"hello","protocol":1,"{nasty}":1}}"#),
        format!(r#"{{"type":"command","id":1,"name":"touch","{nasty}":1,"{nasty}":2}}"#),
        format!(
            r#"{{"type":"command","id":1,"name":"set_formation","formation":"{nasty}","method":"{nasty}"}}"#
        ),
    ];
    for line in &lines {
        let text = err(line).to_string();
        assert!(
            !text.chars().any(needs_escape),
            "{line}: a control character in {text:?}"
        );
    }
}
