//! Giving up a long solve: [`Cancel`], a check the solver polls between bounded
//! pieces of work.
//!
//! A solve started for a crowd that no longer exists (resized, reset, switched to
//! another formation) or in a daemon that is stopping is worth nothing; the caller
//! says so through the check, and the solve returns
//! [`AssignError::Cancelled`](super::AssignError::Cancelled) at its next poll. The
//! solver polls about every [`POLL_WORK`] units of work (a unit is about one cost
//! entry read or one list slot scanned), so a poll costs nothing measurable and a
//! cancelled solve stops within a fraction of a millisecond. This module holds no
//! thread, clock or channel: what the check reads (an atomic generation, a flag) is
//! the caller's.

use std::fmt;

/// Units of work (about one cost entry read or one candidate slot scanned each)
/// between two polls of a [`Cancel`] check in the solver: about 30–100 µs of work.
pub const POLL_WORK: u64 = 1 << 15;

/// A cancellation check: `true` once the work is no longer wanted. `Copy`, so it
/// is passed down by value; [`Cancel::NEVER`] never cancels.
///
/// ```
/// use crowdtouch::crowd::assign::Cancel;
/// use std::sync::atomic::{AtomicU64, Ordering};
/// let generation = AtomicU64::new(7);
/// let wanted = 7;
/// let check = || generation.load(Ordering::Relaxed) != wanted;
/// let cancel = Cancel::new(&check);
/// assert!(!cancel.cancelled());
/// generation.store(8, Ordering::Relaxed);
/// assert!(cancel.cancelled());
/// assert!(!Cancel::NEVER.cancelled());
/// ```
#[derive(Copy, Clone)]
pub struct Cancel<'a> {
    check: Option<&'a dyn Fn() -> bool>,
}

impl<'a> Cancel<'a> {
    /// Never cancels.
    pub const NEVER: Cancel<'static> = Cancel { check: None };

    /// Cancels once `check` returns `true` (it is called at every poll, so it must
    /// be cheap: an atomic load and a comparison).
    pub fn new(check: &'a dyn Fn() -> bool) -> Cancel<'a> {
        Cancel { check: Some(check) }
    }

    /// Whether the work is no longer wanted (calls the check).
    #[inline]
    pub fn cancelled(&self) -> bool {
        self.check.is_some_and(|f| f())
    }

    /// The check as a plain function, for code that cannot name this type (the
    /// mesh module's goal sampling).
    pub fn as_fn(&self) -> impl Fn() -> bool + 'a {
        let check = self.check;
        move || check.is_some_and(|f| f())
    }
}

impl Default for Cancel<'_> {
    fn default() -> Self {
        Cancel::NEVER
    }
}

impl fmt::Debug for Cancel<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.check.is_some() {
            "Cancel(check)"
        } else {
            "Cancel::NEVER"
        })
    }
}
