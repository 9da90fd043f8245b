//! Touch input: the [`TouchFrame`] every source produces, and the sources.
//!
//! A source (a recording replayed, later evdev and hidraw devices) runs on its own
//! thread, turns what it reads into `TouchFrame`s in surface coordinates (the unit
//! square) and hands each to a [`FrameSink`]. The sink is the bounded queue to the
//! control thread; its full-queue policy lives in `pipeline`.
//!
//! # Contact life cycle
//!
//! A frame lists every contact that is down, plus the ones that ended in this frame.
//! A contact first appears with [`ContactFlags::DOWN`], then in later frames with no
//! flag while it moves, and last with [`ContactFlags::UP`] (a deliberate lift) or
//! [`ContactFlags::CANCELLED`] (it vanished: device unplugged, resync after a
//! dropped buffer, shutdown). When frames are coalesced a contact may carry both
//! `DOWN` and `UP`: it began and ended between two delivered frames.

pub mod calibrate;
pub mod discover;
pub mod evdev;
pub mod hid;
pub mod hotplug;
pub mod mt;
pub mod record;
pub mod recording;
pub mod replay;
pub mod synth;
pub mod udev;

use crate::time::Micros;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The most contacts one frame holds. Large touch tables declare up to 60.
pub const MAX_CONTACTS: usize = 64;

/// A contact identifier, unique across devices and never reused while the daemon runs.
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct ContactId(pub u32);

/// Life-cycle and classification bits of a contact in one frame.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct ContactFlags(pub u8);

impl ContactFlags {
    /// No flag: the contact continues.
    pub const NONE: ContactFlags = ContactFlags(0);
    /// The contact began in this frame.
    pub const DOWN: ContactFlags = ContactFlags(1);
    /// The contact was lifted in this frame (deliberately).
    pub const UP: ContactFlags = ContactFlags(2);
    /// The contact ended without a clean lift (unplug, resync, shutdown).
    pub const CANCELLED: ContactFlags = ContactFlags(4);
    /// Firmware or size filter says this is a palm: not used for control.
    pub const PALM: ContactFlags = ContactFlags(8);

    /// Whether every bit of `other` is set.
    pub fn contains(self, other: ContactFlags) -> bool {
        self.0 & other.0 == other.0
    }
    /// Sets the bits of `other`.
    pub fn insert(&mut self, other: ContactFlags) {
        self.0 |= other.0;
    }
    /// Whether the contact ended in this frame (lifted or cancelled).
    pub fn ended(self) -> bool {
        self.0 & (Self::UP.0 | Self::CANCELLED.0) != 0
    }
}

impl std::ops::BitOr for ContactFlags {
    type Output = ContactFlags;
    fn bitor(self, rhs: ContactFlags) -> ContactFlags {
        ContactFlags(self.0 | rhs.0)
    }
}

/// One contact in surface coordinates (unit square, x right, y down).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Contact {
    /// Identifier, stable for the contact's life.
    pub id: ContactId,
    /// Horizontal position in `[0, 1]`.
    pub x: f32,
    /// Vertical position in `[0, 1]`.
    pub y: f32,
    /// Pressure in `[0, 1]` when the device reports it.
    pub pressure: Option<f32>,
    /// Contact ellipse major axis in millimetres, when reported.
    pub major_mm: Option<f32>,
    /// Contact ellipse minor axis in millimetres, when reported.
    pub minor_mm: Option<f32>,
    /// Life-cycle flags in this frame.
    pub flags: ContactFlags,
}

/// Error returned when a frame already holds [`MAX_CONTACTS`] contacts.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct FrameFull;

/// The contacts of one input frame with the time the kernel stamped it.
///
/// Fixed capacity, `Copy`, no heap: the input thread fills one in place and the
/// queue moves it by value.
#[derive(Copy, Clone, Debug)]
pub struct TouchFrame {
    /// Input timestamp (kernel event time on CLOCK_MONOTONIC; virtual in replays).
    pub t: Micros,
    /// When the input thread handed the frame to the queue (CLOCK_MONOTONIC).
    pub t_queued: Micros,
    /// Index of the source device (0 for a single device).
    pub device: u16,
    len: u8,
    contacts: [Contact; MAX_CONTACTS],
}

impl Default for TouchFrame {
    fn default() -> Self {
        TouchFrame::new(Micros::ZERO)
    }
}

impl PartialEq for TouchFrame {
    fn eq(&self, other: &Self) -> bool {
        self.t == other.t && self.device == other.device && self.contacts() == other.contacts()
    }
}

impl TouchFrame {
    /// An empty frame at time `t`.
    pub fn new(t: Micros) -> TouchFrame {
        TouchFrame {
            t,
            t_queued: Micros::ZERO,
            device: 0,
            len: 0,
            contacts: [Contact::default(); MAX_CONTACTS],
        }
    }

    /// The contacts, in insertion order.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts[..self.len as usize]
    }

    /// The contacts, mutable.
    pub fn contacts_mut(&mut self) -> &mut [Contact] {
        &mut self.contacts[..self.len as usize]
    }

    /// Number of contacts.
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the frame holds no contact.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Removes every contact, keeping the time.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Appends a contact.
    ///
    /// # Errors
    /// [`FrameFull`] when the frame already holds [`MAX_CONTACTS`].
    pub fn push(&mut self, c: Contact) -> Result<(), FrameFull> {
        if self.len as usize >= MAX_CONTACTS {
            return Err(FrameFull);
        }
        self.contacts[self.len as usize] = c;
        self.len += 1;
        Ok(())
    }

    /// Whether the frame changes which contacts are down (a touch began or ended).
    ///
    /// Frames that only move contacts may be coalesced; these may not.
    pub fn has_transitions(&self) -> bool {
        self.contacts()
            .iter()
            .any(|c| c.flags.contains(ContactFlags::DOWN) || c.flags.ended())
    }

    /// Folds a later frame into this one, as if both had been delivered together.
    ///
    /// Positions come from `later`; life-cycle flags of both are kept, so a contact
    /// that began in `self` and ended in `later` carries `DOWN | UP`. Contacts that
    /// ended in `self` and are absent from `later` stay, so no lift is lost.
    ///
    /// # Errors
    /// [`FrameFull`] when the union has more than [`MAX_CONTACTS`] contacts; the
    /// contacts that fit are merged, transitions first.
    pub fn merge_later(&mut self, later: &TouchFrame) -> Result<(), FrameFull> {
        let mut result = Ok(());
        self.t = later.t;
        self.t_queued = later.t_queued;
        for c in later.contacts() {
            if let Some(mine) = self.contacts_mut().iter_mut().find(|m| m.id == c.id) {
                let flags = mine.flags | c.flags;
                *mine = *c;
                mine.flags = flags;
            } else if self.push(*c).is_err() {
                result = Err(FrameFull);
            }
        }
        result
    }
}

/// Where a source puts its frames: the bounded queue to the control thread.
///
/// `push` never blocks and never allocates; the implementation decides what
/// happens when the queue is full (see `pipeline::FrameQueue`).
pub trait FrameSink {
    /// Hands one frame on.
    fn push(&mut self, frame: &TouchFrame);
    /// Tries again to hand on frames it had to hold back; returns whether nothing
    /// is held back any more. A reader calls it while it waits for input, so a held
    /// frame (a lift, say) never waits for the next touch. Sinks that never hold
    /// anything back keep the default.
    fn flush(&mut self) -> bool {
        true
    }
}

/// How long a reader waits for input while its sink still holds frames back (µs):
/// it retries [`FrameSink::flush`] at least this often.
pub const FLUSH_RETRY_US: u64 = 1_000;

/// The poll timeout a reader uses (ms): short while `sink` holds frames back (after
/// retrying them), else [`STOP_CHECK_US`].
pub fn reader_timeout_ms(sink: &mut dyn FrameSink) -> u16 {
    let us = if sink.flush() {
        STOP_CHECK_US
    } else {
        FLUSH_RETRY_US
    };
    u16::try_from(us / 1000).unwrap_or(u16::MAX)
}

impl FrameSink for Vec<TouchFrame> {
    fn push(&mut self, frame: &TouchFrame) {
        Vec::push(self, *frame);
    }
}

/// Axis range of a surface axis in device units.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisRange {
    /// Minimum value.
    pub min: f64,
    /// Maximum value.
    pub max: f64,
    /// Resolution in units per millimetre (0 = unknown).
    #[serde(default)]
    pub resolution: f64,
}

impl AxisRange {
    /// Maps a device value into `[0, 1]` (clamped).
    pub fn normalise(&self, v: f64) -> f32 {
        let span = self.max - self.min;
        if span <= 0.0 || !v.is_finite() {
            return 0.0;
        }
        (((v - self.min) / span).clamp(0.0, 1.0)) as f32
    }

    /// Physical length of the axis in millimetres, when the resolution is known.
    pub fn length_mm(&self) -> Option<f64> {
        (self.resolution > 0.0).then(|| (self.max - self.min) / self.resolution)
    }
}

/// What a source knows about the surface it reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfaceInfo {
    /// Device name.
    pub name: String,
    /// X axis in device units.
    pub x: AxisRange,
    /// Y axis in device units.
    pub y: AxisRange,
    /// Most simultaneous contacts the device reports.
    pub max_contacts: u32,
}

impl SurfaceInfo {
    /// Physical size `(width, height)` in millimetres, when both resolutions are known.
    pub fn size_mm(&self) -> Option<(f64, f64)> {
        Some((self.x.length_mm()?, self.y.length_mm()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(id: u32, x: f32, flags: ContactFlags) -> Contact {
        Contact {
            id: ContactId(id),
            x,
            y: 0.5,
            flags,
            ..Contact::default()
        }
    }

    #[test]
    fn merge_keeps_down_and_up() {
        let mut a = TouchFrame::new(Micros(10));
        a.push(c(1, 0.1, ContactFlags::DOWN)).unwrap();
        a.push(c(2, 0.2, ContactFlags::UP)).unwrap();
        let mut b = TouchFrame::new(Micros(20));
        b.push(c(1, 0.3, ContactFlags::UP)).unwrap();
        b.push(c(3, 0.4, ContactFlags::DOWN)).unwrap();
        a.merge_later(&b).unwrap();
        assert_eq!(a.t, Micros(20));
        let got: Vec<_> = a
            .contacts()
            .iter()
            .map(|c| (c.id.0, c.x, c.flags))
            .collect();
        assert_eq!(
            got,
            vec![
                (1, 0.3, ContactFlags::DOWN | ContactFlags::UP),
                (2, 0.2, ContactFlags::UP),
                (3, 0.4, ContactFlags::DOWN)
            ]
        );
    }

    #[test]
    fn push_past_capacity_is_refused() {
        let mut f = TouchFrame::new(Micros(0));
        for i in 0..MAX_CONTACTS as u32 {
            f.push(c(i, 0.0, ContactFlags::NONE)).unwrap();
        }
        assert_eq!(f.push(c(999, 0.0, ContactFlags::NONE)), Err(FrameFull));
        assert_eq!(f.len(), MAX_CONTACTS);
    }

    #[test]
    fn axis_normalises_and_clamps() {
        let a = AxisRange {
            min: 42.0,
            max: 1981.0,
            resolution: 0.0,
        };
        assert_eq!(a.normalise(42.0), 0.0);
        assert_eq!(a.normalise(1981.0), 1.0);
        assert_eq!(a.normalise(5000.0), 1.0);
        assert!(a.length_mm().is_none());
    }
}

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

/// What discovery knows about a touch device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
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
    /// Serial number or unique name, when the device has one.
    pub serial: Option<String>,
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
    /// Reads until `stop` is set (checked at least every [`STOP_CHECK_US`]) or the device fails.
    ///
    /// # Errors
    /// [`Error::Unplugged`] when the device goes away; other variants for I/O failures.
    fn run(&mut self, sink: &mut dyn FrameSink, stop: &AtomicBool) -> Result<(), Error>;
    /// A frame ending every contact still down (CANCELLED); false if none is down.
    fn cancel_all(&mut self, t: Micros, out: &mut TouchFrame) -> bool;
}

/// Longest a device reader blocks before checking its stop flag (µs).
pub const STOP_CHECK_US: u64 = 100_000;
