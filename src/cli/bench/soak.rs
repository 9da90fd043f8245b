//! `crowdtouch bench soak`: a long unattended run of the real daemon.
//!
//! The daemon runs in this process on a config file written for the run (the
//! embedded default with `--agents`): the shipped recordings replay at 120 Hz,
//! looped. Socket clients connect as renderers do (`clients.rs`): one handshakes and
//! never reads, one reconnects every second, the rest read continuously, and with
//! `--churn` one more connects and closes as fast as the daemon answers. Once a
//! period (a minute by default) the process raises SIGHUP on itself and the
//! supervisor's reload path (`reload_on_sighup`, what `crowdtouch run` does on
//! SIGHUP) reads the file again and hands it to the daemon; three times a period
//! the crowd is resized between `--agents` and half of it with the
//! `set_agent_count` command. Each period gives one row: RSS, latency, snapshots,
//! drops, lost touch transitions, and whether every thread's counters moved. The
//! checks at the end are listed in docs/commands.md ("bench soak").

mod clients;
mod report;

use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use clients::{ChurnTally, Clients, ReadTally, StallTally};
use crowdtouch::config::{Config, DEFAULT_CONFIG_RON};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use report::{print_table, Check, ReaderRow, Report, Row, Threads};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// What a soak is asked to do.
#[derive(Clone, Debug)]
pub struct SoakArgs {
    /// Length of the run (minutes; fractions allowed).
    pub minutes: f64,
    /// Agents of the crowd (resized to half of it and back during the run).
    pub agents: u32,
    /// Socket clients: one stalled, one reconnecting, the rest reading.
    pub clients: u32,
    /// One more client that connects and closes over and over.
    pub churn: bool,
    /// Length of one report row (s): 60 in a real soak.
    pub period_s: f64,
    /// Real-time scheduling and locked memory as configured (else off).
    pub realtime: bool,
    /// Machine-readable report.
    pub json: bool,
}

/// RSS may grow by this fraction over the first period's figure.
pub const RSS_GROWTH_LIMIT: f64 = 0.05;
/// A period's p99 latency may be at most this multiple of the median of the
/// periods' p99s.
pub const P99_LIMIT: f64 = 2.0;

fn quantiles(mut v: Vec<u64>) -> (u64, u64, u64) {
    if v.is_empty() {
        return (0, 0, 0);
    }
    v.sort_unstable();
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.99), v[v.len() - 1])
}

/// Connections the daemon must accept beyond the soak's `--clients`: the command
/// connection, a reconnect and a churning connection not yet reaped, and spare.
const SPARE_CLIENTS: u32 = 8;

/// The config file of the run: the embedded default with `agents`, room for
/// `clients` (`socket.max_clients`), quiet logging, real time off unless asked;
/// `generation` goes into a comment so every reload reads a file that changed.
fn config_text(agents: u32, clients: u32, realtime: bool, generation: u64) -> Result<String> {
    let mut text = DEFAULT_CONFIG_RON.to_string();
    let mut edit = |from: &str, to: &str| -> Result<()> {
        anyhow::ensure!(
            text.contains(from),
            "the embedded config has no `{from}` to replace"
        );
        text = text.replacen(from, to, 1);
        Ok(())
    };
    edit("agents: 100,", &format!("agents: {agents},"))?;
    edit("log_level: info,", "log_level: error,")?;
    let max_clients = clients.saturating_add(SPARE_CLIENTS).max(32);
    edit("max_clients: 32,", &format!("max_clients: {max_clients},"))?;
    if !realtime {
        edit("priority: Some(20),", "priority: None,")?;
        edit("lock_memory: true,", "lock_memory: false,")?;
    }
    text.push_str(&format!(
        "\n// bench soak: written for reload {generation}\n"
    ));
    Ok(text)
}

/// Counters read at a period's boundary.
#[derive(Clone, Copy, Default)]
struct Mark {
    frames: u64,
    coalesced: u64,
    lost: u64,
    ticks: u64,
    written: u64,
    dropped: u64,
}

fn mark(d: &Daemon, ticks: u64) -> Mark {
    let input = d.input_counters();
    let p = d.publisher_stats();
    Mark {
        frames: input.frames.load(Ordering::Relaxed),
        coalesced: input.coalesced.load(Ordering::Relaxed),
        lost: input.transitions_lost.load(Ordering::Relaxed),
        ticks,
        written: p.snapshots_sent(),
        dropped: p.snapshots_dropped(),
    }
}

/// Runs the soak, prints the report, and fails when a check failed.
pub fn soak(a: SoakArgs) -> Result<()> {
    anyhow::ensure!(
        a.minutes > 0.0 && a.minutes.is_finite(),
        "--minutes must be positive"
    );
    anyhow::ensure!(
        a.period_s >= 1.0 && a.period_s.is_finite(),
        "--period-seconds must be at least 1"
    );
    anyhow::ensure!(a.agents >= 2, "--agents must be at least 2 for a soak");
    crate::cli::common::process::init_logging(crowdtouch::config::LogLevel::Error);
    let dir = std::env::temp_dir().join(format!("crowdtouch-soak-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let cfg_path = dir.join("crowdtouch.ron");
    let sock = dir.join("crowdtouch.sock");
    let result = run(&a, &cfg_path, &sock);
    let _ = std::fs::remove_dir_all(&dir);
    let report = result?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        print_table(&report)?;
    }
    let failed: Vec<_> = report.checks.iter().filter(|c| !c.ok).collect();
    if !failed.is_empty() {
        bail!(
            "soak: {} check(s) failed: {}",
            failed.len(),
            failed.iter().map(|c| c.name).collect::<Vec<_>>().join(", ")
        );
    }
    Ok(())
}

fn run(a: &SoakArgs, cfg_path: &Path, sock: &Path) -> Result<Report> {
    let write_config = |generation: u64| -> Result<()> {
        std::fs::write(
            cfg_path,
            config_text(a.agents, a.clients, a.realtime, generation)?,
        )
        .with_context(|| format!("writing {}", cfg_path.display()))
    };
    write_config(0)?;
    let sig = crate::cli::common::process::signals()?;
    let cfg = Config::load(cfg_path)?;
    let sources = sources_from_config(&cfg)?;
    let mut daemon = Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path: sock.to_path_buf(),
            collect: None,
        },
    )?;
    let socket: PathBuf = daemon.socket_path().to_path_buf();
    let clients = match Clients::start(&socket, a.clients, a.churn) {
        Ok(c) => c,
        Err(e) => {
            daemon.shutdown();
            return Err(e);
        }
    };
    // Whole periods only: a run shorter than a period is one period of its length.
    let (period, total) = whole_periods(a.minutes * 60.0, a.period_s);
    let start = Instant::now();
    let mut rows = Vec::new();
    let mut ticks = 0u64;
    let mut agents = a.agents;
    let mut before = mark(&daemon, 0);
    let mut period_start = start;
    let mut row = PeriodEvents::default();
    let mut next_resize = 1u32;
    let mut reloaded_this_period = false;
    let mut interrupted = false;
    let mut command_id = 0u64;
    let mut generation = 0u64;
    while start.elapsed() < total {
        if sig.stop.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        if let Some(r) = daemon.next_report(Duration::from_millis(200)) {
            ticks = r.ticks;
            agents = r.agents;
            row.clients_max = row.clients_max.max(r.clients);
            for s in &r.stages {
                match s.stage.as_str() {
                    "assignment" => row.solves += s.count,
                    "end_to_end" => row.e2e_p99_worst = row.e2e_p99_worst.max(s.p99_us),
                    _ => {}
                }
            }
        }
        let into = period_start.elapsed().as_secs_f64() / period.as_secs_f64();
        // Resizes at 1/6, 3/6 and 5/6 of a period: --agents, half, --agents, …
        if next_resize <= 5 && into >= f64::from(next_resize) / 6.0 {
            next_resize += 2;
            let count = if row.resize_to_half {
                a.agents / 2
            } else {
                a.agents
            };
            row.resize_to_half = !row.resize_to_half;
            command_id += 1;
            let body = format!("\"name\":\"set_agent_count\",\"count\":{count}");
            match clients::command(&socket, command_id, &body) {
                Ok(()) => row.resizes += 1,
                Err(e) => {
                    log::error!("soak: resize to {count}: {e:#}");
                    row.resize_failures += 1;
                }
            }
        }
        // SIGHUP at 2/3 of a period, raised on this process: the handler sets the
        // flag the supervisor loop watches, as for `kill -HUP`.
        if !reloaded_this_period && into >= 2.0 / 3.0 {
            reloaded_this_period = true;
            generation += 1;
            write_config(generation)?;
            signal_hook::low_level::raise(signal_hook::consts::SIGHUP).context("raising SIGHUP")?;
        }
        if sig.reload.swap(false, Ordering::Relaxed)
            && crate::cli::common::process::reload_on_sighup(&mut daemon, Some(cfg_path))
        {
            row.reloads += 1;
        }
        let end_of_run = start.elapsed() >= total;
        if period_start.elapsed() >= period || end_of_run {
            let now = mark(&daemon, ticks);
            rows.push(make_row(
                rows.len() + 1,
                start.elapsed().as_secs_f64(),
                &before,
                &now,
                &row,
                &clients,
                agents,
            ));
            before = now;
            let half = row.resize_to_half;
            row = PeriodEvents {
                resize_to_half: half,
                ..PeriodEvents::default()
            };
            period_start = Instant::now();
            next_resize = 1;
            reloaded_this_period = false;
        }
    }
    clients.stopping();
    daemon.shutdown();
    clients.join();
    Ok(finish(a, rows, generation, interrupted))
}

/// The period and the run's length for `seconds` of soak in periods of `period_s`:
/// the run is rounded down to whole periods, and a run shorter than one period is
/// a single period of its own length.
fn whole_periods(seconds: f64, period_s: f64) -> (Duration, Duration) {
    let period = period_s.min(seconds);
    let n = (seconds / period + 1e-9).floor().max(1.0);
    (
        Duration::from_secs_f64(period),
        Duration::from_secs_f64(period * n),
    )
}

/// What the driver itself counted during a period.
#[derive(Default)]
struct PeriodEvents {
    solves: u64,
    e2e_p99_worst: u64,
    clients_max: u32,
    reloads: u64,
    resizes: u64,
    resize_failures: u64,
    /// The next resize goes to half of `--agents`.
    resize_to_half: bool,
}

fn make_row(
    period: usize,
    t_s: f64,
    before: &Mark,
    now: &Mark,
    ev: &PeriodEvents,
    clients: &Clients,
    agents: u32,
) -> Row {
    let readers: Vec<ReadTally> = clients.readers.iter().map(|r| r.take()).collect();
    let reconnecting = clients.reconnecting.take();
    let stalled: StallTally = clients.stalled.take();
    let churn: ChurnTally = clients.churn.as_ref().map(|c| c.take()).unwrap_or_default();
    // The first reader has a thread of its own; the others share one polling thread,
    // whose turn-taking would be part of their figures.
    let latency: Vec<u64> = readers
        .first()
        .map(|r| r.latency_us.clone())
        .unwrap_or_default();
    let samples = latency.len() as u64;
    let (p50, p99, max) = quantiles(latency);
    let dropped_total = now.dropped - before.dropped;
    let told: u64 = readers.iter().map(|r| r.dropped).sum::<u64>() + reconnecting.dropped;
    let threads = Threads {
        input_frames: now.frames - before.frames,
        control_ticks: now.ticks - before.ticks,
        assignment_solves: ev.solves,
        publisher_snapshots_written: now.written - before.written,
    };
    Row {
        period,
        t_s,
        rss_mb: crowdtouch::pipeline::timing::rss_bytes().unwrap_or(0) as f64 / 1e6,
        latency_samples: samples,
        latency_p50_us: p50,
        latency_p99_us: p99,
        latency_max_us: max,
        daemon_e2e_p99_worst_us: ev.e2e_p99_worst,
        published: now.ticks - before.ticks,
        readers: readers.iter().map(ReaderRow::from).collect(),
        reconnecting: ReaderRow::from(&reconnecting),
        churn_cycles: churn.cycles,
        churn_failed: churn.failed,
        stalled_connections: stalled.connections,
        stalled_disconnected: stalled.disconnected,
        stalled_dropped: dropped_total.saturating_sub(told),
        dropped_total,
        transitions_lost: now.lost - before.lost,
        frames_coalesced: now.coalesced - before.coalesced,
        stalled_threads: threads.stalled(),
        threads,
        daemon_clients_max: ev.clients_max,
        reloads: ev.reloads,
        resizes: ev.resizes,
        resize_failures: ev.resize_failures,
        agents,
    }
}

/// The checks over the rows (the rules are in docs/commands.md, "bench soak").
fn finish(a: &SoakArgs, periods: Vec<Row>, sighups: u64, interrupted: bool) -> Report {
    let rss_first = periods.first().map_or(0.0, |r| r.rss_mb);
    let rss_last = periods.last().map_or(0.0, |r| r.rss_mb);
    let rss_max = periods
        .iter()
        .skip(1)
        .map(|r| r.rss_mb)
        .fold(rss_first, f64::max);
    let limit = rss_first * (1.0 + RSS_GROWTH_LIMIT);
    let mut p99s: Vec<u64> = periods.iter().map(|r| r.latency_p99_us).collect();
    p99s.sort_unstable();
    let median = if p99s.is_empty() {
        0
    } else if p99s.len() % 2 == 1 {
        p99s[p99s.len() / 2]
    } else {
        (p99s[p99s.len() / 2 - 1] + p99s[p99s.len() / 2]) / 2
    };
    let over: Vec<String> = periods
        .iter()
        .filter(|r| r.latency_p99_us as f64 > P99_LIMIT * median as f64)
        .map(|r| format!("period {} p99 {} µs", r.period, r.latency_p99_us))
        .collect();
    let lost: u64 = periods.iter().map(|r| r.transitions_lost).sum();
    let sum = |f: &dyn Fn(&ReaderRow) -> u64| -> u64 {
        periods
            .iter()
            .map(|r| r.readers.iter().map(f).sum::<u64>() + f(&r.reconnecting))
            .sum()
    };
    let (missed, silent, reordered) = (
        sum(&|r| r.missed),
        sum(&|r| r.silent),
        sum(&|r| r.reordered),
    );
    let lost_conn = sum(&|r| r.lost_connection);
    // A churning connection may also be counted before it is reaped.
    let clients_limit = a.clients + 2 + u32::from(a.churn);
    let crowded: Vec<String> = periods
        .iter()
        .filter(|r| r.daemon_clients_max > clients_limit)
        .map(|r| format!("period {}: {}", r.period, r.daemon_clients_max))
        .collect();
    let idle: Vec<String> = periods
        .iter()
        .flat_map(|r| {
            let mut v: Vec<String> = r
                .readers
                .iter()
                .enumerate()
                .filter(|(_, x)| x.read == 0)
                .map(|(i, _)| format!("period {}: reader {i} read nothing", r.period))
                .collect();
            if r.reconnecting.read == 0 {
                v.push(format!(
                    "period {}: the reconnecting client read nothing",
                    r.period
                ));
            }
            v
        })
        .collect();
    let stalls: Vec<String> = periods
        .iter()
        .filter(|r| !r.stalled_threads.is_empty())
        .map(|r| format!("period {}: {}", r.period, r.stalled_threads.join(", ")))
        .collect();
    let resize_failures: u64 = periods.iter().map(|r| r.resize_failures).sum();
    let reloads: u64 = periods.iter().map(|r| r.reloads).sum();
    let checks = vec![
        Check {
            name: "rss_flat",
            ok: rss_max <= limit,
            detail: format!(
                "first period {rss_first:.1} MB, largest after it {rss_max:.1} MB, limit {limit:.1} MB (+{:.0} %)",
                RSS_GROWTH_LIMIT * 100.0
            ),
        },
        Check {
            name: "no_lost_transitions",
            ok: lost == 0,
            detail: format!("{lost} touch transitions lost"),
        },
        Check {
            name: "live_readers_get_every_snapshot",
            ok: missed == 0 && reordered == 0 && lost_conn == 0 && idle.is_empty(),
            detail: format!(
                "{missed} snapshots missed by live readers ({silent} of them not announced by `dropped`), {reordered} out of order, {lost_conn} connections lost{}{}",
                if idle.is_empty() { "" } else { "; " },
                idle.join("; ")
            ),
        },
        Check {
            name: "clients_reaped",
            ok: crowded.is_empty(),
            detail: format!(
                "the daemon counted at most {} clients (limit {clients_limit}: the soak's {}, its command connection and one reconnect{} not yet reaped){}{}",
                periods.iter().map(|r| r.daemon_clients_max).max().unwrap_or(0),
                a.clients,
                if a.churn { " and one churning connection" } else { "" },
                if crowded.is_empty() { "" } else { "; over: " },
                crowded.join(", ")
            ),
        },
        Check {
            name: "threads_advance",
            ok: stalls.is_empty(),
            detail: if stalls.is_empty() {
                "input, control, assignment worker and publisher moved every period".into()
            } else {
                stalls.join("; ")
            },
        },
        Check {
            name: "p99_steady",
            ok: over.is_empty(),
            detail: format!(
                "median of the periods' p99s {median} µs, limit {:.0} µs{}{}",
                P99_LIMIT * median as f64,
                if over.is_empty() { "" } else { "; over: " },
                over.join(", ")
            ),
        },
        Check {
            name: "resizes_and_reloads",
            ok: resize_failures == 0 && reloads == sighups,
            detail: format!(
                "{resize_failures} set_agent_count commands refused or unanswered; {reloads} of {sighups} SIGHUPs reloaded the config"
            ),
        },
    ];
    let ok = checks.iter().all(|c| c.ok);
    Report {
        agents: a.agents,
        clients: a.clients,
        churn: a.churn,
        minutes: a.minutes,
        period_s: a.period_s,
        realtime: crowdtouch::rt::realtime_granted(),
        interrupted,
        rss_first_mb: rss_first,
        rss_last_mb: rss_last,
        p99_median_us: median,
        periods,
        checks,
        ok,
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_are_whole_periods() {
        let secs = |(p, t): (Duration, Duration)| (p.as_secs_f64(), t.as_secs_f64());
        assert_eq!(secs(whole_periods(3600.0, 60.0)), (60.0, 3600.0));
        assert_eq!(secs(whole_periods(20.4, 5.0)), (5.0, 20.0));
        assert_eq!(secs(whole_periods(15.0, 60.0)), (15.0, 15.0));
    }

    #[test]
    fn the_run_config_loads_with_the_asked_crowd() {
        let text = config_text(1000, 40, false, 3).unwrap();
        let cfg = Config::from_str(&text, Path::new("soak.ron")).unwrap();
        assert_eq!(cfg.crowd.agents, 1000);
        assert_eq!(cfg.socket.max_clients, 48);
        assert_eq!(cfg.pipeline.realtime.priority, None);
        assert!(!cfg.pipeline.realtime.lock_memory);
        assert!(text.ends_with("reload 3\n"));
    }
}
