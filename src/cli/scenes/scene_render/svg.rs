//! The SVG document: title, heat map, contours, bounds, patches, obstacles, moving
//! things, checkpoints, routes, agents and the goal.

use super::colours::{
    motion_colour, motion_label, BLOCKED_FILL, CHECKPOINT_STROKE, MOVING_FILL, OBSTACLE_FILL,
    ROUTE_STROKE, UNREACHABLE_FILL,
};
use super::contours::iso_segments;
use super::heatmap::{Heat, HEAT_LEVELS};
use super::picture::{Options, Picture};
use super::routes::{simplify, ROUTE_TOLERANCE_PX};
use super::view::{part, FOOTER_PX, MAP_H_PX, MAP_W_PX, MARGIN_PX, PANEL_PX, TITLE_PX};
use crowdtouch::crowd::environment::eikonal::sample;
use crowdtouch::crowd::environment::{DynamicKind, PathMode, Placement, Scene};
use crowdtouch::picture::scale::{heat, nice_step};
use crowdtouch::picture::text::{num, px};
use crowdtouch::picture::{elements, style, Canvas, Frame, Paint, PathData};

/// What [`Picture::heat_blocks`] gives: the block factor, blocks across and down,
/// each block's class and `Φ` at the block centres.
type HeatBlocks = (usize, usize, usize, Vec<Heat>, Vec<f64>);

impl Picture {
    /// The SVG document.
    pub fn svg(&self, scene: &Scene, o: &Options) -> String {
        let b = scene.bounds();
        let f = Frame {
            world: b,
            px_per_m: (MAP_W_PX / b.width()).min(MAP_H_PX / b.height()),
            left_px: MARGIN_PX,
            top_px: TITLE_PX,
            y_up: false,
        };
        let width = MARGIN_PX + f.width_px() + MARGIN_PX + PANEL_PX;
        let height = (TITLE_PX + f.height_px() + FOOTER_PX).max(TITLE_PX + 560.0);
        let step = nice_step(self.phi_max, 8);
        let vmax = (self.phi_max / step).ceil().max(1.0) * step;
        let mut c = Canvas::new(width, height);
        c.raw(&format!(
            r##"<defs><pattern id="unreachable" width="6" height="6" patternUnits="userSpaceOnUse"><rect width="6" height="6" fill="{UNREACHABLE_FILL}"/><path d="M0,6 L6,0" stroke="#8a7fa8" stroke-width="0.8"/></pattern><clipPath id="world"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"##,
            px(f.left_px),
            px(f.top_px),
            px(f.width_px()),
            px(f.height_px())
        ));
        let (gx, gy) = (self.goal.x, self.goal.y);
        c.title(
            (MARGIN_PX, 19.0),
            &format!(
                "{}: grid {} × {} cells of {} m, goal ({gx:.2}, {gy:.2}), t = {} s, {} agents",
                scene.name(),
                self.grid.cols(),
                self.grid.rows(),
                num(self.grid.cell_m()),
                num(o.t_s),
                self.agents.len()
            ),
        );
        c.caption(
            (MARGIN_PX, 37.0),
            &format!(
                "Φ: fast-marching travel time to the goal at {} m/s (eq. 7 with travel-speed patches); routes descend Φ",
                num(o.preferred_speed_m_s)
            ),
        );
        let blocks = self.heat_blocks(f.world, vmax);
        self.heat_map(&mut c, &f, &blocks);
        self.contours(&mut c, &f, &blocks, step, vmax);
        c.rect(
            f.left_px,
            f.top_px,
            f.width_px(),
            f.height_px(),
            &Paint::stroke(style::INK, 1.5).class("bounds"),
        );
        draw_scene(&mut c, &f, scene, o.t_s);
        self.routes_and_agents(&mut c, &f);
        elements::scale_bar(&mut c, &f, (f.left_px, f.top_px + f.height_px() + 18.0));
        self.legend(&mut c, scene, &f, o, step, vmax);
        c.finish()
    }

    /// Heat map: runs of equal blocks along rows, one path per colour.
    fn heat_map(&self, c: &mut Canvas, f: &Frame, heat_blocks: &HeatBlocks) {
        let b = f.world;
        let (factor, nx, ny, blocks, _) = heat_blocks;
        let (factor, nx, ny) = (*factor, *nx, *ny);
        let mut by_fill: std::collections::BTreeMap<String, PathData> = Default::default();
        for bj in 0..ny {
            let mut bi = 0;
            while bi < nx {
                let h = blocks[bj * nx + bi];
                let mut end = bi + 1;
                while end < nx && blocks[bj * nx + end] == h {
                    end += 1;
                }
                let r0 = self.block_rect(b, factor, bi, bj);
                let r1 = self.block_rect(b, factor, end - 1, bj);
                let fill = match h {
                    Heat::Blocked => BLOCKED_FILL.to_string(),
                    Heat::Unreachable => "url(#unreachable)".to_string(),
                    Heat::Level(l) => heat((l as f64 + 0.5) / HEAT_LEVELS as f64),
                };
                let (x0, x1) = (f.x(r0.min[0]), f.x(r1.max[0]));
                let (y0, y1) = (f.y(r0.min[1]), f.y(r0.max[1]));
                if x1 > x0 && y1 > y0 {
                    by_fill
                        .entry(fill)
                        .or_default()
                        .rect(x0, y0, x1 - x0, y1 - y0);
                }
                bi = end;
            }
        }
        c.open_group(r#"class="heatmap" shape-rendering="crispEdges""#);
        for (fill, d) in &by_fill {
            c.path(d, &Paint::fill(fill).class("heat"));
        }
        c.close_group();
    }

    /// Iso-time contours every `step` seconds on the block-centre lattice.
    fn contours(&self, c: &mut Canvas, f: &Frame, heat_blocks: &HeatBlocks, step: f64, vmax: f64) {
        let b = f.world;
        let (factor, nx, ny, _, vals) = heat_blocks;
        let (factor, nx, ny) = (*factor, *nx, *ny);
        c.open_group(r#"class="contours" clip-path="url(#world)""#);
        let paint = Paint::stroke("#5a1a00", style::HAIRLINE_PX)
            .stroke_opacity(0.45)
            .class("contour");
        let levels = (vmax / step).round() as usize;
        for k in 1..levels {
            let level = k as f64 * step;
            let segs = iso_segments(vals, nx, ny, level);
            if segs.is_empty() {
                continue;
            }
            let origin = self.block_centre(b, factor, 0, 0);
            let sz = self.grid.cell_m() * factor as f64;
            let to_px = |(i, j): (f64, f64)| (f.x(origin.x + i * sz), f.y(origin.y + j * sz));
            let mut d = PathData::new();
            for [p, q] in segs {
                d.move_to(to_px(p)).line_to(to_px(q));
            }
            c.path(&d, &paint);
        }
        c.close_group();
    }

    /// Each agent's route (dashed where it does not reach the goal), the agents
    /// (red where the goal is out of reach) and the goal, a ringed cross.
    fn routes_and_agents(&self, c: &mut Canvas, f: &Frame) {
        let tol_m = ROUTE_TOLERANCE_PX / f.px_per_m;
        c.open_group(r#"class="routes" stroke-linejoin="round""#);
        for r in &self.routes {
            let paint = Paint::stroke(ROUTE_STROKE, 1.1)
                .stroke_opacity(0.75)
                .dash(if r.reached { "" } else { "3 2" })
                .class("route");
            elements::track(c, f, &simplify(&r.points, tol_m), &paint);
        }
        c.close_group();
        for &a in &self.agents {
            let reachable = sample(&self.grid, &self.phi, a).is_finite();
            let fill = if reachable { style::PLOT } else { style::ALERT };
            c.circle(
                f.pt(a),
                2.6,
                &Paint::fill_stroke(fill, ROUTE_STROKE, 1.0).class("agent"),
            );
        }
        let (gx, gy) = f.pt(self.goal);
        c.open_group(r#"class="goal""#);
        c.circle(
            (gx, gy),
            7.0,
            &Paint::fill_stroke(style::PLOT, "#000000", 2.0).fill_opacity(0.7),
        );
        let mut cross = PathData::new();
        cross
            .move_to((gx - 11.0, gy))
            .line_to((gx + 11.0, gy))
            .move_to((gx, gy - 11.0))
            .line_to((gx, gy + 11.0));
        c.path(&cross, &Paint::stroke("#000000", 2.0));
        c.close_group();
    }
}

/// The scene at `t_s`: static patches, static obstacles, moving things (their
/// paths dashed) and checkpoints with their formation names, each in a group with
/// its name as a tooltip.
fn draw_scene(c: &mut Canvas, f: &Frame, scene: &Scene, t_s: f64) {
    // Static patches, then moving patches, in file order (the last one wins).
    for p in scene.patches() {
        let m = motion_colour(p.terrain.motion);
        c.open_group("");
        c.tooltip(&format!(
            "{} ({} ×{})",
            p.name,
            motion_label(p.terrain.motion),
            num(p.terrain.speed_factor)
        ));
        let paint = Paint::fill_stroke(m, m, 1.5)
            .fill_opacity(0.22)
            .class("patch");
        for pa in &p.parts {
            part(c, f, pa, &Placement::IDENTITY, &paint);
        }
        c.close_group();
    }
    for ob in scene.obstacles() {
        c.open_group("");
        c.tooltip(&ob.name);
        let paint = Paint::fill_stroke(OBSTACLE_FILL, "#1a1a1a", 1.0).class("obstacle");
        for pa in &ob.parts {
            part(c, f, pa, &Placement::IDENTITY, &paint);
        }
        c.close_group();
    }
    for d in scene.dynamic() {
        // A ping-pong traversal retraces its way back: draw the way out only.
        let all = d.path.points();
        let shown = match d.path.mode() {
            PathMode::PingPong => &all[..all.len().div_ceil(2)],
            PathMode::Looped => all,
        };
        let (colour, paint) = match d.kind {
            DynamicKind::Obstacle => (
                MOVING_FILL,
                Paint::fill_stroke(MOVING_FILL, "#1a1a1a", 1.0)
                    .fill_opacity(0.9)
                    .class("moving-obstacle"),
            ),
            DynamicKind::Patch(t) => {
                let m = motion_colour(t.motion);
                (
                    m,
                    Paint::fill_stroke(m, m, 1.5)
                        .fill_opacity(0.3)
                        .class("moving-patch"),
                )
            }
        };
        c.open_group("");
        c.tooltip(&format!("{} at t = {} s", d.name, num(t_s)));
        elements::track(
            c,
            f,
            shown,
            &Paint::stroke(colour, 1.3).dash("6 4").class("path"),
        );
        let pl = d.placement_at(t_s);
        for pa in &d.parts {
            part(c, f, pa, &pl, &paint);
        }
        c.close_group();
    }
    for cp in scene.checkpoints() {
        c.open_group("");
        c.tooltip(&format!(
            "checkpoint {}: formation {}",
            cp.name, cp.formation
        ));
        let paint = Paint::stroke(CHECKPOINT_STROKE, 2.0)
            .dash("2 2")
            .class("checkpoint");
        part(c, f, &cp.region, &Placement::IDENTITY, &paint);
        let (x, y) = f.pt(cp.region.centre());
        c.text(
            (x, y + 4.0),
            style::SMALL_PX,
            CHECKPOINT_STROKE,
            r##"class="formation" font-weight="bold" text-anchor="middle" stroke="#fbfbf8" stroke-width="3" paint-order="stroke""##,
            &cp.formation,
        );
        c.close_group();
    }
}
