//! `replay --svg`: a picture of what a recording did to the crowd.
//!
//! Draws the world box, the mesh before (grey) and after (blue), each agent's path
//! (thin lines, start dot hollow, end dot filled) and the fingers' paths (red).

use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::picture::{elements, style, Canvas, Frame, Paint};
use crowdtouch::vocab::{MeshView, Snapshot};
use std::collections::BTreeMap;

/// Collects what the picture needs while a replay runs.
#[derive(Default)]
pub struct Trace {
    agent_paths: Vec<Vec<Vec2>>,
    touch_paths: BTreeMap<u32, Vec<Vec2>>,
    first_mesh: Option<MeshView>,
    last_mesh: Option<MeshView>,
    ticks: u64,
}

/// Every how many ticks an agent path gets a point.
const PATH_EVERY_TICKS: u64 = 12;

impl Trace {
    /// Records one tick.
    pub fn tick(&mut self, s: &Snapshot, mesh: Option<&MeshView>) {
        if let Some(m) = mesh {
            if self.first_mesh.is_none() {
                self.first_mesh = Some(m.clone());
            }
            self.last_mesh = Some(m.clone());
        }
        if self.agent_paths.len() != s.agents.len() {
            self.agent_paths = vec![Vec::new(); s.agents.len()];
        }
        if self.ticks % PATH_EVERY_TICKS == 0 {
            for (p, a) in self.agent_paths.iter_mut().zip(&s.agents) {
                p.push(a.pos);
            }
        }
        for t in &s.touches {
            self.touch_paths.entry(t.id).or_default().push(t.pos);
        }
        self.ticks += 1;
    }

    /// Everything drawn, as a box with a margin, within the world.
    fn extent(&self, world: Rect) -> Rect {
        let mut lo = Vec2::repeat(f64::INFINITY);
        let mut hi = Vec2::repeat(f64::NEG_INFINITY);
        let meshes = self
            .first_mesh
            .iter()
            .chain(&self.last_mesh)
            .flat_map(|m| m.vertices.iter());
        let paths = self
            .agent_paths
            .iter()
            .flatten()
            .chain(self.touch_paths.values().flatten());
        for p in meshes.chain(paths) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if !lo.x.is_finite() {
            return world;
        }
        const MARGIN_M: f64 = 0.6;
        Rect {
            min: [
                (lo.x - MARGIN_M).max(world.min[0]),
                (lo.y - MARGIN_M).max(world.min[1]),
            ],
            max: [
                (hi.x + MARGIN_M).min(world.max[0]),
                (hi.y + MARGIN_M).min(world.max[1]),
            ],
        }
    }

    /// The SVG document, cropped to what moved (within `world`).
    pub fn render(&mut self, world: Rect, title: &str) -> String {
        const PX_PER_M: f64 = 90.0;
        const CAPTION_PX: f64 = 28.0;
        let f = Frame {
            world: self.extent(world),
            px_per_m: PX_PER_M,
            left_px: 0.0,
            top_px: 0.0,
            y_up: false,
        };
        let (w, h) = (f.width_px(), f.height_px());
        let mut c = Canvas::new(w, h + CAPTION_PX);
        if let Some(m) = &self.first_mesh {
            let before = Paint::stroke(style::MESH_BEFORE, style::HAIRLINE_PX).class("mesh-before");
            elements::mesh(&mut c, &f, &m.vertices, &m.triangles, &before);
        }
        if let Some(m) = &self.last_mesh {
            let after =
                Paint::fill_stroke(style::MESH_FILL, style::MESH_STROKE, style::HAIRLINE_PX)
                    .fill_opacity(0.5)
                    .class("mesh-after");
            elements::mesh(&mut c, &f, &m.vertices, &m.triangles, &after);
        }
        let path = Paint::stroke(style::PATH, 0.8)
            .stroke_opacity(0.35)
            .class("path");
        let start = Paint::stroke(style::AGENT_START, style::HAIRLINE_PX).class("start");
        let end = Paint::fill(style::AGENT).class("agent");
        for p in &self.agent_paths {
            if p.len() < 2 {
                continue;
            }
            elements::track(&mut c, &f, p, &path);
            c.circle(f.pt(p[0]), 2.2, &start);
            c.circle(f.pt(p[p.len() - 1]), 2.6, &end);
        }
        let finger = Paint::stroke(style::TOUCH, style::BOLD_PX).class("finger");
        for p in self.touch_paths.values() {
            elements::track(&mut c, &f, p, &finger);
            if let Some(&e) = p.last() {
                c.circle(f.pt(e), 6.0, &finger);
            }
        }
        c.caption(
            (6.0, (h + 19.0).round()),
            &format!("{title}: mesh before (grey), after (blue), fingers (red)"),
        );
        c.finish()
    }
}
