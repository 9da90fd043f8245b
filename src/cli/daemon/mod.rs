//! The daemon family: `run`, `demo`, `check-config`, `doctor` and the service's
//! network drop-in (`unit-network`).

pub mod check;
pub mod doctor;
pub mod doctor_check;
pub mod doctor_daemon;
pub mod doctor_device;
pub mod doctor_network;
pub mod unit;

use crate::cli::common::config::{find_config_with_text, set_agents};
use crate::cli::common::output::{self, outln};
use crate::cli::common::process::{
    demo_websocket, init_logging, signals, start_daemon, status_line, supervise,
};
use anyhow::{bail, Result};
use clap::Args;
use crowdtouch::config::{self, Config};
use crowdtouch::pipeline::{Severity, TouchSources};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Config file (default: the search path above).
    #[arg(long, short)]
    pub config: Option<PathBuf>,
    /// Socket path (overrides the config).
    #[arg(long)]
    pub socket: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Number of agents.
    #[arg(long)]
    pub agents: Option<u32>,
    /// Socket path (default: $XDG_RUNTIME_DIR/crowdtouch.sock).
    #[arg(long)]
    pub socket: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Also send the crowd as TUIO 1.1 over UDP to HOST:PORT (touches, agents and
    /// controls: a privileged target, as the demo's touches are synthetic).
    #[arg(long, value_name = "HOST:PORT")]
    pub tuio: Option<String>,
    /// Also serve the live viewer and the WebSocket stream on ADDR (ip:port),
    /// privileged; beyond loopback only with --token.
    #[arg(long, value_name = "ADDR")]
    pub http: Option<String>,
    /// The token WebSocket clients must present with --http (16+ characters).
    #[arg(long, requires = "http")]
    pub token: Option<String>,
    /// A host name the viewer is opened by (`kiosk-7` or `kiosk-7:8080`), besides
    /// the listen address (and `localhost` on loopback); repeatable. Requests
    /// naming any other host are refused (421): the guard against DNS rebinding.
    #[arg(long = "host", value_name = "NAME", requires = "http")]
    pub hosts: Vec<String>,
    /// Also serve the newest stats as Prometheus text at /metrics beside the
    /// viewer (with --token when one is given).
    #[arg(long, requires = "http")]
    pub metrics: bool,
}

pub fn run(a: RunArgs) -> Result<()> {
    // Handlers first: a SIGHUP or SIGTERM during start-up must not kill the process.
    let sig = signals()?;
    let (cfg, path, text) = find_config_with_text(a.config.as_deref())?;
    init_logging(cfg.log_level);
    match &path {
        Some(p) => log::info!("config {}", p.display()),
        None => log::info!(
            "no config file found (looked in {}); using the embedded default",
            config::search_path()
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
    // What check-config reports, at the config's fields. The socket is checked here
    // only when it is the config's (`--socket` is checked when it is bound), and the
    // recordings when they are read next.
    let findings = check::startup_findings(
        &cfg,
        check::Asker::Run {
            socket_given: a.socket.is_some(),
        },
    );
    let shown = path.clone().unwrap_or_else(|| PathBuf::from("<embedded>"));
    let warnings = check::located_findings(&shown, &text, &findings, Severity::Warning);
    for w in warnings.lines() {
        log::warn!("{w}");
    }
    let errors = check::located_findings(&shown, &text, &findings, Severity::Error);
    if !errors.is_empty() {
        bail!("the config cannot be run:\n{errors}");
    }
    let touch = TouchSources::of(&cfg).without_device();
    let daemon = start_daemon(cfg, a.socket)?;
    log::info!("listening on {}", daemon.socket_path().display());
    if let Some(line) = touch {
        log::info!("{line}");
    }
    supervise(sig, daemon, path, None, |r| {
        log::debug!("{}", status_line(r));
        Ok(())
    })
}

pub fn demo(a: DemoArgs) -> Result<()> {
    let sig = signals()?;
    let mut cfg = Config::embedded_default();
    init_logging(cfg.log_level);
    set_agents(&mut cfg, a.agents)?;
    if let Some(target) = &a.tuio {
        cfg.outputs.push(demo_tuio(target));
        if let Some((_, why)) = cfg
            .validate()
            .into_iter()
            .find(|(f, _)| f.starts_with("outputs"))
        {
            anyhow::bail!("--tuio {target}: {why}");
        }
    }
    if let Some(addr) = &a.http {
        cfg.outputs
            .push(demo_websocket(addr, a.token.clone(), &a.hosts, a.metrics)?);
    }
    let daemon = start_daemon(cfg, a.socket)?;
    // From here on, every way out (a line that cannot be written included) stops
    // the daemon and removes its socket.
    let path = daemon.socket_path().display().to_string();
    outln!("crowdtouch demo: serving the crowd on {path}")?;
    if let Some(target) = &a.tuio {
        outln!("  TUIO 1.1:   to {target} (/tuio/2Dcur touches, /tuio/2Dobj agents, /tuio/2Dblb controls)")?;
    }
    if let Some(addr) = &a.http {
        let query = output::token_query(a.token.as_deref());
        outln!("  viewer:     http://{addr}/{query}")?;
        if a.metrics {
            outln!("  metrics:    http://{addr}/metrics")?;
        }
        for h in &a.hosts {
            let port = addr.rsplit_once(':').map_or("", |(_, p)| p);
            let shown = if h.contains(':') && !h.ends_with(']') {
                h.clone()
            } else {
                format!("{h}:{port}")
            };
            outln!("              http://{shown}/{query}")?;
        }
    }
    outln!("  watch it:   crowdtouch watch --socket {path}   (or: cargo run --release -- watch --socket {path})")?;
    outln!("  raw stream: socat - UNIX-CONNECT:{path}")?;
    outln!("  Ctrl-C stops.")?;
    let until = a
        .seconds
        .map(|s| monotonic_now() + Micros::from_secs_f64(s));
    supervise(sig, daemon, None, until, |r| {
        outln!("{}", status_line(r))?;
        Ok(())
    })
}

/// The demo's TUIO output (`demo --tuio HOST:PORT`): TUIO 1.1 with every profile.
pub fn demo_tuio(target: &str) -> config::OutputConfig {
    config::OutputConfig::Tuio {
        target: target.to_string(),
        version: "1.1".to_string(),
        profiles: vec![
            config::TuioProfile::Cursors,
            config::TuioProfile::Objects,
            config::TuioProfile::Blobs,
        ],
        rate_hz: 60.0,
        max_datagram_bytes: 1472,
        source: None,
        privileged: true,
    }
}
