//! Which device to use ([`Selector`], [`InterfacePreference`]), whether a device
//! matches, and the sticky selector that finds a device again after a re-plug.

use crate::input::{DeviceInfo, DeviceKind};
use crate::vocab::parse_vendor_product;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};

/// Which device to use.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Selector {
    /// The best touch device; see [`select()`](super::select()).
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
    pub(super) fn admits(self, kind: DeviceKind) -> bool {
        match self {
            InterfacePreference::Any => true,
            InterfacePreference::Evdev => kind == DeviceKind::Evdev,
            InterfacePreference::Hidraw => kind == DeviceKind::Hidraw,
        }
    }
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
        Selector::Name(pattern) => name_matches(&info.identity.name, pattern),
        Selector::VendorProduct(vp) => {
            parse_vendor_product(vp) == Some((info.identity.vendor, info.identity.product))
        }
        Selector::Path(p) => same_path(&info.identity.node, p),
        Selector::Id(id) => info.stable_id == *id || info.id_path.as_deref() == Some(id.as_str()),
    }
}

/// Whether `candidate` is the device `previous` was (same interface, same stable id),
/// whatever its node is now.
pub fn recognise(previous: &DeviceInfo, candidate: &DeviceInfo) -> bool {
    previous.identity.kind == candidate.identity.kind && previous.stable_id == candidate.stable_id
}

/// The selector that finds `chosen` again after a re-plug: its stable id.
pub fn sticky_selector(chosen: &DeviceInfo) -> Selector {
    Selector::Id(chosen.stable_id.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
