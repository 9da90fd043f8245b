//! Replays on a virtual clock: deterministic, as fast as possible or paced.
//!
//! # Gaps
//!
//! Between two frames the daemon's timer ticks every `period`; a replay does the
//! same, but for at most [`VirtualClock::max_gap`] of a gap: nothing touches the
//! surface in a gap (contacts down stay where they are), so after that long the
//! crowd has had its time to settle, and the clock jumps to the next frame. A
//! gap of any length (up to `u64::MAX` µs) therefore costs at most
//! `max_gap / period` ticks. A frame that lists no contact while none is down
//! carries nothing: it is not played, so a run of them is one gap.

use super::state::Engine;
use super::tick::TickOutput;
use crate::vocab::{Micros, TouchFrame};

/// How a virtual replay ticks.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct VirtualClock {
    /// Timer period between frames, as the daemon's tick (at least 1 µs).
    pub period: Micros,
    /// Timer ticks after the last frame, so the crowd settles.
    pub settle: Micros,
    /// Longest part of a gap between frames played tick by tick; the rest of a
    /// longer gap is skipped.
    pub max_gap: Micros,
}

/// Plays frames through `engine` on a virtual clock: a tick at every frame's time
/// stamp and, between frames, every `clock.period` as the daemon's timer would
/// (for at most `clock.max_gap` of a gap, see the module doc); then
/// `clock.settle` more time of timer ticks. `on_tick` sees every tick's output
/// (events are cleared after it returns).
///
/// `pace(played)` is called before each tick with the time played since the
/// first frame: the virtual time less the gaps skipped (a no-op for
/// as-fast-as-possible replays; a sleep until then for real-time ones).
///
/// Frames come one at a time (a stream); the first error, of a frame or of
/// `on_tick`, stops the replay and is returned. Deterministic: the same frames
/// and config give the same ticks.
///
/// # Errors
/// The first error of `frames` or `on_tick`.
pub fn replay_virtual<E>(
    engine: &mut Engine,
    frames: impl IntoIterator<Item = Result<TouchFrame, E>>,
    clock: VirtualClock,
    mut pace: impl FnMut(Micros),
    mut on_tick: impl FnMut(&TickOutput<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let period = clock.period.0.max(1);
    // Virtual time of the first frame, and the time skipped in gaps since.
    let mut t0: Option<Micros> = None;
    let mut skipped = Micros::ZERO;
    let mut step = |engine: &mut Engine, now: Micros, t0: Micros, skipped: Micros| {
        pace(now.saturating_since(t0).saturating_since(skipped));
        let r = {
            let o = engine.tick(now);
            on_tick(&o)
        };
        engine.clear_events();
        r
    };
    // Time of the last tick; whether contacts are down after the last frame.
    let mut t: Option<Micros> = None;
    let mut down = false;
    for f in frames {
        let f = f?;
        let start = *t0.get_or_insert(f.t);
        if f.is_empty() && !down {
            continue;
        }
        let mut now = match t {
            None => f.t,
            Some(last) => {
                // Timer ticks in the gap: before the frame, and at most `max_gap` in.
                let until = last.0.saturating_add(clock.max_gap.0);
                let mut cur = last.0;
                while let Some(n) = cur.checked_add(period).filter(|&n| n < f.t.0 && n <= until) {
                    cur = n;
                    step(engine, Micros(cur), start, skipped)?;
                }
                if f.t.0 > until {
                    skipped = skipped + Micros(f.t.0 - until);
                }
                Micros(cur)
            }
        };
        now = now.max(f.t);
        engine.push_frame(&f);
        step(engine, now, start, skipped)?;
        t = Some(now);
        down = f.contacts().iter().any(|c| !c.flags.ended());
    }
    let (Some(mut cur), Some(start)) = (t, t0) else {
        return Ok(());
    };
    let end = cur + clock.settle;
    while let Some(n) = cur.0.checked_add(period).filter(|&n| n <= end.0) {
        cur = Micros(n);
        step(engine, cur, start, skipped)?;
    }
    Ok(())
}
