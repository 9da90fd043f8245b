//! Fast marching and environment-aware assignment costs (crowd assignment stage).
//!
//! Run: `cargo bench --bench fmm -- --warm-up-time 1 --measurement-time 3`.
//! Inputs are generated deterministically (seeded) outside the measured closures.
//!
//! * `fmm_field/{uniform,obstacles}/{256,1024}`: one field from one point source,
//!   second order (plus `first_order` at 256²).
//! * `eikonal_costs/*`: the 100 agents × 100 goals cost matrix on a 256² grid
//!   (10.24 m square, 4 cm cells) with walls and a slow patch between the crowd and
//!   its formation: `per_goal_full` is the naive one full field per goal;
//!   `early_stop` marches each goal's field only until every agent's stencil is
//!   frozen (no cache); `moving` adds the field cache while the crowd and the
//!   formation drift by 2 cm per frame (sources change cell about every other frame);
//!   `static` is the cache with nothing moving; `coarse128` / `coarse64` run the
//!   provider on the grid coarsened by 2 and 4 (`eikonal::coarsen`).
//! * `planner/obstacle_course/{1000,5000}/{cold,drifting}`: the environment-aware
//!   plan of the assignment worker (goal-cluster fields, solve, waypoints) at 1,000
//!   and 5,000 agents in a shipped scene.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use crowdtouch::crowd::assign::{CostMatrix, CostProvider, Solver};
use crowdtouch::crowd::environment::eikonal::{
    bench_instance, coarsen, sample, EikonalCosts, EikonalOptions, Fmm, Grid, Order, Sources,
    BENCH_CELL_M,
};
use crowdtouch::geom::Vec2;
use crowdtouch::rng::SplitMix64;

/// Cell size of every bench grid: 4 cm.
const CELL_M: f64 = BENCH_CELL_M;

fn fmm_field(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("fmm_field");
    g.sample_size(10);
    for (name, obstacles) in [("uniform", false), ("obstacles", true)] {
        for n in [256usize, 1024] {
            let (grid, cost) = bench_instance(n, obstacles);
            let src = [Vec2::new(0.2 * n as f64 * CELL_M, 0.3 * n as f64 * CELL_M)];
            let mut phi = vec![0.0; grid.len()];
            let orders: &[(Order, &str)] = if n == 256 {
                &[(Order::Second, ""), (Order::First, "/first_order")]
            } else {
                &[(Order::Second, "")]
            };
            for &(order, suffix) in orders {
                let mut fmm = Fmm::with_order(order);
                fmm.solve_into(&grid, &cost, Sources::Points(&src), &mut phi)
                    .expect("solve");
                g.bench_function(format!("{name}/{n}{suffix}"), |b| {
                    b.iter(|| {
                        fmm.solve_into(
                            black_box(&grid),
                            black_box(&cost),
                            Sources::Points(black_box(&src)),
                            &mut phi,
                        )
                        .expect("solve");
                        black_box(phi[phi.len() / 2])
                    })
                });
            }
        }
    }
    g.finish();
}

/// Frames of agent and goal positions: a crowd of 100 on the left, a formation of
/// 100 (10×10 lattice) on the right, both drifting 2 cm per frame in y.
fn frames(grid: &Grid, frames: usize) -> Vec<(Vec<Vec2>, Vec<Vec2>)> {
    let side = grid.cols() as f64 * CELL_M;
    let mut rng = SplitMix64::new(0xA6E7);
    let agents: Vec<Vec2> = (0..100)
        .map(|_| {
            Vec2::new(
                (0.06 + 0.25 * rng.unit()) * side,
                (0.1 + 0.6 * rng.unit()) * side,
            )
        })
        .collect();
    let goals: Vec<Vec2> = (0..100)
        .map(|k| {
            Vec2::new(
                (0.70 + 0.025 * (k % 10) as f64) * side,
                (0.15 + 0.04 * (k / 10) as f64) * side,
            )
        })
        .collect();
    (0..frames)
        .map(|f| {
            let d = Vec2::new(0.0, 0.02 * f as f64);
            (
                agents.iter().map(|&p| p + d).collect(),
                goals.iter().map(|&p| p + d).collect(),
            )
        })
        .collect()
}

fn eikonal_costs(cr: &mut Criterion) {
    let mut g = cr.benchmark_group("eikonal_costs");
    g.sample_size(10);
    let (grid, cost) = bench_instance(256, true);
    let fr = frames(&grid, 32);
    let mut out = CostMatrix::new(100, 100);

    // Naive: one full field per goal.
    let mut fmm = Fmm::new();
    let mut phi = vec![0.0; grid.len()];
    let (agents, goals) = &fr[0];
    g.bench_function("100x100_256/per_goal_full", |b| {
        b.iter(|| {
            for (j, &goal) in black_box(goals).iter().enumerate() {
                let c = grid.center(grid.cell_of(goal).expect("on grid"));
                fmm.solve_into(&grid, &cost, Sources::Points(&[c]), &mut phi)
                    .expect("solve");
                for (i, &a) in agents.iter().enumerate() {
                    out.set(i, j, sample(&grid, &phi, a));
                }
            }
            black_box(out.get(0, 0))
        })
    });

    let no_cache = EikonalCosts::new(
        grid,
        &cost,
        EikonalOptions {
            cache_fields: 0,
            ..EikonalOptions::default()
        },
    )
    .expect("provider");
    let mut k = 0;
    g.bench_function("100x100_256/early_stop", |b| {
        b.iter(|| {
            let (a, gl) = &fr[k % fr.len()];
            k += 1;
            no_cache.fill(black_box(a), black_box(gl), &mut out);
            black_box(out.get(0, 0))
        })
    });

    let cached = EikonalCosts::new(grid, &cost, EikonalOptions::default()).expect("provider");
    let mut k = 0;
    g.bench_function("100x100_256/moving", |b| {
        b.iter(|| {
            // Forth and back, so the drift never jumps.
            let n = fr.len();
            let f = if (k / n) % 2 == 0 {
                k % n
            } else {
                n - 1 - k % n
            };
            k += 1;
            let (a, gl) = &fr[f];
            cached.fill(black_box(a), black_box(gl), &mut out);
            black_box(out.get(0, 0))
        })
    });
    let st = cached.stats();
    eprintln!(
        "moving: {} fills, {} fields marched, {} cache hits, {} cells per field",
        st.fills,
        st.fields,
        st.cache_hits,
        st.cells_marched / st.fields.max(1)
    );

    let (a, gl) = &fr[0];
    g.bench_function("100x100_256/static", |b| {
        b.iter(|| {
            cached.fill(black_box(a), black_box(gl), &mut out);
            black_box(out.get(0, 0))
        })
    });

    // The same scene on coarser grids (factor 2: 128², 8 cm; factor 4: 64², 16 cm).
    let mut fine = CostMatrix::new(0, 0);
    cached.fill(a, gl, &mut fine);
    let mut solver = Solver::new();
    let best = {
        solver.solve(&fine).expect("feasible");
        solver.total_cost(&fine)
    };
    for factor in [2usize, 4] {
        let mut coarse_cost = Vec::new();
        let coarse = coarsen(&grid, &cost, factor, &mut coarse_cost).expect("coarsen");
        let n = coarse.cols();
        // Accuracy against the 256² costs (not timed): entry error and the fine cost
        // of the assignment solved on the coarse costs.
        let mut m = CostMatrix::new(0, 0);
        EikonalCosts::new(coarse, &coarse_cost, EikonalOptions::default())
            .expect("provider")
            .fill(a, gl, &mut m);
        let mut rel: Vec<f64> = m
            .as_slice()
            .iter()
            .zip(fine.as_slice())
            .map(|(c, f)| (c - f).abs() / f)
            .collect();
        rel.sort_by(f64::total_cmp);
        let assignment = solver.solve(&m).expect("feasible").to_vec();
        let got: f64 = assignment
            .iter()
            .enumerate()
            .map(|(i, &j)| fine.get(i, j))
            .sum();
        eprintln!(
            "coarse{n}: entry error vs 256² median {:.2} %, max {:.2} %; its assignment costs {:.3} % more than the 256² optimum",
            100.0 * rel[rel.len() / 2],
            100.0 * rel[rel.len() - 1],
            100.0 * (got / best - 1.0)
        );
        let no_cache = EikonalCosts::new(
            coarse,
            &coarse_cost,
            EikonalOptions {
                cache_fields: 0,
                ..EikonalOptions::default()
            },
        )
        .expect("provider");
        let mut k = 0;
        g.bench_function(format!("100x100_coarse{n}/early_stop"), |b| {
            b.iter(|| {
                let (a, gl) = &fr[k % fr.len()];
                k += 1;
                no_cache.fill(black_box(a), black_box(gl), &mut out);
                black_box(out.get(0, 0))
            })
        });
        let cached =
            EikonalCosts::new(coarse, &coarse_cost, EikonalOptions::default()).expect("provider");
        let mut k = 0;
        g.bench_function(format!("100x100_coarse{n}/moving"), |b| {
            b.iter(|| {
                let n = fr.len();
                let f = if (k / n) % 2 == 0 {
                    k % n
                } else {
                    n - 1 - k % n
                };
                k += 1;
                let (a, gl) = &fr[f];
                cached.fill(black_box(a), black_box(gl), &mut out);
                black_box(out.get(0, 0))
            })
        });
        let st = cached.stats();
        eprintln!(
            "coarse{n} moving: {} fills, {} fields marched, {} cache hits",
            st.fills, st.fields, st.cache_hits
        );
    }
    g.finish();
}

/// The planner in a shipped scene: `n` agents (1,000 and 5,000) in the start area,
/// their formation east of it (across the obstacle course's barriers and patches),
/// the formation drifting 2 cm west per plan and the crowd 1 cm east. `cold`
/// forgets the previous solution before each plan; `drifting` is the warm chain the
/// worker runs. Both include the cost grid (density refreshed every 0.5 s of scene
/// time, 20 plans per second), the cluster fields, the solve and every agent's
/// waypoint; at 5,000 the plan is the grid transport (no field but the cost grid's,
/// waypoints along its paths). The solver's work of the last plan is printed.
fn planner(cr: &mut Criterion) {
    use crowdtouch::crowd::environment::{load_scene, Planner, PlannerParams};
    let mut g = cr.benchmark_group("planner");
    g.sample_size(10);
    let scene = std::sync::Arc::new(
        load_scene(
            std::path::Path::new("config/scenes/obstacle_course.ron"),
            0.15,
        )
        .expect("shipped scene"),
    );
    for n in [1000, 5000] {
        let mut rng = SplitMix64::new(11);
        let mut free = |x0: f64, y0: f64, x1: f64, y1: f64| -> Vec<Vec2> {
            let mut v = Vec::new();
            while v.len() < n {
                let p = Vec2::new(x0 + (x1 - x0) * rng.unit(), y0 + (y1 - y0) * rng.unit());
                if scene.obstacle_at(p, 0.0).is_none() {
                    v.push(p);
                }
            }
            v
        };
        let mut agents = free(6.0, 3.0, 10.0, 6.0);
        let mut goals = free(11.6, 3.0, 15.6, 6.0);
        let mut p =
            Planner::new(std::sync::Arc::clone(&scene), PlannerParams::new(1.5)).expect("planner");
        let (mut goal_of, mut wp) = (Vec::new(), Vec::new());
        let (mut t, mut k) = (0.0, 0u64);
        for (kind, cold) in [("cold", true), ("drifting", false)] {
            g.bench_function(format!("obstacle_course/{n}/{kind}"), |b| {
                b.iter(|| {
                    // 40 plans (2 s of scene time) of drift, then back to the start.
                    let back = if k % 40 == 39 { -39.0 } else { 1.0 };
                    k += 1;
                    agents.iter_mut().for_each(|a| a.x += 0.01 * back);
                    goals.iter_mut().for_each(|q| q.x -= 0.02 * back);
                    if cold {
                        p.forget();
                    }
                    t += 0.05;
                    p.plan(&agents, &goals, t, &mut goal_of, &mut wp)
                        .expect("plan");
                    black_box(goal_of[0])
                })
            });
            if let Some(ts) = p.transport_stats() {
                eprintln!(
                    "planner {n} {kind}: grid transport, {} arcs, {} pivots, graph cost {:.1} s",
                    ts.arcs, ts.pivots, ts.graph_cost_s
                );
                continue;
            }
            let st = p.solve_stats();
            // Nothing to print when the case was filtered out.
            if st.rows_priced == 0 {
                continue;
            }
            eprintln!(
                "planner {n} {kind}: last plan kept {} pairs, {} row pricings, {} bids, \
                 {} rows scanned",
                st.kept_rows, st.rows_priced, st.bids, st.rows_scanned
            );
        }
    }
}

criterion_group!(benches, fmm_field, eikonal_costs, planner);
criterion_main!(benches);
