//! `crowdtouch check-config FILE`: the config's own errors, and what `run` would
//! refuse at start-up with it, each at its field. [`startup_findings`] is the one
//! start-up check, made by `check-config` and by `run` before it starts.

use crate::cli::common::output::{self, errln, outln};
use anyhow::Result;
use crowdtouch::config::{self, Config};
use crowdtouch::pipeline::{preflight, Finding, Preflight, Severity, TouchSources};
use std::path::{Path, PathBuf};

/// Who makes the start-up check.
#[derive(Clone, Copy, Debug)]
pub enum Asker {
    /// `check-config`: often run by another user than the service's, or while the
    /// daemon runs, so what depends on who asks and when is a warning; the
    /// recordings are read through here.
    CheckConfig,
    /// `run`, about to start: everything is an error; the recordings are read
    /// (and refused, at their line) when the inputs start, just after.
    Run {
        /// `--socket` was given: that path is checked when it is bound, not the
        /// config's.
        socket_given: bool,
    },
}

/// What `run` would refuse (errors) or start with anyway (warnings) from `cfg`:
/// the one check `check-config` and `run` both make, so they agree on what may
/// run. A config needs no input to run: its clients can always touch it
/// ([`TouchSources`]).
pub fn startup_findings(cfg: &Config, asker: Asker) -> Vec<Finding> {
    let socket = cfg.socket.resolved_path();
    let (checked_socket, recordings, starting) = match asker {
        Asker::CheckConfig => (true, true, false),
        Asker::Run { socket_given } => (!socket_given, false, true),
    };
    preflight(
        cfg,
        &Preflight {
            socket: checked_socket.then_some(socket.as_path()),
            recordings,
            starting,
        },
    )
}

/// `file:line:col: field `f`: what` lines for the findings of one severity
/// (warnings say so after the field).
pub fn located_findings(
    path: &Path,
    text: &str,
    findings: &[Finding],
    severity: Severity,
) -> String {
    let problems = findings
        .iter()
        .filter(|f| f.severity == severity)
        .map(|f| {
            let message = match severity {
                Severity::Error => f.message.clone(),
                Severity::Warning => format!("warning: {}", f.message),
            };
            (f.field.clone(), message)
        })
        .collect();
    crowdtouch::located::format_issues(path, &config::locate_issues(text, problems))
}

/// `check-config FILE`: the config's own errors; when there are none, what `run`
/// would meet starting with it (errors and warnings, at their fields); the `ok`
/// line when `run` would start.
pub fn check_config(file: &Path) -> Result<i32> {
    let (c, text) = match Config::load_with_text(file) {
        Ok(loaded) => loaded,
        Err(e) => return Ok(output::fail_with(1, format_args!("{e}"))),
    };
    let socket = c.socket.resolved_path();
    let mut findings = startup_findings(&c, Asker::CheckConfig);
    // The installed service's network (its unit and drop-ins) against the outputs.
    let root = std::env::var_os("CROWDTOUCH_ROOT").map_or_else(|| "/".into(), PathBuf::from);
    findings.extend(super::unit::unit_findings(&c, &root));
    let warnings = located_findings(file, &text, &findings, Severity::Warning);
    let errors = located_findings(file, &text, &findings, Severity::Error);
    if !errors.is_empty() {
        let both = [errors, warnings].join("\n");
        return Ok(output::fail_with(1, format_args!("{}", both.trim_end())));
    }
    if !warnings.is_empty() {
        errln!("{warnings}")?;
    }
    let scene = match c.loaded_scene() {
        Some(s) => format!(", scene \"{}\"", s.name()),
        None => String::new(),
    };
    outln!(
        "{}: ok ({} agents, {} input{}, socket {}{scene})",
        file.display(),
        c.crowd.agents,
        c.inputs.len(),
        if c.inputs.len() == 1 { "" } else { "s" },
        socket.display()
    )?;
    if let Some(line) = TouchSources::of(&c).without_device() {
        outln!("{line}")?;
    }
    Ok(0)
}
