//! Discovery and selection on fake `/dev` + `/sys` + `/run/udev/data` trees built from
//! real device descriptions (`tests/fixtures/sysfs/README.md`).
//!
//! The trees follow real sysfs: the class entries are links into `sys/devices`, an
//! evdev node's `device` is its `inputN` directory whose `device` is the HID device,
//! and a hidraw node's `device` is that same HID device. Device "nodes" are plain
//! files: discovery never opens them (the fake prober stands in for that).

use crowdtouch::input::discover::{
    self, classify_report_descriptor, discover, matches, recognise, scan, select, sticky_selector,
    Bitmap, Found, InterfacePreference, Prober, SelectError, Selector, TouchClass,
};
use crowdtouch::input::{AxisRange, DeviceIdentity, DeviceInfo, DeviceKind, Error, SurfaceInfo};
use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures");
const DELL_ID_PATH: &str = "pci-0000:00:14.0-usb-0:1:1.0";
const ITE_ID_PATH: &str = "pci-0000:00:14.0-usb-0:2:1.0";
const EVDEV_MAJOR: u32 = 13;
const HIDRAW_MAJOR: u32 = 244;

/// Tolerance for axis figures read back from the fixtures.
const EPS: f64 = 1e-9;

fn fixture(rel: &str) -> PathBuf {
    Path::new(FIXTURES).join(rel)
}

/// What an evdev device description says.
#[derive(Clone, Debug, Default)]
struct Desc {
    name: String,
    bus: u16,
    vendor: u16,
    product: u16,
    props: Vec<usize>,
    abs: Vec<usize>,
    /// code → (min, max, resolution)
    absinfo: BTreeMap<usize, (f64, f64, f64)>,
}

/// Parses an evemu header (`N:`, `I:`, `P:`, `B:`, `A:` lines).
fn parse_evemu(text: &str) -> Desc {
    let mut d = Desc::default();
    let mut byte_index: HashMap<u8, usize> = HashMap::new();
    let mut prop_index = 0;
    for line in text.lines() {
        if let Some(n) = line.strip_prefix("N: ") {
            d.name = n.to_string();
        } else if let Some(i) = line.strip_prefix("I: ") {
            let v: Vec<u16> = i
                .split_whitespace()
                .map(|h| u16::from_str_radix(h, 16).unwrap())
                .collect();
            (d.bus, d.vendor, d.product) = (v[0], v[1], v[2]);
        } else if let Some(p) = line.strip_prefix("P: ") {
            for b in p.split_whitespace() {
                let byte = u8::from_str_radix(b, 16).unwrap();
                d.props.extend(
                    (0..8)
                        .filter(|j| byte >> j & 1 == 1)
                        .map(|j| prop_index * 8 + j),
                );
                prop_index += 1;
            }
        } else if let Some(b) = line.strip_prefix("B: ") {
            let mut words = b.split_whitespace();
            let ty = u8::from_str_radix(words.next().unwrap(), 16).unwrap();
            let idx = byte_index.entry(ty).or_insert(0);
            for w in words {
                let byte = u8::from_str_radix(w, 16).unwrap();
                if ty == 3 {
                    d.abs
                        .extend((0..8).filter(|j| byte >> j & 1 == 1).map(|j| *idx * 8 + j));
                }
                *idx += 1;
            }
        } else if let Some(a) = line.strip_prefix("A: ") {
            let v: Vec<&str> = a.split_whitespace().collect();
            let code = usize::from_str_radix(v[0], 16).unwrap();
            let num = |i: usize| v.get(i).map_or(0.0, |s| s.parse::<f64>().unwrap());
            d.absinfo.insert(code, (num(1), num(2), num(5)));
        }
    }
    d
}

/// Parses the device part of a `libinput record` YAML (name, id, ABS codes, absinfo,
/// properties).
fn parse_libinput_record(text: &str) -> Desc {
    let list = |s: &str| -> Vec<usize> {
        let inner = s.split('[').nth(1).unwrap().split(']').next().unwrap();
        inner
            .split(',')
            .filter(|x| !x.trim().is_empty())
            .map(|x| x.trim().parse().unwrap())
            .collect()
    };
    let mut d = Desc::default();
    let mut in_absinfo = false;
    for line in text.lines() {
        let t = line.trim();
        if let Some(n) = t.strip_prefix("name: ") {
            d.name = n.trim_matches('"').to_string();
        } else if t.starts_with("id: [") {
            let v = list(t);
            (d.bus, d.vendor, d.product) = (v[0] as u16, v[1] as u16, v[2] as u16);
        } else if t.starts_with("3: [") && !in_absinfo {
            d.abs = list(t);
        } else if t == "absinfo:" {
            in_absinfo = true;
        } else if t.starts_with("properties: [") {
            d.props = list(t);
            in_absinfo = false;
        } else if in_absinfo && t.contains(": [") {
            let code: usize = t.split(':').next().unwrap().parse().unwrap();
            let v = list(t);
            d.absinfo
                .insert(code, (v[0] as f64, v[1] as f64, v[4] as f64));
        } else {
            in_absinfo = false;
        }
    }
    d
}

fn dell_desc() -> Desc {
    parse_evemu(&std::fs::read_to_string(fixture("dell-canvas-27-touch.evemu")).unwrap())
}

fn egalax_desc() -> Desc {
    parse_evemu(
        &std::fs::read_to_string(fixture(
            "sysfs/egalax-usb-touchcontroller-0eef-0001.single-touch.desc",
        ))
        .unwrap(),
    )
}

fn ite_desc() -> Desc {
    parse_libinput_record(
        &std::fs::read_to_string(fixture("ite-8595-touchpad-06cb-2968.two-finger-scroll.yml"))
            .unwrap(),
    )
}

fn keyboard_desc() -> Desc {
    Desc {
        name: "AT Translated Set 2 keyboard".into(),
        bus: 0x11,
        vendor: 1,
        product: 1,
        ..Desc::default()
    }
}

/// A boot keyboard HID descriptor (Generic Desktop / Keyboard), written for this test.
const KEYBOARD_RDESC: &[u8] = &[
    0x05, 0x01, 0x09, 0x06, 0xa1, 0x01, 0x05, 0x07, 0x19, 0xe0, 0x29, 0xe7, 0x15, 0x00, 0x25, 0x01,
    0x75, 0x01, 0x95, 0x08, 0x81, 0x02, 0x95, 0x01, 0x75, 0x08, 0x81, 0x03, 0x95, 0x06, 0x75, 0x08,
    0x15, 0x00, 0x25, 0x65, 0x05, 0x07, 0x19, 0x00, 0x29, 0x65, 0x81, 0x00, 0xc0,
];

/// What the evdev module's probe would report for a device with this description.
fn evdev_info(node: &Path, d: &Desc) -> DeviceInfo {
    let (cx, cy) = if d.absinfo.contains_key(&0x35) {
        (0x35, 0x36)
    } else {
        (0, 1)
    };
    let axis = |c: usize| {
        let (min, max, resolution) = d.absinfo[&c];
        AxisRange {
            min,
            max,
            resolution,
        }
    };
    DeviceInfo {
        identity: DeviceIdentity {
            kind: DeviceKind::Evdev,
            node: node.to_path_buf(),
            name: d.name.clone(),
            bus: d.bus,
            vendor: d.vendor,
            product: d.product,
            serial: None,
        },
        id_path: None,
        stable_id: String::new(),
        surface: SurfaceInfo {
            name: d.name.clone(),
            x: axis(cx),
            y: axis(cy),
            max_contacts: d.absinfo.get(&0x2f).map_or(1, |a| a.1 as u32 + 1),
        },
        direct: d.props.contains(&1),
        calibration: None,
    }
}

/// What the hid module's probe would report for the Dell Canvas hidraw node
/// (figures from the shared collection's `index.json`: X/Y 0..32767 over
/// 596.7 × 335.7 mm, 10 contacts per report).
fn dell_hidraw_info(node: &Path) -> DeviceInfo {
    let axis = |mm: f64| AxisRange {
        min: 0.0,
        max: 32767.0,
        resolution: 32767.0 / mm,
    };
    DeviceInfo {
        identity: DeviceIdentity {
            kind: DeviceKind::Hidraw,
            node: node.to_path_buf(),
            name: "Advanced Silicon S.A. CoolTouch® System".into(),
            bus: 3,
            vendor: 0x2575,
            product: 0x0204,
            serial: None,
        },
        id_path: None,
        stable_id: String::new(),
        surface: SurfaceInfo {
            name: "Advanced Silicon S.A. CoolTouch® System".into(),
            x: axis(596.7),
            y: axis(335.7),
            max_contacts: 10,
        },
        direct: true,
        calibration: None,
    }
}

#[derive(Clone)]
enum Outcome {
    Ok(Box<DeviceInfo>),
    Denied,
}

/// Answers from a table, and remembers which nodes it was asked about.
#[derive(Default)]
struct FakeProber {
    answers: HashMap<PathBuf, Outcome>,
    asked: RefCell<Vec<PathBuf>>,
}

impl FakeProber {
    fn ok(&mut self, info: DeviceInfo) {
        self.answers
            .insert(info.identity.node.clone(), Outcome::Ok(Box::new(info)));
    }
    fn denied(&mut self, node: &Path) {
        self.answers.insert(node.to_path_buf(), Outcome::Denied);
    }
}

impl Prober for FakeProber {
    fn probe(&self, _kind: DeviceKind, node: &Path) -> Result<DeviceInfo, Error> {
        self.asked.borrow_mut().push(node.to_path_buf());
        match self.answers.get(node) {
            Some(Outcome::Ok(info)) => Ok((**info).clone()),
            Some(Outcome::Denied) => Err(Error::PermissionDenied {
                node: node.to_path_buf(),
                source: std::io::Error::from_raw_os_error(nix::libc::EACCES),
            }),
            None => Err(Error::NotTouch {
                node: node.to_path_buf(),
                reason: "not in the fake table".into(),
            }),
        }
    }
}

/// A fake root directory.
struct Tree {
    tmp: tempfile::TempDir,
}

impl Tree {
    fn new(with_udev: bool) -> Tree {
        let t = Tree {
            tmp: tempfile::tempdir().unwrap(),
        };
        for d in ["dev/input", "sys/class/input", "sys/class/hidraw"] {
            std::fs::create_dir_all(t.root().join(d)).unwrap();
        }
        if with_udev {
            std::fs::create_dir_all(t.root().join("run/udev/data")).unwrap();
        }
        t
    }

    fn root(&self) -> &Path {
        self.tmp.path()
    }

    fn write(&self, path: &Path, contents: impl AsRef<[u8]>) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, contents).unwrap();
    }

    fn link(&self, target: &Path, link: &Path) {
        std::fs::create_dir_all(link.parent().unwrap()).unwrap();
        std::os::unix::fs::symlink(target, link).unwrap();
    }

    /// A HID device directory under a USB port, with its uevent and descriptor.
    fn hid_device(&self, port: &str, d: &Desc, seq: u32, rdesc: &[u8]) -> PathBuf {
        let dir = self.root().join(format!(
            "sys/devices/pci0000:00/0000:00:14.0/usb1/{port}/{port}:1.0/{:04X}:{:04X}:{:04X}.{seq:04X}",
            d.bus, d.vendor, d.product
        ));
        self.write(
            &dir.join("uevent"),
            format!(
                "DRIVER=hid-multitouch\nHID_ID={:04X}:{:08X}:{:08X}\nHID_NAME={}\nHID_PHYS=usb-0000:00:14.0-{port}/input0\nHID_UNIQ=\nMODALIAS=hid:b{:04X}g0004v{:08X}p{:08X}\n",
                d.bus, d.vendor, d.product, d.name, d.bus, d.vendor, d.product
            ),
        );
        self.write(&dir.join("report_descriptor"), rdesc);
        dir
    }

    /// `inputN/eventM` under `parent`, its class link and its node.
    fn add_evdev(&self, parent: &Path, input_n: u32, event_n: u32, d: &Desc) -> PathBuf {
        let input = parent.join(format!("input/input{input_n}"));
        self.write(&input.join("name"), format!("{}\n", d.name));
        self.write(&input.join("uniq"), "\n");
        self.write(
            &input.join("properties"),
            format!("{}\n", Bitmap::from_bits(&d.props)),
        );
        self.write(&input.join("id/bustype"), format!("{:04x}\n", d.bus));
        self.write(&input.join("id/vendor"), format!("{:04x}\n", d.vendor));
        self.write(&input.join("id/product"), format!("{:04x}\n", d.product));
        self.write(
            &input.join("capabilities/abs"),
            format!("{}\n", Bitmap::from_bits(&d.abs)),
        );
        self.link(parent, &input.join("device"));
        let event = input.join(format!("event{event_n}"));
        self.write(
            &event.join("dev"),
            format!("{EVDEV_MAJOR}:{}\n", 64 + event_n),
        );
        self.link(&input, &event.join("device"));
        self.link(
            &event,
            &self.root().join(format!("sys/class/input/event{event_n}")),
        );
        let node = self.root().join(format!("dev/input/event{event_n}"));
        self.write(&node, "");
        node
    }

    /// `hidraw/hidrawN` under the HID device `parent`, its class link and its node.
    fn add_hidraw(&self, parent: &Path, n: u32) -> PathBuf {
        let dir = parent.join(format!("hidraw/hidraw{n}"));
        self.write(&dir.join("dev"), format!("{HIDRAW_MAJOR}:{n}\n"));
        self.link(parent, &dir.join("device"));
        self.link(
            &dir,
            &self.root().join(format!("sys/class/hidraw/hidraw{n}")),
        );
        let node = self.root().join(format!("dev/hidraw{n}"));
        self.write(&node, "");
        node
    }

    /// Removes an evdev node and its class link (the device was unplugged).
    fn remove_evdev(&self, event_n: u32) {
        std::fs::remove_file(self.root().join(format!("dev/input/event{event_n}"))).unwrap();
        std::fs::remove_file(self.root().join(format!("sys/class/input/event{event_n}"))).unwrap();
    }

    fn udev_record(&self, major: u32, minor: u32, props: &[(&str, &str)]) {
        let mut text = String::from("I:1234567\n");
        for (k, v) in props {
            text.push_str(&format!("E:{k}={v}\n"));
        }
        text.push_str("G:seat\n");
        self.write(
            &self.root().join(format!("run/udev/data/c{major}:{minor}")),
            text,
        );
    }
}

/// The nodes of the standard table.
struct Nodes {
    keyboard: PathBuf,
    dell_evdev: PathBuf,
    egalax: PathBuf,
    ite_evdev: PathBuf,
    dell_hidraw: PathBuf,
    ite_hidraw: PathBuf,
    keyboard_hidraw: PathBuf,
}

/// A table with: a PS/2 keyboard (event3), the Dell Canvas as evdev (event5) and
/// hidraw (hidraw0) off one HID device, the eGalax single-touch (event7), the ITE
/// touchpad as evdev (event14) and hidraw (hidraw1, probing denied), a USB keyboard's
/// hidraw (hidraw2), and a mouse node. udev has processed everything but hidraw1.
fn standard_tree(with_udev: bool) -> (Tree, FakeProber, Nodes) {
    let t = Tree::new(with_udev);
    let mut p = FakeProber::default();
    let rdesc = |name: &str| std::fs::read(fixture(&format!("sysfs/{name}"))).unwrap();

    let kbd_parent = t.root().join("sys/devices/platform/i8042/serio0");
    let keyboard = t.add_evdev(&kbd_parent, 3, 3, &keyboard_desc());

    let dell = dell_desc();
    let dell_hid = t.hid_device("1-1", &dell, 1, &rdesc("advanced_silicon_2575_0204.rdesc"));
    let dell_evdev = t.add_evdev(&dell_hid, 12, 5, &dell);
    let dell_hidraw = t.add_hidraw(&dell_hid, 0);
    p.ok(evdev_info(&dell_evdev, &dell));
    p.ok(dell_hidraw_info(&dell_hidraw));

    let eg = egalax_desc();
    let eg_hid = t.hid_device("1-3", &eg, 3, KEYBOARD_RDESC);
    let egalax = t.add_evdev(&eg_hid, 13, 7, &eg);

    let ite = ite_desc();
    let ite_hid = t.hid_device("1-2", &ite, 2, &rdesc("ite_06cb_2968.rdesc"));
    let ite_evdev = t.add_evdev(&ite_hid, 20, 14, &ite);
    let ite_hidraw = t.add_hidraw(&ite_hid, 1);
    p.ok(evdev_info(&ite_evdev, &ite));
    p.denied(&ite_hidraw);

    let usb_kbd = Desc {
        name: "Logitech USB Keyboard".into(),
        bus: 3,
        vendor: 0x046d,
        product: 0xc31c,
        ..Desc::default()
    };
    let usb_kbd_hid = t.hid_device("1-4", &usb_kbd, 4, KEYBOARD_RDESC);
    let keyboard_hidraw = t.add_hidraw(&usb_kbd_hid, 2);

    t.write(&t.root().join("dev/input/mouse0"), "");

    if with_udev {
        let calib = ("LIBINPUT_CALIBRATION_MATRIX", "0 -1 1 1 0 0");
        t.udev_record(EVDEV_MAJOR, 67, &[("ID_INPUT_KEYBOARD", "1")]);
        t.udev_record(
            EVDEV_MAJOR,
            69,
            &[
                ("ID_INPUT_TOUCHSCREEN", "1"),
                ("ID_PATH", DELL_ID_PATH),
                calib,
            ],
        );
        t.udev_record(EVDEV_MAJOR, 71, &[("ID_INPUT_TOUCHSCREEN", "1")]);
        t.udev_record(
            EVDEV_MAJOR,
            78,
            &[("ID_INPUT_TOUCHPAD", "1"), ("ID_PATH", ITE_ID_PATH)],
        );
        t.udev_record(HIDRAW_MAJOR, 0, &[("ID_PATH", DELL_ID_PATH)]);
        t.udev_record(
            HIDRAW_MAJOR,
            2,
            &[("ID_PATH", "pci-0000:00:14.0-usb-0:4:1.0")],
        );
        // hidraw1 (ITE): no record yet.
    }
    let nodes = Nodes {
        keyboard,
        dell_evdev,
        egalax,
        ite_evdev,
        dell_hidraw,
        ite_hidraw,
        keyboard_hidraw,
    };
    (t, p, nodes)
}

fn nodes_of(found: &[Found]) -> Vec<PathBuf> {
    found.iter().map(|f| f.info.identity.node.clone()).collect()
}

#[test]
fn fixture_descriptions_parse_as_expected() {
    let dell = dell_desc();
    assert_eq!((dell.vendor, dell.product), (0x2575, 0x0204));
    assert_eq!(dell.props, vec![1]);
    assert_eq!(dell.abs, vec![0, 1, 0x2f, 0x35, 0x36, 0x39]);
    assert_eq!(dell.absinfo[&0x35], (0.0, 32767.0, 55.0));
    let ite = ite_desc();
    assert_eq!((ite.vendor, ite.product), (0x06cb, 0x2968));
    assert_eq!(ite.abs, vec![0, 1, 47, 53, 54, 55, 57]);
    assert_eq!(ite.props, vec![0, 2]);
    assert_eq!(ite.absinfo[&53], (0.0, 1051.0, 12.0));
    let eg = egalax_desc();
    assert_eq!(eg.abs, vec![0, 1, 2, 3]);
    assert!(eg.props.is_empty());
}

#[test]
fn prefilter_classifies_real_devices_from_sysfs_facts() {
    let (t, _p, n) = standard_tree(true);
    let scanned = scan(t.root());
    assert_eq!(
        scanned.iter().map(|s| s.node.clone()).collect::<Vec<_>>(),
        vec![
            n.keyboard.clone(),
            n.dell_evdev.clone(),
            n.egalax.clone(),
            n.ite_evdev.clone(),
            n.dell_hidraw.clone(),
            n.ite_hidraw.clone(),
            n.keyboard_hidraw.clone()
        ]
    );
    let class: HashMap<PathBuf, TouchClass> = scanned
        .iter()
        .map(|s| (s.node.clone(), s.facts.as_ref().unwrap().touch))
        .collect();
    assert_eq!(class[&n.dell_evdev], TouchClass::Screen);
    assert_eq!(class[&n.dell_hidraw], TouchClass::Screen);
    assert_eq!(class[&n.ite_evdev], TouchClass::Pad);
    assert_eq!(class[&n.ite_hidraw], TouchClass::Pad);
    assert!(matches!(class[&n.egalax], TouchClass::NotTouch(r) if r.contains("ABS_MT_POSITION")));
    assert!(!class[&n.keyboard].is_touch());
    assert!(!class[&n.keyboard_hidraw].is_touch());

    let dell = scanned[1].facts.as_ref().unwrap();
    assert_eq!(
        dell.identity.name,
        "Advanced Silicon S.A. CoolTouch® System"
    );
    assert_eq!(
        (
            dell.identity.bus,
            dell.identity.vendor,
            dell.identity.product
        ),
        (3, 0x2575, 0x0204)
    );
    assert_eq!(dell.devnum, Some((13, 69)));
    assert_eq!(dell.identity.serial, None);
    // Both interfaces of the Dell Canvas hang off the same HID device.
    let hidraw = scanned[4].facts.as_ref().unwrap();
    assert!(dell.parent.is_some());
    assert_eq!(dell.parent, hidraw.parent);
    assert_eq!(hidraw.devnum, Some((244, 0)));
    assert_ne!(dell.parent, scanned[3].facts.as_ref().unwrap().parent);
}

#[test]
fn vendor_page_digitizer_is_accepted() {
    let wacom = std::fs::read(fixture("sysfs/wacom-intuos-pro-m-pth660.touch.rdesc")).unwrap();
    assert_eq!(classify_report_descriptor(&wacom), Ok(TouchClass::Pad));
}

#[test]
fn discovery_lists_touch_devices_with_udev_facts() {
    let (t, p, n) = standard_tree(true);
    let found = discover(t.root(), &p);
    assert_eq!(
        nodes_of(&found),
        vec![
            n.dell_evdev.clone(),
            n.ite_evdev.clone(),
            n.dell_hidraw.clone(),
            n.ite_hidraw.clone()
        ]
    );
    // Non-touch nodes are never opened: the pre-filter works from sysfs alone.
    let asked = p.asked.borrow();
    for never in [&n.keyboard, &n.egalax, &n.keyboard_hidraw] {
        assert!(!asked.contains(never), "{} was probed", never.display());
    }

    let dell = &found[0];
    assert!(dell.usable() && dell.processed);
    assert_eq!(dell.info.identity.kind, DeviceKind::Evdev);
    assert_eq!(dell.info.id_path.as_deref(), Some(DELL_ID_PATH));
    assert_eq!(dell.info.stable_id, DELL_ID_PATH);
    assert_eq!(dell.info.calibration, Some([0.0, -1.0, 1.0, 1.0, 0.0, 0.0]));
    assert!(dell.info.direct);
    assert_eq!(dell.info.surface.max_contacts, 5);
    assert!((dell.info.surface.x.max - 32767.0).abs() < EPS);
    assert!(dell.calibration_error.is_none());

    let ite = &found[1];
    assert!(!ite.info.direct);
    assert_eq!(ite.info.stable_id, ITE_ID_PATH);
    assert_eq!(ite.info.calibration, None);

    let dell_raw = &found[2];
    assert_eq!(dell_raw.info.stable_id, DELL_ID_PATH);
    assert_eq!(dell_raw.parent, dell.parent);
    // udev puts the matrix on the input device; the hidraw sibling inherits it.
    assert_eq!(dell_raw.info.calibration, dell.info.calibration);

    // Probing hidraw1 was refused: listed with the error and what sysfs knows.
    let ite_raw = &found[3];
    assert!(!ite_raw.usable());
    assert!(!ite_raw.processed, "no udev record for c244:1");
    let err = ite_raw.probe_error.as_deref().unwrap();
    assert!(err.contains("permission denied"), "{err}");
    assert_eq!(
        ite_raw.info.identity.name,
        "ITE Tech. Inc. ITE Device(8595) Touchpad"
    );
    assert_eq!(
        (ite_raw.info.identity.vendor, ite_raw.info.identity.product),
        (0x06cb, 0x2968)
    );
    assert_eq!(ite_raw.info.stable_id, "06cb:2968");
}

#[test]
fn auto_picks_the_dell_canvas_through_evdev() {
    let (t, p, n) = standard_tree(true);
    let found = discover(t.root(), &p);
    let pick =
        |sel: &Selector, pref| select(&found, sel, pref).map(|f| f.info.identity.node.clone());
    // The hidraw interface declares more contacts (10 vs 5) but is the same device.
    assert_eq!(
        pick(&Selector::Auto, InterfacePreference::Any),
        Ok(n.dell_evdev.clone())
    );
    assert_eq!(
        pick(&Selector::Auto, InterfacePreference::Evdev),
        Ok(n.dell_evdev.clone())
    );
    assert_eq!(
        pick(&Selector::Auto, InterfacePreference::Hidraw),
        Ok(n.dell_hidraw.clone())
    );
}

#[test]
fn selection_by_name_ids_path_and_stable_id() {
    let (t, p, n) = standard_tree(true);
    let found = discover(t.root(), &p);
    let any = InterfacePreference::Any;
    let pick =
        |sel: Selector, pref| select(&found, &sel, pref).map(|f| f.info.identity.node.clone());

    assert_eq!(
        pick(Selector::Name("cooltouch".into()), any),
        Ok(n.dell_evdev.clone())
    );
    assert_eq!(
        pick(Selector::Name("*TOUCHPAD".into()), any),
        Ok(n.ite_evdev.clone())
    );
    assert_eq!(
        pick(Selector::VendorProduct("2575:0204".into()), any),
        Ok(n.dell_evdev.clone())
    );
    assert_eq!(
        pick(
            Selector::VendorProduct("2575:0204".into()),
            InterfacePreference::Hidraw
        ),
        Ok(n.dell_hidraw.clone())
    );
    assert_eq!(
        pick(Selector::Path(n.dell_hidraw.clone()), any),
        Ok(n.dell_hidraw.clone())
    );
    // A by-path link names the node it points to; Path ignores the preference.
    let link = t
        .root()
        .join("dev/input/by-path/pci-0000:00:14.0-usb-0:2:1.0-event-mouse");
    t.link(Path::new("../event14"), &link);
    assert_eq!(
        pick(Selector::Path(link), InterfacePreference::Hidraw),
        Ok(n.ite_evdev.clone())
    );
    assert_eq!(
        pick(Selector::Id(ITE_ID_PATH.into()), any),
        Ok(n.ite_evdev.clone())
    );
    assert_eq!(
        pick(Selector::Id(DELL_ID_PATH.into()), any),
        Ok(n.dell_evdev.clone())
    );
}

#[test]
fn selection_errors_list_the_candidates() {
    let (t, p, n) = standard_tree(true);
    let found = discover(t.root(), &p);

    let e = select(
        &found,
        &Selector::Name("egalax".into()),
        InterfacePreference::Any,
    )
    .unwrap_err();
    assert!(matches!(e, SelectError::NoMatch { .. }));
    let msg = e.to_string();
    assert!(msg.contains("name \"egalax\""), "{msg}");
    for node in [&n.dell_evdev, &n.ite_evdev, &n.dell_hidraw, &n.ite_hidraw] {
        assert!(msg.contains(&node.display().to_string()), "{msg}");
    }
    assert!(
        msg.contains("2575:0204") && msg.contains("CoolTouch"),
        "{msg}"
    );
    assert!(msg.contains("permission denied"), "{msg}");

    // The ITE hidraw matches but cannot be opened.
    let e = select(
        &found,
        &Selector::VendorProduct("06CB:2968".into()),
        InterfacePreference::Hidraw,
    )
    .unwrap_err();
    assert!(matches!(e, SelectError::Unusable { .. }), "{e}");
    let msg = e.to_string();
    assert!(msg.contains(&n.ite_hidraw.display().to_string()) && msg.contains("permission denied"));

    let e = select(
        &found,
        &Selector::VendorProduct("canvas".into()),
        InterfacePreference::Any,
    )
    .unwrap_err();
    assert!(matches!(e, SelectError::BadSelector { .. }));
    assert!(e.to_string().contains("2575:0204"), "{e}");

    assert_eq!(
        select(&[], &Selector::Auto, InterfacePreference::Any),
        Err(SelectError::NoDevices)
    );
    // Only unusable devices: Auto says why.
    let only_denied: Vec<Found> = found.iter().filter(|f| !f.usable()).cloned().collect();
    let e = select(&only_denied, &Selector::Auto, InterfacePreference::Any).unwrap_err();
    assert!(matches!(e, SelectError::Unusable { .. }));
}

#[test]
fn device_is_recognised_after_coming_back_as_another_node() {
    let (t, mut p, n) = standard_tree(true);
    let before = discover(t.root(), &p);
    let chosen = select(&before, &Selector::Auto, InterfacePreference::Any)
        .unwrap()
        .info
        .clone();
    assert_eq!(chosen.identity.node, n.dell_evdev);

    // Unplug: event5 goes; plug back in: it comes back as event9 (minor 73) under a
    // new input number, with the same ID_PATH.
    t.remove_evdev(5);
    let dell = dell_desc();
    let hid = std::fs::canonicalize(t.root().join("sys/class/hidraw/hidraw0/device")).unwrap();
    let node = t.add_evdev(&hid, 21, 9, &dell);
    p.ok(evdev_info(&node, &dell));
    t.udev_record(
        EVDEV_MAJOR,
        73,
        &[
            ("ID_PATH", DELL_ID_PATH),
            ("LIBINPUT_CALIBRATION_MATRIX", "0 -1 1 1 0 0"),
        ],
    );
    let after = discover(t.root(), &p);
    let back = after
        .iter()
        .find(|f| f.info.identity.kind == DeviceKind::Evdev && f.info.identity.vendor == 0x2575)
        .unwrap();
    assert_eq!(back.info.identity.node, t.root().join("dev/input/event9"));
    assert!(recognise(&chosen, &back.info));
    assert!(matches(&back.info, &sticky_selector(&chosen)));
    // The hotplug path examines just the new node, with the same result.
    let one = discover::discover_node(t.root(), &back.info.identity.node, &p).unwrap();
    assert_eq!(&one, back);
    assert!(discover::discover_node(t.root(), &n.keyboard, &p).is_none());
    assert!(discover::discover_node(t.root(), &t.root().join("dev/input/mouse0"), &p).is_none());
    assert!(matches(&back.info, &Selector::Auto));
    assert!(matches(&back.info, &Selector::Name("CoolTouch".into())));
    assert!(matches(
        &back.info,
        &Selector::VendorProduct("2575:0204".into())
    ));
    // Never by node number.
    assert!(!matches(
        &back.info,
        &Selector::Path(chosen.identity.node.clone())
    ));
    // The same physical device through hidraw is not "the same interface".
    let raw = after
        .iter()
        .find(|f| f.info.identity.kind == DeviceKind::Hidraw)
        .unwrap();
    assert!(!recognise(&chosen, &raw.info));
    assert!(discover::same_physical_device(back, raw));
    // And the other devices are not mistaken for it.
    let ite = after
        .iter()
        .find(|f| f.info.identity.vendor == 0x06cb)
        .unwrap();
    assert!(!matches(&ite.info, &sticky_selector(&chosen)));
}

#[test]
fn without_udev_everything_is_processed_and_ids_come_from_usb_ids() {
    let (t, p, n) = standard_tree(false);
    let found = discover(t.root(), &p);
    assert_eq!(found.len(), 4);
    assert!(found.iter().all(|f| f.processed));
    assert!(found
        .iter()
        .all(|f| f.info.id_path.is_none() && f.info.calibration.is_none()));
    assert_eq!(found[0].info.stable_id, "2575:0204");
    assert_eq!(found[2].info.stable_id, "2575:0204");
    // Still one physical device, still evdev.
    assert_eq!(
        select(&found, &Selector::Auto, InterfacePreference::Any).map(|f| f
            .info
            .identity
            .node
            .clone()),
        Ok(n.dell_evdev)
    );
}

#[test]
fn bad_udev_calibration_is_reported_and_ignored() {
    let (t, p, _n) = standard_tree(true);
    t.udev_record(
        EVDEV_MAJOR,
        69,
        &[
            ("ID_PATH", DELL_ID_PATH),
            ("LIBINPUT_CALIBRATION_MATRIX", "1 0 0 0 1"),
        ],
    );
    let found = discover(t.root(), &p);
    assert_eq!(found[0].info.calibration, None);
    let e = found[0].calibration_error.as_ref().unwrap();
    assert!(e.to_string().contains("6 numbers"), "{e}");
}

#[test]
fn sysfs_errors_name_the_file_and_never_panic() {
    let (t, p, n) = standard_tree(true);
    let abs = t
        .root()
        .join("sys/class/input/event14/device/capabilities/abs");
    std::fs::write(&abs, "zz not hex\n").unwrap();
    let desc = t.root().join("sys/class/hidraw/hidraw0/device/uevent");
    std::fs::write(&desc, "HID_NAME=x\n").unwrap();
    std::fs::remove_file(t.root().join("sys/class/input/event3/device/name")).unwrap();
    let scanned = scan(t.root());
    let err = |node: &Path| {
        scanned
            .iter()
            .find(|s| s.node == node)
            .unwrap()
            .facts
            .as_ref()
            .unwrap_err()
            .to_string()
    };
    let e = err(&n.ite_evdev);
    assert!(
        e.contains("capabilities/abs") && e.contains("zz not hex"),
        "{e}"
    );
    let e = err(&n.dell_hidraw);
    assert!(e.contains("uevent") && e.contains("HID_ID"), "{e}");
    let e = err(&n.keyboard);
    assert!(e.contains("name") && e.contains("cannot read"), "{e}");
    // Discovery falls back to the prober for those: it knows the touch devices and
    // refuses the keyboard.
    let found = discover(t.root(), &p);
    let nodes = nodes_of(&found);
    assert!(nodes.contains(&n.ite_evdev) && nodes.contains(&n.dell_hidraw));
    assert!(!nodes.contains(&n.keyboard));
    // A truncated report descriptor is an error naming the file, not a panic.
    let rd = t
        .root()
        .join("sys/class/hidraw/hidraw1/device/report_descriptor");
    let bytes = std::fs::read(&rd).unwrap();
    std::fs::write(&rd, &bytes[..7]).unwrap();
    let scanned = scan(t.root());
    let s = scanned.iter().find(|s| s.node == n.ite_hidraw).unwrap();
    if let Err(e) = &s.facts {
        assert!(e.to_string().contains("report_descriptor"), "{e}");
    }
}

#[test]
fn empty_or_missing_trees_find_nothing() {
    let t = tempfile::tempdir().unwrap();
    assert!(scan(t.path()).is_empty());
    assert!(discover(t.path(), &FakeProber::default()).is_empty());
}

#[test]
fn selector_and_preference_deserialise_from_ron() {
    let s: Selector = ron::from_str("Name(\"canvas\")").unwrap();
    assert_eq!(s, Selector::Name("canvas".into()));
    let s: Selector = ron::from_str("Auto").unwrap();
    assert_eq!(s, Selector::Auto);
    let s: Selector = ron::from_str("VendorProduct(\"2575:0204\")").unwrap();
    assert_eq!(s.to_string(), "vendor:product 2575:0204");
    let p: InterfacePreference = ron::from_str("hidraw").unwrap();
    assert_eq!(p, InterfacePreference::Hidraw);
}
