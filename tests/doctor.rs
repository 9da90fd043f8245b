//! `crowdtouch doctor` on a kiosk tree of its own (`--root`: `dev/`, `sys/`,
//! `etc/passwd` and `etc/group`, the shipped unit with its generated network
//! drop-in, the udev rule): a healthy table passes with exit status 0, and each
//! fault the system test plants is found, named and given its fix — a device node
//! the group cannot read, the udev rule missing, a TUIO target that cannot be
//! reached, a socket path in a missing directory. `check-config` warns when the
//! installed unit would block an output.

mod common;

use serde_json::Value;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_crowdtouch");
const REPO: &str = env!("CARGO_MANIFEST_DIR");
/// The service user's uid in the tree: nobody real.
const SERVICE_UID: u32 = 64_123;

/// A kiosk's system tree and its config.
struct Kiosk {
    tmp: tempfile::TempDir,
    hidraw: PathBuf,
    config: PathBuf,
}

impl Kiosk {
    fn root(&self) -> &Path {
        self.tmp.path()
    }

    fn write(&self, rel: &str, text: impl AsRef<[u8]>) -> PathBuf {
        let p = self.root().join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    }

    /// The tree: the `crowdtouch` user whose group is this process's group (so the
    /// files made here belong to it), the shipped unit, sysusers file and udev
    /// rule, one hid-multitouch digitizer (`dev/hidraw0`, the Dell Canvas'
    /// descriptor) with the rule applied (group crowdtouch, 0660), and a config
    /// with `inputs` and `outputs` (RON) whose socket is in `run/`.
    fn new(inputs: &str, outputs: &str) -> Kiosk {
        let tmp = tempfile::tempdir().unwrap();
        let gid = nix::unistd::getegid().as_raw();
        let mut k = Kiosk {
            tmp,
            hidraw: PathBuf::new(),
            config: PathBuf::new(),
        };
        k.write(
            "etc/passwd",
            format!("root:x:0:0::/root:/bin/sh\ncrowdtouch:x:{SERVICE_UID}:{gid}:crowdtouch:/nonexistent:/usr/sbin/nologin\n"),
        );
        k.write("etc/group", format!("crowdtouch:x:{gid}:\n"));
        k.write(
            "lib/systemd/system/crowdtouch.service",
            std::fs::read(Path::new(REPO).join("systemd/crowdtouch.service")).unwrap(),
        );
        k.write(
            "lib/udev/rules.d/70-crowdtouch.rules",
            std::fs::read(Path::new(REPO).join("udev/70-crowdtouch.rules")).unwrap(),
        );
        // The digitizer: a HID device under a USB port, its hidraw node.
        let hid = "sys/devices/pci0000:00/0000:00:14.0/usb1/1-1/1-1:1.0/0003:2575:0204.0001";
        k.write(
            &format!("{hid}/uevent"),
            "DRIVER=hid-multitouch\nHID_ID=0003:00002575:00000204\nHID_NAME=Advanced Silicon CoolTouch\nHID_PHYS=usb-0000:00:14.0-1-1/input0\nHID_UNIQ=\n",
        );
        k.write(
            &format!("{hid}/report_descriptor"),
            std::fs::read(
                Path::new(REPO).join("tests/fixtures/sysfs/advanced_silicon_2575_0204.rdesc"),
            )
            .unwrap(),
        );
        let dev = k.root().join(hid);
        k.write(&format!("{hid}/hidraw/hidraw0/dev"), "244:0\n");
        std::os::unix::fs::symlink(&dev, dev.join("hidraw/hidraw0/device")).unwrap();
        std::fs::create_dir_all(k.root().join("sys/class/hidraw")).unwrap();
        std::fs::create_dir_all(k.root().join("sys/class/input")).unwrap();
        std::fs::create_dir_all(k.root().join("dev/input")).unwrap();
        std::os::unix::fs::symlink(
            dev.join("hidraw/hidraw0"),
            k.root().join("sys/class/hidraw/hidraw0"),
        )
        .unwrap();
        k.hidraw = k.write("dev/hidraw0", "");
        k.chmod_node(0o660);
        // The socket's directory: the service's group may create in it.
        std::fs::create_dir_all(k.root().join("run")).unwrap();
        std::fs::set_permissions(k.root().join("run"), std::fs::Permissions::from_mode(0o770))
            .unwrap();
        std::fs::create_dir_all(k.root().join("etc/crowdtouch")).unwrap();
        k.config = k.root().join("etc/crowdtouch/crowdtouch.ron");
        k.set_config(inputs, outputs, &k.root().join("run/ct.sock"));
        k
    }

    fn chmod_node(&self, mode: u32) {
        std::fs::set_permissions(&self.hidraw, std::fs::Permissions::from_mode(mode)).unwrap();
    }

    /// Writes the config: the embedded default with these inputs, outputs and
    /// socket path, no real-time scheduling.
    fn set_config(&self, inputs: &str, outputs: &str, socket: &Path) {
        let text = crowdtouch::config::DEFAULT_CONFIG_RON
            .replacen("priority: Some(20)", "priority: None", 1)
            .replacen("lock_memory: true", "lock_memory: false", 1)
            .replacen("path: None", &format!("path: Some({:?})", socket), 1);
        let start = text.find("inputs: [").expect("the default has inputs");
        let end = start + text[start..].find("\n    ],").expect("its end") + "\n    ],".len();
        let text = format!(
            "{}inputs: {inputs},\n    outputs: {outputs},{}",
            &text[..start],
            &text[end..]
        );
        std::fs::write(&self.config, text).unwrap();
        let c = crowdtouch::config::Config::load(&self.config)
            .unwrap_or_else(|e| panic!("the test's config: {e}"));
        assert_eq!(c.outputs.len(), outputs.matches('(').count());
    }

    /// What systemd's generator writes at daemon-reload.
    fn daemon_reload(&self) {
        let out = Command::new(BIN)
            .args(["unit-network", "--config"])
            .arg(&self.config)
            .arg("--generator")
            .arg(self.root().join("run/systemd/generator"))
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
    }

    fn doctor(&self) -> (i32, Value) {
        let out = Command::new(BIN)
            .args(["doctor", "--json", "--root"])
            .arg(self.root())
            .arg("--config")
            .arg(&self.config)
            .output()
            .unwrap();
        let v: Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stdout)));
        let code = out.status.code().unwrap();
        assert_eq!(v["ok"], code == 0, "exit {code} with {v}");
        (code, v)
    }

    /// The daemon on the kiosk's config (its replay input, its socket).
    fn run_daemon(&self, socket: &Path) -> Child {
        let child = Command::new(BIN)
            .args(["run", "--config"])
            .arg(&self.config)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let end = Instant::now() + Duration::from_secs(20);
        while std::os::unix::net::UnixStream::connect(socket).is_err() {
            assert!(Instant::now() < end, "the daemon did not start");
            std::thread::sleep(Duration::from_millis(50));
        }
        child
    }
}

/// The check named `name` of a doctor report.
fn check<'a>(v: &'a Value, name: &str) -> &'a Value {
    v["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == name)
        .unwrap_or_else(|| panic!("no check {name} in {v:#}"))
}

fn assert_fails(v: &Value, name: &str, detail: &str, fix: &str) {
    let c = check(v, name);
    assert_eq!(c["ok"], false, "{c:#}");
    let (d, f) = (c["detail"].as_str().unwrap(), c["fix"].as_str().unwrap());
    assert!(d.contains(detail), "{name} detail: {d}");
    assert!(f.contains(fix), "{name} fix: {f}");
}

fn assert_passes(v: &Value, name: &str) {
    let c = check(v, name);
    assert_eq!(c["ok"], true, "{c:#}");
    assert!(c["fix"].is_null());
}

const DEVICE: &str = "[Device(select: Auto, interface: Hidraw)]";
const REPLAY: &str = concat!(
    "[Replay(files: [\"",
    env!("CARGO_MANIFEST_DIR"),
    "/config/recordings/01-point-drag.jsonl\"], looped: true)]"
);

/// A table with everything in place: the doctor says nothing is wrong, exit 0.
#[test]
fn a_healthy_table_passes() {
    let addr = common::free_addr();
    let k = Kiosk::new(
        REPLAY,
        &format!("[Tuio(target: \"127.0.0.1:3333\"), WebSocket(listen: \"{addr}\")]"),
    );
    k.daemon_reload();
    let socket = k.root().join("run/ct.sock");
    let mut daemon = k.run_daemon(&socket);
    let (code, v) = k.doctor();
    let _ = daemon.kill();
    let _ = daemon.wait();
    assert_eq!(code, 0, "{v:#}");
    for name in [
        "config",
        "unit",
        "service_user",
        "device",
        "device_access",
        "udev_rule",
        "realtime",
        "socket",
        "output outputs[0].target",
        "output outputs[1].listen",
        "daemon",
    ] {
        assert_passes(&v, name);
    }
    assert!(check(&v, "output outputs[1].listen")["detail"]
        .as_str()
        .unwrap()
        .contains("running daemon"));
    assert!(check(&v, "daemon")["detail"]
        .as_str()
        .unwrap()
        .contains("touches"));
}

/// The device node the group cannot read, then the rule missing: each found with
/// its fix; the device found and selected is named either way.
#[test]
fn device_permissions_and_the_udev_rule_are_checked() {
    let k = Kiosk::new(DEVICE, "[]");
    k.daemon_reload();
    let (_, v) = k.doctor();
    assert_passes(&v, "device_access");
    assert_passes(&v, "udev_rule");
    assert!(check(&v, "device inputs[0]")["detail"]
        .as_str()
        .unwrap()
        .contains("hidraw0"));
    // Fault 1: the node is root-only (the rule not applied to it).
    k.chmod_node(0o600);
    let (code, v) = k.doctor();
    assert_eq!(code, 1);
    assert_fails(
        &v,
        "device_access",
        "may not read and write it",
        "udevadm trigger --subsystem-match=input --subsystem-match=hidraw",
    );
    // Fault 2: the rule is gone.
    k.chmod_node(0o660);
    std::fs::remove_file(k.root().join("lib/udev/rules.d/70-crowdtouch.rules")).unwrap();
    let (code, v) = k.doctor();
    assert_eq!(code, 1);
    assert_fails(
        &v,
        "udev_rule",
        "70-crowdtouch.rules is in none of",
        "70-crowdtouch.rules",
    );
    // The group is another one: installed rule, not applied.
    k.write(
        "lib/udev/rules.d/70-crowdtouch.rules",
        std::fs::read(Path::new(REPO).join("udev/70-crowdtouch.rules")).unwrap(),
    );
    let gid = nix::unistd::getegid().as_raw();
    k.write("etc/group", format!("crowdtouch:x:{}:\n", gid + 1));
    k.write(
        "etc/passwd",
        format!("crowdtouch:x:{SERVICE_UID}:{}::/:/bin/false\n", gid + 1),
    );
    let (_, v) = k.doctor();
    assert_fails(&v, "udev_rule", "not applied to", "udevadm trigger");
    assert_fails(&v, "device_access", "may not", "udevadm trigger");
}

/// A TUIO target that cannot be reached: a name that does not resolve, an address
/// the installed unit's drop-in (made for another config) does not let through.
#[test]
fn an_unreachable_tuio_target_is_named() {
    let k = Kiosk::new(REPLAY, "[Tuio(target: \"127.0.0.1:3333\")]");
    k.daemon_reload();
    let socket = k.root().join("run/ct.sock");
    k.set_config(REPLAY, "[Tuio(target: \"renderer.invalid:3333\")]", &socket);
    let (code, v) = k.doctor();
    assert_eq!(code, 1);
    assert_fails(
        &v,
        "output outputs[0].target",
        "does not resolve",
        "IP address",
    );
    k.set_config(REPLAY, "[Tuio(target: \"198.51.100.7:3333\")]", &socket);
    let (_, v) = k.doctor();
    assert_fails(
        &v,
        "output outputs[0].target",
        "IPAddressDeny",
        "daemon-reload",
    );
    // After the reload the generator lets it through.
    k.daemon_reload();
    let (_, v) = k.doctor();
    let c = check(&v, "output outputs[0].target");
    assert!(
        !c["detail"].as_str().unwrap().contains("IPAddressDeny"),
        "{c:#}"
    );
}

/// A socket path whose directory does not exist.
#[test]
fn a_socket_in_a_missing_directory_is_named() {
    let k = Kiosk::new(REPLAY, "[]");
    let missing = k.root().join("no/such/dir/ct.sock");
    k.set_config(REPLAY, "[]", &missing);
    let (code, v) = k.doctor();
    assert_eq!(code, 1);
    assert_fails(&v, "socket", "no/such/dir", "path: None");
    assert_fails(&v, "daemon", "no daemon answers", "systemctl start");
}

/// `check-config` warns, at the output's line, when the installed unit would block
/// it, and says how to bring the unit in line.
#[test]
fn check_config_warns_when_the_installed_unit_would_block_an_output() {
    let k = Kiosk::new(REPLAY, "[]");
    k.daemon_reload();
    let socket = k.root().join("run/ct.sock");
    k.set_config(REPLAY, "[Tuio(target: \"127.0.0.1:3333\")]", &socket);
    let check_config = || {
        Command::new(BIN)
            .arg("check-config")
            .arg(&k.config)
            .env("CROWDTOUCH_ROOT", k.root())
            .output()
            .unwrap()
    };
    let out = check_config();
    assert!(out.status.success(), "a warning, not an error: {out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("outputs[0].target") && err.contains("warning") && err.contains("AF_INET"),
        "{err}"
    );
    assert!(err.contains("daemon-reload"), "{err}");
    k.daemon_reload();
    let out = check_config();
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("would block"),
        "{out:?}"
    );
}

/// A table with no touch device: the doctor says so and names the clients its
/// touches come from, probes no node (the tree's digitizer is neither selected nor
/// required to have the udev rule applied), and with the daemon running every
/// check passes.
#[test]
fn a_table_with_no_touch_device_is_said_to_be_touched_by_its_clients() {
    let addr = common::free_addr();
    let k = Kiosk::new(
        "[]",
        &format!("[WebSocket(listen: \"{addr}\", privileged: true)]"),
    );
    k.daemon_reload();
    // The digitizer's node is root-only: a device config would fail on it.
    k.chmod_node(0o600);
    let socket = k.root().join("run/ct.sock");
    let mut daemon = k.run_daemon(&socket);
    let (code, v) = k.doctor();
    let _ = daemon.kill();
    let _ = daemon.wait();
    assert_eq!(code, 0, "{v:#}");
    for name in ["config", "device", "device_access", "udev_rule", "daemon"] {
        assert_passes(&v, name);
    }
    assert_eq!(
        check(&v, "device")["detail"],
        format!(
            "no touch device configured: touches come only from clients: the viewer page and \
             the WebSocket clients of http://{addr}/ (`touch` command), privileged clients of \
             the Unix socket (`touch` command: root, the daemon's user, socket.privileged)"
        )
    );
    assert!(check(&v, "udev_rule")["detail"]
        .as_str()
        .unwrap()
        .ends_with("not needed: the config reads no touch device"));
    assert!(
        !v["checks"]
            .as_array()
            .unwrap()
            .iter()
            .any(|c| c["name"].as_str().unwrap().starts_with("device inputs")),
        "{v:#}"
    );
}
