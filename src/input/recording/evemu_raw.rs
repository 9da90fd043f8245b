//! Reading an evemu file without decoding it: the device's capabilities and its
//! raw events, as they would be played back.

use super::error::RecordingError;
use super::evdev_header::default_name;
use super::evemu::{evemu_fields, is_evemu_line, parse_evemu_event};
use crate::input::evdev::{
    AbsAxisInfo, EvdevCapabilities, RawEvent, ABS_MAX, EV_CNT, MASK_BYTES, PROP_BYTES,
};
use crate::vocab::Micros;
use std::path::Path;

/// Reads an evemu file without decoding it: the device's capabilities (`N:`,
/// `I:`, `P:`, `B:`, `A:` lines; `L:`/`S:` state lines are skipped) and every
/// `E:` event, with its time as written (µs).
///
/// `text` may be a whole `.evemu` file, a `.desc`/`.prop` (no events), or a
/// description followed by its `.events`. `name` is used in errors, and as the
/// device name when there is no `N:` line. Bitmask lines add 8 bytes each to
/// their type's bitmask, as evemu reads them; bits beyond what
/// [`EvdevCapabilities`] keeps must be zero.
///
/// # Errors
/// [`RecordingError::Parse`] at the first malformed line (also a header line
/// after the first event).
pub fn read_evemu_raw(
    text: &str,
    name: &Path,
) -> Result<(EvdevCapabilities, Vec<RawEvent>), RecordingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut caps = EvdevCapabilities::new(default_name(name));
    let mut prop_bytes = 0usize;
    let mut mask_bytes = [0usize; EV_CNT];
    let mut events = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let perr = |message: String| RecordingError::parse(name, line, message);
        if let Some(rest) = l.strip_prefix("E:") {
            let (time, ev_type, code, value) = parse_evemu_event(rest).map_err(perr)?;
            events.push(RawEvent {
                t: Micros(time),
                ev_type,
                code,
                value,
            });
            continue;
        }
        if !is_evemu_line(l) {
            return Err(perr(
                "unrecognised line (expected N:, I:, P:, B:, A:, L:, S: or E:)".into(),
            ));
        }
        if !events.is_empty() {
            return Err(perr("header line after the first event".into()));
        }
        caps_header_line(&mut caps, &mut prop_bytes, &mut mask_bytes, l).map_err(perr)?;
    }
    Ok((caps, events))
}

/// Parses a hex byte of a bitmask line.
fn hex_byte(tok: &str) -> Result<u8, String> {
    u8::from_str_radix(tok, 16).map_err(|_| format!("`{tok}` is not a hex byte"))
}

/// Applies one evemu header line to a capability snapshot.
fn caps_header_line(
    caps: &mut EvdevCapabilities,
    prop_bytes: &mut usize,
    mask_bytes: &mut [usize; EV_CNT],
    l: &str,
) -> Result<(), String> {
    let rest = l[2..].trim();
    let toks: Vec<&str> = evemu_fields(rest).collect();
    match &l[..2] {
        "N:" => caps.name = rest.to_string(),
        "I:" => {
            if toks.len() != 4 {
                return Err(format!(
                    "an id line needs `I: bus vendor product version`, found {} fields",
                    toks.len()
                ));
            }
            let mut v = [0u16; 4];
            for (k, tok) in toks.iter().enumerate() {
                v[k] = u16::from_str_radix(tok, 16)
                    .map_err(|_| format!("id field `{tok}` is not a 16-bit hex number"))?;
            }
            [caps.bus, caps.vendor, caps.product, caps.version] = v;
        }
        "P:" => {
            for tok in &toks {
                let b = hex_byte(tok)?;
                if *prop_bytes < PROP_BYTES {
                    for bit in 0..8 {
                        if (b >> bit) & 1 == 1 {
                            caps.set_property((*prop_bytes * 8 + bit) as u16);
                        }
                    }
                } else if b != 0 {
                    return Err(format!(
                        "property bits beyond the first {} bytes are not supported",
                        PROP_BYTES
                    ));
                }
                *prop_bytes += 1;
            }
        }
        "B:" => {
            let Some((ty, bytes)) = toks.split_first() else {
                return Err("a bitmask line needs `B: type bytes...`".into());
            };
            let ty = u16::from_str_radix(ty, 16)
                .ok()
                .filter(|&t| usize::from(t) < EV_CNT)
                .ok_or_else(|| format!("event type `{ty}` is not a hex number below 0x20"))?;
            let at = &mut mask_bytes[usize::from(ty)];
            for tok in bytes {
                let b = hex_byte(tok)?;
                if *at < MASK_BYTES {
                    let old = caps.mask(ty)[*at];
                    caps.set_mask_byte(ty, *at, old | b);
                } else if b != 0 {
                    return Err(format!(
                        "type 0x{ty:02x} bits beyond the first {MASK_BYTES} bytes are not supported"
                    ));
                }
                *at += 1;
            }
        }
        "A:" => {
            if !(5..=6).contains(&toks.len()) {
                return Err(format!(
                    "an axis line needs `A: code min max fuzz flat [resolution]`, found {} fields",
                    toks.len()
                ));
            }
            let code = u16::from_str_radix(toks[0], 16)
                .ok()
                .filter(|&c| c <= ABS_MAX)
                .ok_or_else(|| format!("axis code `{}` is not a hex number up to 0x3f", toks[0]))?;
            let mut v = [0i32; 5];
            for (k, tok) in toks[1..].iter().enumerate() {
                let what = ["min", "max", "fuzz", "flat", "resolution"][k];
                v[k] = tok
                    .parse()
                    .map_err(|_| format!("axis 0x{code:02x} {what} `{tok}` is not an integer"))?;
            }
            caps.set_abs(
                code,
                AbsAxisInfo {
                    value: 0,
                    minimum: v[0],
                    maximum: v[1],
                    fuzz: v[2],
                    flat: v[3],
                    resolution: v[4],
                },
            );
        }
        // LED and switch states: not capabilities.
        _ => {}
    }
    Ok(())
}
