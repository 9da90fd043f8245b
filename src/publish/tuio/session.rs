//! Session ids: the number a TUIO client follows an entity by.
//!
//! One counter serves every kind (cursors, objects, blobs), so ids are unique
//! across them, as TUIO 2.0 asks of `ptr`, `tok` and `bnd` sharing one `alv`
//! list. An agent keeps its id for as long as it exists (agent `i` of one snapshot
//! is agent `i` of the next; a smaller crowd drops the last ones, a larger one
//! gives the new agents fresh ids). A touch or a control gets a fresh id when its
//! contact or control id appears, and keeps it until it is gone: a contact id the
//! device reuses for a later finger is a new session, as TUIO expects.

/// Hands out session ids: 1, 2, 3, … (wrapping to 1 after `i32::MAX`, which at
/// 1,000 new sessions a second takes 24 days).
#[derive(Debug)]
pub struct SessionIds {
    next: i32,
}

impl Default for SessionIds {
    fn default() -> Self {
        SessionIds { next: 1 }
    }
}

impl SessionIds {
    /// A new session id.
    pub fn fresh(&mut self) -> i32 {
        let id = self.next;
        self.next = if self.next == i32::MAX {
            1
        } else {
            self.next + 1
        };
        id
    }
}

/// Entities known by a key (a contact or control id) from one frame to the next,
/// each with its session id and what the previous frame said of it.
#[derive(Debug)]
pub struct Keyed<T> {
    prev: Vec<(u32, i32, T)>,
    now: Vec<(u32, i32, T)>,
}

impl<T> Default for Keyed<T> {
    fn default() -> Self {
        Keyed {
            prev: Vec::new(),
            now: Vec::new(),
        }
    }
}

impl<T: Copy> Keyed<T> {
    /// Starts a frame: what the last frame kept becomes the previous state.
    pub fn begin(&mut self) {
        std::mem::swap(&mut self.prev, &mut self.now);
        self.now.clear();
    }

    /// The session of `key` (fresh when the previous frame did not have it) and its
    /// previous state.
    pub fn session(&mut self, key: u32, ids: &mut SessionIds) -> (i32, Option<T>) {
        if let Some(&(_, s, t)) = self.now.iter().find(|e| e.0 == key) {
            return (s, Some(t));
        }
        match self.prev.iter().find(|e| e.0 == key) {
            Some(&(_, s, t)) => (s, Some(t)),
            None => (ids.fresh(), None),
        }
    }

    /// Keeps `key` in this frame with its session and state.
    pub fn keep(&mut self, key: u32, session: i32, state: T) {
        match self.now.iter_mut().find(|e| e.0 == key) {
            Some(e) => *e = (key, session, state),
            None => self.now.push((key, session, state)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_keeps_its_session_while_present_and_gets_a_new_one_when_it_returns() {
        let mut ids = SessionIds::default();
        let mut k = Keyed::<()>::default();
        k.begin();
        let (a, prev) = k.session(7, &mut ids);
        assert!(prev.is_none());
        k.keep(7, a, ());
        k.begin();
        let (a2, prev) = k.session(7, &mut ids);
        assert_eq!((a2, prev), (a, Some(())));
        // Absent for one frame: gone.
        k.begin();
        k.begin();
        let (a3, _) = k.session(7, &mut ids);
        assert_ne!(a3, a);
    }

    #[test]
    fn ids_wrap_to_one() {
        let mut ids = SessionIds { next: i32::MAX };
        assert_eq!(ids.fresh(), i32::MAX);
        assert_eq!(ids.fresh(), 1);
    }
}
