//! Framing for `binary` clients and the constants of the binary snapshot layout:
//! frame kinds, header offsets and sizes, flag bits, the motion wire codes, and
//! [`frame_json`] that wraps a JSON message in a frame.

use crate::vocab::MotionType;

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
