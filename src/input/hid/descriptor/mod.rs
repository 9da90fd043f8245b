//! Report descriptor → touch layout: which bits of which report hold each finger.
//!
//! [`touch_collections`] parses a report descriptor with `hidreport` (after the
//! pre-scan described in the [module docs](super)) and returns, for every touch
//! application collection, a [`TouchCollection`]: per input report the finger slots
//! ([`Finger`], one per logical collection), the Contact Count and Scan Time
//! fields, the Contact Count Maximum feature and the feature settings that switch
//! the device to multi-touch reporting ([`FeatureSetting`]).
//!
//! # Finger slots
//!
//! Within one input report of a touch application, every variable input field with
//! a per-finger usage (Tip Switch, In Range, Confidence, Contact Identifier, X, Y,
//! Width, Height, Tip Pressure, Azimuth) belongs to a finger. A new finger starts
//! when the innermost collection changes, or — for devices that put all fingers
//! in one collection — when a usage already set in the current finger comes again
//! and that finger is complete (Contact Identifier, X and Y). A repeated usage in
//! an incomplete finger is ignored (the ELAN 04F3:010C declares X/Y twice per
//! finger), as the kernel's hid-multitouch does. A finger needs a Contact
//! Identifier, X, Y, and a Tip Switch or In Range.
//!
//! # Errors
//!
//! Never panics, whatever the bytes: malformed or hostile descriptors give a
//! [`NotTouch`] naming the byte offset.

mod collections;
mod describe;
mod file;
mod finger;
mod layout;
mod prescan;
mod units;

pub use collections::touch_collections;
pub use describe::describe;
pub use file::{read_descriptor_file, DescriptorFileError};
pub use layout::{
    Application, FeatureSetting, Finger, HidField, NotTouch, TouchCollection, TouchReport,
    MAX_DECLARED_CONTACTS,
};
pub use prescan::{MAX_DESCRIPTOR_BYTES, MAX_REPORT_COUNT, MAX_REPORT_SIZE_BITS};
pub use units::unit_name;
