//! `crowdtouch bench gesture`: the cost of one gesture command, piece by piece,
//! against the budgets (one core): the K nearest neighbours over a library
//! of `--library-size` gestures, the blend, synthesis and assignment for `--agents`
//! agents, and loading the library file.
//!
//! # The library
//!
//! Built as the shipped one is (`crowd::motion::build_library`, the shipped seed,
//! 5 gestures per simulated crowd motion) with `⌈N / 50⌉` motions per class, so
//! that 750 gives the shipped library bit for bit, 150 and 1,500 exactly that many
//! gestures. A size that is not a multiple of 50 keeps `N` of the built gestures
//! spread evenly over the list (every class keeps its share), and drops the
//! motions no kept gesture points at.
//!
//! # The queries
//!
//! `--repeats` gestures from the gesture generator with the test set's style
//! ranges (`library test-set`: other devices, speeds, hands than the library's),
//! the ten classes in turn, each drawn by another seed. Per query:
//! - prepare + features: validation, normalisation, resampling, the four features;
//! - KNN: `Searcher::search` on the recogniser's index (with its pruning counts);
//! - blend: each voting neighbour's motion turned to the drawn gesture, blended;
//! - synthesis + assignment: `Synthesiser::synthesise` on the crowd the daemon
//!   starts with at `--agents` (the config's formation), and, on the same
//!   instance, the assignment alone (`CoarseToFine`, as the synthesis runs it) and
//!   the one-level solve it replaced (the equalised matrix and a cold solve);
//! - the whole `GestureRequest::prepare`, as the formation thread runs it.
//!
//! The library load is timed as the daemon loads a library file
//! (`config::load_recogniser`: read the file, parse and validate, index), and its
//! two parts on their own.
//!
//! # Time
//!
//! Every piece is timed twice: by the thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`:
//! the cost on one core, what the budgets are about, hardly changed by other
//! processes on a shared machine) and by the wall clock (which also counts the time
//! the thread waited for a core). The quantiles and the budget check are of the CPU
//! time; the wall clock's p50 and p99 are shown beside them.

use crate::cli::common::output::outln;
use anyhow::{ensure, Context, Result};
use crowdtouch::config::{load_recogniser, Config};
use crowdtouch::crowd::assign::{CoarseToFine, CostMatrix, Solver};
use crowdtouch::crowd::motion::{
    alignment, blend, build_library, rotated, start_costs, BuildParams, GestureRequest, Placement,
    Synthesiser,
};
use crowdtouch::engine::{search_params, Engine};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::knn::{vote, Searcher};
use crowdtouch::gesture::library::{read_library, write_library, Library, MotionClass};
use crowdtouch::gesture::physical::PhysicalFeatures;
use crowdtouch::gesture::recognise::Recogniser;
use crowdtouch::gesture::resample::prepare_scaled;
use crowdtouch::gesture::synth::{generate, GestureStyle, StyleRanges};
use crowdtouch::gesture::track::GestureTracks;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// Gestures per simulated crowd motion in the bench library (as shipped).
const GESTURES_PER_MOTION: usize = 5;

/// What `bench gesture` is asked to do.
pub struct GestureRun {
    /// Gestures in the library.
    pub library_size: usize,
    /// Agents the motions are synthesised for.
    pub agents: u32,
    /// Query gestures (and library loads) timed.
    pub repeats: usize,
    /// Machine-readable output.
    pub json: bool,
}

/// One timed piece: quantiles of the thread's CPU time, and the wall clock's.
#[derive(Serialize, Debug)]
struct Piece {
    piece: String,
    samples: usize,
    p50_ms: f64,
    p99_ms: f64,
    max_ms: f64,
    wall_p50_ms: f64,
    wall_p99_ms: f64,
    /// The budget for this piece at this size, if it has one (ms).
    target_ms: Option<f64>,
    /// Whether the p99 is within the budget.
    met: Option<bool>,
    note: String,
}

/// The whole report.
#[derive(Serialize, Debug)]
struct Report {
    library_gestures: usize,
    library_motions: usize,
    library_bytes: usize,
    library_build_s: f64,
    agents: usize,
    queries: usize,
    recognised_as_drawn: usize,
    pieces: Vec<Piece>,
}

fn quantiles_ms(mut v: Vec<f64>) -> (f64, f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.99), v[v.len() - 1])
}

/// `(CPU ms, wall ms)` samples.
type Samples = Vec<(f64, f64)>;

fn piece(name: &str, samples_ms: Samples, target_ms: Option<f64>, note: String) -> Piece {
    let samples = samples_ms.len();
    let (p50, p99, max) = quantiles_ms(samples_ms.iter().map(|s| s.0).collect());
    let (wall_p50, wall_p99, _) = quantiles_ms(samples_ms.iter().map(|s| s.1).collect());
    Piece {
        piece: name.into(),
        samples,
        p50_ms: p50,
        p99_ms: p99,
        max_ms: max,
        wall_p50_ms: wall_p50,
        wall_p99_ms: wall_p99,
        target_ms,
        met: target_ms.map(|t| p99 <= t),
        note,
    }
}

/// This thread's CPU time (ms).
fn cpu_ms() -> f64 {
    use nix::time::{clock_gettime, ClockId};
    clock_gettime(ClockId::CLOCK_THREAD_CPUTIME_ID).map_or(f64::NAN, |t| {
        t.tv_sec() as f64 * 1e3 + t.tv_nsec() as f64 * 1e-6
    })
}

/// A start of timing: the wall clock and the thread's CPU time.
#[derive(Copy, Clone)]
struct Stamp(Instant, f64);

fn now() -> Stamp {
    Stamp(Instant::now(), cpu_ms())
}

/// `(CPU ms, wall ms)` since `t0`.
fn ms_since(t0: Stamp) -> (f64, f64) {
    (cpu_ms() - t0.1, t0.0.elapsed().as_secs_f64() * 1e3)
}

/// A library of `n` gestures (module doc).
fn bench_library(n: usize) -> Result<Library> {
    ensure!(
        n >= MotionClass::ALL.len(),
        "--library-size must be at least {} (one gesture per class)",
        MotionClass::ALL.len()
    );
    let per_class = n
        .div_ceil(MotionClass::ALL.len() * GESTURES_PER_MOTION)
        .max(1);
    let built = build_library(&BuildParams {
        motions_per_class: per_class,
        gestures_per_motion: GESTURES_PER_MOTION,
        ..BuildParams::default()
    })?;
    Ok(keep_evenly(built, n))
}

/// `n` of `lib`'s gestures spread evenly over its list, and the motions they use.
fn keep_evenly(lib: Library, n: usize) -> Library {
    let total = lib.gestures.len();
    if n >= total {
        return lib;
    }
    // Gesture j is kept when ⌊(j + 1)·n / total⌋ steps past ⌊j·n / total⌋: exactly n.
    let kept: Vec<_> = lib
        .gestures
        .into_iter()
        .enumerate()
        .filter(|(j, _)| (j + 1) * n / total != j * n / total)
        .map(|(_, g)| g)
        .collect();
    let mut new_index = vec![None; lib.motions.len()];
    let mut motions = Vec::new();
    let mut gestures = Vec::with_capacity(kept.len());
    for mut g in kept {
        let old = g.motion as usize;
        let id = *new_index[old].get_or_insert_with(|| {
            motions.push(lib.motions[old].clone());
            motions.len() - 1
        });
        g.motion = id as u32;
        gestures.push(g);
    }
    Library {
        classes: lib.classes,
        motions,
        gestures,
    }
}

/// Query gesture `i`: class `i mod 10`, the test set's style ranges.
fn query(i: usize) -> (MotionClass, GestureTracks) {
    let class = MotionClass::ALL[i % MotionClass::ALL.len()];
    let seed = 0x6E57_C0DE_u64.wrapping_mul(i as u64 + 1) ^ 0x15;
    let style = GestureStyle::random(class, seed, &StyleRanges::test_set());
    (class, generate(class, &style, seed ^ 0xA5A5))
}

/// Runs the workload and prints its table (or JSON).
pub fn gesture(run: &GestureRun) -> Result<()> {
    ensure!(run.agents >= 1, "--agents must be at least 1");
    let repeats = run.repeats.max(1);
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = run.agents;
    let params = search_params(&cfg);

    let t0 = Instant::now();
    let lib = bench_library(run.library_size)?;
    let build_s = t0.elapsed().as_secs_f64();
    let n = lib.gestures.len();
    let bytes = write_library(&lib);
    let path = std::env::temp_dir().join(format!(
        "crowdtouch-bench-gesture-{}.ctgl",
        std::process::id()
    ));
    std::fs::write(&path, &bytes).with_context(|| format!("{}: cannot write", path.display()))?;

    // Library load, as the daemon does it, then its parts.
    let band = cfg.gestures.band;
    let (mut load, mut read, mut index) = (Vec::new(), Vec::new(), Vec::new());
    let mut recogniser = None;
    for _ in 0..repeats {
        let t = now();
        let r = load_recogniser(Some(&path), band, crowdtouch::config::DEFAULT_COLLECTED);
        load.push(ms_since(t));
        recogniser = Some(r.map_err(|e| anyhow::anyhow!(e))?);
        let t = now();
        let l = read_library(&bytes, "bench.ctgl")?;
        read.push(ms_since(t));
        let t = now();
        let r = Recogniser::new(l, "bench.ctgl", band.map(|b| b as usize))?;
        index.push(ms_since(t));
        drop(r);
    }
    let _ = std::fs::remove_file(&path);
    let rec: Arc<Recogniser> = recogniser.context("no library loaded")?;

    let agents: Vec<Vec2> = Engine::new(&cfg, cfg.surface.size_mm, false)
        .agent_positions()
        .to_vec();
    let m = agents.len();
    let mut searcher = Searcher::new();
    let mut synth = Synthesiser::new();
    let mut solver = Solver::new();
    let mut c2f = CoarseToFine::new();
    let mut costs = CostMatrix::new(0, 0);
    let (mut starts, mut mapped) = (Vec::with_capacity(m), Vec::with_capacity(m));
    let (mut prep, mut knn, mut blend_ms, mut synth_ms) = (vec![], vec![], vec![], vec![]);
    let (mut assign_ms, mut motion_ms, mut whole) = (vec![], vec![], vec![]);
    let mut one_level_ms = vec![];
    let (mut computed, mut abandoned, mut pruned, mut right) = (0, 0, 0, 0);
    let mut failed = Vec::new();
    for i in 0..repeats {
        let (class, tracks) = query(i);
        let t = now();
        let Ok((drawn, scale_mm)) = prepare_scaled(&tracks) else {
            failed.push(format!("query {i} ({class}) does not prepare"));
            continue;
        };
        let features = GestureFeatures::of(&drawn);
        let physical = PhysicalFeatures::of(&drawn, Some(scale_mm));
        prep.push(ms_since(t));

        // The recogniser's distance: eq. 12 plus the physical features.
        let t = now();
        let neighbours = searcher
            .search_with(rec.index(), &features, &physical, &params)
            .to_vec();
        knn.push(ms_since(t));
        let s = searcher.stats();
        (computed, abandoned, pruned) = (
            computed + s.computed,
            abandoned + s.abandoned,
            pruned + s.pruned,
        );
        let (voted, _) = vote(&neighbours, |e| rec.class_of(e)).context("empty library")?;
        right += usize::from(voted == class.id());

        // Section 7.2 as `GestureRequest::prepare` runs it: the voted class's
        // neighbours, turned to the drawn gesture, weights renormalised.
        let t = now();
        let l = rec.library();
        let turned: Vec<_> = neighbours
            .iter()
            .filter(|nb| l.gestures[nb.entry].class == voted)
            .map(|nb| {
                let g = &l.gestures[nb.entry];
                let theta = alignment(&g.gesture, &drawn);
                (rotated(&l.motions[g.motion as usize], theta), nb.weight)
            })
            .collect();
        let total: f64 = turned.iter().map(|p| p.1).sum();
        let parts: Vec<_> = turned
            .iter()
            .map(|(mf, w)| {
                let w = if total > 0.0 {
                    w / total
                } else {
                    1.0 / turned.len() as f64
                };
                (mf, w)
            })
            .collect();
        let motion = blend(&parts)?;
        let b = ms_since(t);
        blend_ms.push(b);

        let t = now();
        let placement = Placement::for_crowd(&agents);
        let seed = cfg.gestures.seed ^ i as u64;
        let synthesis = synth.synthesise(&motion, &agents, &placement, seed)?;
        let sy = ms_since(t);
        synth_ms.push(sy);
        motion_ms.push((b.0 + sy.0, b.1 + sy.1));

        // The same assignment on its own: agents to the synthesised starts.
        starts.clear();
        starts.extend(synthesis.trajectories.iter().map(|tr| tr[0]));
        let t = now();
        c2f.solve(&agents, &starts)?;
        assign_ms.push(ms_since(t));
        let t = now();
        start_costs(&agents, &starts, &mut mapped, &mut costs);
        solver.solve(&costs)?;
        one_level_ms.push(ms_since(t));

        let req = GestureRequest {
            id: i as u32,
            epoch: 0,
            tracks,
            agents: agents.clone(),
            recogniser: Arc::clone(&rec),
            search: params,
            seed,
            speed_m_s: cfg.gestures.motion_speed_m_s,
            // What the daemon does with the config's `gestures.apply`.
            apply: match cfg.gestures.apply {
                crowdtouch::config::GestureApply::KeepFormation => {
                    crowdtouch::crowd::motion::ApplyMode::KeepFormation
                }
                crowdtouch::config::GestureApply::AsSampled => {
                    crowdtouch::crowd::motion::ApplyMode::AsSampled
                }
            },
            keep: crowdtouch::crowd::motion::KeepParams {
                min_part_agents: cfg.gestures.min_piece_agents.max(1) as usize,
                radius_m: cfg.crowd.agent_radius_m,
                ..crowdtouch::crowd::motion::KeepParams::default()
            },
        };
        let t = now();
        let p = req.prepare(&mut searcher, &mut synth);
        whole.push(ms_since(t));
        if let Err(e) = p.outcome {
            failed.push(format!("query {i} ({class}): {e}"));
        }
    }

    let q = knn.len().max(1);
    let knn_target = if n <= 150 {
        Some(1.0)
    } else if n <= 1500 {
        Some(5.0)
    } else {
        None
    };
    let motion_target = (m <= 1000).then_some(20.0);
    let load_target = (n <= 1500).then_some(100.0);
    let failures = if failed.is_empty() {
        String::new()
    } else {
        format!("; {} failed: {}", failed.len(), failed.join("; "))
    };
    let pieces = vec![
        piece(
            "prepare + features",
            prep,
            None,
            "validate, normalise (eq. 2), resample to 64, four features (section 5.2)".into(),
        ),
        piece(
            &format!("knn {n} gestures"),
            knn,
            knn_target,
            format!(
                "K={} unbanded={} the recogniser's distance (eq. 12 weight {}, physical features); per query {} computed, {} abandoned, {} pruned",
                params.k,
                params.band.is_none(),
                rec.index().physical_weights().eq12,
                computed / q,
                abandoned / q,
                pruned / q
            ),
        ),
        piece(
            "blend",
            blend_ms,
            None,
            "voting neighbours' motions turned to the gesture, blended (section 7.2)".into(),
        ),
        piece(
            &format!("synthesis + assignment {m}"),
            synth_ms,
            None,
            "sample scores, eq. 16, place, optimal assignment (section 7.3)".into(),
        ),
        piece(
            &format!("  of which assignment {m}"),
            assign_ms,
            None,
            "the same instance again: CoarseToFine (exact; 3 levels at 1,000)".into(),
        ),
        piece(
            &format!("  one-level assignment {m}"),
            one_level_ms,
            None,
            "the same instance, as before: equalised matrix + cold exact solve".into(),
        ),
        piece(
            &format!("blend + synthesis + assign {m}"),
            motion_ms,
            motion_target,
            "the motion for the crowd, per gesture".into(),
        ),
        piece(
            "GestureRequest::prepare",
            whole,
            None,
            format!("the formation thread's whole job per gesture{failures}"),
        ),
        piece(
            &format!("library load {n}"),
            load,
            load_target,
            format!(
                "config::load_recogniser: read the {:.1} MB file, parse + validate, index",
                bytes.len() as f64 / 1e6
            ),
        ),
        piece(
            "  of which read_library",
            read,
            None,
            "parse + validate from memory".into(),
        ),
        piece(
            "  of which Recogniser::new",
            index,
            None,
            "features + LB_Keogh envelopes of every gesture".into(),
        ),
    ];
    let report = Report {
        library_gestures: n,
        library_motions: rec.library().motions.len(),
        library_bytes: bytes.len(),
        library_build_s: build_s,
        agents: m,
        queries: repeats,
        recognised_as_drawn: right,
        pieces,
    };
    print(&report, run.json)
}

fn print(r: &Report, json: bool) -> Result<()> {
    if json {
        outln!("{}", serde_json::to_string_pretty(r)?)?;
        return Ok(());
    }
    outln!(
        "gesture commands: library of {} gestures over {} motions ({:.1} MB, built in {:.1} s), {} agents, {} queries ({} recognised as the class drawn), one core",
        r.library_gestures,
        r.library_motions,
        r.library_bytes as f64 / 1e6,
        r.library_build_s,
        r.agents,
        r.queries,
        r.recognised_as_drawn
    )?;
    outln!(
        "{:<32} {:>7} {:>9} {:>9} {:>9} {:>6} {:>4} {:>16}  note",
        "piece (thread CPU time)",
        "samples",
        "p50 ms",
        "p99 ms",
        "max ms",
        "target",
        "met",
        "wall p50/p99 ms"
    )?;
    for p in &r.pieces {
        let target = p.target_ms.map_or("-".to_string(), |t| format!("{t:.0}"));
        let met = match p.met {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "-",
        };
        outln!(
            "{:<32} {:>7} {:>9.3} {:>9.3} {:>9.3} {:>6} {:>4} {:>16}  {}",
            p.piece,
            p.samples,
            p.p50_ms,
            p.p99_ms,
            p.max_ms,
            target,
            met,
            format!("{:.2}/{:.2}", p.wall_p50_ms, p.wall_p99_ms),
            p.note
        )?;
    }
    Ok(())
}
