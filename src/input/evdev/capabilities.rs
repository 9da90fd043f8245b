//! What an evdev device declares: name, input id, property bits, a code bitmask per
//! event type, and the absinfo of each absolute axis. It comes from a device
//! ([`capabilities`](super::capabilities())) or from a parsed evemu file
//! ([`read_evemu_raw`](crate::input::recording::read_evemu_raw)), and it decides how
//! the device is decoded ([`EvdevCapabilities::decoder_setup`]).

use super::codes::{
    ABS_CNT, ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE, ABS_MT_SLOT,
    ABS_MT_TOUCH_MAJOR, ABS_MT_TOUCH_MINOR, ABS_PRESSURE, ABS_X, ABS_Y, BTN_TOUCH, EV_ABS, EV_CNT,
    EV_KEY, EV_SYN, INPUT_PROP_DIRECT,
};
#[cfg(test)]
use super::codes::{EV_FF, EV_MSC};
use super::mt::{MtAxes, MtProtocol};
use crate::input::{AxisRange, SurfaceInfo};
use crate::vocab::MAX_CONTACTS;
use std::fmt;

/// Bytes of the property bitmask kept (64 properties; the kernel defines 32).
pub const PROP_BYTES: usize = 8;
/// Bytes of each event type's code bitmask kept (`KEY_CNT / 8`, the largest).
pub const MASK_BYTES: usize = 96;

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

/// How a device's events are decoded: what [`MtDecoder::with_protocol`](super::MtDecoder::with_protocol) needs.
#[derive(Clone, Debug, PartialEq)]
pub struct DecoderSetup {
    /// Protocol.
    pub protocol: MtProtocol,
    /// Axes (slots clamped to [`MAX_SLOTS`](super::MAX_SLOTS); 0 for type A and single touch).
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
            let slots = declared.min(super::mt::MAX_SLOTS);
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

/// A protocol B panel with five slots (tests of the evdev and recording code).
#[cfg(test)]
pub(crate) fn sample_panel() -> EvdevCapabilities {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn caps() -> EvdevCapabilities {
        sample_panel()
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
