//! End-to-end: a touch frame stamped with CLOCK_MONOTONIC enters the daemon's input
//! queue; the time until a socket client has read the snapshot that reflects it.
//! The full daemon runs (input thread, control thread, assignment worker,
//! publisher) with 100 and 1,000 agents. `crowdtouch bench e2e` reports the
//! distribution (p50/p99/max) of the same path while replaying at 120 Hz.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::config::{Config, LogLevel};
use crowdtouch::pipeline::{Daemon, DaemonOptions, SourceSpec};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
use std::io::{BufRead, BufReader};
use std::os::unix::net::UnixStream;
use std::time::{Duration, Instant};

fn e2e(c: &mut Criterion) {
    let mut g = c.benchmark_group("end_to_end");
    g.sample_size(30);
    for agents in [100u32, 1000] {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = agents;
        cfg.log_level = LogLevel::Error;
        // No timer ticks between frames: every snapshot after a send reflects it.
        cfg.pipeline.tick_hz = 1.0;
        let dir = std::env::temp_dir().join(format!(
            "crowdtouch-bench-e2e-{}-{agents}",
            std::process::id()
        ));
        let _ = std::fs::create_dir_all(&dir);
        let sock = dir.join("s.sock");
        let (tx, rx) = crossbeam_channel::bounded::<TouchFrame>(64);
        let daemon = Daemon::start(
            cfg,
            vec![SourceSpec::Channel { rx, glass_mm: None }],
            DaemonOptions {
                socket_path: sock.clone(),
                collect: None,
            },
        )
        .expect("daemon starts");
        let mut r = BufReader::new(UnixStream::connect(&sock).expect("connect"));
        let mut line = String::new();
        // Registered once the hello has arrived; only then do snapshots reach us.
        while !line.starts_with("{\"type\":\"hello\"") {
            line.clear();
            r.read_line(&mut line).expect("hello");
        }
        let mut k = 0u32;
        let mut send = |flags: ContactFlags| {
            k += 1;
            let mut f = TouchFrame::new(monotonic_now());
            let x = 0.45 + 0.1 * ((k % 200) as f32 / 200.0);
            let _ = f.push(Contact {
                id: ContactId(1),
                x,
                y: 0.5,
                flags,
                ..Contact::default()
            });
            tx.send(f).expect("daemon input alive");
        };
        let mut wait_snapshot = |r: &mut BufReader<UnixStream>| loop {
            line.clear();
            if r.read_line(&mut line).map(|n| n == 0).unwrap_or(true) {
                panic!("daemon closed the socket");
            }
            if line.starts_with("{\"type\":\"snapshot\"") && !line.contains("\"latency_us\":null") {
                return;
            }
        };
        send(ContactFlags::DOWN);
        wait_snapshot(&mut r);
        std::thread::sleep(Duration::from_millis(200));
        g.bench_function(BenchmarkId::from_parameter(agents), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    // 120 Hz pacing, as a touch table sends.
                    std::thread::sleep(Duration::from_micros(8_333));
                    let t0 = Instant::now();
                    send(ContactFlags::NONE);
                    wait_snapshot(&mut r);
                    total += t0.elapsed();
                }
                total
            })
        });
        send(ContactFlags::UP);
        daemon.shutdown();
        let _ = std::fs::remove_dir_all(&dir);
    }
    g.finish();
}

criterion_group!(benches, e2e);
criterion_main!(benches);
