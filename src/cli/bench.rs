//! `crowdtouch bench`: the standard workloads, measured on this machine.

use crate::cli::common::output::outln;
use anyhow::Result;
use clap::{Args, ValueEnum};
use crowdtouch::config::Config;
use crowdtouch::crowd::mesh::TriMesh;
use crowdtouch::crowd::mesh::{Arap, Constraint};
use crowdtouch::engine::Engine;
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
use std::time::{Duration, Instant};

mod assign;
mod e2e;
mod e2e_clients;
mod e2e_commander;
mod e2e_tuio;
mod edit;
mod gesture;
mod open_space;
mod rows;
mod shutdown;
mod soak;
mod websocket;

use rows::{quantiles, row_from_samples, Row};

/// Which workload to run.
#[derive(Copy, Clone, Debug, PartialEq, Eq, ValueEnum)]
pub enum Workload {
    /// Every workload.
    All,
    /// End-to-end latency: the full daemon replaying at 120 Hz to a socket client.
    E2e,
    /// One ARAP deformation step, 20×20 mesh with an area control.
    Arap,
    /// One control tick (segment + deform + step), without the assignment worker.
    Tick,
    /// Exact assignment of `--n` agents to `--n` goals (squared-Euclidean cost) in
    /// the `--layout`s, cold or `--warm`. Not part of `all`.
    Assign,
    /// A long unattended run of the real daemon (`--minutes`, `--agents`,
    /// `--clients`): SIGHUP reloads, crowd resizes, a stalled and a reconnecting
    /// client; one report row per minute, non-zero exit when a check fails. Not
    /// part of `all`.
    Soak,
    /// One fast-marching field (second order, one point source) on a `--grid`²
    /// grid of 4 cm cells, uniform cost or `--obstacles`. Not part of `all`.
    Fmm,
    /// SIGTERM to exit of `crowdtouch demo` in each state (idle; a resize to
    /// `--agents` being prepared; `--agents` being solved; a formation switch of
    /// `--agents` being prepared), `--repeats` runs each, and how soon a stale
    /// solve is given up when the crowd shrinks back to 100. Not part of `all`.
    Shutdown,
    /// One gesture command, piece by piece, against the budgets: a library
    /// of `--library-size` gestures (built as the shipped one is) loaded from its
    /// file, `--repeats` generated query gestures recognised (features, KNN with
    /// its pruning counts), their neighbours' motions blended and synthesised for
    /// `--agents` agents (assignment included and alone). Not part of `all`.
    Gesture,
    /// Crowd motion editing against the budgets: a cage built plus its first
    /// drag and each later drag on `--people` tracks × 100 samples; collision
    /// detection on `--n` random walkers × 200 samples and on the UCY files of
    /// `tests/fixtures/crowd/`; the engine's tick in edit mode with `--people` tracks
    /// while a finger drags them (`--repeats` of each, ten times as many ticks). Not
    /// part of `all`.
    Edit,
    /// The publisher alone fed `--agents`-agent snapshots at 120 Hz for
    /// `--seconds`, read by `--clients` WebSocket clients in `--format`: end-to-end
    /// latency, encode time, drops, bandwidth. Not part of `all`.
    Websocket,
}

/// Arguments of `bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Workload.
    #[arg(value_enum, default_value_t = Workload::All)]
    workload: Workload,
    /// Agents for the end-to-end and tick workloads.
    #[arg(long, default_value_t = 1000)]
    agents: u32,
    /// Duration of the end-to-end run (s).
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Duration of the soak (minutes; fractions allowed, e.g. 0.25).
    #[arg(long, default_value_t = 60.0)]
    minutes: f64,
    /// Soak: socket clients (at least 3): one stalled, one reconnecting every
    /// second, the rest reading continuously.
    #[arg(long, default_value_t = 4)]
    clients: u32,
    /// Soak: one more client that connects, reads the server's `hello` and closes,
    /// over and over (connect/close churn).
    #[arg(long)]
    churn: bool,
    /// Soak: length of one report row (s); the SIGHUP reload and the three resizes
    /// happen once per row.
    #[arg(long, default_value_t = 60.0)]
    period_seconds: f64,
    /// Tick workload: one tick every 8.3 ms (120 Hz) as in the daemon, sleeping
    /// between them, instead of back to back. The daemon's control thread finds
    /// its data out of the caches after each sleep: this is the figure to compare
    /// with `e2e`'s control tick (10,000 agents: about 1.6 times the back-to-back
    /// time on this project's 2-core machine).
    #[arg(long)]
    paced: bool,
    /// Agents and goals of the assignment workload; random walkers of the edit
    /// workload's collision detection.
    #[arg(long, default_value_t = 1000)]
    n: usize,
    /// Edit workload: tracks of the cage and the tick (at least 3).
    #[arg(long, default_value_t = 200)]
    people: usize,
    /// Assignment workload: warm solves over a chain of frames in which every goal
    /// moves by up to 2 % of the extent (else cold solves of fresh instances).
    #[arg(long)]
    warm: bool,
    /// Assignment workload: solve from the positions as the controllers do
    /// (`Assigner`: the positions mapped to alike spreads, costs computed on demand,
    /// candidate lists from a spatial index, no matrix) instead of from a filled cost
    /// matrix.
    #[arg(long)]
    points: bool,
    /// Assignment workload: where the agents and goals are, `all` or a comma-separated
    /// list of: uniform (the unit square), clustered (agents in a 0.3 m disk, goals in
    /// a 4 × 3 m formation), pinched (the reverse), line (agents on an 8 m × 5 cm
    /// line), to-line (the reverse), corner (agents in a 2 × 2 m corner), shifted
    /// (goals in the formation moved 3 m east).
    #[arg(long, default_value = "uniform")]
    layout: String,
    /// Assignment, shutdown and gesture workloads: timed solves, runs per state,
    /// query gestures and library loads.
    #[arg(long, default_value_t = 50)]
    repeats: usize,
    /// Assignment workload: also write the instances (points, as JSON) to this file,
    /// for `benches/scipy_lsa.py`.
    #[arg(long)]
    dump: Option<std::path::PathBuf>,
    /// Gesture workload: gestures in the library (at least 10; 750 is the shipped
    /// library, multiples of 50 are built exactly).
    #[arg(long, default_value_t = 1500)]
    library_size: usize,
    /// End-to-end workload: replay generated gesture commands drawn in open space
    /// (several in a row, two people at opposite ends of the glass) instead of the
    /// shipped recordings, so that gestures are recognised and synthesised on the
    /// formation thread while the latency is measured.
    #[arg(long)]
    gestures: bool,
    /// End-to-end workload: formation transforms to this formation and back to
    /// `start`, one after the other, while touches are replayed in open space
    /// (the `--gestures` input, recognition off): the latency during transforms.
    #[arg(long)]
    transform: Option<String>,
    /// End-to-end workload: the daemon in edit mode with this many people (a
    /// block over the crowd's area walking slowly, 100 samples each) whose tracks
    /// the shipped recordings' fingers grab, drag and release: the latency while
    /// tracks are edited.
    #[arg(long)]
    edit: Option<usize>,
    /// Fast-marching workload: cells per side of the square grid.
    #[arg(long, default_value_t = 256)]
    grid: usize,
    /// Fast-marching workload: walls, blocks and a slow patch instead of a uniform
    /// cost (the instance of `benches/fmm.rs`).
    #[arg(long)]
    obstacles: bool,
    /// Fast-marching workload: first-order stencils instead of second order.
    #[arg(long)]
    first_order: bool,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
    /// Run the end-to-end workload without real-time scheduling or locked memory
    /// (as on a machine that refuses them).
    #[arg(long)]
    no_realtime: bool,
    /// End-to-end workload in a scene: a scene file, or a shipped name such as
    /// `obstacle_course` (`config/scenes/<name>.ron`, embedded in the binary).
    #[arg(long)]
    scene: Option<std::path::PathBuf>,
    /// End-to-end workload: the snapshot format the client reads.
    #[arg(long, value_enum, default_value_t = e2e_clients::WireFormat::Json)]
    format: e2e_clients::WireFormat,
    /// End-to-end workload: the arrays the client asks for.
    #[arg(long, value_enum, default_value_t = e2e_clients::FieldChoice::All)]
    fields: e2e_clients::FieldChoice,
    /// End-to-end workload: also this many WebSocket clients (a privileged
    /// WebSocket output on a free port) reading what the Unix client reads.
    #[arg(long, default_value_t = 0)]
    websocket_clients: u32,
    /// End-to-end workload: also a TUIO 1.1 output (objects and blobs, 120 Hz,
    /// 64 KiB datagrams) to a UDP reader counting its frames.
    #[arg(long)]
    tuio: bool,
}

/// Runs the chosen workloads and prints a table (or JSON).
pub fn bench(a: BenchArgs) -> Result<()> {
    if a.workload == Workload::Soak {
        return soak::soak(soak::SoakArgs {
            minutes: a.minutes,
            agents: a.agents,
            clients: a.clients,
            churn: a.churn,
            period_s: a.period_seconds,
            realtime: !a.no_realtime,
            json: a.json,
        });
    }
    if a.workload == Workload::Gesture {
        return gesture::gesture(&gesture::GestureRun {
            library_size: a.library_size,
            agents: a.agents,
            repeats: a.repeats,
            json: a.json,
        });
    }
    let mut rows = Vec::new();
    if matches!(a.workload, Workload::All | Workload::Arap) {
        rows.push(arap_step());
    }
    if matches!(a.workload, Workload::All | Workload::Tick) {
        rows.push(control_tick(a.agents, a.paced));
    }
    if a.workload == Workload::Assign {
        let layouts = assign::parse_layouts(&a.layout)?;
        anyhow::ensure!(
            a.dump.is_none() || layouts.len() == 1,
            "--dump writes one layout's instances: name one --layout"
        );
        for layout in layouts {
            rows.push(assign::assign(&assign::AssignRun {
                layout,
                n: a.n,
                warm: a.warm,
                points: a.points,
                repeats: a.repeats,
                dump: a.dump.as_deref(),
            })?);
        }
    }
    if a.workload == Workload::Edit {
        anyhow::ensure!(a.people >= 3, "--people must be at least 3");
        rows.extend(edit::edit(&edit::EditRun {
            people: a.people,
            walkers: a.n,
            repeats: a.repeats,
        })?);
    }
    if a.workload == Workload::Websocket {
        rows.extend(websocket::websocket(
            a.agents as usize,
            a.clients as usize,
            a.seconds,
            a.format,
        )?);
    }
    if a.workload == Workload::Fmm {
        rows.push(fmm(a.grid, a.obstacles, a.first_order, a.repeats)?);
    }
    if a.workload == Workload::Shutdown {
        rows.extend(shutdown::shutdown(a.agents, a.repeats)?);
    }
    if matches!(a.workload, Workload::All | Workload::E2e) {
        rows.extend(e2e::end_to_end(&e2e::E2eRun {
            agents: a.agents,
            seconds: a.seconds,
            realtime: !a.no_realtime,
            scene: a.scene.as_deref(),
            format: a.format,
            fields: a.fields,
            gestures: a.gestures,
            transform: a.transform.as_deref(),
            edit: a.edit,
            websocket_clients: a.websocket_clients,
            tuio: a.tuio,
        })?);
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        outln!(
            "{:<34} {:>8} {:>10} {:>10} {:>10}  note",
            "workload",
            "samples",
            "p50 µs",
            "p99 µs",
            "max µs"
        )?;
        for r in &rows {
            outln!(
                "{:<34} {:>8} {:>10.1} {:>10.1} {:>10.1}  {}",
                r.workload,
                r.samples,
                r.p50_us,
                r.p99_us,
                r.max_us,
                r.note
            )?;
        }
    }
    Ok(())
}

/// The fast-marching workload: `repeats` timed solves of one field from a point
/// source at (0.2, 0.3) of the side; the field is checked outside the timing
/// (`eikonal::sanity_check`, and on a uniform cost its largest deviation from the
/// Euclidean distance).
fn fmm(n: usize, obstacles: bool, first_order: bool, repeats: usize) -> Result<Row> {
    use crowdtouch::crowd::environment::eikonal::{
        bench_instance, sanity_check, Fmm, Order, Sources,
    };
    anyhow::ensure!(
        (2..=8192).contains(&n),
        "--grid must be between 2 and 8192 cells per side"
    );
    let (grid, cost) = bench_instance(n, obstacles);
    let side = n as f64 * grid.cell_m();
    let src = [Vec2::new(0.2 * side, 0.3 * side)];
    let order = if first_order {
        Order::First
    } else {
        Order::Second
    };
    let mut solver = Fmm::with_order(order);
    let mut phi = vec![0.0; grid.len()];
    let mut samples = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        solver.solve_into(&grid, &cost, Sources::Points(&src), &mut phi)?;
        samples.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    sanity_check(&grid, &cost, &phi)
        .map_err(|cell| anyhow::anyhow!("the field breaks an invariant at cell {cell}"))?;
    let reached = phi.iter().filter(|v| v.is_finite()).count();
    let check = if obstacles {
        format!("{reached} of {} cells reachable", grid.len())
    } else {
        let err = (0..grid.len())
            .map(|i| (phi[i] - (grid.center(i) - src[0]).norm()).abs())
            .fold(0.0, f64::max);
        format!(
            "largest deviation from the Euclidean distance {:.1} mm",
            err * 1e3
        )
    };
    let p50 = quantiles(samples.clone()).0;
    Ok(row_from_samples(
        &format!(
            "fmm {n}x{n}{}{}",
            if obstacles { " obstacles" } else { "" },
            if first_order { " first order" } else { "" }
        ),
        samples,
        format!(
            "one field, one point source, 4 cm cells; {:.1} M cells/s at p50; {check}",
            reached as f64 / p50
        ),
    ))
}

/// One ARAP step on a 20×20 mesh with a four-finger area control.
fn arap_step() -> Row {
    let mesh = TriMesh::grid(
        Rect {
            min: [0.0, 0.0],
            max: [4.0, 4.0],
        },
        20,
        20,
    );
    let rest = mesh.rest().to_vec();
    let mut arap = Arap::new(&mesh);
    // Handles at four vertices around the centre; every vertex inside their square
    // is a supplementary point.
    let handles = [(6usize, 6usize), (13, 6), (13, 13), (6, 13)];
    let mut cons = Vec::new();
    for r in 6..=13 {
        for c in 6..=13 {
            let h = handles.contains(&(c, r));
            cons.push(Constraint {
                vertex: (r * 20 + c) as u32,
                weight: if h { 1000.0 } else { 100.0 },
            });
        }
    }
    if let Err(e) = arap.set_constraints(&cons) {
        return row_from_samples("arap_step 20x20 area", vec![], format!("failed: {e}"));
    }
    let centre = Vec2::new(2.0, 2.0);
    let mut targets = vec![Vec2::zeros(); cons.len()];
    let mut out = rest.clone();
    let mut samples = Vec::with_capacity(3000);
    for k in 0..3000 {
        let th = 0.3 * ((k % 200) as f64 / 200.0);
        let (s, c) = th.sin_cos();
        for (t, con) in targets.iter_mut().zip(&cons) {
            let d = rest[con.vertex as usize] - centre;
            *t = centre + Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        }
        let t0 = Instant::now();
        let _ = arap.solve(&targets, &rest, &mut out);
        samples.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    row_from_samples(
        "arap_step 20x20 area",
        samples,
        format!("{} constraints", cons.len()),
    )
}

/// One control tick for `agents` agents with a three-finger area control moving;
/// `paced`: one tick every 8.3 ms, sleeping in between (as the daemon).
fn control_tick(agents: u32, paced: bool) -> Row {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    let mut engine = Engine::new(&cfg, cfg.surface.size_mm, false);
    let mut samples = Vec::with_capacity(2400);
    let period = 8_333u64;
    let fingers = [(0.48f32, 0.45f32), (0.52, 0.45), (0.50, 0.52)];
    let start = Instant::now();
    for k in 0..2400u64 {
        let t = Micros(k * period);
        let mut f = TouchFrame::new(t);
        let phase = k % 600;
        let dx = 0.08 * (phase as f32 / 600.0);
        for (i, &(x, y)) in fingers.iter().enumerate() {
            let flags = match phase {
                0 => ContactFlags::DOWN,
                599 => ContactFlags::UP,
                _ => ContactFlags::NONE,
            };
            let id = ContactId((k / 600) as u32 * 10 + i as u32 + 1);
            let _ = f.push(Contact {
                id,
                x: x + dx,
                y,
                flags,
                ..Contact::default()
            });
        }
        if paced {
            // Sleep until this tick's slot of the 120 Hz clock the run started on.
            let due = start + Duration::from_micros(k * period);
            if let Some(wait) = due.checked_duration_since(Instant::now()) {
                std::thread::sleep(wait);
            }
        }
        let t0 = Instant::now();
        engine.push_frame(&f);
        let o = engine.tick(t);
        drop(o);
        engine.clear_events();
        samples.push(t0.elapsed().as_secs_f64() * 1e6);
    }
    let (name, note) = if paced {
        (
            format!("control_tick {agents} agents paced"),
            "segment + ARAP + goals + agent step + snapshot, one tick every 8.3 ms",
        )
    } else {
        (
            format!("control_tick {agents} agents"),
            "segment + ARAP + goals + agent step + snapshot",
        )
    };
    row_from_samples(&name, samples, note.into())
}
