//! The pictures of `crowdtouch transform --svg` (a run: sources, targets, each
//! agent's path coloured by its subgroup) and `transform compare --svg` (the
//! three measures of formation-transform section 5.1 over time, one curve per
//! variant, as the paper's Figs. 11 and 13).

use super::shared::Recorded;
use super::variant::Variant;
use crowdtouch::crowd::transform::{Measures, TransformPlan};
use crowdtouch::geom::Rect;
use crowdtouch::picture::elements::{self, legend_entry, Chart, Swatch};
use crowdtouch::picture::scale::{self, axis_from_zero, tick_label};
use crowdtouch::picture::{style, Canvas, Frame, Paint, PathData};

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
/// Height of the title band above the panels (px).
const TITLE_BAND_PX: f64 = 34.0;
/// Most points drawn per curve.
const MAX_CURVE_POINTS: usize = 600;
/// The time axis of the measures plot is cut at this many times the slowest
/// arrival when a run went on (timed out) past it.
const CUT_FACTOR: f64 = 3.0;
/// The time axis is never cut shorter than this (s).
const MIN_CUT_S: f64 = 10.0;

/// A run: targets (grey rings of the agent's size), sources (small grey dots),
/// each agent's path and where it ended, coloured by subgroup.
pub fn run_picture(plan: &TransformPlan, rec: &Recorded, radius_m: f64, title: &str) -> String {
    let paths = rec.paths.as_deref().unwrap_or(&[]);
    let everything = plan
        .sources_m
        .iter()
        .chain(&plan.targets_m)
        .chain(paths.iter().flatten());
    let world = crowdtouch::picture::canvas::extent(everything, RUN_MARGIN_M).unwrap_or(Rect {
        min: [-RUN_MARGIN_M, -RUN_MARGIN_M],
        max: [1.0 + RUN_MARGIN_M, 1.0 + RUN_MARGIN_M],
    });
    let k = (RUN_WIDTH_PX / world.width()).clamp(10.0, 120.0);
    // World y up, picture y down.
    let f = Frame {
        world,
        px_per_m: k,
        left_px: 0.0,
        top_px: 0.0,
        y_up: true,
    };
    let h = f.height_px();
    // Wide enough for the caption.
    let mut c = Canvas::new(f.width_px().max(MIN_RUN_WIDTH_PX), h + CAPTION_PX);
    let r_px = f.len(radius_m);
    let target = Paint::stroke(style::AGENT_START, 0.8).class("target");
    for t in &plan.targets_m {
        c.circle(f.pt(*t), r_px, &target);
    }
    elements::agents(
        &mut c,
        &f,
        &plan.sources_m,
        1.6,
        &Paint::fill(style::AGENT_START).class("source"),
    );
    let group_of = &plan.subgroups.group_of;
    for (i, p) in paths.iter().enumerate() {
        let colour = scale::group(group_of.get(i).copied().unwrap_or(0));
        elements::track(
            &mut c,
            &f,
            p,
            &Paint::stroke(&colour, style::LINE_PX)
                .stroke_opacity(0.6)
                .class("path"),
        );
        if let Some(&e) = p.last() {
            c.circle(
                f.pt(e),
                (0.8 * r_px).max(1.5),
                &Paint::fill(&colour).fill_opacity(0.8).class("agent"),
            );
        }
    }
    let sm = &rec.summary;
    // Whole pixels under the drawing, however tall it is.
    let y = (h + 18.0).round();
    c.title((8.0, y), title);
    c.caption(
        (8.0, y + 17.0),
        "grey dots: sources; grey rings: targets (agent size); lines: paths by subgroup; filled: where agents ended",
    );
    c.caption(
        (8.0, y + 34.0),
        &format!(
            "{:.1} % arrived in {:.1} s simulated, {} overlapping pairs, closest two agents {:.3} m; 1 m = {k:.0} px",
            100.0 * sm.arrived_fraction,
            sm.simulated_s,
            sm.overlapping_pairs,
            sm.min_distance_m
        ),
    );
    c.finish()
}

/// Tick values with their labels.
fn labelled(ticks: &[f64]) -> Vec<(f64, String)> {
    let step = if ticks.len() > 1 {
        ticks[1] - ticks[0]
    } else {
        1.0
    };
    ticks.iter().map(|&v| (v, tick_label(v, step))).collect()
}

/// The plotting area of the panel whose box starts at `(ox, oy)`.
fn panel(ox: f64, oy: f64, x_range: (f64, f64), y_top: f64) -> Chart {
    Chart {
        left: ox + AXIS_LEFT_PX,
        top: oy + 18.0,
        right: ox + PANEL_W_PX - 16.0,
        bottom: oy + PANEL_H_PX - AXIS_BOTTOM_PX,
        x_range,
        y_range: (0.0, y_top),
    }
}

/// Series `i` as a line of width `width_px`, with its dash.
fn series_paint(i: usize, width_px: f64) -> Paint {
    Paint::stroke(scale::series(i), width_px).dash(scale::series_dash(i))
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
    let w = 3.0 * PANEL_W_PX;
    let mut c = Canvas::new(w, TITLE_BAND_PX + PANEL_H_PX + legend_h);
    c.title((10.0, 20.0), title);
    if let Some(cut) = cut {
        c.text(
            (w - 12.0, 20.0),
            style::SMALL_PX,
            style::INK_SOFT,
            r#"text-anchor="end""#,
            &format!("time axis cut at {cut:.0} s; the runs that had not all arrived go on to their timeout"),
        );
    }
    for (k, (name, unit, pick)) in panels.iter().enumerate() {
        let ox = k as f64 * PANEL_W_PX;
        let y_max = variants
            .iter()
            .flat_map(|v| v.rec.series.iter().map(|s| pick(&s.1)))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let (yt, y_top) = axis_from_zero(y_max.max(1e-6), 5);
        let (xt, x_top) = axis_from_zero(t_max, 6);
        let ch = panel(ox, TITLE_BAND_PX, (0.0, x_top), y_top);
        ch.draw_axes(
            &mut c,
            (name, 8.0),
            &labelled(&xt),
            &labelled(&yt),
            "time (s)",
            (unit, ox + 16.0),
        );
        for (i, v) in variants.iter().enumerate() {
            // The steps within the time axis.
            let shown = v.rec.series.partition_point(|p| p.0 <= t_max + 1e-9);
            let series = &v.rec.series[..shown];
            if series.is_empty() {
                continue;
            }
            let stride = series.len().div_ceil(MAX_CURVE_POINTS).max(1);
            let last = series.len() - 1;
            let pts = series
                .iter()
                .enumerate()
                .filter(|(j, _)| j % stride == 0 || *j == last)
                .map(|(_, (t, m, _))| (*t, pick(m)))
                .filter(|(_, val)| val.is_finite())
                .map(|(t, val)| (ch.x(t), ch.y(val)));
            let mut d = PathData::new();
            d.polyline(pts);
            c.path(&d, &series_paint(i, 1.4).class("curve"));
        }
    }
    let ly = TITLE_BAND_PX + PANEL_H_PX + 8.0;
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
        let paint = series_paint(i, 2.5);
        let swatch = Swatch::Line {
            paint: &paint,
            len_px: 34.0,
        };
        legend_entry(
            &mut c,
            (AXIS_LEFT_PX, y + 8.0),
            &swatch,
            8.0,
            style::SMALL_PX,
            &what,
        );
    }
    c.finish()
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
    let mut c = Canvas::new(COLS as f64 * pw, TITLE_BAND_PX + 2.0 * ph + legend_h);
    c.title((10.0, 20.0), title);
    let series = |normalised: bool| -> Vec<&SweepPoint> {
        let mut v: Vec<&SweepPoint> = points
            .iter()
            .filter(|p| p.normalised == normalised && p.lambda.is_finite())
            .collect();
        v.sort_by(|a, b| a.lambda.total_cmp(&b.lambda));
        v
    };
    // Raw terms solid in the first series colour, normalised dashed in the third.
    let curves = [
        (series(false), scale::series(0), ""),
        (series(true), scale::series(2), "6 3"),
    ];
    let lambdas: Vec<(f64, String)> = [0.0, 0.25, 0.5, 0.75, 1.0]
        .into_iter()
        .map(|l| (l, tick_label(l, 0.25)))
        .collect();
    for (k, (name, unit)) in PANELS.iter().enumerate() {
        let (ox, oy) = (
            (k % COLS) as f64 * pw,
            TITLE_BAND_PX + (k / COLS) as f64 * ph,
        );
        let y_max = points
            .iter()
            .map(|p| p.values[k].0 + p.values[k].1.max(0.0))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let (yt, y_top) = axis_from_zero(y_max.max(1e-6), 5);
        let ch = panel(ox, oy, (0.0, 1.0), y_top);
        ch.draw_axes(
            &mut c,
            (name, 8.0),
            &lambdas,
            &labelled(&yt),
            "λ",
            (unit, ox + 16.0),
        );
        for (pts, colour, dash) in &curves {
            let mut d = PathData::new();
            let bar = Paint::stroke(colour, 1.2).class("interval");
            let dot = Paint::fill(colour).class("mean");
            for (j, p) in pts.iter().filter(|p| p.values[k].0.is_finite()).enumerate() {
                let (m, ci) = p.values[k];
                let at = (ch.x(p.lambda), ch.y(m));
                if j == 0 {
                    d.move_to(at);
                } else {
                    d.line_to(at);
                }
                if ci.is_finite() && ci > 0.0 {
                    c.line((at.0, ch.y(m - ci)), (at.0, ch.y(m + ci)), &bar);
                }
                c.circle(at, 3.0, &dot);
            }
            c.path(
                &d,
                &Paint::stroke(colour, style::BOLD_PX)
                    .dash(dash)
                    .class("curve"),
            );
        }
    }
    let y = TITLE_BAND_PX + 2.0 * ph + 8.0;
    for (i, (label, (_, colour, dash))) in [
        "ΔE, eq. 3 as printed (raw terms, m²)",
        "ΔE′: each term over its mean over every pair",
    ]
    .iter()
    .zip(&curves)
    .enumerate()
    {
        let paint = Paint::stroke(colour, 2.5).dash(dash);
        let swatch = Swatch::Line {
            paint: &paint,
            len_px: 34.0,
        };
        let x = AXIS_LEFT_PX + i as f64 * 1.5 * pw;
        legend_entry(&mut c, (x, y + 8.0), &swatch, 8.0, style::SMALL_PX, label);
    }
    c.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panel_puts_zero_at_its_bottom_left_and_the_tops_at_its_corner() {
        let ch = panel(420.0, 34.0, (0.0, 10.0), 2.5);
        assert_eq!((ch.x(0.0), ch.y(0.0)), (482.0, 290.0));
        assert_eq!((ch.x(10.0), ch.y(2.5)), (824.0, 52.0));
        let l = labelled(&[0.0, 0.25, 0.5]);
        assert_eq!(l[1].1, "0.25");
    }
}
