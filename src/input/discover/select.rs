//! Picking one device for a selector, or saying why none fits.

use super::probe::{same_physical_device, Found};
use super::selector::{matches, InterfacePreference, Selector};
use super::sysfs::node_order;
use crate::input::DeviceKind;
use crate::vocab::parse_vendor_product;
use std::cmp::Ordering;
use std::fmt;
use std::path::PathBuf;

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
            node: f.info.identity.node.clone(),
            kind: f.info.identity.kind,
            name: f.info.identity.name.clone(),
            vendor: f.info.identity.vendor,
            product: f.info.identity.product,
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
        .then_with(|| (a.info.identity.kind as u8).cmp(&(b.info.identity.kind as u8)))
        .then_with(|| node_order(&a.info.identity.node, &b.info.identity.node))
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
    let admits = |f: &Found| matches!(sel, Selector::Path(_)) || pref.admits(f.info.identity.kind);
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
        let shadowed = f.info.identity.kind == DeviceKind::Hidraw
            && usable
                .iter()
                .any(|g| g.info.identity.kind == DeviceKind::Evdev && same_physical_device(f, g));
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
