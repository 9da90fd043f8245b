//! `bench websocket`: the publisher alone (no control thread) fed `--agents`-agent
//! snapshots at 120 Hz for `--seconds`, read by `--clients` WebSocket clients
//! (tungstenite, each on its own thread) in `--format`. Reports the end-to-end
//! latency (snapshot made → its last byte written to a client's socket), the
//! encode time, what every client received and every drop.

use super::rows::{row_from_samples, Row};
use crate::cli::bench::e2e_clients::WireFormat;
use anyhow::{Context, Result};
use crossbeam_channel::bounded;
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::publish::{
    HelloInfo, Outgoing, PublisherStats, Server, SocketOptions, WebSocketListener, WebSocketOptions,
};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::{AgentView, Snapshot};
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tungstenite::Message;

/// Snapshots per second, the daemon's default tick rate.
const TICK_HZ: u64 = 120;

/// What one client counted.
#[derive(Default)]
struct Counts {
    snapshots: AtomicU64,
    bytes: AtomicU64,
    notices: AtomicU64,
}

/// A crowd of `n` agents spread over the world, moved a little by `k`.
fn snapshot(n: usize, k: u64, world: Rect) -> Snapshot {
    let cols = (n as f64).sqrt().ceil() as usize;
    let (w, h) = (world.width(), world.height());
    let shift = (k % 100) as f64 * 0.001;
    let agents: Vec<AgentView> = (0..n)
        .map(|i| AgentView {
            pos: Vec2::new(
                world.min[0] + w * ((i % cols) as f64 + 0.5) / cols as f64 + shift,
                world.min[1] + h * ((i / cols) as f64 + 0.5) / cols as f64,
            ),
            vel: Vec2::new(0.1, 0.0),
            goal: i as u32,
        })
        .collect();
    let goals = agents.iter().map(|a| a.pos).collect();
    Snapshot {
        seq: k,
        t: monotonic_now(),
        input_t: Some(monotonic_now()),
        agents,
        goals,
        assignment_seq: 0,
        touches: Vec::new(),
        paused: false,
        motions: Vec::new(),
    }
}

/// Runs the workload.
pub fn websocket(
    agents: usize,
    clients: usize,
    seconds: f64,
    format: WireFormat,
) -> Result<Vec<Row>> {
    let world = Rect {
        min: [0.0, 0.0],
        max: [16.0, 9.0],
    };
    let path = std::env::temp_dir().join(format!("ct-bench-ws-{}.sock", std::process::id()));
    let server = Server::bind(
        &SocketOptions {
            mode: 0o600,
            group: None,
            client_queue: 8,
            max_clients: 8,
        },
        &path,
        HelloInfo {
            world,
            agents: agents as u32,
            agent_radius_m: 0.05,
        },
    )?;
    let listener = WebSocketListener::bind(WebSocketOptions {
        viewer: false,
        ..WebSocketOptions::on("127.0.0.1:0".parse()?, true, clients as u32)
    })?;
    let addr = listener.local_addr();
    let server = server.with_websocket(listener);
    let stats: Arc<PublisherStats> = server.stats();
    let (tx, rx) = bounded(crowdtouch::publish::socket::QUEUE_CAPACITY);
    let (commands, _commands_rx) = bounded(64);
    let stop = Arc::new(AtomicBool::new(false));
    let publisher = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || server.run(rx, commands, stop))
    };
    let done = Arc::new(AtomicBool::new(false));
    let mut readers = Vec::new();
    let mut counts = Vec::new();
    for _ in 0..clients {
        let c = Arc::new(Counts::default());
        counts.push(Arc::clone(&c));
        let done = Arc::clone(&done);
        let stream = TcpStream::connect(addr).context("connect to the WebSocket output")?;
        stream.set_read_timeout(Some(Duration::from_millis(100)))?;
        let (mut ws, _) = tungstenite::client(format!("ws://{addr}/ws"), stream)
            .map_err(|e| anyhow::anyhow!("WebSocket handshake: {e}"))?;
        if format == WireFormat::Binary {
            ws.send(Message::Text(
                r#"{"type":"hello","protocol":1,"format":"binary"}"#.into(),
            ))?;
        }
        readers.push(std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                match ws.read() {
                    Ok(Message::Binary(b)) => {
                        c.snapshots.fetch_add(1, Ordering::Relaxed);
                        c.bytes.fetch_add(b.len() as u64, Ordering::Relaxed);
                    }
                    Ok(Message::Text(t)) => {
                        c.bytes.fetch_add(t.len() as u64, Ordering::Relaxed);
                        if t.starts_with(r#"{"type":"snapshot""#) {
                            c.snapshots.fetch_add(1, Ordering::Relaxed);
                        } else if t.starts_with(r#"{"type":"dropped""#) {
                            c.notices.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                    Ok(_) => {}
                    Err(tungstenite::Error::Io(e))
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) => {}
                    Err(_) => break,
                }
            }
        }));
    }
    // Every client admitted (and its binary hello applied) before the first snapshot.
    let admitted = Instant::now();
    while stats.clients() < clients as u32 && admitted.elapsed() < Duration::from_secs(5) {
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(200));
    let _ = stats.take_end_to_end();
    let _ = stats.take_encode();
    let ticks = (seconds * TICK_HZ as f64).round() as u64;
    let period = Duration::from_micros(1_000_000 / TICK_HZ);
    let mut make_us = Vec::with_capacity(ticks as usize);
    let t0 = Instant::now();
    let cpu0 = cpu_time();
    for k in 0..ticks {
        let due = t0 + period * k as u32;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let m0 = Instant::now();
        let s = Arc::new(snapshot(agents, k, world));
        make_us.push(m0.elapsed().as_secs_f64() * 1e6);
        if tx.try_send(Outgoing::Snapshot(s)).is_err() {
            anyhow::bail!("the publisher's queue is full: it stalled");
        }
    }
    std::thread::sleep(Duration::from_millis(500));
    let wall = t0.elapsed().as_secs_f64();
    let cpu = cpu_time().saturating_sub(cpu0);
    done.store(true, Ordering::Relaxed);
    stop.store(true, Ordering::Relaxed);
    drop(tx);
    for r in readers {
        let _ = r.join();
    }
    let _ = publisher.join();
    let e2e = stats.take_end_to_end();
    let enc = stats.take_encode();
    let received: Vec<u64> = counts
        .iter()
        .map(|c| c.snapshots.load(Ordering::Relaxed))
        .collect();
    let mb_s: f64 = counts
        .iter()
        .map(|c| c.bytes.load(Ordering::Relaxed) as f64)
        .sum::<f64>()
        / wall
        / 1e6;
    let notices: u64 = counts
        .iter()
        .map(|c| c.notices.load(Ordering::Relaxed))
        .sum();
    let fmt = match format {
        WireFormat::Json => "json",
        WireFormat::Binary => "binary",
    };
    let note = format!(
        "{ticks} sent at {TICK_HZ} Hz; received per client {received:?}; dropped {} \
         ({notices} notices); {mb_s:.0} MB/s to clients; process CPU {:.0} % of one core \
         (snapshot making included)",
        stats.snapshots_dropped(),
        cpu.as_secs_f64() / wall * 100.0
    );
    let hist_row = |name: String, h: &hdrhistogram::Histogram<u64>, note: String| Row {
        workload: name,
        samples: h.len(),
        p50_us: h.value_at_quantile(0.5) as f64,
        p99_us: h.value_at_quantile(0.99) as f64,
        max_us: h.max() as f64,
        note,
    };
    Ok(vec![
        hist_row(
            format!("websocket e2e {agents} agents × {clients} {fmt}"),
            &e2e,
            note,
        ),
        hist_row(
            format!("websocket encode {agents} {fmt}"),
            &enc,
            "one encoding per tick, shared by every client".to_string(),
        ),
        row_from_samples(
            "websocket bench: making a snapshot",
            make_us,
            "the bench's own cost, not the daemon's".to_string(),
        ),
    ])
}

/// CPU time of this process so far.
fn cpu_time() -> Duration {
    let t = nix::time::clock_gettime(nix::time::ClockId::CLOCK_PROCESS_CPUTIME_ID)
        .unwrap_or(nix::sys::time::TimeSpec::new(0, 0));
    Duration::from(t)
}
