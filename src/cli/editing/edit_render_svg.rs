//! The edit picture's layout (margins, scale bounds, how many points are drawn),
//! its palette (the time colour scale, collisions, fixed places, cages, obstacles)
//! and the helpers that write its numbers and text.

use crowdtouch::geom::Vec2;

/// Width of the plotting area (px).
pub const PLOT_WIDTH_PX: f64 = 880.0;
/// Bounds of the scale (px per metre).
pub const MIN_PX_PER_M: f64 = 6.0;
pub const MAX_PX_PER_M: f64 = 160.0;
/// Margin around what is drawn (m).
pub const MARGIN_M: f64 = 0.5;
/// Room for the title above and the axis labels left of the plot (px).
pub const TOP_PX: f64 = 40.0;
pub const LEFT_PX: f64 = 56.0;
pub const RIGHT_PX: f64 = 20.0;
/// Room under the plot for the axis, the legend and the summary (px).
pub const BOTTOM_PX: f64 = 118.0;
/// Most points drawn per track and per picture; longer tracks are thinned.
pub const MAX_TRACK_POINTS: usize = 400;
pub const MAX_POINTS: usize = 40_000;
/// Bands of the time colour scale.
pub const TIME_BANDS: usize = 12;
/// Viridis-like stops of the time colour scale (early → late).
pub const TIME_STOPS: [[f64; 3]; 5] = [
    [68.0, 1.0, 84.0],
    [59.0, 82.0, 139.0],
    [33.0, 145.0, 140.0],
    [94.0, 201.0, 98.0],
    [253.0, 231.0, 37.0],
];
pub const COLLISION_RED: &str = "#d62728";
pub const FIXED_BLUE: &str = "#1f4e9c";
pub const CAGE_COLOUR: &str = "#e07b00";
pub const OBSTACLE_FILL: &str = "#8c8c8c";

/// A length in metres, rounded to the millimetre, without trailing zeros.
pub fn mm(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    let s = format!("{:.3}", if r == 0.0 { 0.0 } else { r });
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub fn pt(p: Vec2) -> String {
    format!("{},{}", mm(p.x), mm(p.y))
}

pub fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The time colour at `f` in [0, 1].
pub fn time_colour(f: f64) -> String {
    let f = f.clamp(0.0, 1.0) * (TIME_STOPS.len() - 1) as f64;
    let i = (f.floor() as usize).min(TIME_STOPS.len() - 2);
    let u = f - i as f64;
    let c: Vec<u8> = (0..3)
        .map(|k| (TIME_STOPS[i][k] * (1.0 - u) + TIME_STOPS[i + 1][k] * u).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// A tick step of 1, 2 or 5 × 10^n giving about `n` ticks over `span`.
pub fn nice_step(span: f64, n: f64) -> f64 {
    let raw = (span / n).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|k| k * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}
