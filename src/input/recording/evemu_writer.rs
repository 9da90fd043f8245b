//! Writing an evemu file: what `crowdtouch record` makes of an evdev device.
//!
//! [`EvemuWriter`] writes the capabilities and then the raw events in the
//! evemu text format (file version 1.3), which `evemu-device`/`evemu-play`
//! replay through uinput on any Linux machine, and which
//! [`read_recording`](super::read_recording) reads back:
//!
//! ```text
//! # EVEMU 1.3
//! N: <name>
//! I: <bus> <vendor> <product> <version>          (4-digit hex)
//! P: <8 property bitmask bytes>                   (hex; bit 1 = INPUT_PROP_DIRECT)
//! B: <type> <8 bitmask bytes>                     (one or more lines per type)
//! A: <code> <min> <max> <fuzz> <flat> <resolution> (code hex, values decimal)
//! E: <sec>.<usec> <type> <code> <value>           (type/code 4-digit hex, value %04d)
//! ```
//!
//! The bitmask lines follow evemu: for each event type with a kernel maximum
//! (`EV_SYN`, `EV_KEY`, `EV_REL`, `EV_ABS`, `EV_MSC`, `EV_SW`, `EV_LED`,
//! `EV_SND`, `EV_REP`, `EV_FF`) as many 64-bit words as that maximum needs,
//! 8 bytes per line, least significant byte first. Event times are relative to
//! the first event, which is written at `0.000001` as `evemu-record` does
//! ([`EvemuTime::Relative`]), or kept as they are ([`EvemuTime::Absolute`]).

use crate::input::evdev::{
    self as mt, code_name, type_name, EvdevCapabilities, RawEvent, ABS_MAX, EV_ABS, EV_CNT, EV_FF,
    EV_KEY, EV_LED, EV_MSC, EV_REP, EV_SND, EV_SW, EV_SYN, INPUT_PROP_DIRECT,
};
use std::io::{self, Write};

/// The evemu file format version [`EvemuWriter`] writes.
pub const EVEMU_VERSION: &str = "1.3";

/// Event types evemu writes a bitmask for, with the kernel's highest code of each.
const EVEMU_TYPES: [(u16, u16); 10] = [
    (EV_SYN, 0x0f),
    (EV_KEY, 0x2ff),
    (mt::EV_REL, 0x0f),
    (EV_ABS, ABS_MAX),
    (EV_MSC, 0x07),
    (EV_SW, 0x10),
    (EV_LED, 0x0f),
    (EV_SND, 0x07),
    (EV_REP, 0x01),
    (EV_FF, 0x7f),
];

/// How [`EvemuWriter`] writes event times.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum EvemuTime {
    /// Relative to the first event, which is written at `0.000001` (as
    /// `evemu-record` does).
    #[default]
    Relative,
    /// As given.
    Absolute,
}

/// Writes an evemu file: the header from [`EvdevCapabilities`], then one `E:`
/// line per [`RawEvent`].
///
/// Each event line carries a `#` comment naming the event, as evemu writes it
/// (`SYN_REPORT` lines give the milliseconds since the previous one). Writing
/// an event formats into `w` without allocating; wrap files in a
/// `BufWriter`.
#[derive(Debug)]
pub struct EvemuWriter<W: Write> {
    w: W,
    time: EvemuTime,
    /// Microseconds subtracted from event times ([`EvemuTime::Relative`]).
    offset_us: Option<u64>,
    /// Written time of the previous `SYN_REPORT`, in ms.
    last_report_ms: u64,
    events: u64,
}

impl<W: Write> EvemuWriter<W> {
    /// Writes the header of `caps` to `w`; event times will be relative.
    ///
    /// # Errors
    /// Whatever `w` returns.
    pub fn new(caps: &EvdevCapabilities, w: W) -> io::Result<EvemuWriter<W>> {
        EvemuWriter::with_time(caps, w, EvemuTime::Relative)
    }

    /// Writes the header of `caps` to `w`, with times written as `time` says.
    ///
    /// # Errors
    /// Whatever `w` returns.
    pub fn with_time(
        caps: &EvdevCapabilities,
        mut w: W,
        time: EvemuTime,
    ) -> io::Result<EvemuWriter<W>> {
        write_evemu_header(caps, &mut w)?;
        Ok(EvemuWriter {
            w,
            time,
            offset_us: None,
            last_report_ms: 0,
            events: 0,
        })
    }

    /// Writes one event line.
    ///
    /// # Errors
    /// Whatever `w` returns.
    pub fn event(&mut self, ev: &RawEvent) -> io::Result<()> {
        let t = match self.time {
            EvemuTime::Absolute => ev.t.0,
            EvemuTime::Relative => {
                let offset = *self.offset_us.get_or_insert(ev.t.0.saturating_sub(1));
                ev.t.0.saturating_sub(offset)
            }
        };
        write!(
            self.w,
            "E: {}.{:06} {:04x} {:04x} {:04}\t",
            t / 1_000_000,
            t % 1_000_000,
            ev.ev_type,
            ev.code,
            ev.value
        )?;
        let syn = code_name(EV_SYN, ev.code);
        match (ev.ev_type, ev.code) {
            (EV_SYN, mt::SYN_MT_REPORT) => {
                writeln!(self.w, "# ++++++++++++ {syn} ({}) ++++++++++", ev.value)?
            }
            (EV_SYN, _) => {
                let ms = t / 1_000;
                let dt = ms.saturating_sub(self.last_report_ms);
                self.last_report_ms = ms;
                writeln!(
                    self.w,
                    "# ------------ {syn} ({}) ---------- +{dt}ms",
                    ev.value
                )?
            }
            _ => writeln!(
                self.w,
                "# {} / {:<20} {}",
                type_name(ev.ev_type),
                code_name(ev.ev_type, ev.code),
                ev.value
            )?,
        }
        self.events += 1;
        Ok(())
    }

    /// Events written so far.
    pub fn events(&self) -> u64 {
        self.events
    }

    /// Flushes `w`.
    ///
    /// # Errors
    /// Whatever `w` returns.
    pub fn flush(&mut self) -> io::Result<()> {
        self.w.flush()
    }

    /// The writer back.
    pub fn into_inner(self) -> W {
        self.w
    }
}

/// Writes the evemu header (`# EVEMU 1.3`, comments, `N:`, `I:`, `P:`, `B:`,
/// `A:` lines) of `caps`.
///
/// # Errors
/// Whatever `w` returns.
pub fn write_evemu_header(caps: &EvdevCapabilities, w: &mut impl Write) -> io::Result<()> {
    // The name goes on one line; evemu reads it to the end of that line.
    let name: String = caps
        .name
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    let name = if name.trim().is_empty() {
        "unnamed device"
    } else {
        name.trim()
    };
    writeln!(w, "# EVEMU {EVEMU_VERSION}")?;
    writeln!(
        w,
        "# Written by crowdtouch {} (times relative to the first event)",
        env!("CARGO_PKG_VERSION")
    )?;
    writeln!(w, "# Input device name: \"{name}\"")?;
    writeln!(
        w,
        "# Input device ID: bus {:#04x} vendor {:#06x} product {:#06x} version {:#06x}",
        caps.bus, caps.vendor, caps.product, caps.version
    )?;
    for ty in 0..EV_CNT as u16 {
        if ty != EV_SYN && caps.has_type(ty) {
            write!(w, "#   {}:", type_name(ty))?;
            for code in caps.codes(ty) {
                write!(w, " {}", code_name(ty, code))?;
            }
            writeln!(w)?;
        }
    }
    if caps.has_property(INPUT_PROP_DIRECT) {
        writeln!(w, "# Properties: INPUT_PROP_DIRECT")?;
    }
    writeln!(w, "N: {name}")?;
    writeln!(
        w,
        "I: {:04x} {:04x} {:04x} {:04x}",
        caps.bus, caps.vendor, caps.product, caps.version
    )?;
    write!(w, "P:")?;
    for b in caps.property_bytes() {
        write!(w, " {b:02x}")?;
    }
    writeln!(w)?;
    let write_mask = |w: &mut dyn Write, ty: u16, bytes: &[u8]| -> io::Result<()> {
        for line in bytes.chunks(8) {
            write!(w, "B: {ty:02x}")?;
            for b in line {
                write!(w, " {b:02x}")?;
            }
            writeln!(w)?;
        }
        Ok(())
    };
    for (ty, max) in EVEMU_TYPES {
        // The words the kernel maximum needs, and any set bit beyond it.
        let m = caps.mask(ty);
        let words = usize::from(max) / 64 + 1;
        let used = m
            .iter()
            .rposition(|&b| b != 0)
            .map_or(0, |last| last / 8 + 1);
        write_mask(w, ty, &m[..words.max(used) * 8])?;
    }
    for ty in 0..EV_CNT as u16 {
        if EVEMU_TYPES.iter().any(|&(t, _)| t == ty) {
            continue;
        }
        let m = caps.mask(ty);
        if let Some(last) = m.iter().rposition(|&b| b != 0) {
            write_mask(w, ty, &m[..(last / 8 + 1) * 8])?;
        }
    }
    // Bits above ABS_MAX (possible in a bitmask read from a file) have no absinfo.
    for code in caps.codes(EV_ABS).filter(|&c| c <= ABS_MAX) {
        let a = caps.abs(code).unwrap_or_default();
        writeln!(
            w,
            "A: {code:02x} {} {} {} {} {}",
            a.minimum, a.maximum, a.fuzz, a.flat, a.resolution
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::evdev::sample_panel as caps;
    use crate::vocab::Micros;

    #[test]
    fn header_has_evemu_layout() {
        let mut v = Vec::new();
        write_evemu_header(&caps(), &mut v).unwrap();
        let text = String::from_utf8(v).unwrap();
        let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
        assert!(text.starts_with("# EVEMU 1.3\n"));
        assert_eq!(lines[0], "N: Test Panel");
        assert_eq!(lines[1], "I: 0018 2575 0204 0111");
        assert_eq!(lines[2], "P: 02 00 00 00 00 00 00 00");
        let b = |ty: &str| lines.iter().filter(|l| l.starts_with(ty)).count();
        assert_eq!(b("B: 00"), 1);
        assert_eq!(b("B: 01"), 12);
        assert_eq!(b("B: 15"), 2);
        // BTN_TOUCH = 0x14a: byte 0x29, bit 2.
        let keys: Vec<&&str> = lines.iter().filter(|l| l.starts_with("B: 01")).collect();
        assert_eq!(*keys[5], "B: 01 00 04 00 00 00 00 00 00");
        assert!(lines.contains(&"B: 03 00 00 00 00 00 80 60 00"));
        assert!(lines.contains(&"A: 35 0 32767 0 0 55"));
        assert_eq!(lines.last(), Some(&"A: 36 0 32767 0 0 55"));
    }

    #[test]
    fn events_relative_and_absolute() {
        let evs = [
            RawEvent {
                t: Micros(5_000_000),
                ev_type: EV_ABS,
                code: mt::ABS_MT_TRACKING_ID,
                value: -1,
            },
            RawEvent {
                t: Micros(5_006_980),
                ev_type: EV_SYN,
                code: 0,
                value: 0,
            },
        ];
        let mut w = EvemuWriter::new(&caps(), Vec::new()).unwrap();
        for e in &evs {
            w.event(e).unwrap();
        }
        assert_eq!(w.events(), 2);
        let text = String::from_utf8(w.into_inner()).unwrap();
        let ev: Vec<&str> = text.lines().filter(|l| l.starts_with("E:")).collect();
        assert_eq!(
            ev,
            vec![
                "E: 0.000001 0003 0039 -001\t# EV_ABS / ABS_MT_TRACKING_ID   -1",
                "E: 0.006981 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +6ms",
            ]
        );
        let mut w = EvemuWriter::with_time(&caps(), Vec::new(), EvemuTime::Absolute).unwrap();
        w.event(&evs[0]).unwrap();
        let text = String::from_utf8(w.into_inner()).unwrap();
        assert!(text.contains("E: 5.000000 0003 0039 -001\t"));
    }
}
