//! `crowdtouch bench e2e`: the full daemon replaying the shipped recordings at
//! 120 Hz to one socket client reading in the format and field set asked for; with
//! `--gestures`, replaying gesture commands drawn in open space instead
//! ([`super::open_space`]), so that the latency is measured while gestures are
//! recognised and their motions synthesised on the formation thread; with
//! `--transform NAME`, the same open-space touches (recognition off) while a
//! second client keeps formation transforms running (to `NAME`, back to `start`).
//! With `--websocket-clients N` the daemon also has a WebSocket output read by `N`
//! clients (tungstenite, each on its own thread), and with `--tuio` a TUIO 1.1
//! output whose datagrams a UDP reader counts: what each received, every drop and
//! every gap in the sequence numbers, next to the Unix client's latency.

use super::e2e_clients::{hello, read_stream, read_websocket, ClientRead, FieldChoice, WireFormat};
use super::e2e_commander::command_transforms;
use super::e2e_tuio::read_tuio;
use super::rows::{row_from_samples, row_from_stage, Row};
use anyhow::{bail, Context, Result};
use crowdtouch::config::Config;
use crowdtouch::config::{OutputConfig, TuioProfile};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use std::io::Write;
use std::net::{TcpListener, UdpSocket};
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// What `bench e2e` is asked to do.
pub struct E2eRun<'a> {
    pub agents: u32,
    pub seconds: f64,
    pub realtime: bool,
    pub scene: Option<&'a std::path::Path>,
    pub format: WireFormat,
    pub fields: FieldChoice,
    /// Replay generated gesture commands instead of the shipped recordings.
    pub gestures: bool,
    /// Formation transforms to this formation and back, one after the other,
    /// with the open-space input and recognition off.
    pub transform: Option<&'a str>,
    /// Edit mode with this many people, edited by the shipped recordings' fingers.
    pub edit: Option<usize>,
    /// WebSocket clients reading the same stream as the Unix client, on a
    /// privileged WebSocket output (none: no WebSocket output).
    pub websocket_clients: u32,
    /// A TUIO 1.1 output (objects and blobs, 120 Hz, 64 KiB datagrams) to a UDP
    /// reader.
    pub tuio: bool,
}

/// `people` standing in a block over the crowd's area (0.5 m apart, rows of 20)
/// and walking slowly right (0.05 m/s), 100 samples 0.2 s apart: the shipped
/// recordings' fingers land on them.
fn edit_block(people: usize, area: crowdtouch::geom::Rect) -> crowdtouch::crowd::edit::TrackSet {
    use crowdtouch::crowd::edit::{Track, TrackSet};
    use crowdtouch::geom::Vec2;
    let cols = 20.min(people.max(1));
    let rows = people.div_ceil(cols);
    let c = Vec2::new(
        (area.min[0] + area.max[0]) / 2.0,
        (area.min[1] + area.max[1]) / 2.0,
    );
    let times: Vec<f64> = (0..100).map(|k| k as f64 * 0.2).collect();
    let tracks = (0..people)
        .map(|i| {
            let p0 = c + Vec2::new(
                ((i % cols) as f64 - (cols as f64 - 1.0) / 2.0) * 0.5,
                ((i / cols) as f64 - (rows as f64 - 1.0) / 2.0) * 0.5,
            );
            Track::linked(
                i as u64,
                times
                    .iter()
                    .map(|t| p0 + Vec2::new(0.05 * t, 0.0))
                    .collect(),
                times.clone(),
            )
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.2,
    }
}

/// A port on 127.0.0.1 that was free a moment ago.
fn free_tcp_port() -> Result<u16> {
    Ok(TcpListener::bind("127.0.0.1:0")
        .context("finding a free port for the WebSocket output")?
        .local_addr()?
        .port())
}

/// The full daemon replaying the shipped recordings at 120 Hz to one socket
/// client reading `run.format` with `run.fields`.
pub fn end_to_end(run: &E2eRun<'_>) -> Result<Vec<Row>> {
    let agents = run.agents;
    let mut cfg = Config::embedded_default();
    // Counts above the daemon's limit run too: they show why the limit is there.
    cfg.crowd.agents = agents;
    if agents == 0 {
        bail!("--agents must be at least 1");
    }
    let max_agents = cfg.max_agents();
    if let Some(path) = run.scene {
        let path = if path.extension().is_none() && !path.exists() {
            std::path::PathBuf::from(format!("config/scenes/{}.ron", path.display()))
        } else {
            path.to_path_buf()
        };
        let loaded = crowdtouch::crowd::environment::load_scene(&path, cfg.crowd.agent_radius_m)
            .with_context(|| format!("bench scene {}", path.display()))?;
        cfg.set_loaded_scene(Some(std::sync::Arc::new(loaded)));
    }
    if !run.realtime {
        cfg.pipeline.realtime = Default::default();
    }
    if let Some(people) = run.edit {
        if people == 0 {
            bail!("--edit must be at least 1 person");
        }
        let set = edit_block(people, cfg.crowd.formation);
        cfg.set_edit_tracks(
            Some((std::sync::Arc::new(set), "bench-edit-block".into())),
            0.3,
        );
    }
    let recording = std::env::temp_dir().join(format!(
        "crowdtouch-bench-gestures-{}.jsonl",
        std::process::id()
    ));
    let open_space = if run.gestures || run.transform.is_some() {
        let glass = cfg.surface.size_mm.unwrap_or((1210.0, 680.0));
        let written = super::open_space::write_recording(glass, &recording, 0x15)?;
        cfg.inputs = vec![crowdtouch::config::InputConfig::Replay {
            files: vec![recording.clone()],
            looped: true,
            gap_ms: 500,
            reset_between: true,
        }];
        Some(written)
    } else {
        None
    };
    if run.transform.is_some() {
        // Touches stay gestures (not recognised), even one that lands near an
        // agent: the transforms run undisturbed while their input is timed.
        cfg.gestures.enabled = false;
        cfg.gestures.all_touches_are_gestures = true;
    }
    cfg.log_level = crowdtouch::config::LogLevel::Error;
    let ws_addr = if run.websocket_clients > 0 {
        let listen = format!("127.0.0.1:{}", free_tcp_port()?);
        cfg.outputs.push(OutputConfig::WebSocket {
            listen: listen.clone(),
            token: None,
            privileged: true,
            max_clients: run.websocket_clients.max(16),
            max_message_bytes: 64 * 1024,
            viewer: false,
            metrics: false,
            origins: vec![],
            privileged_origins: vec![],
            hosts: vec![],
        });
        Some(listen.parse::<std::net::SocketAddr>()?)
    } else {
        None
    };
    let tuio_socket = if run.tuio {
        let socket = UdpSocket::bind("127.0.0.1:0").context("binding the TUIO reader")?;
        // Room for a few 10,000-agent frames: the reader is not what drops.
        let _ =
            nix::sys::socket::setsockopt(&socket, nix::sys::socket::sockopt::RcvBuf, &(4 << 20));
        socket.set_read_timeout(Some(Duration::from_millis(100)))?;
        cfg.outputs.push(OutputConfig::Tuio {
            target: socket.local_addr()?.to_string(),
            version: "1.1".into(),
            profiles: vec![TuioProfile::Objects, TuioProfile::Blobs],
            rate_hz: 120.0,
            max_datagram_bytes: 65507,
            source: None,
            privileged: false,
        });
        Some(socket)
    } else {
        None
    };
    let sock = std::env::temp_dir().join(format!("crowdtouch-bench-{}.sock", std::process::id()));
    let sources = sources_from_config(&cfg);
    if open_space.is_some() {
        let _ = std::fs::remove_file(&recording);
    }
    let sources = sources?;
    let mut daemon = Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path: sock.clone(),
            collect: None,
        },
    )?;
    let mut stream = UnixStream::connect(&sock).context("connecting the bench client")?;
    stream
        .write_all(format!("{}\n", hello(run.format, run.fields, run.edit.is_some())).as_bytes())
        .context("sending the bench client's hello")?;
    let format = run.format;
    let reader = std::thread::spawn(move || read_stream(stream, format));
    let done = Arc::new(AtomicBool::new(false));
    let mut websockets = Vec::new();
    if let Some(addr) = ws_addr {
        for _ in 0..run.websocket_clients {
            let hello = hello(run.format, run.fields, run.edit.is_some());
            let done = Arc::clone(&done);
            websockets.push(std::thread::spawn(move || {
                read_websocket(addr, hello, done)
            }));
        }
    }
    let tuio_reader = tuio_socket.map(|socket| {
        let done = Arc::clone(&done);
        std::thread::spawn(move || read_tuio(socket, done))
    });
    let commander = match run.transform {
        Some(name) => {
            let s = UnixStream::connect(&sock).context("connecting the transform commander")?;
            let name = name.to_string();
            Some(std::thread::spawn(move || command_transforms(s, &name)))
        }
        None => None,
    };
    let start = monotonic_now();
    let until = start + Micros::from_secs_f64(run.seconds);
    let mut report = None;
    while monotonic_now() < until {
        if let Some(r) = daemon.next_report(Duration::from_millis(200)) {
            report = Some(r);
        }
    }
    let elapsed = monotonic_now().saturating_since(start).as_secs_f64();
    let totals = daemon.totals();
    let input = daemon.input_counters();
    let lost = input
        .transitions_lost
        .load(std::sync::atomic::Ordering::Relaxed);
    let coalesced = input.coalesced.load(std::sync::atomic::Ordering::Relaxed);
    let dropped = daemon.publisher_stats().snapshots_dropped();
    let rss = crowdtouch::pipeline::timing::rss_bytes().unwrap_or(0);
    daemon.shutdown();
    done.store(true, Ordering::Relaxed);
    let read = reader.join().unwrap_or_default();
    let websockets = websockets
        .into_iter()
        .map(|w| {
            w.join()
                .unwrap_or_else(|_| Err(anyhow::anyhow!("a WebSocket client panicked")))
        })
        .collect::<Result<Vec<ClientRead>>>()?;
    let tuio_read = tuio_reader.map(|t| t.join().unwrap_or_default());
    let commanded = commander.map(|c| c.join().unwrap_or_default());
    if let Some(why) = commanded.as_ref().and_then(|c| c.refused.as_ref()) {
        bail!("set_formation was refused: {why}");
    }
    let find = |n: &str| totals.iter().find(|s| s.stage == n);
    let assign = find("assignment");
    let refresh = assign.map(|s| s.count).unwrap_or(0) as f64 / elapsed;
    let wire = format!(
        "{}, {}",
        match run.format {
            WireFormat::Json => "json",
            WireFormat::Binary => "binary",
        },
        match run.fields {
            FieldChoice::All => "all fields",
            FieldChoice::Positions => "positions",
        }
    );
    let beyond = if agents > max_agents {
        format!(" (beyond this config's limit of {max_agents})")
    } else {
        String::new()
    };
    let input_note = match (&open_space, &commanded) {
        (Some(o), Some(c)) => format!(
            "{} open-space touches (recognition off), {:.1} s looped, during transforms to `{}` and back: {} started, {} progress ticks ({:.0} % of snapshots read), ended {}; ",
            o.gestures,
            o.seconds,
            run.transform.unwrap_or(""),
            c.started,
            c.progress,
            100.0 * c.progress as f64 / read.snapshots.max(1) as f64,
            c.outcomes
                .iter()
                .map(|(n, k)| format!("{k} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        (Some(o), None) => format!(
            "{} generated gesture commands in open space, two people, {:.1} s looped; ",
            o.gestures, o.seconds
        ),
        (None, _) => match run.edit {
            Some(p) => format!(
                "edit mode: {p} people × 100 samples grabbed, dragged and released by the shipped recordings' fingers ({} tracks messages while held, {} after a release, JSON only); ",
                read.tracks_partial, read.tracks_full
            ),
            None => String::new(),
        },
    };
    let abandon = find("abandon")
        .map(|s| format!(", {} stale jobs given up", s.count))
        .unwrap_or_default();
    let unix_note = format!(
        "; Unix client: {} snapshots ({:.1}/s, {:.1} MB/s), dropped {} ({} in notices), seq gaps {}",
        read.snapshots,
        read.rates().0,
        read.rates().1,
        read.dropped,
        read.noticed,
        read.seq_gaps
    );
    let mut rows = vec![
        row_from_stage(
            &format!("end_to_end {agents} agents"),
            find("end_to_end"),
            format!(
                "{input_note}input timestamp -> bytes written ({wire}){beyond}; SCHED_FIFO {}; {} snapshots read ({:.1}/s, {:.1} MB/s), {dropped} dropped, touch transitions lost {lost}, motion frames coalesced {coalesced}, RSS {:.1} MB",
                if crowdtouch::rt::realtime_granted() { "on" } else { "off" },
                read.snapshots,
                read.rates().0,
                read.rates().1,
                rss as f64 / 1e6
            ),
        ),
        row_from_samples(
            &format!("client read {agents} agents"),
            read.latency_us,
            match run.format {
                WireFormat::Json => format!("input timestamp -> snapshot read by the client ({wire})"),
                WireFormat::Binary => format!(
                    "input timestamp -> snapshot read by the client, upper bound: latency_us + (read time - t_us) ({wire})"
                ),
            },
        ),
        row_from_stage(&format!("control {agents} agents"), find("control"), "control thread tick, in the daemon".into()),
        row_from_stage(
            &format!("assignment {agents} agents"),
            assign,
            format!("worker solve; refreshed {refresh:.1} times/s{abandon}"),
        ),
        row_from_stage("publish (encode)", find("publish"), format!("snapshot serialisation ({wire})")),
        row_from_stage(
            "input thread",
            find("input"),
            "input timestamp -> frame on the queue (replay source: the added latency of the input thread)".into(),
        ),
        row_from_stage("queue", find("queue"), "frame on the queue -> control thread takes it".into()),
    ];
    rows[1].note.push_str(&unix_note);
    for (i, w) in websockets.into_iter().enumerate() {
        let note = format!(
            "WebSocket client {}/{}, input timestamp -> snapshot read ({wire}{}): {} snapshots ({:.1}/s, {:.1} MB/s), dropped {} ({} in notices), seq gaps {}",
            i + 1,
            run.websocket_clients,
            if run.format == WireFormat::Binary { ", upper bound" } else { "" },
            w.snapshots,
            w.rates().0,
            w.rates().1,
            w.dropped,
            w.noticed,
            w.seq_gaps
        );
        rows.push(row_from_samples(
            &format!("websocket client {} {agents} agents", i + 1),
            w.latency_us,
            note,
        ));
    }
    if let Some(t) = tuio_read {
        let counters = report
            .as_ref()
            .and_then(|r| r.outputs.iter().find(|o| o.output == "tuio"));
        let sent = |k: &str| {
            counters
                .and_then(|c| c.counts.iter().find(|(n, _)| n == k))
                .map_or(0, |(_, v)| *v)
        };
        let (lo, hi) = (
            t.frames.iter().min().copied().unwrap_or(0),
            t.frames.iter().max().copied().unwrap_or(-1),
        );
        let missing = (i64::from(hi) - i64::from(lo) + 1).max(0) as u64 - t.frames.len() as u64;
        let all_dropped = report.as_ref().map_or(0, |r| r.snapshots_dropped);
        let mut row = row_from_samples(
            &format!("tuio {agents} agents"),
            Vec::new(),
            format!(
                "TUIO 1.1 objects+blobs at most 120 Hz, 64 KiB datagrams: {} frames received ({:.1}/s), {} missing between the first and last fseq; {} datagrams ({:.1} MB/s), {} unreadable; the output's own counters at its last stats report: {} frames, {} datagrams, {} send errors, {} skipped by the rate limit, {} entities left out; snapshots dropped by all outputs {all_dropped}",
                t.frames.len(),
                t.frames.len().saturating_sub(1) as f64 / t.span_s(),
                missing,
                t.datagrams,
                t.bytes as f64 / t.span_s() / 1e6,
                t.unreadable,
                sent("frames"),
                sent("datagrams"),
                sent("send_errors"),
                sent("skipped"),
                sent("left_out"),
            ),
        );
        row.samples = t.frames.len() as u64;
        rows.push(row);
    }
    if let Some(g) = find("gesture").filter(|g| g.count > 0 || open_space.is_some()) {
        rows.push(row_from_stage(
            &format!("gesture {agents} agents"),
            Some(g),
            "formation thread: recognise + blend + synthesise + assign, per gesture command".into(),
        ));
    }
    if let Some(t) = find("transform_prepare").filter(|t| t.count > 0) {
        rows.push(row_from_stage(
            &format!("transform prepare {agents} agents"),
            Some(t),
            "formation thread: sample + pair + subgroups, per transform".into(),
        ));
    }
    Ok(rows)
}
