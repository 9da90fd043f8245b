//! The priority queues of the augmenting-path searches: [`ColHeap`] of columns by
//! tentative distance (with decrease-key), and [`PendHeap`] of the [`Pending`] work of
//! scanned rows in a sparse search; and the per-column search state [`Mark`].

/// "Not in the heap".
const ABSENT: u32 = u32::MAX;

/// Binary min-heap of columns keyed by tentative distance, with decrease-key.
/// Capacity is reserved for every column, so it never allocates after sizing.
#[derive(Clone, Debug, Default)]
pub(super) struct ColHeap {
    pub(super) key: Vec<f64>,
    pub(super) col: Vec<u32>,
    pub(super) pos: Vec<u32>,
}

impl ColHeap {
    pub(super) fn size_for(&mut self, cols: usize) {
        self.key = Vec::with_capacity(cols);
        self.col = Vec::with_capacity(cols);
        self.pos.clear();
        self.pos.resize(cols, ABSENT);
    }

    pub(super) fn clear(&mut self) {
        for &c in &self.col {
            self.pos[c as usize] = ABSENT;
        }
        self.key.clear();
        self.col.clear();
    }

    #[inline]
    pub(super) fn push_or_decrease(&mut self, c: u32, k: f64) {
        let p = self.pos[c as usize];
        let at = if p == ABSENT {
            self.key.push(k);
            self.col.push(c);
            self.key.len() - 1
        } else {
            p as usize
        };
        self.sift_up(at, c, k);
    }

    #[inline]
    fn sift_up(&mut self, mut at: usize, c: u32, k: f64) {
        while at > 0 {
            let parent = (at - 1) / 2;
            let pk = self.key[parent];
            if pk <= k {
                break;
            }
            let pc = self.col[parent];
            self.key[at] = pk;
            self.col[at] = pc;
            self.pos[pc as usize] = at as u32;
            at = parent;
        }
        self.key[at] = k;
        self.col[at] = c;
        self.pos[c as usize] = at as u32;
    }

    #[inline]
    pub(super) fn pop(&mut self) -> Option<(f64, u32)> {
        let top_k = *self.key.first()?;
        let top_c = self.col[0];
        self.pos[top_c as usize] = ABSENT;
        let (lk, lc) = match (self.key.pop(), self.col.pop()) {
            (Some(k), Some(c)) => (k, c),
            _ => return Some((top_k, top_c)),
        };
        if !self.key.is_empty() {
            let n = self.key.len();
            let mut at = 0;
            loop {
                let l = 2 * at + 1;
                if l >= n {
                    break;
                }
                let r = l + 1;
                let m = if r < n && self.key[r] < self.key[l] {
                    r
                } else {
                    l
                };
                let mk = self.key[m];
                if mk >= lk {
                    break;
                }
                let mc = self.col[m];
                self.key[at] = mk;
                self.col[at] = mc;
                self.pos[mc as usize] = at as u32;
                at = m;
            }
            self.key[at] = lk;
            self.col[at] = lc;
            self.pos[lc as usize] = at as u32;
        }
        Some((top_k, top_c))
    }
}

/// Pending work of a scanned row in a sparse search: the columns of the row not
/// relaxed yet cannot get a distance below `bound`. `slot < len` means the row's
/// candidate list from `slot` on; [`BEYOND`] means the columns off the list, whose
/// [`key`]s are all at least `lo`.
///
/// [`key`]: super::candidates::key
#[derive(Copy, Clone, Debug)]
pub(super) struct Pending {
    pub(super) bound: f64,
    pub(super) off: f64,
    pub(super) lo: u64,
    pub(super) row: u32,
    pub(super) slot: u32,
}

/// Search state of a column in a sparse search: tentative distance, and the epochs
/// in which it was reached (`seen`) and settled (`done`).
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct Mark {
    pub(super) dist: f64,
    pub(super) seen: u32,
    pub(super) done: u32,
}

/// [`Pending::slot`] of the columns off the candidate list.
pub(super) const BEYOND: u32 = u32::MAX;

/// Binary min-heap of [`Pending`] by `bound` (never NaN). Capacity is reserved for
/// two entries per row, more than a search can hold (one per scanned row plus the
/// free row), so it never allocates after sizing.
#[derive(Clone, Debug, Default)]
pub(super) struct PendHeap {
    pub(super) items: Vec<Pending>,
}

impl PendHeap {
    pub(super) fn size_for(&mut self, rows: usize) {
        self.items = Vec::with_capacity(2 * rows + 2);
    }

    pub(super) fn clear(&mut self) {
        self.items.clear();
    }

    #[inline]
    pub(super) fn min_bound(&self) -> f64 {
        self.items.first().map_or(f64::INFINITY, |p| p.bound)
    }

    #[inline]
    pub(super) fn push(&mut self, p: Pending) {
        self.items.push(p);
        let mut at = self.items.len() - 1;
        while at > 0 {
            let parent = (at - 1) / 2;
            if self.items[parent].bound <= p.bound {
                break;
            }
            self.items[at] = self.items[parent];
            at = parent;
        }
        self.items[at] = p;
    }

    #[inline]
    pub(super) fn pop(&mut self) -> Option<Pending> {
        let top = *self.items.first()?;
        let last = self.items.pop()?;
        let n = self.items.len();
        if n > 0 {
            let mut at = 0;
            loop {
                let l = 2 * at + 1;
                if l >= n {
                    break;
                }
                let r = l + 1;
                let m = if r < n && self.items[r].bound < self.items[l].bound {
                    r
                } else {
                    l
                };
                if self.items[m].bound >= last.bound {
                    break;
                }
                self.items[at] = self.items[m];
                at = m;
            }
            self.items[at] = last;
        }
        Some(top)
    }
}
