//! The daemon as a process: logging, signals, starting it from a config and the
//! supervisor loop (`run`, `demo`, `library collect`, `bench soak`), SIGHUP reloads,
//! the status line, and the viewer's WebSocket output the tools add.

use super::journal;
use super::running::Running;
use anyhow::{Context, Result};
use crowdtouch::config::{self, Config};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::{Micros, StatsReport};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Logs to stderr at `level` (as journal lines under systemd: `journal.rs`);
/// `RUST_LOG` overrides it. Without `RUST_LOG` the
/// logger passes everything and the level is `log`'s maximum, which a config
/// reload changes (`Daemon::reload`).
pub fn init_logging(level: config::LogLevel) {
    let mut b = env_logger::Builder::new();
    let spec = std::env::var("RUST_LOG").ok();
    match &spec {
        Some(spec) => {
            b.filter_level(level.filter());
            b.parse_filters(spec);
        }
        None => {
            b.filter_level(log::LevelFilter::Trace);
        }
    }
    b.format_target(false);
    if journal::stderr_is_journal() {
        journal::use_journal_format(&mut b);
    }
    if b.try_init().is_ok() && spec.is_none() {
        log::set_max_level(level.filter());
    }
}

/// Signal flags of a running daemon.
pub struct Signals {
    pub stop: Arc<AtomicBool>,
    pub reload: Arc<AtomicBool>,
}

pub fn signals() -> Result<Signals> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let s = Signals {
        stop: Arc::new(AtomicBool::new(false)),
        reload: Arc::new(AtomicBool::new(false)),
    };
    for sig in [SIGINT, SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&s.stop))
            .context("installing signal handlers")?;
    }
    signal_hook::flag::register(SIGHUP, Arc::clone(&s.reload))
        .context("installing SIGHUP handler")?;
    Ok(s)
}

/// The supervisor loop shared by `run` and `demo`: until SIGTERM/SIGINT, `until`,
/// or `on_report` fails (a status line that cannot be written); then stops the
/// daemon and returns that failure.
pub fn supervise(
    sig: Signals,
    mut daemon: Running,
    config_path: Option<PathBuf>,
    until: Option<Micros>,
    mut on_report: impl FnMut(&StatsReport) -> Result<()>,
) -> Result<()> {
    let mut watchdog_us = 0u64;
    let watchdog = sd_notify::watchdog_enabled(false, &mut watchdog_us);
    let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Ready]);
    let mut last_ping = monotonic_now();
    let mut finished: Option<Micros> = None;
    let mut outcome = Ok(());
    loop {
        if sig.stop.load(Ordering::Relaxed) || until.is_some_and(|u| monotonic_now() >= u) {
            break;
        }
        // A `library collect` session that asked for everything: a second for its
        // last events to reach the clients, then stop.
        if daemon.collect_finished() {
            let now = monotonic_now();
            if now.saturating_since(*finished.get_or_insert(now)) >= Micros(1_000_000) {
                break;
            }
        }
        if sig.reload.swap(false, Ordering::Relaxed) {
            reload_on_sighup(&mut daemon, config_path.as_deref());
        }
        if let Some(r) = daemon.next_report(Duration::from_millis(200)) {
            if let Err(e) = on_report(&r) {
                outcome = Err(e);
                break;
            }
        }
        // Feed the watchdog only while the control thread is ticking.
        if watchdog && monotonic_now().saturating_since(last_ping).0 * 2 >= watchdog_us {
            if daemon.heartbeat_age() < Micros(watchdog_us / 2) {
                let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Watchdog]);
            } else {
                log::error!(
                    "control thread stalled for {} — not feeding the watchdog",
                    daemon.heartbeat_age()
                );
            }
            last_ping = monotonic_now();
        }
    }
    let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Stopping]);
    log::info!("stopping");
    daemon.shutdown();
    outcome
}

/// What a SIGHUP does: reads the config file again and hands it to the daemon; a
/// config that does not load is reported and the running one stays. Returns whether
/// a new config was handed over (`bench soak` counts them).
pub fn reload_on_sighup(daemon: &mut Daemon, config_path: Option<&Path>) -> bool {
    match config_path {
        Some(p) => match Config::load(p) {
            Ok(c) => {
                log::info!("SIGHUP: reloading {}", p.display());
                daemon.reload(c);
                true
            }
            Err(e) => {
                log::error!(
                    "SIGHUP: new config rejected, the old config and scene keep running:\n{e}"
                );
                false
            }
        },
        None => {
            log::warn!("SIGHUP: running on the embedded default config; nothing to reload");
            false
        }
    }
}

/// Reads the config's inputs and starts the daemon on `socket` (or the config's).
pub fn start_daemon(cfg: Config, socket: Option<PathBuf>) -> Result<Running> {
    let socket_path = socket.unwrap_or_else(|| cfg.socket.resolved_path());
    let sources = sources_from_config(&cfg)?;
    Ok(Running(Some(Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path,
            collect: None,
        },
    )?)))
}

/// One status line: agents, controls, last gesture, latency, drops.
pub fn status_line(r: &StatsReport) -> String {
    let e2e = r
        .stages
        .iter()
        .find(|s| s.stage == "end_to_end")
        .filter(|s| s.count > 0);
    let latency = match e2e {
        Some(s) => format!(
            "p50 {:>5.2} ms p99 {:>5.2} ms",
            s.p50_us as f64 / 1000.0,
            s.p99_us as f64 / 1000.0
        ),
        None => "  - (no client yet)       ".to_string(),
    };
    let assign_per_s = r
        .stages
        .iter()
        .find(|s| s.stage == "assignment")
        .map(|s| s.count)
        .unwrap_or(0) as f64
        / (r.interval_us as f64 * 1e-6);
    format!(
        "agents {:>5} | controls {} | last: {:<28} | latency {latency} | assign {:>4.0}/s | clients {} | dropped snapshots {} touches {}",
        r.agents,
        r.controls,
        r.last_gesture.as_deref().unwrap_or("-"),
        assign_per_s,
        r.clients,
        r.snapshots_dropped,
        r.transitions_lost,
    )
}

/// `demo --http ADDR [--token T] [--host NAME]...`: a privileged WebSocket output
/// with the viewer.
pub fn demo_websocket(
    addr: &str,
    token: Option<String>,
    hosts: &[String],
    metrics: bool,
) -> Result<config::OutputConfig> {
    let hosts = hosts
        .iter()
        .map(|h| config::normalize_host(h).map_err(|why| anyhow::anyhow!("--host {h}: {why}")))
        .collect::<Result<Vec<_>>>()?;
    let parsed: std::net::SocketAddr = addr
        .parse()
        .map_err(|_| anyhow::anyhow!("--http {addr}: not ip:port, like 127.0.0.1:8080"))?;
    match &token {
        None if !config::is_loopback(parsed.ip()) => anyhow::bail!(
            "--http {addr} is reachable from other machines, and its clients may steer the \
             crowd: give --token SECRET (16+ characters), or listen on 127.0.0.1"
        ),
        Some(t) if t.len() < 16 || !t.chars().all(|c| c.is_ascii_graphic()) => {
            anyhow::bail!("--token: at least 16 printable ASCII characters, no spaces")
        }
        _ => {}
    }
    Ok(config::OutputConfig::WebSocket {
        listen: addr.to_string(),
        token,
        privileged: true,
        max_clients: 16,
        max_message_bytes: 64 * 1024,
        viewer: true,
        metrics,
        // The viewer is served by this output: its own origin is privileged, as
        // are clients that send no Origin; pages of other sites are refused.
        origins: vec![],
        privileged_origins: vec![],
        hosts,
    })
}
