//! The layout a descriptor yields: which bits of which report hold each field of a
//! finger, the feature settings to write at open, and reading a field's value and
//! physical size.

use crate::input::{AxisRange, SurfaceInfo};
use serde::Serialize;
use std::fmt;

/// Largest Contact Count Maximum taken from a descriptor (the kernel's `MT_MAX_MAXCONTACT`).
pub const MAX_DECLARED_CONTACTS: i32 = 250;
/// Widest field whose value is decoded (bits).
pub(super) const MAX_VALUE_BITS: usize = 32;
/// Millimetres per centimetre.
const MM_PER_CM: f64 = 10.0;
/// Millimetres per inch.
const MM_PER_INCH: f64 = 25.4;

/// Why a descriptor holds no touch collection crowdtouch can read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{reason}")]
pub struct NotTouch {
    /// What is missing or wrong, with byte offsets where they help.
    pub reason: String,
}

impl NotTouch {
    pub(super) fn new(reason: impl Into<String>) -> NotTouch {
        NotTouch {
            reason: reason.into(),
        }
    }
}

/// The kind of touch application collection.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Application {
    /// Touch Screen (0x0D:0x04): a direct-touch surface.
    TouchScreen,
    /// Touch Pad (0x0D:0x05): an indirect surface.
    TouchPad,
}

impl Application {
    /// Lower-case name (`"touchscreen"`, `"touchpad"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Application::TouchScreen => "touchscreen",
            Application::TouchPad => "touchpad",
        }
    }
}

impl fmt::Display for Application {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Where one value sits in a report, and how to read it.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct HidField {
    /// Usage page as declared.
    pub usage_page: u16,
    /// Usage id as declared.
    pub usage: u16,
    /// Report ID of the report holding the field (`None`: the descriptor has no IDs).
    pub report_id: Option<u8>,
    /// First bit, counted from the start of the report buffer (the report ID byte,
    /// when there is one, is bits 0..8).
    pub bit_offset: u32,
    /// Width in bits (1..=32 for the fields this module reads).
    pub bit_size: u16,
    /// Logical minimum.
    pub logical_min: i32,
    /// Logical maximum.
    pub logical_max: i32,
    /// Physical minimum (0 when not declared).
    pub physical_min: i32,
    /// Physical maximum (0 when not declared).
    pub physical_max: i32,
    /// Unit, raw 32-bit HID unit code (0 = none); see [`unit_name`](super::unit_name).
    pub unit: u32,
    /// Unit exponent (power of ten applied to the physical range).
    pub unit_exponent: i8,
    /// Whether values are two's complement (the logical minimum is negative).
    pub signed: bool,
}

impl HidField {
    /// The field's raw bits, unsigned, or `None` when `report` is too short.
    ///
    /// # Complexity
    /// O(1): at most five bytes are read.
    #[inline]
    pub fn extract_raw(&self, report: &[u8]) -> Option<u32> {
        let start = self.bit_offset as usize;
        let size = usize::from(self.bit_size);
        if size == 0 || size > MAX_VALUE_BITS {
            return None;
        }
        let first = start / 8;
        let shift = start % 8;
        let nbytes = (shift + size).div_ceil(8);
        let bytes = report.get(first..first.checked_add(nbytes)?)?;
        let mut raw: u64 = 0;
        for (i, b) in bytes.iter().enumerate() {
            raw |= u64::from(*b) << (8 * i);
        }
        Some(((raw >> shift) & ((1u64 << size) - 1)) as u32)
    }

    /// The field's value (sign-extended when [`HidField::signed`]), or `None` when
    /// `report` is too short.
    #[inline]
    pub fn extract(&self, report: &[u8]) -> Option<i64> {
        let raw = self.extract_raw(report)?;
        let size = u32::from(self.bit_size);
        if self.signed && size < 32 && (raw >> (size - 1)) & 1 == 1 {
            Some(i64::from(raw) - (1i64 << size))
        } else if self.signed && size == 32 {
            Some(i64::from(raw as i32))
        } else {
            Some(i64::from(raw))
        }
    }

    /// Bytes a report must have to hold this field.
    pub fn end_byte(&self) -> usize {
        (self.bit_offset as usize + usize::from(self.bit_size)).div_ceil(8)
    }

    /// Millimetres per physical unit, for the length units the kernel accepts
    /// (`0x11` centimetre, `0x13` inch) with the unit exponent applied.
    ///
    /// # Formula
    /// `mm = 10^exponent × (10 for cm, 25.4 for inch)` (HID 1.11 §6.2.2.7; the kernel's
    /// `hidinput_calc_abs_res` accepts exactly these two codes).
    pub fn mm_per_physical_unit(&self) -> Option<f64> {
        let base = match self.unit {
            0x11 => MM_PER_CM,
            0x13 => MM_PER_INCH,
            _ => return None,
        };
        Some(base * 10f64.powi(i32::from(self.unit_exponent)))
    }

    /// Physical length of the field's range in millimetres, when its unit is a length.
    pub fn physical_length_mm(&self) -> Option<f64> {
        let span = f64::from(self.physical_max) - f64::from(self.physical_min);
        (span > 0.0).then_some(())?;
        Some(span * self.mm_per_physical_unit()?)
    }

    /// Logical units per millimetre (0 when unknown), as the kernel derives an
    /// evdev axis resolution (without its rounding to an integer).
    ///
    /// # Formula
    /// `(logical_max − logical_min) / physical_length_mm`
    /// # Units
    /// units/mm
    pub fn resolution(&self) -> f64 {
        let span = f64::from(self.logical_max) - f64::from(self.logical_min);
        match self.physical_length_mm() {
            Some(mm) if span > 0.0 && mm > 0.0 => span / mm,
            _ => 0.0,
        }
    }

    /// The field as an axis range in logical units, with [`HidField::resolution`].
    pub fn axis(&self) -> AxisRange {
        AxisRange {
            min: f64::from(self.logical_min),
            max: f64::from(self.logical_max),
            resolution: self.resolution(),
        }
    }
}

/// The fields of one finger slot of a report.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Finger {
    /// Contact Identifier (read unsigned, never range-checked: devices declare
    /// nonsense logical ranges for it).
    pub contact_id: HidField,
    /// X (Generic Desktop 0x30).
    pub x: HidField,
    /// Y (Generic Desktop 0x31).
    pub y: HidField,
    /// Tip Switch.
    pub tip: Option<HidField>,
    /// In Range.
    pub in_range: Option<HidField>,
    /// Confidence (0 = palm).
    pub confidence: Option<HidField>,
    /// Width of the contact.
    pub width: Option<HidField>,
    /// Height of the contact.
    pub height: Option<HidField>,
    /// Tip Pressure.
    pub pressure: Option<HidField>,
    /// Azimuth (parsed and described; not decoded into frames).
    pub azimuth: Option<HidField>,
}

impl Finger {
    /// Bytes a report must have to hold every field of this finger.
    pub fn end_byte(&self) -> usize {
        [
            Some(self.contact_id),
            Some(self.x),
            Some(self.y),
            self.tip,
            self.in_range,
            self.confidence,
            self.width,
            self.height,
            self.pressure,
            self.azimuth,
        ]
        .iter()
        .flatten()
        .map(HidField::end_byte)
        .max()
        .unwrap_or(0)
    }
}

/// One input report of a touch collection.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TouchReport {
    /// Report ID (`None`: the descriptor uses no report IDs).
    pub report_id: Option<u8>,
    /// Size of the report in bytes, report ID byte included.
    pub size_bytes: usize,
    /// Finger slots, in report order.
    pub fingers: Vec<Finger>,
    /// Contact Count: contacts in this frame (first report of a hybrid frame).
    pub contact_count: Option<HidField>,
    /// Scan Time (device time of the scan; parsed, not used for frame times).
    pub scan_time: Option<HidField>,
}

/// A feature report value to set when the device is opened.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct FeatureSetting {
    /// The feature field.
    pub field: HidField,
    /// Size of its feature report in bytes (report ID byte included).
    pub report_bytes: usize,
    /// Value to write.
    pub value: u32,
}

impl FeatureSetting {
    /// Writes the value into a feature report buffer (as read with GET_FEATURE, or
    /// zeroed with the report ID in byte 0). Returns false when `buf` is too short.
    pub fn apply(&self, buf: &mut [u8]) -> bool {
        let f = &self.field;
        let start = f.bit_offset as usize;
        let size = usize::from(f.bit_size).min(MAX_VALUE_BITS);
        if buf.len() < f.end_byte() || size == 0 {
            return false;
        }
        for i in 0..size {
            let bit = start + i;
            let mask = 1u8 << (bit % 8);
            if (self.value >> i) & 1 == 1 {
                buf[bit / 8] |= mask;
            } else {
                buf[bit / 8] &= !mask;
            }
        }
        true
    }
}

/// A touch application collection: everything needed to decode its reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TouchCollection {
    /// Touch Screen or Touch Pad.
    pub application: Application,
    /// The digitizer usages sit on the vendor page 0xFF00 (Wacom touch nodes).
    pub vendor_usages: bool,
    /// Byte offset of the application Collection item in the descriptor.
    pub offset: usize,
    /// Input reports that carry fingers (at least one).
    pub reports: Vec<TouchReport>,
    /// Contact Count Maximum feature field, when declared.
    pub contact_count_max: Option<HidField>,
    /// Size of the Contact Count Maximum feature report in bytes.
    pub contact_count_max_report_bytes: usize,
    /// Input Mode (Device Mode) feature setting for multi-touch reporting: 2
    /// (multi-input) for touchscreens, 3 (touchpad) when the device has a Touch Pad
    /// collection, as the kernel's hid-multitouch writes it.
    pub input_mode: Option<FeatureSetting>,
    /// Other settings written at open: Surface Switch and Button Switch = 1.
    pub switches: Vec<FeatureSetting>,
    /// Every input report ID the descriptor declares, any collection (sorted).
    pub declared_input_ids: Vec<u8>,
    /// Whether the descriptor uses report IDs (byte 0 of every report).
    pub uses_report_ids: bool,
}

impl TouchCollection {
    /// Finger slots in the widest report.
    pub fn contacts_per_report(&self) -> usize {
        self.reports
            .iter()
            .map(|r| r.fingers.len())
            .max()
            .unwrap_or(0)
    }

    /// Contact Count Maximum's logical maximum when the descriptor declares a
    /// plausible one (1..=250); the device's actual value needs a GET_FEATURE.
    pub fn declared_max_contacts(&self) -> Option<u32> {
        let f = self.contact_count_max?;
        (1..=MAX_DECLARED_CONTACTS)
            .contains(&f.logical_max)
            .then_some(f.logical_max as u32)
    }

    /// Most simultaneous contacts: the declared maximum, else the finger slots per
    /// report.
    pub fn max_contacts(&self) -> u32 {
        self.declared_max_contacts()
            .unwrap_or(self.contacts_per_report() as u32)
    }

    /// The first report's first finger (every collection has one).
    pub fn first_finger(&self) -> Option<&Finger> {
        self.reports.first().and_then(|r| r.fingers.first())
    }

    /// The input report IDs carrying fingers.
    pub fn report_ids(&self) -> Vec<u8> {
        self.reports.iter().filter_map(|r| r.report_id).collect()
    }

    /// The surface: X/Y logical ranges with resolutions from the physical size.
    pub fn surface(&self, name: &str) -> SurfaceInfo {
        let (x, y) = match self.first_finger() {
            Some(f) => (f.x.axis(), f.y.axis()),
            None => {
                let unit = AxisRange {
                    min: 0.0,
                    max: 1.0,
                    resolution: 0.0,
                };
                (unit, unit)
            }
        };
        SurfaceInfo {
            name: name.to_string(),
            x,
            y,
            max_contacts: self.max_contacts(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extract_bits_little_endian_and_signed() {
        let f = HidField {
            usage_page: 1,
            usage: 0x30,
            report_id: None,
            bit_offset: 4,
            bit_size: 12,
            logical_min: -2048,
            logical_max: 2047,
            physical_min: 0,
            physical_max: 0,
            unit: 0,
            unit_exponent: 0,
            signed: true,
        };
        // bits 4..16 of [0xF0, 0xFF] = 0xFFF = -1
        assert_eq!(f.extract(&[0xF0, 0xFF]), Some(-1));
        assert_eq!(f.extract_raw(&[0xF0, 0xFF]), Some(0xFFF));
        assert_eq!(f.extract(&[0x10, 0x00]), Some(1));
        assert_eq!(f.extract(&[0x10]), None);
        let u = HidField {
            signed: false,
            bit_size: 32,
            bit_offset: 0,
            ..f
        };
        assert_eq!(u.extract(&[0xff, 0xff, 0xff, 0xff]), Some(u32::MAX as i64));
    }

    #[test]
    fn mm_conversion() {
        let f = HidField {
            usage_page: 1,
            usage: 0x30,
            report_id: None,
            bit_offset: 0,
            bit_size: 16,
            logical_min: 0,
            logical_max: 32767,
            physical_min: 0,
            physical_max: 5967,
            unit: 0x11,
            unit_exponent: -2,
            signed: false,
        };
        // 59.67 cm = 596.7 mm; 32767 / 596.7 = 54.9 units/mm (Dell Canvas, README).
        assert!((f.physical_length_mm().unwrap() - 596.7).abs() < 1e-9);
        assert_eq!(f.resolution().round(), 55.0);
        let inch = HidField {
            unit: 0x13,
            unit_exponent: -2,
            physical_max: 100,
            ..f
        };
        assert!((inch.physical_length_mm().unwrap() - 25.4).abs() < 1e-9);
        let odd = HidField { unit: 0x33, ..f };
        assert_eq!(odd.resolution(), 0.0);
    }
}
