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
//! rare (events, stats, replies) and goes through serde. Plans (`plan`,
//! `demo_motion`) are rare but large, and are written by hand like snapshots.
//!
//! # Files
//! * `hello`: the version, what a client negotiates ([`ClientSettings`]) and the
//!   server hello's facts.
//! * `parse`: client lines ([`parse_client_message`]); `unique_keys` reads them,
//!   refusing a key repeated in one object.
//! * `json`: the hand-written JSON snapshot and mesh.
//! * `messages`: events, stats, replies and the server hello.
//! * `frame`: frame kinds, the binary layout's constants and motion codes.
//! * `binary`: the binary snapshot encoder and decoder.
//! * `plan`: the hand-written `plan` and `demo_motion` messages.
//! * `transform`: a formation transform's `transform` and `transform_end` messages.
//! * `edit`: the edit mode's `tracks` and `edit` messages.
//! * `scene`: the scene's `scene` and `scene_poses` messages.
//! * `numbers`: fixed-point and integer writing shared by the hand-written encoders.

mod binary;
mod edit;
mod frame;
mod hello;
mod json;
mod messages;
mod numbers;
mod parse;
mod plan;
mod scene;
mod transform;
mod unique_keys;

pub use binary::{
    decode_snapshot_binary, encode_snapshot_binary, BinarySnapshot, BinaryTouch, DecodeError,
};
pub use edit::{encode_edit_json, encode_tracks_json};
pub use frame::{
    frame_json, motion_code, motion_from_code, BINARY_DROPPED_OFFSET, BINARY_HEADER_BYTES,
    BINARY_NO_CONTROL, BINARY_SNAPSHOT_VERSION, BINARY_TOUCH_BYTES, FLAG_ASSIGNMENT, FLAG_GOALS,
    FLAG_LATENCY, FLAG_MOTIONS, FLAG_PAUSED, FLAG_POSITIONS, FLAG_TOUCHES, FLAG_VELOCITIES,
    FRAME_KIND_JSON, FRAME_KIND_SNAPSHOT, MOTION_CODES,
};
pub use hello::{
    ClientSettings, FieldSet, Format, HelloInfo, ServerHello, Subscriptions, MAX_LINE_BYTES,
    PROTOCOL_VERSION,
};
pub use json::{
    encode_mesh_json, encode_snapshot_json, encode_snapshot_json_shared, splice_dropped_json,
};
pub use messages::{
    encode_ack, encode_bye, encode_dropped, encode_error, encode_event, encode_server_hello,
    encode_stats,
};
pub use numbers::MAX_COORD_ABS;
pub use parse::{parse_client_message, ClientMessage, ProtocolError};
pub use plan::encode_plan_json;
pub use scene::{encode_scene_json, encode_scene_poses_json};
pub use transform::{encode_transform_end_json, encode_transform_json};

#[cfg(test)]
mod tests;
