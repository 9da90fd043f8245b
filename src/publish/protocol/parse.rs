//! Parsing client lines: `hello` (the settings a client asks for) and `command`,
//! with errors that say what is wrong and where.

use super::hello::{
    ClientSettings, FieldSet, Format, Subscriptions, MAX_LINE_BYTES, PROTOCOL_VERSION,
};
use super::unique_keys::{from_slice_unique, ReadError};
use crate::located::{check_entry_name, json_kind};
use crate::vocab::{ClientContact, Command, MAX_CLIENT_CONTACTS, MAX_CLIENT_CONTACT_ID};
use serde_json::{Map, Value};

/// A parsed client line.
#[derive(Clone, Debug, PartialEq)]
pub enum ClientMessage {
    /// `hello`: (re)negotiate format, subscriptions, rate and fields.
    Hello(ClientSettings),
    /// `command`: ask the daemon to do something; answered by `ack` or `error`.
    Command {
        /// The client's id for it (number or string), echoed in the reply.
        id: Value,
        /// What to do.
        command: Command,
    },
}

/// Why a client line is not a valid client message.
///
/// Every error is fatal (the server answers with `error` and disconnects) except
/// [`ProtocolError::InCommand`]: a well-framed `command` whose body is wrong is
/// answered with a non-fatal `error` echoing the command's id.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProtocolError {
    /// The line exceeds [`MAX_LINE_BYTES`].
    #[error("line is {len} bytes, more than the {max} byte limit")]
    LineTooLong {
        /// Its length (bytes, at least this many).
        len: usize,
        /// The limit.
        max: usize,
    },
    /// The line is not valid JSON.
    #[error("line is not JSON at column {column}: {reason}")]
    NotJson {
        /// 1-based column (byte) of the problem.
        column: usize,
        /// What the JSON parser expected.
        reason: String,
    },
    /// A key appears twice in one object (at any depth): refused rather than
    /// reading one of the two values.
    #[error("duplicate key `{key}` at column {column}: a key may appear once in an object")]
    DuplicateKey {
        /// The key (shortened, control characters escaped).
        key: String,
        /// 1-based column (byte) just past its second occurrence.
        column: usize,
    },
    /// The line is JSON but not an object.
    #[error("message is {found}, not a JSON object")]
    NotObject {
        /// What it is (`an array`, `a number`, ...).
        found: &'static str,
    },
    /// The object has no `type`.
    #[error("missing `type` in message")]
    MissingType,
    /// The `type` is not one a client may send.
    #[error("unknown message type {found} (a client sends \"hello\" or \"command\")")]
    UnknownType {
        /// The `type` value, as JSON (shortened).
        found: String,
    },
    /// A key the message does not have.
    #[error("unknown field `{field}` in {message}")]
    UnknownField {
        /// Message type.
        message: &'static str,
        /// The key.
        field: String,
    },
    /// A required key is absent.
    #[error("missing `{field}` in {message}")]
    MissingField {
        /// Message type.
        message: &'static str,
        /// The key.
        field: &'static str,
    },
    /// A key has a value of the wrong kind or out of range.
    #[error("`{field}` in {message} must be {expected}, got {found}")]
    InvalidValue {
        /// Message type.
        message: &'static str,
        /// The key.
        field: &'static str,
        /// What is allowed.
        expected: &'static str,
        /// The value, as JSON (shortened).
        found: String,
    },
    /// The client speaks another protocol version.
    #[error("protocol version {found} is not supported: this server speaks protocol {supported}")]
    VersionMismatch {
        /// The client's `protocol` value, as JSON.
        found: String,
        /// [`PROTOCOL_VERSION`].
        supported: u32,
    },
    /// A command name the daemon does not know.
    #[error(
        "unknown command `{name}` (known: reset, set_agent_count, set_formation, pause, resume, edit.load, edit.undo, edit.save, edit.retime, edit.select, edit.accept, edit.exit, touch)"
    )]
    UnknownCommand {
        /// The name sent (shortened).
        name: String,
    },
    /// The arguments do not fit the command.
    #[error("invalid arguments for command `{name}`: {reason}")]
    CommandArguments {
        /// Command name.
        name: String,
        /// What is wrong with them.
        reason: String,
    },
    /// A problem inside a `command` message; not fatal, answered with its id.
    #[error("{detail}")]
    InCommand {
        /// The command's id, or `null` when it had none usable.
        id: Value,
        /// The problem.
        detail: Box<ProtocolError>,
    },
}

impl ProtocolError {
    /// Whether the server disconnects the client after reporting this.
    pub fn is_fatal(&self) -> bool {
        !matches!(self, ProtocolError::InCommand { .. })
    }

    /// The id to echo in the `error` reply, when the message was a command with one.
    pub fn command_id(&self) -> Option<&Value> {
        match self {
            ProtocolError::InCommand { id, .. } if !id.is_null() => Some(id),
            _ => None,
        }
    }
}

/// Longest JSON rendering of a bad value quoted back in an error message.
const MAX_QUOTED_CHARS: usize = 40;

/// `v` as JSON, shortened, with every control character escaped: JSON escapes
/// U+0000–U+001F but not DEL, the C1 controls or the bidirectional overrides, and
/// the error may be logged or shown on a terminal.
fn quote(v: &Value) -> String {
    let s = crate::located::escape(&v.to_string());
    if s.chars().count() <= MAX_QUOTED_CHARS {
        s
    } else {
        let mut t: String = s.chars().take(MAX_QUOTED_CHARS).collect();
        t.push('…');
        t
    }
}

fn shorten(s: &str) -> String {
    quote(&Value::String(s.to_string()))
        .trim_matches('"')
        .to_string()
}

/// Parses one client line (without its newline; a trailing `\r` is ignored).
///
/// # Errors
/// A [`ProtocolError`] that says what is wrong and where (column for JSON syntax,
/// message and field otherwise). See [`ProtocolError::is_fatal`].
///
/// # Complexity
/// Linear in the line length; the line is capped at [`MAX_LINE_BYTES`] and serde_json
/// caps nesting depth, so arbitrary bytes cannot exhaust time or stack.
pub fn parse_client_message(line: &[u8]) -> Result<ClientMessage, ProtocolError> {
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    if line.len() > MAX_LINE_BYTES {
        return Err(ProtocolError::LineTooLong {
            len: line.len(),
            max: MAX_LINE_BYTES,
        });
    }
    let value: Value = match from_slice_unique(line) {
        Ok(v) => v,
        Err(ReadError::Duplicate { key, column }) => {
            return Err(duplicate_key(line, shorten(&key), column))
        }
        Err(ReadError::Json(e)) => {
            let full = e.to_string();
            // serde_json appends " at line L column C"; the line is always 1 here.
            let reason = match full.rfind(" at line ") {
                Some(i) => full[..i].to_string(),
                None => full,
            };
            return Err(ProtocolError::NotJson {
                column: e.column().max(1),
                reason: crate::located::escape(&reason),
            });
        }
    };
    let mut map = match value {
        Value::Object(m) => m,
        other => {
            return Err(ProtocolError::NotObject {
                found: json_kind(&other),
            })
        }
    };
    let ty = map.remove("type").ok_or(ProtocolError::MissingType)?;
    match ty.as_str() {
        Some("hello") => parse_hello(map).map(ClientMessage::Hello),
        Some("command") => parse_command(map),
        _ => Err(ProtocolError::UnknownType { found: quote(&ty) }),
    }
}

/// The error for a duplicate key: answered like any other problem of a command
/// (not fatal, with its id) when the line is a `command` with a usable id (read
/// again without the check, on this error path only), else fatal.
fn duplicate_key(line: &[u8], key: String, column: usize) -> ProtocolError {
    let detail = ProtocolError::DuplicateKey { key, column };
    let lenient: Option<Value> = serde_json::from_slice(line).ok();
    match lenient.as_ref().and_then(Value::as_object) {
        Some(m) if m.get("type").and_then(Value::as_str) == Some("command") => {
            let id = match m.get("id") {
                Some(v @ (Value::Number(_) | Value::String(_))) => v.clone(),
                _ => Value::Null,
            };
            ProtocolError::InCommand {
                id,
                detail: Box::new(detail),
            }
        }
        _ => detail,
    }
}

fn parse_hello(map: Map<String, Value>) -> Result<ClientSettings, ProtocolError> {
    const MSG: &str = "hello";
    for key in map.keys() {
        if !matches!(
            key.as_str(),
            "protocol" | "format" | "subscribe" | "max_rate_hz" | "fields"
        ) {
            return Err(ProtocolError::UnknownField {
                message: MSG,
                field: shorten(key),
            });
        }
    }
    match map.get("protocol") {
        None => {
            return Err(ProtocolError::MissingField {
                message: MSG,
                field: "protocol",
            })
        }
        Some(v) if v.as_u64() == Some(u64::from(PROTOCOL_VERSION)) => {}
        Some(v) if v.is_u64() => {
            return Err(ProtocolError::VersionMismatch {
                found: quote(v),
                supported: PROTOCOL_VERSION,
            })
        }
        Some(v) => {
            return Err(ProtocolError::InvalidValue {
                message: MSG,
                field: "protocol",
                expected: "a positive integer",
                found: quote(v),
            })
        }
    }
    let mut s = ClientSettings::default();
    match map.get("format") {
        None | Some(Value::Null) => {}
        Some(v) => {
            s.format = match v.as_str() {
                Some("json") => Format::Json,
                Some("binary") => Format::Binary,
                _ => {
                    return Err(ProtocolError::InvalidValue {
                        message: MSG,
                        field: "format",
                        expected: "\"json\" or \"binary\"",
                        found: quote(v),
                    })
                }
            }
        }
    }
    if let Some(v) = map.get("subscribe").filter(|v| !v.is_null()) {
        let mut subs = Subscriptions::NONE;
        names_into(
            v,
            "subscribe",
            "a list of \"snapshot\", \"mesh\", \"events\", \"stats\", \"plan\", \"transform\"",
            |n| subs.set(n),
        )?;
        s.subscriptions = subs;
    }
    match map.get("fields").filter(|v| !v.is_null()) {
        Some(v) => {
            let mut fields = FieldSet::NONE;
            names_into(
                v,
                "fields",
                "a list of \"positions\", \"velocities\", \"goals\", \"assignment\", \"touches\", \"motions\"",
                |n| fields.set(n),
            )?;
            s.fields = fields;
        }
        None => s.fields = FieldSet::default_for(s.format),
    }
    match map.get("max_rate_hz") {
        None | Some(Value::Null) => {}
        Some(v) => match v.as_f64() {
            Some(hz) if hz.is_finite() && hz > 0.0 => s.max_rate_hz = Some(hz),
            _ => {
                return Err(ProtocolError::InvalidValue {
                    message: MSG,
                    field: "max_rate_hz",
                    expected: "a positive number or null",
                    found: quote(v),
                })
            }
        },
    }
    Ok(s)
}

/// Applies every name of a JSON string array; `set` returns false for unknown names.
fn names_into(
    v: &Value,
    field: &'static str,
    expected: &'static str,
    mut set: impl FnMut(&str) -> bool,
) -> Result<(), ProtocolError> {
    let bad = |found: &Value| ProtocolError::InvalidValue {
        message: "hello",
        field,
        expected,
        found: quote(found),
    };
    let items = v.as_array().ok_or_else(|| bad(v))?;
    for item in items {
        match item.as_str() {
            Some(n) if set(n) => {}
            _ => return Err(bad(item)),
        }
    }
    Ok(())
}

fn parse_command(mut map: Map<String, Value>) -> Result<ClientMessage, ProtocolError> {
    const MSG: &str = "command";
    let in_command = |id: Value, detail: ProtocolError| ProtocolError::InCommand {
        id,
        detail: Box::new(detail),
    };
    let id = match map.remove("id") {
        None => {
            return Err(in_command(
                Value::Null,
                ProtocolError::MissingField {
                    message: MSG,
                    field: "id",
                },
            ))
        }
        Some(v @ (Value::Number(_) | Value::String(_))) => v,
        Some(v) => {
            return Err(in_command(
                Value::Null,
                ProtocolError::InvalidValue {
                    message: MSG,
                    field: "id",
                    expected: "a number or a string",
                    found: quote(&v),
                },
            ))
        }
    };
    let name = match map.get("name") {
        None => {
            return Err(in_command(
                id,
                ProtocolError::MissingField {
                    message: MSG,
                    field: "name",
                },
            ))
        }
        Some(Value::String(n)) => n.clone(),
        Some(v) => {
            let found = quote(v);
            return Err(in_command(
                id,
                ProtocolError::InvalidValue {
                    message: MSG,
                    field: "name",
                    expected: "a string",
                    found,
                },
            ));
        }
    };
    if !Command::NAMES.contains(&name.as_str()) {
        return Err(in_command(
            id,
            ProtocolError::UnknownCommand {
                name: shorten(&name),
            },
        ));
    }
    if name == "touch" {
        return match touch_contacts(&map) {
            Ok(contacts) => Ok(ClientMessage::Command {
                id,
                command: Command::Touch { contacts },
            }),
            Err(reason) => Err(in_command(
                id,
                ProtocolError::CommandArguments { name, reason },
            )),
        };
    }
    if name == "set_formation" {
        // serde's message would not name the field.
        type Check = (&'static str, &'static str, fn(&Value) -> bool);
        let checks: [Check; 2] = [
            ("method", "\"transform\" or \"mesh\"", |v| {
                v.is_null() || matches!(v.as_str(), Some("transform" | "mesh"))
            }),
            ("duration", "a number of seconds", |v| {
                v.is_null() || v.is_number()
            }),
        ];
        for (field, expected, ok) in checks {
            if let Some(v) = map.get(field).filter(|v| !ok(v)) {
                let found = quote(v);
                return Err(in_command(
                    id,
                    ProtocolError::InvalidValue {
                        message: MSG,
                        field,
                        expected,
                        found,
                    },
                ));
            }
        }
    }
    if name == "edit.select" || name == "edit.retime" {
        // serde's message would not name the key or the element.
        if let Err(reason) = edit_lists(&map) {
            return Err(in_command(
                id,
                ProtocolError::CommandArguments { name, reason },
            ));
        }
    }
    if name == "edit.load" || name == "edit.save" {
        if let Err(reason) = edit_entry(&name, &map) {
            return Err(in_command(
                id,
                ProtocolError::CommandArguments { name, reason },
            ));
        }
    }
    let keys: Vec<String> = map.keys().cloned().collect();
    match serde_json::from_value::<Command>(Value::Object(map)) {
        Ok(command) => {
            // serde ignores extra keys on unit variants (`pause`, `resume`) even with
            // `deny_unknown_fields`: every key sent must be one the command has.
            let known = serde_json::to_value(&command).unwrap_or(Value::Null);
            match keys.into_iter().find(|k| known.get(k).is_none()) {
                None => Ok(ClientMessage::Command { id, command }),
                Some(k) => Err(in_command(
                    id,
                    ProtocolError::CommandArguments {
                        name,
                        reason: format!("unknown field `{}`", shorten(&k)),
                    },
                )),
            }
        }
        Err(e) => Err(in_command(
            id,
            ProtocolError::CommandArguments {
                name,
                // serde quotes the value or key it did not expect as it was sent.
                reason: crate::located::escape(&e.to_string()),
            },
        )),
    }
}

/// Checks the file arguments of `edit.load` and `edit.save`: a client names an
/// `entry` of the daemon's edit directory, never a path. The old `path` is refused
/// saying so; an entry that is not a name ([`check_entry_name`]) is refused
/// without touching anything.
fn edit_entry(name: &str, map: &Map<String, Value>) -> Result<(), String> {
    if map.contains_key("path") {
        return Err(format!(
            "`path` is not taken: clients name files of the daemon's edit directory \
             (`edit.dir` in its config) with `entry`, e.g. {{\"name\":\"{name}\",\"entry\":\"group.jsonl\"}}"
        ));
    }
    match map.get("entry") {
        Some(Value::String(e)) => {
            check_entry_name(e).map_err(|e| format!("`entry` is not a file name: {e}"))
        }
        Some(Value::Null) | None => Ok(()),
        Some(v) => Err(format!(
            "`entry` must be a file name (a string), got {}",
            quote(v)
        )),
    }
}

/// The lists of `edit.select` and `edit.retime`, checked element by element so
/// that the error names the key and the element (`lasso[1] must be a point [x,
/// y] of two numbers (m), got [0,null]`); `null` is the key left out.
fn edit_lists(map: &Map<String, Value>) -> Result<(), String> {
    let list = |key: &str| match map.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::Array(a)) => Ok(Some(a)),
        Some(v) => Err(format!("`{key}` must be a list, got {}", quote(v))),
    };
    let pair = |v: &Value| {
        v.as_array()
            .is_some_and(|a| a.len() == 2 && a.iter().all(Value::is_number))
    };
    if let Some(l) = list("lasso")? {
        if let Some((i, v)) = l.iter().enumerate().find(|(_, v)| !pair(v)) {
            return Err(format!(
                "lasso[{i}] must be a point [x, y] of two numbers (m), got {}",
                quote(v)
            ));
        }
    }
    if let Some(w) = map.get("window_s").filter(|v| !v.is_null() && !pair(v)) {
        return Err(format!(
            "`window_s` must be [start, end], two numbers of seconds, got {}",
            quote(w)
        ));
    }
    if let Some(l) = list("ids")? {
        if let Some((i, v)) = l.iter().enumerate().find(|(_, v)| !v.is_u64()) {
            return Err(format!(
                "ids[{i}] must be a person id (an integer >= 0), got {}",
                quote(v)
            ));
        }
    }
    Ok(())
}

/// The contacts of a `touch` command, checked one by one so that the error names
/// the contact and the key (`contacts[2].x must be a number in [0, 1], got null`).
fn touch_contacts(map: &Map<String, Value>) -> Result<Vec<ClientContact>, String> {
    if let Some(k) = map
        .keys()
        .find(|k| !matches!(k.as_str(), "name" | "contacts"))
    {
        return Err(format!("unknown field `{}`", shorten(k)));
    }
    let list = match map.get("contacts") {
        None => {
            return Err(
                "missing `contacts` (a list of {\"id\", \"x\", \"y\"}; [] lifts all)".into(),
            )
        }
        Some(Value::Array(a)) => a,
        Some(v) => {
            return Err(format!(
                "`contacts` must be a list of {{\"id\", \"x\", \"y\"}}, got {}",
                quote(v)
            ))
        }
    };
    if list.len() > MAX_CLIENT_CONTACTS {
        return Err(format!(
            "{} contacts, more than the {MAX_CLIENT_CONTACTS} a touch may list",
            list.len()
        ));
    }
    let mut out: Vec<ClientContact> = Vec::with_capacity(list.len());
    for (k, c) in list.iter().enumerate() {
        let Value::Object(o) = c else {
            return Err(format!(
                "contacts[{k}] must be an object {{\"id\", \"x\", \"y\"}}, got {}",
                quote(c)
            ));
        };
        if let Some(key) = o
            .keys()
            .find(|key| !matches!(key.as_str(), "id" | "x" | "y"))
        {
            return Err(format!("contacts[{k}]: unknown field `{}`", shorten(key)));
        }
        let got = |key: &str| o.get(key).map_or("nothing".to_string(), quote);
        let id = o
            .get("id")
            .and_then(Value::as_u64)
            .filter(|&v| v <= u64::from(MAX_CLIENT_CONTACT_ID))
            .ok_or_else(|| {
                format!(
                    "contacts[{k}].id must be an integer in 0..={MAX_CLIENT_CONTACT_ID}, got {}",
                    got("id")
                )
            })?;
        let coord = |key: &str| {
            o.get(key)
                .and_then(Value::as_f64)
                .filter(|v| (0.0..=1.0).contains(v))
                .ok_or_else(|| {
                    format!(
                        "contacts[{k}].{key} must be a number in [0, 1] (table units), got {}",
                        got(key)
                    )
                })
        };
        let (x, y) = (coord("x")?, coord("y")?);
        let id = id as u32;
        if out.iter().any(|p| p.id == id) {
            return Err(format!("contacts[{k}].id {id} is listed twice"));
        }
        out.push(ClientContact { id, x, y });
    }
    Ok(out)
}
