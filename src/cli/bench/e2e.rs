//! `crowdtouch bench e2e`: the full daemon replaying the shipped recordings at
//! 120 Hz to one socket client reading in the format and field set asked for; with
//! `--gestures`, replaying gesture commands drawn in open space instead
//! ([`super::open_space`]), so that the latency is measured while gestures are
//! recognised and their motions synthesised on the formation thread; with
//! `--transform NAME`, the same open-space touches (recognition off) while a
//! second client keeps formation transforms running (to `NAME`, back to `start`).

use super::{row_from_samples, row_from_stage, Row};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use crowdtouch::config::Config;
use crowdtouch::pipeline::{sources_from_config, Daemon, DaemonOptions};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::time::Duration;

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

/// What the client read.
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
                    out.snapshots += 1;
                    out.bytes += line.len() as u64;
                    if let Some(t) = scalar(&line, "input_t_us") {
                        let now = monotonic_now().0;
                        out.latency_us.push(now.saturating_sub(t) as f64);
                    }
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
                // Offsets count from the frame start, length field included.
                if line.first() == Some(&2) && n >= 60 {
                    let now = monotonic_now().0;
                    out.snapshots += 1;
                    out.bytes += 4 + n as u64;
                    let u64_at = |o: usize| {
                        u64::from_le_bytes(line[o - 4..o + 4].try_into().expect("8 bytes"))
                    };
                    let flags = u16::from_le_bytes([line[2], line[3]]);
                    if flags & 0x40 != 0 {
                        let (t, latency) = (u64_at(16), u64_at(24));
                        out.latency_us
                            .push((now.saturating_sub(t) + latency) as f64);
                    }
                }
            }
        }
    }
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
        },
    )?;
    let mut stream = UnixStream::connect(&sock).context("connecting the bench client")?;
    stream
        .write_all(format!("{}\n", hello(run.format, run.fields, run.edit.is_some())).as_bytes())
        .context("sending the bench client's hello")?;
    let format = run.format;
    let reader = std::thread::spawn(move || read_stream(stream, format));
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
    while monotonic_now() < until {
        let _ = daemon.next_report(Duration::from_millis(200));
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
    let read = reader.join().unwrap_or_default();
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
    let beyond = if agents > crowdtouch::config::MAX_AGENTS {
        format!(
            " (beyond the daemon's limit of {})",
            crowdtouch::config::MAX_AGENTS
        )
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
    let mut rows = vec![
        row_from_stage(
            &format!("end_to_end {agents} agents"),
            find("end_to_end"),
            format!(
                "{input_note}input timestamp -> bytes written ({wire}){beyond}; SCHED_FIFO {}; {} snapshots read ({:.1}/s, {:.1} MB/s), {dropped} dropped, touch transitions lost {lost}, motion frames coalesced {coalesced}, RSS {:.1} MB",
                if crowdtouch::rt::realtime_granted() { "on" } else { "off" },
                read.snapshots,
                read.snapshots as f64 / elapsed,
                read.bytes as f64 / elapsed / 1e6,
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
