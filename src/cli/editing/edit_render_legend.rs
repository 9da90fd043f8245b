//! The edit picture's frame in pixels: the axes in metres under and left of the
//! plot, and the legend (the time scale, a key for each symbol drawn, the one-line
//! summary).

use super::edit_apply::Outcome;
use super::edit_render_svg::{
    nice_step, time_colour, CAGE_COLOUR, COLLISION_RED, FIXED_BLUE, LEFT_PX, TIME_STOPS, TOP_PX,
};
use crowdtouch::crowd::edit::Op;
use crowdtouch::geom::Vec2;
use std::fmt::Write;

pub fn axes(s: &mut String, lo: Vec2, hi: Vec2, k: f64, ph: f64) {
    let px = |x: f64| LEFT_PX + (x - lo.x) * k;
    let py = |y: f64| TOP_PX + (hi.y - y) * k;
    let step = nice_step((hi.x - lo.x).max(hi.y - lo.y), 10.0);
    let label = |v: f64| {
        let v = if v.abs() < step * 1e-6 { 0.0 } else { v };
        if step >= 1.0 {
            format!("{v:.0}")
        } else {
            format!("{v:.1}")
        }
    };
    let _ = writeln!(s, r##"<g id="axes" fill="#333" stroke="#333">"##);
    let _ = writeln!(
        s,
        r##"<rect x="{LEFT_PX:.1}" y="{TOP_PX:.1}" width="{:.1}" height="{ph:.1}" fill="none" stroke-width="1"/>"##,
        (hi.x - lo.x) * k
    );
    let mut x = (lo.x / step).ceil() * step;
    while x <= hi.x {
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><text x="{:.1}" y="{:.1}" stroke="none" text-anchor="middle">{}</text>"##,
            px(x),
            TOP_PX + ph,
            px(x),
            TOP_PX + ph + 5.0,
            px(x),
            TOP_PX + ph + 19.0,
            label(x)
        );
        x += step;
    }
    let mut y = (lo.y / step).ceil() * step;
    while y <= hi.y {
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><text x="{:.1}" y="{:.1}" stroke="none" text-anchor="end">{}</text>"##,
            LEFT_PX - 5.0,
            py(y),
            LEFT_PX,
            py(y),
            LEFT_PX - 8.0,
            py(y) + 4.0,
            label(y)
        );
        y += step;
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" stroke="none" text-anchor="middle">x (m)</text><text x="14" y="{:.1}" stroke="none" transform="rotate(-90 14 {:.1})" text-anchor="middle">y (m)</text>"##,
        LEFT_PX + (hi.x - lo.x) * k / 2.0,
        TOP_PX + ph + 34.0,
        TOP_PX + ph / 2.0,
        TOP_PX + ph / 2.0
    );
    s.push_str("</g>\n");
}

pub fn legend(
    s: &mut String,
    o: &Outcome,
    threshold_m: f64,
    t0: f64,
    t1: f64,
    at_s: &[f64],
    top: f64,
) {
    let _ = writeln!(s, r##"<g id="legend" fill="#333">"##);
    // The time scale.
    let (x0, bw, bh) = (LEFT_PX, 240.0, 10.0);
    let _ = writeln!(
        s,
        r##"<defs><linearGradient id="time-scale">{}</linearGradient></defs>"##,
        (0..TIME_STOPS.len())
            .map(|i| {
                let f = i as f64 / (TIME_STOPS.len() - 1) as f64;
                format!(
                    r##"<stop offset="{:.2}" stop-color="{}"/>"##,
                    f,
                    time_colour(f)
                )
            })
            .collect::<String>()
    );
    let _ = writeln!(
        s,
        r##"<text x="{x0:.1}" y="{:.1}">time after the edit (s)</text>"##,
        top + 6.0
    );
    let _ = writeln!(
        s,
        r##"<rect x="{x0:.1}" y="{:.1}" width="{bw:.0}" height="{bh:.0}" fill="url(#time-scale)"/>"##,
        top + 12.0
    );
    for f in [0.0, 0.5, 1.0] {
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">{:.1}</text>"##,
            x0 + f * bw,
            top + 12.0 + bh + 13.0,
            t0 + f * (t1 - t0)
        );
    }
    // Symbols.
    // Each key is drawn at x = 0 and moved into place.
    let mut at = x0 + bw + 30.0;
    let (x, y) = (0.0_f64, top + 17.0);
    let mut key = |s: &mut String, symbol: String, text: &str| {
        let _ = writeln!(
            s,
            r##"<g transform="translate({at:.1} 0)">{symbol}<text x="24" y="{:.1}" font-size="12">{text}</text></g>"##,
            y + 4.0
        );
        at += 32.0 + 6.7 * text.chars().count() as f64;
    };
    let line = |x: f64, attrs: &str| {
        format!(
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" {attrs}/>"##,
            x,
            x + 20.0
        )
    };
    key(
        s,
        line(x, r##"stroke="#b4b4b4" stroke-width="1.5""##),
        "before",
    );
    if !o.report.drags.is_empty() {
        key(
            s,
            line(
                x,
                &format!(r##"stroke="{CAGE_COLOUR}" stroke-width="1.4" stroke-dasharray="6 4""##),
            ),
            "cage at rest",
        );
        key(
            s,
            line(
                x,
                &format!(r##"stroke="{CAGE_COLOUR}" stroke-width="1.8""##),
            ),
            "deformed",
        );
        key(s, line(x, r##"stroke="#111" stroke-width="2.2""##), "drag");
    }
    if o.script.ops.iter().any(|(op, _)| matches!(op, Op::Fix(_))) {
        key(
            s,
            format!(
                r##"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="{FIXED_BLUE}" fill-opacity="0.25" stroke="{FIXED_BLUE}" stroke-width="2"/>"##,
                x + 5.0,
                y - 5.0
            ),
            "fixed",
        );
    }
    key(
        s,
        format!(
            r##"<circle cx="{:.1}" cy="{y:.1}" r="6" fill="none" stroke="{COLLISION_RED}" stroke-width="1.6"/>"##,
            x + 10.0
        ),
        "collision before",
    );
    key(
        s,
        format!(
            r##"<circle cx="{:.1}" cy="{y:.1}" r="4" fill="{COLLISION_RED}" stroke="#7a0000" stroke-width="0.8"/>"##,
            x + 10.0
        ),
        "after",
    );
    if !at_s.is_empty() {
        key(
            s,
            format!(
                r##"<circle cx="{:.1}" cy="{y:.1}" r="3.5" fill="#ffffff" stroke="#777"/><circle cx="{:.1}" cy="{y:.1}" r="3.5" fill="{}" stroke="#222"/>"##,
                x + 4.0,
                x + 15.0,
                time_colour(0.5)
            ),
            &format!(
                "at {} s: before, after",
                at_s.iter()
                    .map(|t| format!("{t}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        );
    }
    let retimed = if o.report.retimes > 0 {
        format!("; {} retime(s)", o.report.retimes)
    } else {
        String::new()
    };
    let inside = o
        .obstacles
        .as_ref()
        .map(|(_, r, _)| {
            format!(
                "; samples in obstacles: {} before, {} after",
                r.samples_inside_before, r.samples_inside_after
            )
        })
        .unwrap_or_default();
    let _ = writeln!(
        s,
        r##"<text id="summary" x="{x0:.1}" y="{:.1}" font-size="12">{} people, {} drag(s){retimed}; pairs closer than {} m: {} before, {} after; speeds {:.0}–{:.0} % of the input{inside}</text>"##,
        top + 56.0,
        o.after.tracks.len(),
        o.report.drags.len(),
        threshold_m,
        o.collisions_before.pair_count(),
        o.collisions_after.pair_count(),
        100.0 * o.speed.0,
        100.0 * o.speed.1
    );
    s.push_str("</g>\n");
}
