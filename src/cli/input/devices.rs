//! `crowdtouch devices`: the touch devices on this machine, and which one `run` picks.

use crate::cli::common::output::outln;
use anyhow::Result;
use crowdtouch::config::{Config, InputConfig};
use crowdtouch::input::discover::{discover, select, Found};
use crowdtouch::pipeline::device::{preference, selector, SystemProber};
use std::path::Path;

/// Lists touch devices; `--json` for scripts.
pub fn devices(cfg: &Config, json: bool, root: &Path) -> Result<()> {
    let found = discover(root, &SystemProber);
    let picks: Vec<(usize, Result<&Found, String>)> = cfg
        .inputs
        .iter()
        .enumerate()
        .filter_map(|(i, input)| match input {
            InputConfig::Device {
                select: sel,
                interface,
                ..
            } => Some((
                i,
                select(&found, &selector(sel), preference(*interface)).map_err(|e| e.to_string()),
            )),
            InputConfig::Replay { .. } | InputConfig::Tuio { .. } => None,
        })
        .collect();
    let auto = select(
        &found,
        &selector(&Default::default()),
        preference(Default::default()),
    )
    .ok();
    if json {
        let list: Vec<serde_json::Value> = found
            .iter()
            .map(|f| {
                let mut v = serde_json::to_value(&f.info).unwrap_or_default();
                v["udev_processed"] = serde_json::json!(f.processed);
                v["probe_error"] = serde_json::json!(f.probe_error);
                v["picked_by_inputs"] = serde_json::json!(picks
                    .iter()
                    .filter(|(_, p)| p
                        .as_ref()
                        .is_ok_and(|p| p.info.identity.node == f.info.identity.node))
                    .map(|(i, _)| *i)
                    .collect::<Vec<_>>());
                v["auto"] = serde_json::json!(
                    auto.is_some_and(|a| a.info.identity.node == f.info.identity.node)
                );
                v
            })
            .collect();
        outln!("{}", serde_json::to_string_pretty(&list)?)?;
        return Ok(());
    }
    if found.is_empty() {
        outln!(
            "no touch devices found (looked at {} and {})",
            root.join("dev/input/event*").display(),
            root.join("dev/hidraw*").display()
        )?;
    }
    for f in &found {
        let i = &f.info;
        let mark = if auto.is_some_and(|a| a.info.identity.node == i.identity.node) {
            "*"
        } else {
            " "
        };
        outln!(
            "{mark} {:<20} {:<6} {:04x}:{:04x}  {}",
            i.identity.node.display(),
            i.identity.kind.as_str(),
            i.identity.vendor,
            i.identity.product,
            i.identity.name
        )?;
        outln!(
            "      id {}{}",
            i.stable_id,
            if f.processed {
                ""
            } else {
                " (udev has not processed it yet)"
            }
        )?;
        match &f.probe_error {
            Some(e) => outln!("      cannot open: {e}")?,
            None => {
                let s = &i.surface;
                let size = s
                    .size_mm()
                    .map(|(w, h)| format!(", {w:.0} × {h:.0} mm"))
                    .unwrap_or_default();
                outln!(
                    "      {} contacts, x {}..{} y {}..{} (resolution {}/{} units/mm{size}), {}{}",
                    s.max_contacts,
                    s.x.min,
                    s.x.max,
                    s.y.min,
                    s.y.max,
                    s.x.resolution,
                    s.y.resolution,
                    if i.direct { "touchscreen" } else { "touchpad" },
                    if i.calibration.is_some() {
                        ", udev calibration matrix"
                    } else {
                        ""
                    }
                )?;
            }
        }
    }
    outln!()?;
    match auto {
        Some(a) => outln!(
            "* = what select: Auto picks: {}",
            a.info.identity.node.display()
        )?,
        None => outln!("select: Auto picks nothing here")?,
    }
    for (i, p) in &picks {
        match p {
            Ok(f) => outln!(
                "inputs[{i}] of the config reads {} ({})",
                f.info.identity.node.display(),
                f.info.identity.name
            )?,
            Err(e) => outln!("inputs[{i}] of the config finds nothing: {e}")?,
        }
    }
    Ok(())
}
