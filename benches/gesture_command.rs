//! A whole gesture command, as the daemon's formation thread runs it
//! (`GestureRequest::prepare`: validate and resample the gesture, its features, the
//! K = 10 nearest library gestures by eq. 12, the voting neighbours' motions turned
//! and blended, trajectories synthesised and assigned for 1,000 agents), over the
//! shipped library (750 gestures, 150 motions) and a 1,500-gesture library built
//! the same way (`build_library`, 30 motions per class, 5 gestures each); and
//! loading a library: `read_library` (parse + validate) and `Recogniser::new`
//! (features and envelopes of every gesture), for both. One core. The issue's
//! budgets: KNN ≤ 5 ms at 1,500 gestures, blend + synthesis + assignment ≤ 20 ms at
//! 1,000 agents, a load ≤ 100 ms at 1,500.
//!
//! `cargo bench --bench gesture_command -- --warm-up-time 1 --measurement-time 5`
//!
//! The queries are ten generated gestures (`gesture::synth`), one per class, drawn
//! with seeds the libraries do not use; the agents stand where the daemon's default
//! config puts 1,000 of them.

use criterion::{black_box, criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion};
use crowdtouch::config::Config;
use crowdtouch::crowd::motion::{
    build_library, ApplyMode, BuildParams, GestureRequest, KeepParams, Synthesiser,
};
use crowdtouch::engine::{search_params, Engine};
use crowdtouch::gesture::knn::Searcher;
use crowdtouch::gesture::library::{read_library, shipped, write_library, MotionClass};
use crowdtouch::gesture::recognise::Recogniser;
use crowdtouch::gesture::synth::{generate, GestureStyle, StyleRanges};
use std::sync::Arc;

fn requests(rec: &Arc<Recogniser>, cfg: &Config) -> Vec<GestureRequest> {
    let agents = Engine::new(cfg, cfg.surface.size_mm, false)
        .agent_positions()
        .to_vec();
    MotionClass::ALL
        .iter()
        .enumerate()
        .map(|(i, &class)| {
            let seed = 0xC0_11A7D_u64 + i as u64;
            let style = GestureStyle::random(class, seed, &StyleRanges::default());
            GestureRequest {
                id: i as u32,
                epoch: 0,
                tracks: generate(class, &style, seed ^ 0x77),
                agents: agents.clone(),
                recogniser: Arc::clone(rec),
                search: search_params(cfg),
                seed: cfg.gestures.seed ^ i as u64,
                speed_m_s: cfg.gestures.motion_speed_m_s,
                // The default, `gestures.apply: keep_formation`.
                apply: ApplyMode::KeepFormation,
                keep: KeepParams {
                    radius_m: cfg.crowd.agent_radius_m,
                    ..KeepParams::default()
                },
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 1000;
    // A debug build is `cargo test --benches`' smoke run: a small library keeps it
    // to seconds (building 300 motions unoptimised takes minutes).
    let big = build_library(&BuildParams {
        motions_per_class: if cfg!(debug_assertions) { 2 } else { 30 },
        gestures_per_motion: 5,
        ..BuildParams::default()
    })
    .expect("the 1,500-gesture library builds");
    let libraries = [
        ("750_shipped", shipped().expect("the shipped library reads")),
        ("1500", big),
    ];
    let mut g = c.benchmark_group("gesture_command");
    g.sample_size(20);
    for (name, lib) in libraries {
        let bytes = write_library(&lib);
        g.bench_with_input(
            BenchmarkId::new("read_library", name),
            &bytes,
            |b, bytes| b.iter(|| read_library(black_box(bytes), "bench.ctgl").expect("valid")),
        );
        g.bench_with_input(BenchmarkId::new("recogniser_new", name), &lib, |b, lib| {
            b.iter_batched(
                || lib.clone(),
                |l| Recogniser::new(l, "bench", None).expect("indexes"),
                BatchSize::LargeInput,
            )
        });
        g.bench_with_input(
            BenchmarkId::new("read_and_index", name),
            &bytes,
            |b, bytes| {
                b.iter(|| {
                    let l = read_library(black_box(bytes), "bench.ctgl").expect("valid");
                    Recogniser::new(l, "bench", None).expect("indexes")
                })
            },
        );
        let rec = Arc::new(Recogniser::new(lib, name, None).expect("indexes"));
        let mut reqs = requests(&rec, &cfg);
        let (mut searcher, mut synth) = (Searcher::new(), Synthesiser::new());
        // A query the recogniser rejects (a weak vote, far neighbours) gives no
        // motion; the bench times the whole job, so it keeps the queries that do.
        reqs.retain(|r| r.clone().prepare(&mut searcher, &mut synth).outcome.is_ok());
        assert!(
            reqs.len() >= 8,
            "{name}: only {} of 10 queries give a motion",
            reqs.len()
        );
        let mut q = 0usize;
        g.bench_function(BenchmarkId::new("prepare_1000_agents", name), |b| {
            b.iter_batched(
                || {
                    q = (q + 1) % reqs.len();
                    reqs[q].clone()
                },
                |r| r.prepare(&mut searcher, &mut synth),
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
