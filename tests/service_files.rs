//! The shipped data and service files agree with the code: the config parses, every
//! recording loads, the systemd unit, sysusers file and udev rule name the same group,
//! the socket path the unit implies is the one the daemon resolves.

use std::path::Path;
use std::process::Command;

fn read(p: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(p))
        .unwrap_or_else(|e| panic!("{p}: {e}"))
}

fn unit_values<'a>(unit: &'a str, key: &str) -> Vec<&'a str> {
    unit.lines()
        .filter_map(|l| l.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .map(str::trim)
        .collect()
}

#[test]
fn every_shipped_config_file_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let cfg = crowdtouch::config::Config::load(&dir.join("crowdtouch.ron"))
        .expect("config/crowdtouch.ron");
    let sources = crowdtouch::pipeline::sources_from_config(&cfg).expect("its recordings load");
    assert_eq!(sources.len(), 1);
    let mut n = 0;
    for e in std::fs::read_dir(dir.join("recordings")).unwrap() {
        let p = e.unwrap().path();
        let rec = crowdtouch::input::recording::read_recording(&p, Default::default())
            .expect("recording loads");
        assert!(!rec.frames.is_empty(), "{}", p.display());
        n += 1;
    }
    assert!(n >= 6, "at least six shipped recordings, found {n}");
    assert_eq!(
        crowdtouch::input::recording::RECORDINGS.len(),
        n,
        "every shipped recording is embedded"
    );
}

#[test]
fn unit_sysusers_and_udev_agree() {
    let unit = read("systemd/crowdtouch.service");
    let sysusers = read("systemd/crowdtouch.sysusers");
    let rules = read("udev/70-crowdtouch.rules");
    assert_eq!(unit_values(&unit, "Type"), vec!["notify"]);
    assert!(!unit_values(&unit, "WatchdogSec").is_empty());
    assert_eq!(unit_values(&unit, "DevicePolicy"), vec!["closed"]);
    let allow = unit_values(&unit, "DeviceAllow");
    assert!(allow.contains(&"char-input r") && allow.iter().any(|a| a.starts_with("char-hidraw")));
    let group = unit_values(&unit, "Group")[0];
    assert_eq!(unit_values(&unit, "User"), vec![group]);
    assert!(
        sysusers
            .lines()
            .any(|l| l.split_whitespace().take(2).eq(["g", group])),
        "sysusers creates group {group}"
    );
    assert!(
        sysusers
            .lines()
            .any(|l| l.split_whitespace().take(2).eq(["u", group])),
        "sysusers creates user {group}"
    );
    let rule_groups: Vec<&str> = rules
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .filter_map(|l| l.split("GROUP=\"").nth(1))
        .map(|r| r.split('"').next().unwrap())
        .collect();
    assert!(
        rule_groups.len() >= 2 && rule_groups.iter().all(|g| *g == group),
        "{rule_groups:?}"
    );
    // The unit's state directory holds the edit directory clients' edit.load and
    // edit.save use (`edit.dir`'s default: the first one's `tracks`).
    let state: Vec<&str> = unit_values(&unit, "StateDirectory")[0]
        .split_whitespace()
        .collect();
    assert_eq!(
        state,
        [
            "crowdtouch".to_string(),
            format!("crowdtouch/{}", crowdtouch::config::EDIT_DIR_NAME)
        ],
        "{state:?}"
    );
    // The unit's runtime directory is where the daemon puts its socket.
    let rundir = unit_values(&unit, "RuntimeDirectory")[0];
    let exec = unit_values(&unit, "ExecStart")[0];
    assert!(
        exec.contains(" run ") && exec.contains("--config /etc/crowdtouch/crowdtouch.ron"),
        "{exec}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["check-config", "config/crowdtouch.ron"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("RUNTIME_DIRECTORY", format!("/run/{rundir}"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("/run/{rundir}/crowdtouch.sock")),
        "{text}"
    );
}

/// The package's preinst creates the user and group from the same lines as the
/// sysusers file (before the udev rule naming the group is unpacked).
#[test]
fn preinst_creates_what_the_sysusers_file_says() {
    let lines = |text: &str| -> Vec<String> {
        text.lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(str::to_string)
            .collect()
    };
    let sysusers = lines(&read("systemd/crowdtouch.sysusers"));
    let preinst = read("packaging/debian/preinst");
    let here = preinst
        .split("<<'SYSUSERS'\n")
        .nth(1)
        .and_then(|r| r.split("\nSYSUSERS\n").next())
        .expect("a here-document SYSUSERS in preinst");
    assert_eq!(lines(here), sysusers);
}

/// udev rule lines are `KEY{attr}OP"value"` pairs separated by commas.
#[test]
fn udev_rule_syntax() {
    let rules = read("udev/70-crowdtouch.rules");
    for (i, line) in rules.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        for pair in l.split(", ") {
            let ok = ["==", "!=", "+=", "-=", ":=", "="].iter().any(|op| {
                pair.split_once(op).is_some_and(|(k, v)| {
                    !k.is_empty()
                        && k.chars().all(|c| {
                            c.is_ascii_uppercase() || "{}_".contains(c) || c.is_ascii_alphanumeric()
                        })
                        && v.starts_with('"')
                        && v.ends_with('"')
                })
            });
            assert!(ok, "line {}: bad pair {pair:?}", i + 1);
        }
    }
}

#[test]
fn systemd_analyze_verifies_the_unit_where_available() {
    let Ok(v) = Command::new("systemd-analyze").arg("--version").output() else {
        eprintln!("SKIP: systemd-analyze not installed");
        return;
    };
    assert!(v.status.success());
    let dir = tempfile::tempdir().unwrap();
    let unit = read("systemd/crowdtouch.service")
        .replace("/usr/bin/crowdtouch", env!("CARGO_BIN_EXE_crowdtouch"));
    let path = dir.path().join("crowdtouch.service");
    std::fs::write(&path, unit).unwrap();
    let out = Command::new("systemd-analyze")
        .arg("verify")
        // The man page is the package's: not installed where the tests run.
        .arg("--man=no")
        .arg(&path)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !err.contains("Unknown"), "{err}");
}

/// The installation config reads a device and otherwise matches the documented default.
#[test]
fn kiosk_config_differs_from_the_default_only_in_its_inputs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let mut kiosk =
        crowdtouch::config::Config::load(&dir.join("kiosk.ron")).expect("config/kiosk.ron");
    let default = crowdtouch::config::Config::load(&dir.join("crowdtouch.ron")).unwrap();
    assert!(matches!(
        kiosk.inputs.as_slice(),
        [crowdtouch::config::InputConfig::Device { .. }]
    ));
    kiosk.inputs = default.inputs.clone();
    assert_eq!(
        kiosk, default,
        "config/kiosk.ron drifted from config/crowdtouch.ron"
    );
}

/// The config of a table with no touch device reads nothing, serves the viewer to
/// privileged pages, and otherwise matches the documented default.
#[test]
fn no_device_config_differs_from_the_default_only_in_its_inputs_and_outputs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("config");
    let mut table =
        crowdtouch::config::Config::load(&dir.join("no-device.ron")).expect("config/no-device.ron");
    let default = crowdtouch::config::Config::load(&dir.join("crowdtouch.ron")).unwrap();
    assert!(table.inputs.is_empty());
    assert!(matches!(
        table.outputs.as_slice(),
        [crowdtouch::config::OutputConfig::WebSocket {
            privileged: true,
            viewer: true,
            ..
        }]
    ));
    let ways = crowdtouch::pipeline::TouchSources::of(&table);
    assert!(!ways.has_device() && ways.websockets[0].touches());
    table.inputs = default.inputs.clone();
    table.outputs = default.outputs.clone();
    assert_eq!(
        table, default,
        "config/no-device.ron drifted from config/crowdtouch.ron"
    );
}
