//! The legend beside the map: motion types, symbols and the colour scale of `Φ`.

use super::colours::{
    motion_colour, motion_label, BLOCKED_FILL, CHECKPOINT_STROKE, MOVING_FILL, OBSTACLE_FILL,
    ROUTE_STROKE,
};
use super::heatmap::HEAT_LEVELS;
use super::picture::{Options, Picture};
use super::view::MARGIN_PX;
use crowdtouch::crowd::environment::{DynamicKind, Scene};
use crowdtouch::picture::elements::{colour_bar, Direction};
use crowdtouch::picture::scale::heat;
use crowdtouch::picture::text::num;
use crowdtouch::picture::{style, Canvas, Frame, Paint};
use crowdtouch::vocab::MotionType;
use std::fmt::Write;

/// Legend text size (px).
const LEGEND_PX: f64 = 11.5;
/// Colour-scale tick text size (px).
const TICK_PX: f64 = 10.5;

impl Picture {
    pub(super) fn legend(
        &self,
        c: &mut Canvas,
        scene: &Scene,
        v: &Frame,
        o: &Options,
        step: f64,
        vmax: f64,
    ) {
        let x = v.left_px + v.width_px() + MARGIN_PX + 6.0;
        let mut y = v.top_px + 4.0;
        let label = |c: &mut Canvas, y: f64, text: &str| {
            c.text((x + 22.0, y + 9.5), LEGEND_PX, style::INK, "", text);
        };
        c.open_group(r#"class="legend""#);
        c.text(
            (x, y + 8.0),
            LEGEND_PX,
            style::INK,
            r#"font-weight="bold""#,
            "Travel speed × running",
        );
        y += 16.0;
        for m in MotionType::ALL {
            let m_colour = motion_colour(m);
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
            let mut label_text = format!("{} ×{:.2}", motion_label(m), m.default_speed_factor());
            if !factors.is_empty() {
                let f: Vec<String> = factors.iter().map(|f| format!("×{}", num(*f))).collect();
                let _ = write!(label_text, " (here {})", f.join(", "));
            }
            c.rect(
                x,
                y,
                16.0,
                11.0,
                &Paint::fill_stroke(m_colour, m_colour, 1.5)
                    .fill_opacity(0.22)
                    .class("legend-motion"),
            );
            label(c, y, &label_text);
            y += 16.0;
        }
        y += 10.0;
        let swatches: [(Paint, String); 5] = [
            (
                Paint::fill_stroke(OBSTACLE_FILL, "#1a1a1a", 1.0),
                "obstacle".into(),
            ),
            (
                Paint::fill_stroke(MOVING_FILL, "#1a1a1a", 1.0),
                format!("moving, at t = {} s (path dashed)", num(o.t_s)),
            ),
            (
                Paint::stroke(CHECKPOINT_STROKE, 2.0).dash("2 2"),
                "checkpoint: formation".into(),
            ),
            (Paint::fill(BLOCKED_FILL), "blocked cell".into()),
            (
                Paint::fill_stroke("url(#unreachable)", "#8a7fa8", 0.5),
                "unreachable cell".into(),
            ),
        ];
        for (paint, text) in &swatches {
            c.rect(x, y, 16.0, 11.0, paint);
            label(c, y, text);
            y += 16.0;
        }
        c.circle(
            (x + 3.0, y + 5.5),
            2.6,
            &Paint::fill_stroke(style::PLOT, ROUTE_STROKE, 1.0),
        );
        c.line(
            (x + 5.6, y + 5.5),
            (x + 16.0, y + 5.5),
            &Paint::stroke(ROUTE_STROKE, 1.1),
        );
        label(c, y, "agent and its route");
        y += 16.0;
        c.circle((x + 8.0, y + 5.5), 5.0, &Paint::stroke("#000000", 1.6));
        label(c, y, "goal");
        y += 26.0;

        // Colour scale: one band per heat level, ticks every contour step.
        c.text(
            (x, y),
            LEGEND_PX,
            style::INK,
            r#"font-weight="bold""#,
            "Φ: travel time to goal (s)",
        );
        c.text(
            (x, y + 14.0),
            TICK_PX,
            style::INK_SOFT,
            "",
            &format!(
                "at {} m/s; contours every {} s",
                num(o.preferred_speed_m_s),
                num(step)
            ),
        );
        y += 22.0;
        let bar_h = (v.top_px + v.height_px() - y - 8.0).clamp(80.0, 200.0);
        colour_bar(
            c,
            (x, y),
            (18.0, bar_h),
            HEAT_LEVELS,
            Direction::Down,
            &heat,
        );
        let ticks = (vmax / step).round() as usize;
        let tick = Paint::stroke(style::INK, style::LINE_PX);
        for k in 0..=ticks {
            let ty = y + bar_h * (k as f64 * step / vmax);
            c.line((x + 18.0, ty), (x + 22.0, ty), &tick);
            c.text(
                (x + 25.0, ty + 3.5),
                TICK_PX,
                style::INK,
                "",
                &format!("{} s", num(k as f64 * step)),
            );
        }
        c.close_group();
    }
}
