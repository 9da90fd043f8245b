//! Recording what a touch device sends, as an evemu file a real machine plays back.
//!
//! [`EvdevCapabilities`] is a snapshot of what an evdev device declares: name,
//! input id, property bits, a code bitmask per event type, and the absinfo of
//! each absolute axis. It comes from a device ([`super::device::capabilities`])
//! or from a parsed evemu file ([`super::recording::read_evemu_raw`]), and it
//! decides how the device is decoded ([`EvdevCapabilities::decoder_setup`]).
//!
//! [`EvemuWriter`] writes the capabilities and then the raw events in the
//! evemu text format (file version 1.3), which `evemu-device`/`evemu-play`
//! replay through uinput on any Linux machine, and which
//! [`super::recording::read_recording`] reads back:
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
//!
//! [`record_evdev`] is the thin device shell: it opens the node, snapshots its
//! capabilities and writes every event it reads until told to stop.

use super::mt::{
    self, MtAxes, MtProtocol, RawEvent, ABS_MAX, ABS_MT_POSITION_X, ABS_MT_POSITION_Y,
    ABS_MT_PRESSURE, ABS_MT_SLOT, ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_PRESSURE, ABS_X,
    ABS_Y, BTN_TOUCH, EV_ABS, EV_KEY, EV_MSC, EV_SYN,
};
use crate::input::{AxisRange, SurfaceInfo};
use crate::vocab::MAX_CONTACTS;
use std::fmt;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// Event type: switches.
pub const EV_SW: u16 = 0x05;
/// Event type: LEDs.
pub const EV_LED: u16 = 0x11;
/// Event type: sounds.
pub const EV_SND: u16 = 0x12;
/// Event type: key repeat.
pub const EV_REP: u16 = 0x14;
/// Event type: force feedback.
pub const EV_FF: u16 = 0x15;
/// Number of event types (`EV_CNT`).
pub const EV_CNT: usize = 0x20;
/// Number of absolute axis codes (`ABS_CNT`).
pub const ABS_CNT: usize = ABS_MAX as usize + 1;
/// Property bit: the device moves a pointer (touchpads).
pub const INPUT_PROP_POINTER: u16 = 0x00;
/// Property bit: the device is mapped onto a screen (touchscreens).
pub const INPUT_PROP_DIRECT: u16 = 0x01;
/// Bytes of the property bitmask kept (64 properties; the kernel defines 32).
pub const PROP_BYTES: usize = 8;
/// Bytes of each event type's code bitmask kept (`KEY_CNT / 8`, the largest).
pub const MASK_BYTES: usize = 96;
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

/// The absinfo of one absolute axis (`struct input_absinfo`).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct AbsAxisInfo {
    /// Current value (from a device; 0 from a file, which does not record it).
    pub value: i32,
    /// Minimum.
    pub minimum: i32,
    /// Maximum.
    pub maximum: i32,
    /// Noise filter width.
    pub fuzz: i32,
    /// Dead zone.
    pub flat: i32,
    /// Units per millimetre for position axes (0 = unknown).
    pub resolution: i32,
}

impl AbsAxisInfo {
    /// The axis as an [`AxisRange`] (a negative resolution counts as unknown).
    pub fn range(&self) -> AxisRange {
        AxisRange {
            min: f64::from(self.minimum),
            max: f64::from(self.maximum),
            resolution: f64::from(self.resolution.max(0)),
        }
    }
}

/// Why a device cannot be decoded as a touch device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NotTouchReason {
    /// Neither `ABS_MT_POSITION_X/Y` nor a direct (`INPUT_PROP_DIRECT`)
    /// single-touch `ABS_X/ABS_Y` with `BTN_TOUCH`.
    NoTouchAxes,
    /// A position axis whose maximum is not above its minimum.
    EmptyRange {
        /// Axis code.
        code: u16,
        /// Minimum.
        min: i32,
        /// Maximum.
        max: i32,
    },
    /// `ABS_MT_SLOT` not ranging from 0.
    BadSlotAxis {
        /// Minimum.
        min: i32,
        /// Maximum.
        max: i32,
    },
}

impl fmt::Display for NotTouchReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NotTouchReason::NoTouchAxes => write!(
                f,
                "no ABS_MT_POSITION_X/Y axes, and not a direct (INPUT_PROP_DIRECT) \
                 single-touch screen with ABS_X/ABS_Y and BTN_TOUCH"
            ),
            NotTouchReason::EmptyRange { code, min, max } => write!(
                f,
                "position axis 0x{code:02x} has an empty range (min {min}, max {max})"
            ),
            NotTouchReason::BadSlotAxis { min, max } => write!(
                f,
                "ABS_MT_SLOT must range from 0 (found min {min}, max {max})"
            ),
        }
    }
}

/// How a device's events are decoded: what [`mt::MtDecoder::with_protocol`] needs.
#[derive(Clone, Debug, PartialEq)]
pub struct DecoderSetup {
    /// Protocol.
    pub protocol: MtProtocol,
    /// Axes (slots clamped to [`mt::MAX_SLOTS`]; 0 for type A and single touch).
    pub axes: MtAxes,
    /// Slots the device declares (`ABS_MT_SLOT` max + 1), before clamping.
    pub declared_slots: usize,
    /// Most contacts a frame of this device can hold after decoding.
    pub max_contacts: u32,
}

/// What an evdev device declares: the header of an evemu file.
///
/// Fixed-size bitmasks; the name is the only heap data.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EvdevCapabilities {
    /// Device name.
    pub name: String,
    /// Bus type (3 USB, 0x18 I2C, ...).
    pub bus: u16,
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// Version.
    pub version: u16,
    properties: [u8; PROP_BYTES],
    masks: [[u8; MASK_BYTES]; EV_CNT],
    abs: [Option<AbsAxisInfo>; ABS_CNT],
}

impl EvdevCapabilities {
    /// A device named `name` with id 0 and no capability.
    pub fn new(name: impl Into<String>) -> EvdevCapabilities {
        EvdevCapabilities {
            name: name.into(),
            bus: 0,
            vendor: 0,
            product: 0,
            version: 0,
            properties: [0; PROP_BYTES],
            masks: [[0; MASK_BYTES]; EV_CNT],
            abs: [None; ABS_CNT],
        }
    }

    /// Whether property bit `bit` (`INPUT_PROP_*`) is set.
    pub fn has_property(&self, bit: u16) -> bool {
        get_bit(&self.properties, usize::from(bit))
    }

    /// Sets property bit `bit`; `false` when it is beyond the bitmask kept.
    pub fn set_property(&mut self, bit: u16) -> bool {
        set_bit(&mut self.properties, usize::from(bit))
    }

    /// The property bitmask, least significant byte first.
    pub fn property_bytes(&self) -> &[u8; PROP_BYTES] {
        &self.properties
    }

    /// Whether the device is a touchscreen (`INPUT_PROP_DIRECT`).
    pub fn is_direct(&self) -> bool {
        self.has_property(INPUT_PROP_DIRECT)
    }

    /// The code bitmask of event type `ev_type` (empty for a type beyond `EV_CNT`).
    ///
    /// For `EV_SYN` this is whatever the source put there: the kernel's
    /// event-type bitmask from a device (`EVIOCGBIT(0)`), the `B: 00` line from
    /// a file.
    pub fn mask(&self, ev_type: u16) -> &[u8] {
        self.masks
            .get(usize::from(ev_type))
            .map_or(&[][..], |m| &m[..])
    }

    /// Sets byte `index` of event type `ev_type`'s bitmask; `false` when out of range.
    pub fn set_mask_byte(&mut self, ev_type: u16, index: usize, byte: u8) -> bool {
        match self
            .masks
            .get_mut(usize::from(ev_type))
            .and_then(|m| m.get_mut(index))
        {
            Some(b) => {
                *b = byte;
                true
            }
            None => false,
        }
    }

    /// Whether the device declares `code` of event type `ev_type`.
    pub fn has_code(&self, ev_type: u16, code: u16) -> bool {
        get_bit(self.mask(ev_type), usize::from(code))
    }

    /// Declares `code` of event type `ev_type`; `false` when out of range.
    pub fn set_code(&mut self, ev_type: u16, code: u16) -> bool {
        match self.masks.get_mut(usize::from(ev_type)) {
            Some(m) => set_bit(m, usize::from(code)),
            None => false,
        }
    }

    /// Whether the device sends events of type `ev_type` (`EV_SYN` always;
    /// other types when any of their codes is declared).
    pub fn has_type(&self, ev_type: u16) -> bool {
        ev_type == EV_SYN || self.mask(ev_type).iter().any(|&b| b != 0)
    }

    /// The codes declared for `ev_type`, ascending.
    pub fn codes(&self, ev_type: u16) -> impl Iterator<Item = u16> + '_ {
        let m = self.mask(ev_type);
        (0..m.len() * 8)
            .filter(move |&i| get_bit(m, i))
            .map(|i| i as u16)
    }

    /// The absinfo of axis `code`, when declared.
    pub fn abs(&self, code: u16) -> Option<AbsAxisInfo> {
        self.abs.get(usize::from(code)).copied().flatten()
    }

    /// Declares axis `code` with its absinfo; `false` when `code` is beyond `ABS_MAX`.
    pub fn set_abs(&mut self, code: u16, info: AbsAxisInfo) -> bool {
        match self.abs.get_mut(usize::from(code)) {
            Some(a) => {
                *a = Some(info);
                self.set_code(EV_ABS, code)
            }
            None => false,
        }
    }

    /// How to decode this device: type B when it has `ABS_MT_POSITION_X/Y` and
    /// `ABS_MT_SLOT`, type A with the positions and no slot axis, single touch
    /// for a direct (`INPUT_PROP_DIRECT`) screen with `ABS_X/ABS_Y` and
    /// `BTN_TOUCH`.
    ///
    /// # Errors
    /// [`NotTouchReason`] when none applies, or an axis range is unusable.
    pub fn decoder_setup(&self) -> Result<DecoderSetup, NotTouchReason> {
        let range = |code: u16| self.abs(code).map(|a| a.range());
        let check = |code: u16| match self.abs(code) {
            Some(a) if a.maximum > a.minimum => Ok(a.range()),
            Some(a) => Err(NotTouchReason::EmptyRange {
                code,
                min: a.minimum,
                max: a.maximum,
            }),
            None => Err(NotTouchReason::NoTouchAxes),
        };
        if self.abs(ABS_MT_POSITION_X).is_some() && self.abs(ABS_MT_POSITION_Y).is_some() {
            let x = check(ABS_MT_POSITION_X)?;
            let y = check(ABS_MT_POSITION_Y)?;
            let (protocol, declared) = match self.abs(ABS_MT_SLOT) {
                Some(s) if s.minimum != 0 || s.maximum < 0 => {
                    return Err(NotTouchReason::BadSlotAxis {
                        min: s.minimum,
                        max: s.maximum,
                    })
                }
                Some(s) => (MtProtocol::B, s.maximum as usize + 1),
                None => (MtProtocol::A, 0),
            };
            let slots = declared.min(mt::MAX_SLOTS);
            return Ok(DecoderSetup {
                protocol,
                axes: MtAxes {
                    x,
                    y,
                    slots,
                    pressure: range(ABS_MT_PRESSURE),
                    touch_major: range(ABS_MT_TOUCH_MAJOR),
                    touch_minor: range(ABS_MT_TOUCH_MINOR),
                },
                declared_slots: declared,
                max_contacts: if protocol == MtProtocol::B {
                    slots as u32
                } else {
                    MAX_CONTACTS as u32
                },
            });
        }
        let single = self.is_direct()
            && self.abs(ABS_X).is_some()
            && self.abs(ABS_Y).is_some()
            && self.has_code(EV_KEY, BTN_TOUCH);
        if !single {
            return Err(NotTouchReason::NoTouchAxes);
        }
        Ok(DecoderSetup {
            protocol: MtProtocol::SingleTouch,
            axes: MtAxes {
                x: check(ABS_X)?,
                y: check(ABS_Y)?,
                slots: 0,
                pressure: range(ABS_PRESSURE),
                touch_major: None,
                touch_minor: None,
            },
            declared_slots: 0,
            max_contacts: 1,
        })
    }

    /// The surface a decoder set up with `setup` reports.
    pub fn surface(&self, setup: &DecoderSetup) -> SurfaceInfo {
        SurfaceInfo {
            name: self.name.clone(),
            x: setup.axes.x,
            y: setup.axes.y,
            max_contacts: setup.max_contacts,
        }
    }
}

fn get_bit(bytes: &[u8], i: usize) -> bool {
    bytes.get(i / 8).is_some_and(|b| (b >> (i % 8)) & 1 == 1)
}

fn set_bit(bytes: &mut [u8], i: usize) -> bool {
    match bytes.get_mut(i / 8) {
        Some(b) => {
            *b |= 1 << (i % 8);
            true
        }
        None => false,
    }
}

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

/// The kernel name of an event type, or `?`.
pub fn type_name(ev_type: u16) -> &'static str {
    match ev_type {
        EV_SYN => "EV_SYN",
        EV_KEY => "EV_KEY",
        mt::EV_REL => "EV_REL",
        EV_ABS => "EV_ABS",
        EV_MSC => "EV_MSC",
        EV_SW => "EV_SW",
        EV_LED => "EV_LED",
        EV_SND => "EV_SND",
        EV_REP => "EV_REP",
        EV_FF => "EV_FF",
        0x16 => "EV_PWR",
        0x17 => "EV_FF_STATUS",
        _ => "?",
    }
}

/// The kernel name of an event code touch devices send, or `?`.
pub fn code_name(ev_type: u16, code: u16) -> &'static str {
    const ABS: [&str; ABS_CNT] = [
        "ABS_X",
        "ABS_Y",
        "ABS_Z",
        "ABS_RX",
        "ABS_RY",
        "ABS_RZ",
        "ABS_THROTTLE",
        "ABS_RUDDER",
        "ABS_WHEEL",
        "ABS_GAS",
        "ABS_BRAKE",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_HAT0X",
        "ABS_HAT0Y",
        "ABS_HAT1X",
        "ABS_HAT1Y",
        "ABS_HAT2X",
        "ABS_HAT2Y",
        "ABS_HAT3X",
        "ABS_HAT3Y",
        "ABS_PRESSURE",
        "ABS_DISTANCE",
        "ABS_TILT_X",
        "ABS_TILT_Y",
        "ABS_TOOL_WIDTH",
        "?",
        "?",
        "?",
        "ABS_VOLUME",
        "ABS_PROFILE",
        "?",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_MISC",
        "?",
        "?",
        "?",
        "?",
        "?",
        "ABS_RESERVED",
        "ABS_MT_SLOT",
        "ABS_MT_TOUCH_MAJOR",
        "ABS_MT_TOUCH_MINOR",
        "ABS_MT_WIDTH_MAJOR",
        "ABS_MT_WIDTH_MINOR",
        "ABS_MT_ORIENTATION",
        "ABS_MT_POSITION_X",
        "ABS_MT_POSITION_Y",
        "ABS_MT_TOOL_TYPE",
        "ABS_MT_BLOB_ID",
        "ABS_MT_TRACKING_ID",
        "ABS_MT_PRESSURE",
        "ABS_MT_DISTANCE",
        "ABS_MT_TOOL_X",
        "ABS_MT_TOOL_Y",
        "?",
        "?",
    ];
    match (ev_type, code) {
        (EV_SYN, 0) => "SYN_REPORT",
        (EV_SYN, 1) => "SYN_CONFIG",
        (EV_SYN, 2) => "SYN_MT_REPORT",
        (EV_SYN, 3) => "SYN_DROPPED",
        (EV_ABS, c) => ABS.get(usize::from(c)).copied().unwrap_or("?"),
        (EV_KEY, 0x110) => "BTN_LEFT",
        (EV_KEY, 0x111) => "BTN_RIGHT",
        (EV_KEY, 0x112) => "BTN_MIDDLE",
        (EV_KEY, 0x140) => "BTN_TOOL_PEN",
        (EV_KEY, 0x141) => "BTN_TOOL_RUBBER",
        (EV_KEY, mt::BTN_TOOL_FINGER) => "BTN_TOOL_FINGER",
        (EV_KEY, mt::BTN_TOOL_QUINTTAP) => "BTN_TOOL_QUINTTAP",
        (EV_KEY, BTN_TOUCH) => "BTN_TOUCH",
        (EV_KEY, 0x14b) => "BTN_STYLUS",
        (EV_KEY, 0x14c) => "BTN_STYLUS2",
        (EV_KEY, mt::BTN_TOOL_DOUBLETAP) => "BTN_TOOL_DOUBLETAP",
        (EV_KEY, mt::BTN_TOOL_TRIPLETAP) => "BTN_TOOL_TRIPLETAP",
        (EV_KEY, mt::BTN_TOOL_QUADTAP) => "BTN_TOOL_QUADTAP",
        (EV_MSC, 0) => "MSC_SERIAL",
        (EV_MSC, 4) => "MSC_SCAN",
        (EV_MSC, 5) => "MSC_TIMESTAMP",
        _ => "?",
    }
}

/// Records the raw events of the evdev device `node` into `w` as an evemu file,
/// until `stop` is set (checked at least every [`crate::input::STOP_CHECK_US`]).
///
/// Every event the device sends is written as it came (a `SYN_DROPPED` too),
/// with times relative to the first one. The device is not grabbed and its
/// clock is not switched (the times are relative anyway). Returns the number
/// of events written.
///
/// # Errors
/// [`crate::input::Error`] from opening the node, `Unplugged` when it goes away, and
/// [`crate::input::Error::Io`] (op `"write recording"`) when `w` fails.
pub fn record_evdev(
    node: &Path,
    w: impl Write,
    stop: &AtomicBool,
) -> Result<u64, crate::input::Error> {
    let dev = super::device::open_node(node)?;
    let caps = super::device::capabilities(&dev)
        .map_err(|e| crate::input::Error::from_io(node, "query capabilities", e))?;
    let werr = |source| crate::input::Error::Io {
        node: node.to_path_buf(),
        op: "write recording",
        source,
    };
    let mut out = EvemuWriter::new(&caps, w).map_err(werr)?;
    let mut buf = [0u8; super::device::READ_BUF_BYTES];
    while !stop.load(Ordering::Relaxed) {
        let n = super::device::wait_read(
            &dev,
            node,
            &mut buf,
            (crate::input::STOP_CHECK_US / 1000) as u16,
        )?;
        for ev in super::device::parse_input_events(&buf[..n]) {
            out.event(&ev).map_err(werr)?;
        }
        if n > 0 {
            out.flush().map_err(werr)?;
        }
    }
    out.flush().map_err(werr)?;
    Ok(out.events())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::Micros;

    fn caps() -> EvdevCapabilities {
        let mut c = EvdevCapabilities::new("Test\nPanel");
        c.bus = 0x18;
        c.vendor = 0x2575;
        c.product = 0x0204;
        c.version = 0x0111;
        c.set_property(INPUT_PROP_DIRECT);
        c.set_code(EV_KEY, BTN_TOUCH);
        c.set_code(EV_MSC, 5);
        let pos = AbsAxisInfo {
            value: 0,
            minimum: 0,
            maximum: 32767,
            fuzz: 0,
            flat: 0,
            resolution: 55,
        };
        c.set_abs(ABS_MT_POSITION_X, pos);
        c.set_abs(ABS_MT_POSITION_Y, pos);
        c.set_abs(
            ABS_MT_SLOT,
            AbsAxisInfo {
                maximum: 4,
                ..AbsAxisInfo::default()
            },
        );
        c
    }

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

    #[test]
    fn setup_per_protocol() {
        let c = caps();
        let s = c.decoder_setup().unwrap();
        assert_eq!(
            (s.protocol, s.axes.slots, s.max_contacts),
            (MtProtocol::B, 5, 5)
        );
        assert_eq!(c.surface(&s).x.resolution, 55.0);
        let mut a = c.clone();
        a.abs[usize::from(ABS_MT_SLOT)] = None;
        let s = a.decoder_setup().unwrap();
        assert_eq!((s.protocol, s.axes.slots), (MtProtocol::A, 0));
        let mut st = EvdevCapabilities::new("st");
        let r = AbsAxisInfo {
            minimum: 42,
            maximum: 1981,
            ..AbsAxisInfo::default()
        };
        st.set_abs(ABS_X, r);
        st.set_abs(ABS_Y, r);
        st.set_code(EV_KEY, BTN_TOUCH);
        assert_eq!(st.decoder_setup(), Err(NotTouchReason::NoTouchAxes));
        st.set_property(INPUT_PROP_DIRECT);
        let s = st.decoder_setup().unwrap();
        assert_eq!((s.protocol, s.max_contacts), (MtProtocol::SingleTouch, 1));
        let mut bad = c.clone();
        bad.set_abs(ABS_MT_POSITION_Y, AbsAxisInfo::default());
        assert!(matches!(
            bad.decoder_setup(),
            Err(NotTouchReason::EmptyRange { code: 0x36, .. })
        ));
        let mut c2 = c.clone();
        assert!(!c2.set_abs(0x40, r) && !c2.set_code(EV_ABS, 8 * MASK_BYTES as u16));
        assert!(!c2.set_code(0x20, 0) && c2.mask(0x20).is_empty());
        assert_eq!(c.codes(EV_KEY).collect::<Vec<_>>(), vec![BTN_TOUCH]);
        assert!(c.has_type(EV_MSC) && !c.has_type(EV_FF) && c.has_type(EV_SYN));
    }
}
