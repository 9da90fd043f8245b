//! The `plan` and `demo_motion` messages: every agent's planned trajectory, written
//! by hand like the snapshot (a plan of 1,000 agents is 128,000 numbers), sent to
//! clients subscribed to `plan` only.

use super::numbers::{push_fixed3, push_flat_vec2, push_uint};
use crate::vocab::{PlanOrigin, PlanView};

/// Appends one `plan` line (a gesture's motion) or `demo_motion` line (a library
/// motion shown by `library collect`):
///
/// ```text
/// {"type":"plan","gesture":9,"class":"translate","duration_s":4.200,"samples":64,"agents":[[x0,y0,x1,y1,…],…]}
/// {"type":"demo_motion","class":"twist","motion":3,"duration_s":3.000,"samples":64,"agents":[[…],…]}
/// ```
///
/// Coordinates are world metres with three decimals, as in `snapshot` (NaN written
/// as 0, magnitudes clamped to [`MAX_COORD_ABS`](super::MAX_COORD_ABS)); `agents[a]`
/// is the snapshot's agent `a`. Points past the last whole trajectory are not sent.
///
/// # Complexity
/// Linear in the number of points; one growth of `out` at most (reserved up front).
pub fn encode_plan_json(p: &PlanView, out: &mut Vec<u8>) {
    let samples = p.samples as usize;
    let agents = p.agents();
    out.reserve(128 + agents * (2 + samples * 18));
    let mut b = itoa::Buffer::new();
    match p.origin {
        PlanOrigin::Gesture { id } => {
            out.extend_from_slice(b"{\"type\":\"plan\",\"gesture\":");
            push_uint(out, id, &mut b);
            out.extend_from_slice(b",\"class\":");
            push_str(out, &p.class);
        }
        PlanOrigin::Demo { motion } => {
            out.extend_from_slice(b"{\"type\":\"demo_motion\",\"class\":");
            push_str(out, &p.class);
            out.extend_from_slice(b",\"motion\":");
            push_uint(out, motion, &mut b);
        }
    }
    out.extend_from_slice(b",\"duration_s\":");
    push_fixed3(out, p.duration_s);
    out.extend_from_slice(b",\"samples\":");
    push_uint(out, p.samples, &mut b);
    out.extend_from_slice(b",\"agents\":[");
    for a in 0..agents {
        if a > 0 {
            out.push(b',');
        }
        push_flat_vec2(out, p.trajectory(a).iter().copied());
    }
    out.extend_from_slice(b"]}\n");
}

/// Appends `s` as a JSON string (escaped by serde_json; writing a `str` to a `Vec`
/// cannot fail).
fn push_str(out: &mut Vec<u8>, s: &str) {
    let _ = serde_json::to_writer(&mut *out, s);
}
