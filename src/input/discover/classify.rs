//! The pre-filter: whether a node is a touch device, from its sysfs bitmaps (evdev)
//! or its report descriptor (hidraw), without opening it.

use super::bitmap::Bitmap;
use crate::input::evdev::{ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_X, ABS_Y, INPUT_PROP_DIRECT};
use crate::input::hid::usage as u;

/// Why a HID report descriptor does not parse.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DescriptorError {
    /// An item is malformed.
    #[error("invalid item at byte {offset}: {message}")]
    InvalidData {
        /// Byte offset of the item.
        offset: usize,
        /// The parser's description.
        message: String,
    },
    /// An item runs past the end.
    #[error("an item runs past the end of the descriptor")]
    OutOfBounds,
    /// Report ids are inconsistent.
    #[error("mismatching report id")]
    MismatchingReportId,
    /// The parser itself failed on this input.
    #[error("the descriptor parser failed on this input")]
    ParserFailed,
}

impl From<hidreport::ParserError> for DescriptorError {
    fn from(e: hidreport::ParserError) -> DescriptorError {
        match e {
            hidreport::ParserError::InvalidData { offset, message } => {
                DescriptorError::InvalidData { offset, message }
            }
            hidreport::ParserError::OutOfBounds => DescriptorError::OutOfBounds,
            hidreport::ParserError::MismatchingReportId => DescriptorError::MismatchingReportId,
        }
    }
}

/// What the pre-filter concluded from sysfs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum TouchClass {
    /// A touchscreen (`INPUT_PROP_DIRECT`, HID Touch Screen).
    Screen,
    /// A touchpad or other indirect multi-touch surface.
    Pad,
    /// Not a touch device crowdtouch reads; the reason.
    NotTouch(&'static str),
}

impl TouchClass {
    /// Whether the pre-filter lets the node through to probing.
    pub fn is_touch(self) -> bool {
        !matches!(self, TouchClass::NotTouch(_))
    }
}

/// Classifies a HID report descriptor: a Digitizer Touch Screen / Touch Pad
/// application collection with a Contact Identifier input, or a vendor-page 0xFF00
/// application with a 0xFF00 Contact Identifier (Wacom touch nodes).
///
/// A Touch Screen collection without Contact Identifier (single-touch) is not
/// multi-touch.
///
/// # Errors
/// [`DescriptorError`] when the descriptor does not parse.
pub fn classify_report_descriptor(bytes: &[u8]) -> Result<TouchClass, DescriptorError> {
    use hidreport::{CollectionType, Field, Report, ReportDescriptor};
    // The parser must never take the daemon down: a descriptor that trips it is
    // reported like one that fails to parse.
    let parsed = std::panic::catch_unwind(|| ReportDescriptor::try_from(bytes));
    let rd = match parsed {
        Ok(Ok(rd)) => rd,
        Ok(Err(e)) => return Err(e.into()),
        Err(_) => return Err(DescriptorError::ParserFailed),
    };
    let (mut screen, mut pad, mut vendor, mut no_id) = (false, false, false, false);
    for report in rd.input_reports() {
        for field in report.fields() {
            let Field::Variable(var) = field else {
                continue;
            };
            let Some(app) = field
                .collections()
                .iter()
                .find(|c| c.collection_type() == CollectionType::Application)
            else {
                continue;
            };
            let Some(app_usage) = app.usages().first() else {
                continue;
            };
            let app_page = u16::from(app_usage.usage_page);
            let app_id = u16::from(app_usage.usage_id);
            let page = u16::from(var.usage.usage_page);
            let id = u16::from(var.usage.usage_id);
            let contact_id = id == u::CONTACT_ID;
            match (app_page, app_id) {
                (u::PAGE_DIGITIZER, u::TOUCH_SCREEN | u::TOUCH_PAD) => {
                    if page == u::PAGE_DIGITIZER && contact_id {
                        if app_id == u::TOUCH_SCREEN {
                            screen = true;
                        } else {
                            pad = true;
                        }
                    } else {
                        no_id = true;
                    }
                }
                (u::PAGE_VENDOR_FF00, _) if page == u::PAGE_VENDOR_FF00 && contact_id => {
                    vendor = true
                }
                _ => {}
            }
        }
    }
    Ok(if screen {
        TouchClass::Screen
    } else if pad || vendor {
        TouchClass::Pad
    } else if no_id {
        TouchClass::NotTouch("digitizer collection without Contact Identifier (single-touch)")
    } else {
        TouchClass::NotTouch("no Digitizer Touch Screen or Touch Pad collection")
    })
}

/// Classifies an evdev device from its `properties` and `capabilities/abs` bitmaps.
pub fn classify_evdev(properties: &Bitmap, abs: &Bitmap) -> TouchClass {
    let direct = properties.test(usize::from(INPUT_PROP_DIRECT));
    if abs.test(usize::from(ABS_MT_POSITION_X)) && abs.test(usize::from(ABS_MT_POSITION_Y)) {
        if direct {
            TouchClass::Screen
        } else {
            TouchClass::Pad
        }
    } else if direct && abs.test(usize::from(ABS_X)) && abs.test(usize::from(ABS_Y)) {
        TouchClass::Screen
    } else {
        TouchClass::NotTouch("no ABS_MT_POSITION_X/Y (and not a direct-touch device with ABS_X/Y)")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evdev_classification() {
        let mt = Bitmap::from_bits(&[0, 1, 0x35, 0x36]);
        let direct = Bitmap::from_bits(&[usize::from(INPUT_PROP_DIRECT)]);
        let pointer = Bitmap::from_bits(&[0, 2]);
        assert_eq!(classify_evdev(&direct, &mt), TouchClass::Screen);
        assert_eq!(classify_evdev(&pointer, &mt), TouchClass::Pad);
        let st = Bitmap::from_bits(&[0, 1]);
        assert_eq!(classify_evdev(&direct, &st), TouchClass::Screen);
        assert!(!classify_evdev(&Bitmap::default(), &st).is_touch());
        assert!(!classify_evdev(&Bitmap::default(), &Bitmap::from_bits(&[])).is_touch());
    }

    /// A minimal keyboard descriptor (Generic Desktop / Keyboard, 8 modifier bits).
    const KEYBOARD: &[u8] = &[
        0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00, 0x25,
        0x01, 0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0xc0,
    ];

    /// A minimal single-finger touchscreen: Digitizer / Touch Screen / Finger with Tip
    /// Switch, Contact Identifier and X/Y (written for this test).
    const TOUCHSCREEN: &[u8] = &[
        0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, // Digitizer, Touch Screen, Application
        0x09, 0x22, 0xa1, 0x02, // Finger, Logical
        0x09, 0x42, 0x15, 0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, // Tip
        0x75, 0x07, 0x81, 0x03, // padding
        0x09, 0x51, 0x25, 0x0f, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02, // Contact Id
        0x05, 0x01, 0x09, 0x30, 0x09, 0x31, 0x26, 0xff, 0x7f, 0x75, 0x10, 0x95, 0x02, 0x81,
        0x02, // X, Y
        0xc0, 0xc0,
    ];

    #[test]
    fn descriptors_classify() {
        assert_eq!(
            classify_report_descriptor(TOUCHSCREEN),
            Ok(TouchClass::Screen)
        );
        let mut pad = TOUCHSCREEN.to_vec();
        pad[3] = 0x05;
        assert_eq!(classify_report_descriptor(&pad), Ok(TouchClass::Pad));
        assert!(!classify_report_descriptor(KEYBOARD).unwrap().is_touch());
        // Without Contact Identifier (0x51 → 0x30, "Tip Pressure"-like) it is single-touch.
        let mut no_id = TOUCHSCREEN.to_vec();
        no_id[27] = 0x30;
        assert!(matches!(
            classify_report_descriptor(&no_id),
            Ok(TouchClass::NotTouch(r)) if r.contains("Contact Identifier")
        ));
        // Garbage never panics (it may or may not parse).
        let _ = classify_report_descriptor(&[0xa1]);
        let _ = classify_report_descriptor(&[0xff, 0xff, 0xff]);
        let _ = classify_report_descriptor(&[]);
    }
}
