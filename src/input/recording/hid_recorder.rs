//! `hid-recorder` logs: the report descriptor and the raw input reports of a hidraw
//! device, as text.
//!
//! # Format
//!
//! ```text
//! # comment (hid-decode's annotations)
//! D: 0                               device index (multi-device logs); optional
//! R: 177 05 0d 09 04 a1 01 …         descriptor: byte count, then hex bytes
//! N: ActionStar touchscreen          name
//! P: usb-0000:00:14.0-2/input0       physical path (ignored)
//! I: 3 2101 1011                     bus, vendor, product (hex)
//! E: 000000.012345 14 01 ff 01 …     one input report: sec.usec, byte count, hex bytes
//! ```
//!
//! Only the first device (the one whose `R:` comes first) is read; `E:` lines of
//! other devices are skipped with a warning. Timestamps are made relative to the
//! first report; they may all be equal (the ActionStar fixture's placeholders are
//! all zero), but must not go back.
//!
//! [`parse_hid_recorder`] reads a whole log without decoding it (for tools);
//! replays read it a report at a time (`hid_stream.rs`), decoding the first touch
//! collection with [`HidDecoder`](crate::input::hid::HidDecoder) as the other
//! recording formats are.

use super::error::{OnBadFrame, RecordingError};
use super::warnings::{RecordingIssue, Warnings};
use crate::input::hid::{parse_hex_bytes, parse_r_line};
use std::path::Path;

/// One `E:` line.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct HidEvent {
    /// 1-based line in the file.
    pub line: usize,
    /// Timestamp as written, in µs.
    pub time_us: u64,
    start: usize,
    len: usize,
}

/// A hid-recorder log, parsed but not decoded.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HidRecorderLog {
    /// `N:` name.
    pub name: Option<String>,
    /// `I:` bus (3 USB, 0x18 I2C, …).
    pub bus: Option<u16>,
    /// `I:` vendor id.
    pub vendor: Option<u16>,
    /// `I:` product id.
    pub product: Option<u16>,
    /// The report descriptor (`R:`).
    pub descriptor: Vec<u8>,
    /// Line of the `R:`.
    pub descriptor_line: usize,
    /// Problems that did not stop the reading.
    pub warnings: Vec<RecordingIssue>,
    events: Vec<HidEvent>,
    data: Vec<u8>,
}

impl HidRecorderLog {
    /// The input reports in file order, with their bytes.
    pub fn events(&self) -> impl Iterator<Item = (&HidEvent, &[u8])> + '_ {
        self.events
            .iter()
            .map(|e| (e, self.data.get(e.start..e.start + e.len).unwrap_or(&[])))
    }

    /// Number of input reports.
    pub fn len(&self) -> usize {
        self.events.len()
    }

    /// Whether the log holds no input report.
    pub fn is_empty(&self) -> bool {
        self.events.is_empty()
    }
}

/// `sec.usec` → µs.
fn parse_time(s: &str) -> Result<u64, String> {
    let bad = || format!("`{s}` is not a timestamp (sec.usec)");
    let (sec, frac) = s.split_once('.').unwrap_or((s, ""));
    if sec.is_empty() || !sec.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    if frac.len() > 6 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return Err(bad());
    }
    let sec: u64 = sec.parse().map_err(|_| bad())?;
    let mut usec: u64 = if frac.is_empty() {
        0
    } else {
        frac.parse().map_err(|_| bad())?
    };
    for _ in frac.len()..6 {
        usec *= 10;
    }
    sec.checked_mul(1_000_000)
        .and_then(|v| v.checked_add(usec))
        .ok_or_else(bad)
}

/// Parses an `I:` line: bus, vendor, product in hex.
fn parse_id(rest: &str) -> Result<(u16, u16, u16), String> {
    let v: Vec<&str> = rest.split_whitespace().collect();
    let hex = |s: &str| u16::from_str_radix(s, 16).map_err(|_| format!("`{s}` is not hex"));
    match v.as_slice() {
        [bus, vid, pid, ..] => Ok((hex(bus)?, hex(vid)?, hex(pid)?)),
        _ => Err("I: needs bus, vendor and product".into()),
    }
}

/// Parses a hid-recorder log.
///
/// # Errors
/// [`RecordingError::Parse`] with the line: a malformed `R:`/`I:`/`D:`/`E:` line
/// (an `E:` whose byte count does not match, bad hex, a bad timestamp), an `E:`
/// before the `R:`, a second `R:` for the same device, no `R:` at all, an unknown
/// line. With [`OnBadFrame::Skip`] a bad `E:` line is skipped with a warning
/// instead; header problems are always fatal.
pub fn parse_hid_recorder(
    text: &str,
    path: &Path,
    on_bad: OnBadFrame,
) -> Result<HidRecorderLog, RecordingError> {
    let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut issues = Warnings::default();
    let mut header = HidHeader::default();
    let mut events = Vec::new();
    let mut data = Vec::new();
    let mut other_events = 0usize;
    let mut last_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last_line = line;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        match header.take(line, l).map_err(|m| perr(line, m))? {
            HidLine::Header => {}
            HidLine::OtherEvent => other_events += 1,
            HidLine::Event(rest) => {
                let start = data.len();
                match parse_event(rest, &mut data) {
                    Ok((time_us, len)) => events.push(HidEvent {
                        line,
                        time_us,
                        start,
                        len,
                    }),
                    Err(m) => {
                        data.truncate(start);
                        match on_bad {
                            OnBadFrame::Stop => return Err(perr(line, m)),
                            OnBadFrame::Skip => issues.push(line, format!("{m}; report skipped")),
                        }
                    }
                }
            }
        }
    }
    if !header.has_descriptor() {
        return Err(no_descriptor(path, last_line));
    }
    if other_events > 0 {
        issues.push(0, other_devices_note(other_events));
    }
    Ok(HidRecorderLog {
        name: header.name,
        bus: header.bus,
        vendor: header.vendor,
        product: header.product,
        descriptor: header.descriptor,
        descriptor_line: header.descriptor_line,
        warnings: issues.finish(),
        events,
        data,
    })
}

/// The error for a log without an `R:` line, at its last line.
pub(super) fn no_descriptor(path: &Path, last_line: usize) -> RecordingError {
    RecordingError::parse(
        path,
        last_line.max(1),
        "no report descriptor (R: line) in the hid-recorder log",
    )
}

/// The warning for `E:` lines of devices other than the one read.
pub(super) fn other_devices_note(n: usize) -> String {
    format!("{n} input reports of other devices in the log were skipped")
}

/// What a line of a hid-recorder log is, once the header lines are taken in.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum HidLine<'a> {
    /// A header line (`D:`, `R:`, `N:`, `I:`, `P:`), applied.
    Header,
    /// An input report of the device read: what follows `E:`.
    Event(&'a str),
    /// An input report of another device.
    OtherEvent,
}

/// The header lines of a log: the first device's descriptor and identity, and
/// which device the lines now belong to.
#[derive(Debug, Default)]
pub(super) struct HidHeader {
    pub(super) name: Option<String>,
    pub(super) bus: Option<u16>,
    pub(super) vendor: Option<u16>,
    pub(super) product: Option<u16>,
    pub(super) descriptor: Vec<u8>,
    pub(super) descriptor_line: usize,
    /// The device of the lines (`D:`).
    device: u32,
    /// The device read: the one whose `R:` comes first.
    ours: Option<u32>,
}

impl HidHeader {
    /// Whether an `R:` line was read.
    pub(super) fn has_descriptor(&self) -> bool {
        self.ours.is_some()
    }

    /// Takes in one trimmed line that is neither blank nor a comment, the
    /// `line`-th of the log.
    ///
    /// # Errors
    /// A malformed `R:`/`I:`/`D:` line, an `E:` before the `R:`, a second `R:`
    /// for the same device, an unknown line.
    pub(super) fn take<'a>(&mut self, line: usize, l: &'a str) -> Result<HidLine<'a>, String> {
        let Some((tag, rest)) = l.split_once(':') else {
            return Err(format!("unknown line `{}`", prefix(l)));
        };
        let mine = self.ours.is_none_or(|d| d == self.device);
        match tag {
            "D" => {
                self.device = rest
                    .trim()
                    .parse()
                    .map_err(|_| "D: needs a device number".to_string())?;
            }
            "R" if self.ours.is_none() => {
                self.descriptor = parse_r_line(rest)?;
                self.descriptor_line = line;
                self.ours = Some(self.device);
            }
            "R" if mine => return Err("a second R: line for the same device".to_string()),
            "N" if mine => self.name = Some(rest.trim().to_string()),
            "I" if mine => {
                let (b, v, p) = parse_id(rest)?;
                (self.bus, self.vendor, self.product) = (Some(b), Some(v), Some(p));
            }
            "R" | "N" | "I" | "P" => {}
            "E" if self.ours.is_none() => {
                return Err("input report (E:) before the report descriptor (R:)".to_string())
            }
            "E" if !mine => return Ok(HidLine::OtherEvent),
            "E" => return Ok(HidLine::Event(rest)),
            _ => return Err(format!("unknown line `{}`", prefix(l))),
        }
        Ok(HidLine::Header)
    }
}

/// The first characters of a line, for messages.
fn prefix(l: &str) -> String {
    l.chars().take(24).collect()
}

/// Parses what follows `E:`: `sec.usec len bytes…`, appending the bytes.
pub(super) fn parse_event(rest: &str, data: &mut Vec<u8>) -> Result<(u64, usize), String> {
    let mut it = rest.split_whitespace();
    let time = parse_time(it.next().ok_or("empty E: line")?)?;
    let len: usize = it
        .next()
        .ok_or("E: has no byte count")?
        .parse()
        .map_err(|_| "E: byte count is not a number".to_string())?;
    let n = parse_hex_bytes(it, data)?;
    if n != len {
        return Err(format!("E: announces {len} bytes but holds {n}"));
    }
    Ok((time, n))
}

/// Writes a hid-recorder log: the header (`R:`, `N:`, `I:`) and then one `E:`
/// line per input report, with times relative to the first report as
/// `hid-recorder` writes them. [`parse_hid_recorder`] (and `hid-replay` from
/// hid-tools) read it back.
#[derive(Debug)]
pub struct HidRecorderWriter<W: std::io::Write> {
    out: W,
    first_us: Option<u64>,
    reports: u64,
}

impl<W: std::io::Write> HidRecorderWriter<W> {
    /// Writes the header: descriptor, name (line breaks replaced by spaces) and
    /// bus/vendor/product.
    ///
    /// # Errors
    /// The writer's.
    pub fn new(
        mut out: W,
        descriptor: &[u8],
        name: &str,
        bus: u16,
        vendor: u16,
        product: u16,
    ) -> std::io::Result<Self> {
        write!(out, "R: {}", descriptor.len())?;
        for b in descriptor {
            write!(out, " {b:02x}")?;
        }
        writeln!(out)?;
        let name: String = name
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
        writeln!(out, "N: {}", name.trim())?;
        writeln!(out, "I: {bus:x} {vendor:04x} {product:04x}")?;
        Ok(HidRecorderWriter {
            out,
            first_us: None,
            reports: 0,
        })
    }

    /// Writes one input report read at `t_us` (any clock; only differences matter).
    ///
    /// # Errors
    /// The writer's.
    pub fn report(&mut self, t_us: u64, bytes: &[u8]) -> std::io::Result<()> {
        let first = *self.first_us.get_or_insert(t_us);
        let rel = t_us.saturating_sub(first);
        write!(
            self.out,
            "E: {:06}.{:06} {}",
            rel / 1_000_000,
            rel % 1_000_000,
            bytes.len()
        )?;
        for b in bytes {
            write!(self.out, " {b:02x}")?;
        }
        writeln!(self.out)?;
        self.reports += 1;
        Ok(())
    }

    /// Flushes the writer.
    ///
    /// # Errors
    /// The writer's.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }

    /// Reports written so far.
    pub fn reports(&self) -> u64 {
        self.reports
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times() {
        assert_eq!(parse_time("000000.000000"), Ok(0));
        assert_eq!(parse_time("000001.5"), Ok(1_500_000));
        assert_eq!(parse_time("12"), Ok(12_000_000));
        assert!(parse_time("-1.0").is_err());
        assert!(parse_time("1.1234567").is_err());
        assert!(parse_time("99999999999999999999.0").is_err());
    }

    #[test]
    fn header_errors_name_the_line() {
        let p = Path::new("x.hid");
        let e = parse_hid_recorder("# c\nE: 0.0 1 01\n", p, OnBadFrame::Skip).unwrap_err();
        assert!(matches!(e, RecordingError::Parse { line: 2, .. }), "{e}");
        let e = parse_hid_recorder("R: 1 05\nX: what\n", p, OnBadFrame::Skip).unwrap_err();
        assert!(matches!(e, RecordingError::Parse { line: 2, .. }), "{e}");
        let log =
            parse_hid_recorder("R: 1 05\nE: 0.1 2 01\nE: 0.2 1 01\n", p, OnBadFrame::Skip).unwrap();
        assert_eq!(log.len(), 1);
        assert_eq!(log.warnings[0].line, 2);
        let e = parse_hid_recorder("R: 1 05\nE: 0.1 2 01\n", p, OnBadFrame::Stop).unwrap_err();
        assert!(matches!(e, RecordingError::Parse { line: 2, .. }), "{e}");
    }

    #[test]
    fn other_devices_are_skipped() {
        let p = Path::new("x.hid");
        let text = "D: 0\nR: 1 05\nI: 3 1 2\nD: 1\nR: 1 06\nI: 3 3 4\nD: 0\nE: 0.0 1 01\nD: 1\nE: 0.0 1 02\n";
        let log = parse_hid_recorder(text, p, OnBadFrame::Stop).unwrap();
        assert_eq!(log.descriptor, vec![5]);
        assert_eq!((log.vendor, log.product), (Some(1), Some(2)));
        let got: Vec<&[u8]> = log.events().map(|(_, b)| b).collect();
        assert_eq!(got, vec![&[1u8][..]]);
        assert!(log.warnings[0].message.contains("other devices"));
    }

    #[test]
    fn writer_output_reads_back() {
        let descriptor = [0x05u8, 0x0d, 0x09, 0x04, 0xa1, 0x01, 0xc0];
        let mut buf = Vec::new();
        let mut w =
            HidRecorderWriter::new(&mut buf, &descriptor, "Panel\nOne", 3, 0x2101, 0x1011).unwrap();
        w.report(5_000_000, &[0x01, 0xff, 0x10]).unwrap();
        w.report(6_234_567, &[0x01, 0x00]).unwrap();
        assert_eq!(w.reports(), 2);
        let text = String::from_utf8(buf).unwrap();
        assert!(text.contains("E: 000001.234567 2 01 00"), "{text}");
        let log = parse_hid_recorder(&text, Path::new("w.hid"), OnBadFrame::Stop).unwrap();
        assert_eq!(log.descriptor, descriptor);
        assert_eq!(log.name.as_deref(), Some("Panel One"));
        assert_eq!(
            (log.bus, log.vendor, log.product),
            (Some(3), Some(0x2101), Some(0x1011))
        );
        let ev: Vec<(u64, Vec<u8>)> = log.events().map(|(e, b)| (e.time_us, b.to_vec())).collect();
        assert_eq!(
            ev,
            vec![(0, vec![0x01, 0xff, 0x10]), (1_234_567, vec![0x01, 0x00])]
        );
    }
}
