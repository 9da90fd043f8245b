//! Wire protocol v1: message types, the client-message parser and the encoders.
//!
//! Everything here is pure (bytes in, bytes out, no sockets, no clocks), so it is
//! tested as plain functions. The byte-level reference for renderer authors is
//! `docs/protocol.md`; keep the two in step.
//!
//! # Framing
//! * `json` clients (the default): one JSON object per line (`\n`), UTF-8.
//! * `binary` clients: every message is a frame, `u32` little-endian length of what
//!   follows, then a one-byte kind: [`FRAME_KIND_JSON`] (the rest is the same JSON
//!   object a `json` client gets, without the newline) or [`FRAME_KIND_SNAPSHOT`]
//!   (the binary snapshot layout of [`encode_snapshot_binary`]).
//!
//! # Hot path
//! Snapshots are encoded by hand ([`encode_snapshot_json`], [`encode_snapshot_binary`]):
//! coordinates are written as fixed 3-decimal numbers (millimetre, mm/s precision) from
//! scaled integers with `itoa`, never through float formatting. Everything else is
//! rare (events, stats, replies) and goes through serde.

use crate::geom::Vec2;
use crate::located::json_kind;
use crate::vocab::MotionType;
use crate::vocab::{ClientId, Command, Event, MeshView, Snapshot, StatsReport};
use serde_json::{Map, Value};

/// The protocol version this server speaks.
pub const PROTOCOL_VERSION: u32 = 1;

/// Longest client line accepted (bytes, without the newline); longer is a fatal error.
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// Largest coordinate magnitude written (m or m/s). Larger values and infinities are
/// clamped to it and NaN is written as 0, so the output is always valid JSON.
pub const MAX_COORD_ABS: f64 = 1.0e9;

/// Frame kind byte: the frame holds one JSON message (no trailing newline).
pub const FRAME_KIND_JSON: u8 = 1;
/// Frame kind byte: the frame holds a binary snapshot.
pub const FRAME_KIND_SNAPSHOT: u8 = 2;
/// Version byte of the binary snapshot layout.
pub const BINARY_SNAPSHOT_VERSION: u8 = 1;
/// Bytes from the start of a binary snapshot frame (length field included) to its
/// first array.
pub const BINARY_HEADER_BYTES: usize = 64;
/// Offset of the `u64` dropped count in a binary snapshot frame (length field included).
pub const BINARY_DROPPED_OFFSET: usize = 32;
/// `control` value of a binary touch record that drives no control.
pub const BINARY_NO_CONTROL: u32 = u32::MAX;
/// Bytes per touch record in a binary snapshot.
pub const BINARY_TOUCH_BYTES: usize = 16;

/// Binary snapshot flag: positions array present.
pub const FLAG_POSITIONS: u16 = 1 << 0;
/// Binary snapshot flag: velocities array present.
pub const FLAG_VELOCITIES: u16 = 1 << 1;
/// Binary snapshot flag: goals array present.
pub const FLAG_GOALS: u16 = 1 << 2;
/// Binary snapshot flag: assignment array present.
pub const FLAG_ASSIGNMENT: u16 = 1 << 3;
/// Binary snapshot flag: touch records present.
pub const FLAG_TOUCHES: u16 = 1 << 4;
/// Binary snapshot flag: the simulation is paused.
pub const FLAG_PAUSED: u16 = 1 << 5;
/// Binary snapshot flag: `latency_us` is valid (otherwise it is 0 and means "none").
pub const FLAG_LATENCY: u16 = 1 << 6;
/// Binary snapshot flag: the motions array is present (the client named `motions` in
/// its `fields` and the daemon runs a scene).
pub const FLAG_MOTIONS: u16 = 1 << 7;

/// Wire code of each motion type in a binary snapshot's motions array, one byte per
/// agent. The numbering is part of protocol 1: codes are never renumbered or reused,
/// a new motion type gets the next free code (clients must tolerate codes they do
/// not know). Documented in `docs/protocol.md`.
pub const MOTION_CODES: [(u8, MotionType); 7] = [
    (0, MotionType::Run),
    (1, MotionType::Crawl),
    (2, MotionType::Duck),
    (3, MotionType::Swim),
    (4, MotionType::Jump),
    (5, MotionType::ClimbUp),
    (6, MotionType::ClimbDown),
];

/// The binary wire code of a motion type (see [`MOTION_CODES`]).
pub fn motion_code(m: MotionType) -> u8 {
    match m {
        MotionType::Run => 0,
        MotionType::Crawl => 1,
        MotionType::Duck => 2,
        MotionType::Swim => 3,
        MotionType::Jump => 4,
        MotionType::ClimbUp => 5,
        MotionType::ClimbDown => 6,
    }
}

/// The motion type of a binary wire code; `None` for a code this version does not
/// know.
pub fn motion_from_code(code: u8) -> Option<MotionType> {
    MOTION_CODES
        .iter()
        .find(|(c, _)| *c == code)
        .map(|(_, m)| *m)
}

/// How a client wants its messages.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub enum Format {
    /// One JSON object per line.
    #[default]
    Json,
    /// Length-prefixed frames; snapshots in the binary layout.
    Binary,
}

impl Format {
    /// Name on the wire.
    pub fn as_str(self) -> &'static str {
        match self {
            Format::Json => "json",
            Format::Binary => "binary",
        }
    }
}

/// Which message streams a client receives. Replies (`hello`, `ack`, `error`,
/// `dropped`, `bye`) are always sent.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Subscriptions {
    /// `snapshot` messages.
    pub snapshot: bool,
    /// `mesh` messages.
    pub mesh: bool,
    /// Events: `control`, `gesture`, `reset`, `paused`.
    pub events: bool,
    /// `stats` messages.
    pub stats: bool,
}

impl Subscriptions {
    /// Every stream (the default).
    pub const ALL: Subscriptions = Subscriptions {
        snapshot: true,
        mesh: true,
        events: true,
        stats: true,
    };
    /// No stream.
    pub const NONE: Subscriptions = Subscriptions {
        snapshot: false,
        mesh: false,
        events: false,
        stats: false,
    };
    /// Wire names known to the parser, in wire order.
    pub const NAMES: [&'static str; 4] = ["snapshot", "mesh", "events", "stats"];

    /// The names of the streams switched on, in wire order.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [self.snapshot, self.mesh, self.events, self.stats];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    fn set(&mut self, name: &str) -> bool {
        match name {
            "snapshot" => self.snapshot = true,
            "mesh" => self.mesh = true,
            "events" => self.events = true,
            "stats" => self.stats = true,
            _ => return false,
        }
        true
    }
}

impl Default for Subscriptions {
    fn default() -> Self {
        Subscriptions::ALL
    }
}

/// Which per-agent arrays a snapshot carries.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct FieldSet {
    /// `positions`.
    pub positions: bool,
    /// `velocities`.
    pub velocities: bool,
    /// `goals` (goal positions).
    pub goals: bool,
    /// `assignment` (goal index per agent) and `assignment_seq`.
    pub assignment: bool,
    /// `touches`.
    pub touches: bool,
    /// `motions` (each agent's motion type on its terrain; sent only when the daemon
    /// runs a scene). Binary clients get it only when they name it in `fields`
    /// ([`FieldSet::BINARY_DEFAULT`]).
    pub motions: bool,
}

impl FieldSet {
    /// Every field (the default).
    pub const ALL: FieldSet = FieldSet {
        positions: true,
        velocities: true,
        goals: true,
        assignment: true,
        touches: true,
        motions: true,
    };
    /// What a binary client gets when its `hello` has no `fields`: every array of
    /// the original binary layout, not `motions`, so a client written before the
    /// motions array existed keeps its exact layout. Naming `motions` adds it.
    pub const BINARY_DEFAULT: FieldSet = FieldSet {
        motions: false,
        ..FieldSet::ALL
    };
    /// The fields a `hello` without `fields` gets in `format`.
    pub fn default_for(format: Format) -> FieldSet {
        match format {
            Format::Json => FieldSet::ALL,
            Format::Binary => FieldSet::BINARY_DEFAULT,
        }
    }
    /// No per-agent array: only the scalar header fields.
    pub const NONE: FieldSet = FieldSet {
        positions: false,
        velocities: false,
        goals: false,
        assignment: false,
        touches: false,
        motions: false,
    };
    /// Wire names known to the parser, in wire order.
    pub const NAMES: [&'static str; 6] = [
        "positions",
        "velocities",
        "goals",
        "assignment",
        "touches",
        "motions",
    ];

    /// The names of the fields switched on, in wire order.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [
            self.positions,
            self.velocities,
            self.goals,
            self.assignment,
            self.touches,
            self.motions,
        ];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    /// The binary flag bits for this set's arrays that every snapshot carries when
    /// asked ([`FLAG_MOTIONS`] also needs a scene: see [`encode_snapshot_binary`]).
    pub fn flags(&self) -> u16 {
        let mut f = 0;
        if self.positions {
            f |= FLAG_POSITIONS;
        }
        if self.velocities {
            f |= FLAG_VELOCITIES;
        }
        if self.goals {
            f |= FLAG_GOALS;
        }
        if self.assignment {
            f |= FLAG_ASSIGNMENT;
        }
        if self.touches {
            f |= FLAG_TOUCHES;
        }
        f
    }

    fn set(&mut self, name: &str) -> bool {
        match name {
            "positions" => self.positions = true,
            "velocities" => self.velocities = true,
            "goals" => self.goals = true,
            "assignment" => self.assignment = true,
            "touches" => self.touches = true,
            "motions" => self.motions = true,
            _ => return false,
        }
        true
    }
}

impl Default for FieldSet {
    fn default() -> Self {
        FieldSet::ALL
    }
}

/// What one client asked for. A client `hello` replaces all of it; omitted keys take
/// the defaults ([`ClientSettings::default`]: JSON, every stream, full rate, every field).
#[derive(Copy, Clone, Debug, PartialEq, Default)]
pub struct ClientSettings {
    /// Wire format.
    pub format: Format,
    /// Streams received.
    pub subscriptions: Subscriptions,
    /// Most snapshots per second, `None` for every tick.
    pub max_rate_hz: Option<f64>,
    /// Arrays in each snapshot.
    pub fields: FieldSet,
}

impl ClientSettings {
    /// Smallest interval between two snapshots for this client (µs), if rate limited.
    pub fn min_interval_us(&self) -> Option<u64> {
        // `as` saturates: a tiny rate gives u64::MAX (effectively "once").
        self.max_rate_hz.map(|hz| (1.0e6 / hz).round() as u64)
    }
}

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
        "unknown command `{name}` (known: reset, set_agent_count, set_formation, pause, resume)"
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

fn quote(v: &Value) -> String {
    let s = v.to_string();
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
    let value: Value = serde_json::from_slice(line).map_err(|e| {
        let full = e.to_string();
        // serde_json appends " at line L column C"; the line is always 1 here.
        let reason = match full.rfind(" at line ") {
            Some(i) => full[..i].to_string(),
            None => full,
        };
        ProtocolError::NotJson {
            column: e.column().max(1),
            reason,
        }
    })?;
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
            "a list of \"snapshot\", \"mesh\", \"events\", \"stats\"",
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
    if !matches!(
        name.as_str(),
        "reset" | "set_agent_count" | "set_formation" | "pause" | "resume"
    ) {
        return Err(in_command(
            id,
            ProtocolError::UnknownCommand {
                name: shorten(&name),
            },
        ));
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
                reason: e.to_string(),
            },
        )),
    }
}

// ---------------------------------------------------------------------------------
// Number writing (hot path).

/// "00" to "99": two decimal digits per table lookup.
const DIGIT_PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Bytes enough for one fixed-3 number: sign, 10 integer digits (|v| ≤ 1e9), point, 3 decimals.
const FIXED3_MAX_BYTES: usize = 16;

/// Writes `v` as a fixed 3-decimal number (`-12.345`) right-aligned into `buf`,
/// returning where it starts. It is the integer `round(v * 1000)` with a point
/// before its last three digits; NaN is written as `0.000` and |v| is clamped to
/// [`MAX_COORD_ABS`].
#[inline]
fn fmt_fixed3(v: f64, buf: &mut [u8; FIXED3_MAX_BYTES]) -> usize {
    let v = sanitize(v);
    // Round half away from zero; `as` truncates toward zero.
    let scaled = (v * 1000.0 + 0.5f64.copysign(v)) as i64;
    let mag = scaled.unsigned_abs();
    let frac = (mag % 1000) as usize;
    let mut int = mag / 1000;
    let mut i = FIXED3_MAX_BYTES - 4;
    buf[i] = b'.';
    buf[i + 1] = b'0' + (frac / 100) as u8;
    buf[i + 2..i + 4].copy_from_slice(&DIGIT_PAIRS[2 * (frac % 100)..2 * (frac % 100) + 2]);
    while int >= 100 {
        let pair = (int % 100) as usize;
        int /= 100;
        i -= 2;
        buf[i..i + 2].copy_from_slice(&DIGIT_PAIRS[2 * pair..2 * pair + 2]);
    }
    if int >= 10 {
        i -= 2;
        let pair = int as usize;
        buf[i..i + 2].copy_from_slice(&DIGIT_PAIRS[2 * pair..2 * pair + 2]);
    } else {
        i -= 1;
        buf[i] = b'0' + int as u8;
    }
    if scaled < 0 {
        i -= 1;
        buf[i] = b'-';
    }
    i
}

/// Appends `v` as a fixed 3-decimal number (see [`fmt_fixed3`]).
#[inline]
fn push_fixed3(out: &mut Vec<u8>, v: f64) {
    let mut buf = [0u8; FIXED3_MAX_BYTES];
    let at = fmt_fixed3(v, &mut buf);
    out.extend_from_slice(&buf[at..]);
}

/// Appends `x,y` as two fixed 3-decimal numbers with one copy.
#[inline]
fn push_fixed3_pair(out: &mut Vec<u8>, p: Vec2) {
    let mut bx = [0u8; FIXED3_MAX_BYTES];
    let mut by = [0u8; FIXED3_MAX_BYTES];
    let ax = fmt_fixed3(p.x, &mut bx);
    let ay = fmt_fixed3(p.y, &mut by);
    let mut pair = [0u8; 2 * FIXED3_MAX_BYTES + 1];
    let nx = FIXED3_MAX_BYTES - ax;
    let ny = FIXED3_MAX_BYTES - ay;
    pair[..nx].copy_from_slice(&bx[ax..]);
    pair[nx] = b',';
    pair[nx + 1..nx + 1 + ny].copy_from_slice(&by[ay..]);
    out.extend_from_slice(&pair[..nx + 1 + ny]);
}

#[inline]
fn sanitize(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(-MAX_COORD_ABS, MAX_COORD_ABS)
    }
}

#[inline]
fn push_uint(out: &mut Vec<u8>, v: impl itoa::Integer, buf: &mut itoa::Buffer) {
    out.extend_from_slice(buf.format(v).as_bytes());
}

/// Appends `[x0,y0,x1,y1,…]`.
fn push_flat_vec2(out: &mut Vec<u8>, it: impl Iterator<Item = Vec2>) {
    out.push(b'[');
    let mut first = true;
    for p in it {
        if !first {
            out.push(b',');
        }
        first = false;
        push_fixed3_pair(out, p);
    }
    out.push(b']');
}

fn push_u32_list(out: &mut Vec<u8>, it: impl Iterator<Item = u32>, buf: &mut itoa::Buffer) {
    out.push(b'[');
    let mut first = true;
    for v in it {
        if !first {
            out.push(b',');
        }
        first = false;
        push_uint(out, v, buf);
    }
    out.push(b']');
}

/// Rough bytes of a JSON snapshot, to reserve once.
fn json_size_hint(s: &Snapshot, fields: &FieldSet) -> usize {
    let per_agent = 18 * (usize::from(fields.positions) + usize::from(fields.velocities))
        + 6 * usize::from(fields.assignment);
    256 + s.agents.len() * per_agent
        + usize::from(fields.goals) * 18 * s.goals.len()
        + usize::from(fields.touches) * 64 * s.touches.len()
        + usize::from(fields.motions) * 13 * s.motions.len()
}

/// Writes the part of a JSON snapshot before the dropped count; returns nothing.
fn snapshot_json_head(
    s: &Snapshot,
    latency_us: Option<u64>,
    out: &mut Vec<u8>,
    b: &mut itoa::Buffer,
) {
    out.extend_from_slice(b"{\"type\":\"snapshot\",\"seq\":");
    push_uint(out, s.seq, b);
    out.extend_from_slice(b",\"t_us\":");
    push_uint(out, s.t.0, b);
    out.extend_from_slice(b",\"latency_us\":");
    match latency_us {
        Some(l) => push_uint(out, l, b),
        None => out.extend_from_slice(b"null"),
    }
    // The input event's own CLOCK_MONOTONIC time (the kernel timestamp), so a client
    // on the same machine can measure input → its own read without the daemon's help.
    out.extend_from_slice(b",\"input_t_us\":");
    match s.input_t {
        Some(t) => push_uint(out, t.0, b),
        None => out.extend_from_slice(b"null"),
    }
    out.extend_from_slice(b",\"dropped\":");
}

/// Writes the part of a JSON snapshot after the dropped count, newline included.
fn snapshot_json_tail(s: &Snapshot, fields: &FieldSet, out: &mut Vec<u8>, b: &mut itoa::Buffer) {
    out.extend_from_slice(b",\"agents\":");
    push_uint(out, s.agents.len(), b);
    out.extend_from_slice(if s.paused {
        b",\"paused\":true"
    } else {
        b",\"paused\":false"
    });
    if fields.positions {
        out.extend_from_slice(b",\"positions\":");
        push_flat_vec2(out, s.agents.iter().map(|a| a.pos));
    }
    if fields.velocities {
        out.extend_from_slice(b",\"velocities\":");
        push_flat_vec2(out, s.agents.iter().map(|a| a.vel));
    }
    if fields.goals {
        out.extend_from_slice(b",\"goals\":");
        push_flat_vec2(out, s.goals.iter().copied());
    }
    if fields.assignment {
        out.extend_from_slice(b",\"assignment_seq\":");
        push_uint(out, s.assignment_seq, b);
        out.extend_from_slice(b",\"assignment\":");
        push_u32_list(out, s.agents.iter().map(|a| a.goal), b);
    }
    if fields.touches {
        out.extend_from_slice(b",\"touches\":[");
        for (i, t) in s.touches.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            out.extend_from_slice(b"{\"id\":");
            push_uint(out, t.id, b);
            out.extend_from_slice(b",\"x\":");
            push_fixed3(out, t.pos.x);
            out.extend_from_slice(b",\"y\":");
            push_fixed3(out, t.pos.y);
            out.extend_from_slice(b",\"control\":");
            match t.control {
                Some(c) => push_uint(out, c, b),
                None => out.extend_from_slice(b"null"),
            }
            out.push(b'}');
        }
        out.push(b']');
    }
    if fields.motions && !s.motions.is_empty() {
        out.extend_from_slice(b",\"motions\":[");
        for (i, m) in s.motions.iter().enumerate() {
            if i > 0 {
                out.push(b',');
            }
            out.push(b'"');
            out.extend_from_slice(m.as_str().as_bytes());
            out.push(b'"');
        }
        out.push(b']');
    }
    out.extend_from_slice(b"}\n");
}

/// Appends one `snapshot` JSON line (newline included) to `out`.
///
/// Arrays are flat: `positions` is `[x0,y0,x1,y1,…]` (m), `velocities` likewise (m/s),
/// `goals` `[gx0,gy0,…]` (m), `assignment` one goal index per agent. Numbers have
/// exactly 3 decimals (mm precision).
///
/// # Complexity
/// O(agents + goals + touches), one reservation (`benches/publish_encode.rs`
/// measures it).
pub fn encode_snapshot_json(
    s: &Snapshot,
    latency_us: Option<u64>,
    dropped: u64,
    fields: &FieldSet,
    out: &mut Vec<u8>,
) {
    let mut b = itoa::Buffer::new();
    out.reserve(json_size_hint(s, fields));
    snapshot_json_head(s, latency_us, out, &mut b);
    push_uint(out, dropped, &mut b);
    snapshot_json_tail(s, fields, out, &mut b);
}

/// Like [`encode_snapshot_json`] but leaves the dropped count out, returning the
/// byte offset where it belongs, so the bytes can be shared by every client and each
/// writer splices in its own count.
pub fn encode_snapshot_json_shared(
    s: &Snapshot,
    latency_us: Option<u64>,
    fields: &FieldSet,
    out: &mut Vec<u8>,
) -> usize {
    let mut b = itoa::Buffer::new();
    out.reserve(json_size_hint(s, fields));
    snapshot_json_head(s, latency_us, out, &mut b);
    let at = out.len();
    snapshot_json_tail(s, fields, out, &mut b);
    at
}

/// Splices a dropped count into bytes from [`encode_snapshot_json_shared`].
pub fn splice_dropped_json(shared: &[u8], at: usize, dropped: u64, out: &mut Vec<u8>) {
    let at = at.min(shared.len());
    out.reserve(shared.len() + 20);
    out.extend_from_slice(&shared[..at]);
    out.extend_from_slice(itoa::Buffer::new().format(dropped).as_bytes());
    out.extend_from_slice(&shared[at..]);
}

/// `bytes` rounded up to a multiple of 4, so the next array stays 4-byte aligned.
#[inline]
fn padded4(bytes: usize) -> usize {
    bytes.div_ceil(4) * 4
}

#[inline]
fn push_f32(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(&(sanitize(v) as f32).to_le_bytes());
}

/// Appends one binary snapshot frame to `out`.
///
/// # Layout (all little-endian; offsets from the frame start)
/// ```text
///  0 u32 length of the rest of the frame      24 u64 latency_us (FLAG_LATENCY)
///  4 u8  kind = 2 (FRAME_KIND_SNAPSHOT)       32 u64 dropped
///  5 u8  version = 1                          40 u64 assignment_seq
///  6 u16 flags (FLAG_*)                       48 u32 agents n
///  8 u64 seq                                  52 u32 goals g
/// 16 u64 t_us                                 56 u32 touches k
///                                             60 u32 reserved (0)
/// 64 positions  f32[2n]  if FLAG_POSITIONS    x0,y0,x1,y1,…  (m)
///    velocities f32[2n]  if FLAG_VELOCITIES   (m/s)
///    goals      f32[2g]  if FLAG_GOALS        (m)
///    assignment u32[n]   if FLAG_ASSIGNMENT
///    touches    k × {u32 id, u32 control (0xFFFFFFFF = none), f32 x, f32 y} if FLAG_TOUCHES
///    motions    u8[n], zero-padded to a multiple of 4 bytes, if FLAG_MOTIONS
/// ```
/// Counts are always the true counts; an array is present only when its flag is set.
/// `motions` ([`motion_code`] per agent) is sent when `fields.motions` is set and the
/// snapshot has one motion per agent (the daemon runs a scene); without it the frame
/// is byte for byte the layout that had no motions array.
///
/// # Complexity
/// O(agents + goals + touches), one reservation.
pub fn encode_snapshot_binary(
    s: &Snapshot,
    latency_us: Option<u64>,
    dropped: u64,
    fields: &FieldSet,
    out: &mut Vec<u8>,
) {
    let start = out.len();
    let n = s.agents.len();
    let g = s.goals.len();
    let k = s.touches.len();
    let motions = fields.motions && n > 0 && s.motions.len() == n;
    let mut flags = fields.flags();
    if s.paused {
        flags |= FLAG_PAUSED;
    }
    if latency_us.is_some() {
        flags |= FLAG_LATENCY;
    }
    if motions {
        flags |= FLAG_MOTIONS;
    }
    let body = 8 * n * (usize::from(fields.positions) + usize::from(fields.velocities))
        + 8 * g * usize::from(fields.goals)
        + 4 * n * usize::from(fields.assignment)
        + BINARY_TOUCH_BYTES * k * usize::from(fields.touches)
        + padded4(n) * usize::from(motions);
    out.reserve(BINARY_HEADER_BYTES + body);
    out.extend_from_slice(&[0; 4]); // length, patched below
    out.push(FRAME_KIND_SNAPSHOT);
    out.push(BINARY_SNAPSHOT_VERSION);
    out.extend_from_slice(&flags.to_le_bytes());
    out.extend_from_slice(&s.seq.to_le_bytes());
    out.extend_from_slice(&s.t.0.to_le_bytes());
    out.extend_from_slice(&latency_us.unwrap_or(0).to_le_bytes());
    out.extend_from_slice(&dropped.to_le_bytes());
    out.extend_from_slice(&s.assignment_seq.to_le_bytes());
    for c in [n, g, k] {
        out.extend_from_slice(&u32::try_from(c).unwrap_or(u32::MAX).to_le_bytes());
    }
    out.extend_from_slice(&[0; 4]);
    debug_assert_eq!(out.len() - start, BINARY_HEADER_BYTES);
    if fields.positions {
        for a in &s.agents {
            push_f32(out, a.pos.x);
            push_f32(out, a.pos.y);
        }
    }
    if fields.velocities {
        for a in &s.agents {
            push_f32(out, a.vel.x);
            push_f32(out, a.vel.y);
        }
    }
    if fields.goals {
        for p in &s.goals {
            push_f32(out, p.x);
            push_f32(out, p.y);
        }
    }
    if fields.assignment {
        for a in &s.agents {
            out.extend_from_slice(&a.goal.to_le_bytes());
        }
    }
    if fields.touches {
        for t in &s.touches {
            out.extend_from_slice(&t.id.to_le_bytes());
            out.extend_from_slice(&t.control.unwrap_or(BINARY_NO_CONTROL).to_le_bytes());
            push_f32(out, t.pos.x);
            push_f32(out, t.pos.y);
        }
    }
    if motions {
        out.extend(s.motions.iter().map(|&m| motion_code(m)));
        out.resize(out.len() + padded4(n) - n, 0);
    }
    let len = u32::try_from(out.len() - start - 4).unwrap_or(u32::MAX);
    out[start..start + 4].copy_from_slice(&len.to_le_bytes());
}

/// Wraps one JSON message (with or without its trailing newline) in a binary frame:
/// `u32` LE length, [`FRAME_KIND_JSON`], the JSON bytes without the newline.
pub fn frame_json(json: &[u8], out: &mut Vec<u8>) {
    let json = json.strip_suffix(b"\n").unwrap_or(json);
    let len = u32::try_from(json.len() + 1).unwrap_or(u32::MAX);
    out.reserve(json.len() + 5);
    out.extend_from_slice(&len.to_le_bytes());
    out.push(FRAME_KIND_JSON);
    out.extend_from_slice(json);
}

/// Why a binary frame could not be decoded.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// Fewer bytes than the layout needs.
    #[error("frame is truncated: {need} bytes needed, {have} present")]
    Truncated {
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        have: usize,
    },
    /// The frame holds something else.
    #[error("frame kind {kind} is not a binary snapshot")]
    NotASnapshot {
        /// Its kind byte.
        kind: u8,
    },
    /// A layout version this code does not read.
    #[error("binary snapshot version {version} is not supported")]
    UnsupportedVersion {
        /// Its version byte.
        version: u8,
    },
}

/// One touch of a decoded binary snapshot.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BinaryTouch {
    /// Contact id.
    pub id: u32,
    /// Control driven, if any.
    pub control: Option<u32>,
    /// Position (m).
    pub pos: [f32; 2],
}

/// A decoded binary snapshot (for clients and tests).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct BinarySnapshot {
    /// Tick sequence number.
    pub seq: u64,
    /// Tick time (µs).
    pub t_us: u64,
    /// Input-to-encode latency (µs).
    pub latency_us: Option<u64>,
    /// Snapshots this client lost so far.
    pub dropped: u64,
    /// Tick the assignment was solved on.
    pub assignment_seq: u64,
    /// Simulation paused.
    pub paused: bool,
    /// Agent count.
    pub agents: u32,
    /// Goal count.
    pub goal_count: u32,
    /// Positions (m), when sent.
    pub positions: Option<Vec<[f32; 2]>>,
    /// Velocities (m/s), when sent.
    pub velocities: Option<Vec<[f32; 2]>>,
    /// Goal positions (m), when sent.
    pub goals: Option<Vec<[f32; 2]>>,
    /// Goal index per agent, when sent.
    pub assignment: Option<Vec<u32>>,
    /// Touches, when sent.
    pub touches: Option<Vec<BinaryTouch>>,
    /// Each agent's motion wire code ([`motion_from_code`] gives the type), when
    /// sent.
    pub motions: Option<Vec<u8>>,
}

fn rd_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0; 4];
    a.copy_from_slice(&b[at..at + 4]);
    u32::from_le_bytes(a)
}

fn rd_u64(b: &[u8], at: usize) -> u64 {
    let mut a = [0; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

fn rd_f32(b: &[u8], at: usize) -> f32 {
    f32::from_bits(rd_u32(b, at))
}

/// Decodes a binary snapshot frame (length field included; bytes after the frame
/// are ignored).
///
/// # Errors
/// [`DecodeError`] when the frame is short, of another kind or another version.
pub fn decode_snapshot_binary(frame: &[u8]) -> Result<BinarySnapshot, DecodeError> {
    let have = frame.len();
    if have < BINARY_HEADER_BYTES {
        return Err(DecodeError::Truncated {
            need: BINARY_HEADER_BYTES,
            have,
        });
    }
    if frame[4] != FRAME_KIND_SNAPSHOT {
        return Err(DecodeError::NotASnapshot { kind: frame[4] });
    }
    if frame[5] != BINARY_SNAPSHOT_VERSION {
        return Err(DecodeError::UnsupportedVersion { version: frame[5] });
    }
    let total = 4 + rd_u32(frame, 0) as usize;
    let flags = u16::from_le_bytes([frame[6], frame[7]]);
    let n = rd_u32(frame, 48) as usize;
    let g = rd_u32(frame, 52) as usize;
    let k = rd_u32(frame, 56) as usize;
    let has = |f: u16| flags & f != 0;
    let need = BINARY_HEADER_BYTES
        + 8 * n * (usize::from(has(FLAG_POSITIONS)) + usize::from(has(FLAG_VELOCITIES)))
        + 8 * g * usize::from(has(FLAG_GOALS))
        + 4 * n * usize::from(has(FLAG_ASSIGNMENT))
        + BINARY_TOUCH_BYTES * k * usize::from(has(FLAG_TOUCHES))
        + padded4(n) * usize::from(has(FLAG_MOTIONS));
    if total < need || have < need {
        return Err(DecodeError::Truncated {
            need,
            have: have.min(total),
        });
    }
    let mut at = BINARY_HEADER_BYTES;
    let mut pairs = |count: usize| {
        let v: Vec<[f32; 2]> = (0..count)
            .map(|i| [rd_f32(frame, at + 8 * i), rd_f32(frame, at + 8 * i + 4)])
            .collect();
        at += 8 * count;
        v
    };
    let positions = has(FLAG_POSITIONS).then(|| pairs(n));
    let velocities = has(FLAG_VELOCITIES).then(|| pairs(n));
    let goals = has(FLAG_GOALS).then(|| pairs(g));
    let assignment = has(FLAG_ASSIGNMENT).then(|| {
        let v: Vec<u32> = (0..n).map(|i| rd_u32(frame, at + 4 * i)).collect();
        at += 4 * n;
        v
    });
    let touches = has(FLAG_TOUCHES).then(|| {
        (0..k)
            .map(|i| {
                let o = at + BINARY_TOUCH_BYTES * i;
                let c = rd_u32(frame, o + 4);
                BinaryTouch {
                    id: rd_u32(frame, o),
                    control: (c != BINARY_NO_CONTROL).then_some(c),
                    pos: [rd_f32(frame, o + 8), rd_f32(frame, o + 12)],
                }
            })
            .collect()
    });
    at += BINARY_TOUCH_BYTES * k * usize::from(has(FLAG_TOUCHES));
    let motions = has(FLAG_MOTIONS).then(|| frame[at..at + n].to_vec());
    Ok(BinarySnapshot {
        seq: rd_u64(frame, 8),
        t_us: rd_u64(frame, 16),
        latency_us: has(FLAG_LATENCY).then(|| rd_u64(frame, 24)),
        dropped: rd_u64(frame, BINARY_DROPPED_OFFSET),
        assignment_seq: rd_u64(frame, 40),
        paused: has(FLAG_PAUSED),
        agents: n as u32,
        goal_count: g as u32,
        positions,
        velocities,
        goals,
        assignment,
        touches,
        motions,
    })
}

// ---------------------------------------------------------------------------------
// Other messages (rare; serde where convenient).

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

/// Appends one `mesh` JSON line: `vertices` flat `[x0,y0,…]` (m, 3 decimals),
/// `triangles` flat `[a0,b0,c0,a1,…]` only when `with_triangles`, `outline` always.
///
/// # Complexity
/// O(vertices + triangles + outline).
pub fn encode_mesh_json(m: &MeshView, with_triangles: bool, out: &mut Vec<u8>) {
    let mut b = itoa::Buffer::new();
    out.reserve(
        128 + 18 * m.vertices.len()
            + 6 * m.outline.len()
            + usize::from(with_triangles) * 20 * m.triangles.len(),
    );
    out.extend_from_slice(b"{\"type\":\"mesh\",\"seq\":");
    push_uint(out, m.seq, &mut b);
    out.extend_from_slice(b",\"topology\":");
    push_uint(out, m.topology, &mut b);
    out.extend_from_slice(b",\"vertices\":");
    push_flat_vec2(out, m.vertices.iter().copied());
    if with_triangles {
        out.extend_from_slice(b",\"triangles\":");
        push_u32_list(out, m.triangles.iter().flatten().copied(), &mut b);
    }
    out.extend_from_slice(b",\"outline\":");
    push_u32_list(out, m.outline.iter().copied(), &mut b);
    out.extend_from_slice(b"}\n");
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
    },
}

/// Appends one event JSON line (`control`, `gesture`, `reset`, `formation`, `paused`
/// or `device`).
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
            t_us: t.0,
        },
        Event::GestureEnd {
            id,
            fingers,
            contacts,
            duration_us,
            cancelled,
            t,
        } => Wire::Gesture {
            phase: "end",
            id: *id,
            fingers: Some(*fingers),
            contacts: Some(*contacts),
            duration_us: Some(*duration_us),
            cancelled: Some(*cancelled),
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

/// The server `hello`: static facts plus the settings in force for this client.
#[derive(Clone, Debug)]
pub struct ServerHello<'a> {
    /// Static facts.
    pub info: &'a HelloInfo,
    /// The client's id (appears in the daemon's log lines about it).
    pub client: ClientId,
    /// Current agent count.
    pub agents: u32,
    /// Settings now in force.
    pub settings: &'a ClientSettings,
    /// Snapshots queued for this client before the oldest are dropped.
    pub client_queue: u32,
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
    };
    push_json_line(out, &v);
}

/// Static facts sent in the server hello.
#[derive(Clone, Debug)]
pub struct HelloInfo {
    /// The world rectangle (m).
    pub world: crate::geom::Rect,
    /// Agent count at start (the hello reports the current count once snapshots flow).
    pub agents: u32,
    /// Agent radius (m).
    pub agent_radius_m: f64,
}

#[cfg(test)]
mod tests;
