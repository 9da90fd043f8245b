//! Stage timing against budgets: histograms, overrun counts, summaries.
//!
//! Each thread owns the [`StageTimer`]s of its stages (no locks, no allocation per
//! sample: the histogram's range is fixed up front) and hands [`StageStats`]
//! summaries on once per stats interval.

use crate::vocab::StageStats;
use hdrhistogram::Histogram;

/// Largest value a stage histogram records (µs); larger samples are clamped.
pub const MAX_RECORDED_US: u64 = 60_000_000;

/// A histogram of one stage's durations with its budget.
#[derive(Clone, Debug)]
pub struct StageTimer {
    name: &'static str,
    budget_us: u64,
    hist: Histogram<u64>,
    overruns: u64,
    overruns_total: u64,
}

/// A fresh histogram covering 1 µs ..= [`MAX_RECORDED_US`] with 3 significant digits.
pub fn new_histogram() -> Histogram<u64> {
    match Histogram::new_with_bounds(1, MAX_RECORDED_US, 3) {
        Ok(h) => h,
        // The bounds above are constants that hdrhistogram accepts.
        Err(e) => unreachable!("histogram bounds: {e}"),
    }
}

impl StageTimer {
    /// A timer for `name` with a budget in µs.
    pub fn new(name: &'static str, budget_us: u64) -> StageTimer {
        StageTimer {
            name,
            budget_us,
            hist: new_histogram(),
            overruns: 0,
            overruns_total: 0,
        }
    }

    /// Stage name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Changes the budget (config reload).
    pub fn set_budget(&mut self, budget_us: u64) {
        self.budget_us = budget_us;
    }

    /// Records one sample; returns whether it overran the budget.
    pub fn record(&mut self, us: u64) -> bool {
        self.hist.saturating_record(us.clamp(1, MAX_RECORDED_US));
        if us > self.budget_us {
            self.overruns += 1;
            self.overruns_total += 1;
            true
        } else {
            false
        }
    }

    /// Merges samples recorded elsewhere (e.g. another thread's histogram).
    pub fn absorb(&mut self, other: &Histogram<u64>) {
        let _ = self.hist.add(other);
        // Overruns of absorbed samples: count values above budget.
        let over: u64 = other
            .iter_recorded()
            .filter(|v| v.value_iterated_to() > self.budget_us)
            .map(|v| v.count_at_value())
            .sum();
        self.overruns += over;
        self.overruns_total += over;
    }

    /// Overruns since start.
    pub fn overruns_total(&self) -> u64 {
        self.overruns_total
    }

    /// The interval's summary; starts a new interval.
    pub fn take(&mut self) -> StageStats {
        let s = self.peek();
        self.hist.reset();
        self.overruns = 0;
        s
    }

    /// The interval's summary so far.
    pub fn peek(&self) -> StageStats {
        let h = &self.hist;
        let empty = h.is_empty();
        StageStats {
            stage: self.name.to_string(),
            count: h.len(),
            p50_us: if empty { 0 } else { h.value_at_quantile(0.5) },
            p99_us: if empty { 0 } else { h.value_at_quantile(0.99) },
            max_us: if empty { 0 } else { h.max() },
            budget_us: self.budget_us,
            overruns: self.overruns,
        }
    }

    /// The underlying histogram of the current interval.
    pub fn histogram(&self) -> &Histogram<u64> {
        &self.hist
    }
}

/// Resident set size of this process in bytes, from `/proc/self/status`.
pub fn rss_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_overruns_and_quantiles() {
        let mut t = StageTimer::new("control", 100);
        for us in 1..=200u64 {
            t.record(us);
        }
        let s = t.take();
        assert_eq!(s.count, 200);
        assert_eq!(s.overruns, 100);
        assert!((99..=101).contains(&s.p50_us), "{}", s.p50_us);
        assert!(s.p99_us >= 197 && s.max_us >= 199);
        assert_eq!(t.peek().count, 0);
        assert_eq!(t.overruns_total(), 100);
    }

    #[test]
    fn absorb_counts_overruns_of_other_histograms() {
        let mut other = new_histogram();
        other.record(50).unwrap();
        other.record(5000).unwrap();
        let mut t = StageTimer::new("e2e", 4000);
        t.absorb(&other);
        let s = t.take();
        assert_eq!((s.count, s.overruns), (2, 1));
    }

    #[test]
    fn rss_is_read() {
        assert!(rss_bytes().unwrap() > 1024 * 1024);
    }
}
