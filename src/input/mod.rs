//! Touch input: the sources that produce [`TouchFrame`](crate::vocab::TouchFrame)s.
//!
//! A source (a recording replayed, an evdev or hidraw device, TUIO over UDP) runs on its own
//! thread, turns what it reads into `TouchFrame`s in surface coordinates (the unit
//! square) and hands each to a [`FrameSink`]. The sink is the bounded queue to the
//! control thread; its full-queue policy lives in `pipeline`.

pub mod calibrate;
pub mod discover;
pub mod evdev;
pub mod hid;
pub mod hotplug;
pub mod recording;
pub mod replay;
pub mod synth;
pub mod tuio;
pub mod udev;

mod device;
mod sink;
mod surface;

pub use device::{DeviceIdentity, DeviceInfo, DeviceKind, DeviceReader, Error};
pub use sink::{reader_timeout_ms, FrameSink, FLUSH_RETRY_US, STOP_CHECK_US};
pub use surface::{AxisRange, SurfaceInfo};
