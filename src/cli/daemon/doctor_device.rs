//! `doctor`'s checks of the service's account and touch devices: the `crowdtouch`
//! user and group, which device each `Device` input would read, whether the
//! service user may open it, and the udev rule that gives it the group; for a
//! config without a `Device` input, where its touches come from.
//!
//! Access is judged from the node's owner, group and mode against the service
//! user's uid and groups (from `ROOT/etc/passwd` and `ROOT/etc/group`, where
//! systemd-sysusers writes them), not by opening it: `doctor` runs as whoever
//! asks, often root, while the daemon runs as `crowdtouch`.

use super::doctor_check::Check;
use super::unit::SERVICE_USER;
use crowdtouch::config::{Config, InputConfig};
use crowdtouch::input::discover::{discover, select, Found, SelectError};
use crowdtouch::input::DeviceKind;
use crowdtouch::pipeline::device::{preference, selector, SystemProber};
use crowdtouch::pipeline::TouchSources;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// The udev rule the package installs, by name.
pub const UDEV_RULE: &str = "70-crowdtouch.rules";
/// Where udev reads rules (udev(7)), relative to the root.
const RULE_DIRS: [&str; 4] = [
    "etc/udev/rules.d",
    "run/udev/rules.d",
    "usr/lib/udev/rules.d",
    "lib/udev/rules.d",
];
/// The commands that apply the rule to the nodes there are. udevd is restarted
/// rather than told to reload: it resolves a rule's group when it loads the rules
/// and reloads them only when the files change, so a rule it read before the group
/// existed keeps the nodes root-only until it restarts.
pub const UDEV_TRIGGER: &str = "sudo systemctl restart systemd-udevd && sudo udevadm trigger \
     --subsystem-match=input --subsystem-match=hidraw";

/// The service user's ids.
#[derive(Clone, Debug, PartialEq)]
pub struct Account {
    /// User id.
    pub uid: u32,
    /// Primary group id.
    pub gid: u32,
    /// Every group it is in (primary included).
    pub groups: Vec<u32>,
}

/// `name`'s entry in a passwd or group file: its fields after the name.
fn entry<'a>(text: &'a str, name: &str) -> Option<Vec<&'a str>> {
    text.lines().find_map(|l| {
        let mut f = l.split(':');
        (f.next() == Some(name)).then(|| f.collect())
    })
}

/// The service user's account under `root`: `Err` says what is missing.
pub fn account(root: &Path) -> Result<Account, String> {
    let passwd = std::fs::read_to_string(root.join("etc/passwd")).unwrap_or_default();
    let group = std::fs::read_to_string(root.join("etc/group")).unwrap_or_default();
    let user = entry(&passwd, SERVICE_USER);
    let grp = entry(&group, SERVICE_USER);
    let (uid, gid) = match &user {
        Some(f) => (
            f.get(1).and_then(|v| v.parse().ok()),
            f.get(2).and_then(|v| v.parse().ok()),
        ),
        None => (None, None),
    };
    match (uid, gid, &grp) {
        (Some(uid), Some(gid), Some(g)) => {
            let mut groups = vec![gid];
            for l in group.lines() {
                let f: Vec<&str> = l.split(':').collect();
                if f.len() == 4
                    && f[3].split(',').any(|m| m == SERVICE_USER)
                    && !groups.iter().any(|x| Some(*x) == f[2].parse().ok())
                {
                    groups.extend(f[2].parse::<u32>().ok());
                }
            }
            let own: Option<u32> = g.get(1).and_then(|v| v.parse().ok());
            if own != Some(gid) {
                return Err(format!(
                    "user {SERVICE_USER}'s primary group is {gid}, not the group {SERVICE_USER} ({})",
                    own.map_or("?".to_string(), |g| g.to_string())
                ));
            }
            Ok(Account { uid, gid, groups })
        }
        _ => Err(match (user.is_some(), grp.is_some()) {
            (false, false) => format!(
                "neither a user nor a group {SERVICE_USER} in {}",
                root.join("etc/{passwd,group}").display()
            ),
            (false, true) => format!(
                "no user {SERVICE_USER} in {}",
                root.join("etc/passwd").display()
            ),
            _ => format!(
                "no group {SERVICE_USER} in {}",
                root.join("etc/group").display()
            ),
        }),
    }
}

/// `service_user`: the account exists.
pub fn check_account(acct: &Result<Account, String>) -> Check {
    match acct {
        Ok(a) => Check::ok(
            "service_user",
            format!(
                "user {SERVICE_USER} (uid {}) and group {SERVICE_USER} (gid {}) exist",
                a.uid, a.gid
            ),
        ),
        Err(why) => Check::fail(
            "service_user",
            why.clone(),
            "sudo systemd-sysusers (the package's sysusers file creates both; without the \
             package: install systemd/crowdtouch.sysusers as /etc/sysusers.d/crowdtouch.conf first)",
        ),
    }
}

/// Whether `acct` may open `node` for what the daemon needs (read for evdev, read
/// and write for hidraw), from the node's owner, group and mode.
fn may_open(acct: &Account, meta: &std::fs::Metadata, kind: DeviceKind) -> bool {
    let need = match kind {
        DeviceKind::Evdev => 0o4,
        DeviceKind::Hidraw => 0o6,
    };
    let mode = meta.mode();
    let bits = if meta.uid() == acct.uid {
        mode >> 6
    } else if acct.groups.contains(&meta.gid()) {
        mode >> 3
    } else {
        mode
    } & 0o7;
    bits & need == need
}

/// The device checks: `device` (what each `Device` input selects), `device_access`
/// (the service user may open it), `udev_rule` (installed, and applied to every
/// touch node found). A config with no `Device` input reads no device: `device`
/// says where its touches come from instead, and no node is probed.
pub fn check_devices(cfg: &Config, root: &Path, acct: &Result<Account, String>) -> Vec<Check> {
    let inputs: Vec<(usize, &InputConfig)> = cfg
        .inputs
        .iter()
        .enumerate()
        .filter(|(_, i)| matches!(i, InputConfig::Device { .. }))
        .collect();
    let rule = RULE_DIRS
        .iter()
        .map(|d| root.join(d).join(UDEV_RULE))
        .find(|p| p.is_file());
    if let Some(line) = TouchSources::of(cfg).without_device() {
        let rule = match &rule {
            Some(r) => format!("{} installed", r.display()),
            None => format!("{UDEV_RULE} not installed"),
        };
        return vec![
            Check::ok("device", line),
            Check::ok("device_access", "no device node to open"),
            Check::ok(
                "udev_rule",
                format!("{rule}; not needed: the config reads no touch device"),
            ),
        ];
    }
    let found = discover(root, &SystemProber);
    let mut out = Vec::new();
    // The nodes the service will need: each input's pick, or its candidates.
    let mut nodes: Vec<(PathBuf, DeviceKind)> = Vec::new();
    for (i, input) in &inputs {
        let InputConfig::Device {
            select: sel,
            interface,
            ..
        } = input
        else {
            continue;
        };
        let name = format!("device inputs[{i}]");
        match select(&found, &selector(sel), preference(*interface)) {
            Ok(f) => {
                nodes.push((f.info.identity.node.clone(), f.info.identity.kind));
                out.push(Check::ok(&name, describe(f)));
            }
            Err(SelectError::Unusable { found: c, .. }) => {
                let matching: Vec<&Found> = found
                    .iter()
                    .filter(|f| c.0.iter().any(|s| s.node == f.info.identity.node))
                    .collect();
                nodes.extend(
                    matching
                        .iter()
                        .map(|f| (f.info.identity.node.clone(), f.info.identity.kind)),
                );
                let why: Vec<String> = matching
                    .iter()
                    .map(|f| {
                        format!(
                            "{}: {}",
                            f.info.identity.node.display(),
                            f.probe_error.as_deref().unwrap_or("?")
                        )
                    })
                    .collect();
                let denied_here = !nix::unistd::geteuid().is_root()
                    && matching.iter().all(|f| {
                        f.probe_error
                            .as_deref()
                            .is_some_and(|e| e.contains("ermission denied"))
                    });
                if denied_here {
                    out.push(Check::ok(
                        &name,
                        format!(
                            "found, but this user may not open it to read its ranges ({}); the \
                             service's own access is checked below",
                            why.join("; ")
                        ),
                    ));
                } else {
                    out.push(Check::fail(
                        &name,
                        format!("a matching device cannot be read: {}", why.join("; ")),
                        "`crowdtouch devices` lists what is there; `crowdtouch record` \
                         tells whether the node delivers events",
                    ));
                }
            }
            Err(e) => out.push(Check::fail(
                &name,
                e.to_string(),
                "plug the table in, or change the input's `select` (`crowdtouch devices` \
                 lists the touch devices and the one Auto picks)",
            )),
        }
    }
    out.push(check_access(&nodes, acct, rule.is_some()));
    out.push(check_rule(rule.as_deref(), &found, acct));
    out
}

/// One line about a selected device.
fn describe(f: &Found) -> String {
    let i = &f.info.identity;
    format!(
        "{} ({} {:04x}:{:04x}, {})",
        i.node.display(),
        i.kind.as_str(),
        i.vendor,
        i.product,
        i.name
    )
}

/// `device_access`: the service user may open every node it will need.
fn check_access(
    nodes: &[(PathBuf, DeviceKind)],
    acct: &Result<Account, String>,
    rule_installed: bool,
) -> Check {
    let Ok(acct) = acct else {
        return Check::fail(
            "device_access",
            format!("no {SERVICE_USER} user to check the nodes for"),
            "create it first (service_user)",
        );
    };
    if nodes.is_empty() {
        return Check::ok("device_access", "no device node to open");
    }
    let mut bad = Vec::new();
    let mut good = Vec::new();
    for (node, kind) in nodes {
        match std::fs::metadata(node) {
            Ok(m) if may_open(acct, &m, *kind) => good.push(format!(
                "{} ({}, gid {} mode {:04o})",
                node.display(),
                kind.as_str(),
                m.gid(),
                m.mode() & 0o7777
            )),
            Ok(m) => bad.push(format!(
                "{} is uid {} gid {} mode {:04o}: user {SERVICE_USER} (groups {:?}) may not {} it",
                node.display(),
                m.uid(),
                m.gid(),
                m.mode() & 0o7777,
                acct.groups,
                match kind {
                    DeviceKind::Evdev => "read",
                    DeviceKind::Hidraw => "read and write",
                }
            )),
            Err(e) => bad.push(format!("{}: {e}", node.display())),
        }
    }
    if bad.is_empty() {
        Check::ok(
            "device_access",
            format!("user {SERVICE_USER} may open {}", good.join(", ")),
        )
    } else {
        let fix = if rule_installed {
            format!(
                "the udev rule gives touch nodes group {SERVICE_USER} and mode 0640/0660 when it \
                 is applied: {UDEV_TRIGGER}"
            )
        } else {
            format!("install the udev rule ({UDEV_RULE}, in the package), then {UDEV_TRIGGER}")
        };
        Check::fail("device_access", bad.join("; "), fix)
    }
}

/// `udev_rule`: installed, and every touch node found has its group.
fn check_rule(rule: Option<&Path>, found: &[Found], acct: &Result<Account, String>) -> Check {
    let Some(rule) = rule else {
        return Check::fail(
            "udev_rule",
            format!(
                "{UDEV_RULE} is in none of /etc/udev/rules.d, /run/udev/rules.d, \
                 /usr/lib/udev/rules.d, /lib/udev/rules.d: touch nodes stay root-only"
            ),
            format!(
                "reinstall the package (sudo apt install --reinstall ./crowdtouch_*.deb), or \
                 sudo install -m 0644 udev/{UDEV_RULE} /etc/udev/rules.d/; then {UDEV_TRIGGER}"
            ),
        );
    };
    let gid = acct.as_ref().ok().map(|a| a.gid);
    let unapplied: Vec<String> = found
        .iter()
        .filter_map(|f| {
            let node = &f.info.identity.node;
            let m = std::fs::metadata(node).ok()?;
            (Some(m.gid()) != gid).then(|| format!("{} (gid {})", node.display(), m.gid()))
        })
        .collect();
    if unapplied.is_empty() {
        Check::ok(
            "udev_rule",
            format!(
                "{} installed; {} touch node{} with group {SERVICE_USER}",
                rule.display(),
                found.len(),
                if found.len() == 1 { "" } else { "s" }
            ),
        )
    } else {
        Check::fail(
            "udev_rule",
            format!(
                "{} installed, not applied to {}",
                rule.display(),
                unapplied.join(", ")
            ),
            UDEV_TRIGGER.to_string(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accounts_are_read_from_passwd_and_group() {
        let root = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(root.path().join("etc")).unwrap();
        assert!(account(root.path()).unwrap_err().starts_with("neither"));
        std::fs::write(
            root.path().join("etc/passwd"),
            "root:x:0:0::/root:/bin/sh\ncrowdtouch:x:990:985:crowdtouch:/nonexistent:/usr/sbin/nologin\n",
        )
        .unwrap();
        assert!(account(root.path()).unwrap_err().starts_with("no group"));
        std::fs::write(
            root.path().join("etc/group"),
            "root:x:0:\ncrowdtouch:x:985:\nrender:x:44:kiosk,crowdtouch\n",
        )
        .unwrap();
        let a = account(root.path()).unwrap();
        assert_eq!((a.uid, a.gid), (990, 985));
        assert_eq!(a.groups, vec![985, 44]);
    }
}
