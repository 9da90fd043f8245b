//! `crowdtouch formations`: the formation shapes a config defines, as a list or a
//! picture.

use super::output::outln;
use anyhow::{Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::formation::{Placement, START};
use crowdtouch::crowd::mesh::{goal_positions, sample_goals, TriMesh};
use crowdtouch::geom::Vec2;
use std::fmt::Write as _;
use std::path::Path;

/// Pixels per metre in the picture.
const PX_PER_M: f64 = 40.0;
/// Width and height of one formation's panel (m).
const PANEL_M: f64 = 8.0;
/// Panels per row.
const PER_ROW: usize = 4;

/// Lists the formations of `cfg` (and draws them into `svg` when given): each
/// meshed as a switch would lay it out for the config's crowd, at the area of
/// `crowd.formation`, heading `+x`, with as many vertices as the start mesh and one
/// goal per agent.
pub fn formations(cfg: &Config, svg: Option<&Path>) -> Result<()> {
    let rect = cfg.crowd.formation;
    let area = rect.width() * rect.height();
    let vertices = (cfg.mesh.cols * cfg.mesh.rows) as usize;
    let agents = cfg.crowd.agents as usize;
    let lib = cfg.formation_library();
    let mut panels: Vec<(String, TriMesh, Vec<Vec2>)> = Vec::new();
    let start = TriMesh::grid(rect, cfg.mesh.cols as usize, cfg.mesh.rows as usize);
    let centre = Vec2::new(0.5 * PANEL_M, 0.5 * PANEL_M);
    let mut start = start;
    start.translate(centre - rect.center());
    panels.push((START.to_string(), start, Vec::new()));
    for name in lib.names() {
        let f = lib.get(name).context("formation listed but not found")?;
        let place = Placement {
            centre_m: centre,
            heading: Vec2::new(1.0, 0.0),
            area_m2: area,
        };
        let m = f
            .mesh(&place, vertices)
            .with_context(|| format!("formation `{name}` cannot be meshed"))?;
        panels.push((name.to_string(), m, f.placed_outline(&place)));
    }
    outln!(
        "{:<12} {:>8} {:>9} {:>10}   (meshed at {area:.1} m², {vertices} vertices asked, {agents} agents)",
        "formation", "outline", "vertices", "triangles"
    )?;
    for (name, m, outline) in &panels {
        let outline = if name == START {
            "grid".to_string()
        } else {
            outline.len().to_string()
        };
        outln!(
            "{name:<12} {outline:>8} {:>9} {:>10}",
            m.vertex_count(),
            m.triangles().len()
        )?;
    }
    if let Some(path) = svg {
        let text = draw(&panels, agents);
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
        outln!("wrote {}", path.display())?;
    }
    Ok(())
}

fn draw(panels: &[(String, TriMesh, Vec<Vec2>)], agents: usize) -> String {
    let rows = panels.len().div_ceil(PER_ROW);
    let (w, h) = (
        PER_ROW as f64 * PANEL_M * PX_PER_M,
        rows as f64 * PANEL_M * PX_PER_M,
    );
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="sans-serif" font-size="14"><rect width="100%" height="100%" fill="#ffffff"/>"##
    );
    for (k, (name, mesh, outline)) in panels.iter().enumerate() {
        let (ox, oy) = (
            (k % PER_ROW) as f64 * PANEL_M * PX_PER_M,
            (k / PER_ROW) as f64 * PANEL_M * PX_PER_M,
        );
        // World y up, picture y down.
        let px = |p: &Vec2| (ox + p.x * PX_PER_M, oy + (PANEL_M - p.y) * PX_PER_M);
        let _ = writeln!(
            s,
            r##"<rect x="{ox:.1}" y="{oy:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#dddddd"/>"##,
            PANEL_M * PX_PER_M,
            PANEL_M * PX_PER_M
        );
        let v = mesh.rest();
        for t in mesh.triangles() {
            let [a, b, c] = t.map(|i| px(&v[i as usize]));
            let _ = writeln!(
                s,
                r##"<path d="M{:.1},{:.1}L{:.1},{:.1}L{:.1},{:.1}Z" fill="#dbe8f7" stroke="#6f9fd8" stroke-width="0.8"/>"##,
                a.0, a.1, b.0, b.1, c.0, c.1
            );
        }
        if !outline.is_empty() {
            let d: String = outline
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let (x, y) = px(p);
                    format!("{}{x:.1},{y:.1}", if i == 0 { 'M' } else { 'L' })
                })
                .collect();
            let _ = writeln!(
                s,
                r##"<path d="{d}Z" fill="none" stroke="#1f4e8c" stroke-width="2"/>"##
            );
        }
        let samples = sample_goals(mesh, agents);
        let mut goals = Vec::new();
        goal_positions(mesh, &samples, v, &mut goals);
        for g in &goals {
            let (x, y) = px(g);
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="2.2" fill="#c0392b"/>"##
            );
        }
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-weight="bold">{name}</text><text x="{:.1}" y="{:.1}" fill="#555555">{} vertices, {} goals, heading →</text>"##,
            ox + 8.0,
            oy + 20.0,
            ox + 8.0,
            oy + 38.0,
            mesh.vertex_count(),
            goals.len()
        );
    }
    s.push_str("</svg>\n");
    s
}
