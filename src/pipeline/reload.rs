//! A config reload on the supervisor's side: the parts applied outside the control
//! thread (the socket file's mode and group, the log level), what stays pending
//! until a restart, and the one log line that says what the reload did.
//!
//! Which field is applied live and which needs a restart is decided by the table
//! next to the config model ([`crate::config::FIELDS`], [`crate::config::plan_reload`]).

use crate::config::{show_value, LogLevel, ReloadClass, ReloadPlan, SocketConfig};
use crate::vocab::RestartPending;
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::Path;

/// A live field the reload could not apply: its path and why.
pub(super) type NotApplied = (&'static str, String);

/// Gives the socket file at `path` the new config's mode and group when they
/// changed. A change that fails is undone in `new` (the running value stays in
/// effect, and the next reload tries again) and returned with the reason.
pub(super) fn apply_socket_access(
    path: &Path,
    running: &SocketConfig,
    new: &mut SocketConfig,
) -> Vec<NotApplied> {
    let mut failed = Vec::new();
    let ours = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_socket());
    if new.mode != running.mode {
        let mode = new.mode_bits();
        let done = if ours {
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
                .map_err(|e| format!("cannot change the mode of {}: {e}", path.display()))
        } else {
            Err(format!("{} is not a socket any more", path.display()))
        };
        if let Err(why) = done {
            new.mode.clone_from(&running.mode);
            failed.push(("socket.mode", why));
        }
    }
    if new.group != running.group {
        let done = if !ours {
            Err(format!("{} is not a socket any more", path.display()))
        } else {
            match &new.group {
                // Back to the process's own group.
                None => chown_group(path, nix::unistd::getegid()),
                Some(name) => match nix::unistd::Group::from_name(name) {
                    Ok(Some(g)) => chown_group(path, g.gid),
                    Ok(None) => Err(format!("there is no group \"{name}\"")),
                    Err(e) => Err(format!("cannot look up group \"{name}\": {e}")),
                },
            }
        };
        if let Err(why) = done {
            new.group.clone_from(&running.group);
            failed.push(("socket.group", why));
        }
    }
    failed
}

fn chown_group(path: &Path, gid: nix::unistd::Gid) -> Result<(), String> {
    nix::unistd::chown(path, None, Some(gid))
        .map_err(|e| format!("cannot give {} to group {gid}: {e}", path.display()))
}

/// Sets the log level for the lines that follow, unless `RUST_LOG` decides it (as
/// it does at start).
pub(super) fn apply_log_level(level: LogLevel) {
    if std::env::var_os("RUST_LOG").is_none() {
        log::set_max_level(level.filter());
    }
}

/// The restart fields of `plan` as `stats` publishes them; the running socket path
/// is the one actually served.
pub(super) fn pending(plan: &ReloadPlan, socket_path: &Path) -> Vec<RestartPending> {
    plan.of(ReloadClass::Restart)
        .map(|c| RestartPending {
            field: c.path.clone(),
            running: if c.path == "socket.path" {
                serde_json::Value::String(socket_path.display().to_string())
            } else {
                c.old.clone()
            },
            configured: c.new.clone(),
        })
        .collect()
}

/// The log line of a reload and its level: what was applied, what needs a restart
/// (old → new; the running values stay), what could not be applied and why.
/// `scene_file_changed`: the scene was swapped although its path stayed.
pub(super) fn summary(
    plan: &ReloadPlan,
    failed: &[NotApplied],
    scene_file_changed: bool,
    socket_path: &Path,
) -> (log::Level, String) {
    let mut applied: Vec<String> = plan
        .of(ReloadClass::Live)
        .filter(|c| !failed.iter().any(|(p, _)| *p == c.path))
        .map(|c| c.describe())
        .collect();
    if scene_file_changed {
        applied.push("scene (the file changed)".to_string());
    }
    let restart: Vec<String> = plan
        .of(ReloadClass::Restart)
        .map(|c| {
            if c.path == "socket.path" {
                format!("{} (serving {})", c.describe(), socket_path.display())
            } else {
                c.describe()
            }
        })
        .collect();
    let mut parts = Vec::new();
    if !applied.is_empty() {
        parts.push(format!("applied {}", applied.join(", ")));
    }
    if !restart.is_empty() {
        parts.push(format!(
            "needs restart (the old values stay in use): {}",
            restart.join(", ")
        ));
    }
    if !failed.is_empty() {
        let list: Vec<String> = failed
            .iter()
            .map(|(path, why)| {
                let new = plan
                    .changes
                    .iter()
                    .find(|c| c.path == *path)
                    .map_or(String::new(), |c| format!(" {}", show_value(&c.new)));
                format!("{path}{new} ({why})")
            })
            .collect();
        parts.push(format!("not applied: {}", list.join(", ")));
    }
    if parts.is_empty() {
        parts.push("no field changed".to_string());
    }
    let level = if restart.is_empty() && failed.is_empty() {
        log::Level::Info
    } else {
        log::Level::Warn
    };
    (level, format!("config reloaded: {}", parts.join("; ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{plan_reload, Config};
    use std::path::PathBuf;

    #[test]
    fn the_line_names_what_was_applied_and_what_needs_a_restart() {
        let running = Config::embedded_default();
        let mut new = running.clone();
        new.crowd.agents = 500;
        new.socket.max_clients = 2;
        new.socket.path = Some(PathBuf::from("/run/b.sock"));
        let plan = plan_reload(&running, new);
        let (level, line) = summary(&plan, &[], false, Path::new("/run/a.sock"));
        assert_eq!(level, log::Level::Warn);
        assert_eq!(
            line,
            "config reloaded: applied crowd.agents 100 → 500, socket.max_clients 32 → 2; \
             needs restart (the old values stay in use): socket.path None → \"/run/b.sock\" \
             (serving /run/a.sock)"
        );
        let p = pending(&plan, Path::new("/run/a.sock"));
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].field, "socket.path");
        assert_eq!(p[0].running, "/run/a.sock");
        assert_eq!(p[0].configured, "/run/b.sock");
    }

    #[test]
    fn an_unchanged_file_says_so_and_a_failure_says_why() {
        let running = Config::embedded_default();
        let plan = plan_reload(&running, running.clone());
        let (level, line) = summary(&plan, &[], false, Path::new("/s"));
        assert_eq!(
            (level, line.as_str()),
            (log::Level::Info, "config reloaded: no field changed")
        );
        let (_, line) = summary(&plan, &[], true, Path::new("/s"));
        assert_eq!(line, "config reloaded: applied scene (the file changed)");
        let mut new = running.clone();
        new.socket.group = Some("nosuchgroup-crowdtouch".to_string());
        let plan = plan_reload(&running, new);
        let failed = [("socket.group", "there is no group".to_string())];
        let (level, line) = summary(&plan, &failed, false, Path::new("/s"));
        assert_eq!(level, log::Level::Warn);
        assert_eq!(
            line,
            "config reloaded: not applied: socket.group \"nosuchgroup-crowdtouch\" (there is no group)"
        );
    }

    #[test]
    fn socket_mode_and_group_change_the_file_or_keep_the_running_values() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("s.sock");
        let _listener = std::os::unix::net::UnixListener::bind(&path).expect("bind");
        let running = Config::embedded_default().socket;
        let mut new = running.clone();
        new.mode = "0600".to_string();
        new.group = Some("nosuchgroup-crowdtouch".to_string());
        let failed = apply_socket_access(&path, &running, &mut new);
        let mode = std::fs::metadata(&path).expect("stat").permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        assert_eq!(new.mode, "0600");
        assert_eq!(failed.len(), 1, "{failed:?}");
        assert_eq!(failed[0].0, "socket.group");
        assert!(failed[0].1.contains("no group"), "{failed:?}");
        assert_eq!(
            new.group, running.group,
            "the running group stays in effect"
        );
    }
}
