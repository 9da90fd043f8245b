//! `crowdtouch doctor [--json]`: what is wrong with this table, for the person at
//! the kiosk, each finding with its fix. It looks at the service as systemd would
//! run it (user `crowdtouch`, the installed unit and its drop-ins, the unit's
//! runtime directory), whoever runs the command.
//!
//! Checks, in order: `config` (loads, and what `run` would refuse), `unit` (the
//! service is installed and reads this config), `service_user`, `device inputs[i]`
//! (what each `Device` input selects; `device` with no `Device` input: that no
//! touch device is configured, and which clients touch instead), `device_access`
//! (user `crowdtouch` may open it), `udev_rule` (installed and applied),
//! `realtime` (the RT priority and memory lock the config asks for are within the
//! unit's limits), `socket` (the service's socket path, its directory and mode),
//! one `output …` per network output or input (a TUIO target resolves and is
//! routable, a WebSocket address can be bound or is the running daemon's, a token
//! where it is needed, the unit lets it through), and `daemon` (running, and its
//! last `stats`: latency, drops, touches, devices).
//!
//! `--json` prints one object, `{"ok": bool, "checks": [{"name", "ok", "detail",
//! "fix"}]}` (`fix` is `null` for a check that passed). Exit status 0 only when
//! every check passed.

use super::doctor_check::Check;
use super::doctor_daemon::{ask_daemon, check_daemon};
use super::doctor_device::{self as device, Account};
use super::doctor_network::check_network;
use super::unit::{self, InstalledUnit, SERVICE_CONFIG, SERVICE_RUNTIME_DIR, SERVICE_USER};
use crate::cli::common::output::{outln, OutputError};
use anyhow::Result;
use crowdtouch::config::{self, Config};
use crowdtouch::pipeline::{preflight, Preflight, Severity};
use serde::Serialize;
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// `crowdtouch doctor`'s arguments.
#[derive(clap::Args, Debug)]
pub struct DoctorArgs {
    /// Config to check (default: the one the service reads,
    /// /etc/crowdtouch/crowdtouch.ron, else the search path of `run`).
    #[arg(long, short)]
    pub config: Option<PathBuf>,
    /// One JSON object: {"ok": bool, "checks": [{"name", "ok", "detail", "fix"}]}.
    #[arg(long)]
    pub json: bool,
    /// The system's root (tests: a tree with dev/, sys/, etc/, lib/).
    #[arg(long, default_value = "/", hide = true)]
    pub root: PathBuf,
}

#[derive(Serialize)]
struct Report<'a> {
    ok: bool,
    checks: &'a [Check],
}

/// Runs every check and prints them; the exit status.
pub fn doctor(a: &DoctorArgs) -> Result<i32> {
    let checks = run_checks(a);
    let ok = checks.iter().all(|c| c.ok);
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&Report {
                ok,
                checks: &checks
            })?
        )?;
    } else {
        print_text(&checks)?;
    }
    Ok(if ok { 0 } else { 1 })
}

fn print_text(checks: &[Check]) -> Result<(), OutputError> {
    for c in checks {
        outln!(
            "{} {}: {}",
            if c.ok { "ok  " } else { "FAIL" },
            c.name,
            c.detail
        )?;
        if let Some(fix) = &c.fix {
            outln!("     fix: {fix}")?;
        }
    }
    let bad = checks.iter().filter(|c| !c.ok).count();
    if bad == 0 {
        outln!("\nnothing wrong found ({} checks)", checks.len())
    } else {
        outln!("\n{bad} of {} checks failed", checks.len())
    }
}

/// The config `doctor` looks at: `--config`, else the service's, else the search
/// path's first.
fn config_path(a: &DoctorArgs) -> Option<PathBuf> {
    if let Some(p) = &a.config {
        return Some(p.clone());
    }
    let service = a.root.join(SERVICE_CONFIG.trim_start_matches('/'));
    if service.is_file() {
        return Some(service);
    }
    config::search_path().into_iter().find(|p| p.is_file())
}

fn run_checks(a: &DoctorArgs) -> Vec<Check> {
    let mut out = Vec::new();
    let path = config_path(a);
    let cfg = match &path {
        Some(p) => match Config::load(p) {
            Ok(c) => {
                out.push(check_preflight(&c, p));
                Some(c)
            }
            Err(e) => {
                out.push(Check::fail(
                    "config",
                    e.to_string(),
                    format!(
                        "edit {} at the line and field named (crowdtouch check-config {} \
                         says the same)",
                        p.display(),
                        p.display()
                    ),
                ));
                None
            }
        },
        None => {
            out.push(Check::fail(
                "config",
                format!("no config file: {SERVICE_CONFIG} does not exist"),
                "reinstall the package (it ships the config), or copy config/kiosk.ron there",
            ));
            None
        }
    };
    let installed = unit::installed(&a.root);
    out.push(check_unit(installed.as_ref(), path.as_deref(), &a.root));
    let acct = device::account(&a.root);
    out.push(device::check_account(&acct));
    let Some(cfg) = cfg else {
        return out;
    };
    out.extend(device::check_devices(&cfg, &a.root, &acct));
    out.push(check_realtime(&cfg, installed.as_ref()));
    let socket = service_socket(&cfg, installed.is_some());
    out.push(check_socket(&cfg, &socket, installed.is_some(), &acct));
    let daemon = ask_daemon(&socket);
    out.extend(check_network(&cfg, installed.as_ref(), daemon.is_ok()));
    out.push(check_daemon(&socket, daemon));
    out
}

/// `config`: loads; what `run` would refuse (the socket aside: `socket` below).
fn check_preflight(cfg: &Config, path: &Path) -> Check {
    let findings = preflight(
        cfg,
        &Preflight {
            socket: None,
            recordings: true,
            starting: false,
        },
    );
    let errors: Vec<String> = findings
        .iter()
        .filter(|f| f.severity == Severity::Error)
        .map(|f| format!("{}: {}", f.field, f.message))
        .collect();
    if errors.is_empty() {
        Check::ok(
            "config",
            format!(
                "{}: loads ({} agents, {} input{}, {} output{})",
                path.display(),
                cfg.crowd.agents,
                cfg.inputs.len(),
                if cfg.inputs.len() == 1 { "" } else { "s" },
                cfg.outputs.len(),
                if cfg.outputs.len() == 1 { "" } else { "s" }
            ),
        )
    } else {
        Check::fail(
            "config",
            format!("{}: {}", path.display(), errors.join("; ")),
            format!(
                "crowdtouch check-config {} shows each at its line",
                path.display()
            ),
        )
    }
}

/// `unit`: the service is installed, reads this config.
fn check_unit(installed: Option<&InstalledUnit>, config: Option<&Path>, root: &Path) -> Check {
    let Some(u) = installed else {
        return Check::fail(
            "unit",
            format!("{} is not installed", unit::UNIT),
            "sudo apt install ./crowdtouch_*.deb (docs/install.md)",
        );
    };
    let exec = u.last("ExecStart").unwrap_or_default();
    let service_config = root.join(SERVICE_CONFIG.trim_start_matches('/'));
    match config {
        Some(c) if c != service_config && !exec.contains(&*c.to_string_lossy()) => Check::fail(
            "unit",
            format!(
                "{} runs `{exec}`, not {}: the service does not read the config checked here",
                u.path.display(),
                c.display()
            ),
            format!("edit {SERVICE_CONFIG} (or run doctor without --config)"),
        ),
        _ => Check::ok(
            "unit",
            format!(
                "{} ({} drop-in{})",
                u.path.display(),
                u.dropins.len(),
                if u.dropins.len() == 1 { "" } else { "s" }
            ),
        ),
    }
}

/// A systemd limit (`LimitMEMLOCK=256M`, `infinity`, `soft:hard`) in bytes or
/// units: the soft limit, which is what applies.
fn parse_limit(v: &str) -> Option<u64> {
    let v = v.split(':').next()?;
    if v == "infinity" {
        return Some(u64::MAX);
    }
    let (num, mul) = match v.chars().last()? {
        'K' => (&v[..v.len() - 1], 1u64 << 10),
        'M' => (&v[..v.len() - 1], 1 << 20),
        'G' => (&v[..v.len() - 1], 1 << 30),
        'T' => (&v[..v.len() - 1], 1 << 40),
        _ => (v, 1),
    };
    num.parse::<u64>().ok().map(|n| n.saturating_mul(mul))
}

/// `realtime`: the SCHED_FIFO priority and memory lock the config asks for fit the
/// unit's limits (or this process's, without the unit).
fn check_realtime(cfg: &Config, installed: Option<&InstalledUnit>) -> Check {
    let rt = &cfg.pipeline.realtime;
    if rt.priority.is_none() && !rt.lock_memory {
        return Check::ok(
            "realtime",
            "the config asks for neither SCHED_FIFO nor locked memory",
        );
    }
    use nix::sys::resource::{getrlimit, Resource};
    let (rtprio, memlock, whose) = match installed {
        Some(u) => (
            u.last("LimitRTPRIO").and_then(parse_limit),
            u.last("LimitMEMLOCK").and_then(parse_limit),
            "the unit's",
        ),
        None => (
            getrlimit(Resource::RLIMIT_RTPRIO).ok().map(|l| l.0),
            getrlimit(Resource::RLIMIT_MEMLOCK).ok().map(|l| l.0),
            "this shell's",
        ),
    };
    /// Below this the daemon's memory cannot all be locked (its resident size is
    /// tens of MiB with a thousand agents: docs/benchmarks.md).
    const MIN_MEMLOCK_BYTES: u64 = 64 << 20;
    let mut bad = Vec::new();
    if let Some(p) = rt.priority {
        if rtprio.unwrap_or(0) < u64::from(p) {
            bad.push(format!(
                "pipeline.realtime.priority {p} is above {whose} RLIMIT_RTPRIO ({})",
                rtprio.unwrap_or(0)
            ));
        }
    }
    if rt.lock_memory && memlock.unwrap_or(0) < MIN_MEMLOCK_BYTES {
        bad.push(format!(
            "lock_memory needs RLIMIT_MEMLOCK of at least {} MiB, {whose} is {} KiB",
            MIN_MEMLOCK_BYTES >> 20,
            memlock.unwrap_or(0) >> 10
        ));
    }
    if bad.is_empty() {
        Check::ok(
            "realtime",
            format!(
                "priority {:?} and lock_memory {} within {whose} limits (RTPRIO {}, MEMLOCK {})",
                rt.priority,
                rt.lock_memory,
                show_limit(rtprio),
                show_limit(memlock)
            ),
        )
    } else {
        Check::fail(
            "realtime",
            bad.join("; "),
            "lower pipeline.realtime.priority, or raise LimitRTPRIO=/LimitMEMLOCK= in a \
             drop-in (sudo systemctl edit crowdtouch); the daemon runs without them, at normal \
             priority, and logs it",
        )
    }
}

fn show_limit(l: Option<u64>) -> String {
    match l {
        Some(u64::MAX) => "unlimited".into(),
        Some(n) => n.to_string(),
        None => "unset".into(),
    }
}

/// The socket path the service binds: the config's, else the unit's runtime
/// directory's (or what this process would resolve without the unit).
fn service_socket(cfg: &Config, unit_installed: bool) -> PathBuf {
    match (&cfg.socket.path, unit_installed) {
        (Some(p), _) => p.clone(),
        (None, true) => Path::new(SERVICE_RUNTIME_DIR).join("crowdtouch.sock"),
        (None, false) => cfg.socket.resolved_path(),
    }
}

/// `socket`: its directory exists (or is the unit's runtime directory), the
/// service may create the socket there, and the socket's mode lets the group in.
fn check_socket(
    cfg: &Config,
    path: &Path,
    unit_installed: bool,
    acct: &Result<Account, String>,
) -> Check {
    let dir = path.parent().unwrap_or(Path::new("/"));
    let runtime = unit_installed && dir == Path::new(SERVICE_RUNTIME_DIR);
    let meta = match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => m,
        Ok(_) => {
            return Check::fail(
                "socket",
                format!("{}: {} is not a directory", path.display(), dir.display()),
                "set socket.path to a path in an existing directory, or `path: None` (the \
                 unit's /run/crowdtouch)",
            )
        }
        Err(_) if runtime => {
            return Check::ok(
                "socket",
                format!(
                    "{} (systemd creates {} when it starts the service)",
                    path.display(),
                    dir.display()
                ),
            )
        }
        Err(e) => {
            return Check::fail(
                "socket",
                format!(
                    "{}: its directory {} cannot be used: {e}",
                    path.display(),
                    dir.display()
                ),
                format!(
                    "set socket.path: None in the config (the service then uses \
                     {SERVICE_RUNTIME_DIR}/crowdtouch.sock, which systemd creates), or create {}",
                    dir.display()
                ),
            )
        }
    };
    if let (Ok(a), false) = (acct, runtime) {
        let bits = if meta.uid() == a.uid {
            meta.mode() >> 6
        } else if a.groups.contains(&meta.gid()) {
            meta.mode() >> 3
        } else {
            meta.mode()
        } & 0o3;
        if bits != 0o3 {
            return Check::fail(
                "socket",
                format!(
                    "user {SERVICE_USER} may not create {} in {} (uid {} gid {} mode {:04o})",
                    path.file_name()
                        .map_or_else(String::new, |n| n.to_string_lossy().into()),
                    dir.display(),
                    meta.uid(),
                    meta.gid(),
                    meta.mode() & 0o7777
                ),
                format!(
                    "socket.path: None (the unit's {SERVICE_RUNTIME_DIR}), or give the directory \
                     to the {SERVICE_USER} group"
                ),
            );
        }
    }
    let mode = &cfg.socket.mode;
    match std::fs::metadata(path) {
        Ok(m) => {
            let actual = m.permissions().mode() & 0o777;
            Check::ok(
                "socket",
                format!(
                    "{} (mode {actual:04o}, gid {}; renderers must be in its group)",
                    path.display(),
                    m.gid()
                ),
            )
        }
        Err(_) => Check::ok(
            "socket",
            format!("{} can be created (mode {mode} when bound)", path.display()),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_read_as_systemd_writes_them() {
        assert_eq!(parse_limit("256M"), Some(256 << 20));
        assert_eq!(parse_limit("infinity"), Some(u64::MAX));
        assert_eq!(parse_limit("50"), Some(50));
        assert_eq!(parse_limit("64K:128K"), Some(64 << 10));
        assert_eq!(parse_limit("lots"), None);
    }
}
