//! Preflight: what `run` would refuse at start-up, found from a config without
//! starting, binding or opening anything for good, each at the config field it
//! comes from. `check-config` reports these with the config's own errors; `run`
//! makes the same checks before it starts.
//!
//! The checks are the ones start-up makes, called here on their own: the socket
//! path and group as [`Server::bind`](crate::publish::Server::bind) checks them
//! ([`crate::publish::socket::preflight`]), the recordings read as
//! [`sources_from_config`](super::sources_from_config) reads them. A few things
//! depend on who asks and when: a daemon listening on the socket now, whether this
//! user may create the socket or give it to its group, and a `$RUNTIME_DIRECTORY`
//! that systemd creates only when it starts the service. `check-config` is often
//! run by someone else than the service, or while the daemon runs, so for it those
//! are warnings; for `run` ([`Preflight::starting`]) they are errors.
//!
//! Input CPUs that are not online are a warning, not an error: one config is often
//! shared by machines of several sizes, and start-up pins the input thread to the
//! listed CPUs that exist (and leaves it unpinned when none does).

use crate::config::{Config, InputConfig};
use crate::input::recording::{OnBadFrame, RecordingError, RecordingStream};
use crate::publish::socket::preflight as socket;
use crate::publish::Error as SocketError;
use std::path::Path;

/// Where the kernel lists the CPUs that are online.
const ONLINE_CPUS_FILE: &str = "/sys/devices/system/cpu/online";

/// How bad a finding is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    /// `run` refuses to start.
    Error,
    /// `run` starts, but not as the config says (or not for every user or moment).
    Warning,
}

/// One problem, at the dotted path of the config field it comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Finding {
    /// Config field (`socket.path`, `inputs[0].files[1]`).
    pub field: String,
    /// Error or warning.
    pub severity: Severity,
    /// What is wrong.
    pub message: String,
}

/// What to check.
#[derive(Clone, Copy, Debug)]
pub struct Preflight<'a> {
    /// The socket path the daemon would bind (`None`: not checked here).
    pub socket: Option<&'a Path>,
    /// Read every recording a `Replay` input names.
    pub recordings: bool,
    /// The checks are made by the process that is about to start the daemon: a
    /// live daemon on the socket and this user's permissions are errors.
    pub starting: bool,
}

/// Every problem `run` would meet starting from `cfg`
/// ([`crate::config::locate_issues`] places them in the config's text).
pub fn preflight(cfg: &Config, what: &Preflight<'_>) -> Vec<Finding> {
    let mut out = Vec::new();
    let user_dependent = if what.starting {
        Severity::Error
    } else {
        Severity::Warning
    };
    let mut gid = None;
    if let Some(group) = &cfg.socket.group {
        match socket::lookup_group(group) {
            Ok(g) => gid = Some(g),
            Err(e) => out.push(finding("socket.group", Severity::Error, e.to_string())),
        }
    }
    for (i, u) in cfg.socket.privileged.users.iter().enumerate() {
        if let Err(e) = socket::resolve_peers(std::slice::from_ref(u), &[]) {
            out.push(finding(
                &format!("socket.privileged.users[{i}]"),
                Severity::Error,
                e.to_string(),
            ));
        }
    }
    for (i, g) in cfg.socket.privileged.groups.iter().enumerate() {
        if let Err(e) = socket::resolve_peers(&[], std::slice::from_ref(g)) {
            out.push(finding(
                &format!("socket.privileged.groups[{i}]"),
                Severity::Error,
                e.to_string(),
            ));
        }
    }
    if let Some(path) = what.socket {
        let resolved = if cfg.socket.path.is_none() {
            " (`path: None` resolves to this path here)"
        } else {
            ""
        };
        match socket::inspect_socket_path(path) {
            Ok(_) => {
                let dir = socket::socket_dir(path);
                if !socket::dir_writable(dir) {
                    out.push(finding(
                        "socket.path",
                        user_dependent,
                        format!(
                            "{}: this user (uid {}) may not create the socket in {}{resolved}",
                            path.display(),
                            nix::unistd::geteuid(),
                            dir.display()
                        ),
                    ));
                }
            }
            // systemd creates the service's runtime directory when it starts it.
            Err(e @ SocketError::NoDirectory { .. })
                if cfg.socket.path.is_none()
                    && std::env::var_os("RUNTIME_DIRECTORY").is_some() =>
            {
                out.push(finding(
                    "socket.path",
                    user_dependent,
                    format!(
                        "{e}{resolved}; systemd creates $RUNTIME_DIRECTORY when it starts the service"
                    ),
                ))
            }
            Err(e @ SocketError::InUse { .. }) => out.push(finding(
                "socket.path",
                user_dependent,
                format!("{e}{resolved}; `run` refuses to start while it listens"),
            )),
            Err(e) => out.push(finding(
                "socket.path",
                Severity::Error,
                format!("{e}{resolved}"),
            )),
        }
    }
    if let (Some(group), Some(gid)) = (&cfg.socket.group, gid) {
        if !socket::may_use_group(gid) {
            out.push(finding(
                "socket.group",
                user_dependent,
                format!(
                    "this user (uid {}) is not in group `{group}` and may not give the socket to it",
                    nix::unistd::geteuid()
                ),
            ));
        }
    }
    if what.recordings {
        for (i, input) in cfg.inputs.iter().enumerate() {
            if let InputConfig::Replay { files, .. } = input {
                for (j, f) in files.iter().enumerate() {
                    if let Err(e) = read_through(f) {
                        out.push(finding(
                            &format!("inputs[{i}].files[{j}]"),
                            Severity::Error,
                            format!("recording not usable: {e}"),
                        ));
                    }
                }
            }
        }
    }
    if let Some(f) = edit_dir_finding(cfg) {
        out.push(f);
    }
    if let Some(cpus) = &cfg.pipeline.realtime.input_cpus {
        if let Some(online) = online_cpus() {
            out.extend(cpu_findings(cpus, &online));
        }
    }
    out
}

/// A warning when the config names an edit directory that is not there: the
/// daemon starts, but clients' `edit.load` and `edit.save` are refused until it
/// exists (the daemon creates nothing outside it, and not it either). The default
/// directory under `$STATE_DIRECTORY` is the unit's to create, so only a `dir` the
/// config sets is checked.
fn edit_dir_finding(cfg: &Config) -> Option<Finding> {
    let dir = cfg.edit.as_ref()?.dir.as_ref()?;
    let what = match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => return None,
        Ok(_) => "is not a directory",
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => "does not exist",
        Err(_) => "cannot be read by this user",
    };
    Some(finding(
        "edit.dir",
        Severity::Warning,
        format!(
            "{} {what}: clients' edit.load and edit.save are refused until it is a directory \
             the daemon's user may read (and write, to save)",
            dir.display()
        ),
    ))
}

fn finding(field: &str, severity: Severity, message: String) -> Finding {
    Finding {
        field: field.to_string(),
        severity,
        message,
    }
}

/// A warning for each listed CPU that is not online.
fn cpu_findings(cpus: &[usize], online: &[usize]) -> Vec<Finding> {
    let kept: Vec<usize> = cpus
        .iter()
        .copied()
        .filter(|c| online.contains(c))
        .collect();
    let effect = if kept.is_empty() {
        "none of the listed CPUs is, so the input thread is not pinned (it runs on any CPU)"
            .to_string()
    } else {
        format!("the input thread is pinned to CPUs {kept:?} only")
    };
    cpus.iter()
        .enumerate()
        .filter(|(_, c)| !online.contains(c))
        .map(|(k, c)| {
            finding(
                &format!("pipeline.realtime.input_cpus[{k}]"),
                Severity::Warning,
                format!(
                    "CPU {c} is not online on this machine (online: {}); {effect}",
                    cpu_list(online)
                ),
            )
        })
        .collect()
}

/// The CPUs online now, from the kernel's list (`0-3,6`); `None` when it cannot
/// be read.
pub fn online_cpus() -> Option<Vec<usize>> {
    parse_cpu_list(std::fs::read_to_string(ONLINE_CPUS_FILE).ok()?.trim())
}

/// Parses the kernel's CPU list format (`0-3,6`).
fn parse_cpu_list(s: &str) -> Option<Vec<usize>> {
    let mut out = Vec::new();
    for part in s.split(',').filter(|p| !p.is_empty()) {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b): (usize, usize) = (a.parse().ok()?, b.parse().ok()?);
                if b < a || b - a > 1 << 16 {
                    return None;
                }
                out.extend(a..=b);
            }
            None => out.push(part.parse().ok()?),
        }
    }
    Some(out)
}

/// Writes a CPU list back in the kernel's format.
fn cpu_list(cpus: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < cpus.len() {
        let mut j = i;
        while j + 1 < cpus.len() && cpus[j + 1] == cpus[j] + 1 {
            j += 1;
        }
        parts.push(if j > i {
            format!("{}-{}", cpus[i], cpus[j])
        } else {
            cpus[i].to_string()
        });
        i = j + 1;
    }
    parts.join(",")
}

/// Reads a recording through, a frame at a time, as `run` does before it starts
/// (memory does not grow with the recording's length).
fn read_through(path: &Path) -> Result<(), RecordingError> {
    let mut stream = RecordingStream::load(path, OnBadFrame::Stop)?;
    while stream.next_frame()?.is_some() {
        drop(stream.take_warnings());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_lists_read_and_write_in_the_kernels_format() {
        assert_eq!(parse_cpu_list("0-3,6"), Some(vec![0, 1, 2, 3, 6]));
        assert_eq!(parse_cpu_list("0"), Some(vec![0]));
        assert_eq!(parse_cpu_list("3-1"), None);
        assert_eq!(parse_cpu_list("x"), None);
        assert_eq!(cpu_list(&[0, 1, 2, 3, 6, 8, 9]), "0-3,6,8-9");
    }

    #[test]
    fn cpus_not_online_are_warned_about_at_their_entry() {
        let f = cpu_findings(&[1, 99], &[0, 1]);
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].field, "pipeline.realtime.input_cpus[1]");
        assert_eq!(f[0].severity, Severity::Warning);
        assert_eq!(
            f[0].message,
            "CPU 99 is not online on this machine (online: 0-1); the input thread is pinned to CPUs [1] only"
        );
        let f = cpu_findings(&[99], &[0, 1]);
        assert!(f[0].message.ends_with("none of the listed CPUs is, so the input thread is not pinned (it runs on any CPU)"), "{}", f[0].message);
        assert!(cpu_findings(&[0, 1], &[0, 1]).is_empty());
    }

    #[test]
    fn an_edit_directory_the_config_sets_is_warned_about_unless_it_is_one() {
        use crate::config::{EditConfig, DEFAULT_CONFIG_RON};
        let mut cfg = Config::from_str(DEFAULT_CONFIG_RON, Path::new("c")).expect("default");
        assert!(
            edit_dir_finding(&cfg).is_none(),
            "no edit entry: nothing said"
        );
        let tmp = std::env::temp_dir().join(format!("ct-preflight-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&tmp);
        let mut edit = |dir: &Path| {
            cfg.edit = Some(EditConfig {
                tracks: Default::default(),
                dir: Some(dir.to_path_buf()),
                allow_overwrite: false,
                threshold_m: 0.3,
                preview: true,
            });
            edit_dir_finding(&cfg)
        };
        let f = edit(&tmp).expect("a missing directory is warned about");
        assert_eq!(
            (f.field.as_str(), f.severity),
            ("edit.dir", Severity::Warning)
        );
        assert!(f.message.contains("does not exist"), "{}", f.message);
        std::fs::write(&tmp, b"").unwrap();
        let f = edit(&tmp).expect("a file is warned about");
        assert!(f.message.contains("is not a directory"), "{}", f.message);
        std::fs::remove_file(&tmp).unwrap();
        std::fs::create_dir(&tmp).unwrap();
        assert!(edit(&tmp).is_none());
        std::fs::remove_dir(&tmp).unwrap();
    }
}
