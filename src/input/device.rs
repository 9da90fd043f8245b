//! Touch devices: what they are, how they fail, and the reader a device thread runs.

use super::sink::FrameSink;
use super::surface::SurfaceInfo;
use crate::vocab::{Micros, TouchFrame};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The two kernel interfaces a touch device is read through.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DeviceKind {
    /// An evdev node (`/dev/input/eventN`), multi-touch protocol A or B.
    Evdev,
    /// A hidraw node (`/dev/hidrawN`) of a HID digitizer, read through hidapi.
    Hidraw,
}

impl DeviceKind {
    /// Lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            DeviceKind::Evdev => "evdev",
            DeviceKind::Hidraw => "hidraw",
        }
    }
}

/// Who a device is: the interface and node it is read through, and what it says
/// about itself. Sysfs tells it before a device is opened
/// ([`SysfsFacts`](crate::input::discover::SysfsFacts)); a probe tells it again with the
/// rest of [`DeviceInfo`].
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeviceIdentity {
    /// Interface.
    pub kind: DeviceKind,
    /// Device node.
    pub node: PathBuf,
    /// Name the device reports.
    pub name: String,
    /// Bus type (3 USB, 0x18 I2C, ...).
    pub bus: u16,
    /// USB/HID vendor id.
    pub vendor: u16,
    /// USB/HID product id.
    pub product: u16,
    /// Serial number or unique name (`uniq` / `HID_UNIQ`), when the device has one.
    pub serial: Option<String>,
}

/// What discovery knows about a touch device.
///
/// Serialised flat: the identity's fields come first, as if they were this struct's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// Interface, node, name, ids and serial.
    #[serde(flatten)]
    pub identity: DeviceIdentity,
    /// udev `ID_PATH`, when udev has processed the device.
    pub id_path: Option<String>,
    /// Identity that survives re-plugging and renumbering: `ID_PATH`, else
    /// `vendor:product:serial` (`vvvv:pppp` without a serial).
    pub stable_id: String,
    /// Axis ranges, resolution and contact count.
    pub surface: SurfaceInfo,
    /// A touchscreen (INPUT_PROP_DIRECT / HID Touch Screen) rather than a touchpad.
    pub direct: bool,
    /// `LIBINPUT_CALIBRATION_MATRIX` from udev, row-major `[a, b, c, d, e, f]`.
    pub calibration: Option<[f64; 6]>,
}

impl DeviceInfo {
    /// The stable identity for a device: `ID_PATH` when known, else
    /// `vendor:product:serial` (or `vendor:product`).
    pub fn make_stable_id(
        id_path: Option<&str>,
        vendor: u16,
        product: u16,
        serial: Option<&str>,
    ) -> String {
        match (id_path, serial) {
            (Some(p), _) if !p.is_empty() => p.to_string(),
            (_, Some(s)) if !s.is_empty() => format!("{vendor:04x}:{product:04x}:{s}"),
            _ => format!("{vendor:04x}:{product:04x}"),
        }
    }
}

/// Why reading a device stopped or could not start. Every variant names the node.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The device went away (ENODEV): unplugged or its driver unbound.
    #[error("{node}: device unplugged")]
    Unplugged {
        /// Node.
        node: PathBuf,
    },
    /// Permission denied (EACCES/EPERM): the udev rule or group membership is missing.
    #[error("{node}: permission denied — is the user in the group the udev rule gives (crowdtouch), and is the rule installed? ({source})")]
    PermissionDenied {
        /// Node.
        node: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The device is grabbed by another program (EBUSY).
    #[error("{node}: device busy — another program holds an exclusive grab ({source})")]
    Busy {
        /// Node.
        node: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The node does not exist.
    #[error("{node}: no such device node")]
    NotFound {
        /// Node.
        node: PathBuf,
    },
    /// The device is not a touch device crowdtouch can read.
    #[error("{node}: not a multi-touch device: {reason}")]
    NotTouch {
        /// Node.
        node: PathBuf,
        /// Why.
        reason: String,
    },
    /// Any other I/O error.
    #[error("{node}: {op}: {source}")]
    Io {
        /// Node.
        node: PathBuf,
        /// What was being done.
        op: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    /// Classifies an I/O error on `node` into the variants above.
    pub fn from_io(node: impl Into<PathBuf>, op: &'static str, source: std::io::Error) -> Error {
        let node = node.into();
        match source.raw_os_error() {
            Some(nix::libc::ENODEV) | Some(nix::libc::ENXIO) => Error::Unplugged { node },
            Some(nix::libc::ENOENT) => Error::NotFound { node },
            Some(nix::libc::EACCES) | Some(nix::libc::EPERM) => {
                Error::PermissionDenied { node, source }
            }
            Some(nix::libc::EBUSY) => Error::Busy { node, source },
            _ => Error::Io { node, op, source },
        }
    }
}

/// An open touch device, read on its own input thread.
///
/// `run` blocks reading the device and hands every complete frame to `sink`
/// (frames are in the device's unit square; calibration is applied by the caller).
/// It returns `Ok(())` when `stop` is set, or an [`Error`] when the device fails
/// (`Unplugged` when it goes away). Implementations allocate nothing per event.
pub trait DeviceReader: Send {
    /// What the device is.
    fn info(&self) -> &DeviceInfo;
    /// Reads until `stop` is set (checked at least every [`STOP_CHECK_US`](super::STOP_CHECK_US)) or the device fails.
    ///
    /// # Errors
    /// [`Error::Unplugged`] when the device goes away; other variants for I/O failures.
    fn run(&mut self, sink: &mut dyn FrameSink, stop: &AtomicBool) -> Result<(), Error>;
    /// A frame ending every contact still down (CANCELLED); false if none is down.
    fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool;
}
