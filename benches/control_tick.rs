//! One control tick (segment + ARAP + goals + agent step + snapshot), without the
//! assignment worker, for crowds of 100 to 10,000 agents with a three-finger area
//! control moving, and for 5,000 agents in the obstacle course
//! (`control_tick/obstacle_course/5000`: the terrain under every agent, obstacles).
//! `crowdtouch bench tick` measures the same workload's distribution.
//! Also one formation switch (`formation_switch/{prepare,apply}/N`) and one resize
//! (`resize/{prepare,apply}/N`), each in its two halves.
//!
//! In edit mode (`edit_tick/*`), the tick with 200 loaded people × 100 samples
//! playing: idle, and while a one-finger drag holds their group. The drag's jobs
//! (cage and deformation), which the daemon runs on the formation thread, are taken
//! with `take_edit_job`, run and applied outside the measured time.
//!
//! Cancellation polls (`crowd::assign::Cancel`) are on in every solve: the
//! figures include them (`Cancel::NEVER` is polled the same way).

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::config::Config;
use crowdtouch::crowd::assign::Cancel;
use crowdtouch::crowd::edit::{Track, TrackSet};
use crowdtouch::crowd::environment::load_scene;
use crowdtouch::engine::Engine;
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{Command, FormationMethod, Micros};
use crowdtouch::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

const PERIOD_US: u64 = 8_333;

fn frame(k: u64, flags: ContactFlags) -> TouchFrame {
    let fingers = [(0.48f32, 0.45f32), (0.52, 0.45), (0.50, 0.52)];
    let mut f = TouchFrame::new(Micros(k * PERIOD_US));
    // Back and forth, so the crowd stays on the table however long criterion runs.
    let phase = (k % 400) as f32 / 400.0;
    let dx = 0.04 * (1.0 - (2.0 * phase - 1.0).abs());
    for (i, &(x, y)) in fingers.iter().enumerate() {
        let c = Contact {
            id: ContactId(i as u32 + 1),
            x: x + dx,
            y,
            flags,
            ..Contact::default()
        };
        let _ = f.push(c);
    }
    f
}

fn control_tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("control_tick");
    for agents in [100u32, 1000, 5000, 10_000] {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = agents;
        let mut engine = Engine::new(&cfg, None, false);
        // The control begins and its grouping window closes before measuring.
        let mut k = 0u64;
        engine.push_frame(&frame(k, ContactFlags::DOWN));
        for _ in 0..60 {
            k += 1;
            engine.push_frame(&frame(k, ContactFlags::NONE));
            drop(engine.tick(Micros(k * PERIOD_US)));
            engine.clear_events();
        }
        g.bench_function(BenchmarkId::from_parameter(agents), |b| {
            b.iter(|| {
                k += 1;
                engine.push_frame(black_box(&frame(k, ContactFlags::NONE)));
                let out = engine.tick(Micros(k * PERIOD_US));
                black_box(&out.snapshot);
                drop(out);
                engine.clear_events();
            })
        });
    }
    // In a scene: the crowd dragged 2.0 m east and 1.5 m south into the obstacle
    // course first (some agents in its patches, some against its obstacles), then
    // the same area control moving there. The step reads the terrain under every
    // agent (its speed limit, its motion type) and keeps it out of the obstacles.
    let agents = 5000u32;
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    let scene =
        load_scene(Path::new("config/scenes/obstacle_course.ron"), 0.15).expect("shipped scene");
    cfg.set_loaded_scene(Some(Arc::new(scene)));
    let mut engine = Engine::new(&cfg, None, false);
    let shift = |k: u64| (k.min(120) as f32 / 120.0) * 0.125;
    let into = |k: u64, flags| moved(frame(k, flags), shift(k), shift(k) * 1.336);
    let mut k = 0u64;
    engine.push_frame(&into(k, ContactFlags::DOWN));
    for _ in 0..240 {
        k += 1;
        engine.push_frame(&into(k, ContactFlags::NONE));
        drop(engine.tick(Micros(k * PERIOD_US)));
        engine.clear_events();
    }
    g.bench_function(BenchmarkId::new("obstacle_course", agents), |b| {
        b.iter(|| {
            k += 1;
            engine.push_frame(black_box(&into(k, ContactFlags::NONE)));
            let out = engine.tick(Micros(k * PERIOD_US));
            black_box(&out.snapshot);
            drop(out);
            engine.clear_events();
        })
    });
    g.finish();
}

/// `f` with every contact moved by `(dx, dy)` (unit square).
fn moved(f: TouchFrame, dx: f32, dy: f32) -> TouchFrame {
    let mut out = TouchFrame::new(f.t);
    for c in f.contacts() {
        let _ = out.push(Contact {
            x: c.x + dx,
            y: c.y + dy,
            ..*c
        });
    }
    out
}

/// A formation switch (mesh-formation-control section 7.3), as a checkpoint or a
/// `set_formation` command makes it, in its two parts: `prepare` is what the
/// daemon's formation thread does (the arrow meshed at the crowd's area with the
/// default mesh's 80 vertices, one goal sample per agent, and the least-effort
/// pairing of formation-transform eq. 3: the exact solve on agents × agents costs
/// computed as it reads them); `apply` is what the control thread does with the
/// result (the new ARAP system, goals, topology, pairing), inside one tick.
fn formation_switch(c: &mut Criterion) {
    let mut g = c.benchmark_group("formation_switch");
    g.sample_size(10);
    for agents in [100u32, 1000, 5000] {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = agents;
        // The mesh switch (a formation transform is `transform_prepare`'s).
        cfg.formations.method = FormationMethod::Mesh;
        let request = || {
            let mut e = Engine::new(&cfg, None, false);
            e.set_switch_worker(true);
            e.set_formation("arrow", Micros(0)).unwrap();
            let r = e.take_switch_request().unwrap();
            (e, r)
        };
        g.bench_with_input(BenchmarkId::new("prepare", agents), &agents, |b, _| {
            b.iter_batched(
                request,
                |(e, r)| (e, r.prepare()),
                criterion::BatchSize::LargeInput,
            )
        });
        g.bench_with_input(BenchmarkId::new("apply", agents), &agents, |b, _| {
            b.iter_batched(
                || {
                    let (e, r) = request();
                    (e, r.prepare())
                },
                |(mut e, p)| {
                    e.apply_switch(p, Micros(1)).unwrap();
                    black_box(e.goals().len());
                    e
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

/// A resize (`set_agent_count`) from 100 agents, in its two halves: `prepare` is
/// what the daemon's formation thread does (one goal sample per agent on the
/// mesh), `apply` what the control thread does with it between two ticks (the
/// agents on their new goals, a new generation).
fn resize(c: &mut Criterion) {
    let mut g = c.benchmark_group("resize");
    g.sample_size(10);
    for agents in [1000u32, 5000] {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = 100;
        let request = || {
            let mut e = Engine::new(&cfg, None, false);
            e.set_switch_worker(true);
            e.set_agent_count(agents, Micros(0)).unwrap();
            let r = e.take_resize_request().unwrap();
            (e, r)
        };
        g.bench_with_input(BenchmarkId::new("prepare", agents), &agents, |b, _| {
            b.iter_batched(
                request,
                |(e, r)| (e, r.prepare(Cancel::NEVER)),
                criterion::BatchSize::LargeInput,
            )
        });
        g.bench_with_input(BenchmarkId::new("apply", agents), &agents, |b, _| {
            b.iter_batched(
                || {
                    let (e, r) = request();
                    (e, r.prepare(Cancel::NEVER).unwrap())
                },
                |(mut e, p)| {
                    assert!(e.apply_resize(p, Micros(1)));
                    black_box(e.goals().len());
                    e
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

/// 200 people in a 20 × 10 block 0.6 m apart (one group), walking +x at 0.1 m/s,
/// 100 samples 0.1 s apart, on the default 16 × 9 m world.
fn edit_tracks() -> TrackSet {
    let times: Vec<f64> = (0..100).map(|k| k as f64 * 0.1).collect();
    let tracks = (0..200u64)
        .map(|i| {
            let p0 = edit_person(i);
            let points = times.iter().map(|t| p0 + Vec2::new(0.1 * t, 0.0)).collect();
            Track::linked(i, points, times.clone())
        })
        .collect();
    TrackSet {
        tracks,
        step_s: 0.1,
    }
}

/// Where person `i` of [`edit_tracks`] starts (m).
fn edit_person(i: u64) -> Vec2 {
    Vec2::new(2.0 + 0.6 * (i % 20) as f64, 1.5 + 0.6 * (i / 20) as f64)
}

/// A one-finger frame at world position `p` (default world 16 × 9 m).
fn edit_frame(k: u64, p: Vec2, flags: ContactFlags) -> TouchFrame {
    let mut f = TouchFrame::new(Micros(k * PERIOD_US));
    let _ = f.push(Contact {
        id: ContactId(1),
        x: (p.x / 16.0) as f32,
        y: (p.y / 9.0) as f32,
        flags,
        ..Contact::default()
    });
    f
}

/// Runs and applies the engine's pending edit job, as the formation thread would.
fn run_edit_job(engine: &mut Engine, now: Micros) -> bool {
    match engine.take_edit_job() {
        Some(job) => {
            engine.apply_edit(job.run(), now);
            true
        }
        None => false,
    }
}

fn edit_tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("control_tick");
    let cfg = Config::embedded_default();
    let loaded = || {
        let mut engine = Engine::new(&cfg, None, false);
        // Edit jobs to the outbox, as for the daemon's formation thread.
        engine.set_switch_worker(true);
        drop(engine.tick(Micros(PERIOD_US)));
        engine.clear_events();
        engine.load_tracks(edit_tracks(), "bench", Micros(PERIOD_US));
        drop(engine.tick(Micros(2 * PERIOD_US)));
        engine.clear_events();
        engine
    };

    let mut engine = loaded();
    let mut k = 2u64;
    g.bench_function("edit_200_tracks_idle", |b| {
        b.iter(|| {
            k += 1;
            let out = engine.tick(Micros(k * PERIOD_US));
            black_box(&out.snapshot);
            drop(out);
            engine.clear_events();
        })
    });

    // Paused at t = 0 so the finger lands on person 105 (middle of the block).
    let mut engine = loaded();
    engine
        .command(&Command::Pause, Micros(3 * PERIOD_US))
        .expect("pause");
    let mut k = 3u64;
    drop(engine.tick(Micros(k * PERIOD_US)));
    engine.clear_events();
    let held = edit_person(105);
    let at = |k: u64| {
        // Back and forth within ±0.5 m, so the drag keeps moving.
        let phase = (k % 120) as f64 / 120.0;
        held + Vec2::new(0.0, 0.5 - (2.0 * phase - 1.0).abs())
    };
    k += 1;
    engine.push_frame(&edit_frame(k, at(k), ContactFlags::DOWN));
    let mut jobs = 0;
    for _ in 0..30 {
        drop(engine.tick(Micros(k * PERIOD_US)));
        engine.clear_events();
        jobs += usize::from(run_edit_job(&mut engine, Micros(k * PERIOD_US)));
        k += 1;
        engine.push_frame(&edit_frame(k, at(k), ContactFlags::NONE));
    }
    assert!(jobs > 1, "the drag grabs the group and makes edit jobs");
    g.bench_function("edit_200_tracks_dragging", |b| {
        b.iter_custom(|iters| {
            let mut timed = Duration::ZERO;
            for _ in 0..iters {
                k += 1;
                let f = edit_frame(k, at(k), ContactFlags::NONE);
                let t0 = Instant::now();
                engine.push_frame(black_box(&f));
                let out = engine.tick(Micros(k * PERIOD_US));
                black_box(&out.snapshot);
                drop(out);
                timed += t0.elapsed();
                engine.clear_events();
                run_edit_job(&mut engine, Micros(k * PERIOD_US));
            }
            timed
        })
    });
    g.finish();
}

criterion_group!(benches, control_tick, edit_tick, formation_switch, resize);
criterion_main!(benches);
