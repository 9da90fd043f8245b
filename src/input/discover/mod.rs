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
//! [`select()`] then picks one device for a [`Selector`]; see [`select()`] for the
//! `Auto` rule. [`matches()`] and [`recognise`] tell whether a device that appears

mod bitmap;
mod classify;
mod probe;
mod select;
mod selector;
mod sysfs;

pub use bitmap::Bitmap;
pub use classify::{classify_evdev, classify_report_descriptor, DescriptorError, TouchClass};
pub use probe::{discover, discover_node, examine, same_physical_device, Found, Prober};
pub use select::{select, Candidates, SelectError, Summary};
pub use selector::{
    matches, name_matches, recognise, sticky_selector, InterfacePreference, Selector,
};
pub use sysfs::{evdev_facts, hidraw_facts, parse_hid_id, scan, Scanned, SysfsError, SysfsFacts};
