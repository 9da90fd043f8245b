//! The scale bar under the map and the legend beside it: motion types, symbols
//! and the colour scale of `Φ`.

use super::colours::{
    motion_colour, motion_label, ramp, BLOCKED_FILL, CHECKPOINT_STROKE, MOVING_FILL, OBSTACLE_FILL,
    ROUTE_STROKE,
};
use super::contours::nice_step;
use super::heatmap::HEAT_LEVELS;
use super::picture::{Options, Picture};
use super::text::{num, xml_escape};
use super::view::{View, MARGIN_PX};
use crowdtouch::crowd::environment::{DynamicKind, Scene};
use crowdtouch::vocab::MotionType;
use std::fmt::Write;

impl Picture {
    pub(super) fn scale_bar(&self, s: &mut String, v: &View) {
        let len_m = nice_step(v.bounds.width() / 4.0, 1);
        let units = [len_m / 2.0, len_m / 2.0];
        let (x, y) = (v.x0, v.y0 + v.h() + 18.0);
        let _ = writeln!(s, r##"<g class="scale-bar" font-size="11" fill="#222">"##);
        let mut at = x;
        for (k, u) in units.iter().enumerate() {
            let w = u * v.px_per_m;
            let fill = if k % 2 == 0 { "#222" } else { "#fbfbf8" };
            let _ = writeln!(
                s,
                r##"<rect x="{at:.1}" y="{y:.1}" width="{w:.1}" height="6" fill="{fill}" stroke="#222" stroke-width="1"/>"##
            );
            at += w;
        }
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}">0</text><text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text x="{at:.1}" y="{:.1}" text-anchor="end">{} m</text>"#,
            y + 19.0,
            x + units[0] * v.px_per_m,
            y + 19.0,
            num(len_m / 2.0),
            y + 19.0,
            num(len_m)
        );
        s.push_str("</g>\n");
    }

    pub(super) fn legend(
        &self,
        s: &mut String,
        scene: &Scene,
        v: &View,
        o: &Options,
        step: f64,
        vmax: f64,
    ) {
        let x = v.x0 + v.w() + MARGIN_PX + 6.0;
        let mut y = v.y0 + 4.0;
        let _ = writeln!(s, r##"<g class="legend" font-size="11.5" fill="#222">"##);
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" font-weight="bold">Travel speed × running</text>"#,
            y + 8.0
        );
        y += 16.0;
        for m in MotionType::ALL {
            let c = motion_colour(m);
            let mut factors: Vec<f64> = scene
                .patches()
                .iter()
                .map(|p| p.terrain)
                .chain(scene.dynamic().iter().filter_map(|d| match d.kind {
                    DynamicKind::Patch(t) => Some(t),
                    DynamicKind::Obstacle => None,
                }))
                .filter(|t| t.motion == m && t.speed_factor != m.default_speed_factor())
                .map(|t| t.speed_factor)
                .collect();
            factors.sort_by(f64::total_cmp);
            factors.dedup();
            let mut label = format!("{} ×{:.2}", motion_label(m), m.default_speed_factor());
            if !factors.is_empty() {
                let f: Vec<String> = factors.iter().map(|f| format!("×{}", num(*f))).collect();
                let _ = write!(label, " (here {})", f.join(", "));
            }
            let _ = writeln!(
                s,
                r#"<rect class="legend-motion" x="{x:.1}" y="{y:.1}" width="16" height="11" fill="{c}" fill-opacity="0.22" stroke="{c}" stroke-width="1.5"/><text x="{:.1}" y="{:.1}">{}</text>"#,
                x + 22.0,
                y + 9.5,
                xml_escape(&label)
            );
            y += 16.0;
        }
        y += 10.0;
        let swatch = |s: &mut String, y: f64, attrs: &str, label: &str| {
            let _ = writeln!(
                s,
                r#"<rect x="{x:.1}" y="{y:.1}" width="16" height="11" {attrs}/><text x="{:.1}" y="{:.1}">{label}</text>"#,
                x + 22.0,
                y + 9.5
            );
        };
        swatch(
            s,
            y,
            &format!(r##"fill="{OBSTACLE_FILL}" stroke="#1a1a1a""##),
            "obstacle",
        );
        y += 16.0;
        swatch(
            s,
            y,
            &format!(r##"fill="{MOVING_FILL}" stroke="#1a1a1a""##),
            &format!("moving, at t = {} s (path dashed)", num(o.t_s)),
        );
        y += 16.0;
        swatch(
            s,
            y,
            &format!(
                r#"fill="none" stroke="{CHECKPOINT_STROKE}" stroke-width="2" stroke-dasharray="2 2""#
            ),
            "checkpoint: formation",
        );
        y += 16.0;
        swatch(s, y, &format!(r#"fill="{BLOCKED_FILL}""#), "blocked cell");
        y += 16.0;
        swatch(
            s,
            y,
            r##"fill="url(#unreachable)" stroke="#8a7fa8" stroke-width="0.5""##,
            "unreachable cell",
        );
        y += 16.0;
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="2.6" fill="#ffffff" stroke="{ROUTE_STROKE}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{ROUTE_STROKE}" stroke-width="1.1"/><text x="{:.1}" y="{:.1}">agent and its route</text>"##,
            x + 3.0,
            y + 5.5,
            x + 5.6,
            y + 5.5,
            x + 16.0,
            y + 5.5,
            x + 22.0,
            y + 9.5
        );
        y += 16.0;
        let _ = writeln!(
            s,
            r##"<circle cx="{:.1}" cy="{:.1}" r="5" fill="none" stroke="#000" stroke-width="1.6"/><text x="{:.1}" y="{:.1}">goal</text>"##,
            x + 8.0,
            y + 5.5,
            x + 22.0,
            y + 9.5
        );
        y += 26.0;

        // Colour scale: one band per heat level, ticks every contour step.
        let _ = writeln!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" font-weight="bold">Φ: travel time to goal (s)</text>"#,
            y
        );
        let _ = writeln!(
            s,
            r##"<text x="{x:.1}" y="{:.1}" font-size="10.5" fill="#555">at {} m/s; contours every {} s</text>"##,
            y + 14.0,
            num(o.preferred_speed_m_s),
            num(step)
        );
        y += 22.0;
        let bar_h = (v.y0 + v.h() - y - 8.0).clamp(80.0, 200.0);
        let band = bar_h / HEAT_LEVELS as f64;
        s.push_str(r#"<g class="colour-scale" shape-rendering="crispEdges">"#);
        for l in 0..HEAT_LEVELS {
            let _ = write!(
                s,
                r#"<rect x="{x:.1}" y="{:.2}" width="18" height="{:.2}" fill="{}"/>"#,
                y + l as f64 * band,
                band + 0.05,
                ramp((l as f64 + 0.5) / HEAT_LEVELS as f64)
            );
        }
        s.push_str("</g>\n");
        let _ = writeln!(
            s,
            r##"<rect x="{x:.1}" y="{y:.1}" width="18" height="{bar_h:.1}" fill="none" stroke="#222" stroke-width="0.8"/>"##
        );
        let ticks = (vmax / step).round() as usize;
        for k in 0..=ticks {
            let ty = y + bar_h * (k as f64 * step / vmax);
            let _ = writeln!(
                s,
                r##"<line x1="{:.1}" y1="{ty:.1}" x2="{:.1}" y2="{ty:.1}" stroke="#222"/><text x="{:.1}" y="{:.1}" font-size="10.5">{} s</text>"##,
                x + 18.0,
                x + 22.0,
                x + 25.0,
                ty + 3.5,
                num(k as f64 * step)
            );
        }
        s.push_str("</g>\n");
    }
}
