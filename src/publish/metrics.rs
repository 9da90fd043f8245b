//! `/metrics`: the newest `stats` report in the Prometheus text exposition format
//! (version 0.0.4), served beside the viewer by a WebSocket output with
//! `metrics: true` (docs/install.md "Metrics").
//!
//! Every figure is the report's own, so `/metrics` and `stats` agree: counters
//! (`_total`) are the report's since-start counts, gauges its current values, and
//! each stage's latency is a histogram since start in the buckets of
//! `pipeline::report::HISTOGRAM_BOUNDS_US`, converted to seconds.

use crate::vocab::{DeviceState, StatsReport};
use std::fmt::Write;

/// The `Content-Type` of the text exposition format.
pub const CONTENT_TYPE: &str = "text/plain; version=0.0.4; charset=utf-8";

/// A label value escaped as the format asks (`\\`, `\"`, `\n`).
fn label(v: &str) -> String {
    let mut out = String::with_capacity(v.len());
    for c in v.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '"' => out.push_str("\\\""),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out
}

/// One metric family's `# HELP` and `# TYPE` lines.
fn family(out: &mut String, name: &str, kind: &str, help: &str) {
    let _ = writeln!(out, "# HELP {name} {help}");
    let _ = writeln!(out, "# TYPE {name} {kind}");
}

/// A family of one unlabelled sample.
fn single(out: &mut String, name: &str, kind: &str, help: &str, value: f64) {
    family(out, name, kind, help);
    let _ = writeln!(out, "{name} {value}");
}

/// Microseconds as seconds.
fn seconds(us: u64) -> f64 {
    us as f64 * 1e-6
}

/// Microseconds as an exact decimal number of seconds (`50` → `0.00005`), for the
/// `le` labels: a float would print `0.000049999999999999996`.
fn seconds_text(us: u64) -> String {
    let frac = format!("{:06}", us % 1_000_000);
    let frac = frac.trim_end_matches('0');
    if frac.is_empty() {
        (us / 1_000_000).to_string()
    } else {
        format!("{}.{frac}", us / 1_000_000)
    }
}

/// The exposition of `report` (`None` before the daemon's first report: only
/// `crowdtouch_info` and `crowdtouch_stats_reported 0`).
pub fn render(report: Option<&StatsReport>) -> String {
    let mut out = String::with_capacity(8 * 1024);
    family(
        &mut out,
        "crowdtouch_info",
        "gauge",
        "The daemon's version (always 1).",
    );
    let _ = writeln!(
        out,
        "crowdtouch_info{{version=\"{}\"}} 1",
        env!("CARGO_PKG_VERSION")
    );
    single(
        &mut out,
        "crowdtouch_stats_reported",
        "gauge",
        "Whether the daemon has made a stats report yet (the figures below are its newest).",
        f64::from(u8::from(report.is_some())),
    );
    let Some(r) = report else {
        return out;
    };
    single(
        &mut out,
        "crowdtouch_stats_interval_seconds",
        "gauge",
        "Length of the interval the newest report covers.",
        seconds(r.interval_us),
    );
    stages(&mut out, r);
    let counters: [(&str, &str, u64); 9] = [
        (
            "crowdtouch_frames_total",
            "Touch frames received since start, every input.",
            r.frames,
        ),
        (
            "crowdtouch_frames_coalesced_total",
            "Motion-only frames merged into others because the input queue was full.",
            r.frames_coalesced,
        ),
        (
            "crowdtouch_transitions_lost_total",
            "Touch-downs or lifts lost merging frames (must stay 0).",
            r.transitions_lost,
        ),
        (
            "crowdtouch_touches_total",
            "Touches seen since start: every contact that landed.",
            r.touches,
        ),
        (
            "crowdtouch_ticks_total",
            "Control ticks since start.",
            r.ticks,
        ),
        (
            "crowdtouch_assignments_total",
            "Assignments of agents to goals applied since start.",
            r.assignments,
        ),
        (
            "crowdtouch_snapshots_dropped_total",
            "Snapshots dropped for slow clients since start.",
            r.snapshots_dropped,
        ),
        (
            "crowdtouch_formation_switches_total",
            "Formation switches at scene checkpoints since start.",
            r.formation_switches,
        ),
        (
            "crowdtouch_transforms_total",
            "Formation transforms started since start.",
            r.transforms,
        ),
    ];
    for (name, help, v) in counters {
        single(&mut out, name, "counter", help, v as f64);
    }
    let gauges: [(&str, &str, f64); 4] = [
        (
            "crowdtouch_assignment_rate_hertz",
            "Assignments applied per second over the newest interval.",
            r.assignment_hz,
        ),
        (
            "crowdtouch_clients",
            "Connected clients of every output (a TUIO target counts as one).",
            f64::from(r.clients),
        ),
        (
            "crowdtouch_agents",
            "Agents in the crowd.",
            f64::from(r.agents),
        ),
        (
            "crowdtouch_controls",
            "Live controls (fingers on the crowd).",
            f64::from(r.controls),
        ),
    ];
    for (name, help, v) in gauges {
        single(&mut out, name, "gauge", help, v);
    }
    if let Some(rss) = r.rss_bytes {
        single(
            &mut out,
            "crowdtouch_resident_memory_bytes",
            "gauge",
            "Resident memory of the daemon.",
            rss as f64,
        );
    }
    family(
        &mut out,
        "crowdtouch_formation",
        "gauge",
        "The formation the crowd is in (1 for it).",
    );
    let _ = writeln!(
        out,
        "crowdtouch_formation{{formation=\"{}\"}} 1",
        label(&r.formation)
    );
    single(
        &mut out,
        "crowdtouch_restart_pending",
        "gauge",
        "Config fields changed by a reload that wait for a restart.",
        r.restart_pending.len() as f64,
    );
    if !r.restart_pending.is_empty() {
        family(
            &mut out,
            "crowdtouch_restart_pending_field",
            "gauge",
            "A config field that waits for a restart (1 for each).",
        );
        for p in &r.restart_pending {
            let _ = writeln!(
                out,
                "crowdtouch_restart_pending_field{{field=\"{}\"}} 1",
                label(&p.field)
            );
        }
    }
    devices(&mut out, r);
    outputs(&mut out, r);
    out
}

/// Each stage's latency histogram since start, its overruns and budget.
fn stages(out: &mut String, r: &StatsReport) {
    if !r.histograms.is_empty() {
        family(
            out,
            "crowdtouch_stage_latency_seconds",
            "histogram",
            "Durations of each pipeline stage since start (end_to_end: kernel timestamp to bytes written).",
        );
        for h in &r.histograms {
            let stage = label(&h.stage);
            for (le, n) in &h.buckets {
                let _ = writeln!(
                    out,
                    "crowdtouch_stage_latency_seconds_bucket{{stage=\"{stage}\",le=\"{}\"}} {n}",
                    seconds_text(*le)
                );
            }
            let _ = writeln!(
                out,
                "crowdtouch_stage_latency_seconds_bucket{{stage=\"{stage}\",le=\"+Inf\"}} {}",
                h.count
            );
            let _ = writeln!(
                out,
                "crowdtouch_stage_latency_seconds_sum{{stage=\"{stage}\"}} {}",
                seconds(h.sum_us)
            );
            let _ = writeln!(
                out,
                "crowdtouch_stage_latency_seconds_count{{stage=\"{stage}\"}} {}",
                h.count
            );
        }
        family(
            out,
            "crowdtouch_stage_overruns_total",
            "counter",
            "Samples of each stage over its budget since start.",
        );
        for h in &r.histograms {
            let _ = writeln!(
                out,
                "crowdtouch_stage_overruns_total{{stage=\"{}\"}} {}",
                label(&h.stage),
                h.overruns
            );
        }
    }
    if !r.stages.is_empty() {
        family(
            out,
            "crowdtouch_stage_budget_seconds",
            "gauge",
            "Each stage's budget from the config.",
        );
        for s in &r.stages {
            let _ = writeln!(
                out,
                "crowdtouch_stage_budget_seconds{{stage=\"{}\"}} {}",
                label(&s.stage),
                seconds(s.budget_us)
            );
        }
    }
}

/// Each device input's state, one sample per state (1 for the one it is in).
fn devices(out: &mut String, r: &StatsReport) {
    if r.devices.is_empty() {
        return;
    }
    family(
        out,
        "crowdtouch_device_state",
        "gauge",
        "Each Device input's state: 1 for the state it is in (none before its first attempt).",
    );
    for d in &r.devices {
        for s in [
            DeviceState::Attached,
            DeviceState::Unplugged,
            DeviceState::Failed,
        ] {
            let _ = writeln!(
                out,
                "crowdtouch_device_state{{input=\"{}\",node=\"{}\",state=\"{}\"}} {}",
                d.input,
                label(&d.node),
                s.as_str(),
                u8::from(d.state == Some(s))
            );
        }
    }
}

/// The outputs' and network inputs' own counters.
fn outputs(out: &mut String, r: &StatsReport) {
    if r.outputs.is_empty() {
        return;
    }
    family(
        out,
        "crowdtouch_output_events_total",
        "counter",
        "Each output's and network input's own counts since start (docs/protocol.md, stats outputs).",
    );
    for o in &r.outputs {
        for (name, v) in &o.counts {
            let _ = writeln!(
                out,
                "crowdtouch_output_events_total{{output=\"{}\",address=\"{}\",event=\"{}\"}} {v}",
                label(&o.output),
                label(&o.address),
                label(name)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{DeviceStatus, OutputCounters, RestartPending, StageHistogram};

    #[test]
    fn bucket_bounds_are_exact_decimals() {
        assert_eq!(seconds_text(50), "0.00005");
        assert_eq!(seconds_text(125_000), "0.125");
        assert_eq!(seconds_text(1_000_000), "1");
        assert_eq!(seconds_text(2_500_000), "2.5");
    }

    #[test]
    fn label_values_are_escaped() {
        assert_eq!(label("a\"b\\c\nd"), "a\\\"b\\\\c\\nd");
    }

    #[test]
    fn before_the_first_report_only_the_info_is_served() {
        let text = render(None);
        assert!(text.contains("crowdtouch_stats_reported 0\n"));
        assert!(!text.contains("crowdtouch_ticks_total"));
    }

    #[test]
    fn every_sample_line_belongs_to_a_declared_family() {
        let r = StatsReport {
            ticks: 7,
            rss_bytes: Some(4096),
            formation: "a \"quoted\" one".into(),
            histograms: vec![StageHistogram {
                stage: "control".into(),
                buckets: vec![(50, 1), (100, 3)],
                count: 4,
                sum_us: 400,
                overruns: 1,
            }],
            devices: vec![DeviceStatus {
                input: 0,
                state: Some(DeviceState::Failed),
                node: String::new(),
                message: Some("no device".into()),
            }],
            outputs: vec![OutputCounters {
                output: "tuio".into(),
                address: "127.0.0.1:3333".into(),
                counts: vec![("frames".into(), 9)],
            }],
            restart_pending: vec![RestartPending {
                field: "socket.path".into(),
                ..Default::default()
            }],
            ..Default::default()
        };
        let text = render(Some(&r));
        let mut declared = Vec::new();
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("# TYPE ") {
                declared.push(rest.split(' ').next().unwrap().to_string());
                continue;
            }
            if line.starts_with('#') {
                continue;
            }
            let name = line.split(['{', ' ']).next().unwrap();
            let base = ["_bucket", "_sum", "_count"]
                .iter()
                .find_map(|s| name.strip_suffix(s))
                .filter(|b| declared.iter().any(|d| d == b))
                .unwrap_or(name);
            assert!(declared.iter().any(|d| d == base), "undeclared: {line}");
        }
        assert!(text.contains("crowdtouch_ticks_total 7\n"));
        assert!(text.contains(
            "crowdtouch_stage_latency_seconds_bucket{stage=\"control\",le=\"+Inf\"} 4\n"
        ));
        assert!(
            text.contains("crowdtouch_device_state{input=\"0\",node=\"\",state=\"failed\"} 1\n")
        );
        assert!(text.contains("formation=\"a \\\"quoted\\\" one\""));
    }
}
