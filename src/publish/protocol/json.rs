//! The JSON messages written by hand for the hot path: `snapshot` (whole, or shared
//! by every client with the dropped count spliced in per client) and `mesh`.

use super::hello::FieldSet;
use super::numbers::{push_fixed3, push_flat_vec2, push_u32_list, push_uint};
use crate::vocab::{MeshView, Snapshot};

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
    if m.outlines.len() > 1 {
        out.extend_from_slice(b",\"outlines\":[");
        for (k, loop_) in m.outlines.iter().enumerate() {
            if k > 0 {
                out.push(b',');
            }
            push_u32_list(out, loop_.iter().copied(), &mut b);
        }
        out.push(b']');
    }
    out.extend_from_slice(b"}\n");
}
