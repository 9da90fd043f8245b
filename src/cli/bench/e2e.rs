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

use super::rows::{row_from_samples, row_from_stage, Row};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use crowdtouch::config::Config;
use crowdtouch::config::{OutputConfig, TuioProfile};
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream, UdpSocket};
use std::os::unix::net::UnixStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use tungstenite::Message;

/// Snapshot format of the bench client.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum WireFormat {
    /// One JSON line per snapshot.
    Json,
    /// Binary snapshot frames.
    Binary,
}

/// Arrays the bench client asks for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum FieldChoice {
    /// Positions, velocities, goals, assignment, touches (and motions in JSON).
    All,
    /// Positions only.
    Positions,
}

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

/// What the transform commander saw.
#[derive(Default)]
struct Commanded {
    /// `set_formation` commands acknowledged.
    started: u64,
    /// `transform` progress messages read.
    progress: u64,
    /// Transforms that ended, by outcome.
    outcomes: Vec<(String, u64)>,
    /// The first refusal, if any.
    refused: Option<String>,
}

/// Sends `set_formation` to `name` and back to `start` over `stream`, the next one
/// when the last one ended, until the daemon closes the stream.
fn command_transforms(stream: UnixStream, name: &str) -> Commanded {
    let mut out = Commanded::default();
    let Ok(mut w) = stream.try_clone() else {
        return out;
    };
    let mut r = BufReader::new(stream);
    if w.write_all(b"{\"type\":\"hello\",\"protocol\":1,\"subscribe\":[\"transform\"]}\n")
        .is_err()
    {
        return out;
    }
    let targets = [name, "start"];
    let mut k = 0usize;
    let mut line = String::new();
    let send = |w: &mut UnixStream, k: usize| {
        let cmd = format!(
            "{{\"type\":\"command\",\"id\":{k},\"name\":\"set_formation\",\"formation\":\"{}\",\"method\":\"transform\"}}\n",
            targets[k % 2]
        );
        w.write_all(cmd.as_bytes()).is_ok()
    };
    let mut hellos = 0;
    // A request that starts no transform (refused, or the formation the crowd is
    // in) is followed by the next one after this long without progress.
    let _ = r.get_ref().set_read_timeout(Some(Duration::from_secs(5)));
    loop {
        line.clear();
        match r.read_line(&mut line) {
            Ok(0) => return out,
            Ok(_) => {}
            Err(e)
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut =>
            {
                k += 1;
                if hellos < 2 || !send(&mut w, k) {
                    return out;
                }
                continue;
            }
            Err(_) => return out,
        }
        let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else {
            continue;
        };
        match v["type"].as_str() {
            Some("hello") => {
                hellos += 1;
                if hellos == 2 && !send(&mut w, k) {
                    return out;
                }
            }
            Some("ack") => out.started += 1,
            Some("error") => {
                out.refused
                    .get_or_insert_with(|| v["message"].as_str().unwrap_or("").to_string());
            }
            Some("transform") => out.progress += 1,
            Some("transform_end") => {
                let o = v["outcome"].as_str().unwrap_or("?").to_string();
                match out.outcomes.iter_mut().find(|(n, _)| *n == o) {
                    Some((_, c)) => *c += 1,
                    None => out.outcomes.push((o, 1)),
                }
                if v["outcome"] != "superseded" {
                    k += 1;
                    if !send(&mut w, k) {
                        return out;
                    }
                }
            }
            _ => {}
        }
    }
}

/// What a client read.
#[derive(Default)]
struct ClientRead {
    snapshots: u64,
    /// `tracks` messages (edit mode): while fingers hold people, and after releases.
    tracks_partial: u64,
    tracks_full: u64,
    bytes: u64,
    /// Input event → the snapshot read here (µs): exact in JSON (`input_t_us`),
    /// an upper bound in binary (`latency_us` plus read time − tick time).
    latency_us: Vec<f64>,
    /// The highest cumulative `dropped` a snapshot carried.
    dropped: u64,
    /// The counts of the `dropped` notices, summed.
    noticed: u64,
    /// Sequence numbers missing between snapshots read.
    seq_gaps: u64,
    last_seq: Option<u64>,
    /// When the first and the last snapshot were read (µs, monotonic).
    first_us: u64,
    last_us: u64,
}

impl ClientRead {
    /// Counts one snapshot of `bytes` bytes read now.
    fn snapshot(&mut self, s: Seen, bytes: u64) {
        let now = monotonic_now().0;
        if self.snapshots == 0 {
            self.first_us = now;
        }
        self.last_us = now;
        self.snapshots += 1;
        self.bytes += bytes;
        if let Some(l) = s.latency_us {
            self.latency_us.push(l);
        }
        self.dropped = self.dropped.max(s.dropped.unwrap_or(0));
        if let Some(seq) = s.seq {
            if let Some(last) = self.last_seq {
                self.seq_gaps += seq.saturating_sub(last + 1);
            }
            self.last_seq = Some(seq);
        }
    }

    /// Snapshots and megabytes per second between the first snapshot read and
    /// the last (the daemon's start and shutdown left out).
    fn rates(&self) -> (f64, f64) {
        let s = self.last_us.saturating_sub(self.first_us) as f64 / 1e6;
        if self.snapshots < 2 || s <= 0.0 {
            return (0.0, 0.0);
        }
        (
            (self.snapshots - 1) as f64 / s,
            self.bytes as f64 * (self.snapshots - 1) as f64 / self.snapshots as f64 / s / 1e6,
        )
    }

    /// Counts a JSON message other than a snapshot.
    fn message(&mut self, m: &[u8]) {
        if m.starts_with(b"{\"type\":\"dropped\"") {
            self.noticed += scalar(m, "count").unwrap_or(0);
        }
    }
}

/// What a snapshot said about itself.
struct Seen {
    seq: Option<u64>,
    dropped: Option<u64>,
    latency_us: Option<f64>,
}

/// A JSON snapshot line or message read now.
fn seen_json(m: &[u8]) -> Seen {
    Seen {
        seq: scalar(m, "seq"),
        dropped: scalar(m, "dropped"),
        latency_us: scalar(m, "input_t_us").map(|t| monotonic_now().0.saturating_sub(t) as f64),
    }
}

/// A binary snapshot frame read now, without its length field; `None` when it
/// is not one.
fn seen_binary(body: &[u8]) -> Option<Seen> {
    // Offsets count from the frame start, length field included.
    let u64_at = |o: usize| -> Option<u64> {
        Some(u64::from_le_bytes(body.get(o - 4..o + 4)?.try_into().ok()?))
    };
    if body.first() != Some(&2) || body.len() < 60 {
        return None;
    }
    let now = monotonic_now().0;
    let flags = u16::from_le_bytes([body[2], body[3]]);
    let latency_us = if flags & 0x40 != 0 {
        let (t, latency) = (u64_at(16)?, u64_at(24)?);
        Some((now.saturating_sub(t) + latency) as f64)
    } else {
        None
    };
    Some(Seen {
        seq: u64_at(8),
        dropped: u64_at(32),
        latency_us,
    })
}

fn hello(format: WireFormat, fields: FieldChoice, edit: bool) -> String {
    let format = match format {
        WireFormat::Json => "json",
        WireFormat::Binary => "binary",
    };
    let fields = match fields {
        FieldChoice::Positions => r#"["positions"]"#,
        FieldChoice::All => {
            r#"["positions","velocities","goals","assignment","touches","motions"]"#
        }
    };
    format!(
        r#"{{"type":"hello","protocol":1,"format":"{format}","subscribe":["snapshot"{}],"fields":{fields}}}"#,
        if edit { r#","edit""# } else { "" }
    )
}

/// The number after `"key":` in the first bytes of a JSON snapshot line (the
/// scalar fields come first), `None` when absent or `null`.
fn scalar(line: &[u8], key: &str) -> Option<u64> {
    let head = &line[..line.len().min(256)];
    let pat = format!("\"{key}\":");
    let at = head.windows(pat.len()).position(|w| w == pat.as_bytes())? + pat.len();
    let digits: Vec<u8> = head[at..]
        .iter()
        .copied()
        .take_while(u8::is_ascii_digit)
        .collect();
    std::str::from_utf8(&digits).ok()?.parse().ok()
}

/// Reads the daemon's stream until it closes: JSON lines, or (after the answer
/// to the client's hello) binary frames.
fn read_stream(stream: UnixStream, format: WireFormat) -> ClientRead {
    let mut r = BufReader::with_capacity(1 << 20, stream);
    let mut out = ClientRead::default();
    let mut line = Vec::new();
    // The connect hello, then the answer to ours (the last message in JSON).
    let mut hellos = 0;
    while hellos < 2 {
        line.clear();
        if r.read_until(b'\n', &mut line).map_or(true, |n| n == 0) {
            return out;
        }
        if line.starts_with(b"{\"type\":\"hello\"") {
            hellos += 1;
        }
    }
    loop {
        match format {
            WireFormat::Json => {
                line.clear();
                if r.read_until(b'\n', &mut line).map_or(true, |n| n == 0) {
                    return out;
                }
                if line.starts_with(b"{\"type\":\"tracks\"") {
                    const PARTIAL: &[u8] = b"\"full\":false";
                    if line.windows(PARTIAL.len()).any(|w| w == PARTIAL) {
                        out.tracks_partial += 1;
                    } else {
                        out.tracks_full += 1;
                    }
                }
                if line.starts_with(b"{\"type\":\"snapshot\"") {
                    out.snapshot(seen_json(&line), line.len() as u64);
                } else {
                    out.message(&line);
                }
            }
            WireFormat::Binary => {
                let mut len = [0u8; 4];
                if r.read_exact(&mut len).is_err() {
                    return out;
                }
                let n = u32::from_le_bytes(len) as usize;
                line.resize(n, 0);
                if r.read_exact(&mut line).is_err() {
                    return out;
                }
                match seen_binary(&line) {
                    Some(s) => out.snapshot(s, 4 + n as u64),
                    // A kind-1 frame: one JSON message.
                    None => out.message(line.get(4..).unwrap_or_default()),
                }
            }
        }
    }
}

/// A port on 127.0.0.1 that was free a moment ago.
fn free_tcp_port() -> Result<u16> {
    Ok(TcpListener::bind("127.0.0.1:0")
        .context("finding a free port for the WebSocket output")?
        .local_addr()?
        .port())
}

/// One WebSocket client: connects, sends the same hello as the Unix client and
/// reads every message until the daemon closes the connection (or `done`).
fn read_websocket(
    addr: std::net::SocketAddr,
    hello: String,
    done: Arc<AtomicBool>,
) -> Result<ClientRead> {
    let stream = TcpStream::connect(addr).context("connecting a WebSocket client")?;
    stream.set_read_timeout(Some(Duration::from_millis(200)))?;
    let (mut ws, _) = tungstenite::client(format!("ws://{addr}/ws"), stream)
        .map_err(|e| anyhow::anyhow!("WebSocket handshake: {e}"))?;
    ws.send(Message::Text(hello.into()))?;
    let mut out = ClientRead::default();
    loop {
        match ws.read() {
            Ok(Message::Text(t)) => {
                let t = t.as_bytes();
                if t.starts_with(b"{\"type\":\"snapshot\"") {
                    out.snapshot(seen_json(t), t.len() as u64);
                } else {
                    out.message(t);
                }
            }
            Ok(Message::Binary(b)) => {
                if let Some(s) = b.get(4..).and_then(seen_binary) {
                    out.snapshot(s, b.len() as u64);
                }
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if done.load(Ordering::Relaxed) {
                    return Ok(out);
                }
            }
            Err(_) => return Ok(out),
        }
    }
}

/// What the TUIO reader received.
#[derive(Default)]
struct TuioRead {
    datagrams: u64,
    bytes: u64,
    /// Distinct `fseq` frame numbers seen.
    frames: std::collections::HashSet<i32>,
    /// Datagrams that are not an OSC bundle holding an `fseq`.
    unreadable: u64,
    /// When the first and the last datagram arrived (µs, monotonic).
    first_us: u64,
    last_us: u64,
}

impl TuioRead {
    /// Seconds between the first datagram and the last.
    fn span_s(&self) -> f64 {
        (self.last_us.saturating_sub(self.first_us) as f64 / 1e6).max(1e-6)
    }
}

/// Reads datagrams on `socket` until `done`.
fn read_tuio(socket: UdpSocket, done: Arc<AtomicBool>) -> TuioRead {
    let mut out = TuioRead::default();
    let mut buf = vec![0u8; 65536];
    while !done.load(Ordering::Relaxed) {
        let Ok(n) = socket.recv(&mut buf) else {
            continue;
        };
        let now = monotonic_now().0;
        if out.datagrams == 0 {
            out.first_us = now;
        }
        out.last_us = now;
        out.datagrams += 1;
        out.bytes += n as u64;
        match bundle_fseq(&buf[..n]) {
            Some(f) => {
                out.frames.insert(f);
            }
            None => out.unreadable += 1,
        }
    }
    out
}

/// An OSC string at `at`: its bytes and the offset after its padding.
fn osc_str(b: &[u8], at: usize) -> Option<(&[u8], usize)> {
    let len = b.get(at..)?.iter().position(|&c| c == 0)?;
    Some((&b[at..at + len], at + (len + 4) / 4 * 4))
}

/// The frame number of a TUIO bundle: the int after `"fseq"` in the first
/// message whose arguments start with the string `fseq` (a small OSC walk over
/// the bundle's elements, not a full decoder). `None` for anything else.
fn bundle_fseq(b: &[u8]) -> Option<i32> {
    const HEAD: &[u8] = b"#bundle\0";
    if !b.starts_with(HEAD) {
        return None;
    }
    let mut at = HEAD.len() + 8;
    while at < b.len() {
        let size = u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize;
        let el = b.get(at + 4..(at + 4).checked_add(size)?)?;
        at += 4 + size;
        let Some((_addr, t)) = osc_str(el, 0) else {
            continue;
        };
        let Some((tags, a)) = osc_str(el, t) else {
            continue;
        };
        if !tags.starts_with(b",si") {
            continue;
        }
        let Some((first, i)) = osc_str(el, a) else {
            continue;
        };
        if first == b"fseq" {
            return Some(i32::from_be_bytes(el.get(i..i + 4)?.try_into().ok()?));
        }
    }
    None
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A TUIO 1.1 bundle as the output sends it: `alive`, then `fseq`.
    fn bundle(fseq: i32) -> Vec<u8> {
        use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
        let msg = |args: Vec<OscType>| {
            OscPacket::Message(OscMessage {
                addr: "/tuio/2Dobj".into(),
                args,
            })
        };
        rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
            timetag: OscTime::from((0, 1)),
            content: vec![
                msg(vec![OscType::String("alive".into()), OscType::Int(3)]),
                msg(vec![OscType::String("fseq".into()), OscType::Int(fseq)]),
            ],
        }))
        .unwrap()
    }

    #[test]
    fn the_tuio_reader_finds_the_frame_number_and_refuses_the_rest() {
        assert_eq!(bundle_fseq(&bundle(4812)), Some(4812));
        let b = bundle(7);
        assert_eq!(bundle_fseq(&b[..b.len() - 2]), None);
        assert_eq!(bundle_fseq(b"/tuio/2Dobj\0,s\0\0fseq\0\0\0\0"), None);
    }

    proptest::proptest! {
        #[test]
        fn the_tuio_reader_never_panics(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200), cut in 0usize..200) {
            let _ = bundle_fseq(&bytes);
            let mut b = bundle(1);
            b.truncate(cut.min(b.len()));
            b.extend_from_slice(&bytes);
            let _ = bundle_fseq(&b);
        }
    }

    #[test]
    fn a_client_counts_gaps_and_the_highest_dropped() {
        let mut c = ClientRead::default();
        for (seq, dropped) in [(1, 0), (2, 0), (5, 2), (6, 2)] {
            c.snapshot(
                Seen {
                    seq: Some(seq),
                    dropped: Some(dropped),
                    latency_us: None,
                },
                10,
            );
        }
        c.message(br#"{"type":"dropped","count":2,"total":2}"#);
        assert_eq!(
            (c.snapshots, c.seq_gaps, c.dropped, c.noticed),
            (4, 2, 2, 2)
        );
    }
}
