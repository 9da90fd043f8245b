//! `/metrics`: the newest `stats` report as Prometheus text, served by a WebSocket
//! output with `metrics: true` (and by `crowdtouch demo --http ADDR --metrics`),
//! read by an independent parser of the format (`prometheus-parse`); its values
//! are the report's.

mod common;

use common::{daemon_on_channel, free_addr, send_drag};
use crowdtouch::config::{Config, OutputConfig};
use crowdtouch::vocab::StatsReport;
use prometheus_parse::{Sample, Scrape, Value};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

const TOKEN: &str = "0123456789abcdef-metrics";

/// `GET path` on `addr` (with `auth` headers): the status and the body.
fn get(addr: SocketAddr, path: &str, auth: &str) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\n{auth}\r\n").unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let (head, body) = text.split_once("\r\n\r\n").unwrap();
    let status = head[9..12].parse().unwrap();
    if status == 200 {
        assert!(
            head.contains("Content-Type: text/plain; version=0.0.4"),
            "{head}"
        );
    }
    (status, body.to_string())
}

fn scrape(body: &str) -> Scrape {
    Scrape::parse(body.lines().map(|l| Ok(l.to_string()))).expect("the exposition parses")
}

/// The one sample of `name` whose labels include `labels`.
fn sample<'a>(s: &'a Scrape, name: &str, labels: &[(&str, &str)]) -> &'a Sample {
    let found: Vec<&Sample> = s
        .samples
        .iter()
        .filter(|x| x.metric == name && labels.iter().all(|(k, v)| x.labels.get(k) == Some(*v)))
        .collect();
    assert_eq!(found.len(), 1, "{name} {labels:?}: {found:?}");
    found[0]
}

fn number(s: &Scrape, name: &str) -> f64 {
    match sample(s, name, &[]).value {
        Value::Counter(v) | Value::Gauge(v) | Value::Untyped(v) => v,
        ref other => panic!("{name} is {other:?}"),
    }
}

fn websocket(addr: SocketAddr, metrics: bool, token: Option<&str>) -> OutputConfig {
    let mut o: OutputConfig = ron::from_str("WebSocket()").unwrap();
    if let OutputConfig::WebSocket {
        listen,
        metrics: m,
        token: t,
        ..
    } = &mut o
    {
        *listen = addr.to_string();
        *m = metrics;
        *t = token.map(str::to_string);
    }
    o
}

/// A drag, then a report; `/metrics` serves that report's figures.
#[test]
fn metrics_agree_with_the_stats_report() {
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 40;
    cfg.pipeline.realtime = Default::default();
    cfg.pipeline.stats_interval_ms = 250;
    cfg.outputs = vec![websocket(addr, true, Some(TOKEN))];
    let (mut d, tx) = daemon_on_channel(cfg, &dir.path().join("ct.sock"), 4096);
    let bearer = format!("Authorization: Bearer {TOKEN}\r\n");

    // Before the first report: only the daemon's version, and that no report is in.
    let (status, body) = get(addr, "/metrics", &bearer);
    assert_eq!(status, 200);
    let s = scrape(&body);
    assert!(number(&s, "crowdtouch_stats_reported") <= 1.0);
    // Without the output's token: refused.
    assert_eq!(get(addr, "/metrics", "").0, 401);

    let drag = std::thread::spawn(move || {
        send_drag(&tx, true);
        tx
    });
    let _tx = drag.join().unwrap();
    let r: std::sync::Arc<StatsReport> = loop {
        let r = d.next_report(Duration::from_secs(5)).unwrap();
        if r.touches == 1 && r.controls == 0 && r.assignments > 0 {
            break r;
        }
    };
    // The publisher hands the report to the HTTP side when it has sent it.
    let end = Instant::now() + Duration::from_secs(5);
    let s = loop {
        let s = scrape(&get(addr, "/metrics", &bearer).1);
        if number(&s, "crowdtouch_stats_reported") == 1.0
            && number(&s, "crowdtouch_ticks_total") == r.ticks as f64
        {
            break s;
        }
        assert!(Instant::now() < end, "/metrics never showed the report");
        std::thread::sleep(Duration::from_millis(20));
    };
    d.shutdown();

    for (name, v) in [
        ("crowdtouch_frames_total", r.frames as f64),
        (
            "crowdtouch_frames_coalesced_total",
            r.frames_coalesced as f64,
        ),
        (
            "crowdtouch_transitions_lost_total",
            r.transitions_lost as f64,
        ),
        ("crowdtouch_touches_total", r.touches as f64),
        ("crowdtouch_ticks_total", r.ticks as f64),
        ("crowdtouch_assignments_total", r.assignments as f64),
        ("crowdtouch_assignment_rate_hertz", r.assignment_hz),
        (
            "crowdtouch_snapshots_dropped_total",
            r.snapshots_dropped as f64,
        ),
        ("crowdtouch_clients", f64::from(r.clients)),
        ("crowdtouch_agents", f64::from(r.agents)),
        ("crowdtouch_controls", f64::from(r.controls)),
        (
            "crowdtouch_formation_switches_total",
            r.formation_switches as f64,
        ),
        ("crowdtouch_transforms_total", r.transforms as f64),
        ("crowdtouch_restart_pending", r.restart_pending.len() as f64),
        (
            "crowdtouch_stats_interval_seconds",
            r.interval_us as f64 * 1e-6,
        ),
    ] {
        let got = number(&s, name);
        assert!(
            (got - v).abs() <= 1e-9 * v.abs().max(1.0),
            "{name}: /metrics {got}, stats {v}"
        );
    }
    assert_eq!(
        number(&s, "crowdtouch_resident_memory_bytes"),
        r.rss_bytes.unwrap() as f64
    );
    assert_eq!(r.touches, 1);
    assert!(r.frames > 100);
    assert!(r.assignments > 0);
    let f = sample(&s, "crowdtouch_formation", &[("formation", "start")]);
    assert!(matches!(f.value, Value::Gauge(v) if v == 1.0));

    // Each stage's histogram: the count, the sum and the cumulative buckets since
    // start, as the report has them.
    assert!(!r.histograms.is_empty());
    for h in &r.histograms {
        let stage = h.stage.as_str();
        let hist = sample(&s, "crowdtouch_stage_latency_seconds", &[("stage", stage)]);
        let Value::Histogram(buckets) = &hist.value else {
            panic!("{stage}: {:?}", hist.value)
        };
        for (le_us, n) in &h.buckets {
            let b = buckets
                .iter()
                .find(|b| (b.less_than - *le_us as f64 * 1e-6).abs() < 1e-12)
                .unwrap_or_else(|| panic!("{stage}: no bucket le={le_us} µs in {buckets:?}"));
            assert_eq!(b.count, *n as f64, "{stage} le={le_us}");
        }
        let inf = buckets.iter().find(|b| b.less_than.is_infinite()).unwrap();
        assert_eq!(inf.count, h.count as f64, "{stage} +Inf");
        let count = sample(
            &s,
            "crowdtouch_stage_latency_seconds_count",
            &[("stage", stage)],
        );
        assert!(
            matches!(count.value, Value::Untyped(v) | Value::Counter(v) if v == h.count as f64)
        );
        let over = sample(&s, "crowdtouch_stage_overruns_total", &[("stage", stage)]);
        assert!(matches!(over.value, Value::Counter(v) if v == h.overruns as f64));
    }
    let control = r.histograms.iter().find(|h| h.stage == "control").unwrap();
    assert!(control.count > 100, "every tick is timed: {control:?}");
}

/// `demo --http ADDR --metrics` serves `/metrics` beside the viewer; without
/// `--metrics` there is no such page.
#[test]
fn the_demo_serves_metrics_when_asked() {
    for with in [true, false] {
        let dir = tempfile::tempdir().unwrap();
        let addr = free_addr();
        let mut args = vec![
            "demo".to_string(),
            "--agents".into(),
            "30".into(),
            "--seconds".into(),
            "6".into(),
            "--socket".into(),
            dir.path().join("d.sock").display().to_string(),
            "--http".into(),
            addr.to_string(),
        ];
        if with {
            args.push("--metrics".into());
        }
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
            .args(&args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let end = Instant::now() + Duration::from_secs(5);
        let (status, body) = loop {
            if TcpStream::connect(addr).is_ok() {
                let (st, body) = get(addr, "/metrics", "");
                if st != 200 || body.contains("crowdtouch_ticks_total") {
                    break (st, body);
                }
            }
            assert!(Instant::now() < end, "the demo served nothing on {addr}");
            std::thread::sleep(Duration::from_millis(100));
        };
        let _ = child.kill();
        let _ = child.wait();
        if with {
            assert_eq!(status, 200);
            let s = scrape(&body);
            assert!(number(&s, "crowdtouch_ticks_total") > 0.0);
            assert!(number(&s, "crowdtouch_agents") == 30.0);
        } else {
            assert_eq!(status, 404);
        }
    }
}
