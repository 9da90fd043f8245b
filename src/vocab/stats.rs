//! Pipeline health: the figures published in `stats` messages.

use super::time::Micros;
use serde::{Deserialize, Serialize};

/// Timing of one pipeline stage over the last stats interval.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageStats {
    /// Stage name (`input`, `queue`, `control`, `publish`, `end_to_end`, ...).
    pub stage: String,
    /// Samples in the interval.
    pub count: u64,
    /// Median (µs).
    pub p50_us: u64,
    /// 99th percentile (µs).
    pub p99_us: u64,
    /// Maximum (µs).
    pub max_us: u64,
    /// Budget from the config (µs).
    pub budget_us: u64,
    /// Samples over budget in the interval.
    pub overruns: u64,
}

/// Pipeline health, published periodically.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StatsReport {
    /// Time of the report (CLOCK_MONOTONIC µs).
    pub t: Micros,
    /// Length of the interval these figures cover (µs).
    pub interval_us: u64,
    /// Per-stage timings over the interval.
    pub stages: Vec<StageStats>,
    /// Touch frames received since start.
    pub frames: u64,
    /// Motion-only frames merged into others because the queue was full, since start.
    pub frames_coalesced: u64,
    /// Touch-down or touch-up transitions lost since start (must stay 0).
    pub transitions_lost: u64,
    /// Control ticks since start.
    pub ticks: u64,
    /// Assignments applied since start.
    pub assignments: u64,
    /// Assignments applied per second over the interval: the assignments applied
    /// since the previous report divided by the interval's length.
    pub assignment_hz: f64,
    /// Snapshots dropped for slow clients since start (all clients).
    pub snapshots_dropped: u64,
    /// Connected clients.
    pub clients: u32,
    /// Agents.
    pub agents: u32,
    /// Active controls.
    pub controls: u32,
    /// Resident memory of the process (bytes), when known.
    pub rss_bytes: Option<u64>,
    /// The most recent control or gesture, described for people (`"area control, 3
    /// fingers"`).
    pub last_gesture: Option<String>,
    /// The formation the crowd is in (`start`, or the last one switched to).
    #[serde(default)]
    pub formation: String,
    /// Formation switches at scene checkpoints since start.
    #[serde(default)]
    pub formation_switches: u64,
    /// Formation transforms started since start.
    #[serde(default)]
    pub transforms: u64,
    /// The last transform that ended, summarised.
    #[serde(default)]
    pub last_transform: Option<super::transform::TransformSummary>,
    /// Config fields changed in the file by a reload that the daemon keeps at their
    /// running values until it restarts (empty when the file and the daemon agree).
    #[serde(default)]
    pub restart_pending: Vec<RestartPending>,
    /// Counters of the outputs that report their own (a TUIO target's datagrams,
    /// bytes, send errors…), one entry per output; absent when none does.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<OutputCounters>,
    /// Touches seen since start: every contact that landed, on any input.
    #[serde(default)]
    pub touches: u64,
    /// Each `Device` input's state (the last `device` event), in config order;
    /// absent when the daemon reads no device.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub devices: Vec<DeviceStatus>,
    /// Every stage's histogram since start (`/metrics`); not sent in `stats`,
    /// whose `stages` summarise the interval.
    #[serde(skip)]
    pub histograms: Vec<StageHistogram>,
}

/// A `Device` input's state in `stats`: what its last `device` event said.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceStatus {
    /// Index of the input in the config.
    pub input: u16,
    /// Attached, unplugged or failed; `None` before the first event.
    pub state: Option<super::event::DeviceState>,
    /// The node it was read through (`/dev/input/event5`), when one was found.
    pub node: String,
    /// Why, for `failed` and `unplugged`.
    pub message: Option<String>,
}

/// One stage's durations since start, in cumulative buckets (a Prometheus
/// histogram).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StageHistogram {
    /// Stage name.
    pub stage: String,
    /// `(upper bound µs, samples ≤ it)`, bounds increasing; the last bucket is the
    /// largest bound, `count` covers the rest (`+Inf`).
    pub buckets: Vec<(u64, u64)>,
    /// Samples since start.
    pub count: u64,
    /// Sum of the samples (µs), from the histogram's recorded values (three
    /// significant digits).
    pub sum_us: u64,
    /// Samples over the stage's budget since start.
    pub overruns: u64,
}

/// One output's own counters in `stats` (since start).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OutputCounters {
    /// The output (`tuio`, …).
    pub output: String,
    /// Where it sends or listens (`127.0.0.1:3333`).
    pub address: String,
    /// Named counts, in the output's order.
    pub counts: Vec<(String, u64)>,
}

/// A config field whose new value needs a restart: what runs, and what the file says.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RestartPending {
    /// Dotted path of the field (`socket.path`).
    pub field: String,
    /// The value in use, as JSON (`null` for none).
    pub running: serde_json::Value,
    /// The value in the config file, used after a restart.
    pub configured: serde_json::Value,
}
