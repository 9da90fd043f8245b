//! `replay --svg`: a picture of what a recording did to the crowd.
//!
//! Draws the world box, the mesh before (grey) and after (blue), each agent's path
//! (thin lines, start dot hollow, end dot filled) and the fingers' paths (red).

use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::vocab::{MeshView, Snapshot};
use std::collections::BTreeMap;
use std::fmt::Write;

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
        let world = self.extent(world);
        const PX_PER_M: f64 = 90.0;
        let (w, h) = (world.width() * PX_PER_M, world.height() * PX_PER_M);
        let x = |p: Vec2| (p.x - world.min[0]) * PX_PER_M;
        let y = |p: Vec2| (p.y - world.min[1]) * PX_PER_M;
        let mut s = String::new();
        let _ = writeln!(
            s,
            r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w:.0} {:.0}" width="{w:.0}" height="{:.0}" font-family="sans-serif">"##,
            h + 28.0,
            h + 28.0
        );
        let _ = writeln!(
            s,
            r##"<rect x="0" y="0" width="{w:.0}" height="{:.0}" fill="#fbfbf8"/>"##,
            h + 28.0
        );
        let mesh_svg = |m: &MeshView, stroke: &str, fill: &str, s: &mut String| {
            for t in m.triangles.iter() {
                let pts: Vec<String> = t
                    .iter()
                    .map(|&v| {
                        format!(
                            "{:.1},{:.1}",
                            x(m.vertices[v as usize]),
                            y(m.vertices[v as usize])
                        )
                    })
                    .collect();
                let _ = writeln!(
                    s,
                    r##"<polygon points="{}" fill="{fill}" stroke="{stroke}" stroke-width="0.6"/>"##,
                    pts.join(" ")
                );
            }
        };
        if let Some(m) = &self.first_mesh {
            mesh_svg(m, "#bbb", "none", &mut s);
        }
        if let Some(m) = &self.last_mesh {
            mesh_svg(m, "#4a78c2", "#4a78c214", &mut s);
        }
        for p in &self.agent_paths {
            if p.len() < 2 {
                continue;
            }
            let pts: Vec<String> = p
                .iter()
                .map(|&q| format!("{:.1},{:.1}", x(q), y(q)))
                .collect();
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="#555" stroke-opacity="0.35" stroke-width="0.8"/>"##,
                pts.join(" ")
            );
            let (a, b) = (p[0], p[p.len() - 1]);
            let _ = writeln!(
                s,
                r##"<circle cx="{:.1}" cy="{:.1}" r="2.2" fill="none" stroke="#777" stroke-width="0.7"/>"##,
                x(a),
                y(a)
            );
            let _ = writeln!(
                s,
                r##"<circle cx="{:.1}" cy="{:.1}" r="2.6" fill="#1d3f7a"/>"##,
                x(b),
                y(b)
            );
        }
        for p in self.touch_paths.values() {
            let pts: Vec<String> = p
                .iter()
                .map(|&q| format!("{:.1},{:.1}", x(q), y(q)))
                .collect();
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="#d33" stroke-width="2" stroke-linecap="round"/>"##,
                pts.join(" ")
            );
            if let Some(&e) = p.last() {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{:.1}" cy="{:.1}" r="6" fill="none" stroke="#d33" stroke-width="2"/>"##,
                    x(e),
                    y(e)
                );
            }
        }
        let _ = writeln!(
            s,
            r##"<text x="6" y="{:.0}" font-size="13" fill="#333">{}: mesh before (grey), after (blue), fingers (red)</text>"##,
            h + 19.0,
            xml_escape(title)
        );
        s.push_str("</svg>\n");
        s
    }
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
