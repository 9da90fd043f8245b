//! The binary snapshot: its encoder (the layout is on [`encode_snapshot_binary`]) and
//! a decoder for clients and tests.

use super::frame::{
    motion_code, BINARY_DROPPED_OFFSET, BINARY_HEADER_BYTES, BINARY_NO_CONTROL,
    BINARY_SNAPSHOT_VERSION, BINARY_TOUCH_BYTES, FLAG_ASSIGNMENT, FLAG_GOALS, FLAG_LATENCY,
    FLAG_MOTIONS, FLAG_PAUSED, FLAG_POSITIONS, FLAG_TOUCHES, FLAG_VELOCITIES, FRAME_KIND_SNAPSHOT,
};
use super::hello::FieldSet;
use super::numbers::sanitize;
use crate::vocab::Snapshot;

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
    /// Each agent's motion wire code ([`motion_from_code`](super::motion_from_code)
    /// gives the type), when sent.
    pub motions: Option<Vec<u8>>,
}

pub(super) fn rd_u32(b: &[u8], at: usize) -> u32 {
    let mut a = [0; 4];
    a.copy_from_slice(&b[at..at + 4]);
    u32::from_le_bytes(a)
}

pub(super) fn rd_u64(b: &[u8], at: usize) -> u64 {
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
