//! Finding the config (`--config`, the search path, the embedded default) and the
//! overrides the commands apply to it.

use anyhow::{bail, Result};
use crowdtouch::config::{self, Config};
use std::path::{Path, PathBuf};

pub fn find_config(explicit: Option<&Path>) -> Result<(Config, Option<PathBuf>)> {
    find_config_with_text(explicit).map(|(cfg, path, _)| (cfg, path))
}

/// [`find_config`], with the text the config was read from (the embedded
/// default's for none).
pub fn find_config_with_text(explicit: Option<&Path>) -> Result<(Config, Option<PathBuf>, String)> {
    if let Some(p) = explicit {
        let (cfg, text) = Config::load_with_text(p)?;
        return Ok((cfg, Some(p.to_path_buf()), text));
    }
    for p in config::search_path() {
        if p.exists() {
            let (cfg, text) = Config::load_with_text(&p)?;
            return Ok((cfg, Some(p), text));
        }
    }
    Ok((
        Config::embedded_default(),
        None,
        config::DEFAULT_CONFIG_RON.to_string(),
    ))
}

/// Applies `--agents`, checked like the config field.
pub fn set_agents(cfg: &mut Config, agents: Option<u32>) -> Result<()> {
    if let Some(n) = agents {
        cfg.crowd.agents = n;
        if let Some((field, msg)) = cfg.validate().into_iter().next() {
            bail!("--agents: {field}: {msg}");
        }
    }
    Ok(())
}
