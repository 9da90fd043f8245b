//! Replays on a virtual clock: deterministic, as fast as possible or paced.

use super::state::Engine;
use super::tick::TickOutput;
use crate::vocab::{Micros, TouchFrame};

/// Plays frames through `engine` on a virtual clock: a tick at every frame's time
/// stamp and, between frames, every `period` as the daemon's timer would; then
/// `settle` more time of timer ticks. `on_tick` sees every tick's output (events are
/// cleared after it returns). `pace(t)` is called before each tick (a no-op for
/// as-fast-as-possible replays; a sleep for real-time ones).
///
/// Deterministic: the same frames and config give the same ticks.
///
/// # Errors
/// The first error `on_tick` returns stops the replay and is returned.
pub fn replay_virtual<E>(
    engine: &mut Engine,
    frames: &[TouchFrame],
    period: Micros,
    settle: Micros,
    mut pace: impl FnMut(Micros),
    mut on_tick: impl FnMut(&TickOutput<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let period = Micros(period.0.max(1));
    let mut t = frames.first().map_or(Micros::ZERO, |f| f.t);
    let mut step = |engine: &mut Engine, now: Micros| -> Result<(), E> {
        pace(now);
        let r = {
            let o = engine.tick(now);
            on_tick(&o)
        };
        engine.clear_events();
        r
    };
    for f in frames {
        while t + period < f.t {
            t = t + period;
            step(engine, t)?;
        }
        t = t.max(f.t);
        engine.push_frame(f);
        step(engine, t)?;
    }
    let end = t + settle;
    while t + period <= end {
        t = t + period;
        step(engine, t)?;
    }
    Ok(())
}
