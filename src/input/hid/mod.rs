//! Raw HID digitizers: report descriptors, input reports, hid-recorder logs, hidraw devices.
//!
//! A HID touch device describes its reports in a *report descriptor*; this module
//! turns that description into a layout of bit fields ([`descriptor`]), decodes
//! input reports with it into [`TouchFrame`](crate::vocab::TouchFrame)s ([`report`]),
//! reads `hid-recorder` logs ([`recorder`]) and opens hidraw nodes through hidapi
//! ([`device`]). Everything but `device` is pure and runs on captured bytes.
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
//! help, done in [`descriptor`] before the bytes reach it (with `hidreport`'s own
//! item tokenizer, not a second parser):
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
//! Units are decoded here from the raw 32-bit value ([`descriptor::unit_name`]), never
//! through `hidreport::Unit`.

pub mod descriptor;
pub mod device;
pub mod recorder;
pub mod report;

pub use descriptor::{
    describe, read_descriptor_file, touch_collections, Application, DescriptorFileError,
    FeatureSetting, Finger, HidField, NotTouch, TouchCollection, TouchReport,
};
pub use device::{enumerate, probe, record_hidraw, HidOptions, HidReader};
pub use recorder::{parse_hid_recorder, HidRecorderLog, HidRecorderWriter};
pub use report::{HidCounters, HidDecoder, ReportError};

/// Usage pages and usages this module looks for (HID Usage Tables 1.5).
pub mod usage {
    /// Generic Desktop page.
    pub const PAGE_GENERIC_DESKTOP: u16 = 0x01;
    /// Digitizer page.
    pub const PAGE_DIGITIZER: u16 = 0x0D;
    /// The vendor page on which Wacom touch nodes mirror the digitizer usages.
    pub const PAGE_VENDOR_FF00: u16 = 0xFF00;
    /// Generic Desktop X.
    pub const X: u16 = 0x30;
    /// Generic Desktop Y.
    pub const Y: u16 = 0x31;
    /// Wacom vendor-page X (0xFF00:0x130).
    pub const VENDOR_X: u16 = 0x130;
    /// Wacom vendor-page Y (0xFF00:0x131).
    pub const VENDOR_Y: u16 = 0x131;
    /// Digitizer: Touch Screen application.
    pub const TOUCH_SCREEN: u16 = 0x04;
    /// Digitizer: Touch Pad application.
    pub const TOUCH_PAD: u16 = 0x05;
    /// Digitizer: Device Configuration application (holds Input Mode).
    pub const DEVICE_CONFIGURATION: u16 = 0x0E;
    /// Digitizer: Finger logical collection.
    pub const FINGER: u16 = 0x22;
    /// Digitizer: Tip Pressure.
    pub const TIP_PRESSURE: u16 = 0x30;
    /// Digitizer: In Range.
    pub const IN_RANGE: u16 = 0x32;
    /// Digitizer: Azimuth.
    pub const AZIMUTH: u16 = 0x3F;
    /// Digitizer: Tip Switch.
    pub const TIP_SWITCH: u16 = 0x42;
    /// Digitizer: Confidence (0 = palm or other unintended contact).
    pub const CONFIDENCE: u16 = 0x47;
    /// Digitizer: Width.
    pub const WIDTH: u16 = 0x48;
    /// Digitizer: Height.
    pub const HEIGHT: u16 = 0x49;
    /// Digitizer: Contact Identifier.
    pub const CONTACT_ID: u16 = 0x51;
    /// Digitizer: Input Mode (formerly Device Mode) feature.
    pub const INPUT_MODE: u16 = 0x52;
    /// Digitizer: Contact Count.
    pub const CONTACT_COUNT: u16 = 0x54;
    /// Digitizer: Contact Count Maximum feature.
    pub const CONTACT_COUNT_MAX: u16 = 0x55;
    /// Digitizer: Scan Time.
    pub const SCAN_TIME: u16 = 0x56;
    /// Digitizer: Surface Switch feature (touchpads: report contacts).
    pub const SURFACE_SWITCH: u16 = 0x57;
    /// Digitizer: Button Switch feature (touchpads: report buttons).
    pub const BUTTON_SWITCH: u16 = 0x58;
}
