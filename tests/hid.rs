//! Raw HID digitizers: descriptors against the fixtures' `index.json`, the
//! recordings against their decoded oracles, bad reports, hybrid frames, the
//! hid-recorder reader, `describe`, robustness (property tests) and the
//! allocation-free report path.
//!
//! Fixture provenance and licences: `tests/fixtures/README.md`. The oracles
//! (decoded values, counts, histograms, index.json facts) come from the shared
//! fixture collection's README, established independently of this decoder.
//! Reports marked SYNTHETIC are built here on a real device's layout.

use crowdtouch::input::hid::{
    describe, read_descriptor_file, touch_collections, Application, HidCounters, HidDecoder,
    ReportError, TouchCollection,
};
use crowdtouch::input::recording::parse_hid_recorder;
use crowdtouch::input::recording::{
    parse_recording, read_recording, OnBadFrame, Recording, RecordingError,
};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{ContactFlags, TouchFrame, MAX_CONTACTS};
use proptest::prelude::*;
use serde_json::Value;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::path::{Path, PathBuf};

const EPS: f32 = 1e-6;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/hid")
        .join(name)
}

fn rdesc(name: &str) -> Vec<u8> {
    std::fs::read(fixture(&format!("descriptors/{name}.rdesc"))).expect("fixture")
}

fn collection(name: &str) -> TouchCollection {
    touch_collections(&rdesc(name))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .remove(0)
}

fn hex(s: &str) -> Vec<u8> {
    s.split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect()
}

/// The four real ActionStar reports (fixture README, section 2).
const ACTIONSTAR: [&str; 4] = [
    "01 ff 01 57 1b 89 09 ff 02 7b 3b ea 07 02",
    "01 ff 01 54 1b 92 09 ff 02 7b 3b ec 07 02",
    "01 ff 02 81 3b f8 07 fe 01 54 1b 92 09 02",
    "01 ff 02 81 3b f8 07 fc 01 54 1b 92 09 02",
];

fn ids_flags(f: &TouchFrame) -> Vec<(u32, ContactFlags)> {
    f.contacts().iter().map(|c| (c.id.0, c.flags)).collect()
}

/// Checks the life cycle: one DOWN per id, nothing before it, nothing after its
/// end, every id ended by the last frame; positions in the unit square.
fn check_life_cycle(frames: &[TouchFrame]) {
    let mut down: HashSet<u32> = HashSet::new();
    let mut seen: HashSet<u32> = HashSet::new();
    for (i, f) in frames.iter().enumerate() {
        assert!(f.len() <= MAX_CONTACTS);
        let mut in_frame = HashSet::new();
        for c in f.contacts() {
            assert!(in_frame.insert(c.id.0), "frame {i}: id {} twice", c.id.0);
            assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
            if c.flags.contains(ContactFlags::DOWN) {
                assert!(seen.insert(c.id.0), "frame {i}: id {} DOWN again", c.id.0);
                down.insert(c.id.0);
            } else {
                assert!(down.contains(&c.id.0), "frame {i}: id {} not down", c.id.0);
            }
            if c.flags.ended() {
                down.remove(&c.id.0);
            }
        }
    }
    assert!(down.is_empty(), "still down at the end: {down:?}");
}

/// Contacts down after each frame → number of frames.
fn histogram(frames: &[TouchFrame]) -> BTreeMap<usize, usize> {
    let mut h = BTreeMap::new();
    for f in frames {
        let n = f.contacts().iter().filter(|c| !c.flags.ended()).count();
        *h.entry(n).or_insert(0) += 1;
    }
    h
}

// ---------------------------------------------------------------------------
// Descriptors

#[test]
fn descriptors_match_index_json() {
    let index: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("descriptors/index.json")).unwrap())
            .unwrap();
    let mut checked = 0;
    for dev in index.as_array().unwrap() {
        let name = dev["file"].as_str().unwrap();
        let path = fixture(&format!("descriptors/{name}.rdesc"));
        if !path.exists() {
            continue; // kept apart for acceptance checks
        }
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(
            bytes.len() as u64,
            dev["rdesc_len"].as_u64().unwrap(),
            "{name}"
        );
        let ours = touch_collections(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        let expected: Vec<&Value> = dev["collections"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["contacts_per_report"].as_u64().unwrap() > 0)
            .collect();
        assert_eq!(ours.len(), expected.len(), "{name}: collections");
        for (c, e) in ours.iter().zip(expected) {
            let app = match c.application {
                Application::TouchScreen => "TouchScreen",
                Application::TouchPad => "TouchPad",
            };
            assert_eq!(app, e["app"].as_str().unwrap(), "{name}");
            assert_eq!(
                c.contacts_per_report() as u64,
                e["contacts_per_report"].as_u64().unwrap(),
                "{name}: contacts per report"
            );
            assert_eq!(
                u64::from(c.reports[0].contact_count.is_some()),
                e["contact_count"].as_u64().unwrap(),
                "{name}: contact count"
            );
            assert_eq!(
                c.contact_count_max.is_some(),
                e["contact_max_feature"].as_bool().unwrap(),
                "{name}: contact count maximum"
            );
            let rids: Vec<u64> = c.report_ids().iter().map(|&i| u64::from(i)).collect();
            let want: Vec<u64> = e["input_rids"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap())
                .collect();
            assert_eq!(rids, want, "{name}: report ids");
            let f = c.first_finger().unwrap();
            for (axis, key) in [(f.x, "x_range"), (f.y, "y_range")] {
                let got = [
                    i64::from(axis.logical_min),
                    i64::from(axis.logical_max),
                    i64::from(axis.physical_min),
                    i64::from(axis.physical_max),
                    i64::from(axis.unit),
                    i64::from(axis.unit_exponent),
                ];
                let want: Vec<i64> = e[key]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_i64().unwrap())
                    .collect();
                assert_eq!(got.to_vec(), want, "{name}: {key}");
            }
            // Every finger of the report has the same axes and distinct bits.
            let mut offsets = HashSet::new();
            for r in &c.reports {
                for fg in &r.fingers {
                    assert_eq!(fg.x.logical_max, f.x.logical_max, "{name}");
                    assert!(offsets.insert(fg.contact_id.bit_offset), "{name}");
                    assert!(fg.end_byte() <= r.size_bytes, "{name}");
                }
            }
        }
        checked += 1;
    }
    assert!(checked >= 12, "only {checked} descriptors checked");
}

#[test]
fn resolution_follows_the_kernel_cross_checks() {
    // Fixture README: evdev absinfo resolution = logical range / physical mm, rounded.
    let dell = collection("advanced_silicon_2575_0204").surface("dell");
    assert_eq!(dell.x.resolution.round(), 55.0);
    assert_eq!(dell.y.resolution.round(), 98.0);
    let ite = collection("ite_06cb_2968");
    assert_eq!(ite.application, Application::TouchPad);
    let s = ite.surface("ite");
    assert_eq!(s.x.resolution.round(), 12.0);
    let (w, h) = s.size_mm().unwrap();
    assert_eq!((w as u32, h as u32), (87, 47)); // "Size in mm: 87x47"
    let elan = collection("elan_04f3_010c").surface("elan");
    assert_eq!(elan.x.resolution.round(), 10.0);
    assert_eq!(elan.x.max, 3312.0);
    // The kernel's maxima for the other pairs.
    assert_eq!(collection("quanta_0408_3001").surface("").x.max, 1920.0);
    let cando = collection("elan_04f3_0732").surface("");
    assert_eq!((cando.x.max, cando.y.max), (3008.0, 1856.0));
    assert_eq!(collection("irtouch_6615_0070").surface("").x.max, 32767.0);
    // No physical size: resolution unknown.
    assert_eq!(
        collection("zytronic_14c8_0006").surface("").x.resolution,
        0.0
    );
    // Unit 0x33 (inch³) is not a length: unknown, as in the kernel.
    assert_eq!(collection("3m_0596_0500").surface("").x.resolution, 0.0);
}

#[test]
fn multi_touch_mode_settings() {
    let m = collection("3m_0596_0500");
    let mode = m.input_mode.unwrap();
    assert_eq!((mode.field.report_id, mode.value), (Some(0x11), 2));
    assert_eq!((mode.field.usage_page, mode.field.usage), (0x0D, 0x52));
    // ITE touchpad: Input Mode 3 and Surface/Button Switch = 1.
    let ite = collection("ite_06cb_2968");
    assert_eq!(ite.input_mode.unwrap().value, 3);
    let sw: BTreeSet<u16> = ite.switches.iter().map(|s| s.field.usage).collect();
    assert_eq!(sw, BTreeSet::from([0x57, 0x58]));
    assert!(ite.switches.iter().all(|s| s.value == 1));
    // Writing a setting keeps the other bits of the report.
    let mut buf = vec![0x11, 0xff, 0xff];
    assert!(mode.apply(&mut buf));
    assert_eq!(buf[1], 2);
    assert_eq!(buf[2], 0xff);
    assert!(collection("actionstar_2101_1011").input_mode.is_none());
}

#[test]
fn goodix_descriptor_large_with_pen_and_vendor() {
    let d = read_descriptor_file(&fixture(
        "goodix-27c6-0e30.lenovo-duet.touch-and-usi-pen.hid",
    ))
    .unwrap();
    assert_eq!(d.len(), 1156);
    let cs = touch_collections(&d).unwrap();
    assert_eq!(cs.len(), 1);
    let c = &cs[0];
    assert_eq!(c.report_ids(), vec![1]);
    assert_eq!(c.contacts_per_report(), 5);
    assert_eq!(c.declared_max_contacts(), Some(10));
    assert!(c.declared_input_ids.contains(&8)); // the pen
    let f = c.first_finger().unwrap();
    // `25 ff` with a zero minimum is 255 (kernel), not -1 (hidreport alone).
    let w = f.width.unwrap();
    assert_eq!((w.logical_max, w.physical_max), (255, 255));
    assert!(f.height.is_some() && f.pressure.is_some());
    assert_eq!((f.x.logical_max, f.y.logical_max), (7200, 11520));
}

#[test]
fn wacom_vendor_page_touch() {
    let d = read_descriptor_file(&fixture(
        "wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
    ))
    .unwrap();
    assert_eq!(d.len(), 549);
    let c = touch_collections(&d).unwrap().remove(0);
    assert!(c.vendor_usages);
    assert_eq!(c.application, Application::TouchPad);
    assert_eq!(c.report_ids(), vec![0x21]);
    assert_eq!(c.contacts_per_report(), 5);
    assert!(c.reports[0].contact_count.is_some());
    let f = c.first_finger().unwrap();
    assert_eq!((f.x.usage_page, f.x.usage), (0xFF00, 0x130));
    assert_eq!((f.x.logical_max, f.y.logical_max), (8960, 5920));
    // 22400 × 10^-3 cm = 224 mm; 8960 / 224 = 40 units/mm.
    assert!((f.x.resolution() - 40.0).abs() < 1e-9);
    assert!(f.width.is_some() && f.height.is_some());
    // Contact Count Maximum's logical maximum (255) is not a plausible count.
    assert!(c.contact_count_max.is_some());
    assert_eq!(c.declared_max_contacts(), None);
}

/// SYNTHETIC: a Touch Screen collection with tip, X, Y and a Contact Count but no
/// Contact Identifier, the layout of the Microsoft 045E:0C1B negative case.
const NO_CONTACT_ID: [u8; 57] = [
    0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x01, 0x09, 0x22, 0xa1, 0x02, 0x09, 0x42, 0x15, 0x00,
    0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, 0x95, 0x07, 0x81, 0x03, 0x05, 0x01, 0x09, 0x30,
    0x09, 0x31, 0x26, 0xff, 0x7f, 0x75, 0x10, 0x95, 0x02, 0x81, 0x02, 0xc0, 0x05, 0x0d, 0x09, 0x54,
    0x25, 0x0a, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0xc0,
];

#[test]
fn negative_descriptors_say_why() {
    let e = touch_collections(&NO_CONTACT_ID).unwrap_err();
    assert!(e.reason.contains("no Contact Identifier"), "{e}");
    assert!(
        e.reason
            .contains("Touch Screen application collection at byte 4"),
        "{e}"
    );
    let mouse = [
        0x05, 0x01, 0x09, 0x02, 0xa1, 0x01, 0x09, 0x30, 0x15, 0x81, 0x25, 0x7f, 0x75, 0x08, 0x95,
        0x01, 0x81, 0x06, 0xc0,
    ];
    let e = touch_collections(&mouse).unwrap_err();
    assert!(e.reason.contains("no Touch Screen or Touch Pad"), "{e}");
    // Truncated in the middle of an item.
    let d = rdesc("actionstar_2101_1011");
    let e = touch_collections(&d[..59]).unwrap_err();
    assert!(e.reason.contains("byte 58"), "{e}");
    // SYNTHETIC: a finger with a Contact Identifier but no X/Y, and one with no
    // Tip Switch or In Range.
    let no_xy = [
        0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x01, 0x09, 0x22, 0xa1, 0x02, 0x09, 0x42, 0x15,
        0x00, 0x25, 0x01, 0x75, 0x01, 0x95, 0x01, 0x81, 0x02, 0x95, 0x07, 0x81, 0x03, 0x09, 0x51,
        0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0xc0, 0xc0,
    ];
    let e = touch_collections(&no_xy).unwrap_err();
    assert!(e.reason.contains("has no X/Y"), "{e}");
    let no_tip = [
        0x05, 0x0d, 0x09, 0x04, 0xa1, 0x01, 0x85, 0x01, 0x09, 0x22, 0xa1, 0x02, 0x09, 0x51, 0x15,
        0x00, 0x25, 0x0f, 0x75, 0x08, 0x95, 0x01, 0x81, 0x02, 0x05, 0x01, 0x09, 0x30, 0x09, 0x31,
        0x26, 0xff, 0x0f, 0x75, 0x10, 0x95, 0x02, 0x81, 0x02, 0xc0, 0xc0,
    ];
    let e = touch_collections(&no_tip).unwrap_err();
    assert!(
        e.reason
            .contains("finger 1 of input report 1 has no Tip Switch or In Range"),
        "{e}"
    );
    let e = touch_collections(&vec![0u8; 5000]).unwrap_err();
    assert!(e.reason.contains("5000 bytes"), "{e}");
    // eGalax: the second touch screen collection (a stylus layout) is ignored.
    let v = describe(&rdesc("egalax_capacitive_0eef_7224"));
    assert_eq!(v["touch"], true);
    assert_eq!(v["collections"].as_array().unwrap().len(), 1);
    let ignored = v["ignored"].as_array().unwrap();
    assert_eq!(ignored.len(), 1);
    assert!(ignored[0]["reason"]
        .as_str()
        .unwrap()
        .contains("no Contact Identifier"));
    let v = describe(&NO_CONTACT_ID);
    assert_eq!(v["touch"], false);
    assert!(v["reason"].as_str().unwrap().contains("Contact Identifier"));
}

#[test]
fn describe_reports_the_layout() {
    let v = describe(&rdesc("actionstar_2101_1011"));
    let c = &v["collections"][0];
    assert_eq!(c["application"], "touchscreen");
    assert_eq!(c["contacts_per_report"], 2);
    assert_eq!(c["max_contacts"], 2);
    assert_eq!(c["report_ids"], serde_json::json!([1]));
    assert_eq!(c["input_mode"], Value::Null);
    let x = &c["finger_fields"]["x"];
    assert_eq!(x["logical"], serde_json::json!([0, 19967]));
    assert_eq!(x["physical"], serde_json::json!([0, 880]));
    assert_eq!(x["unit_name"], "inch^3");
    assert_eq!(x["unit_exponent"], -2);
    assert_eq!(c["fingers"].as_array().unwrap().len(), 2);
    let v = describe(&rdesc("3m_0596_0500"));
    let c = &v["collections"][0];
    assert_eq!(c["input_mode"]["value"], 2);
    assert_eq!(c["input_mode"]["report_id"], 17);
    assert_eq!(c["contacts_per_report"], 10);
    let v = describe(&rdesc("ite_06cb_2968"));
    assert_eq!(v["collections"][0]["application"], "touchpad");
    assert_eq!(v["collections"][0]["input_mode"]["value"], 3);
    let dell = describe(&rdesc("advanced_silicon_2575_0204"));
    let size = dell["collections"][0]["surface"]["size_mm"]
        .as_array()
        .unwrap();
    assert!((size[0].as_f64().unwrap() - 596.7).abs() < 1e-9);
}

#[test]
fn descriptor_files_in_every_form() {
    let raw = rdesc("actionstar_2101_1011");
    assert_eq!(
        read_descriptor_file(&fixture("descriptors/actionstar_2101_1011.rdesc")).unwrap(),
        raw
    );
    assert_eq!(
        read_descriptor_file(&fixture("descriptors/actionstar_2101_1011.hid")).unwrap(),
        raw
    );
    let dir = tempfile::tempdir().unwrap();
    let dump = dir.path().join("dump.txt");
    let text: Vec<String> = raw.iter().map(|b| format!("0x{b:02x},")).collect();
    std::fs::write(&dump, format!("// comment\n{}\n", text.join(" "))).unwrap();
    assert_eq!(read_descriptor_file(&dump).unwrap(), raw);
    let bad = dir.path().join("bad.hid");
    std::fs::write(&bad, "# x\nR: 3 05 0d\n").unwrap();
    let e = read_descriptor_file(&bad).unwrap_err().to_string();
    assert!(e.contains(":2:") && e.contains("announces 3"), "{e}");
    let empty = dir.path().join("empty");
    std::fs::write(&empty, b"").unwrap();
    assert!(read_descriptor_file(&empty).is_err());
    assert!(read_descriptor_file(&dir.path().join("missing")).is_err());
}

#[test]
fn device_info_from_sysfs_facts() {
    use crowdtouch::input::hid::{device_info, parse_hid_uevent};
    use crowdtouch::input::{DeviceKind, Error};
    let u = parse_hid_uevent("HID_ID=0003:00002101:00001011\nHID_NAME=ActionStar\nHID_UNIQ=\n")
        .unwrap();
    let node = Path::new("/dev/hidraw4");
    let (info, tc) = device_info(node, &u, &rdesc("actionstar_2101_1011")).unwrap();
    assert_eq!(info.identity.kind, DeviceKind::Hidraw);
    assert_eq!(
        (
            info.identity.bus,
            info.identity.vendor,
            info.identity.product
        ),
        (3, 0x2101, 0x1011)
    );
    assert_eq!(info.stable_id, "2101:1011");
    assert!(info.direct);
    assert_eq!(info.surface.name, "ActionStar");
    assert_eq!(info.surface.x.max, 19967.0);
    assert_eq!(info.surface.max_contacts, 2);
    assert_eq!(tc.report_ids(), vec![1]);
    let (pad, _) = device_info(node, &u, &rdesc("ite_06cb_2968")).unwrap();
    assert!(!pad.direct);
    match device_info(node, &u, &NO_CONTACT_ID) {
        Err(Error::NotTouch { node: n, reason }) => {
            assert_eq!(n, node);
            assert!(reason.contains("Contact Identifier"));
        }
        other => panic!("{other:?}"),
    }
}

// ---------------------------------------------------------------------------
// Reports

#[test]
fn actionstar_decodes_to_the_oracle() {
    let c = collection("actionstar_2101_1011");
    let f0 = c.reports[0].fingers[0];
    let f1 = c.reports[0].fingers[1];
    // Raw decoded values per finger: (tip, in range, confidence, id, X, Y).
    let raw = |f: &crowdtouch::input::hid::Finger, b: &[u8]| {
        (
            f.tip.unwrap().extract(b).unwrap(),
            f.in_range.unwrap().extract(b).unwrap(),
            f.confidence.unwrap().extract(b).unwrap(),
            f.contact_id.extract(b).unwrap(),
            f.x.extract(b).unwrap(),
            f.y.extract(b).unwrap(),
        )
    };
    let r: Vec<Vec<u8>> = ACTIONSTAR.iter().map(|s| hex(s)).collect();
    assert_eq!(raw(&f0, &r[0]), (1, 1, 1, 1, 6999, 2441));
    assert_eq!(raw(&f1, &r[0]), (1, 1, 1, 2, 15227, 2026));
    let r1 = raw(&f0, &r[1]);
    assert_eq!((r1.4, r1.5), (6996, 2450));
    assert_eq!(raw(&f1, &r[1]).5, 2028);
    assert_eq!(raw(&f0, &r[2]), (1, 1, 1, 2, 15233, 2040));
    let r2 = raw(&f1, &r[2]);
    assert_eq!((r2.0, r2.3), (0, 1));
    assert_eq!(raw(&f1, &r[3]).1, 0);
    assert_eq!(c.reports[0].contact_count.unwrap().extract(&r[3]), Some(2));

    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    let (xs, ys) = (19967.0f32, 11263.0f32);
    assert!(dec.report(Micros(10), &r[0], &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::DOWN), (2, ContactFlags::DOWN)]
    );
    assert!((f.contacts()[0].x - 6999.0 / xs).abs() < EPS);
    assert!((f.contacts()[1].y - 2026.0 / ys).abs() < EPS);
    assert!(dec.report(Micros(20), &r[1], &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::NONE), (2, ContactFlags::NONE)]
    );
    assert!((f.contacts()[0].x - 6996.0 / xs).abs() < EPS);
    assert!((f.contacts()[1].y - 2028.0 / ys).abs() < EPS);
    // r2: contact 1 released (tip 0), at its last position; slot order swapped.
    assert!(dec.report(Micros(30), &r[2], &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)]
    );
    assert!((f.contacts()[0].x - 6996.0 / xs).abs() < EPS);
    assert!((f.contacts()[0].y - 2450.0 / ys).abs() < EPS);
    assert!((f.contacts()[1].x - 15233.0 / xs).abs() < EPS);
    assert_eq!(dec.active_contacts(), 1);
    // r3: contact 1 out of range too; nothing changes for it.
    assert!(dec.report(Micros(40), &r[3], &mut f));
    assert_eq!(ids_flags(&f), vec![(2, ContactFlags::NONE)]);
    assert_eq!(f.t, Micros(40));
    let c = dec.counters();
    assert_eq!(
        (c.reports, c.frames, c.contacts_begun, c.contacts_lifted),
        (4, 4, 2, 1)
    );
    assert!(dec.cancel_all(Micros(50), &mut f));
    assert_eq!(ids_flags(&f), vec![(2, ContactFlags::CANCELLED)]);
    assert!(!dec.cancel_all(Micros(60), &mut f));
}

#[test]
fn actionstar_recording_with_placeholder_times() {
    let rec = read_recording(
        &fixture("actionstar-2101-1011.inrange-sequence.hid"),
        OnBadFrame::Stop,
    )
    .unwrap();
    assert_eq!(rec.surface.name, "uhid test ActionStar_2101_1011");
    assert_eq!((rec.surface.x.max, rec.surface.y.max), (19967.0, 11263.0));
    assert_eq!(rec.surface.max_contacts, 2);
    assert_eq!(rec.frames.len(), 5);
    let times: Vec<u64> = rec.frames.iter().map(|f| f.t.0).collect();
    assert_eq!(times, vec![0, 0, 0, 0, 1_000]);
    assert_eq!(ids_flags(&rec.frames[2])[0], (1, ContactFlags::UP));
    assert_eq!(
        ids_flags(&rec.frames[4]),
        vec![(2, ContactFlags::CANCELLED)]
    );
    check_life_cycle(&rec.frames);
    assert!(rec.warnings.is_empty(), "{:?}", rec.warnings);
}

fn wacom() -> Recording {
    read_recording(
        &fixture("wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid"),
        OnBadFrame::Stop,
    )
    .unwrap()
}

#[test]
fn wacom_two_fingers_match_the_oracle() {
    let rec = wacom();
    assert_eq!(rec.frames.len(), 72);
    assert_eq!(
        histogram(&rec.frames),
        BTreeMap::from([(0, 1), (1, 2), (2, 69)])
    );
    let ids: BTreeSet<u32> = rec
        .frames
        .iter()
        .flat_map(|f| f.contacts().iter().map(|c| c.id.0))
        .collect();
    assert_eq!(ids, BTreeSet::from([1, 2]));
    check_life_cycle(&rec.frames);
    assert!((rec.duration().as_secs_f64() - 0.71).abs() < 0.01);
    assert!((rec.surface.x.resolution - 40.0).abs() < 1e-9);
    // Sizes in mm through the fields' own physical ranges: width 2/41 of 22.38 mm.
    let c = rec.frames[0].contacts()[0];
    assert!((c.major_mm.unwrap() - 2.0 / 41.0 * 22.38).abs() < 1e-4);
    assert!((c.minor_mm.unwrap() - 2.0 / 31.0 * 14.81).abs() < 1e-4);
    // A vertical movement: Y travels several times further than X.
    let span = |axis: fn(&crowdtouch::vocab::Contact) -> f32| {
        let v: Vec<f32> = rec
            .frames
            .iter()
            .flat_map(|f| f.contacts().iter().filter(|c| c.id.0 == 1).map(axis))
            .collect();
        v.iter().fold(f32::MIN, |a, &b| a.max(b)) - v.iter().fold(f32::MAX, |a, &b| a.min(b))
    };
    let (dx, dy) = (span(|c| c.x), span(|c| c.y));
    assert!(dy > 4.0 * dx, "dx {dx} dy {dy}");
}

#[test]
fn goodix_pen_reports_give_no_touch_frames() {
    let path = fixture("goodix-27c6-0e30.lenovo-duet.touch-and-usi-pen.hid");
    let text = std::fs::read_to_string(&path).unwrap();
    let log = parse_hid_recorder(&text, &path, OnBadFrame::Stop).unwrap();
    assert_eq!(log.len(), 40);
    assert_eq!(
        (log.bus, log.vendor, log.product),
        (Some(0x18), Some(0x27c6), Some(0x0e30))
    );
    let c = touch_collections(&log.descriptor).unwrap().remove(0);
    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    for (_, bytes) in log.events() {
        assert_eq!(dec.decode(Micros(0), bytes, &mut f), Ok(false));
    }
    let n = dec.counters();
    assert_eq!((n.reports, n.other_reports, n.frames), (40, 40, 0));
    assert!(matches!(
        read_recording(&path, OnBadFrame::Stop),
        Err(RecordingError::Empty { .. })
    ));
}

#[test]
fn bad_reports_are_counted_and_skipped() {
    let c = collection("actionstar_2101_1011");
    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    let r0 = hex(ACTIONSTAR[0]);
    assert!(dec.report(Micros(0), &r0, &mut f));
    let before = f;
    let t = Micros(1);
    assert_eq!(dec.decode(t, &[], &mut f), Err(ReportError::Empty));
    assert_eq!(
        dec.decode(t, &r0[..13], &mut f),
        Err(ReportError::Truncated {
            report_id: Some(1),
            len: 13,
            need: 14
        })
    );
    let mut other = r0.clone();
    other[0] = 0x05;
    assert_eq!(
        dec.decode(t, &other, &mut f),
        Err(ReportError::UnknownReportId { id: 5 })
    );
    // Feature report 2 is not an input report.
    other[0] = 0x02;
    assert_eq!(
        dec.decode(t, &other, &mut f),
        Err(ReportError::UnknownReportId { id: 2 })
    );
    let mut too_many = r0.clone();
    too_many[13] = 3;
    assert_eq!(
        dec.decode(t, &too_many, &mut f),
        Err(ReportError::CountAboveMax { count: 3, max: 2 })
    );
    assert_eq!(f, before, "a refused report leaves the frame alone");
    let n = dec.counters();
    assert_eq!(
        (
            n.malformed,
            n.truncated,
            n.unknown_report_id,
            n.count_above_max
        ),
        (1, 1, 2, 1)
    );
    // The contacts are unaffected: the next good report continues them.
    assert!(dec.report(Micros(2), &hex(ACTIONSTAR[1]), &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::NONE), (2, ContactFlags::NONE)]
    );
    assert_eq!(dec.counters().contacts_begun, 2);
}

#[test]
fn bad_reports_in_a_recording_name_their_line() {
    let text = std::fs::read_to_string(fixture("actionstar-2101-1011.inrange-sequence.hid"))
        .unwrap()
        .replace(
            "E: 000000.000000 14 01 ff 01 54",
            "E: 000000.000000 14 07 ff 01 54",
        );
    let p = Path::new("a.hid");
    match parse_recording(&text, p, OnBadFrame::Stop) {
        Err(RecordingError::Parse { line, message, .. }) => {
            assert_eq!(line, 15);
            assert!(message.contains("report ID 7"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    let rec = parse_recording(&text, p, OnBadFrame::Skip).unwrap();
    assert_eq!(rec.frames.len(), 4);
    assert_eq!(rec.warnings[0].line, 15);
    check_life_cycle(&rec.frames);
    // Byte count mismatch, and time going back.
    let text =
        std::fs::read_to_string(fixture("actionstar-2101-1011.inrange-sequence.hid")).unwrap();
    let short = text.replacen(
        "E: 000000.000000 14 01 ff 02 81",
        "E: 000000.000000 15 01 ff 02 81",
        1,
    );
    assert!(matches!(
        parse_recording(&short, p, OnBadFrame::Stop),
        Err(RecordingError::Parse { line: 16, .. })
    ));
    let back = text.replacen(
        "E: 000000.000000 14 01 ff 02 81",
        "E: 1.0 14 01 ff 02 81",
        1,
    );
    assert!(matches!(
        parse_recording(&back, p, OnBadFrame::Stop),
        Err(RecordingError::Parse { line: 17, .. })
    ));
    // A descriptor with no touch collection.
    let mouse = "R: 19 05 01 09 02 a1 01 09 30 15 81 25 7f 75 08 95 01 81 06 c0\nE: 0.0 1 00\n";
    match parse_recording(mouse, p, OnBadFrame::Stop) {
        Err(RecordingError::Parse {
            line: 1, message, ..
        }) => {
            assert!(message.contains("no Touch Screen"), "{message}")
        }
        other => panic!("{other:?}"),
    }
}

/// SYNTHETIC report in the ActionStar layout: `(id, tip, x, y)` per slot, count.
fn actionstar_report(slots: [(u8, bool, u16, u16); 2], count: u8) -> Vec<u8> {
    let mut b = vec![0x01];
    for (id, tip, x, y) in slots {
        b.push(if tip { 0x07 } else { 0x06 });
        b.push(id);
        b.extend_from_slice(&x.to_le_bytes());
        b.extend_from_slice(&y.to_le_bytes());
    }
    b.push(count);
    b
}

#[test]
fn hybrid_frames_span_reports() {
    let c = collection("actionstar_2101_1011");
    let mut dec = HidDecoder::new(&c);
    dec.set_max_contacts(4);
    let mut f = TouchFrame::default();
    // Four contacts, two slots per report: count 4 then count 0.
    let a = actionstar_report([(10, true, 100, 100), (11, true, 200, 200)], 4);
    let b = actionstar_report([(12, true, 300, 300), (13, true, 400, 400)], 0);
    assert!(!dec.report(Micros(1), &a, &mut f));
    assert!(dec.frame_pending());
    assert!(dec.report(Micros(2), &b, &mut f));
    assert_eq!(f.t, Micros(2));
    assert_eq!(f.len(), 4);
    assert!(f.contacts().iter().all(|c| c.flags == ContactFlags::DOWN));
    // Three contacts: count 3 then one valid slot of two.
    let a = actionstar_report([(10, true, 110, 100), (11, true, 210, 200)], 3);
    let b = actionstar_report([(12, true, 310, 300), (99, true, 0, 0)], 0);
    assert!(!dec.report(Micros(3), &a, &mut f));
    assert!(dec.report(Micros(4), &b, &mut f));
    // 13 was not listed: lifted. 99 was beyond the count: ignored.
    assert_eq!(
        ids_flags(&f),
        vec![
            (4, ContactFlags::UP),
            (1, ContactFlags::NONE),
            (2, ContactFlags::NONE),
            (3, ContactFlags::NONE)
        ]
    );
    // The second report of a frame is lost: the next frame starts; the partial
    // frame's new contact is delivered with DOWN then.
    let a = actionstar_report([(20, true, 1, 1), (11, true, 2, 2)], 4);
    assert!(!dec.report(Micros(5), &a, &mut f));
    let a = actionstar_report([(20, true, 1, 1), (11, true, 2, 2)], 2);
    assert!(dec.report(Micros(6), &a, &mut f));
    assert_eq!(dec.counters().incomplete_frames, 1);
    let got = ids_flags(&f);
    assert!(got.contains(&(5, ContactFlags::DOWN)), "{got:?}");
    assert!(got.contains(&(2, ContactFlags::NONE)), "{got:?}");
    // 1 and 3 were in neither report: lifted.
    assert!(got.contains(&(1, ContactFlags::UP)) && got.contains(&(3, ContactFlags::UP)));
    // Count 0 with no frame under way: nobody touches.
    let z = actionstar_report([(0, false, 0, 0), (0, false, 0, 0)], 0);
    assert!(dec.report(Micros(7), &z, &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(2, ContactFlags::UP), (5, ContactFlags::UP)]
    );
    assert_eq!(dec.active_contacts(), 0);
}

#[test]
fn wacom_layout_hybrid_seven_fingers() {
    // SYNTHETIC reports on the Wacom layout: 7 contacts as 5 + 2 slots.
    let d = read_descriptor_file(&fixture(
        "wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
    ))
    .unwrap();
    let c = touch_collections(&d).unwrap().remove(0);
    let mut dec = HidDecoder::new(&c);
    let report = |count: u8, ids: &[u8]| {
        let mut b = vec![0u8; 44];
        b[0] = 0x21;
        b[1] = count;
        for (i, id) in ids.iter().enumerate() {
            let s = 2 + 8 * i;
            b[s] = *id;
            b[s + 1] = 1;
            b[s + 2..s + 4].copy_from_slice(&(1000u16 * u16::from(*id)).to_le_bytes());
            b[s + 4..s + 6].copy_from_slice(&500u16.to_le_bytes());
        }
        b
    };
    let mut f = TouchFrame::default();
    assert!(!dec.report(Micros(1), &report(7, &[1, 2, 3, 4, 5]), &mut f));
    assert!(dec.report(Micros(2), &report(0, &[6, 7]), &mut f));
    assert_eq!(f.len(), 7);
    let x6 = f.contacts()[5].x;
    assert!((x6 - 6000.0 / 8960.0).abs() < EPS);
}

#[test]
fn not_seen_means_up_and_ids_are_never_reused() {
    let c = collection("actionstar_2101_1011");
    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    let none = (0, false, 0, 0);
    dec.report(
        Micros(1),
        &actionstar_report([(1, true, 10, 10), (2, true, 20, 20)], 2),
        &mut f,
    );
    // Only contact 2 listed: contact 1 ended.
    assert!(dec.report(
        Micros(2),
        &actionstar_report([(2, true, 21, 20), none], 1),
        &mut f
    ));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)]
    );
    assert_eq!(dec.counters().contacts_not_seen, 1);
    // HID id 1 again: a new contact, id 3.
    assert!(dec.report(
        Micros(3),
        &actionstar_report([(2, true, 21, 20), (1, true, 5, 5)], 2),
        &mut f
    ));
    assert_eq!(
        ids_flags(&f),
        vec![(3, ContactFlags::DOWN), (2, ContactFlags::NONE)]
    );
    // The same HID id twice in a frame: the second is ignored.
    assert!(dec.report(
        Micros(4),
        &actionstar_report([(2, true, 30, 30), (2, true, 99, 99)], 2),
        &mut f
    ));
    assert_eq!(dec.counters().duplicate_contacts, 1);
    let two = f.contacts().iter().find(|c| c.id.0 == 2).unwrap();
    assert!((two.x - 30.0 / 19967.0).abs() < EPS);
    // ... and contact 3, not listed, ended.
    assert!(ids_flags(&f).contains(&(3, ContactFlags::UP)));
    // Began in a frame that never completed, lifted in the next: DOWN | UP.
    dec.set_max_contacts(4);
    assert!(!dec.report(
        Micros(5),
        &actionstar_report([(2, true, 30, 30), (7, true, 1, 1)], 3),
        &mut f
    ));
    assert!(dec.report(
        Micros(6),
        &actionstar_report([(2, true, 30, 30), (7, false, 1, 1)], 2),
        &mut f
    ));
    assert_eq!(
        ids_flags(&f),
        vec![
            (4, ContactFlags::DOWN | ContactFlags::UP),
            (2, ContactFlags::NONE)
        ]
    );
    assert_eq!(dec.counters().incomplete_frames, 1);
    assert_eq!(dec.next_id(), 5);
}

#[test]
fn confidence_zero_marks_a_palm() {
    let c = collection("actionstar_2101_1011");
    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    let mut r = hex(ACTIONSTAR[0]);
    r[1] = 0x03; // tip, in range, confidence 0
    assert!(dec.report(Micros(0), &r, &mut f));
    assert_eq!(
        f.contacts()[0].flags,
        ContactFlags::DOWN | ContactFlags::PALM
    );
    assert_eq!(f.contacts()[1].flags, ContactFlags::DOWN);
    assert!(dec.report(Micros(1), &hex(ACTIONSTAR[1]), &mut f));
    assert_eq!(f.contacts()[0].flags, ContactFlags::NONE);
}

#[test]
fn serial_reporting_without_contact_count() {
    // SYNTHETIC reports on the eGalax 0EEF:7224 layout: one finger per report,
    // no Contact Count. Every report is a frame; contacts end by tip 0 only.
    let c = collection("egalax_capacitive_0eef_7224");
    assert!(c.reports[0].contact_count.is_none());
    let mut dec = HidDecoder::new(&c);
    let report = |tip: bool, id: u8, x: u16| {
        let mut b = vec![0x04, u8::from(tip) | 0x02 | (id << 2) | 0x80];
        b.extend_from_slice(&x.to_le_bytes());
        b.extend_from_slice(&1000u16.to_le_bytes());
        b
    };
    let mut f = TouchFrame::default();
    assert!(dec.report(Micros(1), &report(true, 1, 100), &mut f));
    assert!(dec.report(Micros(2), &report(true, 2, 200), &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(2, ContactFlags::DOWN), (1, ContactFlags::NONE)]
    );
    assert!(dec.report(Micros(3), &report(false, 1, 100), &mut f));
    assert_eq!(
        ids_flags(&f),
        vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)]
    );
    assert_eq!(dec.active_contacts(), 1);
}

#[test]
fn contacts_beyond_the_maximum_are_refused() {
    let c = collection("actionstar_2101_1011");
    let mut dec = HidDecoder::new(&c);
    dec.set_max_contacts(1);
    let mut f = TouchFrame::default();
    assert!(dec.report(
        Micros(1),
        &actionstar_report([(1, true, 1, 1), (0, false, 0, 0)], 1),
        &mut f
    ));
    let r = actionstar_report([(1, true, 1, 1), (2, true, 2, 2)], 1);
    assert!(dec.report(Micros(2), &r, &mut f));
    assert_eq!(f.len(), 1);
    assert_eq!(dec.counters().contacts_over_capacity, 0);
    // Serial layout without a count: a second finger beyond max 1 is refused.
    let e = collection("egalax_capacitive_0eef_7224");
    let mut dec = HidDecoder::new(&e);
    dec.set_max_contacts(1);
    for id in [1u8, 2] {
        dec.report(Micros(1), &[0x04, 0x03 | (id << 2), 0, 0, 0, 0], &mut f);
    }
    assert_eq!(dec.counters().contacts_over_capacity, 1);
    assert_eq!(dec.active_contacts(), 1);
}

#[test]
fn ten_finger_frames_for_large_tables() {
    // SYNTHETIC: the 3M 0596:0500 layout, 10 fingers per report, all down.
    let c = collection("3m_0596_0500");
    let mut dec = HidDecoder::new(&c);
    let mut f = TouchFrame::default();
    let mut frames = Vec::new();
    for step in 0..3 {
        assert!(dec.report(Micros(1), &synthetic_3m_report(&c, step), &mut f));
        assert_eq!(f.len(), 10);
        frames.push(f);
    }
    assert!(frames[0]
        .contacts()
        .iter()
        .all(|c| c.flags == ContactFlags::DOWN));
    assert!(frames[2]
        .contacts()
        .iter()
        .all(|c| c.flags == ContactFlags::NONE));
    let d = frames[1].contacts()[3].x - frames[0].contacts()[3].x;
    assert!((d - 1.0 / 32767.0).abs() < EPS);
    assert!(dec.cancel_all(Micros(2), &mut f));
    frames.push(f);
    check_life_cycle(&frames);
}

/// SYNTHETIC 3M report: 10 fingers down at distinct positions shifted by `step`.
fn synthetic_3m_report(c: &TouchCollection, step: u16) -> Vec<u8> {
    let r = &c.reports[0];
    let mut b = vec![0u8; r.size_bytes];
    b[0] = r.report_id.unwrap();
    let put = |b: &mut Vec<u8>, f: &crowdtouch::input::hid::HidField, v: u32| {
        for i in 0..f.bit_size as u32 {
            let bit = (f.bit_offset + i) as usize;
            if (v >> i) & 1 == 1 {
                b[bit / 8] |= 1 << (bit % 8);
            }
        }
    };
    for (i, fg) in r.fingers.iter().enumerate() {
        put(&mut b, &fg.tip.unwrap(), 1);
        if let Some(conf) = fg.confidence {
            put(&mut b, &conf, 1);
        }
        put(&mut b, &fg.contact_id, i as u32);
        put(&mut b, &fg.x, 1000 + 3000 * i as u32 + u32::from(step));
        put(&mut b, &fg.y, 2000 + 1000 * i as u32);
    }
    put(&mut b, &r.contact_count.unwrap(), 10);
    b
}

// ---------------------------------------------------------------------------
// Robustness

fn all_fixture_descriptors() -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = std::fs::read_dir(fixture("descriptors"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rdesc"))
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    for r in [
        "wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid",
        "goodix-27c6-0e30.lenovo-duet.touch-and-usi-pen.hid",
    ] {
        out.push(read_descriptor_file(&fixture(r)).unwrap());
    }
    out
}

/// Feeds reports and checks frame invariants; ends with `cancel_all`.
fn feed_checked(dec: &mut HidDecoder, reports: &[Vec<u8>]) {
    let mut frames = Vec::new();
    let mut f = TouchFrame::default();
    for (i, r) in reports.iter().enumerate() {
        if dec.report(Micros(i as u64), r, &mut f) {
            frames.push(f);
        }
    }
    if dec.cancel_all(Micros(u64::MAX), &mut f) {
        frames.push(f);
    }
    check_life_cycle(&frames);
    assert_eq!(dec.active_contacts(), 0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(0x4849_4400), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_descriptor_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let _ = touch_collections(&bytes);
        let _ = describe(&bytes);
    }

    #[test]
    fn mutated_real_descriptors_never_panic(
        which in 0usize..16,
        edits in proptest::collection::vec((any::<u16>(), any::<u8>()), 1..8),
        cut in any::<u16>(),
    ) {
        let all = all_fixture_descriptors();
        let mut d = all[which % all.len()].clone();
        for (pos, v) in edits {
            let i = pos as usize % d.len();
            d[i] = v;
        }
        let keep = (cut as usize % (d.len() + 1)).max(1);
        d.truncate(keep);
        if let Ok(cs) = touch_collections(&d) {
            for c in &cs {
                // Layouts from mutated descriptors decode arbitrary reports safely.
                let mut dec = HidDecoder::new(c);
                let n = dec.max_report_bytes().clamp(1, 64);
                let reports: Vec<Vec<u8>> = (0..8u8)
                    .map(|k| (0..n).map(|j| (j as u8).wrapping_mul(31).wrapping_add(k)).collect())
                    .collect();
                feed_checked(&mut dec, &reports);
            }
        }
        let _ = describe(&d);
    }

    #[test]
    fn arbitrary_reports_keep_the_life_cycle(
        which in 0usize..16,
        reports in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..48), 0..40),
        fix_id in any::<bool>(),
    ) {
        let all = all_fixture_descriptors();
        let cs = touch_collections(&all[which % all.len()]).unwrap();
        let c = &cs[0];
        let id = c.reports[0].report_id;
        let reports: Vec<Vec<u8>> = reports
            .into_iter()
            .map(|mut r| {
                if fix_id {
                    if let (Some(id), Some(b)) = (id, r.first_mut()) {
                        *b = id;
                    }
                    // Small contact ids and counts, so contacts meet again.
                    for b in r.iter_mut().skip(1) {
                        *b &= 0x0f;
                    }
                }
                r
            })
            .collect();
        let mut dec = HidDecoder::new(c);
        feed_checked(&mut dec, &reports);
        let n: HidCounters = dec.counters();
        prop_assert_eq!(n.reports as usize, reports.len());
    }

    #[test]
    fn arbitrary_hid_recorder_text_never_panics(
        lines in proptest::collection::vec(
            prop_oneof![
                Just("R: 3 05 0d 09".to_string()),
                Just("E: 0.000001 14 01 ff 01 57 1b 89 09 ff 02 7b 3b ea 07 02".to_string()),
                "[A-Z]: [0-9a-f .]{0,40}",
                "[ -~]{0,30}",
            ],
            0..20,
        ),
    ) {
        let text = lines.join("\n");
        let p = Path::new("p.hid");
        let _ = parse_hid_recorder(&text, p, OnBadFrame::Skip);
        let _ = parse_recording(&format!("R: 177 {}\n{text}", ACTIONSTAR_RDESC_HEX), p, OnBadFrame::Skip);
    }
}

/// The ActionStar descriptor as hid-recorder hex.
const ACTIONSTAR_RDESC_HEX: &str = "05 0d 09 04 a1 01 85 01 09 22 a1 02 09 42 15 00 25 01 75 01 95 01 81 02 09 32 81 02 09 47 81 02 95 05 81 03 09 51 75 08 95 01 81 02 05 01 35 00 55 0e 65 33 75 10 95 01 09 30 26 ff 4d 46 70 03 81 02 09 31 26 ff 2b 46 f1 01 81 02 46 00 00 c0 a1 02 05 0d 09 42 15 00 25 01 75 01 95 01 81 02 09 32 81 02 09 47 81 02 95 05 81 03 09 51 75 08 95 01 81 02 05 01 35 00 55 0e 65 33 75 10 95 01 09 30 26 ff 4d 46 70 03 81 02 09 31 26 ff 2b 46 f1 01 81 02 46 00 00 c0 05 0d 09 54 75 08 95 01 81 02 05 0d 85 02 09 55 25 02 75 08 95 01 b1 02 c0";

#[test]
fn actionstar_hex_constant_is_the_fixture() {
    assert_eq!(hex(ACTIONSTAR_RDESC_HEX), rdesc("actionstar_2101_1011"));
}

// ---------------------------------------------------------------------------
// Allocation-free report path

struct Counting;

thread_local! {
    static ARMED: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; only counts calls made on threads that
// armed the counter (thread-locals with const initialisers never allocate).
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if ARMED.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if ARMED.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn decoding_reports_allocates_nothing() {
    let c = collection("3m_0596_0500");
    let mut dec = HidDecoder::new(&c);
    let reports: Vec<Vec<u8>> = (0..50).map(|s| synthetic_3m_report(&c, s)).collect();
    let bad = vec![0x10u8; 3];
    let mut f = TouchFrame::default();
    COUNT.with(|n| n.set(0));
    ARMED.with(|a| a.set(true));
    let mut frames = 0;
    for (i, r) in reports.iter().enumerate() {
        frames += usize::from(dec.report(Micros(i as u64), r, &mut f));
        let _ = dec.decode(Micros(i as u64), &bad, &mut f);
        let _ = dec.decode(Micros(i as u64), &[0x77], &mut f);
    }
    dec.cancel_all(Micros(99), &mut f);
    ARMED.with(|a| a.set(false));
    assert_eq!(COUNT.with(Cell::get), 0, "allocations on the report path");
    assert_eq!(frames, 50);
}
