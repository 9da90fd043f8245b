//! Layout extraction: the touch application collections of a parsed descriptor,
//! their finger slots, Contact Count and Scan Time fields, Contact Count Maximum and
//! multi-touch mode settings, or why none is usable.

use super::finger::{is_finger_usage, FingerBuilder};
use super::layout::{
    Application, FeatureSetting, Finger, HidField, NotTouch, TouchCollection, TouchReport,
};
use super::prescan::{normalise, parse_error};
use crate::input::hid::usage as u;
use hidreport::{Collection, CollectionType, Field, Report, ReportDescriptor, VariableField};

fn collection_offset(c: &Collection) -> Option<usize> {
    let s = format!("{:?}", c.id());
    let digits: String = s.chars().filter(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// First usage of a collection as `(page, id)`.
fn collection_usage(c: &Collection) -> Option<(u16, u16)> {
    c.usages()
        .first()
        .map(|u| (u16::from(u.usage_page), u16::from(u.usage_id)))
}

/// The outermost application collection of a field.
fn application_of(v: &VariableField) -> Option<&Collection> {
    v.collections
        .iter()
        .find(|c| c.collection_type() == CollectionType::Application)
}

/// Whether an application usage is a touch application; `(kind, vendor)`.
fn touch_application(usage: (u16, u16)) -> Option<(Application, bool)> {
    let kind = match usage.1 {
        u::TOUCH_SCREEN => Application::TouchScreen,
        u::TOUCH_PAD => Application::TouchPad,
        _ => return None,
    };
    match usage.0 {
        u::PAGE_DIGITIZER => Some((kind, false)),
        u::PAGE_VENDOR_FF00 => Some((kind, true)),
        _ => None,
    }
}

/// A usage as this module reads it: vendor-page usages of a Wacom-style touch
/// application mapped to their digitizer / Generic Desktop twins.
fn effective_usage(page: u16, id: u16, vendor: bool) -> (u16, u16) {
    if vendor && page == u::PAGE_VENDOR_FF00 {
        match id {
            u::VENDOR_X => (u::PAGE_GENERIC_DESKTOP, u::X),
            u::VENDOR_Y => (u::PAGE_GENERIC_DESKTOP, u::Y),
            id if id < 0x100 => (u::PAGE_DIGITIZER, id),
            id => (page, id),
        }
    } else {
        (page, id)
    }
}

fn field_of(v: &VariableField, report_id: Option<u8>) -> HidField {
    let logical_min = i32::from(v.logical_minimum);
    HidField {
        usage_page: u16::from(v.usage.usage_page),
        usage: u16::from(v.usage.usage_id),
        report_id,
        bit_offset: u32::try_from(v.bits.start).unwrap_or(u32::MAX),
        bit_size: u16::try_from(v.bits.len()).unwrap_or(u16::MAX),
        logical_min,
        logical_max: i32::from(v.logical_maximum),
        physical_min: v.physical_minimum.map_or(0, i32::from),
        physical_max: v.physical_maximum.map_or(0, i32::from),
        unit: v.unit.map_or(0, u32::from),
        unit_exponent: v.unit_exponent.map_or(0, |e| e.exponent()),
        signed: logical_min < 0,
    }
}

/// A touch application collection that could not be used, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Rejected {
    pub(super) application: Application,
    pub(super) offset: Option<usize>,
    pub(super) reason: String,
}

/// What a descriptor holds.
pub(super) struct Analysis {
    pub(super) collections: Vec<TouchCollection>,
    pub(super) rejected: Vec<Rejected>,
}

/// All variable fields of one direction, with their report IDs.
fn variable_fields<R: Report>(reports: &[R]) -> Vec<(Option<u8>, usize, &VariableField)> {
    let mut out = Vec::new();
    for r in reports {
        let id = r.report_id().as_ref().map(u8::from);
        for f in r.fields() {
            if let Field::Variable(v) = f {
                out.push((id, r.size_in_bytes(), v));
            }
        }
    }
    out
}

pub(super) fn analyse(desc: &[u8]) -> Result<Analysis, NotTouch> {
    let norm = normalise(desc)?;
    let rd = ReportDescriptor::try_from(&norm.bytes[..])
        .map_err(|e| parse_error(&e, |o| norm.original_offset(o)))?;
    let inputs = variable_fields(rd.input_reports());
    let features = variable_fields(rd.feature_reports());
    let offset_of = |c: &Collection| collection_offset(c).map(|o| norm.original_offset(o));

    let mut declared_input_ids: Vec<u8> = rd
        .input_reports()
        .iter()
        .filter_map(|r| r.report_id().as_ref().map(u8::from))
        .collect();
    declared_input_ids.sort_unstable();
    declared_input_ids.dedup();
    let uses_report_ids = rd.input_reports().iter().any(|r| r.report_id().is_some())
        || rd.feature_reports().iter().any(|r| r.report_id().is_some());

    // Touch applications, in descriptor order.
    let mut apps: Vec<(&Collection, Application, bool)> = Vec::new();
    for (_, _, v) in inputs.iter().chain(features.iter()) {
        if let Some(app) = application_of(v) {
            if apps.iter().any(|(a, _, _)| *a == app) {
                continue;
            }
            if let Some((kind, vendor)) = collection_usage(app).and_then(touch_application) {
                apps.push((app, kind, vendor));
            }
        }
    }
    apps.sort_by_key(|(a, _, _)| collection_offset(a));
    let any_touchpad = apps.iter().any(|(_, k, _)| *k == Application::TouchPad);

    // Multi-touch mode settings: the first Input Mode, Surface/Button Switch, in a
    // touch or Device Configuration application.
    let in_config_or_touch = |v: &VariableField| {
        application_of(v)
            .and_then(collection_usage)
            .is_some_and(|usage| {
                usage == (u::PAGE_DIGITIZER, u::DEVICE_CONFIGURATION)
                    || touch_application(usage).is_some()
            })
    };
    let setting = |id: Option<u8>, bytes: usize, v: &VariableField, value: u32| FeatureSetting {
        field: field_of(v, id),
        report_bytes: bytes,
        value,
    };
    let mut input_mode = None;
    let mut switches = Vec::new();
    for (id, bytes, v) in &features {
        if !in_config_or_touch(v) {
            continue;
        }
        let vendor = application_of(v)
            .and_then(collection_usage)
            .and_then(touch_application)
            .is_some_and(|(_, vendor)| vendor);
        let usage = effective_usage(
            u16::from(v.usage.usage_page),
            u16::from(v.usage.usage_id),
            vendor,
        );
        match usage {
            (u::PAGE_DIGITIZER, u::INPUT_MODE) if input_mode.is_none() => {
                let mode = if any_touchpad { 3 } else { 2 };
                input_mode = Some(setting(*id, *bytes, v, mode));
            }
            (u::PAGE_DIGITIZER, u::SURFACE_SWITCH | u::BUTTON_SWITCH) => {
                switches.push(setting(*id, *bytes, v, 1));
            }
            _ => {}
        }
    }

    let mut collections = Vec::new();
    let mut rejected = Vec::new();
    for (app, kind, vendor) in &apps {
        let eff = |v: &VariableField| {
            effective_usage(
                u16::from(v.usage.usage_page),
                u16::from(v.usage.usage_id),
                *vendor,
            )
        };
        // Input reports of this application, in order of first appearance.
        let mut report_ids: Vec<(Option<u8>, usize)> = Vec::new();
        for (id, bytes, v) in &inputs {
            if application_of(v) == Some(app) && !report_ids.iter().any(|(i, _)| i == id) {
                report_ids.push((*id, *bytes));
            }
        }
        let mut reports = Vec::new();
        let mut problems: Vec<String> = Vec::new();
        for (rid, size_bytes) in report_ids {
            let mut builders: Vec<FingerBuilder<'_>> = Vec::new();
            let mut cur = FingerBuilder::default();
            let mut contact_count = None;
            let mut scan_time = None;
            for (id, _, v) in &inputs {
                if *id != rid || application_of(v) != Some(app) {
                    continue;
                }
                let usage = eff(v);
                let field = field_of(v, rid);
                match usage {
                    (u::PAGE_DIGITIZER, u::CONTACT_COUNT) => {
                        contact_count.get_or_insert(field);
                        continue;
                    }
                    (u::PAGE_DIGITIZER, u::SCAN_TIME) => {
                        scan_time.get_or_insert(field);
                        continue;
                    }
                    _ => {}
                }
                let key = v.collections.last().filter(|c| *c != *app);
                if !is_finger_usage(usage) {
                    continue;
                }
                let new_key = key != cur.key && !cur.is_empty();
                let repeated = cur.slot(usage).is_some_and(|s| s.is_some());
                if new_key || (repeated && cur.complete()) {
                    builders.push(std::mem::take(&mut cur));
                } else if repeated {
                    // A duplicate usage in an incomplete finger: ignored.
                    continue;
                }
                cur.key = key;
                if let Some(s) = cur.slot(usage) {
                    *s = Some(field);
                }
            }
            if !cur.is_empty() {
                builders.push(cur);
            }
            let mut fingers = Vec::new();
            for (i, b) in builders.iter().enumerate() {
                match b.build() {
                    Ok(f) => fingers.push(f),
                    Err(why) => problems.push(format!(
                        "finger {} of input report {} has {why}",
                        i + 1,
                        rid.map_or("(no ID)".to_string(), |r| r.to_string())
                    )),
                }
            }
            if !fingers.is_empty() {
                let need = fingers
                    .iter()
                    .map(Finger::end_byte)
                    .chain(contact_count.iter().map(HidField::end_byte))
                    .max()
                    .unwrap_or(0);
                reports.push(TouchReport {
                    report_id: rid,
                    size_bytes: size_bytes.max(need),
                    fingers,
                    contact_count,
                    scan_time,
                });
            }
        }
        let where_ = match offset_of(app) {
            Some(o) => format!(
                "{} application collection at byte {o}",
                application_label(*kind)
            ),
            None => format!("{} application collection", application_label(*kind)),
        };
        if reports.is_empty() {
            let has = |usage: (u16, u16)| {
                inputs
                    .iter()
                    .any(|(_, _, v)| application_of(v) == Some(app) && eff(v) == usage)
            };
            let reason = if !has((u::PAGE_DIGITIZER, u::CONTACT_ID)) {
                format!(
                    "the {where_} has no Contact Identifier (a single-touch or \
                     mouse-emulation layout, not multi-touch)"
                )
            } else if !has((u::PAGE_GENERIC_DESKTOP, u::X)) || !has((u::PAGE_GENERIC_DESKTOP, u::Y))
            {
                format!("the {where_} has no X/Y")
            } else if let Some(p) = problems.first() {
                format!("the {where_}: {p}")
            } else {
                format!("the {where_} has no finger fields")
            };
            rejected.push(Rejected {
                application: *kind,
                offset: offset_of(app),
                reason,
            });
            continue;
        }
        // Contact Count Maximum of this application.
        let mut contact_count_max = None;
        let mut contact_count_max_report_bytes = 0;
        for (id, bytes, v) in &features {
            if application_of(v) == Some(app) && eff(v) == (u::PAGE_DIGITIZER, u::CONTACT_COUNT_MAX)
            {
                contact_count_max = Some(field_of(v, *id));
                contact_count_max_report_bytes = *bytes;
                break;
            }
        }
        collections.push(TouchCollection {
            application: *kind,
            vendor_usages: *vendor,
            offset: offset_of(app).unwrap_or(0),
            reports,
            contact_count_max,
            contact_count_max_report_bytes,
            input_mode,
            switches: switches.clone(),
            declared_input_ids: declared_input_ids.clone(),
            uses_report_ids,
        });
    }
    Ok(Analysis {
        collections,
        rejected,
    })
}

fn application_label(kind: Application) -> &'static str {
    match kind {
        Application::TouchScreen => "Touch Screen",
        Application::TouchPad => "Touch Pad",
    }
}

/// The touch application collections of a report descriptor.
///
/// # Errors
/// [`NotTouch`] when there is none crowdtouch can read, saying why: no digitizer
/// touch application, a touch collection with no Contact Identifier, no X/Y,
/// an unparsable descriptor (with the byte offset), a descriptor over
/// [`MAX_DESCRIPTOR_BYTES`](super::MAX_DESCRIPTOR_BYTES).
///
/// # Example
/// ```
/// use crowdtouch::input::hid::touch_collections;
/// // A mouse.
/// let mouse = [0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x30, 0x15, 0x81, 0x25, 0x7f,
///              0x75, 0x08, 0x95, 0x01, 0x81, 0x06, 0xc0];
/// let err = touch_collections(&mouse).unwrap_err();
/// assert!(err.reason.contains("no Touch Screen or Touch Pad"), "{}", err.reason);
/// ```
pub fn touch_collections(descriptor: &[u8]) -> Result<Vec<TouchCollection>, NotTouch> {
    let a = analyse(descriptor)?;
    if a.collections.is_empty() {
        return Err(no_collection(&a));
    }
    Ok(a.collections)
}

/// Why an analysis found no usable collection.
pub(super) fn no_collection(a: &Analysis) -> NotTouch {
    if a.rejected.is_empty() {
        return NotTouch::new(
            "no Touch Screen or Touch Pad application collection (digitizer page 0x0D, \
             usage 0x04/0x05) with input fields",
        );
    }
    let reasons: Vec<&str> = a.rejected.iter().map(|r| r.reason.as_str()).collect();
    NotTouch::new(reasons.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_descriptors_are_refused_not_panicking() {
        // Usage before any Usage Page: hidreport would `expect`.
        let r = touch_collections(&[0x09, 0x01, 0xa1, 0x01, 0xc0]);
        assert!(r.is_err());
        // A 4-billion-usage range.
        let r = touch_collections(&[
            0x05, 0x01, 0x1b, 0, 0, 0, 0, 0x2b, 0xff, 0xff, 0xff, 0xff, 0xa1, 0x01,
        ]);
        assert!(r.unwrap_err().reason.contains("range"));
        // Report Count 0xFFFFFFFF.
        let r = touch_collections(&[
            0x05, 0x01, 0x09, 0x30, 0x75, 0x08, 0x97, 0xff, 0xff, 0xff, 0xff, 0x81, 0x02,
        ]);
        assert!(r.unwrap_err().reason.contains("Report Count"));
        // Truncated item.
        let r = touch_collections(&[0x05]);
        assert!(r.unwrap_err().reason.contains("byte 0"));
        assert!(touch_collections(&[]).is_err());
        // Unit system nibble 0xF.
        let r = touch_collections(&[
            0x05, 0x01, 0x65, 0x0f, 0x09, 0x30, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02,
        ]);
        assert!(r.is_err());
    }
}
