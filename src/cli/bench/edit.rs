//! `bench edit`: crowd motion editing against the budgets.
//!
//! - The spatial editor on `people` tracks × 100 samples (a 20-wide block walking a
//!   gently curving path, as `benches/edit_cage.rs`): a cage built and its first drag
//!   (what the first edited tracks after a touch-down cost), then each later drag of
//!   the same handle with the samples written back.
//! - Collision detection (`collide::detect`, threshold 0.3 m) on `walkers` random
//!   walkers × 200 samples (60 × 60 m, 1.3 m/s, 0.1 s step), and on each UCY file
//!   in `tests/fixtures/crowd/` when the source tree is at hand.
//! - The engine's tick in edit mode with `people` tracks loaded while a finger drags
//!   their group; the drag's jobs (the formation thread's work in the daemon) are run
//!   and applied outside the measured time.

use super::rows::{row_from_samples, Row};
use anyhow::{Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{read_tracks, ReadOptions};
use crowdtouch::crowd::edit::{
    detect, Cage, CageParams, Handle, Selection, SelectionQuery, Track, TrackSet,
};
use crowdtouch::engine::Engine;
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::{Command, Contact, ContactFlags, ContactId, Micros, TouchFrame};
use std::path::Path;
use std::time::Instant;

/// Collision threshold (m), `edit check`'s default.
const THRESHOLD_M: f64 = 0.3;

/// What to run.
pub struct EditRun {
    /// Tracks of the cage and tick workloads.
    pub people: usize,
    /// Random walkers of the collision workload.
    pub walkers: usize,
    /// Timed repetitions of each workload (ticks: ten times as many).
    pub repeats: usize,
}

fn us(t0: Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e6
}

/// `people` in a block 20 wide, 0.8 m apart with 0.1 m of jitter, walking a gently
/// curving path at 1.2 m/s, 100 samples 0.5 s apart.
fn block(people: usize) -> TrackSet {
    let mut rng = SplitMix64::new(17);
    let tracks = (0..people as u64)
        .map(|i| {
            let (row, col) = ((i / 20) as f64, (i % 20) as f64);
            let off = Vec2::new(
                -0.8 * row + rng.uniform(-0.1, 0.1),
                0.8 * col + rng.uniform(-0.1, 0.1),
            );
            let pts = (0..100)
                .map(|j| {
                    let s = 0.6 * j as f64;
                    Vec2::new(s, 4.0 * (s / 20.0).sin()) + off
                })
                .collect();
            Track::linked(i, pts, (0..100).map(|j| 0.5 * j as f64).collect())
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.5,
    }
}

/// `n` random walkers × 200 samples in a 60 × 60 m square at 1.3 m/s, 0.1 s apart:
/// the heading turns by up to ±0.3 rad a step and reflects at the walls.
pub fn walkers(n: usize, seed: u64) -> TrackSet {
    let (side, speed, step) = (60.0, 1.3, 0.1);
    let mut rng = SplitMix64::new(seed);
    let tracks = (0..n as u64)
        .map(|id| {
            let mut p = Vec2::new(rng.uniform(0.0, side), rng.uniform(0.0, side));
            let mut h = rng.uniform(0.0, std::f64::consts::TAU);
            let mut pts = Vec::with_capacity(200);
            for _ in 0..200 {
                pts.push(p);
                h += rng.uniform(-0.3, 0.3);
                let mut q = p + Vec2::new(h.cos(), h.sin()) * (speed * step);
                if !(0.0..=side).contains(&q.x) {
                    h = std::f64::consts::PI - h;
                    q.x = q.x.clamp(0.0, side);
                }
                if !(0.0..=side).contains(&q.y) {
                    h = -h;
                    q.y = q.y.clamp(0.0, side);
                }
                p = q;
            }
            Track::linked(id, pts, (0..200).map(|j| step * j as f64).collect())
        })
        .collect();
    TrackSet {
        tracks,
        step_s: step,
    }
}

fn cage_rows(people: usize, repeats: usize) -> Result<Vec<Row>> {
    let set = block(people);
    let sel = Selection::select(&set, &SelectionQuery::default())?;
    let params = CageParams::default();
    let mut first = Vec::with_capacity(repeats);
    let mut later = Vec::with_capacity(repeats);
    let mut out = set.clone();
    let mut shape = (0, 0);
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        let mut cage = Cage::new(&set, &sel, &params)?;
        let i = cage.hull().len() / 3;
        let v = cage.hull()[i];
        cage.drag(&[(Handle::Hull(i), v + Vec2::new(0.5, 0.5))], &[])?;
        cage.apply(&mut out)?;
        first.push(us(t0));
        shape = (cage.hull().len(), cage.mesh_vertices().len());
        for k in 1..=10 {
            let a = 0.05 * k as f64;
            let t0 = Instant::now();
            cage.drag(&[(Handle::Hull(i), v + Vec2::new(0.5 + a, 0.5 - a))], &[])?;
            cage.apply(&mut out)?;
            later.push(us(t0));
        }
    }
    let what = format!(
        "{people} tracks x 100 samples, {} hull / {} mesh vertices",
        shape.0, shape.1
    );
    Ok(vec![
        row_from_samples(
            "edit cage new + first drag",
            first,
            format!("{what}; budget 16 ms"),
        ),
        row_from_samples("edit drag + apply", later, what),
    ])
}

fn detect_row(name: &str, set: &TrackSet, repeats: usize, budget: &str) -> Result<Row> {
    let samples: usize = set.tracks.iter().map(|t| t.len()).sum();
    let mut times = Vec::with_capacity(repeats);
    let mut pairs = 0;
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        let c = detect(set, THRESHOLD_M)?;
        times.push(us(t0));
        pairs = c.pair_count();
    }
    Ok(row_from_samples(
        name,
        times,
        format!(
            "{} people, {samples} samples, {pairs} pairs < {THRESHOLD_M} m; budget {budget}",
            set.tracks.len()
        ),
    ))
}

fn detect_rows(walker_count: usize, repeats: usize) -> Result<Vec<Row>> {
    let mut rows = vec![detect_row(
        &format!("edit detect {walker_count} walkers"),
        &walkers(walker_count, 0x5EED),
        repeats,
        "200 ms at 1000 x 200",
    )?];
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/crowd");
    if let Ok(entries) = std::fs::read_dir(&dir) {
        let mut files: Vec<_> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "txt"))
            .collect();
        files.sort();
        for f in files {
            let (set, _) = read_tracks(&f, None, &ReadOptions::default())
                .map_err(anyhow::Error::msg)
                .with_context(|| format!("{}", f.display()))?;
            let stem = f
                .file_stem()
                .map_or(String::new(), |s| s.to_string_lossy().into_owned());
            rows.push(detect_row(
                &format!("edit detect {stem}"),
                &set,
                repeats,
                "50 ms",
            )?);
        }
    }
    Ok(rows)
}

/// People 0.6 m apart in a block 20 wide (one group), walking +x at 0.1 m/s, 100
/// samples 0.1 s apart, inside the default 16 × 9 m world.
fn group(people: usize) -> TrackSet {
    let times: Vec<f64> = (0..100).map(|k| k as f64 * 0.1).collect();
    let tracks = (0..people as u64)
        .map(|i| {
            let p0 = group_person(i);
            let pts = times.iter().map(|t| p0 + Vec2::new(0.1 * t, 0.0)).collect();
            Track::linked(i, pts, times.clone())
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.1,
    }
}

fn group_person(i: u64) -> Vec2 {
    Vec2::new(2.0 + 0.6 * (i % 20) as f64, 1.5 + 0.6 * (i / 20) as f64)
}

fn tick_row(people: usize, repeats: usize) -> Result<Row> {
    const PERIOD_US: u64 = 8_333;
    let cfg = Config::embedded_default();
    let mut e = Engine::new(&cfg, None, false);
    // Edit jobs to the outbox, as for the daemon's formation thread.
    e.set_switch_worker(true);
    drop(e.tick(Micros(PERIOD_US)));
    e.clear_events();
    e.load_tracks(group(people), "bench", Micros(PERIOD_US));
    e.command(&Command::Pause, Micros(2 * PERIOD_US))?;
    drop(e.tick(Micros(2 * PERIOD_US)));
    e.clear_events();
    let held = group_person(people as u64 / 2);
    let frame = |k: u64, flags: ContactFlags| {
        let phase = (k % 120) as f64 / 120.0;
        let p = held + Vec2::new(0.0, 0.5 - (2.0 * phase - 1.0).abs());
        let mut f = TouchFrame::new(Micros(k * PERIOD_US));
        let _ = f.push(Contact {
            id: ContactId(1),
            x: (p.x / 16.0) as f32,
            y: (p.y / 9.0) as f32,
            flags,
            ..Contact::default()
        });
        f
    };
    let ticks = 10 * repeats.max(1);
    let mut times = Vec::with_capacity(ticks);
    let mut jobs = 0u64;
    for k in 3..3 + 30 + ticks as u64 {
        let f = frame(
            k,
            if k == 3 {
                ContactFlags::DOWN
            } else {
                ContactFlags::NONE
            },
        );
        let t0 = Instant::now();
        e.push_frame(&f);
        drop(e.tick(Micros(k * PERIOD_US)));
        let t = us(t0);
        e.clear_events();
        if k >= 33 {
            times.push(t);
        }
        if let Some(job) = e.take_edit_job() {
            e.apply_edit(job.run(), Micros(k * PERIOD_US));
            jobs += 1;
        }
    }
    anyhow::ensure!(jobs > 1, "the finger did not grab the group");
    Ok(row_from_samples(
        &format!("edit tick {people} tracks dragging"),
        times,
        format!("control thread only; {jobs} edit jobs run outside the timing"),
    ))
}

/// Runs the workloads (module doc).
///
/// # Errors
/// A workload that fails (an editor error, an unreadable fixture).
pub fn edit(run: &EditRun) -> Result<Vec<Row>> {
    let mut rows = cage_rows(run.people, run.repeats)?;
    rows.extend(detect_rows(run.walkers, run.repeats)?);
    rows.push(tick_row(run.people, run.repeats)?);
    Ok(rows)
}
