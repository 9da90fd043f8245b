//! Recycled `Arc`s for what the engine publishes every tick.

use std::sync::Arc;

/// Pooled items kept for reuse.
const POOL_CAP: usize = 32;

/// A recycling pool of `Arc`s: an item is reused once every other holder dropped it.
pub(super) struct ArcPool<T> {
    items: Vec<Arc<T>>,
}

impl<T: Default + Clone> ArcPool<T> {
    pub(super) fn new() -> Self {
        ArcPool {
            items: Vec::with_capacity(POOL_CAP),
        }
    }
    pub(super) fn acquire(&mut self) -> Arc<T> {
        match self
            .items
            .iter()
            .position(|a| Arc::strong_count(a) == 1 && Arc::weak_count(a) == 0)
        {
            Some(i) => self.items.swap_remove(i),
            None => Arc::new(T::default()),
        }
    }
    pub(super) fn keep(&mut self, a: &Arc<T>) {
        if self.items.len() < POOL_CAP {
            self.items.push(Arc::clone(a));
        }
    }
}
