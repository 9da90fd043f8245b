//! Report descriptor → touch layout: which bits of which report hold each finger.
//!
//! [`touch_collections`] parses a report descriptor with `hidreport` (after the
//! pre-scan described in the [module docs](super)) and returns, for every touch
//! application collection, a [`TouchCollection`]: per input report the finger slots
//! ([`Finger`], one per logical collection), the Contact Count and Scan Time
//! fields, the Contact Count Maximum feature and the feature settings that switch
//! the device to multi-touch reporting ([`FeatureSetting`]).
//!
//! # Finger slots
//!
//! Within one input report of a touch application, every variable input field with
//! a per-finger usage (Tip Switch, In Range, Confidence, Contact Identifier, X, Y,
//! Width, Height, Tip Pressure, Azimuth) belongs to a finger. A new finger starts
//! when the innermost collection changes, or — for devices that put all fingers
//! in one collection — when a usage already set in the current finger comes again
//! and that finger is complete (Contact Identifier, X and Y). A repeated usage in
//! an incomplete finger is ignored (the ELAN 04F3:010C declares X/Y twice per
//! finger), as the kernel's hid-multitouch does. A finger needs a Contact
//! Identifier, X, Y, and a Tip Switch or In Range.
//!
//! # Errors
//!
//! Never panics, whatever the bytes: malformed or hostile descriptors give a
//! [`NotTouch`] naming the byte offset.

use super::usage as u;
use crate::input::{AxisRange, SurfaceInfo};
use hidreport::hid::{GlobalItem, Item, ItemType, LocalItem, MainItem, ReportDescriptorItems};
use hidreport::{Collection, CollectionType, Field, Report, ReportDescriptor, VariableField};
use serde::Serialize;
use serde_json::{json, Value};
use std::fmt;
use std::path::{Path, PathBuf};

/// Most bytes in a report descriptor (the kernel's `HID_MAX_DESCRIPTOR_SIZE`).
pub const MAX_DESCRIPTOR_BYTES: usize = 4096;
/// Largest Report Size (bits) a data item may use (the kernel's limit).
pub const MAX_REPORT_SIZE_BITS: u64 = 256;
/// Largest Report Count a data item may use (the kernel's `HID_MAX_USAGES`).
pub const MAX_REPORT_COUNT: u64 = 12_288;
/// Largest Contact Count Maximum taken from a descriptor (the kernel's `MT_MAX_MAXCONTACT`).
pub const MAX_DECLARED_CONTACTS: i32 = 250;
/// Most usages one Usage Minimum/Maximum pair may expand to.
const MAX_USAGE_RANGE: u64 = 65_536;
/// Most data bits all items of a descriptor may declare together.
const MAX_TOTAL_BITS: u64 = 1 << 24;
/// Rough bound on the memory `hidreport` may use for one descriptor, in bytes.
const MAX_PARSE_COST_BYTES: u64 = 64 << 20;
/// Widest field whose value is decoded (bits).
const MAX_VALUE_BITS: usize = 32;
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
    fn new(reason: impl Into<String>) -> NotTouch {
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
    /// Unit, raw 32-bit HID unit code (0 = none); see [`unit_name`].
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

    /// Description for [`describe`].
    fn to_json(self) -> Value {
        json!({
            "usage": format!("0x{:04x}:0x{:04x}", self.usage_page, self.usage),
            "report_id": self.report_id,
            "bit_offset": self.bit_offset,
            "bit_size": self.bit_size,
            "logical": [self.logical_min, self.logical_max],
            "physical": [self.physical_min, self.physical_max],
            "unit": format!("0x{:x}", self.unit),
            "unit_name": unit_name(self.unit),
            "unit_exponent": self.unit_exponent,
            "signed": self.signed,
            "physical_length_mm": self.physical_length_mm(),
        })
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

    fn named_fields(&self) -> Vec<(&'static str, HidField)> {
        let mut v = vec![
            ("contact_id", self.contact_id),
            ("x", self.x),
            ("y", self.y),
        ];
        for (name, f) in [
            ("tip_switch", self.tip),
            ("in_range", self.in_range),
            ("confidence", self.confidence),
            ("width", self.width),
            ("height", self.height),
            ("tip_pressure", self.pressure),
            ("azimuth", self.azimuth),
        ] {
            if let Some(f) = f {
                v.push((name, f));
            }
        }
        v
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

// ---------------------------------------------------------------------------
// Pre-scan: make the bytes safe for hidreport and correct its Maximum signedness.

/// The descriptor as handed to `hidreport`, with a map back to original offsets.
struct Normalised {
    bytes: Vec<u8>,
    /// `(first normalised offset, bytes inserted before it)`, increasing.
    shifts: Vec<(usize, usize)>,
}

impl Normalised {
    fn original_offset(&self, off: usize) -> usize {
        let shift = self
            .shifts
            .iter()
            .rev()
            .find(|(start, _)| *start <= off)
            .map_or(0, |(_, s)| *s);
        off.saturating_sub(shift)
    }
}

/// hidreport's global state, as far as the pre-scan needs it.
#[derive(Copy, Clone, Default)]
struct ScanGlobals {
    logical_min_negative: bool,
    physical_min_negative: bool,
    report_size: u64,
    report_count: u64,
}

/// hidreport's local state, as far as the pre-scan needs it.
#[derive(Copy, Clone, Default)]
struct ScanLocals {
    usages: u64,
    usage_min: Option<u32>,
    usage_max: Option<u32>,
}

impl ScanLocals {
    /// Usages hidreport's `compile_usages` would create.
    fn compiled(&self) -> u64 {
        match (self.usage_min, self.usage_max) {
            (Some(min), Some(max)) if max >= min => u64::from(max - min) + 1,
            (Some(_), _) => 0,
            (None, _) => self.usages,
        }
    }
}

/// Widens a Logical/Physical Maximum item whose data hidreport would sign-extend
/// but the kernel reads unsigned. Returns the replacement bytes.
fn widen_maximum(item: &[u8]) -> Option<Vec<u8>> {
    let data = item.get(1..)?;
    let top_set = data.last().is_some_and(|b| b & 0x80 != 0);
    let (code, width) = match data.len() {
        1 => (2u8, 2usize),
        2 => (3, 4),
        _ => return None,
    };
    if !top_set {
        return None;
    }
    let mut out = Vec::with_capacity(1 + width);
    out.push((item[0] & 0xFC) | code);
    out.extend_from_slice(data);
    out.resize(1 + width, 0);
    Some(out)
}

/// Checks a descriptor against the kernel's limits and `hidreport`'s weak spots,
/// and returns the bytes to parse (see the [module docs](super)).
fn normalise(desc: &[u8]) -> Result<Normalised, NotTouch> {
    if desc.is_empty() {
        return Err(NotTouch::new("the report descriptor is empty"));
    }
    if desc.len() > MAX_DESCRIPTOR_BYTES {
        return Err(NotTouch::new(format!(
            "the report descriptor has {} bytes, more than the {MAX_DESCRIPTOR_BYTES} HID allows",
            desc.len()
        )));
    }
    let items = ReportDescriptorItems::try_from(desc).map_err(|e| parse_error(&e, |o| o))?;
    // Usage Page (0) first: a page-less Usage then gets page 0, as in the kernel,
    // instead of hidreport's `expect`.
    let prefix = [0x05u8, 0x00];
    let mut out = Vec::with_capacity(desc.len() + prefix.len() + 16);
    out.extend_from_slice(&prefix);
    let mut shifts = vec![(0usize, prefix.len())];
    let mut globals = vec![ScanGlobals::default()];
    let mut locals = vec![ScanLocals::default()];
    let mut open: Vec<u64> = Vec::new();
    let mut open_cost: u64 = 0;
    let mut cost: u64 = 0;
    let mut total_bits: u64 = 0;
    let mut copied_to = 0usize;
    let too_complex = |offset: usize| {
        NotTouch::new(format!(
            "unparsable report descriptor at byte {offset}: it declares more fields, \
             usages or nesting than a device can have"
        ))
    };
    for it in items.iter() {
        let offset = it.offset();
        let item = it.item();
        let raw = item.bytes();
        let (Some(g), Some(l)) = (globals.last().copied(), locals.last().copied()) else {
            break;
        };
        let mut replacement = None;
        match item.item_type() {
            ItemType::Main(main) => match main {
                MainItem::Collection(_) => {
                    let n = l.compiled();
                    if n > MAX_USAGE_RANGE {
                        return Err(usage_range_error(offset, n));
                    }
                    let c = 48 + 4 * n;
                    cost = cost.saturating_add(c);
                    open.push(c);
                    open_cost = open_cost.saturating_add(c);
                    reset_top(&mut locals);
                }
                MainItem::EndCollection => {
                    let Some(c) = open.pop() else {
                        // hidreport refuses the descriptor here.
                        break;
                    };
                    open_cost = open_cost.saturating_sub(c);
                    reset_top(&mut locals);
                }
                MainItem::Input(_) | MainItem::Output(_) | MainItem::Feature(_) => {
                    if g.report_size > 0 && g.report_count > 0 {
                        if g.report_size > MAX_REPORT_SIZE_BITS {
                            return Err(NotTouch::new(format!(
                                "unparsable report descriptor at byte {offset}: Report Size {} \
                                 bits is more than the {MAX_REPORT_SIZE_BITS} allowed",
                                g.report_size
                            )));
                        }
                        if g.report_count > MAX_REPORT_COUNT {
                            return Err(NotTouch::new(format!(
                                "unparsable report descriptor at byte {offset}: Report Count {} \
                                 is more than the {MAX_REPORT_COUNT} allowed",
                                g.report_count
                            )));
                        }
                        total_bits += g.report_size * g.report_count;
                        if total_bits > MAX_TOTAL_BITS {
                            return Err(too_complex(offset));
                        }
                        let flags = raw.get(1).copied().unwrap_or(0);
                        let constant = flags & 1 != 0;
                        let variable = flags & 2 != 0;
                        if constant {
                            cost = cost.saturating_add(64);
                        } else {
                            let n = l.compiled();
                            if n > MAX_USAGE_RANGE {
                                return Err(usage_range_error(offset, n));
                            }
                            let per_field = 200u64.saturating_add(open_cost);
                            let fields = if variable { g.report_count } else { 1 };
                            cost = cost
                                .saturating_add(4 * n)
                                .saturating_add(fields.saturating_mul(per_field));
                        }
                    }
                    reset_top(&mut locals);
                }
            },
            ItemType::Global(global) => {
                let Some(top) = globals.last_mut() else {
                    break;
                };
                match global {
                    GlobalItem::LogicalMinimum(v) => top.logical_min_negative = i32::from(v) < 0,
                    GlobalItem::PhysicalMinimum(v) => top.physical_min_negative = i32::from(v) < 0,
                    GlobalItem::LogicalMaximum(_) if !g.logical_min_negative => {
                        replacement = widen_maximum(raw);
                    }
                    GlobalItem::PhysicalMaximum(_) if !g.physical_min_negative => {
                        replacement = widen_maximum(raw);
                    }
                    GlobalItem::ReportSize(v) => top.report_size = usize::from(v) as u64,
                    GlobalItem::ReportCount(v) => top.report_count = usize::from(v) as u64,
                    GlobalItem::Push => {
                        globals.push(g);
                        locals.push(l);
                        cost = cost.saturating_add(64 + 8 * l.usages);
                    }
                    GlobalItem::Pop => {
                        if globals.len() <= 1 {
                            // hidreport refuses the descriptor here.
                            break;
                        }
                        globals.pop();
                        locals.pop();
                    }
                    _ => {}
                }
            }
            ItemType::Local(local) => {
                let Some(top) = locals.last_mut() else {
                    break;
                };
                match local {
                    LocalItem::Usage(..) | LocalItem::UsageId(_) => {
                        top.usages += 1;
                        cost = cost.saturating_add(8);
                    }
                    LocalItem::UsageMinimum(v) => top.usage_min = Some(u32::from(v)),
                    LocalItem::UsageMaximum(v) => top.usage_max = Some(u32::from(v)),
                    _ => {}
                }
            }
            ItemType::Long | ItemType::Reserved => {}
        }
        if cost > MAX_PARSE_COST_BYTES {
            return Err(too_complex(offset));
        }
        if let Some(new) = replacement {
            out.extend_from_slice(&desc[copied_to..offset]);
            out.extend_from_slice(&new);
            copied_to = offset + raw.len();
            let grown = new.len() - raw.len();
            let shift = shifts.last().map_or(0, |s| s.1) + grown;
            shifts.push((out.len(), shift));
        }
    }
    out.extend_from_slice(desc.get(copied_to..).unwrap_or(&[]));
    Ok(Normalised { bytes: out, shifts })
}

fn reset_top(locals: &mut [ScanLocals]) {
    if let Some(top) = locals.last_mut() {
        *top = ScanLocals::default();
    }
}

fn usage_range_error(offset: usize, n: u64) -> NotTouch {
    NotTouch::new(format!(
        "unparsable report descriptor at byte {offset}: a Usage Minimum/Maximum range of \
         {n} usages (at most {MAX_USAGE_RANGE} accepted)"
    ))
}

fn parse_error(e: &hidreport::ParserError, map: impl Fn(usize) -> usize) -> NotTouch {
    match e {
        hidreport::ParserError::InvalidData { offset, message } => NotTouch::new(format!(
            "unparsable report descriptor at byte {}: {message}",
            map(*offset)
        )),
        other => NotTouch::new(format!("unparsable report descriptor: {other}")),
    }
}

// ---------------------------------------------------------------------------
// Layout extraction

/// The byte offset of a collection, from `CollectionId`'s `Debug` form (hidreport
/// has no accessor); `None` if that form ever changes.
fn collection_offset(c: &Collection) -> Option<usize> {
    let s = format!("{:?}", c.id());
    let digits: String = s.chars().filter(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// First usage of a collection as `(page, id)`.
fn collection_usage(c: &Collection) -> Option<(u16, u16)> {
    c.usages()
        .first()
        .map(|u| (u16::from(u.usage_page), u16::from(u.usage_id)))
}

/// The outermost application collection of a field.
fn application_of(v: &VariableField) -> Option<&Collection> {
    v.collections
        .iter()
        .find(|c| c.collection_type() == CollectionType::Application)
}

/// Whether an application usage is a touch application; `(kind, vendor)`.
fn touch_application(usage: (u16, u16)) -> Option<(Application, bool)> {
    let kind = match usage.1 {
        u::TOUCH_SCREEN => Application::TouchScreen,
        u::TOUCH_PAD => Application::TouchPad,
        _ => return None,
    };
    match usage.0 {
        u::PAGE_DIGITIZER => Some((kind, false)),
        u::PAGE_VENDOR_FF00 => Some((kind, true)),
        _ => None,
    }
}

/// A usage as this module reads it: vendor-page usages of a Wacom-style touch
/// application mapped to their digitizer / Generic Desktop twins.
fn effective_usage(page: u16, id: u16, vendor: bool) -> (u16, u16) {
    if vendor && page == u::PAGE_VENDOR_FF00 {
        match id {
            u::VENDOR_X => (u::PAGE_GENERIC_DESKTOP, u::X),
            u::VENDOR_Y => (u::PAGE_GENERIC_DESKTOP, u::Y),
            id if id < 0x100 => (u::PAGE_DIGITIZER, id),
            id => (page, id),
        }
    } else {
        (page, id)
    }
}

fn field_of(v: &VariableField, report_id: Option<u8>) -> HidField {
    let logical_min = i32::from(v.logical_minimum);
    HidField {
        usage_page: u16::from(v.usage.usage_page),
        usage: u16::from(v.usage.usage_id),
        report_id,
        bit_offset: u32::try_from(v.bits.start).unwrap_or(u32::MAX),
        bit_size: u16::try_from(v.bits.len()).unwrap_or(u16::MAX),
        logical_min,
        logical_max: i32::from(v.logical_maximum),
        physical_min: v.physical_minimum.map_or(0, i32::from),
        physical_max: v.physical_maximum.map_or(0, i32::from),
        unit: v.unit.map_or(0, u32::from),
        unit_exponent: v.unit_exponent.map_or(0, |e| e.exponent()),
        signed: logical_min < 0,
    }
}

/// A finger being assembled from consecutive fields.
#[derive(Default)]
struct FingerBuilder<'a> {
    key: Option<&'a Collection>,
    contact_id: Option<HidField>,
    x: Option<HidField>,
    y: Option<HidField>,
    tip: Option<HidField>,
    in_range: Option<HidField>,
    confidence: Option<HidField>,
    width: Option<HidField>,
    height: Option<HidField>,
    pressure: Option<HidField>,
    azimuth: Option<HidField>,
}

impl<'a> FingerBuilder<'a> {
    fn slot(&mut self, usage: (u16, u16)) -> Option<&mut Option<HidField>> {
        Some(match usage {
            (u::PAGE_GENERIC_DESKTOP, u::X) => &mut self.x,
            (u::PAGE_GENERIC_DESKTOP, u::Y) => &mut self.y,
            (u::PAGE_DIGITIZER, u::CONTACT_ID) => &mut self.contact_id,
            (u::PAGE_DIGITIZER, u::TIP_SWITCH) => &mut self.tip,
            (u::PAGE_DIGITIZER, u::IN_RANGE) => &mut self.in_range,
            (u::PAGE_DIGITIZER, u::CONFIDENCE) => &mut self.confidence,
            (u::PAGE_DIGITIZER, u::WIDTH) => &mut self.width,
            (u::PAGE_DIGITIZER, u::HEIGHT) => &mut self.height,
            (u::PAGE_DIGITIZER, u::TIP_PRESSURE) => &mut self.pressure,
            (u::PAGE_DIGITIZER, u::AZIMUTH) => &mut self.azimuth,
            _ => return None,
        })
    }

    fn complete(&self) -> bool {
        self.contact_id.is_some() && self.x.is_some() && self.y.is_some()
    }

    fn is_empty(&self) -> bool {
        [
            self.contact_id,
            self.x,
            self.y,
            self.tip,
            self.in_range,
            self.confidence,
            self.width,
            self.height,
            self.pressure,
            self.azimuth,
        ]
        .iter()
        .all(Option::is_none)
    }

    /// The finger, or what it lacks.
    fn build(&self) -> Result<Finger, &'static str> {
        let (Some(contact_id), Some(x), Some(y)) = (self.contact_id, self.x, self.y) else {
            return Err(if self.contact_id.is_none() {
                "no Contact Identifier"
            } else {
                "no X/Y"
            });
        };
        if self.tip.is_none() && self.in_range.is_none() {
            return Err("no Tip Switch or In Range");
        }
        for f in [contact_id, x, y] {
            if f.bit_size == 0 || usize::from(f.bit_size) > MAX_VALUE_BITS {
                return Err("a Contact Identifier, X or Y field wider than 32 bits");
            }
        }
        for f in [x, y] {
            if f.logical_max <= f.logical_min {
                return Err("an X or Y logical range that is empty");
            }
        }
        let usable = |f: Option<HidField>| {
            f.filter(|f| f.bit_size > 0 && usize::from(f.bit_size) <= MAX_VALUE_BITS)
        };
        Ok(Finger {
            contact_id,
            x,
            y,
            tip: usable(self.tip),
            in_range: usable(self.in_range),
            confidence: usable(self.confidence),
            width: usable(self.width),
            height: usable(self.height),
            pressure: usable(self.pressure),
            azimuth: usable(self.azimuth),
        })
    }
}

/// Whether a usage belongs to a finger slot.
fn is_finger_usage(usage: (u16, u16)) -> bool {
    FingerBuilder::default().slot(usage).is_some()
}

/// A touch application collection that could not be used, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Rejected {
    application: Application,
    offset: Option<usize>,
    reason: String,
}

/// What a descriptor holds.
struct Analysis {
    collections: Vec<TouchCollection>,
    rejected: Vec<Rejected>,
}

/// All variable fields of one direction, with their report IDs.
fn variable_fields<R: Report>(reports: &[R]) -> Vec<(Option<u8>, usize, &VariableField)> {
    let mut out = Vec::new();
    for r in reports {
        let id = r.report_id().as_ref().map(u8::from);
        for f in r.fields() {
            if let Field::Variable(v) = f {
                out.push((id, r.size_in_bytes(), v));
            }
        }
    }
    out
}

fn analyse(desc: &[u8]) -> Result<Analysis, NotTouch> {
    let norm = normalise(desc)?;
    let rd = ReportDescriptor::try_from(&norm.bytes[..])
        .map_err(|e| parse_error(&e, |o| norm.original_offset(o)))?;
    let inputs = variable_fields(rd.input_reports());
    let features = variable_fields(rd.feature_reports());
    let offset_of = |c: &Collection| collection_offset(c).map(|o| norm.original_offset(o));

    let mut declared_input_ids: Vec<u8> = rd
        .input_reports()
        .iter()
        .filter_map(|r| r.report_id().as_ref().map(u8::from))
        .collect();
    declared_input_ids.sort_unstable();
    declared_input_ids.dedup();
    let uses_report_ids = rd.input_reports().iter().any(|r| r.report_id().is_some())
        || rd.feature_reports().iter().any(|r| r.report_id().is_some());

    // Touch applications, in descriptor order.
    let mut apps: Vec<(&Collection, Application, bool)> = Vec::new();
    for (_, _, v) in inputs.iter().chain(features.iter()) {
        if let Some(app) = application_of(v) {
            if apps.iter().any(|(a, _, _)| *a == app) {
                continue;
            }
            if let Some((kind, vendor)) = collection_usage(app).and_then(touch_application) {
                apps.push((app, kind, vendor));
            }
        }
    }
    apps.sort_by_key(|(a, _, _)| collection_offset(a));
    let any_touchpad = apps.iter().any(|(_, k, _)| *k == Application::TouchPad);

    // Multi-touch mode settings: the first Input Mode, Surface/Button Switch, in a
    // touch or Device Configuration application.
    let in_config_or_touch = |v: &VariableField| {
        application_of(v)
            .and_then(collection_usage)
            .is_some_and(|usage| {
                usage == (u::PAGE_DIGITIZER, u::DEVICE_CONFIGURATION)
                    || touch_application(usage).is_some()
            })
    };
    let setting = |id: Option<u8>, bytes: usize, v: &VariableField, value: u32| FeatureSetting {
        field: field_of(v, id),
        report_bytes: bytes,
        value,
    };
    let mut input_mode = None;
    let mut switches = Vec::new();
    for (id, bytes, v) in &features {
        if !in_config_or_touch(v) {
            continue;
        }
        let vendor = application_of(v)
            .and_then(collection_usage)
            .and_then(touch_application)
            .is_some_and(|(_, vendor)| vendor);
        let usage = effective_usage(
            u16::from(v.usage.usage_page),
            u16::from(v.usage.usage_id),
            vendor,
        );
        match usage {
            (u::PAGE_DIGITIZER, u::INPUT_MODE) if input_mode.is_none() => {
                let mode = if any_touchpad { 3 } else { 2 };
                input_mode = Some(setting(*id, *bytes, v, mode));
            }
            (u::PAGE_DIGITIZER, u::SURFACE_SWITCH | u::BUTTON_SWITCH) => {
                switches.push(setting(*id, *bytes, v, 1));
            }
            _ => {}
        }
    }

    let mut collections = Vec::new();
    let mut rejected = Vec::new();
    for (app, kind, vendor) in &apps {
        let eff = |v: &VariableField| {
            effective_usage(
                u16::from(v.usage.usage_page),
                u16::from(v.usage.usage_id),
                *vendor,
            )
        };
        // Input reports of this application, in order of first appearance.
        let mut report_ids: Vec<(Option<u8>, usize)> = Vec::new();
        for (id, bytes, v) in &inputs {
            if application_of(v) == Some(app) && !report_ids.iter().any(|(i, _)| i == id) {
                report_ids.push((*id, *bytes));
            }
        }
        let mut reports = Vec::new();
        let mut problems: Vec<String> = Vec::new();
        for (rid, size_bytes) in report_ids {
            let mut builders: Vec<FingerBuilder<'_>> = Vec::new();
            let mut cur = FingerBuilder::default();
            let mut contact_count = None;
            let mut scan_time = None;
            for (id, _, v) in &inputs {
                if *id != rid || application_of(v) != Some(app) {
                    continue;
                }
                let usage = eff(v);
                let field = field_of(v, rid);
                match usage {
                    (u::PAGE_DIGITIZER, u::CONTACT_COUNT) => {
                        contact_count.get_or_insert(field);
                        continue;
                    }
                    (u::PAGE_DIGITIZER, u::SCAN_TIME) => {
                        scan_time.get_or_insert(field);
                        continue;
                    }
                    _ => {}
                }
                let key = v.collections.last().filter(|c| *c != *app);
                if !is_finger_usage(usage) {
                    continue;
                }
                let new_key = key != cur.key && !cur.is_empty();
                let repeated = cur.slot(usage).is_some_and(|s| s.is_some());
                if new_key || (repeated && cur.complete()) {
                    builders.push(std::mem::take(&mut cur));
                } else if repeated {
                    // A duplicate usage in an incomplete finger: ignored.
                    continue;
                }
                cur.key = key;
                if let Some(s) = cur.slot(usage) {
                    *s = Some(field);
                }
            }
            if !cur.is_empty() {
                builders.push(cur);
            }
            let mut fingers = Vec::new();
            for (i, b) in builders.iter().enumerate() {
                match b.build() {
                    Ok(f) => fingers.push(f),
                    Err(why) => problems.push(format!(
                        "finger {} of input report {} has {why}",
                        i + 1,
                        rid.map_or("(no ID)".to_string(), |r| r.to_string())
                    )),
                }
            }
            if !fingers.is_empty() {
                let need = fingers
                    .iter()
                    .map(Finger::end_byte)
                    .chain(contact_count.iter().map(HidField::end_byte))
                    .max()
                    .unwrap_or(0);
                reports.push(TouchReport {
                    report_id: rid,
                    size_bytes: size_bytes.max(need),
                    fingers,
                    contact_count,
                    scan_time,
                });
            }
        }
        let where_ = match offset_of(app) {
            Some(o) => format!(
                "{} application collection at byte {o}",
                application_label(*kind)
            ),
            None => format!("{} application collection", application_label(*kind)),
        };
        if reports.is_empty() {
            let has = |usage: (u16, u16)| {
                inputs
                    .iter()
                    .any(|(_, _, v)| application_of(v) == Some(app) && eff(v) == usage)
            };
            let reason = if !has((u::PAGE_DIGITIZER, u::CONTACT_ID)) {
                format!(
                    "the {where_} has no Contact Identifier (a single-touch or \
                     mouse-emulation layout, not multi-touch)"
                )
            } else if !has((u::PAGE_GENERIC_DESKTOP, u::X)) || !has((u::PAGE_GENERIC_DESKTOP, u::Y))
            {
                format!("the {where_} has no X/Y")
            } else if let Some(p) = problems.first() {
                format!("the {where_}: {p}")
            } else {
                format!("the {where_} has no finger fields")
            };
            rejected.push(Rejected {
                application: *kind,
                offset: offset_of(app),
                reason,
            });
            continue;
        }
        // Contact Count Maximum of this application.
        let mut contact_count_max = None;
        let mut contact_count_max_report_bytes = 0;
        for (id, bytes, v) in &features {
            if application_of(v) == Some(app) && eff(v) == (u::PAGE_DIGITIZER, u::CONTACT_COUNT_MAX)
            {
                contact_count_max = Some(field_of(v, *id));
                contact_count_max_report_bytes = *bytes;
                break;
            }
        }
        collections.push(TouchCollection {
            application: *kind,
            vendor_usages: *vendor,
            offset: offset_of(app).unwrap_or(0),
            reports,
            contact_count_max,
            contact_count_max_report_bytes,
            input_mode,
            switches: switches.clone(),
            declared_input_ids: declared_input_ids.clone(),
            uses_report_ids,
        });
    }
    Ok(Analysis {
        collections,
        rejected,
    })
}

fn application_label(kind: Application) -> &'static str {
    match kind {
        Application::TouchScreen => "Touch Screen",
        Application::TouchPad => "Touch Pad",
    }
}

/// The touch application collections of a report descriptor.
///
/// # Errors
/// [`NotTouch`] when there is none crowdtouch can read, saying why: no digitizer
/// touch application, a touch collection with no Contact Identifier, no X/Y,
/// an unparsable descriptor (with the byte offset), a descriptor over
/// [`MAX_DESCRIPTOR_BYTES`].
///
/// # Example
/// ```
/// use crowdtouch::input::hid::touch_collections;
/// // A mouse.
/// let mouse = [0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x30, 0x15, 0x81, 0x25, 0x7f,
///              0x75, 0x08, 0x95, 0x01, 0x81, 0x06, 0xc0];
/// let err = touch_collections(&mouse).unwrap_err();
/// assert!(err.reason.contains("no Touch Screen or Touch Pad"), "{}", err.reason);
/// ```
pub fn touch_collections(descriptor: &[u8]) -> Result<Vec<TouchCollection>, NotTouch> {
    let a = analyse(descriptor)?;
    if a.collections.is_empty() {
        return Err(no_collection(&a));
    }
    Ok(a.collections)
}

/// Why an analysis found no usable collection.
fn no_collection(a: &Analysis) -> NotTouch {
    if a.rejected.is_empty() {
        return NotTouch::new(
            "no Touch Screen or Touch Pad application collection (digitizer page 0x0D, \
             usage 0x04/0x05) with input fields",
        );
    }
    let reasons: Vec<&str> = a.rejected.iter().map(|r| r.reason.as_str()).collect();
    NotTouch::new(reasons.join("; "))
}

/// A readable name for a HID unit code (HID 1.11 §6.2.2.7), e.g. `"cm"`,
/// `"inch^3"`, `"cm*s^-1"`; `"none"` for 0.
pub fn unit_name(unit: u32) -> String {
    if unit == 0 {
        return "none".into();
    }
    let nibble = |i: u32| (unit >> (4 * i)) & 0xF;
    let exponent = |n: u32| if n >= 8 { n as i32 - 16 } else { n as i32 };
    let system = nibble(0);
    let (length, mass, temperature) = match system {
        1 => ("cm", "g", "K"),
        2 => ("rad", "g", "K"),
        3 => ("inch", "slug", "F"),
        4 => ("deg", "slug", "F"),
        0 => ("", "", ""),
        _ => return format!("vendor or reserved unit 0x{unit:x}"),
    };
    let mut parts = Vec::new();
    for (i, name) in [
        (1, length),
        (2, mass),
        (3, "s"),
        (4, temperature),
        (5, "A"),
        (6, "cd"),
    ] {
        let e = exponent(nibble(i));
        if e == 0 || name.is_empty() {
            continue;
        }
        parts.push(if e == 1 {
            name.to_string()
        } else {
            format!("{name}^{e}")
        });
    }
    if parts.is_empty() {
        format!("0x{unit:x}")
    } else {
        parts.join("*")
    }
}

/// Describes a report descriptor's touch collections as JSON (for
/// `crowdtouch hid describe`).
///
/// `{"touch": true, "descriptor_bytes": N, "collections": [...], "ignored": [...]}`,
/// one object per usable touch application collection with `application`,
/// `contacts_per_report`, `max_contacts` (and its source), `report_ids`,
/// `contact_count`, `contact_count_maximum`, `input_mode`, `surface` (X/Y ranges,
/// resolution, size in mm) and `finger_fields` (every field of the first finger
/// with logical/physical ranges and units) plus `fingers` (bit offsets of all);
/// `ignored` lists touch collections that cannot be used and why. When there is
/// none: `{"touch": false, "reason": "..."}`.
pub fn describe(descriptor: &[u8]) -> Value {
    let a = match analyse(descriptor) {
        Ok(a) => a,
        Err(e) => return json!({"touch": false, "reason": e.reason}),
    };
    if a.collections.is_empty() {
        return json!({"touch": false, "reason": no_collection(&a).reason});
    }
    let collections: Vec<Value> = a.collections.iter().map(describe_collection).collect();
    let ignored: Vec<Value> = a
        .rejected
        .iter()
        .map(|r| json!({"application": r.application, "offset": r.offset, "reason": r.reason}))
        .collect();
    json!({
        "touch": true,
        "descriptor_bytes": descriptor.len(),
        "collections": collections,
        "ignored": ignored,
    })
}

fn describe_collection(c: &TouchCollection) -> Value {
    let surface = c.surface("");
    let first = c.first_finger().copied();
    let finger_fields: serde_json::Map<String, Value> = first
        .map(|f| {
            f.named_fields()
                .into_iter()
                .map(|(n, f)| (n.to_string(), f.to_json()))
                .collect()
        })
        .unwrap_or_default();
    let fingers: Vec<Value> = c
        .reports
        .iter()
        .flat_map(|r| r.fingers.iter())
        .map(|f| {
            let m: serde_json::Map<String, Value> = f
                .named_fields()
                .into_iter()
                .map(|(n, f)| (n.to_string(), json!([f.bit_offset, f.bit_size])))
                .collect();
            Value::Object(m)
        })
        .collect();
    let (max_contacts, source) = match c.declared_max_contacts() {
        Some(n) => (
            n,
            "Contact Count Maximum feature (logical maximum; the device may report fewer)",
        ),
        None => (
            c.max_contacts(),
            "finger slots per report (no usable Contact Count Maximum)",
        ),
    };
    let contact_count = c.reports.first().and_then(|r| r.contact_count);
    let axis = |a: &AxisRange| json!({"min": a.min, "max": a.max, "resolution": a.resolution, "length_mm": a.length_mm()});
    json!({
        "application": c.application,
        "vendor_usages": c.vendor_usages,
        "offset": c.offset,
        "contacts_per_report": c.contacts_per_report(),
        "max_contacts": max_contacts,
        "max_contacts_source": source,
        "report_ids": c.report_ids(),
        "report_bytes": c.reports.iter().map(|r| r.size_bytes).collect::<Vec<_>>(),
        "hybrid": contact_count.is_some(),
        "contact_count": contact_count.map(HidField::to_json),
        "contact_count_maximum": c.contact_count_max.map(HidField::to_json),
        "input_mode": c.input_mode.map(|s| json!({
            "report_id": s.field.report_id,
            "bit_offset": s.field.bit_offset,
            "bit_size": s.field.bit_size,
            "value": s.value,
        })),
        "surface": {"x": axis(&surface.x), "y": axis(&surface.y), "size_mm": surface.size_mm()},
        "finger_fields": finger_fields,
        "fingers": fingers,
    })
}

// ---------------------------------------------------------------------------
// Descriptor files

/// Why a descriptor file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum DescriptorFileError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// Larger than any descriptor or hid-recorder header could be.
    #[error("{}: {size} bytes is too large for a report descriptor file", path.display())]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Size.
        size: u64,
    },
    /// Text that does not hold a descriptor.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// File.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file is empty.
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// File.
        path: PathBuf,
    },
}

/// Largest descriptor file read: a hid-recorder log with events may be large.
const MAX_DESCRIPTOR_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// Reads a report descriptor from raw bytes (a sysfs `report_descriptor`, an
/// `.rdesc` dump), a hid-recorder file (its first `R:` line) or a text hex dump
/// (`05 0d 09 04 …`, `0x05, 0x0d, …`).
///
/// # Errors
/// [`DescriptorFileError`]: I/O, an empty or oversized file, an `R:` line whose
/// byte count does not match, bad hex.
pub fn read_descriptor_file(path: &Path) -> Result<Vec<u8>, DescriptorFileError> {
    use std::io::Read;
    let io = |source| DescriptorFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_DESCRIPTOR_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_DESCRIPTOR_FILE_BYTES {
        return Err(DescriptorFileError::TooLarge {
            path: path.to_path_buf(),
            size: bytes.len() as u64,
        });
    }
    if bytes.is_empty() {
        return Err(DescriptorFileError::Empty {
            path: path.to_path_buf(),
        });
    }
    let Ok(text) = std::str::from_utf8(&bytes) else {
        return Ok(bytes);
    };
    let perr = |line, message: String| DescriptorFileError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    // hid-recorder: the first R: line.
    for (i, l) in text.lines().enumerate() {
        let l = l.trim();
        if let Some(rest) = l.strip_prefix("R:") {
            return super::hex::parse_r_line(rest).map_err(|m| perr(i + 1, m));
        }
    }
    // A hex dump: only hex byte tokens, commas, `0x` prefixes, comments.
    if let Some(parsed) = parse_hex_dump(text) {
        return parsed.map_err(|(line, m)| perr(line, m));
    }
    Ok(bytes)
}

/// Parses a text hex dump; `None` when the text does not look like one (then it
/// is taken as raw bytes).
fn parse_hex_dump(text: &str) -> Option<Result<Vec<u8>, (usize, String)>> {
    let mut out = Vec::new();
    let mut any = false;
    for (i, l) in text.lines().enumerate() {
        let l = l.split("//").next().unwrap_or("");
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        for tok in l.split(|c: char| c.is_whitespace() || c == ',') {
            if tok.is_empty() {
                continue;
            }
            let hex = tok
                .strip_prefix("0x")
                .or_else(|| tok.strip_prefix("0X"))
                .unwrap_or(tok);
            if hex.is_empty() || hex.len() > 2 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
                if any {
                    return Some(Err((i + 1, format!("`{tok}` is not a hex byte"))));
                }
                return None;
            }
            any = true;
            out.push(u8::from_str_radix(hex, 16).ok()?);
        }
    }
    any.then_some(Ok(out))
}

impl fmt::Display for Application {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
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
    fn widen_unsigned_maxima() {
        assert_eq!(widen_maximum(&[0x25, 0xff]), Some(vec![0x26, 0xff, 0x00]));
        assert_eq!(
            widen_maximum(&[0x26, 0xff, 0xff]),
            Some(vec![0x27, 0xff, 0xff, 0, 0])
        );
        assert_eq!(widen_maximum(&[0x25, 0x7f]), None);
        assert_eq!(widen_maximum(&[0x27, 0xff, 0xff, 0xff, 0xff]), None);
    }

    #[test]
    fn unit_names() {
        assert_eq!(unit_name(0x11), "cm");
        assert_eq!(unit_name(0x13), "inch");
        assert_eq!(unit_name(0x33), "inch^3");
        assert_eq!(unit_name(0), "none");
        assert_eq!(unit_name(0xF011), "cm*s^-1");
        assert!(unit_name(0x0F).contains("vendor"));
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

    #[test]
    fn hostile_descriptors_are_refused_not_panicking() {
        // Usage before any Usage Page: hidreport would `expect`.
        let r = touch_collections(&[0x09, 0x01, 0xa1, 0x01, 0xc0]);
        assert!(r.is_err());
        // A 4-billion-usage range.
        let r = touch_collections(&[
            0x05, 0x01, 0x1b, 0, 0, 0, 0, 0x2b, 0xff, 0xff, 0xff, 0xff, 0xa1, 0x01,
        ]);
        assert!(r.unwrap_err().reason.contains("range"));
        // Report Count 0xFFFFFFFF.
        let r = touch_collections(&[
            0x05, 0x01, 0x09, 0x30, 0x75, 0x08, 0x97, 0xff, 0xff, 0xff, 0xff, 0x81, 0x02,
        ]);
        assert!(r.unwrap_err().reason.contains("Report Count"));
        // Truncated item.
        let r = touch_collections(&[0x05]);
        assert!(r.unwrap_err().reason.contains("byte 0"));
        assert!(touch_collections(&[]).is_err());
        // Unit system nibble 0xF.
        let r = touch_collections(&[
            0x05, 0x01, 0x65, 0x0f, 0x09, 0x30, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02,
        ]);
        assert!(r.is_err());
    }
}
