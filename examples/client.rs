//! A small crowdtouch client, the way a renderer would write one: std + serde_json,
//! nothing from the crowdtouch crate, so it can be copied into another project.
//!
//! ```text
//! cargo run --example client -- [--socket PATH] [--binary] [--rate HZ]
//!                                [--subscribe snapshot,events] [--fields positions,motions]
//!                                [--command pause]
//! ```
//! Prints one line per message: a summary for snapshots (seq, agent count, latency,
//! drops, centroid, and how many agents do each motion when the daemon runs a
//! scene), the JSON for everything else. See docs/protocol.md.

use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::PathBuf;

/// Where the daemon listens unless told otherwise (same rules as the daemon).
fn default_socket() -> PathBuf {
    if let Some(p) = std::env::var_os("CROWDTOUCH_SOCKET") {
        return p.into();
    }
    if let Some(d) = std::env::var_os("XDG_RUNTIME_DIR") {
        return PathBuf::from(d).join("crowdtouch.sock");
    }
    let run = PathBuf::from("/run/crowdtouch/crowdtouch.sock");
    if run.exists() {
        return run;
    }
    use std::os::unix::fs::MetadataExt;
    let uid = std::fs::metadata("/proc/self")
        .map(|m| m.uid())
        .unwrap_or(0);
    PathBuf::from(format!("/tmp/crowdtouch-{uid}.sock"))
}

/// Prints a line; exits quietly when stdout is gone (`client | head`).
macro_rules! say {
    ($($arg:tt)*) => {
        if writeln!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(0);
        }
    };
}

struct Options {
    socket: PathBuf,
    binary: bool,
    rate: Option<f64>,
    subscribe: Option<Vec<String>>,
    fields: Option<Vec<String>>,
    command: Option<String>,
}

fn options() -> Result<Options, String> {
    let mut o = Options {
        socket: default_socket(),
        binary: false,
        rate: None,
        subscribe: None,
        fields: None,
        command: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--socket" => o.socket = value()?.into(),
            "--binary" => o.binary = true,
            "--rate" => o.rate = Some(value()?.parse().map_err(|e| format!("--rate: {e}"))?),
            "--subscribe" => o.subscribe = Some(value()?.split(',').map(String::from).collect()),
            "--fields" => o.fields = Some(value()?.split(',').map(String::from).collect()),
            "--command" => o.command = Some(value()?),
            "-h" | "--help" => return Err("usage: client [--socket PATH] [--binary] [--rate HZ] [--subscribe a,b] [--fields a,b] [--command NAME]".into()),
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    Ok(o)
}

/// Reads one message: a JSON line, or (binary) one frame. `None` at end of stream.
enum Message {
    Json(Value),
    Snapshot(Vec<u8>),
}

fn read_message(r: &mut BufReader<UnixStream>, binary: bool) -> std::io::Result<Option<Message>> {
    if !binary {
        let mut line = String::new();
        if r.read_line(&mut line)? == 0 {
            return Ok(None);
        }
        let v = serde_json::from_str(&line).map_err(std::io::Error::other)?;
        return Ok(Some(Message::Json(v)));
    }
    let mut len = [0u8; 4];
    match r.read_exact(&mut len) {
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
        other => other?,
    }
    let mut frame = vec![0u8; 4 + u32::from_le_bytes(len) as usize];
    frame[..4].copy_from_slice(&len);
    r.read_exact(&mut frame[4..])?;
    match frame[4] {
        1 => Ok(Some(Message::Json(
            serde_json::from_slice(&frame[5..]).map_err(std::io::Error::other)?,
        ))),
        _ => Ok(Some(Message::Snapshot(frame))),
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// Binary motion codes (docs/protocol.md, "Motions array"): the byte is the index.
const MOTIONS: [&str; 7] = [
    "run",
    "crawl",
    "duck",
    "swim",
    "jump",
    "climb_up",
    "climb_down",
];

/// " motions run=40 swim=10" for a list of motion names; empty for none.
fn motion_counts<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut counts = std::collections::BTreeMap::new();
    for m in names {
        *counts.entry(m).or_insert(0) += 1;
    }
    if counts.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = counts.iter().map(|(m, c)| format!("{m}={c}")).collect();
    format!(" motions {}", parts.join(" "))
}

/// Summary of a binary snapshot frame (layout in docs/protocol.md).
fn summarise_binary(f: &[u8]) -> String {
    if f.len() < 64 {
        return "short frame".into();
    }
    let flags = u16::from_le_bytes([f[6], f[7]]);
    let (seq, dropped, n) = (u64_at(f, 8), u64_at(f, 32), u32_at(f, 48) as usize);
    let (g, k) = (u32_at(f, 52) as usize, u32_at(f, 56) as usize);
    let latency = if flags & 0x40 != 0 {
        format!("{} us", u64_at(f, 24))
    } else {
        "-".into()
    };
    let mut centroid = (0.0f64, 0.0f64);
    if flags & 0x01 != 0 && n > 0 && f.len() >= 64 + 8 * n {
        for i in 0..n {
            let at = 64 + 8 * i;
            centroid.0 += f64::from(f32::from_bits(u32_at(f, at)));
            centroid.1 += f64::from(f32::from_bits(u32_at(f, at + 4)));
        }
        centroid = (centroid.0 / n as f64, centroid.1 / n as f64);
    }
    // The arrays come in flag order; the motions (flag 0x80) are last, a byte each.
    let has = |bit: u16| usize::from(flags & bit != 0);
    let motions_at = 64
        + 8 * n * (has(0x01) + has(0x02))
        + 8 * g * has(0x04)
        + 4 * n * has(0x08)
        + 16 * k * has(0x10);
    let motions = match f.get(motions_at..motions_at + n) {
        Some(codes) if flags & 0x80 != 0 => motion_counts(
            codes
                .iter()
                .map(|&c| MOTIONS.get(c as usize).copied().unwrap_or("unknown")),
        ),
        _ => String::new(),
    };
    format!(
        "snapshot seq={seq} agents={n} latency={latency} dropped={dropped} centroid=({:.3}, {:.3}){motions}",
        centroid.0, centroid.1
    )
}

/// Summary of a JSON snapshot.
fn summarise_json(v: &Value) -> String {
    let n = v["agents"].as_u64().unwrap_or(0);
    let mut centroid = (0.0, 0.0);
    if let Some(p) = v["positions"].as_array() {
        // Flat: [x0, y0, x1, y1, ...]
        for xy in p.chunks(2) {
            centroid.0 += xy[0].as_f64().unwrap_or(0.0);
            centroid.1 += xy.get(1).and_then(Value::as_f64).unwrap_or(0.0);
        }
        let k = (p.len() / 2).max(1) as f64;
        centroid = (centroid.0 / k, centroid.1 / k);
    }
    let latency = v["latency_us"]
        .as_u64()
        .map_or("-".into(), |l| format!("{l} us"));
    let motions = match v["motions"].as_array() {
        Some(m) => motion_counts(m.iter().filter_map(Value::as_str)),
        None => String::new(),
    };
    format!(
        "snapshot seq={} agents={n} latency={latency} dropped={} centroid=({:.3}, {:.3}){motions}",
        v["seq"], v["dropped"], centroid.0, centroid.1
    )
}

fn main() {
    let o = match options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let stream = match UnixStream::connect(&o.socket) {
        Ok(s) => s,
        Err(e) => {
            eprintln!(
                "{}: cannot connect: {e} (is crowdtouch running?)",
                o.socket.display()
            );
            std::process::exit(1);
        }
    };
    let mut writer = stream.try_clone().expect("clone socket");
    let mut reader = BufReader::new(stream);

    // The server speaks first: its hello, as a JSON line.
    let mut binary = false;
    match read_message(&mut reader, false) {
        Ok(Some(Message::Json(hello))) => say!("{hello}"),
        other => {
            eprintln!("no hello from the server: {:?}", other.err());
            std::process::exit(1);
        }
    }

    // Ask for what we want (omitted keys take the defaults).
    let wants_hello = o.binary || o.rate.is_some() || o.subscribe.is_some() || o.fields.is_some();
    if wants_hello {
        let mut hello = json!({"type": "hello", "protocol": 1,
                               "format": if o.binary { "binary" } else { "json" },
                               "max_rate_hz": o.rate});
        if let Some(s) = &o.subscribe {
            hello["subscribe"] = json!(s);
        }
        if let Some(f) = &o.fields {
            hello["fields"] = json!(f);
        }
        writeln!(writer, "{hello}").expect("send hello");
    }
    if let Some(name) = &o.command {
        writeln!(
            writer,
            "{}",
            json!({"type": "command", "id": 1, "name": name})
        )
        .expect("send command");
    }

    loop {
        let msg = match read_message(&mut reader, binary) {
            Ok(Some(m)) => m,
            Ok(None) => {
                say!("connection closed");
                return;
            }
            Err(e) => {
                eprintln!("read failed: {e}");
                std::process::exit(1);
            }
        };
        match msg {
            Message::Snapshot(frame) => say!("{}", summarise_binary(&frame)),
            Message::Json(v) => match v["type"].as_str() {
                Some("snapshot") => say!("{}", summarise_json(&v)),
                Some("hello") => {
                    say!("{v}");
                    // Everything after the answer to our hello is in the new format.
                    binary = v["format"] == "binary";
                }
                Some("bye") => {
                    say!("{v}");
                    return;
                }
                _ => say!("{v}"),
            },
        }
    }
}
