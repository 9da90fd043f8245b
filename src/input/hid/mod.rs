//! Raw HID digitizers: report descriptors, input reports, hidraw devices.
//!
//! A HID touch device describes its reports in a *report descriptor*; this module
//! turns that description into a layout of bit fields (`descriptor/`:
//! [`touch_collections`]), decodes input reports with it into
//! [`TouchFrame`](crate::vocab::TouchFrame)s (`report.rs`: [`HidDecoder`]) and opens
//! hidraw nodes through hidapi (`device.rs`: [`HidReader`]). Everything but
//! `device.rs` is pure and runs on captured bytes; `hid-recorder` logs are read by
//! [`crate::input::recording`].
//!
//! ```text
//!  report descriptor ──touch_collections──► TouchCollection ──HidDecoder::new──► HidDecoder
//!  (sysfs, hidapi, R: line)                 (bit layout per finger)
//!
//!  input report bytes ──HidDecoder::report(t, bytes, &mut frame)──► true when a frame completes
//!  (hidraw read, E: line)
//! ```
//!
//! # What counts as a touch device
//!
//! An application collection with usage Touch Screen (0x0D:0x04) or Touch Pad
//! (0x0D:0x05) whose input report holds, per finger, a Contact Identifier, X and Y
//! (Generic Desktop 0x30/0x31) and a Tip Switch or In Range. Wacom touch nodes
//! declare the same usages on the vendor page 0xFF00 (application 0xFF00:0x05,
//! X = 0xFF00:0x130, Y = 0xFF00:0x131); inside such an application the vendor
//! usages are read as their digitizer twins. Everything else (pens, mice, vendor
//! collections) is ignored; a descriptor with no usable collection is refused with
//! a [`NotTouch`] that says why.
//!
//! # Where `hidreport` falls short
//!
//! Descriptors are parsed by the `hidreport` 0.6 crate. Three things in it need
//! help, done in `descriptor/prescan.rs` before the bytes reach it (with
//! `hidreport`'s own item tokenizer, not a second parser):
//!
//! * it panics on some malformed input (a Usage with no Usage Page in effect:
//!   `compile_usages` calls `expect`; `Unit::system` on a unit system nibble above 4)
//!   and allocates without bound for huge Report Counts or Usage Minimum/Maximum
//!   ranges. A pre-scan refuses such descriptors with the byte offset, applying the
//!   kernel's limits (4096 bytes, Report Size ≤ 256, Report Count ≤ 12288), and
//!   prefixes `Usage Page (0)` so a page-less Usage gets page 0 as in the kernel;
//! * it sign-extends a Logical/Physical Maximum even when the minimum is not
//!   negative (`25 ff` reads as −1, not 255; the Goodix fixture's Width/Height).
//!   The kernel reads it unsigned; the pre-scan widens such items (`25 ff` →
//!   `26 ff 00`) so `hidreport` sees the kernel's value;
//! * `CollectionId` has no accessor for the collection's byte offset; it is read
//!   from its `Debug` form, for messages only.
//!
//! Units are decoded here from the raw 32-bit value ([`unit_name`]), never
//! through `hidreport::Unit`.

mod descriptor;
mod device;
mod hex;
mod report;
pub mod usage;

pub use descriptor::{
    describe, read_descriptor_file, touch_collections, unit_name, Application, DescriptorFileError,
    FeatureSetting, Finger, HidField, NotTouch, TouchCollection, TouchReport,
    MAX_DECLARED_CONTACTS, MAX_DESCRIPTOR_BYTES, MAX_REPORT_COUNT, MAX_REPORT_SIZE_BITS,
};
pub use device::{
    device_info, enumerate, parse_hid_uevent, probe, record_hidraw, HidOptions, HidReader,
    HidUevent,
};
pub(crate) use hex::{parse_hex_bytes, parse_r_line};
pub use report::{HidCounters, HidDecoder, ReportError};
