//! Assembling one finger slot from the consecutive fields of an input report.

use super::layout::{Finger, HidField, MAX_VALUE_BITS};
use crate::input::hid::usage as u;
use hidreport::Collection;

/// A finger being assembled from consecutive fields.
#[derive(Default)]
pub(super) struct FingerBuilder<'a> {
    pub(super) key: Option<&'a Collection>,
    contact_id: Option<HidField>,
    x: Option<HidField>,
    y: Option<HidField>,
    tip: Option<HidField>,
    in_range: Option<HidField>,
    confidence: Option<HidField>,
    width: Option<HidField>,
    height: Option<HidField>,
    pressure: Option<HidField>,
    azimuth: Option<HidField>,
}

impl<'a> FingerBuilder<'a> {
    pub(super) fn slot(&mut self, usage: (u16, u16)) -> Option<&mut Option<HidField>> {
        Some(match usage {
            (u::PAGE_GENERIC_DESKTOP, u::X) => &mut self.x,
            (u::PAGE_GENERIC_DESKTOP, u::Y) => &mut self.y,
            (u::PAGE_DIGITIZER, u::CONTACT_ID) => &mut self.contact_id,
            (u::PAGE_DIGITIZER, u::TIP_SWITCH) => &mut self.tip,
            (u::PAGE_DIGITIZER, u::IN_RANGE) => &mut self.in_range,
            (u::PAGE_DIGITIZER, u::CONFIDENCE) => &mut self.confidence,
            (u::PAGE_DIGITIZER, u::WIDTH) => &mut self.width,
            (u::PAGE_DIGITIZER, u::HEIGHT) => &mut self.height,
            (u::PAGE_DIGITIZER, u::TIP_PRESSURE) => &mut self.pressure,
            (u::PAGE_DIGITIZER, u::AZIMUTH) => &mut self.azimuth,
            _ => return None,
        })
    }

    pub(super) fn complete(&self) -> bool {
        self.contact_id.is_some() && self.x.is_some() && self.y.is_some()
    }

    pub(super) fn is_empty(&self) -> bool {
        [
            self.contact_id,
            self.x,
            self.y,
            self.tip,
            self.in_range,
            self.confidence,
            self.width,
            self.height,
            self.pressure,
            self.azimuth,
        ]
        .iter()
        .all(Option::is_none)
    }

    /// The finger, or what it lacks.
    pub(super) fn build(&self) -> Result<Finger, &'static str> {
        let (Some(contact_id), Some(x), Some(y)) = (self.contact_id, self.x, self.y) else {
            return Err(if self.contact_id.is_none() {
                "no Contact Identifier"
            } else {
                "no X/Y"
            });
        };
        if self.tip.is_none() && self.in_range.is_none() {
            return Err("no Tip Switch or In Range");
        }
        for f in [contact_id, x, y] {
            if f.bit_size == 0 || usize::from(f.bit_size) > MAX_VALUE_BITS {
                return Err("a Contact Identifier, X or Y field wider than 32 bits");
            }
        }
        for f in [x, y] {
            if f.logical_max <= f.logical_min {
                return Err("an X or Y logical range that is empty");
            }
        }
        let usable = |f: Option<HidField>| {
            f.filter(|f| f.bit_size > 0 && usize::from(f.bit_size) <= MAX_VALUE_BITS)
        };
        Ok(Finger {
            contact_id,
            x,
            y,
            tip: usable(self.tip),
            in_range: usable(self.in_range),
            confidence: usable(self.confidence),
            width: usable(self.width),
            height: usable(self.height),
            pressure: usable(self.pressure),
            azimuth: usable(self.azimuth),
        })
    }
}

/// Whether a usage belongs to a finger slot.
pub(super) fn is_finger_usage(usage: (u16, u16)) -> bool {
    FingerBuilder::default().slot(usage).is_some()
}
