//! `bench e2e`'s snapshot clients: the wire format and fields they ask for (their
//! hello), the Unix socket client and the WebSocket clients reading the daemon's
//! stream, and what each read (snapshots, bytes, latencies, drops, sequence gaps).

use anyhow::{Context, Result};
use clap::ValueEnum;
use crowdtouch::rt::monotonic_now;
use std::io::{BufRead, BufReader, Read};
use std::net::TcpStream;
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

/// What a client read.
#[derive(Default)]
pub struct ClientRead {
    pub snapshots: u64,
    /// `tracks` messages (edit mode): while fingers hold people, and after releases.
    pub tracks_partial: u64,
    pub tracks_full: u64,
    bytes: u64,
    /// Input event → the snapshot read here (µs): exact in JSON (`input_t_us`),
    /// an upper bound in binary (`latency_us` plus read time − tick time).
    pub latency_us: Vec<f64>,
    /// The highest cumulative `dropped` a snapshot carried.
    pub dropped: u64,
    /// The counts of the `dropped` notices, summed.
    pub noticed: u64,
    /// Sequence numbers missing between snapshots read.
    pub seq_gaps: u64,
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
    pub fn rates(&self) -> (f64, f64) {
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

pub fn hello(format: WireFormat, fields: FieldChoice, edit: bool) -> String {
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
pub fn read_stream(stream: UnixStream, format: WireFormat) -> ClientRead {
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

/// One WebSocket client: connects, sends the same hello as the Unix client and
/// reads every message until the daemon closes the connection (or `done`).
pub fn read_websocket(
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

#[cfg(test)]
mod tests {
    use super::*;

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
