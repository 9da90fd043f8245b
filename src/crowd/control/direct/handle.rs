//! A finger's handle on the mesh and the check points it follows
//! (mesh-formation-control section 4.1: "We represent each trajectory as a set of
//! two-dimensional check points by dividing the trajectory into segments of a
//! pre-defined length").

use crate::geom::Vec2;
use crate::vocab::ContactId;

/// A handle this close to the last point of its trajectory has arrived (m). The
/// opposing force of section 4.1 holds a handle back by up to `force × dt` short of
/// its target while the agents lag (about 8 mm with 0.5 m of lag at 120 Hz), so
/// arriving means "within a centimetre".
pub(super) const ARRIVED_M: f64 = 0.01;

/// Check points a handle keeps ahead of it; the oldest is dropped when full.
pub(super) const PATH_CAPACITY: usize = 128;

/// Check points along a finger's trajectory, oldest first (fixed capacity).
#[derive(Clone, Debug)]
pub(super) struct Path {
    pts: [Vec2; PATH_CAPACITY],
    head: usize,
    len: usize,
}

impl Path {
    fn new() -> Path {
        Path {
            pts: [Vec2::zeros(); PATH_CAPACITY],
            head: 0,
            len: 0,
        }
    }
    fn get(&self, i: usize) -> Vec2 {
        self.pts[(self.head + i) % PATH_CAPACITY]
    }
    fn last(&self) -> Option<Vec2> {
        (self.len > 0).then(|| self.get(self.len - 1))
    }
    fn push(&mut self, p: Vec2) {
        if self.len == PATH_CAPACITY {
            // Drop the oldest check point: the handle shortcuts a little.
            self.pop_front();
        }
        self.pts[(self.head + self.len) % PATH_CAPACITY] = p;
        self.len += 1;
    }
    fn pop_front(&mut self) {
        if self.len > 0 {
            self.head = (self.head + 1) % PATH_CAPACITY;
            self.len -= 1;
        }
    }
    fn front(&self) -> Option<Vec2> {
        (self.len > 0).then(|| self.get(0))
    }
    /// Moves every check point by `d`.
    fn shift(&mut self, d: Vec2) {
        for i in 0..self.len {
            let k = (self.head + i) % PATH_CAPACITY;
            self.pts[k] += d;
        }
    }
}

/// `z · v` for the similarity `z = x + iy` (rotation × scale, a complex number).
pub(super) fn turn(z: Vec2, v: Vec2) -> Vec2 {
    Vec2::new(z.x * v.x - z.y * v.y, z.y * v.x + z.x * v.y)
}

/// `z⁻¹ · v`; `v` when `z` is (nearly) zero.
pub(super) fn unturn(z: Vec2, v: Vec2) -> Vec2 {
    let n2 = z.norm_squared();
    if n2 < 1e-24 {
        return v;
    }
    Vec2::new(z.x * v.x + z.y * v.y, z.x * v.y - z.y * v.x) / n2
}

/// One finger's hold on the mesh: the vertex nearest where it landed (a control
/// point of section 4.1), the constraint target that vertex follows, and the check
/// points still ahead of it.
#[derive(Clone, Debug)]
pub(super) struct Handle {
    pub(super) finger: ContactId,
    pub(super) vertex: u32,
    /// The vertex's user-mesh position minus the finger's position when it landed,
    /// in the hand's frame at landing (m): the target is `finger + z · offset`
    /// for the hand's similarity `z` since then.
    pub(super) offset: Vec2,
    /// The vertex's final-mesh position (where the finger saw it) minus the
    /// finger's landing position, in the hand's frame at landing (m): the finger's
    /// own point carried into the user mesh is `pos − z · grip`.
    pub(super) grip: Vec2,
    /// Current constraint target (m, user mesh).
    pub(super) pos: Vec2,
    /// Where the finger wants the handle: its latest position + `z · offset` (m).
    pub(super) goal: Vec2,
    path: Path,
}

impl Handle {
    /// A handle on `vertex`, at `user` on the user mesh and `seen` on the final
    /// mesh, for a finger landed at `finger_at` (m).
    pub(super) fn new(
        finger: ContactId,
        vertex: u32,
        user: Vec2,
        seen: Vec2,
        finger_at: Vec2,
    ) -> Handle {
        Handle {
            finger,
            vertex,
            offset: user - finger_at,
            grip: seen - finger_at,
            pos: user,
            goal: user,
            path: Path::new(),
        }
    }

    /// The finger's point carried into the user mesh, for the hand's similarity
    /// `z` (m).
    pub(super) fn finger_point(&self, z: Vec2) -> Vec2 {
        self.pos - turn(z, self.grip)
    }

    /// Distance still to go: through the check points to the goal (m).
    pub(super) fn remaining(&self) -> f64 {
        let mut d = 0.0;
        let mut prev = self.pos;
        for i in 0..self.path.len {
            let p = self.path.get(i);
            d += (p - prev).norm();
            prev = p;
        }
        d + (self.goal - prev).norm()
    }

    /// Whether the handle is within [`ARRIVED_M`] of the last point of its
    /// trajectory, along the check points.
    pub(super) fn arrived(&self) -> bool {
        self.remaining() <= ARRIVED_M
    }

    /// Adds check points up to the finger's latest target.
    pub(super) fn record(&mut self, goal: Vec2, spacing: f64) {
        self.goal = goal;
        let mut last = self.path.last().unwrap_or(self.pos);
        let mut d = goal - last;
        let mut n = d.norm();
        while n >= spacing {
            last += d * (spacing / n);
            self.path.push(last);
            d = goal - last;
            n = d.norm();
        }
    }

    /// Moves along the check points by `dist` metres.
    pub(super) fn advance(&mut self, mut dist: f64) {
        while dist > 0.0 {
            let next = self.path.front().unwrap_or(self.goal);
            let d = next - self.pos;
            let n = d.norm();
            if n <= dist {
                self.pos = next;
                dist -= n;
                if self.path.len == 0 {
                    return;
                }
                self.path.pop_front();
            } else {
                self.pos += d * (dist / n);
                return;
            }
        }
    }

    /// Moves the handle onto another vertex `d` away (a formation switch), keeping
    /// its finger where it is: the offsets are in the hand's landing frame, so the
    /// move is turned back by the hand's similarity `z` before it is added
    /// (`finger + z · (offset + z⁻¹ d) = old target + d`).
    pub(super) fn rebase(&mut self, vertex: u32, d: Vec2, z: Vec2) {
        let back = unturn(z, d);
        self.vertex = vertex;
        self.offset += back;
        self.grip += back;
        self.pos += d;
        self.goal += d;
        self.path.shift(d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_handle_follows_its_check_points_to_the_goal_and_arrives() {
        let mut h = Handle::new(ContactId(1), 0, Vec2::zeros(), Vec2::zeros(), Vec2::zeros());
        // An L-shaped trajectory: the handle goes round the corner, not across it.
        h.record(Vec2::new(1.0, 0.0), 0.1);
        h.record(Vec2::new(1.0, 1.0), 0.1);
        assert!((h.remaining() - 2.0).abs() < 1e-9, "{}", h.remaining());
        h.advance(1.05);
        assert!((h.pos - Vec2::new(1.0, 0.05)).norm() < 1e-9, "{}", h.pos);
        assert!(!h.arrived());
        h.advance(0.93);
        assert!(!h.arrived(), "2 cm short");
        h.advance(0.015);
        assert!(h.arrived(), "5 mm short");
        h.advance(10.0);
        assert!(h.arrived() && h.pos == Vec2::new(1.0, 1.0));
    }

    #[test]
    fn rebase_keeps_the_target_of_a_turned_and_scaled_hand() {
        let finger = Vec2::new(2.0, 1.0);
        let mut h = Handle::new(
            ContactId(1),
            3,
            finger + Vec2::new(0.2, 0.1),
            finger,
            finger,
        );
        // The hand turned by 90° and shrank to 0.6: z = 0.6 i.
        let z = Vec2::new(0.0, 0.6);
        let target = |h: &Handle| finger + turn(z, h.offset);
        h.record(target(&h), 0.05);
        h.advance(10.0);
        let before = target(&h);
        let d = Vec2::new(-0.15, 0.25);
        h.rebase(7, d, z);
        assert!((target(&h) - (before + d)).norm() < 1e-12);
        assert!((h.pos - (before + d)).norm() < 1e-12);
        assert!((unturn(z, turn(z, d)) - d).norm() < 1e-12);
    }
}
