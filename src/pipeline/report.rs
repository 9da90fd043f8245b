//! What the supervisor adds to the control thread's figures when it makes a
//! `stats` report: the assignment rate over the interval, every `Device` input's
//! state, and each stage's histogram since start (for `/metrics`).

use super::timing::StageTimer;
use crate::vocab::{DeviceState, DeviceStatus, StageHistogram};
use std::sync::{Mutex, PoisonError};

/// Upper bounds (µs) of the buckets a stage's histogram is exported in: from the
/// queue's tens of microseconds to the end-to-end budget's tens of milliseconds,
/// and a second for a stalled stage.
pub const HISTOGRAM_BOUNDS_US: [u64; 14] = [
    50, 100, 250, 500, 1_000, 2_000, 4_000, 8_000, 16_000, 32_000, 64_000, 125_000, 250_000,
    1_000_000,
];

/// Events per second: `count` now against `previous` one interval of
/// `interval_us` ago (0 for an empty interval; a counter that went back, as after
/// a restart of its source, counts from zero).
pub fn rate_hz(count: u64, previous: u64, interval_us: u64) -> f64 {
    if interval_us == 0 {
        return 0.0;
    }
    count.saturating_sub(previous) as f64 / (interval_us as f64 * 1e-6)
}

/// A stage's histogram since start in the cumulative buckets of
/// [`HISTOGRAM_BOUNDS_US`].
pub fn stage_histogram(total: &StageTimer) -> StageHistogram {
    let h = total.histogram();
    let buckets = HISTOGRAM_BOUNDS_US
        .iter()
        .map(|&le| {
            // Samples are recorded from 1 µs up (StageTimer::record clamps).
            let n = if h.is_empty() {
                0
            } else {
                h.count_between(1, le)
            };
            (le, n)
        })
        .collect();
    let sum_us = h
        .iter_recorded()
        .map(|v| v.value_iterated_to().saturating_mul(v.count_at_value()))
        .fold(0u64, u64::saturating_add);
    StageHistogram {
        stage: total.name().to_string(),
        buckets,
        count: h.len(),
        sum_us,
        overruns: total.overruns_total(),
    }
}

/// Every `Device` input's last state, written by the input threads when their
/// device is attached, unplugged or fails (rare: a lock is fine), read by the
/// supervisor once per report.
#[derive(Debug, Default)]
pub struct DeviceBoard {
    slots: Mutex<Vec<DeviceStatus>>,
}

impl DeviceBoard {
    /// A board for the `Device` inputs at these config indices, none reported yet.
    pub fn new(inputs: impl IntoIterator<Item = u16>) -> DeviceBoard {
        DeviceBoard {
            slots: Mutex::new(
                inputs
                    .into_iter()
                    .map(|input| DeviceStatus {
                        input,
                        state: None,
                        node: String::new(),
                        message: None,
                    })
                    .collect(),
            ),
        }
    }

    /// Input `input` reached `state` (through `node`, `message` saying why).
    pub fn set(&self, input: u16, state: DeviceState, node: &str, message: Option<&str>) {
        let mut slots = self.slots.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(s) = slots.iter_mut().find(|s| s.input == input) {
            s.state = Some(state);
            if !node.is_empty() {
                s.node = node.to_string();
            }
            s.message = message.map(str::to_string);
        }
    }

    /// Every input's state, in config order.
    pub fn snapshot(&self) -> Vec<DeviceStatus> {
        self.slots
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_is_the_increase_over_the_interval() {
        assert_eq!(rate_hz(130, 100, 1_000_000), 30.0);
        assert_eq!(rate_hz(115, 100, 500_000), 30.0);
        assert_eq!(rate_hz(5, 100, 1_000_000), 0.0, "a counter that went back");
        assert_eq!(rate_hz(5, 0, 0), 0.0, "an empty interval");
    }

    #[test]
    fn buckets_are_cumulative_and_count_every_sample() {
        let mut t = StageTimer::new("control", 1_000);
        for us in [10, 60, 60, 900, 3_000, 2_000_000] {
            t.record(us);
        }
        let h = stage_histogram(&t);
        assert_eq!(h.stage, "control");
        assert_eq!(h.count, 6);
        assert_eq!(h.overruns, 2);
        let at = |le: u64| h.buckets.iter().find(|b| b.0 == le).unwrap().1;
        assert_eq!(at(50), 1);
        assert_eq!(at(100), 3);
        assert_eq!(at(1_000), 4);
        assert_eq!(at(4_000), 5);
        assert_eq!(at(1_000_000), 5, "the 2 s sample is only in +Inf");
        assert!(h
            .buckets
            .windows(2)
            .all(|w| w[0].0 < w[1].0 && w[0].1 <= w[1].1));
        // Three significant digits: the sum is within 0.1 % of the samples'.
        let exact = 10 + 60 + 60 + 900 + 3_000 + 2_000_000u64;
        assert!(h.sum_us.abs_diff(exact) * 1000 <= exact, "{}", h.sum_us);
        assert_eq!(stage_histogram(&StageTimer::new("idle", 1)).count, 0);
    }

    #[test]
    fn the_board_keeps_each_inputs_last_state() {
        let b = DeviceBoard::new([0, 2]);
        assert!(b.snapshot().iter().all(|s| s.state.is_none()));
        b.set(2, DeviceState::Failed, "", Some("permission denied"));
        b.set(2, DeviceState::Attached, "/dev/input/event5", None);
        b.set(7, DeviceState::Attached, "/dev/input/event9", None);
        let s = b.snapshot();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].state, None);
        assert_eq!(s[1].state, Some(DeviceState::Attached));
        assert_eq!(s[1].node, "/dev/input/event5");
        assert_eq!(s[1].message, None);
    }
}
