//! Finding touch devices, and choosing one.
//!
//! [`discover`] works in three steps, every path relative to a root (`/` normally, a
//! temporary tree in tests):
//!
//! 1. **Scan** ([`scan`]): list `ROOT/dev/input/event*` and `ROOT/dev/hidraw*` and read
//!    what sysfs says about each without opening the node: for evdev
//!    `ROOT/sys/class/input/eventN/device/{name, id/*, uniq, properties, capabilities/abs}`,
//!    for hidraw `ROOT/sys/class/hidraw/hidrawN/device/{uevent, report_descriptor}`.
//! 2. **Pre-filter** ([`TouchClass`]): an evdev node is touch-capable when its ABS
//!    bitmap has `ABS_MT_POSITION_X` and `_Y`, or it is `INPUT_PROP_DIRECT` with
//!    `ABS_X`/`ABS_Y`; a hidraw node when its report descriptor has a Digitizer
//!    Touch Screen or Touch Pad application collection with a Contact Identifier
//!    (or the vendor-page 0xFF00 digitizer layout some Wacom touch nodes use).
//! 3. **Probe** the nodes that pass through a [`Prober`] (which opens the device for
//!    its axis ranges; the daemon implements it with the evdev and hidraw modules) and
//!    add udev's facts: `ID_PATH`, `LIBINPUT_CALIBRATION_MATRIX`, the stable id, and
//!    whether udev has processed the node yet.
//!
//! A node that fails to probe (permission denied, busy) is still listed, with the
//! error, so `crowdtouch devices` can say why it cannot be used.
//!
//! [`select`] then picks one device for a [`Selector`]; see [`select`] for the
//! `Auto` rule. [`matches()`] and [`recognise`] tell whether a device that appears
//! later is the one that was selected (by stable id, never by node number).

use crate::input::calibrate::CalibrationError;
use crate::input::udev::{self, UdevDb};
use crate::input::{AxisRange, DeviceInfo, DeviceKind, Error, SurfaceInfo};
use crate::vocab::parse_vendor_product;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// `INPUT_PROP_DIRECT`: a touchscreen, not a touchpad.
pub const INPUT_PROP_DIRECT: usize = 0x01;
/// `ABS_X`.
pub const ABS_X: usize = 0x00;
/// `ABS_Y`.
pub const ABS_Y: usize = 0x01;
/// `ABS_MT_POSITION_X`.
pub const ABS_MT_POSITION_X: usize = 0x35;
/// `ABS_MT_POSITION_Y`.
pub const ABS_MT_POSITION_Y: usize = 0x36;

/// HID usage page Digitizers.
const PAGE_DIGITIZER: u16 = 0x0D;
/// HID usage page of the vendor-defined digitizer layout (Wacom touch nodes).
const PAGE_VENDOR_FF00: u16 = 0xFF00;
/// Digitizers: Touch Screen application.
const USAGE_TOUCH_SCREEN: u16 = 0x04;
/// Digitizers: Touch Pad application.
const USAGE_TOUCH_PAD: u16 = 0x05;
/// Digitizers: Contact Identifier.
const USAGE_CONTACT_ID: u16 = 0x51;

/// Bits per word in the kernel's sysfs bitmaps (a C `long`).
const LONG_BITS: usize = nix::libc::c_long::BITS as usize;

/// Opens a device to learn what sysfs does not say (axis ranges, contact count).
///
/// The daemon implements it with `input::evdev::probe` and `input::hid::probe`;
/// tests use a fake.
pub trait Prober {
    /// Probes `node`, an interface of kind `kind`.
    ///
    /// # Errors
    /// An [`Error`] naming the node (permission denied, busy, not a touch device, ...).
    fn probe(&self, kind: DeviceKind, node: &Path) -> Result<DeviceInfo, Error>;
}

/// A sysfs file that could not be read or understood. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum SysfsError {
    /// The file could not be read.
    #[error("{file}: cannot read: {source}")]
    Read {
        /// The file.
        file: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file's content is not what the kernel writes there.
    #[error("{file}: expected {expected}, found {found:?}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// What was expected.
        expected: &'static str,
        /// What was found (trimmed, at most 80 characters).
        found: String,
    },
    /// The HID report descriptor does not parse.
    #[error("{file}: report descriptor does not parse: {source}")]
    Descriptor {
        /// The file.
        file: PathBuf,
        /// What the parser said.
        #[source]
        source: DescriptorError,
    },
}

/// Why a HID report descriptor does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DescriptorError {
    /// An item is malformed.
    #[error("invalid item at byte {offset}: {message}")]
    InvalidData {
        /// Byte offset of the item.
        offset: usize,
        /// The parser's description.
        message: String,
    },
    /// An item runs past the end.
    #[error("an item runs past the end of the descriptor")]
    OutOfBounds,
    /// Report ids are inconsistent.
    #[error("mismatching report id")]
    MismatchingReportId,
    /// The parser itself failed on this input.
    #[error("the descriptor parser failed on this input")]
    ParserFailed,
}

impl From<hidreport::ParserError> for DescriptorError {
    fn from(e: hidreport::ParserError) -> DescriptorError {
        match e {
            hidreport::ParserError::InvalidData { offset, message } => {
                DescriptorError::InvalidData { offset, message }
            }
            hidreport::ParserError::OutOfBounds => DescriptorError::OutOfBounds,
            hidreport::ParserError::MismatchingReportId => DescriptorError::MismatchingReportId,
        }
    }
}

/// What the pre-filter concluded from sysfs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TouchClass {
    /// A touchscreen (`INPUT_PROP_DIRECT`, HID Touch Screen).
    Screen,
    /// A touchpad or other indirect multi-touch surface.
    Pad,
    /// Not a touch device crowdtouch reads; the reason.
    NotTouch(&'static str),
}

impl TouchClass {
    /// Whether the pre-filter lets the node through to probing.
    pub fn is_touch(self) -> bool {
        !matches!(self, TouchClass::NotTouch(_))
    }
}

/// What sysfs says about one node.
#[derive(Clone, Debug, PartialEq)]
pub struct SysfsFacts {
    /// Interface.
    pub kind: DeviceKind,
    /// Device node.
    pub node: PathBuf,
    /// Name the device reports.
    pub name: String,
    /// Bus type.
    pub bus: u16,
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// `uniq` / `HID_UNIQ`, when not empty.
    pub serial: Option<String>,
    /// `(major, minor)` from the class directory's `dev` file.
    pub devnum: Option<(u32, u32)>,
    /// Pre-filter verdict.
    pub touch: TouchClass,
    /// Canonical sysfs path of the physical device both interfaces hang off (the HID
    /// device for USB/I2C HID touchscreens), when resolvable.
    pub parent: Option<PathBuf>,
}

/// One scanned node: its kind and path, and what sysfs said (or why it could not).
#[derive(Debug)]
pub struct Scanned {
    /// Interface.
    pub kind: DeviceKind,
    /// Device node.
    pub node: PathBuf,
    /// Sysfs facts.
    pub facts: Result<SysfsFacts, SysfsError>,
}

/// A touch device discovery found.
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    /// What is known about it (from the prober, or only from sysfs when probing failed).
    pub info: DeviceInfo,
    /// Whether udev has processed the node (always true without udev).
    pub processed: bool,
    /// Why probing failed; `None` when the device can be used.
    pub probe_error: Option<String>,
    /// Canonical sysfs path of the physical device, used to pair the evdev and hidraw
    /// interfaces of one device.
    pub parent: Option<PathBuf>,
    /// udev's `LIBINPUT_CALIBRATION_MATRIX` was set but is invalid (then ignored).
    pub calibration_error: Option<CalibrationError>,
}

impl Found {
    /// Whether the device probed fine.
    pub fn usable(&self) -> bool {
        self.probe_error.is_none()
    }
}

/// A kernel bitmap as sysfs prints it (`capabilities/abs`, `properties`): hex words of
/// a C `long`, most significant first, separated by spaces, leading zero words left
/// out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Bitmap {
    /// Words, least significant first; each holds [`LONG_BITS`] bits.
    words: Vec<u64>,
}

impl Bitmap {
    /// Parses sysfs text.
    ///
    /// # Errors
    /// A short description of what is wrong.
    pub fn parse(text: &str) -> Result<Bitmap, &'static str> {
        let mut words = Vec::new();
        for w in text.split_whitespace().rev() {
            let v = u64::from_str_radix(w, 16).map_err(|_| "hexadecimal words")?;
            if LONG_BITS < 64 && v >> LONG_BITS != 0 {
                return Err("words no wider than a C long");
            }
            words.push(v);
        }
        if words.is_empty() {
            return Err("at least one hexadecimal word");
        }
        Ok(Bitmap { words })
    }

    /// A bitmap with the given bits set.
    pub fn from_bits(bits: &[usize]) -> Bitmap {
        let mut words = vec![0u64; bits.iter().max().map_or(1, |m| m / LONG_BITS + 1)];
        for &b in bits {
            words[b / LONG_BITS] |= 1u64 << (b % LONG_BITS);
        }
        Bitmap { words }
    }

    /// Whether bit `bit` is set.
    pub fn test(&self, bit: usize) -> bool {
        self.words
            .get(bit / LONG_BITS)
            .is_some_and(|w| w >> (bit % LONG_BITS) & 1 == 1)
    }
}

impl fmt::Display for Bitmap {
    /// The kernel's format (`input_print_bitmap`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let top = self.words.iter().rposition(|&w| w != 0);
        match top {
            None => f.write_str("0"),
            Some(top) => {
                for i in (0..=top).rev() {
                    write!(f, "{:x}", self.words[i])?;
                    if i > 0 {
                        f.write_str(" ")?;
                    }
                }
                Ok(())
            }
        }
    }
}

/// Classifies a HID report descriptor: a Digitizer Touch Screen / Touch Pad
/// application collection with a Contact Identifier input, or a vendor-page 0xFF00
/// application with a 0xFF00 Contact Identifier (Wacom touch nodes).
///
/// A Touch Screen collection without Contact Identifier (single-touch) is not
/// multi-touch.
///
/// # Errors
/// [`DescriptorError`] when the descriptor does not parse.
pub fn classify_report_descriptor(bytes: &[u8]) -> Result<TouchClass, DescriptorError> {
    use hidreport::{CollectionType, Field, Report, ReportDescriptor};
    // The parser must never take the daemon down: a descriptor that trips it is
    // reported like one that fails to parse.
    let parsed = std::panic::catch_unwind(|| ReportDescriptor::try_from(bytes));
    let rd = match parsed {
        Ok(Ok(rd)) => rd,
        Ok(Err(e)) => return Err(e.into()),
        Err(_) => return Err(DescriptorError::ParserFailed),
    };
    let (mut screen, mut pad, mut vendor, mut no_id) = (false, false, false, false);
    for report in rd.input_reports() {
        for field in report.fields() {
            let Field::Variable(var) = field else {
                continue;
            };
            let Some(app) = field
                .collections()
                .iter()
                .find(|c| c.collection_type() == CollectionType::Application)
            else {
                continue;
            };
            let Some(app_usage) = app.usages().first() else {
                continue;
            };
            let app_page = u16::from(app_usage.usage_page);
            let app_id = u16::from(app_usage.usage_id);
            let page = u16::from(var.usage.usage_page);
            let id = u16::from(var.usage.usage_id);
            let contact_id = id == USAGE_CONTACT_ID;
            match (app_page, app_id) {
                (PAGE_DIGITIZER, USAGE_TOUCH_SCREEN | USAGE_TOUCH_PAD) => {
                    if page == PAGE_DIGITIZER && contact_id {
                        if app_id == USAGE_TOUCH_SCREEN {
                            screen = true;
                        } else {
                            pad = true;
                        }
                    } else {
                        no_id = true;
                    }
                }
                (PAGE_VENDOR_FF00, _) if page == PAGE_VENDOR_FF00 && contact_id => vendor = true,
                _ => {}
            }
        }
    }
    Ok(if screen {
        TouchClass::Screen
    } else if pad || vendor {
        TouchClass::Pad
    } else if no_id {
        TouchClass::NotTouch("digitizer collection without Contact Identifier (single-touch)")
    } else {
        TouchClass::NotTouch("no Digitizer Touch Screen or Touch Pad collection")
    })
}

/// Classifies an evdev device from its `properties` and `capabilities/abs` bitmaps.
pub fn classify_evdev(properties: &Bitmap, abs: &Bitmap) -> TouchClass {
    let direct = properties.test(INPUT_PROP_DIRECT);
    if abs.test(ABS_MT_POSITION_X) && abs.test(ABS_MT_POSITION_Y) {
        if direct {
            TouchClass::Screen
        } else {
            TouchClass::Pad
        }
    } else if direct && abs.test(ABS_X) && abs.test(ABS_Y) {
        TouchClass::Screen
    } else {
        TouchClass::NotTouch("no ABS_MT_POSITION_X/Y (and not a direct-touch device with ABS_X/Y)")
    }
}

fn clip(text: &str) -> String {
    text.trim().chars().take(80).collect()
}

fn read_bytes(file: &Path) -> Result<Vec<u8>, SysfsError> {
    std::fs::read(file).map_err(|source| SysfsError::Read {
        file: file.to_path_buf(),
        source,
    })
}

fn read_text(file: &Path) -> Result<String, SysfsError> {
    let bytes = read_bytes(file)?;
    let text = String::from_utf8_lossy(&bytes);
    Ok(text.trim_end_matches(['\n', '\0']).to_string())
}

/// Reads a file that may be missing on some kernels: `Ok(None)` when it does not exist.
fn read_optional(file: &Path) -> Result<Option<String>, SysfsError> {
    match read_text(file) {
        Ok(t) => Ok(Some(t)),
        Err(SysfsError::Read { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

fn read_hex_u16(file: &Path) -> Result<u16, SysfsError> {
    let text = read_text(file)?;
    u16::from_str_radix(text.trim(), 16).map_err(|_| SysfsError::Parse {
        file: file.to_path_buf(),
        expected: "a 16-bit hexadecimal number",
        found: clip(&text),
    })
}

fn read_bitmap(file: &Path) -> Result<Bitmap, SysfsError> {
    let text = read_text(file)?;
    Bitmap::parse(&text).map_err(|expected| SysfsError::Parse {
        file: file.to_path_buf(),
        expected,
        found: clip(&text),
    })
}

fn read_devnum(file: &Path) -> Result<Option<(u32, u32)>, SysfsError> {
    match read_optional(file)? {
        None => Ok(None),
        Some(text) => udev::parse_dev(&text)
            .map(Some)
            .ok_or_else(|| SysfsError::Parse {
                file: file.to_path_buf(),
                expected: "major:minor",
                found: clip(&text),
            }),
    }
}

fn non_empty(s: Option<String>) -> Option<String> {
    s.map(|s| s.trim().to_string()).filter(|s| !s.is_empty())
}

/// Reads the sysfs facts of `ROOT/dev/input/eventN`.
///
/// # Errors
/// A [`SysfsError`] naming the file that could not be read or parsed.
pub fn evdev_facts(root: &Path, node: &Path) -> Result<SysfsFacts, SysfsError> {
    let class = sysfs_class(root, node);
    let dev = class.join("device");
    let name = read_text(&dev.join("name"))?;
    let bus = read_hex_u16(&dev.join("id/bustype"))?;
    let vendor = read_hex_u16(&dev.join("id/vendor"))?;
    let product = read_hex_u16(&dev.join("id/product"))?;
    let serial = non_empty(read_optional(&dev.join("uniq"))?);
    let properties = match read_optional(&dev.join("properties"))? {
        None => Bitmap::default(),
        Some(text) => Bitmap::parse(&text).map_err(|expected| SysfsError::Parse {
            file: dev.join("properties"),
            expected,
            found: clip(&text),
        })?,
    };
    let abs = read_bitmap(&dev.join("capabilities/abs"))?;
    Ok(SysfsFacts {
        kind: DeviceKind::Evdev,
        node: node.to_path_buf(),
        name,
        bus,
        vendor,
        product,
        serial,
        devnum: read_devnum(&class.join("dev"))?,
        touch: classify_evdev(&properties, &abs),
        // eventN/device is the inputN directory; its `device` link is the physical device.
        parent: std::fs::canonicalize(dev.join("device")).ok(),
    })
}

/// Parses the `HID_ID` of a HID uevent (`0003:00002575:00000204`) into
/// `(bus, vendor, product)`.
pub fn parse_hid_id(s: &str) -> Option<(u16, u16, u16)> {
    let mut parts = s.trim().split(':');
    let mut next = || -> Option<u16> {
        let v = u32::from_str_radix(parts.next()?, 16).ok()?;
        u16::try_from(v).ok()
    };
    let ids = (next()?, next()?, next()?);
    parts.next().is_none().then_some(ids)
}

/// Reads the sysfs facts of `ROOT/dev/hidrawN`.
///
/// # Errors
/// A [`SysfsError`] naming the file that could not be read or parsed.
pub fn hidraw_facts(root: &Path, node: &Path) -> Result<SysfsFacts, SysfsError> {
    let class = sysfs_class(root, node);
    let dev = class.join("device");
    let uevent_file = dev.join("uevent");
    let uevent: BTreeMap<String, String> = read_text(&uevent_file)?
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let hid_id = uevent.get("HID_ID").map(String::as_str).unwrap_or("");
    let (bus, vendor, product) = parse_hid_id(hid_id).ok_or_else(|| SysfsError::Parse {
        file: uevent_file.clone(),
        expected: "HID_ID=bus:vendor:product (hexadecimal, 16-bit values)",
        found: clip(hid_id),
    })?;
    let rdesc_file = dev.join("report_descriptor");
    let rdesc = read_bytes(&rdesc_file)?;
    let touch = classify_report_descriptor(&rdesc).map_err(|source| SysfsError::Descriptor {
        file: rdesc_file,
        source,
    })?;
    Ok(SysfsFacts {
        kind: DeviceKind::Hidraw,
        node: node.to_path_buf(),
        name: uevent.get("HID_NAME").cloned().unwrap_or_default(),
        bus,
        vendor,
        product,
        serial: non_empty(uevent.get("HID_UNIQ").cloned()),
        devnum: read_devnum(&class.join("dev"))?,
        touch,
        parent: std::fs::canonicalize(&dev).ok(),
    })
}

fn sysfs_class(root: &Path, node: &Path) -> PathBuf {
    udev::sysfs_class_dir(root, node).unwrap_or_else(|| root.join("sys/class/unknown"))
}

/// The number after a node name's prefix (`event12` → 12), for natural ordering.
fn node_number(node: &Path) -> u64 {
    let name = node.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let digits: String = name.chars().skip_while(|c| !c.is_ascii_digit()).collect();
    digits.parse().unwrap_or(u64::MAX)
}

fn node_order(a: &Path, b: &Path) -> Ordering {
    node_number(a).cmp(&node_number(b)).then_with(|| a.cmp(b))
}

fn list_nodes(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut nodes: Vec<PathBuf> = entries
        .filter_map(Result::ok)
        .filter(|e| {
            e.file_name().to_str().is_some_and(|n| {
                n.strip_prefix(prefix)
                    .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
            })
        })
        .map(|e| e.path())
        .collect();
    nodes.sort_by(|a, b| node_order(a, b));
    nodes
}

/// Lists `ROOT/dev/input/event*` then `ROOT/dev/hidraw*` (each in numeric order) with
/// their sysfs facts. Opens nothing.
pub fn scan(root: &Path) -> Vec<Scanned> {
    let evdev = list_nodes(&root.join("dev/input"), "event")
        .into_iter()
        .map(|node| Scanned {
            kind: DeviceKind::Evdev,
            facts: evdev_facts(root, &node),
            node,
        });
    let hidraw = list_nodes(&root.join("dev"), "hidraw")
        .into_iter()
        .map(|node| Scanned {
            kind: DeviceKind::Hidraw,
            facts: hidraw_facts(root, &node),
            node,
        });
    evdev.chain(hidraw).collect()
}

fn info_from_facts(kind: DeviceKind, node: &Path, facts: Option<&SysfsFacts>) -> DeviceInfo {
    let unknown_axis = AxisRange {
        min: 0.0,
        max: 0.0,
        resolution: 0.0,
    };
    let name = facts.map(|f| f.name.clone()).unwrap_or_default();
    DeviceInfo {
        kind,
        node: node.to_path_buf(),
        name: name.clone(),
        bus: facts.map_or(0, |f| f.bus),
        vendor: facts.map_or(0, |f| f.vendor),
        product: facts.map_or(0, |f| f.product),
        serial: facts.and_then(|f| f.serial.clone()),
        id_path: None,
        stable_id: String::new(),
        surface: SurfaceInfo {
            name,
            x: unknown_axis,
            y: unknown_axis,
            max_contacts: 0,
        },
        direct: facts.is_some_and(|f| f.touch == TouchClass::Screen),
        calibration: None,
    }
}

/// Probes one scanned node and adds udev's facts. `None` when the node is not a touch
/// device.
pub fn examine(
    root: &Path,
    udev: &UdevDb,
    scanned: &Scanned,
    prober: &dyn Prober,
) -> Option<Found> {
    let facts = match &scanned.facts {
        Ok(f) if !f.touch.is_touch() => return None,
        Ok(f) => Some(f),
        Err(e) => {
            log::warn!("{e}; probing the node to find out what it is");
            None
        }
    };
    let (mut info, probe_error) = match prober.probe(scanned.kind, &scanned.node) {
        Ok(mut info) => {
            info.kind = scanned.kind;
            info.node = scanned.node.clone();
            if let Some(f) = facts {
                if info.name.is_empty() {
                    info.name = f.name.clone();
                }
                if info.vendor == 0 && info.product == 0 {
                    (info.bus, info.vendor, info.product) = (f.bus, f.vendor, f.product);
                }
                if info.serial.is_none() {
                    info.serial = f.serial.clone();
                }
            }
            info.serial = non_empty(info.serial.take());
            (info, None)
        }
        // Without sysfs the prober is the only judge of what the node is.
        Err(Error::NotTouch { .. }) if facts.is_none() => return None,
        Err(e) => {
            let msg = match &scanned.facts {
                Err(sys) => format!("{e} (and {sys})"),
                Ok(_) => e.to_string(),
            };
            (
                info_from_facts(scanned.kind, &scanned.node, facts),
                Some(msg),
            )
        }
    };
    let devnum = facts
        .and_then(|f| f.devnum)
        .or_else(|| udev::device_number(root, &scanned.node));
    let props = devnum.and_then(|(maj, min)| udev.properties(maj, min));
    let processed = match devnum {
        Some((maj, min)) => udev.processed(maj, min),
        None => !udev.present(),
    };
    let mut calibration_error = None;
    if let Some(props) = &props {
        info.id_path = non_empty(props.get("ID_PATH").cloned());
        if let Some(m) = props.get("LIBINPUT_CALIBRATION_MATRIX") {
            match udev::parse_calibration_matrix(m) {
                Ok(m) => info.calibration = Some(m),
                Err(e) => {
                    log::warn!(
                        "{}: udev LIBINPUT_CALIBRATION_MATRIX ignored: {e}",
                        scanned.node.display()
                    );
                    calibration_error = Some(e);
                }
            }
        }
    }
    info.stable_id = DeviceInfo::make_stable_id(
        info.id_path.as_deref(),
        info.vendor,
        info.product,
        info.serial.as_deref(),
    );
    Some(Found {
        info,
        processed,
        probe_error,
        parent: facts.and_then(|f| f.parent.clone()),
        calibration_error,
    })
}

/// Finds the touch devices under `root`: scan, pre-filter, probe, udev facts.
///
/// Non-touch nodes are left out; touch nodes that fail to probe are listed with
/// [`Found::probe_error`]. Evdev nodes come first, each kind in node order.
///
/// udev sets `LIBINPUT_CALIBRATION_MATRIX` on input devices only; a hidraw node with
/// none of its own takes the matrix of its evdev sibling (the same physical device,
/// see [`same_physical_device`]), since both report the same normalised surface.
pub fn discover(root: &Path, prober: &dyn Prober) -> Vec<Found> {
    let udev = UdevDb::new(root);
    let mut found: Vec<Found> = scan(root)
        .iter()
        .filter_map(|s| examine(root, &udev, s, prober))
        .collect();
    for i in 0..found.len() {
        if found[i].info.kind != DeviceKind::Hidraw || found[i].info.calibration.is_some() {
            continue;
        }
        let inherited = found
            .iter()
            .find(|e| e.info.kind == DeviceKind::Evdev && same_physical_device(e, &found[i]))
            .and_then(|e| e.info.calibration);
        found[i].info.calibration = inherited;
    }
    found
}

/// Examines one node (after a hotplug `Added` and [`crate::input::hotplug::Watcher::wait_ready`]):
/// `None` when it is not a touch device or not an `event*`/`hidraw*` node.
pub fn discover_node(root: &Path, node: &Path, prober: &dyn Prober) -> Option<Found> {
    let name = node.file_name()?.to_str()?;
    let scanned = if name.starts_with("event") {
        Scanned {
            kind: DeviceKind::Evdev,
            node: node.to_path_buf(),
            facts: evdev_facts(root, node),
        }
    } else if name.starts_with("hidraw") {
        Scanned {
            kind: DeviceKind::Hidraw,
            node: node.to_path_buf(),
            facts: hidraw_facts(root, node),
        }
    } else {
        return None;
    };
    examine(root, &UdevDb::new(root), &scanned, prober)
}

/// Which device to use.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Selector {
    /// The best touch device; see [`select`].
    Auto,
    /// By name: a case-insensitive substring, or a glob over the whole name when it
    /// contains `*` or `?`.
    Name(String),
    /// By USB/HID ids, `"2575:0204"` (hexadecimal).
    VendorProduct(String),
    /// By node path (`/dev/input/event5`, or a link to it such as
    /// `/dev/input/by-path/...`).
    Path(PathBuf),
    /// By stable id ([`DeviceInfo::stable_id`]: udev `ID_PATH`, else
    /// `vendor:product:serial`).
    Id(String),
}

impl fmt::Display for Selector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Selector::Auto => f.write_str("auto"),
            Selector::Name(n) => write!(f, "name {n:?}"),
            Selector::VendorProduct(vp) => write!(f, "vendor:product {vp}"),
            Selector::Path(p) => write!(f, "path {}", p.display()),
            Selector::Id(id) => write!(f, "id {id:?}"),
        }
    }
}

/// Which interface to read a device through.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InterfacePreference {
    /// Either; evdev wins when one device shows both (the kernel already decodes
    /// the digitizer protocol).
    #[default]
    Any,
    /// Only evdev nodes.
    Evdev,
    /// Only hidraw nodes.
    Hidraw,
}

impl fmt::Display for InterfacePreference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InterfacePreference::Any => "any",
            InterfacePreference::Evdev => "evdev",
            InterfacePreference::Hidraw => "hidraw",
        })
    }
}

impl InterfacePreference {
    fn admits(self, kind: DeviceKind) -> bool {
        match self {
            InterfacePreference::Any => true,
            InterfacePreference::Evdev => kind == DeviceKind::Evdev,
            InterfacePreference::Hidraw => kind == DeviceKind::Hidraw,
        }
    }
}

/// One line of a candidate list in a [`SelectError`].
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Node.
    pub node: PathBuf,
    /// Interface.
    pub kind: DeviceKind,
    /// Name.
    pub name: String,
    /// Vendor id.
    pub vendor: u16,
    /// Product id.
    pub product: u16,
    /// Stable id.
    pub stable_id: String,
    /// Why it cannot be used, if it cannot.
    pub problem: Option<String>,
}

impl From<&Found> for Summary {
    fn from(f: &Found) -> Summary {
        Summary {
            node: f.info.node.clone(),
            kind: f.info.kind,
            name: f.info.name.clone(),
            vendor: f.info.vendor,
            product: f.info.product,
            stable_id: f.info.stable_id.clone(),
            problem: f.probe_error.clone(),
        }
    }
}

/// The devices a selection looked at, printed one per line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Candidates(pub Vec<Summary>);

impl fmt::Display for Candidates {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str(" none");
        }
        for s in &self.0 {
            write!(
                f,
                "\n  {} ({}) {:?} {:04x}:{:04x} id {}",
                s.node.display(),
                s.kind.as_str(),
                s.name,
                s.vendor,
                s.product,
                s.stable_id
            )?;
            if let Some(p) = &s.problem {
                write!(f, " — unusable: {p}")?;
            }
        }
        Ok(())
    }
}

/// Why no device was selected. Every variant lists what was found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SelectError {
    /// Discovery found no touch device at all.
    #[error("no touch device found (looked at /dev/input/event* and /dev/hidraw*; is the device plugged in and the user allowed to read sysfs?)")]
    NoDevices,
    /// No device matches the selector.
    #[error("no touch device matches {selector} (interface: {preference}); found:{found}")]
    NoMatch {
        /// The selector.
        selector: Selector,
        /// The interface preference.
        preference: InterfacePreference,
        /// Every touch device found.
        found: Candidates,
    },
    /// Devices match, but none probed fine.
    #[error("every touch device matching {selector} is unusable:{found}")]
    Unusable {
        /// The selector.
        selector: Selector,
        /// The matching devices, with their errors.
        found: Candidates,
    },
    /// The selector itself is malformed.
    #[error("{selector}: {reason}")]
    BadSelector {
        /// The selector.
        selector: Selector,
        /// What is wrong.
        reason: &'static str,
    },
}

/// Case-insensitive glob: `*` any run of characters, `?` one character.
fn glob_match(pattern: &[char], text: &[char]) -> bool {
    let (mut p, mut t) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while t < text.len() {
        if p < pattern.len() && (pattern[p] == '?' || pattern[p] == text[t]) {
            p += 1;
            t += 1;
        } else if p < pattern.len() && pattern[p] == '*' {
            star = Some((p, t));
            p += 1;
        } else if let Some((sp, st)) = star {
            p = sp + 1;
            t = st + 1;
            star = Some((sp, st + 1));
        } else {
            return false;
        }
    }
    pattern[p..].iter().all(|&c| c == '*')
}

/// Whether a device name matches a [`Selector::Name`] pattern.
pub fn name_matches(name: &str, pattern: &str) -> bool {
    let name = name.to_lowercase();
    let pattern = pattern.to_lowercase();
    if pattern.contains(['*', '?']) {
        let p: Vec<char> = pattern.chars().collect();
        let t: Vec<char> = name.chars().collect();
        glob_match(&p, &t)
    } else {
        name.contains(&pattern)
    }
}

fn same_path(node: &Path, wanted: &Path) -> bool {
    node == wanted
        || match (std::fs::canonicalize(node), std::fs::canonicalize(wanted)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
}

/// Whether `info` satisfies the selector. `Auto` matches every device.
///
/// A device that comes back after an unplug usually has a new node number, so the
/// daemon recognises it by [`recognise`] (stable id), or by matching
/// `Selector::Id(previous.stable_id)`, never by `Path` of an `eventN` node.
pub fn matches(info: &DeviceInfo, sel: &Selector) -> bool {
    match sel {
        Selector::Auto => true,
        Selector::Name(pattern) => name_matches(&info.name, pattern),
        Selector::VendorProduct(vp) => {
            parse_vendor_product(vp) == Some((info.vendor, info.product))
        }
        Selector::Path(p) => same_path(&info.node, p),
        Selector::Id(id) => info.stable_id == *id || info.id_path.as_deref() == Some(id.as_str()),
    }
}

/// Whether `candidate` is the device `previous` was (same interface, same stable id),
/// whatever its node is now.
pub fn recognise(previous: &DeviceInfo, candidate: &DeviceInfo) -> bool {
    previous.kind == candidate.kind && previous.stable_id == candidate.stable_id
}

/// The selector that finds `chosen` again after a re-plug: its stable id.
pub fn sticky_selector(chosen: &DeviceInfo) -> Selector {
    Selector::Id(chosen.stable_id.clone())
}

/// Whether `a` and `b` are the evdev and hidraw interfaces of one physical device:
/// same vendor:product, and the same stable id or the same sysfs parent.
pub fn same_physical_device(a: &Found, b: &Found) -> bool {
    a.info.kind != b.info.kind
        && a.info.vendor == b.info.vendor
        && a.info.product == b.info.product
        && (a.info.stable_id == b.info.stable_id
            || matches!((&a.parent, &b.parent), (Some(pa), Some(pb)) if pa == pb))
}

fn area_mm2(f: &Found) -> f64 {
    f.info.surface.size_mm().map_or(0.0, |(w, h)| w * h)
}

/// The `Auto` order: direct first, more contacts, larger surface, evdev before
/// hidraw, node order.
fn rank(a: &Found, b: &Found) -> Ordering {
    b.info
        .direct
        .cmp(&a.info.direct)
        .then_with(|| {
            b.info
                .surface
                .max_contacts
                .cmp(&a.info.surface.max_contacts)
        })
        .then_with(|| area_mm2(b).total_cmp(&area_mm2(a)))
        .then_with(|| (a.info.kind as u8).cmp(&(b.info.kind as u8)))
        .then_with(|| node_order(&a.info.node, &b.info.node))
}

/// Picks one device.
///
/// # The `Auto` rule
/// 1. Only devices that probed fine, and only the interfaces `pref` admits
///    (`Any`: both; `Evdev` / `Hidraw`: only that kind).
/// 2. When one physical device shows as both evdev and hidraw (same vendor:product
///    and same stable id or sysfs parent) and its evdev node probed fine, the hidraw
///    node is dropped: the kernel already decodes the digitizer protocol.
///    (`pref: Hidraw` admits only hidraw; an unusable evdev node leaves the hidraw
///    one in the running.)
/// 3. Touchscreens (direct) before touchpads; then more contacts; then the larger
///    physical surface (unknown size counts as zero); then node order (`event2`
///    before `event10`).
///
/// The other selectors keep the devices that [`matches()`] accepts and `pref` admits
/// (`Path` ignores `pref`: it names a node), and pick among them by the same rule.
///
/// # Errors
/// [`SelectError::NoDevices`] when `found` is empty, [`SelectError::NoMatch`] and
/// [`SelectError::Unusable`] listing the candidates, [`SelectError::BadSelector`] for
/// a malformed `VendorProduct`.
pub fn select<'a>(
    found: &'a [Found],
    sel: &Selector,
    pref: InterfacePreference,
) -> Result<&'a Found, SelectError> {
    if let Selector::VendorProduct(vp) = sel {
        if parse_vendor_product(vp).is_none() {
            return Err(SelectError::BadSelector {
                selector: sel.clone(),
                reason: "expected vendor:product in hexadecimal, like 2575:0204",
            });
        }
    }
    if found.is_empty() {
        return Err(SelectError::NoDevices);
    }
    let admits = |f: &Found| matches!(sel, Selector::Path(_)) || pref.admits(f.info.kind);
    let matching: Vec<&Found> = found
        .iter()
        .filter(|f| admits(f) && matches(&f.info, sel))
        .collect();
    if matching.is_empty() {
        return Err(SelectError::NoMatch {
            selector: sel.clone(),
            preference: pref,
            found: Candidates(found.iter().map(Summary::from).collect()),
        });
    }
    let usable: Vec<&Found> = matching.iter().copied().filter(|f| f.usable()).collect();
    if usable.is_empty() {
        return Err(SelectError::Unusable {
            selector: sel.clone(),
            found: Candidates(matching.iter().map(|f| Summary::from(*f)).collect()),
        });
    }
    let mut best: Option<&Found> = None;
    for &f in &usable {
        let shadowed = f.info.kind == DeviceKind::Hidraw
            && usable
                .iter()
                .any(|g| g.info.kind == DeviceKind::Evdev && same_physical_device(f, g));
        if shadowed {
            continue;
        }
        if best.is_none_or(|b| rank(f, b) == Ordering::Less) {
            best = Some(f);
        }
    }
    // Every usable hidraw node is shadowed only if an evdev one exists, so `best` is set.
    best.ok_or(SelectError::Unusable {
        selector: sel.clone(),
        found: Candidates(matching.iter().map(|f| Summary::from(*f)).collect()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bitmaps_parse_and_print_in_the_kernel_format() {
        // Dell Canvas ABS: X, Y, MT_SLOT, MT_POSITION_X/Y, MT_TRACKING_ID.
        let b = Bitmap::from_bits(&[0, 1, 0x2f, 0x35, 0x36, 0x39]);
        assert_eq!(b.to_string(), "260800000000003");
        let p = Bitmap::parse("260800000000003\n").unwrap();
        assert_eq!(p, b);
        assert!(p.test(0x35) && p.test(0x36) && !p.test(0x37) && !p.test(1000));
        // Multi-word: bit 64 lives in the second word, printed first.
        let k = Bitmap::from_bits(&[1, 64]);
        assert_eq!(k.to_string(), "1 2");
        assert_eq!(Bitmap::parse("1 2").unwrap(), k);
        assert_eq!(Bitmap::from_bits(&[]).to_string(), "0");
        assert!(Bitmap::parse("").is_err());
        assert!(Bitmap::parse("xyz").is_err());
    }

    #[test]
    fn evdev_classification() {
        let mt = Bitmap::from_bits(&[0, 1, 0x35, 0x36]);
        let direct = Bitmap::from_bits(&[INPUT_PROP_DIRECT]);
        let pointer = Bitmap::from_bits(&[0, 2]);
        assert_eq!(classify_evdev(&direct, &mt), TouchClass::Screen);
        assert_eq!(classify_evdev(&pointer, &mt), TouchClass::Pad);
        let st = Bitmap::from_bits(&[0, 1]);
        assert_eq!(classify_evdev(&direct, &st), TouchClass::Screen);
        assert!(!classify_evdev(&Bitmap::default(), &st).is_touch());
        assert!(!classify_evdev(&Bitmap::default(), &Bitmap::from_bits(&[])).is_touch());
    }

    #[test]
    fn hid_ids_parse() {
        assert_eq!(
            parse_hid_id("0003:00002575:00000204"),
            Some((3, 0x2575, 0x0204))
        );
        assert_eq!(
            parse_hid_id("0018:000004F3:0000425A"),
            Some((0x18, 0x04f3, 0x425a))
        );
        assert_eq!(parse_hid_id("0003:00012575:00000204"), None);
        assert_eq!(parse_hid_id("0003:2575"), None);
        assert_eq!(parse_hid_id("0003:2575:0204:1"), None);
    }

    #[test]
    fn names_match_by_substring_or_glob() {
        let n = "Advanced Silicon S.A. CoolTouch® System";
        assert!(name_matches(n, "cooltouch"));
        assert!(name_matches(n, "ADVANCED*system"));
        assert!(name_matches(n, "*touch?*"));
        assert!(!name_matches(n, "advanced*touch"));
        assert!(!name_matches(n, "egalax"));
        assert!(name_matches(n, "*"));
    }

    /// A minimal keyboard descriptor (Generic Desktop / Keyboard, 8 modifier bits).
    const KEYBOARD: &[u8] = &[
        0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00, 0x25,
        0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0xc0,
    ];

    /// A minimal single-finger touchscreen: Digitizer / Touch Screen / Finger with Tip
    /// Switch, Contact Identifier and X/Y (written for this test).
    const TOUCHSCREEN: &[u8] = &[
        0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, // Digitizer, Touch Screen, Application
        0x09, 0x22, 0xa1, 0x02, // Finger, Logical
        0x09, 0x42, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, // Tip
        0x75, 0x07, 0x81, 0x03, // padding
        0x09, 0x51, 0x25, 0x0f, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02, // Contact Id
        0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x26, 0xff, 0x7f, 0x75, 0x10, 0x95, 0x02, 0x81,
        0x02, // X, Y
        0xc0, 0xc0,
    ];

    #[test]
    fn descriptors_classify() {
        assert_eq!(
            classify_report_descriptor(TOUCHSCREEN),
            Ok(TouchClass::Screen)
        );
        let mut pad = TOUCHSCREEN.to_vec();
        pad[3] = 0x05;
        assert_eq!(classify_report_descriptor(&pad), Ok(TouchClass::Pad));
        assert!(!classify_report_descriptor(KEYBOARD).unwrap().is_touch());
        // Without Contact Identifier (0x51 → 0x30, "Tip Pressure"-like) it is single-touch.
        let mut no_id = TOUCHSCREEN.to_vec();
        no_id[27] = 0x30;
        assert!(matches!(
            classify_report_descriptor(&no_id),
            Ok(TouchClass::NotTouch(r)) if r.contains("Contact Identifier")
        ));
        // Garbage never panics (it may or may not parse).
        let _ = classify_report_descriptor(&[0xa1]);
        let _ = classify_report_descriptor(&[0xff, 0xff, 0xff]);
        let _ = classify_report_descriptor(&[]);
    }
}
