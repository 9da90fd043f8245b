//! The JSON description of a descriptor's touch collections (`crowdtouch hid
//! describe`).

use super::collections::analyse;
use super::collections::no_collection;
use super::layout::{Finger, HidField, TouchCollection};
use super::units::unit_name;
use crate::input::AxisRange;
use serde_json::{json, Value};

/// Describes a report descriptor's touch collections as JSON (for
/// `crowdtouch hid describe`).
///
/// `{"touch": true, "descriptor_bytes": N, "collections": [...], "ignored": [...]}`,
/// one object per usable touch application collection with `application`,
/// `contacts_per_report`, `max_contacts` (and its source), `report_ids`,
/// `contact_count`, `contact_count_maximum`, `input_mode`, `surface` (X/Y ranges,
/// resolution, size in mm) and `finger_fields` (every field of the first finger
/// with logical/physical ranges and units) plus `fingers` (bit offsets of all);
/// `ignored` lists touch collections that cannot be used and why. When there is
/// none: `{"touch": false, "reason": "..."}`.
pub fn describe(descriptor: &[u8]) -> Value {
    let a = match analyse(descriptor) {
        Ok(a) => a,
        Err(e) => return json!({"touch": false, "reason": e.reason}),
    };
    if a.collections.is_empty() {
        return json!({"touch": false, "reason": no_collection(&a).reason});
    }
    let collections: Vec<Value> = a.collections.iter().map(describe_collection).collect();
    let ignored: Vec<Value> = a
        .rejected
        .iter()
        .map(|r| json!({"application": r.application, "offset": r.offset, "reason": r.reason}))
        .collect();
    json!({
        "touch": true,
        "descriptor_bytes": descriptor.len(),
        "collections": collections,
        "ignored": ignored,
    })
}

fn describe_collection(c: &TouchCollection) -> Value {
    let surface = c.surface("");
    let first = c.first_finger().copied();
    let finger_fields: serde_json::Map<String, Value> = first
        .map(|f| {
            f.named_fields()
                .into_iter()
                .map(|(n, f)| (n.to_string(), f.to_json()))
                .collect()
        })
        .unwrap_or_default();
    let fingers: Vec<Value> = c
        .reports
        .iter()
        .flat_map(|r| r.fingers.iter())
        .map(|f| {
            let m: serde_json::Map<String, Value> = f
                .named_fields()
                .into_iter()
                .map(|(n, f)| (n.to_string(), json!([f.bit_offset, f.bit_size])))
                .collect();
            Value::Object(m)
        })
        .collect();
    let (max_contacts, source) = match c.declared_max_contacts() {
        Some(n) => (
            n,
            "Contact Count Maximum feature (logical maximum; the device may report fewer)",
        ),
        None => (
            c.max_contacts(),
            "finger slots per report (no usable Contact Count Maximum)",
        ),
    };
    let contact_count = c.reports.first().and_then(|r| r.contact_count);
    let axis = |a: &AxisRange| json!({"min": a.min, "max": a.max, "resolution": a.resolution, "length_mm": a.length_mm()});
    json!({
        "application": c.application,
        "vendor_usages": c.vendor_usages,
        "offset": c.offset,
        "contacts_per_report": c.contacts_per_report(),
        "max_contacts": max_contacts,
        "max_contacts_source": source,
        "report_ids": c.report_ids(),
        "report_bytes": c.reports.iter().map(|r| r.size_bytes).collect::<Vec<_>>(),
        "hybrid": contact_count.is_some(),
        "contact_count": contact_count.map(HidField::to_json),
        "contact_count_maximum": c.contact_count_max.map(HidField::to_json),
        "input_mode": c.input_mode.map(|s| json!({
            "report_id": s.field.report_id,
            "bit_offset": s.field.bit_offset,
            "bit_size": s.field.bit_size,
            "value": s.value,
        })),
        "surface": {"x": axis(&surface.x), "y": axis(&surface.y), "size_mm": surface.size_mm()},
        "finger_fields": finger_fields,
        "fingers": fingers,
    })
}

impl HidField {
    /// Description for [`describe`].
    fn to_json(self) -> Value {
        json!({
            "usage": format!("0x{:04x}:0x{:04x}", self.usage_page, self.usage),
            "report_id": self.report_id,
            "bit_offset": self.bit_offset,
            "bit_size": self.bit_size,
            "logical": [self.logical_min, self.logical_max],
            "physical": [self.physical_min, self.physical_max],
            "unit": format!("0x{:x}", self.unit),
            "unit_name": unit_name(self.unit),
            "unit_exponent": self.unit_exponent,
            "signed": self.signed,
            "physical_length_mm": self.physical_length_mm(),
        })
    }
}

impl Finger {
    /// The fields present, named as in [`describe`]'s output.
    fn named_fields(&self) -> Vec<(&'static str, HidField)> {
        let mut v = vec![
            ("contact_id", self.contact_id),
            ("x", self.x),
            ("y", self.y),
        ];
        for (name, f) in [
            ("tip_switch", self.tip),
            ("in_range", self.in_range),
            ("confidence", self.confidence),
            ("width", self.width),
            ("height", self.height),
            ("tip_pressure", self.pressure),
            ("azimuth", self.azimuth),
        ] {
            if let Some(f) = f {
                v.push((name, f));
            }
        }
        v
    }
}
