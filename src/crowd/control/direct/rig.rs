//! A control turned into constraints (mesh-formation-control section 4.2): one
//! handle per finger plus supplementary soft constraints — for a line control the
//! vertices between its two handles, moved by linear interpolation of the handles;
//! for an area control the vertices inside the fingers' convex hull and points
//! sampled on and inside it ([`super::area`]), moved by their mean value
//! coordinates in that hull.

use super::area::{candidate_triangles, locate, sample_hull, sample_spacing};
use super::handle::{turn, Handle};
use crate::crowd::mesh::{convex_hull, mean_value_coordinates, point_in_convex_polygon};
use crate::geom::Vec2;
use crate::gesture::segment::{control_kind, Control};
use crate::vocab::ControlKind;

/// How a supplementary point's target follows the handles.
#[derive(Copy, Clone, Debug)]
pub(super) enum Support {
    /// Line control: position `t` along handle a→b and `d` across it, both relative
    /// to the handle distance.
    Line { t: f64, d: f64 },
    /// Area control: mean value coordinates over the hull of the fingers' points,
    /// `Rig::mvc[first..first + frame.len()]`; `grip` is `Σ_k w_k grip_k`, so the
    /// target is `Σ_k w_k pos_k − z · grip`.
    Area { first: u32, grip: Vec2 },
}

/// A supplementary constraint on a mesh vertex.
#[derive(Copy, Clone, Debug)]
pub(super) struct Supplementary {
    pub(super) vertex: u32,
    pub(super) support: Support,
}

/// A supplementary constraint on a point inside a mesh triangle (area samples).
#[derive(Copy, Clone, Debug)]
pub(super) struct Sample {
    pub(super) corners: [u32; 3],
    pub(super) bary: [f64; 3],
    pub(super) support: Support,
}

/// Buffers reused by every support built (no allocation once they have grown).
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    fingers: Vec<Vec2>,
    hull: Vec<Vec2>,
    points: Vec<Vec2>,
    triangles: Vec<u32>,
    weights: Vec<f64>,
}

/// The mesh a support is built on: its triangles, the user-mesh pose and the
/// mean edge length (m).
pub(super) struct MeshPose<'a> {
    pub(super) triangles: &'a [[u32; 3]],
    pub(super) verts: &'a [Vec2],
    pub(super) spacing_m: f64,
}

/// One control's constraints.
#[derive(Clone, Debug)]
pub(super) struct Rig {
    pub(super) id: u32,
    pub(super) kind: ControlKind,
    pub(super) handles: Vec<Handle>,
    /// Handle indices forming the hull (area) or the two ends (line).
    pub(super) frame: Vec<usize>,
    pub(super) supp: Vec<Supplementary>,
    pub(super) samples: Vec<Sample>,
    /// Mean value coordinates of the area supports, `frame.len()` each.
    pub(super) mvc: Vec<f64>,
    /// The hand's similarity since its fingers landed (`x + iy`), as last seen.
    pub(super) hand: Vec2,
    /// Every finger lifted: the handles go on through their remaining check points
    /// (section 4.1) until they arrive, a new control lands or a reset.
    pub(super) lifted: bool,
}

impl Rig {
    /// An empty rig (its buffers are reused through [`Rig::reuse`]).
    pub(super) fn new() -> Rig {
        Rig {
            id: 0,
            kind: ControlKind::Point,
            handles: Vec::new(),
            frame: Vec::new(),
            supp: Vec::new(),
            samples: Vec::new(),
            mvc: Vec::new(),
            hand: Vec2::new(1.0, 0.0),
            lifted: false,
        }
    }

    /// Makes a retired rig the rig of control `id`, keeping its buffers.
    pub(super) fn reuse(&mut self, id: u32) {
        self.id = id;
        self.kind = ControlKind::Point;
        self.handles.clear();
        self.frame.clear();
        self.supp.clear();
        self.samples.clear();
        self.mvc.clear();
        self.hand = Vec2::new(1.0, 0.0);
        self.lifted = false;
    }

    /// Where a supplementary point should be now (m, user mesh).
    pub(super) fn target(&self, s: &Support) -> Vec2 {
        match *s {
            Support::Line { t, d } => {
                let a = self.handles[self.frame[0]].pos;
                let b = self.handles[self.frame[1]].pos;
                let ab = b - a;
                a + ab * t + perp(ab) * d
            }
            Support::Area { first, grip } => {
                let w = &self.mvc[first as usize..first as usize + self.frame.len()];
                let at = self
                    .frame
                    .iter()
                    .zip(w)
                    .fold(Vec2::zeros(), |acc, (&hi, &w)| {
                        acc + self.handles[hi].pos * w
                    });
                at - turn(self.hand, grip)
            }
        }
    }

    /// Whether every handle stands on its last check point.
    pub(super) fn arrived(&self) -> bool {
        self.handles.iter().all(Handle::arrived)
    }

    /// Builds the supplementary points of section 4.2 for handles in place.
    pub(super) fn build_support(&mut self, mesh: &MeshPose<'_>, scratch: &mut Scratch) {
        self.kind = control_kind(self.handles.len());
        self.supp.clear();
        self.samples.clear();
        self.mvc.clear();
        self.frame.clear();
        match self.kind {
            ControlKind::Point => {}
            ControlKind::Line => self.line_support(0, 1, mesh),
            ControlKind::Area => self.area_support(mesh, scratch),
        }
    }

    fn is_handle_vertex(&self, v: u32) -> bool {
        self.handles.iter().any(|h| h.vertex == v)
    }

    /// Vertices within half a mesh spacing of the segment between handles `i` and
    /// `j`, strictly between its ends.
    fn line_support(&mut self, i: usize, j: usize, mesh: &MeshPose<'_>) {
        self.frame.extend([i, j]);
        let (a, b) = (self.handles[i].pos, self.handles[j].pos);
        let ab = b - a;
        let l2 = ab.norm_squared();
        if l2 < 1e-12 {
            return;
        }
        let tol = 0.5 * mesh.spacing_m;
        for (v, p) in mesh.verts.iter().enumerate() {
            if self.is_handle_vertex(v as u32) {
                continue;
            }
            let t = (p - a).dot(&ab) / l2;
            let across = perp(ab).dot(&(p - a)) / l2;
            if (0.0..=1.0).contains(&t) && (across * l2.sqrt()).abs() <= tol {
                self.supp.push(Supplementary {
                    vertex: v as u32,
                    support: Support::Line { t, d: across },
                });
            }
        }
    }

    /// The hull of the fingers' points; the vertices inside it and the points
    /// sampled on and inside it, each with its mean value coordinates.
    fn area_support(&mut self, mesh: &MeshPose<'_>, s: &mut Scratch) {
        s.fingers.clear();
        s.fingers
            .extend(self.handles.iter().map(|h| h.finger_point(self.hand)));
        let hull = convex_hull(&s.fingers);
        if hull.len() < 3 {
            // Collinear fingers: a line between the two farthest handles.
            let (i, j) = farthest_pair(&self.handles);
            self.line_support(i, j, mesh);
            return;
        }
        s.hull.clear();
        s.hull.extend(hull.iter().map(|&i| s.fingers[i]));
        self.frame.extend_from_slice(&hull);
        s.weights.clear();
        s.weights.resize(hull.len(), 0.0);
        for (v, p) in mesh.verts.iter().enumerate() {
            if self.is_handle_vertex(v as u32) || !point_in_convex_polygon(&s.hull, *p) {
                continue;
            }
            if let Some(support) = self.area_weights(&s.hull, *p, &mut s.weights) {
                self.supp.push(Supplementary {
                    vertex: v as u32,
                    support,
                });
            }
        }
        let h = sample_spacing(&s.hull, mesh.spacing_m);
        sample_hull(&s.hull, h, &mut s.points);
        candidate_triangles(mesh.triangles, mesh.verts, &s.hull, &mut s.triangles);
        for &p in &s.points {
            let Some((corners, bary)) = locate(mesh.triangles, &s.triangles, mesh.verts, p) else {
                continue;
            };
            if let Some(support) = self.area_weights(&s.hull, p, &mut s.weights) {
                self.samples.push(Sample {
                    corners,
                    bary,
                    support,
                });
            }
        }
    }

    /// `p`'s mean value coordinates in `hull`, stored in `mvc`.
    fn area_weights(&mut self, hull: &[Vec2], p: Vec2, w: &mut [f64]) -> Option<Support> {
        mean_value_coordinates(hull, p, w).ok()?;
        let first = self.mvc.len() as u32;
        self.mvc.extend_from_slice(w);
        let grip = self
            .frame
            .iter()
            .zip(w.iter())
            .fold(Vec2::zeros(), |acc, (&k, &wk)| {
                acc + self.handles[k].grip * wk
            });
        Some(Support::Area { first, grip })
    }
}

/// The least-squares similarity (rotation × scale, as a complex number `x + iy`)
/// carrying the fingers' landing positions to their current ones; `(1, 0)` for one
/// finger or when the fingers landed on one point.
pub(super) fn hand_similarity(c: &Control) -> Vec2 {
    let n = c.fingers.len();
    if n < 2 {
        return Vec2::new(1.0, 0.0);
    }
    let a0 = c.fingers.iter().map(|f| f.world_down).sum::<Vec2>() / n as f64;
    let b0 = c.fingers.iter().map(|f| f.world).sum::<Vec2>() / n as f64;
    let (mut re, mut im, mut norm) = (0.0, 0.0, 0.0);
    for f in &c.fingers {
        let (a, b) = (f.world_down - a0, f.world - b0);
        // conj(a) * b
        re += a.x * b.x + a.y * b.y;
        im += a.x * b.y - a.y * b.x;
        norm += a.norm_squared();
    }
    if norm < 1e-12 {
        return Vec2::new(1.0, 0.0);
    }
    Vec2::new(re / norm, im / norm)
}

/// `v` rotated by +90°.
fn perp(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

fn farthest_pair(handles: &[Handle]) -> (usize, usize) {
    let mut best = (0, 0, -1.0);
    for i in 0..handles.len() {
        for j in i + 1..handles.len() {
            let d = (handles[i].pos - handles[j].pos).norm_squared();
            if d > best.2 {
                best = (i, j, d);
            }
        }
    }
    (best.0, best.1)
}
