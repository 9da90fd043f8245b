//! The SVG document: title, heat map, contours, bounds, patches, obstacles, moving
//! things, checkpoints, routes, agents and the goal.

use super::colours::{
    motion_colour, motion_label, ramp, BLOCKED_FILL, CHECKPOINT_STROKE, MOVING_FILL, OBSTACLE_FILL,
    ROUTE_STROKE, UNREACHABLE_FILL,
};
use super::contours::{iso_segments, nice_step};
use super::heatmap::{Heat, HEAT_LEVELS};
use super::picture::{Options, Picture};
use super::routes::{simplify, ROUTE_TOLERANCE_PX};
use super::text::{f1, num, xml_escape};
use super::view::{part_svg, View, FOOTER_PX, MAP_H_PX, MAP_W_PX, MARGIN_PX, PANEL_PX, TITLE_PX};
use crowdtouch::crowd::environment::eikonal::sample;
use crowdtouch::crowd::environment::{DynamicKind, PathMode, Placement, Scene};
use std::fmt::Write;

impl Picture {
    /// The SVG document.
    pub fn svg(&self, scene: &Scene, o: &Options) -> String {
        let b = scene.bounds();
        let px_per_m = (MAP_W_PX / b.width()).min(MAP_H_PX / b.height());
        let v = View {
            bounds: b,
            px_per_m,
            x0: MARGIN_PX,
            y0: TITLE_PX,
        };
        let width = MARGIN_PX + v.w() + MARGIN_PX + PANEL_PX;
        let height = (TITLE_PX + v.h() + FOOTER_PX).max(TITLE_PX + 560.0);
        let step = nice_step(self.phi_max, 8);
        let vmax = (self.phi_max / step).ceil().max(1.0) * step;
        let mut s = String::with_capacity(1 << 17);
        let _ = writeln!(
            s,
            r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width:.0} {height:.0}" width="{width:.0}" height="{height:.0}" font-family="sans-serif">"##
        );
        let _ = writeln!(
            s,
            r##"<defs><pattern id="unreachable" width="6" height="6" patternUnits="userSpaceOnUse"><rect width="6" height="6" fill="{UNREACHABLE_FILL}"/><path d="M0,6 L6,0" stroke="#8a7fa8" stroke-width="0.8"/></pattern><clipPath id="world"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath></defs>"##,
            v.x0,
            v.y0,
            v.w(),
            v.h()
        );
        let _ = writeln!(
            s,
            r##"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="#fbfbf8"/>"##
        );
        // Title.
        let (gx, gy) = (self.goal.x, self.goal.y);
        let _ = writeln!(
            s,
            r##"<text class="title" x="{MARGIN_PX:.0}" y="19" font-size="15" fill="#222">{}: grid {} × {} cells of {} m, goal ({:.2}, {:.2}), t = {} s, {} agents</text>"##,
            xml_escape(scene.name()),
            self.grid.cols(),
            self.grid.rows(),
            num(self.grid.cell_m()),
            gx,
            gy,
            num(o.t_s),
            self.agents.len()
        );
        let _ = writeln!(
            s,
            r##"<text x="{MARGIN_PX:.0}" y="37" font-size="11.5" fill="#555">Φ: fast-marching travel time to the goal at {} m/s (eq. 7 with travel-speed patches); routes descend Φ</text>"##,
            num(o.preferred_speed_m_s)
        );

        // Heat map: runs of equal blocks along rows, one path per colour.
        let (f, nx, ny, heat, vals) = self.heat_blocks(b, vmax);
        let mut by_fill: std::collections::BTreeMap<String, String> = Default::default();
        for bj in 0..ny {
            let mut bi = 0;
            while bi < nx {
                let h = heat[bj * nx + bi];
                let mut end = bi + 1;
                while end < nx && heat[bj * nx + end] == h {
                    end += 1;
                }
                let r0 = self.block_rect(b, f, bi, bj);
                let r1 = self.block_rect(b, f, end - 1, bj);
                let fill = match h {
                    Heat::Blocked => BLOCKED_FILL.to_string(),
                    Heat::Unreachable => "url(#unreachable)".to_string(),
                    Heat::Level(l) => ramp((l as f64 + 0.5) / HEAT_LEVELS as f64),
                };
                let (x0, x1) = (v.x(r0.min[0]), v.x(r1.max[0]));
                let (y0, y1) = (v.y(r0.min[1]), v.y(r0.max[1]));
                if x1 > x0 && y1 > y0 {
                    let d = by_fill.entry(fill).or_default();
                    let _ = write!(
                        d,
                        "M{} {}h{}v{}h-{}z",
                        f1(x0),
                        f1(y0),
                        f1(x1 - x0),
                        f1(y1 - y0),
                        f1(x1 - x0)
                    );
                }
                bi = end;
            }
        }
        s.push_str(r#"<g class="heatmap" shape-rendering="crispEdges">"#);
        s.push('\n');
        for (fill, d) in &by_fill {
            let _ = writeln!(s, r#"<path class="heat" fill="{fill}" d="{d}"/>"#);
        }
        s.push_str("</g>\n");

        // Iso-time contours on the block-centre lattice.
        s.push_str(r##"<g class="contours" fill="none" stroke="#5a1a00" stroke-opacity="0.45" stroke-width="0.7" clip-path="url(#world)">"##);
        s.push('\n');
        let levels = (vmax / step).round() as usize;
        for k in 1..levels {
            let level = k as f64 * step;
            let segs = iso_segments(&vals, nx, ny, level);
            if segs.is_empty() {
                continue;
            }
            let to_px = |(i, j): (f64, f64)| {
                let c = self.block_centre(b, f, 0, 0);
                let sz = self.grid.cell_m() * f as f64;
                (v.x(c.x + i * sz), v.y(c.y + j * sz))
            };
            let mut d = String::new();
            for [p, q] in segs {
                let (p, q) = (to_px(p), to_px(q));
                let _ = write!(d, "M{:.1},{:.1}L{:.1},{:.1}", p.0, p.1, q.0, q.1);
            }
            let _ = writeln!(
                s,
                r#"<path class="contour" data-s="{}" d="{d}"/>"#,
                num(level)
            );
        }
        s.push_str("</g>\n");

        // Bounds.
        let _ = writeln!(
            s,
            r##"<rect class="bounds" x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#222" stroke-width="1.5"/>"##,
            v.x0,
            v.y0,
            v.w(),
            v.h()
        );

        // Static patches, then moving patches, in file order (the last one wins).
        for p in scene.patches() {
            let c = motion_colour(p.terrain.motion);
            let _ = writeln!(
                s,
                "<g><title>{} ({} ×{})</title>",
                xml_escape(&p.name),
                motion_label(p.terrain.motion),
                num(p.terrain.speed_factor)
            );
            for part in &p.parts {
                part_svg(
                    &mut s,
                    &v,
                    part,
                    &Placement::IDENTITY,
                    "patch",
                    &format!(r#"fill="{c}" fill-opacity="0.22" stroke="{c}" stroke-width="1.5""#),
                );
            }
            s.push_str("</g>\n");
        }

        // Static obstacles.
        for ob in scene.obstacles() {
            let _ = writeln!(s, "<g><title>{}</title>", xml_escape(&ob.name));
            for part in &ob.parts {
                part_svg(
                    &mut s,
                    &v,
                    part,
                    &Placement::IDENTITY,
                    "obstacle",
                    &format!(r##"fill="{OBSTACLE_FILL}" stroke="#1a1a1a" stroke-width="1""##),
                );
            }
            s.push_str("</g>\n");
        }

        // Moving things: the path dashed, the parts where they are at t.
        for d in scene.dynamic() {
            // A ping-pong traversal retraces its way back: draw the way out only.
            let all = d.path.points();
            let shown = match d.path.mode() {
                PathMode::PingPong => &all[..all.len().div_ceil(2)],
                PathMode::Looped => all,
            };
            let pts: Vec<String> = shown.iter().map(|&p| v.pt(p)).collect();
            let (class, fill, attrs) = match d.kind {
                DynamicKind::Obstacle => (
                    "moving-obstacle",
                    MOVING_FILL,
                    format!(
                        r##"fill="{MOVING_FILL}" fill-opacity="0.9" stroke="#1a1a1a" stroke-width="1""##
                    ),
                ),
                DynamicKind::Patch(t) => {
                    let c = motion_colour(t.motion);
                    (
                        "moving-patch",
                        c,
                        format!(r#"fill="{c}" fill-opacity="0.3" stroke="{c}" stroke-width="1.5""#),
                    )
                }
            };
            let _ = writeln!(
                s,
                "<g><title>{} at t = {} s</title>",
                xml_escape(&d.name),
                num(o.t_s)
            );
            let _ = writeln!(
                s,
                r#"<polyline class="path" points="{}" fill="none" stroke="{fill}" stroke-width="1.3" stroke-dasharray="6 4"/>"#,
                pts.join(" ")
            );
            let pl = d.placement_at(o.t_s);
            for part in &d.parts {
                part_svg(&mut s, &v, part, &pl, class, &attrs);
            }
            s.push_str("</g>\n");
        }

        // Checkpoints, outlined, with their formation names.
        for c in scene.checkpoints() {
            let _ = writeln!(
                s,
                "<g><title>checkpoint {}: formation {}</title>",
                xml_escape(&c.name),
                xml_escape(&c.formation)
            );
            part_svg(
                &mut s,
                &v,
                &c.region,
                &Placement::IDENTITY,
                "checkpoint",
                &format!(
                    r#"fill="none" stroke="{CHECKPOINT_STROKE}" stroke-width="2" stroke-dasharray="2 2""#
                ),
            );
            let p = c.region.centre();
            let _ = writeln!(
                s,
                r##"<text class="formation" x="{:.1}" y="{:.1}" font-size="12" font-weight="bold" text-anchor="middle" fill="{CHECKPOINT_STROKE}" stroke="#fbfbf8" stroke-width="3" paint-order="stroke">{}</text>"##,
                v.x(p.x),
                v.y(p.y) + 4.0,
                xml_escape(&c.formation)
            );
            s.push_str("</g>\n");
        }

        // Routes and agents.
        let tol_m = ROUTE_TOLERANCE_PX / px_per_m;
        s.push_str(&format!(
            r#"<g fill="none" stroke="{ROUTE_STROKE}" stroke-width="1.1" stroke-opacity="0.75" stroke-linejoin="round">"#
        ));
        s.push('\n');
        for r in &self.routes {
            let pts: Vec<String> = simplify(&r.points, tol_m)
                .into_iter()
                .map(|p| v.pt(p))
                .collect();
            let extra = if r.reached {
                ""
            } else {
                r#" stroke-dasharray="3 2""#
            };
            let _ = writeln!(
                s,
                r#"<polyline class="route" points="{}"{extra}/>"#,
                pts.join(" ")
            );
        }
        s.push_str("</g>\n");
        for &a in &self.agents {
            let reachable = sample(&self.grid, &self.phi, a).is_finite();
            let fill = if reachable { "#ffffff" } else { "#d33" };
            let _ = writeln!(
                s,
                r#"<circle class="agent" cx="{:.1}" cy="{:.1}" r="2.6" fill="{fill}" stroke="{ROUTE_STROKE}" stroke-width="1"/>"#,
                v.x(a.x),
                v.y(a.y)
            );
        }
        // Goal: a ringed cross.
        let (gx, gy) = (v.x(self.goal.x), v.y(self.goal.y));
        let _ = writeln!(
            s,
            r##"<g class="goal" stroke="#000" stroke-width="2" fill="none"><circle cx="{gx:.1}" cy="{gy:.1}" r="7" fill="#ffffff" fill-opacity="0.7"/><path d="M{:.1},{gy:.1}H{:.1}M{gx:.1},{:.1}V{:.1}"/></g>"##,
            gx - 11.0,
            gx + 11.0,
            gy - 11.0,
            gy + 11.0
        );

        self.scale_bar(&mut s, &v);
        self.legend(&mut s, scene, &v, o, step, vmax);
        s.push_str("</svg>\n");
        s
    }
}
