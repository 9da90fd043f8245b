//! The pictures of `crowdtouch transform --svg` (a run: sources, targets, each
//! agent's path coloured by its subgroup) and `transform compare --svg` (the
//! three measures of formation-transform section 5.1 over time, one curve per
//! variant, as the paper's Figs. 11 and 13).

use super::shared::Recorded;
use super::variant::Variant;
use crowdtouch::crowd::transform::{Measures, TransformPlan};
use crowdtouch::geom::Vec2;
use std::fmt::Write;

/// Widest picture of a run (px).
const RUN_WIDTH_PX: f64 = 960.0;
/// Narrowest picture of a run (px): room for its caption.
const MIN_RUN_WIDTH_PX: f64 = 900.0;
/// Margin around what a run picture shows (m).
const RUN_MARGIN_M: f64 = 0.8;
/// Height of the caption under a picture (px).
const CAPTION_PX: f64 = 62.0;
/// One panel of the measures plot (px), axes inside.
const PANEL_W_PX: f64 = 420.0;
const PANEL_H_PX: f64 = 300.0;
/// Room for the axis labels left of and under a panel's plotting area (px).
const AXIS_LEFT_PX: f64 = 62.0;
const AXIS_BOTTOM_PX: f64 = 44.0;
/// Most points drawn per curve.
const MAX_CURVE_POINTS: usize = 600;
/// The time axis of the measures plot is cut at this many times the slowest
/// arrival when a run went on (timed out) past it.
const CUT_FACTOR: f64 = 3.0;
/// The time axis is never cut shorter than this (s).
const MIN_CUT_S: f64 = 10.0;
/// Colours of the compare variants, in their order.
const VARIANT_COLOURS: [&str; 8] = [
    "#1f4e9c", "#17becf", "#e07b00", "#2b9348", "#8e44ad", "#c0392b", "#7f6000", "#555555",
];

/// Subgroup `k`'s colour: hues a golden angle apart.
fn group_colour(k: u32) -> String {
    let hue = (k as f64 * 137.508) % 360.0;
    format!("hsl({hue:.0},65%,42%)")
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A run: targets (grey rings of the agent's size), sources (small grey dots),
/// each agent's path and where it ended, coloured by subgroup.
pub fn run_picture(plan: &TransformPlan, rec: &Recorded, radius_m: f64, title: &str) -> String {
    let paths = rec.paths.as_deref().unwrap_or(&[]);
    let mut lo = Vec2::repeat(f64::INFINITY);
    let mut hi = Vec2::repeat(f64::NEG_INFINITY);
    for p in plan
        .sources_m
        .iter()
        .chain(&plan.targets_m)
        .chain(paths.iter().flatten())
    {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    if !(lo.x.is_finite() && hi.x.is_finite()) {
        lo = Vec2::zeros();
        hi = Vec2::new(1.0, 1.0);
    }
    lo -= Vec2::repeat(RUN_MARGIN_M);
    hi += Vec2::repeat(RUN_MARGIN_M);
    let (wm, hm) = (hi.x - lo.x, hi.y - lo.y);
    let k = (RUN_WIDTH_PX / wm).clamp(10.0, 120.0);
    let h = hm * k;
    // Wide enough for the caption.
    let w = (wm * k).max(MIN_RUN_WIDTH_PX);
    // World y up, picture y down.
    let px = |p: Vec2| ((p.x - lo.x) * k, (hi.y - p.y) * k);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{:.0}" viewBox="0 0 {w:.0} {:.0}" font-family="sans-serif" font-size="13">"##,
        h + CAPTION_PX,
        h + CAPTION_PX
    );
    let _ = writeln!(s, r##"<rect width="100%" height="100%" fill="#fbfbf8"/>"##);
    let r_px = radius_m * k;
    for t in &plan.targets_m {
        let (x, y) = px(*t);
        let _ = writeln!(
            s,
            r##"<circle cx="{x:.1}" cy="{y:.1}" r="{r_px:.1}" fill="none" stroke="#9a9a9a" stroke-width="0.8"/>"##
        );
    }
    for q in &plan.sources_m {
        let (x, y) = px(*q);
        let _ = writeln!(
            s,
            r##"<circle cx="{x:.1}" cy="{y:.1}" r="1.6" fill="#8a8a8a"/>"##
        );
    }
    let group_of = &plan.subgroups.group_of;
    for (i, p) in paths.iter().enumerate() {
        let colour = group_colour(group_of.get(i).copied().unwrap_or(0));
        if p.len() >= 2 {
            let pts: Vec<String> = p
                .iter()
                .map(|&q| {
                    let (x, y) = px(q);
                    format!("{x:.1},{y:.1}")
                })
                .collect();
            let _ = writeln!(
                s,
                r##"<polyline points="{}" fill="none" stroke="{colour}" stroke-opacity="0.6" stroke-width="1"/>"##,
                pts.join(" ")
            );
        }
        if let Some(&e) = p.last() {
            let (x, y) = px(e);
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}" fill="{colour}" fill-opacity="0.8"/>"##,
                (0.8 * r_px).max(1.5)
            );
        }
    }
    let sm = &rec.summary;
    let lines = [
        (title.to_string(), "#222"),
        (
            "grey dots: sources; grey rings: targets (agent size); lines: paths by subgroup; filled: where agents ended".to_string(),
            "#555",
        ),
        (
            format!(
                "{:.1} % arrived in {:.1} s simulated, {} overlapping pairs, closest two agents {:.3} m; 1 m = {k:.0} px",
                100.0 * sm.arrived_fraction,
                sm.simulated_s,
                sm.overlapping_pairs,
                sm.min_distance_m
            ),
            "#555",
        ),
    ];
    for (j, (text, colour)) in lines.iter().enumerate() {
        let _ = writeln!(
            s,
            r##"<text x="8" y="{:.0}" fill="{colour}">{}</text>"##,
            h + 18.0 + 17.0 * j as f64,
            xml_escape(text)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// Round tick values covering `[lo, hi]`, about `n` of them.
fn ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = (hi - lo).max(1e-12);
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() * step;
    (0..)
        .map(|i| first + i as f64 * step)
        .take_while(|&v| v <= hi + 1e-9 * step)
        .collect()
}

/// A tick label: as few decimals as the step needs (0.025 keeps three).
fn tick_label(v: f64, step: f64) -> String {
    let decimals = (0..6)
        .find(|&d| {
            let k = 10f64.powi(d as i32);
            ((step * k).round() - step * k).abs() < 1e-6 * step.abs().max(1e-12) * k
        })
        .unwrap_or(6);
    format!("{v:.decimals$}")
}

/// Ticks from 0 to the first round value at or above `hi`, that value.
fn axis(hi: f64, n: usize) -> (Vec<f64>, f64) {
    let t = ticks(0.0, hi, n);
    let step = if t.len() > 1 { t[1] - t[0] } else { hi };
    let top = ((hi / step).ceil() * step).max(step);
    (ticks(0.0, top, n), top)
}

/// The three measures over time: one panel each (`I_d` in bits, `σ_min_dis` and
/// `σ_curr_eft` in metres, time in seconds), one curve per variant, a legend.
pub fn measures_plot(variants: &[Variant], title: &str) -> String {
    type Pick = fn(&Measures) -> f64;
    let panels: [(&str, &str, Pick); 3] = [
        ("I_d, eq. 17", "I_d (bits)", |m| m.i_d),
        ("σ_min_dis, eq. 24", "σ_min_dis (m)", |m| {
            m.sigma_min_dis_m
        }),
        ("σ_curr_eft, eq. 26", "σ_curr_eft (m)", |m| {
            m.sigma_curr_eft_m
        }),
    ];
    let t_max = variants
        .iter()
        .filter_map(|v| v.rec.series.last().map(|s| s.0))
        .fold(0.0f64, f64::max)
        .max(1e-3);
    // Runs that time out go on long after the others arrived: the axis is cut
    // at a few times the slowest arrival so the transforms themselves show.
    let slowest_arrival = variants
        .iter()
        .filter_map(|v| v.rec.arrival_s())
        .fold(0.0f64, f64::max);
    let cut = (slowest_arrival > 0.0 && t_max > CUT_FACTOR * slowest_arrival)
        .then(|| (CUT_FACTOR * slowest_arrival).max(MIN_CUT_S).min(t_max));
    let t_max = cut.unwrap_or(t_max);
    let legend_h = 22.0 * variants.len() as f64 + 16.0;
    let (w, h) = (3.0 * PANEL_W_PX, 34.0 + PANEL_H_PX + legend_h);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="sans-serif" font-size="12">"##
    );
    let _ = writeln!(
        s,
        r##"<rect width="100%" height="100%" fill="#ffffff"/><text x="10" y="20" font-size="14" fill="#222">{}</text>"##,
        xml_escape(title)
    );
    if let Some(c) = cut {
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="20" fill="#666" text-anchor="end">time axis cut at {c:.0} s; the runs that had not all arrived go on to their timeout</text>"##,
            w - 12.0
        );
    }
    let top = 34.0;
    for (k, (name, unit, pick)) in panels.iter().enumerate() {
        let ox = k as f64 * PANEL_W_PX;
        let (x0, x1) = (ox + AXIS_LEFT_PX, ox + PANEL_W_PX - 16.0);
        let (y0, y1) = (top + PANEL_H_PX - AXIS_BOTTOM_PX, top + 18.0);
        let y_max = variants
            .iter()
            .flat_map(|v| v.rec.series.iter().map(|s| pick(&s.1)))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let (yt, y_top) = axis(y_max.max(1e-6), 5);
        let (xt, x_top) = axis(t_max, 6);
        let sx = |t: f64| x0 + (x1 - x0) * t / x_top;
        let sy = |v: f64| y0 - (y0 - y1) * v / y_top;
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="13" font-weight="bold" fill="#222" text-anchor="middle">{}</text>"##,
            0.5 * (x0 + x1),
            top + 10.0,
            xml_escape(name)
        );
        let step_y = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
        for v in &yt {
            let y = sy(*v);
            let _ = writeln!(
                s,
                r##"<line x1="{x0:.1}" y1="{y:.1}" x2="{x1:.1}" y2="{y:.1}" stroke="#eeeeee"/><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#444">{}</text>"##,
                x0 - 5.0,
                y + 4.0,
                tick_label(*v, step_y)
            );
        }
        let step_x = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
        for t in &xt {
            let x = sx(*t);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{:.1}" stroke="#444"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" fill="#444">{}</text>"##,
                y0 + 4.0,
                y0 + 17.0,
                tick_label(*t, step_x)
            );
        }
        let _ = writeln!(
            s,
            r##"<path d="M{x0:.1},{y1:.1}L{x0:.1},{y0:.1}L{x1:.1},{y0:.1}" fill="none" stroke="#444"/><text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#222">time (s)</text><text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle" fill="#222">{}</text>"##,
            0.5 * (x0 + x1),
            y0 + 34.0,
            ox + 16.0,
            0.5 * (y0 + y1),
            xml_escape(unit)
        );
        for (i, v) in variants.iter().enumerate() {
            // The steps within the time axis.
            let shown = v.rec.series.partition_point(|p| p.0 <= t_max + 1e-9);
            let series = &v.rec.series[..shown];
            if series.is_empty() {
                continue;
            }
            let stride = series.len().div_ceil(MAX_CURVE_POINTS).max(1);
            let mut d = String::new();
            let last = series.len() - 1;
            for (j, (t, m, _)) in series.iter().enumerate() {
                if j % stride != 0 && j != last {
                    continue;
                }
                let val = pick(m);
                if !val.is_finite() {
                    continue;
                }
                let _ = write!(
                    d,
                    "{}{:.1},{:.1}",
                    if d.is_empty() { 'M' } else { 'L' },
                    sx(*t),
                    sy(val)
                );
            }
            let _ = writeln!(
                s,
                r##"<path d="{d}" fill="none" stroke="{}" stroke-width="1.4"{}/>"##,
                VARIANT_COLOURS[i % VARIANT_COLOURS.len()],
                dash(i)
            );
        }
    }
    let ly = top + PANEL_H_PX + 8.0;
    for (i, v) in variants.iter().enumerate() {
        let y = ly + 22.0 * i as f64;
        let sm = &v.rec.summary;
        let arrival = match v.rec.arrival_s() {
            Some(t) => format!("arrived in {t:.1} s"),
            None => format!(
                "{:.1} % arrived at the timeout",
                100.0 * sm.arrived_fraction
            ),
        };
        let what = format!(
            "{}: {} pairing, {}; {arrival}",
            v.name,
            v.cost.name(),
            match v.mover() {
                crowdtouch::crowd::transform::Mover::Orca => "ORCA".to_string(),
                crowdtouch::crowd::transform::Mover::Rvo => "RVO".to_string(),
                crowdtouch::crowd::transform::Mover::Steering => "steering".to_string(),
                crowdtouch::crowd::transform::Mover::SocialForce => format!(
                    "social forces, feedback {}",
                    super::shared::on_off(v.feedback())
                ),
            }
        );
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{}" stroke-width="2.5"{}/><text x="{:.1}" y="{:.1}" fill="#222">{}</text>"##,
            AXIS_LEFT_PX,
            y + 8.0,
            AXIS_LEFT_PX + 34.0,
            y + 8.0,
            VARIANT_COLOURS[i % VARIANT_COLOURS.len()],
            dash(i),
            AXIS_LEFT_PX + 42.0,
            y + 12.0,
            xml_escape(&what)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// One row of a `--lambdas` sweep for [`lambda_plot`]: its λ, whether on the
/// normalised terms, and (mean, 95 % half-width) of, in order, the agents paired
/// differently from travel-only (%), the travel term `Σ|s t|²` (m²), the time
/// (s), `I_d` (bits), `σ_min_dis` (m) and `σ_curr_eft` (m).
pub struct SweepPoint {
    /// λ of eq. 3.
    pub lambda: f64,
    /// On the normalised terms.
    pub normalised: bool,
    /// The six values, each (mean, 95 % half-width).
    pub values: [(f64, f64); 6],
}

/// A λ sweep: six panels against λ (the pairing's change and travel, the time,
/// the three measures of section 5.1), one curve for the raw terms of eq. 3 and
/// one for the normalised terms, each point with its 95 % interval.
pub fn lambda_plot(points: &[SweepPoint], title: &str) -> String {
    const PANELS: [(&str, &str); 6] = [
        ("paired differently from λ = 1", "agents (%)"),
        ("travel term Σ|s t|²", "m²"),
        ("time (arrival, or rest)", "s"),
        ("I_d, eq. 17", "bits"),
        ("σ_min_dis, eq. 24", "m"),
        ("σ_curr_eft, eq. 26", "m"),
    ];
    const COLS: usize = 3;
    let (pw, ph) = (PANEL_W_PX, PANEL_H_PX);
    let legend_h = 40.0;
    let (w, h) = (COLS as f64 * pw, 34.0 + 2.0 * ph + legend_h);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}" font-family="sans-serif" font-size="12">"##
    );
    let _ = writeln!(
        s,
        r##"<rect width="100%" height="100%" fill="#ffffff"/><text x="10" y="20" font-size="14" fill="#222">{}</text>"##,
        xml_escape(title)
    );
    let series = |normalised: bool| -> Vec<&SweepPoint> {
        let mut v: Vec<&SweepPoint> = points
            .iter()
            .filter(|p| p.normalised == normalised && p.lambda.is_finite())
            .collect();
        v.sort_by(|a, b| a.lambda.total_cmp(&b.lambda));
        v
    };
    let curves = [
        (series(false), VARIANT_COLOURS[0], ""),
        (
            series(true),
            VARIANT_COLOURS[2],
            r##" stroke-dasharray="6 3""##,
        ),
    ];
    for (k, (name, unit)) in PANELS.iter().enumerate() {
        let (ox, oy) = ((k % COLS) as f64 * pw, 34.0 + (k / COLS) as f64 * ph);
        let (x0, x1) = (ox + AXIS_LEFT_PX, ox + pw - 16.0);
        let (y0, y1) = (oy + ph - AXIS_BOTTOM_PX, oy + 18.0);
        let y_max = points
            .iter()
            .map(|p| p.values[k].0 + p.values[k].1.max(0.0))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let (yt, y_top) = axis(y_max.max(1e-6), 5);
        let sx = |l: f64| x0 + (x1 - x0) * l;
        let sy = |v: f64| y0 - (y0 - y1) * v / y_top;
        let _ = writeln!(
            s,
            r##"<text x="{:.1}" y="{:.1}" font-size="13" font-weight="bold" fill="#222" text-anchor="middle">{}</text>"##,
            0.5 * (x0 + x1),
            oy + 10.0,
            xml_escape(name)
        );
        let step_y = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
        for v in &yt {
            let y = sy(*v);
            let _ = writeln!(
                s,
                r##"<line x1="{x0:.1}" y1="{y:.1}" x2="{x1:.1}" y2="{y:.1}" stroke="#eeeeee"/><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#444">{}</text>"##,
                x0 - 5.0,
                y + 4.0,
                tick_label(*v, step_y)
            );
        }
        for l in [0.0, 0.25, 0.5, 0.75, 1.0] {
            let x = sx(l);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{:.1}" stroke="#444"/><text x="{x:.1}" y="{:.1}" text-anchor="middle" fill="#444">{}</text>"##,
                y0 + 4.0,
                y0 + 17.0,
                tick_label(l, 0.25)
            );
        }
        let _ = writeln!(
            s,
            r##"<path d="M{x0:.1},{y1:.1}L{x0:.1},{y0:.1}L{x1:.1},{y0:.1}" fill="none" stroke="#444"/><text x="{:.1}" y="{:.1}" text-anchor="middle" fill="#222">λ</text><text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle" fill="#222">{}</text>"##,
            0.5 * (x0 + x1),
            y0 + 34.0,
            ox + 16.0,
            0.5 * (y0 + y1),
            xml_escape(unit)
        );
        for (pts, colour, dash) in &curves {
            let mut d = String::new();
            for p in pts {
                let (m, ci) = p.values[k];
                if !m.is_finite() {
                    continue;
                }
                let (x, y) = (sx(p.lambda), sy(m));
                let _ = write!(d, "{}{x:.1},{y:.1}", if d.is_empty() { 'M' } else { 'L' });
                if ci.is_finite() && ci > 0.0 {
                    let _ = writeln!(
                        s,
                        r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="{colour}" stroke-width="1.2"/>"##,
                        sy(m - ci),
                        sy(m + ci)
                    );
                }
                let _ = writeln!(
                    s,
                    r##"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="{colour}"/>"##
                );
            }
            if !d.is_empty() {
                let _ = writeln!(
                    s,
                    r##"<path d="{d}" fill="none" stroke="{colour}" stroke-width="2"{dash}/>"##
                );
            }
        }
    }
    let y = 34.0 + 2.0 * ph + 8.0;
    for (i, (label, (_, colour, dash))) in [
        "ΔE, eq. 3 as printed (raw terms, m²)",
        "ΔE′: each term over its mean over every pair",
    ]
    .iter()
    .zip(&curves)
    .enumerate()
    {
        let x = AXIS_LEFT_PX + i as f64 * 1.5 * pw;
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="2.5"{dash}/><text x="{:.1}" y="{:.1}" fill="#222">{}</text>"##,
            y + 8.0,
            x + 34.0,
            y + 8.0,
            x + 42.0,
            y + 12.0,
            xml_escape(label)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The dash of variant `i`'s curve: the variants sharing the least-effort
/// pairing (no feedback, ORCA, RVO, steering) dashed.
fn dash(i: usize) -> &'static str {
    match i {
        4 => r##" stroke-dasharray="6 3""##,
        5 => r##" stroke-dasharray="2 2""##,
        6 => r##" stroke-dasharray="8 2 2 2""##,
        7 => r##" stroke-dasharray="1 3""##,
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        let t = ticks(0.0, 1.0, 5);
        assert_eq!(t.len(), 6);
        for (k, v) in t.iter().enumerate() {
            assert!((v - 0.2 * k as f64).abs() < 1e-12, "{t:?}");
        }
        let t = ticks(0.0, 37.0, 6);
        assert_eq!(t.first(), Some(&0.0));
        assert!(t.len() >= 4 && t.len() <= 9 && *t.last().unwrap() <= 37.0);
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(0.025, 0.025), "0.025");
        assert_eq!(tick_label(0.5, 0.5), "0.5");
        let (t, top) = axis(1.45, 5);
        assert_eq!((t.len(), top), (4, 1.5));
        assert_eq!(tick_label(20.0, 10.0), "20");
    }
}
