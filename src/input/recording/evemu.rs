//! The evemu reader (`evemu-record` text), decoded through the shared event stream.
//!
//! Header lines `N:` name, `I:`, `P:`, `B:`, `A: code min max fuzz flat
//! [resolution]` (code in hex; old files have no resolution column), then
//! `E: sec.usec type code value [# comment]` (type and code in hex, value decimal,
//! possibly zero-padded or negative). Timestamps may be absolute or relative; they
//! are made relative to the first event. Files holding only `E:` lines are paired
//! with their `.desc` through [`read_evemu_with_desc`].

use super::error::{OnBadFrame, RecordingError};
use super::evdev_header::{default_name, AbsInfo, DeviceHeader, HeaderCtx};
use super::event_stream::EventStream;
use super::lines::{too_long_message, LineFault, LineReader};
use super::warnings::Warnings;
use crate::input::evdev::ABS_MAX;
use crate::input::SurfaceInfo;
use crate::vocab::TouchFrame;
use std::path::Path;

/// Whether `line` (trimmed) is an evemu header or event line.
pub(super) fn is_evemu_line(line: &str) -> bool {
    ["N:", "I:", "P:", "B:", "A:", "L:", "S:", "E:"]
        .iter()
        .any(|p| line.starts_with(p))
}

/// The device header of a `.desc`/`.prop` text (`N:`/`I:`/`P:`/`B:`/`A:` lines),
/// for an events file that has none.
///
/// # Errors
/// [`RecordingError::Parse`] at a malformed line, "in the device description".
pub(super) fn parse_evemu_desc(
    desc: &str,
    path: &Path,
    w: &mut Warnings,
) -> Result<DeviceHeader, RecordingError> {
    let ctx = HeaderCtx {
        path,
        prefix: DESC_PREFIX,
    };
    let mut hdr = DeviceHeader::default();
    let desc = desc.strip_prefix('\u{feff}').unwrap_or(desc);
    for (i, raw) in desc.lines().enumerate() {
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        if l.starts_with("E:") {
            w.push(
                0,
                "the device description holds events; they are ignored".into(),
            );
            break;
        }
        if !is_evemu_line(l) {
            return Err(ctx.err(i + 1, "unrecognised line (expected N:, I:, P:, B: or A:)"));
        }
        evemu_header_line(&mut hdr, i + 1, l).map_err(|m| ctx.err(i + 1, m))?;
    }
    Ok(hdr)
}

/// How errors about a separate description begin.
const DESC_PREFIX: &str = "in the device description: ";

/// Parses `sec.usec` into microseconds.
fn parse_evemu_time(s: &str) -> Result<u64, String> {
    let bad = || format!("timestamp `{s}` is not `seconds.microseconds`");
    let (sec, frac) = s.split_once('.').unwrap_or((s, ""));
    if sec.is_empty() || !sec.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    if !frac.bytes().all(|b| b.is_ascii_digit()) || frac.len() > 9 {
        return Err(bad());
    }
    let sec: u64 = sec.parse().map_err(|_| bad())?;
    let mut usec: u64 = 0;
    for (i, b) in frac.bytes().take(6).enumerate() {
        usec += u64::from(b - b'0') * 10u64.pow(5 - i as u32);
    }
    sec.checked_mul(1_000_000)
        .and_then(|v| v.checked_add(usec))
        .ok_or_else(|| format!("timestamp `{s}` is out of range"))
}

/// The fields of an evemu line after its `X:` prefix, up to a `#` comment.
pub(super) fn evemu_fields(rest: &str) -> impl Iterator<Item = &str> {
    rest.split_whitespace().take_while(|t| !t.starts_with('#'))
}

/// Parses an `E:` line into `(time_us, type, code, value)`.
pub(super) fn parse_evemu_event(rest: &str) -> Result<(u64, u16, u16, i32), String> {
    let mut f = [""; 4];
    let mut n = 0;
    for tok in evemu_fields(rest) {
        if n < 4 {
            f[n] = tok;
        }
        n += 1;
    }
    if n != 4 {
        return Err(format!(
            "an event line needs 4 fields (`E: sec.usec type code value`), found {n}"
        ));
    }
    let time = parse_evemu_time(f[0])?;
    let ty = u16::from_str_radix(f[1], 16)
        .map_err(|_| format!("event type `{}` is not a 16-bit hex number", f[1]))?;
    let code = u16::from_str_radix(f[2], 16)
        .map_err(|_| format!("event code `{}` is not a 16-bit hex number", f[2]))?;
    let value: i32 = f[3]
        .parse()
        .map_err(|_| format!("event value `{}` is not a 32-bit decimal integer", f[3]))?;
    Ok((time, ty, code, value))
}

/// Applies one header line (`N:`, `I:`, `P:`, `B:`, `A:`) to `hdr`.
fn evemu_header_line(hdr: &mut DeviceHeader, line: usize, l: &str) -> Result<(), String> {
    let rest = l[2..].trim();
    match &l[..2] {
        "N:" => {
            hdr.name = Some(rest.to_string());
            Ok(())
        }
        "A:" => {
            let toks: Vec<&str> = evemu_fields(rest).collect();
            if !(5..=6).contains(&toks.len()) {
                return Err(format!(
                    "an axis line needs `A: code min max fuzz flat [resolution]`, found {} fields",
                    toks.len()
                ));
            }
            let code = u16::from_str_radix(toks[0], 16)
                .map_err(|_| format!("axis code `{}` is not a hex number", toks[0]))?;
            if code > ABS_MAX {
                return Err(format!(
                    "unknown axis code 0x{code:x} (the highest is 0x{ABS_MAX:x})"
                ));
            }
            let mut v = [0i32; 5];
            for (i, tok) in toks[1..].iter().enumerate() {
                let what = ["min", "max", "fuzz", "flat", "resolution"][i];
                v[i] = tok
                    .parse()
                    .map_err(|_| format!("axis 0x{code:02x} {what} `{tok}` is not an integer"))?;
            }
            if hdr.abs[code as usize].is_some() {
                return Err(format!("axis 0x{code:02x} is declared twice"));
            }
            hdr.abs[code as usize] = Some(AbsInfo {
                min: v[0],
                max: v[1],
                resolution: v[4],
                line,
            });
            Ok(())
        }
        // Bus/vendor/product, properties and capability bits are not needed.
        _ => Ok(()),
    }
}

/// An evemu event: `(time_us, type, code, value)`, or what is wrong with its line.
type EventLine = Result<(u64, u16, u16, i32), String>;

/// Reads evemu text a frame at a time.
pub(super) struct EvemuReader {
    lines: LineReader,
    stream: EventStream,
    /// The header came from a separate description: header lines in the text
    /// are ignored.
    has_desc: bool,
    /// The first event line, read while looking for the end of the header.
    first: Option<(usize, EventLine)>,
}

impl EvemuReader {
    /// Reads the header, from `desc` (a description's, see [`parse_evemu_desc`])
    /// or from the top of the text, up to the first event.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad header line, no axis, an empty axis
    /// range; [`RecordingError::Unsupported`] for a device without multi-touch
    /// axes; [`RecordingError::Empty`] when there is no event.
    pub(super) fn open(
        mut lines: LineReader,
        desc: Option<&DeviceHeader>,
        path: &Path,
        on_bad: OnBadFrame,
        w: &mut Warnings,
    ) -> Result<(EvemuReader, SurfaceInfo), RecordingError> {
        let mut hdr = desc.cloned().unwrap_or_default();
        let ctx = HeaderCtx { path, prefix: "" };
        // Header problems point into the description when there is one.
        let hctx = HeaderCtx {
            path,
            prefix: if desc.is_some() { DESC_PREFIX } else { "" },
        };
        let dflt = default_name(path);
        let first = loop {
            let (line, l) = match lines.next_line() {
                Ok(Some((n, l))) => (n, l.trim()),
                Ok(None) => {
                    // A header with no events: say what is wrong with the device first.
                    hdr.mt_axes(&hctx, 1, &dflt, w)?;
                    return Err(RecordingError::Empty {
                        path: path.to_path_buf(),
                    });
                }
                Err(f) => return Err(f.at(path, lines.line())),
            };
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            if let Some(rest) = l.strip_prefix("E:") {
                break (line, parse_evemu_event(rest));
            }
            if !is_evemu_line(l) {
                let m = "unrecognised line (expected N:, I:, P:, B:, A: or E:)";
                return Err(ctx.err(line, m));
            }
            if desc.is_none() {
                evemu_header_line(&mut hdr, line, l).map_err(|m| ctx.err(line, m))?;
            }
        };
        let at = if desc.is_some() { 1 } else { first.0 };
        let (axes, surface) = hdr.mt_axes(&hctx, at, &dflt, w)?;
        let reader = EvemuReader {
            lines,
            stream: EventStream::new(on_bad, axes, &hdr),
            has_desc: desc.is_some(),
            first: Some(first),
        };
        Ok((reader, surface))
    }

    /// The source, for reading again from the start.
    pub(super) fn into_lines(self) -> LineReader {
        self.lines
    }

    /// Bytes read so far.
    pub(super) fn consumed(&self) -> u64 {
        self.lines.consumed()
    }

    /// The next frame into `out`, and the line that closed it; `None` after the last.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad event with [`OnBadFrame::Stop`];
    /// [`RecordingError::Empty`] at the end when no frame was decoded.
    pub(super) fn next(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        loop {
            let (line, event) = match self.first.take() {
                Some(first) => first,
                None => match self.lines.next_line() {
                    Ok(Some((line, l))) => {
                        let l = l.trim();
                        if l.is_empty() || l.starts_with('#') {
                            continue;
                        }
                        match l.strip_prefix("E:") {
                            Some(rest) => (line, parse_evemu_event(rest)),
                            // The description is authoritative; a header
                            // repeated in the events file is ignored.
                            None if self.has_desc && is_evemu_line(l) => continue,
                            None if is_evemu_line(l) => {
                                (line, Err("header line after the first event".into()))
                            }
                            None => (
                                line,
                                Err("unrecognised line (expected N:, I:, P:, B:, A: or E:)".into()),
                            ),
                        }
                    }
                    Ok(None) => {
                        let line = self.lines.line();
                        return Ok(self.stream.finish(path, out, w)?.then_some(line));
                    }
                    Err(LineFault::TooLong) => {
                        self.lines
                            .skip_rest()
                            .map_err(|e| LineFault::Io(e).at(path, self.lines.line()))?;
                        (self.lines.line(), Err(too_long_message()))
                    }
                    Err(f) => return Err(f.at(path, self.lines.line())),
                },
            };
            match event {
                Ok(ev) => {
                    if self.stream.event(path, line, ev, out, w)? {
                        return Ok(Some(line));
                    }
                }
                Err(m) => self.stream.bad(path, line, m, w)?,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evemu_time_forms() {
        assert_eq!(parse_evemu_time("0.000001"), Ok(1));
        assert_eq!(
            parse_evemu_time("1357751031.716015"),
            Ok(1_357_751_031_716_015)
        );
        assert_eq!(parse_evemu_time("2.5"), Ok(2_500_000));
        assert_eq!(parse_evemu_time("3"), Ok(3_000_000));
        assert!(parse_evemu_time("-1.0").is_err());
        assert!(parse_evemu_time("1.2.3").is_err());
        assert!(parse_evemu_time("99999999999999999999.0").is_err());
    }

    #[test]
    fn evemu_event_fields() {
        assert_eq!(
            parse_evemu_event(" 0.000001 0003 0039 -001\t# EV_ABS / ABS_MT_TRACKING_ID"),
            Ok((1, 3, 0x39, -1))
        );
        assert!(parse_evemu_event(" 0.1 0003 0035")
            .unwrap_err()
            .contains("4 fields"));
        assert!(parse_evemu_event(" 0.1 0003 zz 1")
            .unwrap_err()
            .contains("code"));
    }
}
