//! A budget of things per second: a burst at once, then a sustained rate (a token
//! bucket counted in microseconds of credit). The socket gives one to each client
//! for its lines, and one to the listener for connections.

use crate::vocab::Micros;

/// Lines a client may send per second, sustained.
pub const LINES_PER_SECOND: u64 = 200;
/// Lines a client may send at once after a quiet spell.
pub const LINE_BURST: u64 = 50;
/// Connections the socket accepts per second, sustained (connect/close churn beyond
/// it waits in the listen backlog).
pub const ACCEPTS_PER_SECOND: u64 = 200;
/// Connections the socket accepts at once after a quiet spell.
pub const ACCEPT_BURST: u64 = 64;

/// A budget of `per_second`, up to `burst` at once.
#[derive(Debug)]
pub(crate) struct Budget {
    cost_us: u64,
    cap_us: u64,
    credit_us: u64,
    last: Micros,
}

impl Budget {
    /// A full budget at `now`.
    pub fn new(per_second: u64, burst: u64, now: Micros) -> Budget {
        let cost_us = 1_000_000 / per_second.max(1);
        Budget {
            cost_us,
            cap_us: cost_us * burst.max(1),
            credit_us: cost_us * burst.max(1),
            last: now,
        }
    }

    /// Whether one may be taken at `now`.
    pub fn ready(&mut self, now: Micros) -> bool {
        let earned = now.saturating_since(self.last).0;
        self.last = self.last.max(now);
        self.credit_us = (self.credit_us + earned).min(self.cap_us);
        self.credit_us >= self.cost_us
    }

    /// Takes one at `now`; false when the budget is spent.
    pub fn take(&mut self, now: Micros) -> bool {
        if self.ready(now) {
            self.credit_us -= self.cost_us;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_budget_allows_a_burst_then_the_sustained_rate() {
        let t0 = Micros(1_000_000);
        let mut b = Budget::new(LINES_PER_SECOND, LINE_BURST, t0);
        let burst = (0..1000).take_while(|_| b.take(t0)).count() as u64;
        assert_eq!(burst, LINE_BURST);
        // One second later: one second's worth, up to the burst.
        let t1 = Micros(t0.0 + 1_000_000);
        let more = (0..1000).take_while(|_| b.take(t1)).count() as u64;
        assert_eq!(more, LINES_PER_SECOND.min(LINE_BURST));
        // Then one per 1/LINES_PER_SECOND s.
        let cost = 1_000_000 / LINES_PER_SECOND;
        let steps = (1..=100u64)
            .filter(|k| b.take(Micros(t1.0 + k * cost)))
            .count();
        assert_eq!(steps, 100);
        assert!(!b.take(Micros(t1.0 + 100 * cost)));
        // A long quiet spell refills only up to the burst.
        let t2 = Micros(t1.0 + 3_600_000_000);
        let after = (0..1000).take_while(|_| b.take(t2)).count() as u64;
        assert_eq!(after, LINE_BURST);
        // Time going backwards (it cannot, on CLOCK_MONOTONIC) earns nothing.
        assert!(!b.take(t0));
        assert!(!b.ready(t0), "ready takes nothing");
        let t3 = Micros(t2.0 + cost);
        assert!(b.ready(t3) && b.ready(t3) && b.take(t3) && !b.ready(t3));
    }
}
