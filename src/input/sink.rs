//! Where a source puts its frames.

use crate::vocab::TouchFrame;

/// Where a source puts its frames: the bounded queue to the control thread.
///
/// `push` never blocks and never allocates; the implementation decides what
/// happens when the queue is full (see `pipeline::FrameQueue`, `src/pipeline/queue.rs`).
pub trait FrameSink {
    /// Hands one frame on.
    fn push(&mut self, frame: &TouchFrame);
    /// Tries again to hand on frames it had to hold back; returns whether nothing
    /// is held back any more. A reader calls it while it waits for input, so a held
    /// frame (a lift, say) never waits for the next touch. Sinks that never hold
    /// anything back keep the default.
    fn flush(&mut self) -> bool {
        true
    }
}

/// Longest a device reader blocks before checking its stop flag (µs).
pub const STOP_CHECK_US: u64 = 100_000;

/// How long a reader waits for input while its sink still holds frames back (µs):
/// it retries [`FrameSink::flush`] at least this often.
pub const FLUSH_RETRY_US: u64 = 1_000;

/// The poll timeout a reader uses (ms): short while `sink` holds frames back (after
/// retrying them), else [`STOP_CHECK_US`].
pub fn reader_timeout_ms(sink: &mut dyn FrameSink) -> u16 {
    let us = if sink.flush() {
        STOP_CHECK_US
    } else {
        FLUSH_RETRY_US
    };
    u16::try_from(us / 1000).unwrap_or(u16::MAX)
}

impl FrameSink for Vec<TouchFrame> {
    fn push(&mut self, frame: &TouchFrame) {
        Vec::push(self, *frame);
    }
}
