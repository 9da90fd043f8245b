//! The scan: list the event and hidraw nodes under a root and read what sysfs says
//! about each, without opening the node.

use super::bitmap::Bitmap;
use super::classify::{classify_evdev, classify_report_descriptor, DescriptorError, TouchClass};
use crate::input::udev;
use crate::input::{DeviceIdentity, DeviceKind};
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

/// What sysfs says about one node.
#[derive(Clone, Debug, PartialEq)]
pub struct SysfsFacts {
    /// Interface, node, name, ids, and `uniq` / `HID_UNIQ` as serial when not empty.
    pub identity: DeviceIdentity,
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

pub(super) fn non_empty(s: Option<String>) -> Option<String> {
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
        identity: DeviceIdentity {
            kind: DeviceKind::Evdev,
            node: node.to_path_buf(),
            name,
            bus,
            vendor,
            product,
            serial,
        },
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
        identity: DeviceIdentity {
            kind: DeviceKind::Hidraw,
            node: node.to_path_buf(),
            name: uevent.get("HID_NAME").cloned().unwrap_or_default(),
            bus,
            vendor,
            product,
            serial: non_empty(uevent.get("HID_UNIQ").cloned()),
        },
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

pub(super) fn node_order(a: &Path, b: &Path) -> Ordering {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
