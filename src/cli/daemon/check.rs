//! `crowdtouch check-config FILE`: the config's own errors, and what `run` would
//! refuse at start-up with it, each at its field.

use crate::cli::common::output::{self, errln, outln};
use anyhow::Result;
use crowdtouch::config::{self, Config};
use crowdtouch::pipeline::{preflight, Finding, Preflight, Severity};
use std::path::{Path, PathBuf};

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
    let mut findings = preflight(
        &c,
        &Preflight {
            socket: Some(&socket),
            recordings: true,
            starting: false,
        },
    );
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
    Ok(0)
}
