//! Usage pages and usages the HID code looks for (HID Usage Tables 1.5).

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
