//! Issue 27 finding 5, a ping flood against the daemon's WebSocket output, in a test
//! binary of its own: the daemon runs in its own process (its RSS is read from
//! /proc) and the flood loads the machine, so no other test runs beside it (cargo
//! runs test binaries one after another).

mod common;

use common::{free_addr, raw_upgrade};
use std::io::Write;
use std::net::TcpStream;
use std::path::Path;
use std::time::{Duration, Instant};
use tungstenite::{Message, WebSocket};

/// A masked ping frame from a client, with `payload` (at most 125 bytes).
fn ping_frame(payload: &[u8]) -> Vec<u8> {
    let key = [0x12, 0x34, 0x56, 0x78];
    let mut f = vec![0x89, 0x80 | payload.len() as u8];
    f.extend_from_slice(&key);
    f.extend(payload.iter().enumerate().map(|(i, b)| b ^ key[i % 4]));
    f
}

/// The daemon's resident memory (kB), from /proc.
fn rss_kb(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

/// Issue 27 finding 5: 16 clients send 125-byte pings for 10 s and read nothing,
/// while a well-behaved client reads. The daemon (`run` on the shipped config's
/// recordings with a WebSocket output for 17 clients, in its own process)
/// stays within 100 MB of its idle RSS and the good client misses no snapshot.
/// The flood stops early once the limit is passed (the old daemon grew ~240 MB/s
/// per client), so a failure costs the machine little.
#[test]
fn a_ping_flood_grows_no_memory_and_starves_no_reader() {
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
    use std::sync::Arc;
    const FLOODERS: usize = 16;
    const FLOOD: Duration = Duration::from_secs(10);
    const LIMIT_KB: u64 = 100 * 1024;
    let dir = tempfile::tempdir().unwrap();
    let addr = free_addr();
    // The shipped config (its recordings by absolute path), 200 agents, and a
    // WebSocket output with room for the flooders and the good client.
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut text = crowdtouch::config::DEFAULT_CONFIG_RON.replace(
        "\"recordings/",
        &format!("\"{}/", manifest.join("config/recordings").display()),
    );
    text = text.replacen("agents: 100,", "agents: 200,", 1);
    let end = text.rfind(')').expect("the config's closing paren");
    text.insert_str(
        end,
        &format!(
            "    outputs: [WebSocket(listen: \"{addr}\", privileged: true, max_clients: {})],\n",
            FLOODERS + 1
        ),
    );
    let config = dir.path().join("crowdtouch.ron");
    std::fs::write(&config, text).unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
        .args(["run", "--config"])
        .arg(&config)
        .arg("--socket")
        .arg(dir.path().join("ct.sock"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("the built binary runs");
    let pid = child.id();
    let t0 = Instant::now();
    while TcpStream::connect(addr).is_err() {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "the daemon never listened"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    // The good client: every snapshot's seq, and any dropped notice.
    let stop = Arc::new(AtomicBool::new(false));
    let (snaps, gaps, drops) = (
        Arc::new(AtomicU64::new(0)),
        Arc::new(AtomicU64::new(0)),
        Arc::new(AtomicU64::new(0)),
    );
    let stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let (mut good, _): (WebSocket<TcpStream>, _) =
        tungstenite::client(format!("ws://{addr}/ws"), stream).expect("the good client connects");
    let reader = {
        let (stop, snaps, gaps, drops) = (stop.clone(), snaps.clone(), gaps.clone(), drops.clone());
        std::thread::spawn(move || {
            let mut last: Option<u64> = None;
            while !stop.load(Ordering::Relaxed) {
                let text = match good.read() {
                    Ok(Message::Text(t)) => t,
                    Ok(Message::Close(_)) => break,
                    Ok(_) => continue,
                    Err(tungstenite::Error::Io(e))
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                        ) =>
                    {
                        continue
                    }
                    Err(_) => break,
                };
                let v: serde_json::Value = serde_json::from_str(text.as_str()).unwrap();
                if v["type"] == "dropped" {
                    drops.fetch_add(1, Ordering::Relaxed);
                }
                if v["type"] == "snapshot" {
                    let seq = v["seq"].as_u64().unwrap();
                    if last.is_some_and(|l| seq != l + 1) {
                        gaps.fetch_add(1, Ordering::Relaxed);
                    }
                    if v["dropped"].as_u64().unwrap_or(0) > 0 {
                        drops.fetch_add(1, Ordering::Relaxed);
                    }
                    last = Some(seq);
                    snaps.fetch_add(1, Ordering::Relaxed);
                }
            }
        })
    };
    std::thread::sleep(Duration::from_secs(2));
    let idle = rss_kb(pid).expect("the daemon's RSS");
    let before = snaps.load(Ordering::Relaxed);
    let ping = ping_frame(&[b'p'; 125]);
    let flooders: Vec<_> = (0..FLOODERS)
        .map(|_| {
            let (stop, ping) = (stop.clone(), ping.clone());
            let mut s = raw_upgrade(addr);
            s.set_write_timeout(Some(Duration::from_millis(50)))
                .unwrap();
            std::thread::spawn(move || {
                let (mut sent, start) = (0u64, Instant::now());
                while !stop.load(Ordering::Relaxed) && start.elapsed() < FLOOD {
                    match s.write_all(&ping) {
                        Ok(()) => sent += 1,
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) => {}
                        Err(_) => break, // the daemon dropped it
                    }
                }
                sent
            })
        })
        .collect();
    let (mut peak, start) = (idle, Instant::now());
    while start.elapsed() < FLOOD + Duration::from_millis(500) {
        let now = rss_kb(pid).unwrap_or(0);
        peak = peak.max(now);
        if now > idle + LIMIT_KB {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    stop.store(true, Ordering::Relaxed);
    let sent: u64 = flooders.into_iter().map(|t| t.join().unwrap()).sum();
    reader.join().unwrap();
    let _ = nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(pid as i32),
        nix::sys::signal::Signal::SIGTERM,
    );
    let _ = child.wait();
    let (snaps, gaps, drops) = (
        snaps.load(Ordering::Relaxed) - before,
        gaps.load(Ordering::Relaxed),
        drops.load(Ordering::Relaxed),
    );
    println!(
        "ping flood: {FLOODERS} clients sent {sent} pings in {:.1} s; daemon RSS idle {idle} kB, \
         peak {peak} kB (+{} kB); the good client got {snaps} snapshots, {gaps} seq gaps, \
         {drops} drop notices",
        start.elapsed().as_secs_f64(),
        peak - idle
    );
    assert!(
        peak <= idle + LIMIT_KB,
        "RSS grew from {idle} kB to {peak} kB under the ping flood"
    );
    assert!(
        snaps > 100,
        "the good client kept reading: {snaps} snapshots"
    );
    assert_eq!((gaps, drops), (0, 0), "the good client missed snapshots");
}
