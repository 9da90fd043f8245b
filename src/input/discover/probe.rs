//! Probing the nodes the pre-filter lets through, adding udev's facts, and
//! discovery as a whole (scan, pre-filter, probe).

use super::classify::TouchClass;
use super::sysfs::{evdev_facts, hidraw_facts, non_empty, scan, Scanned, SysfsFacts};
use crate::input::calibrate::CalibrationError;
use crate::input::udev::{self, UdevDb};
use crate::input::{AxisRange, DeviceIdentity, DeviceInfo, DeviceKind, Error, SurfaceInfo};
use std::path::{Path, PathBuf};

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

fn info_from_facts(kind: DeviceKind, node: &Path, facts: Option<&SysfsFacts>) -> DeviceInfo {
    let unknown_axis = AxisRange {
        min: 0.0,
        max: 0.0,
        resolution: 0.0,
    };
    let name = facts.map(|f| f.identity.name.clone()).unwrap_or_default();
    DeviceInfo {
        identity: DeviceIdentity {
            kind,
            node: node.to_path_buf(),
            name: name.clone(),
            bus: facts.map_or(0, |f| f.identity.bus),
            vendor: facts.map_or(0, |f| f.identity.vendor),
            product: facts.map_or(0, |f| f.identity.product),
            serial: facts.and_then(|f| f.identity.serial.clone()),
        },
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
            let id = &mut info.identity;
            id.kind = scanned.kind;
            id.node = scanned.node.clone();
            if let Some(f) = facts {
                let sysfs = &f.identity;
                if id.name.is_empty() {
                    id.name = sysfs.name.clone();
                }
                if id.vendor == 0 && id.product == 0 {
                    (id.bus, id.vendor, id.product) = (sysfs.bus, sysfs.vendor, sysfs.product);
                }
                if id.serial.is_none() {
                    id.serial = sysfs.serial.clone();
                }
            }
            id.serial = non_empty(id.serial.take());
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
        info.identity.vendor,
        info.identity.product,
        info.identity.serial.as_deref(),
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
        if found[i].info.identity.kind != DeviceKind::Hidraw || found[i].info.calibration.is_some()
        {
            continue;
        }
        let inherited = found
            .iter()
            .find(|e| {
                e.info.identity.kind == DeviceKind::Evdev && same_physical_device(e, &found[i])
            })
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

/// Whether `a` and `b` are the evdev and hidraw interfaces of one physical device:
/// same vendor:product, and the same stable id or the same sysfs parent.
pub fn same_physical_device(a: &Found, b: &Found) -> bool {
    a.info.identity.kind != b.info.identity.kind
        && a.info.identity.vendor == b.info.identity.vendor
        && a.info.identity.product == b.info.identity.product
        && (a.info.stable_id == b.info.stable_id
            || matches!((&a.parent, &b.parent), (Some(pa), Some(pb)) if pa == pb))
}
