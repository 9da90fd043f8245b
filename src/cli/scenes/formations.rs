//! `crowdtouch formations`: the formation shapes a config defines (shipped ones
//! from `config/formations/` and the config's `formations.shapes`), as a list or a
//! picture: outlines, holes, pieces, the mesh a switch builds and the target points
//! sampled for the config's agents (formation-transform section 3.1).

use crate::cli::common::output::outln;
use anyhow::{Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::formation::{Piece, Placement, SampleParams, START};
use crowdtouch::crowd::mesh::TriMesh;
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::picture::{elements, style, Canvas, Frame, Paint};
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
    let side_px = PANEL_M * PX_PER_M;
    let mut c = Canvas::new(PER_ROW as f64 * side_px, rows as f64 * side_px);
    let mesh = Paint::fill_stroke(style::MESH_FILL, style::MESH_STROKE, 0.8).class("mesh");
    let target = Paint::fill(style::TARGET).class("target");
    for (k, p) in panels.iter().enumerate() {
        let f = Frame {
            world: Rect {
                min: [0.0, 0.0],
                max: [PANEL_M, PANEL_M],
            },
            px_per_m: PX_PER_M,
            left_px: (k % PER_ROW) as f64 * side_px,
            top_px: (k / PER_ROW) as f64 * side_px,
            y_up: true,
        };
        let (ox, oy) = (f.left_px, f.top_px);
        c.rect(
            ox,
            oy,
            side_px,
            side_px,
            &Paint::stroke(style::PANEL_EDGE, style::LINE_PX),
        );
        elements::mesh(&mut c, &f, p.mesh.rest(), p.mesh.triangles(), &mesh);
        // Outlines solid, holes dashed.
        for piece in &p.pieces {
            let outline = Paint::stroke(style::OUTLINE, style::BOLD_PX).class("outline");
            elements::hull(&mut c, &f, &piece.outline, &outline);
            let hole = outline.dash("6 3").class("hole");
            for h in &piece.holes {
                elements::hull(&mut c, &f, h, &hole);
            }
        }
        let (count, note) = match &p.targets {
            Ok(t) => {
                elements::agents(&mut c, &f, t, 2.2, &target);
                (t.len(), String::new())
            }
            Err(e) => (0, format!(" ({e})")),
        };
        c.text(
            (ox + 8.0, oy + 20.0),
            style::TITLE_PX,
            style::INK,
            r#"font-weight="bold""#,
            &p.name,
        );
        c.caption(
            (ox + 8.0, oy + 38.0),
            &format!(
                "{} vertices, {count} targets, heading →{note}",
                p.mesh.vertex_count()
            ),
        );
    }
    c.finish()
}
