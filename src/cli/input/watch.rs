//! `crowdtouch watch`: a terminal client of the protocol.
//!
//! Draws agents as braille dots in a box scaled to the world, the mesh outline, and
//! touches (their control id, or `g` for a gesture), with a latency line underneath.

use crate::cli::common::output::{out, outln};
use anyhow::{Context, Result};
use clap::Args;
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A canvas of braille cells (2×4 dots per character).
struct Canvas {
    w: usize,
    h: usize,
    dots: Vec<u8>,
    chars: Vec<Option<char>>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        Canvas {
            w,
            h,
            dots: vec![0; w * h],
            chars: vec![None; w * h],
        }
    }
    fn clear(&mut self) {
        self.dots.iter_mut().for_each(|d| *d = 0);
        self.chars.iter_mut().for_each(|c| *c = None);
    }
    fn dot(&mut self, px: i64, py: i64) {
        if px < 0 || py < 0 || px >= 2 * self.w as i64 || py >= 4 * self.h as i64 {
            return;
        }
        let (cx, cy) = (px as usize / 2, py as usize / 4);
        let (sx, sy) = (px as usize % 2, py as usize % 4);
        // Braille dot numbering: column 0 rows 0-2 = bits 0,1,2; column 1 = 3,4,5; row 3 = 6,7.
        let bit = match (sx, sy) {
            (0, 3) => 6,
            (1, 3) => 7,
            (0, y) => y,
            (_, y) => 3 + y,
        };
        self.dots[cy * self.w + cx] |= 1 << bit;
    }
    fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64)) {
        let n = (x1 - x0).abs().max((y1 - y0).abs()).max(1);
        for k in 0..=n {
            self.dot(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n);
        }
    }
    fn put(&mut self, cx: i64, cy: i64, c: char) {
        if cx >= 0 && cy >= 0 && (cx as usize) < self.w && (cy as usize) < self.h {
            self.chars[cy as usize * self.w + cx as usize] = Some(c);
        }
    }
    fn render(&self, out: &mut String) {
        out.push('┌');
        out.extend(std::iter::repeat_n('─', self.w));
        out.push_str("┐\r\n");
        for y in 0..self.h {
            out.push('│');
            for x in 0..self.w {
                let i = y * self.w + x;
                match self.chars[i] {
                    Some(c) => {
                        out.push_str("\x1b[1;33m");
                        out.push(c);
                        out.push_str("\x1b[0m");
                    }
                    None if self.dots[i] == 0 => out.push(' '),
                    None => out.push(char::from_u32(0x2800 + self.dots[i] as u32).unwrap_or('?')),
                }
            }
            out.push_str("│\r\n");
        }
        out.push('└');
        out.extend(std::iter::repeat_n('─', self.w));
        out.push_str("┘\r\n");
    }
}

fn flat_pairs(v: &Value) -> Vec<(f64, f64)> {
    let a = v.as_array().map(Vec::as_slice).unwrap_or(&[]);
    a.chunks_exact(2)
        .map(|c| (c[0].as_f64().unwrap_or(0.0), c[1].as_f64().unwrap_or(0.0)))
        .collect()
}

#[derive(Default)]
struct View {
    world: ([f64; 2], [f64; 2]),
    agents: Vec<(f64, f64)>,
    mesh: Vec<(f64, f64)>,
    outline: Vec<usize>,
    touches: Vec<(f64, f64, Option<u64>)>,
    seq: u64,
    dropped: u64,
    latencies: Vec<u64>,
    snapshots: u64,
    last_event: String,
}

impl View {
    fn take(&mut self, v: &Value) {
        match v.get("type").and_then(Value::as_str) {
            Some("hello") => {
                let w = &v["world"];
                let p = |k: &str, i: usize| w[k][i].as_f64().unwrap_or(0.0);
                self.world = ([p("min", 0), p("min", 1)], [p("max", 0), p("max", 1)]);
            }
            Some("mesh") => {
                self.mesh = flat_pairs(&v["vertices"]);
                if let Some(o) = v["outline"].as_array() {
                    self.outline = o
                        .iter()
                        .filter_map(|x| x.as_u64().map(|x| x as usize))
                        .collect();
                }
            }
            Some("snapshot") => {
                self.snapshots += 1;
                self.seq = v["seq"].as_u64().unwrap_or(0);
                self.dropped = v["dropped"].as_u64().unwrap_or(0);
                if let Some(l) = v["latency_us"].as_u64() {
                    self.latencies.push(l);
                }
                self.agents = flat_pairs(&v["positions"]);
                self.touches = v["touches"]
                    .as_array()
                    .map(|ts| {
                        ts.iter()
                            .map(|t| {
                                (
                                    t["x"].as_f64().unwrap_or(0.0),
                                    t["y"].as_f64().unwrap_or(0.0),
                                    t["control"].as_u64(),
                                )
                            })
                            .collect()
                    })
                    .unwrap_or_default();
            }
            Some("control") | Some("gesture") => {
                self.last_event = format!(
                    "{} {} {}",
                    v["type"].as_str().unwrap_or(""),
                    v["phase"].as_str().unwrap_or(""),
                    v["kind"].as_str().unwrap_or("")
                );
            }
            Some("error") => {
                self.last_event = format!("error: {}", v["message"].as_str().unwrap_or(""))
            }
            _ => {}
        }
    }

    fn draw(&mut self, canvas: &mut Canvas, out: &mut String, fps: f64) {
        canvas.clear();
        let (min, max) = self.world;
        let (ww, wh) = ((max[0] - min[0]).max(1e-9), (max[1] - min[1]).max(1e-9));
        let (pw, ph) = (2.0 * canvas.w as f64, 4.0 * canvas.h as f64);
        let s = (pw / ww).min(ph / wh);
        let to_px = |x: f64, y: f64| (((x - min[0]) * s) as i64, ((y - min[1]) * s) as i64);
        if self.outline.len() > 1 {
            for k in 0..self.outline.len() {
                let (a, b) = (self.outline[k], self.outline[(k + 1) % self.outline.len()]);
                if let (Some(&pa), Some(&pb)) = (self.mesh.get(a), self.mesh.get(b)) {
                    canvas.line(to_px(pa.0, pa.1), to_px(pb.0, pb.1));
                }
            }
        }
        for &(x, y) in &self.agents {
            let (px, py) = to_px(x, y);
            canvas.dot(px, py);
        }
        for &(x, y, c) in &self.touches {
            let (px, py) = to_px(x, y);
            let ch = match c {
                Some(id) => char::from_digit((id % 10) as u32, 10).unwrap_or('*'),
                None => 'g',
            };
            canvas.put(px / 2, py / 4, ch);
        }
        out.clear();
        out.push_str("\x1b[H");
        canvas.render(out);
        self.latencies.sort_unstable();
        let q = |p: f64| -> f64 {
            if self.latencies.is_empty() {
                0.0
            } else {
                self.latencies[((self.latencies.len() - 1) as f64 * p) as usize] as f64 / 1000.0
            }
        };
        out.push_str(&format!(
            "agents {:>5}  seq {:>8}  {:>5.0} snapshots/s  latency p50 {:>5.2} ms p99 {:>5.2} ms  dropped {}  {}\x1b[K\r\n",
            self.agents.len(),
            self.seq,
            self.snapshots as f64 * fps,
            q(0.5),
            q(0.99),
            self.dropped,
            self.last_event
        ));
        self.latencies.clear();
        self.snapshots = 0;
    }
}

/// Runs the watcher until the daemon closes the socket, Ctrl-C, or `seconds`.
pub fn watch(socket: Option<PathBuf>, fps: f64, seconds: Option<f64>) -> Result<()> {
    let mut reader = crate::cli::common::socket::connect(socket)?;
    let stop = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGINT, Arc::clone(&stop))?;
    signal_hook::flag::register(signal_hook::consts::SIGTERM, Arc::clone(&stop))?;
    let (tx, rx) = crossbeam_channel::bounded::<Value>(4096);
    std::thread::spawn(move || {
        let mut line = String::new();
        while let Ok(Some(())) = crate::cli::common::socket::read_line(&mut reader, &mut line) {
            if let Ok(v) = serde_json::from_str::<Value>(&line) {
                if tx.send(v).is_err() {
                    break;
                }
            }
        }
    });
    let (cols, rows) = terminal_size::terminal_size()
        .map(|(w, h)| (w.0 as usize, h.0 as usize))
        .unwrap_or((100, 32));
    let mut canvas = Canvas::new(
        cols.saturating_sub(2).max(20),
        rows.saturating_sub(4).max(8),
    );
    let mut view = View::default();
    let mut out = String::new();
    let frame = Micros::from_secs_f64(1.0 / fps.clamp(1.0, 120.0));
    let until = seconds.map(|s| monotonic_now() + Micros::from_secs_f64(s));
    let stdout = std::io::stdout();
    out!("\x1b[2J\x1b[?25l")?;
    let mut ended = false;
    while !stop.load(Ordering::Relaxed) && until.is_none_or(|u| monotonic_now() < u) {
        let deadline = monotonic_now() + frame;
        loop {
            let left = deadline.saturating_since(monotonic_now());
            if left == Micros::ZERO {
                break;
            }
            match rx.recv_timeout(std::time::Duration::from_micros(left.0)) {
                Ok(v) => view.take(&v),
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => break,
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
                    ended = true;
                    break;
                }
            }
        }
        view.draw(&mut canvas, &mut out, 1.0 / frame.as_secs_f64());
        let mut lock = stdout.lock();
        lock.write_all(out.as_bytes())
            .and_then(|()| lock.flush())
            .context("drawing on stdout")?;
        if ended {
            break;
        }
    }
    out!("\x1b[?25h\r\n")?;
    if ended {
        outln!("the daemon closed the connection")?;
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct WatchArgs {
    /// Socket path (default: as the daemon resolves it).
    #[arg(long)]
    pub socket: Option<PathBuf>,
    /// Redraws per second.
    #[arg(long, default_value_t = 20.0)]
    pub fps: f64,
    /// Stop after this many seconds.
    #[arg(long)]
    pub seconds: Option<f64>,
}
