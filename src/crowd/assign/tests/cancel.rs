//! Cancelling a solve: it stops at the first poll after the check says so, in every
//! phase, with [`AssignError::Cancelled`], having read a bounded number of cost
//! entries since; the next solve is exact; a check that never fires changes nothing.

use super::support::points;
use crate::crowd::assign::cancel::{Cancel, POLL_WORK};
use crate::crowd::assign::costs::{CostMatrix, CostProvider, CostSource, SquaredDistance};
use crate::crowd::assign::error::AssignError;
use crate::crowd::assign::solver::{Solver, Strategy as Algo};
use crate::crowd::assign::{Assigner, PointMetric};
use crate::geom::Vec2;
use crate::rng::SplitMix64;
use std::cell::Cell;

/// A matrix that counts the entries the solver reads (a row read counts its
/// columns).
struct Counting<'a> {
    m: &'a CostMatrix,
    reads: Cell<u64>,
}

impl CostSource for Counting<'_> {
    fn rows(&self) -> usize {
        self.m.rows()
    }
    fn cols(&self) -> usize {
        self.m.cols()
    }
    fn get(&self, i: usize, j: usize) -> f64 {
        self.reads.set(self.reads.get() + 1);
        self.m.get(i, j)
    }
    fn row<'a>(&'a self, i: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        self.reads.set(self.reads.get() + self.m.cols() as u64);
        CostSource::row(self.m, i, buf)
    }
}

fn instance(seed: u64, rows: usize, cols: usize) -> CostMatrix {
    let mut rng = SplitMix64::new(seed);
    let agents = points(&mut rng, rows);
    // Goals in a band away from the agents: the solve has to move prices a lot.
    let goals: Vec<Vec2> = points(&mut rng, cols)
        .into_iter()
        .map(|g| Vec2::new(2.0 + 0.3 * g.x, g.y))
        .collect();
    let mut c = CostMatrix::new(0, 0);
    SquaredDistance.fill(&agents, &goals, &mut c);
    c
}

/// Entries a solve may still read after its check first says "cancelled": up to
/// the next poll ([`POLL_WORK`] units, a unit being at least one entry read), plus
/// the row in progress.
fn slack(cols: usize) -> u64 {
    2 * POLL_WORK + 4 * cols as u64
}

/// Trips the check once `reads` entries were read, at several points of the solve
/// (so every phase gets cancelled somewhere), and checks that the solve stops with
/// `Cancelled` within the slack, and that the same solver then solves exactly.
fn cancelled_everywhere(mut make: impl FnMut() -> Solver, c: &CostMatrix, warm_first: bool) {
    let reference = {
        let mut s = make();
        let src = Counting {
            m: c,
            reads: Cell::new(0),
        };
        if warm_first {
            s.solve_warm_with(&src).unwrap();
        } else {
            s.solve_with(&src).unwrap();
        }
        assert!(s.verify_optimal(c, 1e-9));
        (s.total_cost(c), src.reads.get())
    };
    let (best, total) = reference;
    assert!(
        total > 8 * POLL_WORK,
        "the instance is too small to be cancelled mid-way: {total} reads"
    );
    for tenth in 0..9 {
        let trip_at = total * tenth / 10;
        let mut s = make();
        let src = Counting {
            m: c,
            reads: Cell::new(0),
        };
        let tripped = Cell::new(None::<u64>);
        let check = || {
            let r = src.reads.get();
            if r >= trip_at && tripped.get().is_none() {
                tripped.set(Some(r));
            }
            tripped.get().is_some()
        };
        let r = if warm_first {
            s.solve_warm_with_cancel(&src, Cancel::new(&check))
                .map(|_| ())
        } else {
            s.solve_with_cancel(&src, Cancel::new(&check)).map(|_| ())
        };
        assert_eq!(
            r,
            Err(AssignError::Cancelled),
            "tripped at {trip_at} of {total} reads"
        );
        let at = tripped.get().expect("the check fired");
        let after = src.reads.get() - at;
        assert!(
            after <= slack(c.cols()),
            "{after} entries read after the check fired at {at} (of {total})"
        );
        assert!(s.assignment().is_empty());
        // The solver is usable at once, and exact.
        s.solve_warm(c).unwrap();
        assert!(s.verify_optimal(c, 1e-9));
        assert!((s.total_cost(c) - best).abs() <= 1e-9 * best.abs().max(1.0));
    }
}

#[test]
fn a_cold_sparse_solve_stops_at_the_next_poll_in_every_phase() {
    let c = instance(11, 400, 400);
    cancelled_everywhere(|| Solver::with_strategy(Algo::Sparse), &c, false);
}

#[test]
fn a_dense_solve_stops_at_the_next_poll() {
    let c = instance(12, 300, 300);
    cancelled_everywhere(|| Solver::with_strategy(Algo::Dense), &c, false);
}

#[test]
fn a_rectangular_solve_stops_at_the_next_poll() {
    let c = instance(13, 250, 400);
    cancelled_everywhere(|| Solver::with_strategy(Algo::Sparse), &c, false);
}

#[test]
fn a_sparse_solve_with_few_candidates_stops_in_its_dense_finish() {
    // One candidate per row and no sparse round: the dense finish does the rest.
    let c = instance(14, 300, 300);
    let make = || {
        let mut s = Solver::with_options(Algo::Sparse, 1);
        s.max_rounds = Some(0);
        s
    };
    let mut s = make();
    s.solve(&c).unwrap();
    assert!(s.stats().dense_finish, "{:?}", s.stats());
    cancelled_everywhere(make, &c, false);
}

#[test]
fn a_warm_solve_stops_at_the_next_poll() {
    let c = instance(15, 400, 400);
    let mut shifted = c.clone();
    for r in 0..shifted.rows() {
        for v in shifted.row_mut(r) {
            *v *= 1.0 + 0.1 * ((r % 7) as f64);
        }
    }
    // Warm from the solution of `c`, then solve the changed costs.
    let make = || {
        let mut s = Solver::with_strategy(Algo::Sparse);
        s.solve(&c).unwrap();
        s
    };
    cancelled_everywhere(make, &shifted, true);
}

#[test]
fn a_check_that_fires_at_once_costs_one_poll() {
    let c = instance(16, 400, 400);
    let calls = Cell::new(0u32);
    let check = || {
        calls.set(calls.get() + 1);
        true
    };
    let mut s = Solver::new();
    assert_eq!(
        s.solve_with_cancel(&c, Cancel::new(&check)).map(|_| ()),
        Err(AssignError::Cancelled)
    );
    assert_eq!(calls.get(), 1);
    assert_eq!(s.stats().polls, 1);
    // Fired at the n-th poll: exactly n polls, then the solve stops.
    for n in [2u32, 5, 9] {
        calls.set(0);
        let check = || {
            calls.set(calls.get() + 1);
            calls.get() >= n
        };
        let mut s = Solver::new();
        assert_eq!(
            s.solve_with_cancel(&c, Cancel::new(&check)).map(|_| ()),
            Err(AssignError::Cancelled)
        );
        assert_eq!((calls.get(), s.stats().polls), (n, n as u64));
    }
}

#[test]
fn a_check_that_never_fires_changes_nothing() {
    let c = instance(17, 400, 400);
    let mut plain = Solver::new();
    let a = plain.solve(&c).unwrap().to_vec();
    let check = || false;
    let mut polled = Solver::new();
    let b = polled
        .solve_with_cancel(&c, Cancel::new(&check))
        .unwrap()
        .to_vec();
    assert_eq!(a, b);
    assert!(polled.stats().polls > 0);
    assert_eq!(
        SolveCounters::of(&plain),
        SolveCounters::of(&polled),
        "the same work"
    );
}

/// The work counters of a solve, without the polls.
#[derive(Debug, PartialEq)]
struct SolveCounters(u64, u64, u64, u64, u32);

impl SolveCounters {
    fn of(s: &Solver) -> SolveCounters {
        let t = s.stats();
        SolveCounters(
            t.rows_priced,
            t.rows_scanned,
            t.bids,
            t.augmentations,
            t.rounds,
        )
    }
}

#[test]
fn the_assigner_from_positions_stops_at_the_next_poll() {
    let mut rng = SplitMix64::new(18);
    let agents = points(&mut rng, 3000);
    let goals: Vec<Vec2> = points(&mut rng, 3000)
        .into_iter()
        .map(|g| Vec2::new(g.x * 4.0, g.y * 0.1))
        .collect();
    let mut reference = Assigner::new(PointMetric::Squared);
    let mut want = Vec::new();
    reference.solve(&agents, &goals, &mut want).unwrap();
    let polls = reference.stats().polls;
    assert!(polls > 4, "{polls} polls");
    let mut a = Assigner::new(PointMetric::Squared);
    let mut goal_of = vec![7u32; 3];
    for n in [1, polls / 2, polls - 1] {
        let calls = Cell::new(0u64);
        let check = || {
            calls.set(calls.get() + 1);
            calls.get() >= n
        };
        assert_eq!(
            a.solve_cancellable(&agents, &goals, &mut goal_of, Cancel::new(&check)),
            Err(AssignError::Cancelled)
        );
        assert_eq!((calls.get(), a.stats().polls), (n, n));
        assert_eq!(goal_of, vec![7u32; 3], "untouched");
    }
    a.solve(&agents, &goals, &mut goal_of).unwrap();
    assert_eq!(goal_of, want);
}
