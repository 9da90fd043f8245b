//! The edit picture's legend under the plot: the time scale, a key for each symbol
//! drawn, the one-line summary.

use super::edit_apply::Outcome;
use super::edit_render_svg::{BEFORE_GREY, COLLISION_DARK, LEFT_PX};
use crowdtouch::crowd::edit::Op;
use crowdtouch::picture::scale::time;
use crowdtouch::picture::text::num;
use crowdtouch::picture::{style, Canvas, Paint};

/// The legend, its first line at `top` (px).
pub fn legend(
    c: &mut Canvas,
    o: &Outcome,
    threshold_m: f64,
    t0: f64,
    t1: f64,
    at_s: &[f64],
    top: f64,
) {
    c.open_group(r#"class="legend""#);
    // The time scale.
    let (x0, bw, bh) = (LEFT_PX, 240.0, 10.0);
    const STOPS: usize = 5;
    c.raw(&format!(
        r#"<defs><linearGradient id="time-scale">{}</linearGradient></defs>"#,
        (0..STOPS)
            .map(|i| {
                let f = i as f64 / (STOPS - 1) as f64;
                format!(r#"<stop offset="{}" stop-color="{}"/>"#, num(f), time(f))
            })
            .collect::<String>()
    ));
    let small = style::SMALL_PX;
    c.text(
        (x0, top + 6.0),
        small,
        style::INK,
        "",
        "time after the edit (s)",
    );
    c.rect(x0, top + 12.0, bw, bh, &Paint::fill("url(#time-scale)"));
    for f in [0.0, 0.5, 1.0] {
        c.text(
            (x0 + f * bw, top + 12.0 + bh + 13.0),
            small,
            style::AXIS,
            r#"text-anchor="middle""#,
            &format!("{:.1}", t0 + f * (t1 - t0)),
        );
    }
    // Symbols: each key's symbol in the 20 px before its label.
    let mut at = x0 + bw + 30.0;
    let y = top + 17.0;
    let mut key = |c: &mut Canvas, symbol: &dyn Fn(&mut Canvas, f64), text: &str| {
        symbol(c, at);
        c.text((at + 24.0, y + 4.0), small, style::INK, "", text);
        at += 32.0 + 6.7 * text.chars().count() as f64;
    };
    let line = |paint: Paint| move |c: &mut Canvas, x: f64| c.line((x, y), (x + 20.0, y), &paint);
    key(c, &line(Paint::stroke(BEFORE_GREY, 1.5)), "before");
    if !o.report.drags.is_empty() {
        key(
            c,
            &line(Paint::stroke(style::CAGE, 1.4).dash("6 4")),
            "cage at rest",
        );
        key(c, &line(Paint::stroke(style::CAGE, 1.8)), "deformed");
        key(c, &line(Paint::stroke("#111111", 2.2)), "drag");
    }
    if o.script.ops.iter().any(|(op, _)| matches!(op, Op::Fix(_))) {
        let fixed = Paint::fill_stroke(style::FIXED, style::FIXED, 2.0).fill_opacity(0.25);
        key(
            c,
            &|c: &mut Canvas, x: f64| c.rect(x + 5.0, y - 5.0, 10.0, 10.0, &fixed),
            "fixed",
        );
    }
    let ring = Paint::stroke(style::ALERT, 1.6);
    key(
        c,
        &|c: &mut Canvas, x: f64| c.circle((x + 10.0, y), 6.0, &ring),
        "collision before",
    );
    let dot = Paint::fill_stroke(style::ALERT, COLLISION_DARK, 0.8);
    key(
        c,
        &|c: &mut Canvas, x: f64| c.circle((x + 10.0, y), 4.0, &dot),
        "after",
    );
    if !at_s.is_empty() {
        let before = Paint::fill_stroke(style::PLOT, style::AGENT_START, 1.0);
        let after = Paint::fill_stroke(&time(0.5), style::INK, 1.0);
        key(
            c,
            &|c: &mut Canvas, x: f64| {
                c.circle((x + 4.0, y), 3.5, &before);
                c.circle((x + 15.0, y), 3.5, &after);
            },
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
    c.text(
        (x0, top + 56.0),
        small,
        style::INK,
        r#"class="summary""#,
        &format!(
            "{} people, {} drag(s){retimed}; pairs closer than {} m: {} before, {} after; speeds {:.0}–{:.0} % of the input{inside}",
            o.after.tracks.len(),
            o.report.drags.len(),
            threshold_m,
            o.collisions_before.pair_count(),
            o.collisions_after.pair_count(),
            100.0 * o.speed.0,
            100.0 * o.speed.1
        ),
    );
    c.close_group();
}
