//! The trial cells of a march ([`Fmm`](super::Fmm)), ordered by tentative `Φ`: a 4-ary
//! min-heap without decrease-key.

/// Children per node of [`Heap`] (4-ary: half the depth of a binary heap, and the
/// children share a cache line).
const HEAP_ARITY: usize = 4;

/// A trial cell in the heap: its tentative `Φ` (as the bits of a non-negative
/// `f64`, which order as integers do), its index in the padded arrays and in the
/// grid (16 bytes).
#[derive(Copy, Clone, Debug)]
pub(super) struct Trial {
    pub(super) key: u64,
    pub(super) padded: u32,
    pub(super) cell: u32,
}

/// 4-ary min-heap of trial cells keyed by their tentative `Φ`, without
/// decrease-key: a lowered value is pushed again and the stale entry is skipped when
/// it surfaces (its cell is frozen by then, since the lower entry surfaced first).
/// No position array to keep up to date on every move, and no trial-value array:
/// every update pushes (a cell is pushed once per neighbour that freezes before it,
/// at most four times).
#[derive(Clone, Debug, Default)]
pub(super) struct Heap {
    pub(super) items: Vec<Trial>,
}

impl Heap {
    pub(super) fn clear(&mut self) {
        self.items.clear();
    }

    #[inline]
    pub(super) fn push(&mut self, item: Trial) {
        let mut hole = self.items.len();
        self.items.push(item);
        while hole > 0 {
            let parent = (hole - 1) / HEAP_ARITY;
            let p = self.items[parent];
            if p.key <= item.key {
                break;
            }
            self.items[hole] = p;
            hole = parent;
        }
        self.items[hole] = item;
    }

    /// Removes and returns the entry with the smallest key.
    ///
    /// Bottom-up (Floyd): the hole at the root moves down along the smallest
    /// children to a leaf without comparing against the last item, which then sifts
    /// up from there (it came from the bottom, so it rarely climbs). The smallest of
    /// four children is found with selects, not branches.
    #[inline]
    pub(super) fn pop(&mut self) -> Option<Trial> {
        let top = *self.items.first()?;
        let last = self.items.pop().expect("non-empty");
        let n = self.items.len();
        if n == 0 {
            return Some(top);
        }
        let items = &mut self.items;
        let mut hole = 0;
        loop {
            let first = HEAP_ARITY * hole + 1;
            let c = if first + HEAP_ARITY <= n {
                let k = |j: usize| items[j].key;
                let (a, ka) = if k(first + 1) < k(first) {
                    (first + 1, k(first + 1))
                } else {
                    (first, k(first))
                };
                let (b, kb) = if k(first + 3) < k(first + 2) {
                    (first + 3, k(first + 3))
                } else {
                    (first + 2, k(first + 2))
                };
                if kb < ka {
                    b
                } else {
                    a
                }
            } else if first < n {
                (first + 1..n).fold(
                    first,
                    |c, j| if items[j].key < items[c].key { j } else { c },
                )
            } else {
                break;
            };
            items[hole] = items[c];
            hole = c;
        }
        while hole > 0 {
            let parent = (hole - 1) / HEAP_ARITY;
            if items[parent].key <= last.key {
                break;
            }
            items[hole] = items[parent];
            hole = parent;
        }
        items[hole] = last;
        Some(top)
    }
}
