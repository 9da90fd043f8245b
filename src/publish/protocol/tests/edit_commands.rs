//! `edit.load` and `edit.save` name entries of the daemon's edit directory, never
//! paths (issue 27, finding 1): the old `path` is refused saying what to use, an
//! `entry` that is not a file name is refused before anything is asked of the
//! daemon.

use crate::publish::protocol::{parse_client_message, ClientMessage, ProtocolError};
use crate::vocab::Command;
use serde_json::Value;

fn command(line: &str) -> Result<Command, String> {
    match parse_client_message(line.as_bytes()) {
        Ok(ClientMessage::Command { command, .. }) => Ok(command),
        Ok(other) => panic!("not a command: {other:?}"),
        Err(e) => {
            assert!(!e.is_fatal(), "{e}");
            assert!(matches!(e, ProtocolError::InCommand { .. }), "{e}");
            assert_eq!(e.command_id(), Some(&Value::from(1)));
            Err(e.to_string())
        }
    }
}

#[test]
fn entries_parse() {
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.load","entry":"group.jsonl"}"#),
        Ok(Command::EditLoad {
            entry: "group.jsonl".into()
        })
    );
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.save","entry":"out.jsonl"}"#),
        Ok(Command::EditSave {
            entry: Some("out.jsonl".into()),
            overwrite: false
        })
    );
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.save","overwrite":true}"#),
        Ok(Command::EditSave {
            entry: None,
            overwrite: true
        })
    );
}

#[test]
fn a_path_is_refused_saying_to_name_an_entry() {
    for line in [
        r#"{"type":"command","id":1,"name":"edit.load","path":"/etc/shadow"}"#,
        r#"{"type":"command","id":1,"name":"edit.save","path":"/any/where.txt","overwrite":true}"#,
        r#"{"type":"command","id":1,"name":"edit.load","path":"group.jsonl"}"#,
    ] {
        let e = command(line).unwrap_err();
        assert!(
            e.contains("`path` is not taken") && e.contains("`entry`") && e.contains("`edit.dir`"),
            "{e}"
        );
    }
}

#[test]
fn entries_that_are_not_names_are_refused() {
    for (entry, what) in [
        (r#""/etc/shadow""#, "holds `/` at byte 0"),
        (r#""../x.jsonl""#, "holds `/` at byte 2"),
        (r#""..""#, "starts with `.`"),
        (r#""""#, "the name is empty"),
        (r#""a\u0000b""#, "holds '\\0' at byte 1"),
        (r#""a\u001b[2J""#, "holds '\\u{1b}' at byte 1"),
        ("42", "must be a file name (a string), got 42"),
    ] {
        for name in ["edit.load", "edit.save"] {
            let line = format!(r#"{{"type":"command","id":1,"name":"{name}","entry":{entry}}}"#);
            let e = command(&line).unwrap_err();
            assert!(
                e.starts_with(&format!("invalid arguments for command `{name}`: ")),
                "{e}"
            );
            assert!(e.contains(what), "{entry}: {e}");
        }
    }
}

/// `edit.select`, `edit.accept` and `edit.retime` with `ids` as a client sends
/// them (docs/protocol.md); a bad value or an unknown key is refused at its key.
#[test]
fn selection_accept_and_group_retime_parse() {
    assert_eq!(
        command(
            r#"{"type":"command","id":1,"name":"edit.select","lasso":[[2,1],[6.5,1],[6,4]],"window_s":[10,20],"ids":[3,7]}"#
        ),
        Ok(Command::EditSelect {
            lasso: Some(vec![[2.0, 1.0], [6.5, 1.0], [6.0, 4.0]]),
            window_s: Some([10.0, 20.0]),
            ids: Some(vec![3, 7]),
        })
    );
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.select"}"#),
        Ok(Command::EditSelect {
            lasso: None,
            window_s: None,
            ids: None,
        })
    );
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.accept"}"#),
        Ok(Command::EditAccept)
    );
    assert_eq!(
        command(r#"{"type":"command","id":1,"name":"edit.retime","at_s":1,"to_s":2,"ids":[4]}"#),
        Ok(Command::EditRetime {
            at_s: 1.0,
            to_s: 2.0,
            ids: Some(vec![4]),
        })
    );
    for (line, why) in [
        (
            r#"{"type":"command","id":1,"name":"edit.select","lasso":[[0,0],[0,null],[2,0]]}"#,
            "lasso[1] must be a point [x, y] of two numbers (m), got [0,null]",
        ),
        (
            r#"{"type":"command","id":1,"name":"edit.select","window_s":[1]}"#,
            "`window_s` must be [start, end]",
        ),
        (
            r#"{"type":"command","id":1,"name":"edit.retime","at_s":1,"to_s":2,"ids":[4,-1]}"#,
            "ids[1] must be a person id",
        ),
        (
            r#"{"type":"command","id":1,"name":"edit.select","rect":[0,0,1,1]}"#,
            "rect",
        ),
        (
            r#"{"type":"command","id":1,"name":"edit.accept","now":true}"#,
            "now",
        ),
    ] {
        let e = command(line).unwrap_err();
        assert!(e.contains(why), "{line}: {e}");
    }
}
