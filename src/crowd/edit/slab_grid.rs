//! The uniform grid collision detection (`collide.rs`) lays over each time slab:
//! the cells a piece's box covers, and how one slab's cells map to buckets.

use crate::geom::Vec2;

/// The most grid cells one piece is entered into; a piece covering more is compared
/// with every piece of its slab instead.
pub(super) const MAX_CELLS_PER_PIECE: i64 = 64;

/// The cells a box covers, `None` when more than [`MAX_CELLS_PER_PIECE`].
pub(super) fn cell_range(b: &(Vec2, Vec2), cell: f64) -> Option<(i64, i64, i64, i64)> {
    let x0 = (b.0.x / cell).floor() as i64;
    let x1 = (b.1.x / cell).floor() as i64;
    let y0 = (b.0.y / cell).floor() as i64;
    let y1 = (b.1.y / cell).floor() as i64;
    let cells = (x1 - x0 + 1).saturating_mul(y1 - y0 + 1);
    (cells <= MAX_CELLS_PER_PIECE).then_some((x0, x1, y0, y1))
}

fn cell_key(x: i64, y: i64) -> u64 {
    ((x as u32 as u64) << 32) | (y as u32 as u64)
}

/// The bucket of a cell key among `nb` (a power of two).
fn bucket_of(key: u64, nb: usize) -> usize {
    (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & (nb - 1)
}

/// How one slab's cells map to buckets: row by row over the cells' bounding box
/// when it holds no more than [`DENSE_CELLS_PER_ENTRY`] cells per entry (neighbouring
/// cells in neighbouring buckets: people near each other read memory near each
/// other), else hashed into a power of two of buckets (a bucket may then hold
/// several cells: the box test drops the extra pieces). Either way at most two
/// buckets (4 bytes each) per entry, or 32 for a slab of fewer than 16 entries.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct SlabGrid {
    /// The cell size (metres).
    pub(super) cell: f64,
    x0: i64,
    y0: i64,
    w: i64,
    h: i64,
    /// The number of buckets.
    pub(super) buckets: usize,
    dense: bool,
}

/// See [`SlabGrid`].
pub(super) const DENSE_CELLS_PER_ENTRY: i64 = 2;

impl SlabGrid {
    pub(super) fn new(
        cell: f64,
        (x0, x1, y0, y1): (i64, i64, i64, i64),
        entries: usize,
    ) -> SlabGrid {
        let w = x1.saturating_sub(x0).saturating_add(1).max(1);
        let h = y1.saturating_sub(y0).saturating_add(1).max(1);
        let limit = (entries as i64)
            .max(16)
            .saturating_mul(DENSE_CELLS_PER_ENTRY);
        let dense = entries > 0 && w.checked_mul(h).is_some_and(|c| c <= limit);
        SlabGrid {
            cell,
            x0,
            y0,
            w,
            h,
            buckets: if dense {
                (w * h) as usize
            } else {
                entries.next_power_of_two().max(2)
            },
            dense,
        }
    }

    pub(super) fn bucket(&self, x: i64, y: i64) -> Option<usize> {
        if self.dense {
            let (dx, dy) = (x - self.x0, y - self.y0);
            (dx >= 0 && dy >= 0 && dx < self.w && dy < self.h).then(|| (dy * self.w + dx) as usize)
        } else {
            Some(bucket_of(cell_key(x, y), self.buckets))
        }
    }
}

pub(super) fn overlap(a: &(Vec2, Vec2), b: &(Vec2, Vec2)) -> bool {
    a.0.x <= b.1.x && b.0.x <= a.1.x && a.0.y <= b.1.y && b.0.y <= a.1.y
}
