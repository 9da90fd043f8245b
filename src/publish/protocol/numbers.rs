//! Number writing for the hand-written encoders (hot path): fixed 3-decimal
//! coordinates from scaled integers, integers with `itoa`, flat JSON arrays. No float
//! formatting, no allocation beyond the output buffer.

use crate::geom::Vec2;

/// Largest coordinate magnitude written (m or m/s). Larger values and infinities are
/// clamped to it and NaN is written as 0, so the output is always valid JSON.
pub const MAX_COORD_ABS: f64 = 1.0e9;

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
pub(super) fn push_fixed3(out: &mut Vec<u8>, v: f64) {
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
pub(super) fn sanitize(v: f64) -> f64 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(-MAX_COORD_ABS, MAX_COORD_ABS)
    }
}

#[inline]
pub(super) fn push_uint(out: &mut Vec<u8>, v: impl itoa::Integer, buf: &mut itoa::Buffer) {
    out.extend_from_slice(buf.format(v).as_bytes());
}

/// Appends `[x0,y0,x1,y1,…]`.
pub(super) fn push_flat_vec2(out: &mut Vec<u8>, it: impl Iterator<Item = Vec2>) {
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

pub(super) fn push_u32_list(
    out: &mut Vec<u8>,
    it: impl Iterator<Item = u32>,
    buf: &mut itoa::Buffer,
) {
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
