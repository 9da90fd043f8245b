//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod edit_session;
pub mod run_process;

use crowdtouch::config::Config;
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::geom::Vec2;
use crowdtouch::input::recording::{OnBadFrame, Recording};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{Event, MeshView, Snapshot};
use serde_json::Value;
use std::convert::Infallible;
use std::io::{BufRead, BufReader};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Path of a shipped recording.
pub fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/recordings")
        .join(name)
}

/// Loads a shipped recording.
pub fn load(name: &str) -> Recording {
    crowdtouch::input::recording::load_recording(&shipped(name), OnBadFrame::Stop)
        .expect("shipped recording loads")
}

/// Everything a replay produced.
pub struct Run {
    pub snapshots: Vec<Arc<Snapshot>>,
    pub events: Vec<Event>,
    pub meshes: Vec<Arc<MeshView>>,
}

impl Run {
    pub fn last(&self) -> &Snapshot {
        self.snapshots.last().expect("at least one snapshot")
    }
    pub fn first_mesh(&self) -> &MeshView {
        self.meshes.first().expect("a mesh")
    }
    pub fn last_mesh(&self) -> &MeshView {
        self.meshes.last().expect("a mesh")
    }
    /// Snapshot with sequence number `seq`.
    pub fn at(&self, seq: u64) -> &Snapshot {
        &self.snapshots[(seq - 1) as usize]
    }
}

/// Replays a shipped recording through the engine on a virtual clock with inline
/// (exact, every tick) assignment, then lets the crowd settle.
pub fn replay(name: &str, cfg: &Config, settle_s: f64) -> Run {
    let rec = load(name);
    let mut engine = Engine::new(cfg, rec.surface.size_mm(), true);
    let mut run = Run {
        snapshots: vec![],
        events: vec![],
        meshes: vec![],
    };
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(settle_s),
        max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
    };
    replay_virtual(
        &mut engine,
        rec.frames.iter().map(|f| Ok(*f)),
        clock,
        |_| {},
        |o| {
            run.snapshots.push(Arc::new((*o.snapshot).clone()));
            run.events.extend(o.events.iter().cloned());
            if let Some(m) = &o.mesh {
                run.meshes.push(Arc::new((**m).clone()));
            }
            Ok::<(), Infallible>(())
        },
    )
    .unwrap();
    run
}

/// Reads a socket client's JSON lines until `until` returns true (that line is the
/// last one returned) or `secs` are up.
pub fn read_until(
    r: &mut BufReader<UnixStream>,
    secs: f64,
    mut until: impl FnMut(&Value) -> bool,
) -> Vec<Value> {
    r.get_ref()
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let end = Instant::now() + Duration::from_secs_f64(secs);
    let mut out = vec![];
    let mut line = String::new();
    while Instant::now() < end {
        match r.read_line(&mut line) {
            Ok(0) => break,
            Ok(_) => {
                let v: Value = serde_json::from_str(&line)
                    .unwrap_or_else(|e| panic!("bad line {line:?}: {e}"));
                line.clear();
                let stop = until(&v);
                out.push(v);
                if stop {
                    break;
                }
            }
            Err(e)
                if e.kind() == std::io::ErrorKind::WouldBlock
                    || e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) => panic!("read: {e}"),
        }
    }
    out
}

pub fn centroid(ps: impl IntoIterator<Item = Vec2>) -> Vec2 {
    let (mut s, mut n) = (Vec2::zeros(), 0.0);
    for p in ps {
        s += p;
        n += 1.0;
    }
    s / n
}

/// Minimum total cost of assigning `agents` to `goals` with squared-distance cost,
/// computed by an independent solver (pathfinding's Kuhn–Munkres on costs scaled to
/// integers), in the same units as the sum of squared distances.
pub fn reference_optimal_cost(agents: &[Vec2], goals: &[Vec2]) -> f64 {
    const SCALE: f64 = 1e6;
    let n = agents.len();
    let mut data = Vec::with_capacity(n * goals.len());
    for a in agents {
        for g in goals {
            data.push(-((a - g).norm_squared() * SCALE).round() as i64);
        }
    }
    let m = pathfinding::matrix::Matrix::from_vec(n, goals.len(), data).expect("matrix");
    let (total, _) = pathfinding::kuhn_munkres::kuhn_munkres(&m);
    -(total as f64) / SCALE
}

/// Total squared-distance cost of an assignment.
pub fn assignment_cost(agents: &[Vec2], goals: &[Vec2], goal_of: impl Iterator<Item = u32>) -> f64 {
    agents
        .iter()
        .zip(goal_of)
        .map(|(a, g)| (a - goals[g as usize]).norm_squared())
        .sum()
}

/// Best rigid transform (rotation + translation) from `a` to `b` (2-D Procrustes);
/// returns (angle in radians, max residual in metres).
pub fn rigid_fit(a: &[Vec2], b: &[Vec2]) -> (f64, f64) {
    let ca = centroid(a.iter().copied());
    let cb = centroid(b.iter().copied());
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (p, q) = (p - ca, q - cb);
        sxx += p.x * q.x + p.y * q.y;
        sxy += p.x * q.y - p.y * q.x;
    }
    let th = sxy.atan2(sxx);
    let (s, c) = th.sin_cos();
    let mut worst: f64 = 0.0;
    for (p, q) in a.iter().zip(b) {
        let d = p - ca;
        let r = cb + Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        worst = worst.max((r - q).norm());
    }
    (th, worst)
}

/// The reloaded scene of the reload tests: a block in the middle of the default
/// crowd start (6,3)..(10,6) and a pool over its west part.
pub const BLOCK_IN_THE_CROWD: &str = "(
    version: 1,
    name: \"block in the crowd\",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    obstacles: [
        (name: \"block\", parts: [
            Polygon(vertices_m: [(7.4, 3.9), (8.6, 3.9), (8.6, 5.1), (7.4, 5.1)]),
        ]),
    ],
    patches: [
        (name: \"pool\", motion: swim, parts: [
            Polygon(vertices_m: [(5.0, 2.0), (6.9, 2.0), (6.9, 7.0), (5.0, 7.0)]),
        ]),
    ],
)";

/// Whether `p` is inside [`BLOCK_IN_THE_CROWD`]'s block shrunk by `margin_m` on
/// every side (a millimetre covers the rounding of positions on the wire).
pub fn in_crowd_block(p: Vec2, margin_m: f64) -> bool {
    p.x > 7.4 + margin_m && p.x < 8.6 - margin_m && p.y > 3.9 + margin_m && p.y < 5.1 - margin_m
}

/// The `outputs` entry named `output` of a `stats` report, and a reader of its
/// counts by name (panics naming what is missing).
pub fn output_counts(
    report: &crowdtouch::vocab::StatsReport,
    output: &str,
) -> (serde_json::Value, impl Fn(&str) -> u64) {
    let stats = serde_json::to_value(report).unwrap();
    let entry = stats["outputs"]
        .as_array()
        .and_then(|o| o.iter().find(|e| e["output"] == output))
        .unwrap_or_else(|| panic!("no {output} in the stats' outputs: {stats}"))
        .clone();
    let counts = entry.clone();
    (entry, move |k: &str| {
        counts["counts"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c[0] == k)
            .and_then(|c| c[1].as_u64())
            .unwrap_or_else(|| panic!("no {k} in {counts}"))
    })
}

/// The daemon on `cfg` serving its socket at `socket`, with one channel source of
/// `capacity` frames: the touch frames the test sends (keep the sender: dropping it
/// ends the source).
pub fn daemon_on_channel(
    cfg: Config,
    socket: &Path,
    capacity: usize,
) -> (
    crowdtouch::pipeline::Daemon,
    crossbeam_channel::Sender<crowdtouch::vocab::TouchFrame>,
) {
    use crowdtouch::pipeline::{Daemon, DaemonOptions, SourceSpec};
    let (tx, rx) = crossbeam_channel::bounded(capacity);
    let daemon = Daemon::start(
        cfg,
        vec![SourceSpec::Channel { rx, glass_mm: None }],
        DaemonOptions {
            socket_path: socket.to_path_buf(),
            collect: None,
        },
    )
    .expect("daemon starts");
    (daemon, tx)
}

/// A port free a moment ago on loopback.
pub fn free_addr() -> std::net::SocketAddr {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
}

/// A WebSocket upgrade of `/ws` on `addr` by hand (HTTP/1.1, the RFC's sample key,
/// version 13, no Origin), its `101` head read: the stream is then the client's
/// side of the WebSocket, for frames written by hand.
pub fn raw_upgrade(addr: std::net::SocketAddr) -> std::net::TcpStream {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    let head = format!(
        "GET /ws HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    );
    s.write_all(head.as_bytes()).unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n\r\n") {
        s.read_exact(&mut b).unwrap();
        head.push(b[0]);
    }
    assert!(
        head.starts_with(b"HTTP/1.1 101"),
        "{}",
        String::from_utf8_lossy(&head)
    );
    s
}

/// Writes `frames` as a JSONL recording of a glass of `glass_mm` (0.1 mm units)
/// named `device`.
pub fn write_jsonl(
    frames: &[crowdtouch::vocab::TouchFrame],
    glass_mm: (f64, f64),
    device: &str,
    path: &Path,
) {
    use crowdtouch::input::{AxisRange, SurfaceInfo};
    let axis = |mm: f64| AxisRange {
        min: 0.0,
        max: mm * 10.0,
        resolution: 10.0,
    };
    let surface = SurfaceInfo {
        name: device.to_string(),
        x: axis(glass_mm.0),
        y: axis(glass_mm.1),
        max_contacts: 10,
    };
    let file = std::fs::File::create(path).unwrap();
    let mut w =
        crowdtouch::input::recording::JsonlWriter::new(&surface, std::io::BufWriter::new(file))
            .unwrap();
    for f in frames {
        w.frame(f).unwrap();
    }
    w.flush().unwrap();
}

/// The shipped one-finger drag over the crowd, stamped now; `paced` sends it at its
/// own pace, otherwise as fast as the channel takes it.
pub fn send_drag(tx: &crossbeam_channel::Sender<crowdtouch::vocab::TouchFrame>, paced: bool) {
    let rec = crowdtouch::input::recording::read_recording(
        &shipped("01-point-drag.jsonl"),
        crowdtouch::input::recording::OnBadFrame::Stop,
    )
    .unwrap();
    let start = std::time::Instant::now();
    let t0 = rec.frames[0].t;
    for f in &rec.frames {
        if paced {
            let due = std::time::Duration::from_micros(f.t.saturating_since(t0).0);
            if let Some(wait) = due.checked_sub(start.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        let mut g = crowdtouch::vocab::TouchFrame::new(crowdtouch::rt::monotonic_now());
        for c in f.contacts() {
            g.push(*c).unwrap();
        }
        tx.send(g).unwrap();
    }
}
