//! `bench soak`'s report: a row per period (RSS, latency, snapshots, drops, every
//! thread's counters, the clients' figures), the checks of the run, and the table
//! printed without `--json`.

use super::clients::ReadTally;
use crate::cli::common::output::outln;
use anyhow::Result;
use serde::Serialize;

/// A reading client's figures for one period.
#[derive(Serialize, Debug, Clone)]
pub struct ReaderRow {
    pub connections: u64,
    pub read: u64,
    pub missed: u64,
    pub silent: u64,
    pub dropped: u64,
    pub reordered: u64,
    pub lost_connection: u64,
}

impl From<&ReadTally> for ReaderRow {
    fn from(t: &ReadTally) -> Self {
        ReaderRow {
            connections: t.connections,
            read: t.read,
            missed: t.missed,
            silent: t.silent,
            dropped: t.dropped,
            reordered: t.reordered,
            lost_connection: t.lost_connection,
        }
    }
}

/// How far each thread's counters moved in one period.
#[derive(Serialize, Debug, Clone, Default)]
pub struct Threads {
    /// Frames the input thread queued.
    pub input_frames: u64,
    /// Control ticks (one snapshot published each).
    pub control_ticks: u64,
    /// Solves the assignment worker finished.
    pub assignment_solves: u64,
    /// Snapshots the socket output wrote to clients.
    pub publisher_snapshots_written: u64,
}

impl Threads {
    /// The threads whose counter did not move.
    pub fn stalled(&self) -> Vec<&'static str> {
        [
            ("input", self.input_frames),
            ("control", self.control_ticks),
            ("assignment worker", self.assignment_solves),
            ("publisher", self.publisher_snapshots_written),
        ]
        .into_iter()
        .filter(|(_, n)| *n == 0)
        .map(|(name, _)| name)
        .collect()
    }
}

/// One report period.
#[derive(Serialize, Debug, Clone)]
pub struct Row {
    /// 1-based period number.
    pub period: usize,
    /// Seconds since the start at the period's end.
    pub t_s: f64,
    /// RSS of the process (daemon and the soak's clients) at the period's end (MB).
    pub rss_mb: f64,
    /// Latency samples: snapshots with an input time read by the first reader.
    pub latency_samples: u64,
    /// Input → read by the first reader (a thread of its own), µs.
    pub latency_p50_us: u64,
    pub latency_p99_us: u64,
    pub latency_max_us: u64,
    /// Worst of the daemon's own per-second end-to-end p99 (input → bytes written).
    pub daemon_e2e_p99_worst_us: u64,
    /// Snapshots the control thread published (ticks).
    pub published: u64,
    /// Each continuously reading client.
    pub readers: Vec<ReaderRow>,
    /// The client that reconnects every second (gaps counted within a connection).
    pub reconnecting: ReaderRow,
    /// Connect/close cycles of the churning client (`--churn`), and failed ones.
    pub churn_cycles: u64,
    pub churn_failed: u64,
    /// Connections of the stalled client, and how many the daemon closed.
    pub stalled_connections: u64,
    pub stalled_disconnected: u64,
    /// Snapshots the daemon dropped for the stalled client: every drop the socket
    /// output counted minus those the other clients were told about.
    pub stalled_dropped: u64,
    /// Every snapshot drop the socket output counted.
    pub dropped_total: u64,
    /// Touch-down and lift transitions lost on the input queue.
    pub transitions_lost: u64,
    /// Motion frames coalesced on the input queue (allowed).
    pub frames_coalesced: u64,
    pub threads: Threads,
    /// Threads whose counter did not move this period.
    pub stalled_threads: Vec<&'static str>,
    /// Most clients the daemon counted in one stats report of the period.
    pub daemon_clients_max: u32,
    /// Config reloads handed to the daemon by the SIGHUP path.
    pub reloads: u64,
    /// Crowd resizes acknowledged (and refused or unanswered ones).
    pub resizes: u64,
    pub resize_failures: u64,
    /// Agents at the period's end.
    pub agents: u32,
}

/// One check of the run.
#[derive(Serialize, Debug, Clone)]
pub struct Check {
    pub name: &'static str,
    pub ok: bool,
    pub detail: String,
}

/// The whole report (`--json`).
#[derive(Serialize, Debug)]
pub struct Report {
    pub agents: u32,
    pub clients: u32,
    pub churn: bool,
    pub minutes: f64,
    pub period_s: f64,
    pub realtime: bool,
    pub interrupted: bool,
    pub periods: Vec<Row>,
    pub rss_first_mb: f64,
    pub rss_last_mb: f64,
    pub p99_median_us: u64,
    pub checks: Vec<Check>,
    pub ok: bool,
}

pub fn print_table(r: &Report) -> Result<()> {
    outln!(
        "bench soak: {} agents (resized to {} and back), {} clients{}, {} min, {} s periods, SCHED_FIFO {}",
        r.agents,
        r.agents / 2,
        r.clients,
        if r.churn { " and connect/close churn" } else { "" },
        r.minutes,
        r.period_s,
        if r.realtime { "on" } else { "off" }
    )?;
    outln!(
        "{:>4} {:>7} {:>8} {:>8} {:>8} {:>9} {:>8} {:>6} {:>13} {:>10} {:>11} {:>9} {:>5} {:>7} {:>4} {:>4} {:>7}",
        "per", "RSS MB", "p50 ms", "p99 ms", "max ms", "dmn p99", "publ", "miss", "read/reader", "recon", "stall drop", "drops all", "lost", "threads", "hup", "rsz", "churn"
    )?;
    for p in &r.periods {
        let reads: Vec<String> = p.readers.iter().map(|x| x.read.to_string()).collect();
        let missed: u64 = p.readers.iter().map(|x| x.missed).sum::<u64>() + p.reconnecting.missed;
        outln!(
            "{:>4} {:>7.1} {:>8.2} {:>8.2} {:>8.2} {:>9.2} {:>8} {:>6} {:>13} {:>10} {:>11} {:>9} {:>5} {:>7} {:>4} {:>4} {:>7}",
            p.period,
            p.rss_mb,
            p.latency_p50_us as f64 / 1e3,
            p.latency_p99_us as f64 / 1e3,
            p.latency_max_us as f64 / 1e3,
            p.daemon_e2e_p99_worst_us as f64 / 1e3,
            p.published,
            missed,
            reads.join("/"),
            format!("{}/{}", p.reconnecting.connections, p.reconnecting.read),
            format!("{}/{}d", p.stalled_dropped, p.stalled_disconnected),
            p.dropped_total,
            p.transitions_lost,
            if p.stalled_threads.is_empty() { "ok" } else { "STALL" },
            p.reloads,
            p.resizes,
            p.churn_cycles,
        )?;
    }
    outln!(
        "RSS {:.1} → {:.1} MB; p99 median {:.2} ms",
        r.rss_first_mb,
        r.rss_last_mb,
        r.p99_median_us as f64 / 1e3
    )?;
    outln!(
        "latency: input → read by the first reader (p50/p99/max); dmn p99: the worst per-second p99 the daemon measured (input → bytes written); recon: connections/snapshots; stall drop: snapshots dropped for the stalled client / times the daemon disconnected it"
    )?;
    for c in &r.checks {
        outln!(
            "{} {}: {}",
            if c.ok { "ok  " } else { "FAIL" },
            c.name,
            c.detail
        )?;
    }
    Ok(())
}
