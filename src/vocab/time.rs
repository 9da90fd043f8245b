//! Time on CLOCK_MONOTONIC, in microseconds.
//!
//! Every timestamp in crowdtouch is a [`Micros`] on CLOCK_MONOTONIC: the kernel's
//! input event time (evdev switched with `EVIOCSCLOCKID`), the control tick time and
//! the instant bytes were written to a client all share one clock, so their
//! differences are latencies. Cores take `now` as a parameter and never read a
//! clock themselves; only the thread shells read it (`rt::monotonic_now`).

use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::{Add, Sub};

/// A point in time on CLOCK_MONOTONIC (or a virtual clock in replays), in microseconds.
#[derive(
    Copy, Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct Micros(pub u64);

impl Micros {
    /// Zero.
    pub const ZERO: Micros = Micros(0);

    /// From seconds (rounded to the nearest microsecond, negative clamps to zero).
    pub fn from_secs_f64(s: f64) -> Micros {
        Micros((s * 1e6).round().max(0.0) as u64)
    }

    /// As seconds.
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 * 1e-6
    }

    /// `self - earlier`, or zero when `earlier` is later.
    pub fn saturating_since(self, earlier: Micros) -> Micros {
        Micros(self.0.saturating_sub(earlier.0))
    }
}

impl Add for Micros {
    type Output = Micros;
    fn add(self, rhs: Micros) -> Micros {
        Micros(self.0.saturating_add(rhs.0))
    }
}

impl Sub for Micros {
    type Output = Micros;
    fn sub(self, rhs: Micros) -> Micros {
        Micros(self.0.saturating_sub(rhs.0))
    }
}

impl fmt::Display for Micros {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}us", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip() {
        assert_eq!(Micros::from_secs_f64(1.25), Micros(1_250_000));
        assert_eq!(Micros(1_250_000).as_secs_f64(), 1.25);
        assert_eq!(Micros(5) - Micros(9), Micros::ZERO);
        assert_eq!(Micros(5).saturating_since(Micros(2)), Micros(3));
    }
}
