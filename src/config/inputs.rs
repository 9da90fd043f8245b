//! The `inputs` sections: where touches come from and how a device is corrected.

use crate::geom::Rect;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One input source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum InputConfig {
    /// Replay recordings (the recorded-input simulator), through the same thread and
    /// queue a device uses.
    Replay {
        /// Recording files, played in order (relative paths are relative to the config file).
        files: Vec<PathBuf>,
        /// Start again after the last file.
        #[serde(default)]
        looped: bool,
        /// Pause between files (ms).
        #[serde(default = "default_gap_ms")]
        gap_ms: u64,
        /// Reset the crowd (agents walk back) before each file.
        #[serde(default)]
        reset_between: bool,
    },
    /// A touch device (evdev or hidraw), found by discovery, read on a real-time
    /// thread, re-attached when it comes back after an unplug.
    Device {
        /// Which device.
        #[serde(default)]
        select: DeviceSelect,
        /// Through which interface.
        #[serde(default)]
        interface: DeviceInterface,
        /// Take the device exclusively (EVIOCGRAB) so the desktop does not also react.
        /// Applied once every finger has lifted.
        #[serde(default)]
        grab: bool,
        /// The part of the table this device covers, in table units (the unit square);
        /// `None` is the whole table. Several devices make one table this way.
        #[serde(default)]
        region: Option<Rect>,
        /// Rotation, flips and calibration matrix.
        #[serde(default)]
        calibration: CalibrationConfig,
        /// Contacts larger than this (mm, from the reported contact size) are palms:
        /// ignored for control and reported as such. `None` keeps every contact
        /// (firmware palm flags still apply).
        #[serde(default = "default_palm_max_mm")]
        palm_max_mm: Option<f64>,
        /// Physical size of the surface (mm) when the device reports no resolution.
        #[serde(default)]
        size_mm: Option<(f64, f64)>,
    },
    /// TUIO cursors over OSC/UDP (camera tables such as reacTIVision, TUIO
    /// simulators, phone apps): TUIO 1.1 `/tuio/2Dcur` and TUIO 2.0 `ptr`, read on
    /// an input thread of their own, through the same queue a device uses.
    Tuio {
        /// Address to listen on, `ip:port` (3333 is TUIO's port).
        #[serde(default = "default_tuio_listen")]
        listen: String,
        /// The part of the table the TUIO surface covers, in table units; `None`
        /// is the whole table.
        #[serde(default)]
        region: Option<Rect>,
        /// Rotation and flips (the matrix too) applied to the TUIO coordinates.
        #[serde(default)]
        calibration: CalibrationConfig,
        /// A sender silent this long (ms) has its touches lifted.
        #[serde(default = "default_tuio_timeout_ms")]
        timeout_ms: u64,
        /// Sessions (cursors) one sender may have down, that is in one of its
        /// frames; further ones are refused and counted (`sessions_refused`).
        /// 1 ..= [`TUIO_MOST_SESSIONS_PER_FRAME`].
        #[serde(default = "default_tuio_sessions")]
        max_sessions_per_frame: u32,
        /// Senders (peer address and source name) followed at once; a frame of
        /// another is refused and counted (`senders_refused`) while these hold
        /// touches down. 1 ..= [`TUIO_MOST_SENDERS`].
        #[serde(default = "default_tuio_senders")]
        max_senders: u32,
        /// Datagrams taken from one peer address (ip:port) per second (a token
        /// bucket of one second's worth each); the rest are dropped and counted
        /// (`flood_dropped`). Each peer has its own: one flooding cannot starve
        /// another. [`TUIO_PACKETS_PER_S`].
        #[serde(default = "default_tuio_packets_per_s")]
        max_packets_per_s: u32,
    },
}

/// The most `Tuio.max_sessions_per_frame`: a touch frame's capacity.
pub const TUIO_MOST_SESSIONS_PER_FRAME: u32 = crate::vocab::MAX_CONTACTS as u32;

/// The most `Tuio.max_senders`.
pub const TUIO_MOST_SENDERS: u32 = 64;

/// The allowed `Tuio.max_packets_per_s` (per peer address).
pub const TUIO_PACKETS_PER_S: std::ops::RangeInclusive<u32> = 10..=100_000;

fn default_tuio_sessions() -> u32 {
    TUIO_MOST_SESSIONS_PER_FRAME
}

fn default_tuio_senders() -> u32 {
    8
}

fn default_tuio_packets_per_s() -> u32 {
    4_000
}

/// The default `Tuio.listen`: every interface, TUIO's port.
pub const DEFAULT_TUIO_LISTEN: &str = "0.0.0.0:3333";

fn default_tuio_listen() -> String {
    DEFAULT_TUIO_LISTEN.to_string()
}

fn default_tuio_timeout_ms() -> u64 {
    1000
}

fn default_gap_ms() -> u64 {
    1000
}

/// Which touch device a `Device` input reads.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceSelect {
    /// The best touch device found: a touchscreen over a touchpad, then the one with
    /// the most contacts, then the largest (`crowdtouch devices` shows the pick).
    #[default]
    Auto,
    /// Name contains this text (case-insensitive), or matches it as a `*` glob.
    Name(String),
    /// USB/HID ids, `"2575:0204"` (hex).
    VendorProduct(String),
    /// A device node, `"/dev/input/event5"` (changes between boots; prefer `Id`).
    Path(PathBuf),
    /// A stable id as `crowdtouch devices` prints it (udev ID_PATH, or vendor:product:serial).
    Id(String),
}

/// Which kernel interface to read a device through.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceInterface {
    /// evdev when the kernel handles the device, else hidraw.
    #[default]
    Any,
    /// `/dev/input/eventN` only.
    Evdev,
    /// `/dev/hidrawN` only (raw HID digitizer reports).
    Hidraw,
}

/// How a device's coordinates are corrected before they reach the table.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// Clockwise rotation in degrees: 0, 90, 180 or 270.
    #[serde(default)]
    pub rotation: u16,
    /// Mirror left-right (after rotation).
    #[serde(default)]
    pub flip_x: bool,
    /// Mirror top-bottom (after rotation).
    #[serde(default)]
    pub flip_y: bool,
    /// 2×3 matrix `(a, b, c, d, e, f)` in libinput's LIBINPUT_CALIBRATION_MATRIX
    /// convention (`x' = a·x + b·y + c`, `y' = d·x + e·y + f` on unit coordinates),
    /// applied first. `None` uses the udev property when the device has one.
    /// `crowdtouch calibrate --write` fills this in.
    #[serde(default)]
    pub matrix: Option<[f64; 6]>,
}

/// Default largest contact that still counts as a finger (mm).
pub const DEFAULT_PALM_MAX_MM: f64 = 30.0;

fn default_palm_max_mm() -> Option<f64> {
    Some(DEFAULT_PALM_MAX_MM)
}
