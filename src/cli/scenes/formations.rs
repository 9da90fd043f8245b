//! `crowdtouch formations`: the formation shapes a config defines (shipped ones
//! from `config/formations/` and the config's `formations.shapes`), as a list or a
//! picture: outlines, holes, pieces, the mesh a switch builds and the target points
//! sampled for the config's agents (formation-transform section 3.1).

use crate::cli::common::output::outln;
use anyhow::{Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::formation::{Piece, Placement, SampleParams, START};
use crowdtouch::crowd::mesh::TriMesh;
use crowdtouch::geom::Vec2;
use std::fmt::Write as _;
use std::path::Path;

/// Pixels per metre in the picture.
const PX_PER_M: f64 = 40.0;
/// Width and height of one formation's panel (m).
const PANEL_M: f64 = 8.0;
/// Panels per row.
const PER_ROW: usize = 4;

/// Seed of the sampled target points drawn.
const SEED: u64 = 16;

/// One formation as drawn.
struct Panel {
    name: String,
    mesh: TriMesh,
    pieces: Vec<Piece>,
    /// The sampled target points, or why there are none.
    targets: Result<Vec<Vec2>, String>,
}

/// Lists the formations of `cfg` (and draws them into `svg` when given): each
/// meshed as a switch would lay it out for the config's crowd, at the area of
/// `crowd.formation` (a bitmap with a size of its own at that size), heading `+x`,
/// with as many vertices as the start mesh, and sampled with one target point per
/// agent at two agent radii apart.
pub fn formations(cfg: &Config, svg: Option<&Path>) -> Result<()> {
    let rect = cfg.crowd.formation;
    let area = rect.width() * rect.height();
    let vertices = (cfg.mesh.cols * cfg.mesh.rows) as usize;
    let agents = cfg.crowd.agents as usize;
    let params = SampleParams {
        min_spacing_m: 2.0 * cfg.crowd.agent_radius_m,
        ..SampleParams::default()
    };
    let lib = cfg.formation_library();
    let mut panels: Vec<Panel> = Vec::new();
    let centre = Vec2::new(0.5 * PANEL_M, 0.5 * PANEL_M);
    let mut start = TriMesh::grid(rect, cfg.mesh.cols as usize, cfg.mesh.rows as usize);
    start.translate(centre - rect.center());
    panels.push(Panel {
        name: START.to_string(),
        mesh: start,
        pieces: Vec::new(),
        targets: Err("the start grid".into()),
    });
    for name in lib.names() {
        let f = lib.get(name).context("formation listed but not found")?;
        let place = Placement {
            centre_m: centre,
            heading: Vec2::new(1.0, 0.0),
            area_m2: area,
        };
        let mesh = f
            .mesh(&place, vertices)
            .with_context(|| format!("formation `{name}` cannot be meshed"))?;
        let targets = match f.sample(&place, agents, &params, SEED, &|| false) {
            Ok(Some(t)) => Ok(t),
            Ok(None) => Err("cancelled".into()),
            Err(e) => Err(e.to_string()),
        };
        panels.push(Panel {
            name: name.to_string(),
            mesh,
            pieces: f.placed_pieces(&place),
            targets,
        });
    }
    outln!(
        "{:<12} {:>6} {:>6} {:>8} {:>9} {:>10} {:>8}   (at {area:.1} m², {vertices} mesh vertices asked, {agents} agents {:.2} m apart)",
        "formation", "pieces", "holes", "outline", "vertices", "triangles", "targets", params.min_spacing_m
    )?;
    for p in &panels {
        let (pieces, holes, outline) = if p.name == START {
            ("-".to_string(), "-".to_string(), "grid".to_string())
        } else {
            (
                p.pieces.len().to_string(),
                p.pieces
                    .iter()
                    .map(|k| k.holes.len())
                    .sum::<usize>()
                    .to_string(),
                p.pieces
                    .iter()
                    .map(|k| k.outline.len() + k.holes.iter().map(Vec::len).sum::<usize>())
                    .sum::<usize>()
                    .to_string(),
            )
        };
        let targets = match &p.targets {
            Ok(t) => t.len().to_string(),
            Err(_) if p.name == START => "-".to_string(),
            Err(e) => format!("none: {e}"),
        };
        outln!(
            "{:<12} {pieces:>6} {holes:>6} {outline:>8} {:>9} {:>10} {targets:>8}",
            p.name,
            p.mesh.vertex_count(),
            p.mesh.triangles().len()
        )?;
    }
    if let Some(path) = svg {
        let text = draw(&panels);
        std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))?;
        outln!("wrote {}", path.display())?;
    }
    Ok(())
}

fn draw(panels: &[Panel]) -> String {
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
    for (k, p) in panels.iter().enumerate() {
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
        let v = p.mesh.rest();
        for t in p.mesh.triangles() {
            let [a, b, c] = t.map(|i| px(&v[i as usize]));
            let _ = writeln!(
                s,
                r##"<path d="M{:.1},{:.1}L{:.1},{:.1}L{:.1},{:.1}Z" fill="#dbe8f7" stroke="#6f9fd8" stroke-width="0.8"/>"##,
                a.0, a.1, b.0, b.1, c.0, c.1
            );
        }
        // Outlines solid, holes dashed.
        for piece in &p.pieces {
            for (ring, dash) in std::iter::once((&piece.outline, "")).chain(
                piece
                    .holes
                    .iter()
                    .map(|h| (h, r##" stroke-dasharray="6 3""##)),
            ) {
                let d: String = ring
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let (x, y) = px(q);
                        format!("{}{x:.1},{y:.1}", if i == 0 { 'M' } else { 'L' })
                    })
                    .collect();
                let _ = writeln!(
                    s,
                    r##"<path d="{d}Z" fill="none" stroke="#1f4e8c" stroke-width="2"{dash}/>"##
                );
            }
        }
        let (count, note) = match &p.targets {
            Ok(t) => {
                for g in t {
                    let (x, y) = px(g);
                    let _ = writeln!(
                        s,
                        r##"<circle cx="{x:.1}" cy="{y:.1}" r="2.2" fill="#c0392b"/>"##
                    );
                }
                (t.len(), String::new())
            }
            Err(e) => (0, format!(" ({e})")),
        };
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-weight="bold">{}</text><text x="{:.1}" y="{:.1}" fill="#555555">{} vertices, {count} targets, heading →{}</text>"##,
            ox + 8.0,
            oy + 20.0,
            p.name,
            ox + 8.0,
            oy + 38.0,
            p.mesh.vertex_count(),
            xml_escape(&note)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
