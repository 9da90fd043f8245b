//! Scales: round steps between ticks and contour levels, tick labels, and the
//! colour scales (heat, time, categorical series, subgroups).

/// A step of 1, 2 or 5 × 10ⁿ giving at most `n` intervals over `span`: contour
/// levels and map axes. `1` when `span` is not a positive number.
pub fn nice_step(span: f64, n: usize) -> f64 {
    step_from(span, n, &[1.0, 2.0, 5.0, 10.0])
}

/// A step of 1, 2, 2.5 or 5 × 10ⁿ giving at most `n` intervals over `span`: the
/// value axes of charts, where 2.5 keeps quarter steps.
pub fn fine_step(span: f64, n: usize) -> f64 {
    step_from(span, n, &[1.0, 2.0, 2.5, 5.0, 10.0])
}

fn step_from(span: f64, n: usize, mantissas: &[f64]) -> f64 {
    if !(span.is_finite() && span > 0.0) {
        return 1.0;
    }
    let raw = span / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    mantissas
        .iter()
        .map(|m| m * mag)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * mag)
}

/// The multiples of `step` in `[lo, hi]`.
pub fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    if !(step > 0.0 && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let first = (lo / step).ceil();
    (0..)
        .map(|i| (first + i as f64) * step)
        .take_while(|&v| v <= hi + 1e-9 * step)
        .take(10_000)
        .collect()
}

/// A chart's value axis from 0: the ticks (about `n` intervals, [`fine_step`]) up
/// to the first tick at or above `hi`, and that top.
pub fn axis_from_zero(hi: f64, n: usize) -> (Vec<f64>, f64) {
    let step = fine_step(hi.max(1e-12), n);
    let top = ((hi / step).ceil() * step).max(step);
    (ticks(0.0, top, step), top)
}

/// A tick label with as few decimals as the step needs (0.025 keeps three).
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = (0..6)
        .find(|&d| {
            let k = 10f64.powi(d as i32);
            ((step * k).round() - step * k).abs() < 1e-6 * step.abs().max(1e-12) * k
        })
        .unwrap_or(6);
    let v = if v.abs() < step.abs() * 1e-6 { 0.0 } else { v };
    format!("{v:.decimals$}")
}

fn lerp_stops(stops: &[(f64, [f64; 3])], u: f64) -> String {
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let k = stops
        .iter()
        .position(|s| s.0 >= u)
        .unwrap_or(stops.len() - 1)
        .max(1);
    let ((u0, c0), (u1, c1)) = (stops[k - 1], stops[k]);
    let f = ((u - u0) / (u1 - u0)).clamp(0.0, 1.0);
    let ch = |i: usize| (c0[i] + (c1[i] - c0[i]) * f).round() as u8;
    format!("#{:02x}{:02x}{:02x}", ch(0), ch(1), ch(2))
}

/// The heat scale at `u ∈ [0, 1]`: near-white (near) through yellow and orange to
/// dark red (far), as mesh-formation-control Fig. 6. NaN reads as 0.
pub fn heat(u: f64) -> String {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [255.0, 252.0, 235.0]),
        (0.25, [253.0, 219.0, 140.0]),
        (0.5, [252.0, 146.0, 84.0]),
        (0.75, [215.0, 48.0, 31.0]),
        (1.0, [127.0, 0.0, 0.0]),
    ];
    lerp_stops(&STOPS, u)
}

/// The time scale at `u ∈ [0, 1]` (early → late): a viridis-like ramp, readable
/// in grey and by colour-blind readers. NaN reads as 0.
pub fn time(u: f64) -> String {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [68.0, 1.0, 84.0]),
        (0.25, [59.0, 82.0, 139.0]),
        (0.5, [33.0, 145.0, 140.0]),
        (0.75, [94.0, 201.0, 98.0]),
        (1.0, [253.0, 231.0, 37.0]),
    ];
    lerp_stops(&STOPS, u)
}

/// Colours of the series of a chart (variants, curves), in their order.
pub const SERIES: [&str; 8] = [
    "#1f4e9c", "#17becf", "#e07b00", "#2b9348", "#8e44ad", "#c0392b", "#7f6000", "#555555",
];

/// Series `i`'s colour (the list repeats).
pub fn series(i: usize) -> &'static str {
    SERIES[i % SERIES.len()]
}

/// Dashes that tell series apart beyond their colour: the first four solid.
pub fn series_dash(i: usize) -> &'static str {
    match i {
        4 => "6 3",
        5 => "2 2",
        6 => "8 2 2 2",
        7 => "1 3",
        _ => "",
    }
}

/// Group `k`'s colour among many (subgroups): hues a golden angle apart.
pub fn group(k: u32) -> String {
    let hue = (k as f64 * 137.508) % 360.0;
    format!("hsl({hue:.0},65%,42%)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_1_2_5_and_fine_steps_keep_quarters() {
        assert_eq!(nice_step(10.0, 10), 1.0);
        assert_eq!(nice_step(13.0, 8), 2.0);
        assert_eq!(nice_step(0.9, 3), 0.5);
        assert_eq!(nice_step(f64::NAN, 5), 1.0);
        assert_eq!(nice_step(-1.0, 5), 1.0);
        assert_eq!(fine_step(1.2, 5), 0.25);
        assert_eq!(nice_step(1.2, 5), 0.5);
        // Brute force: the step is the smallest 1–2–5 candidate giving ≤ n intervals.
        for span in [0.013, 0.7, 3.3, 47.0, 1234.5] {
            for n in 1..12 {
                let best = (-6..6)
                    .flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)))
                    .filter(|c| span / c <= n as f64 * (1.0 + 1e-12))
                    .fold(f64::INFINITY, f64::min);
                let s = nice_step(span, n);
                assert!(
                    (s - best).abs() <= 1e-12 * best,
                    "{span} {n}: {s} vs {best}"
                );
            }
        }
    }

    #[test]
    fn ticks_cover_the_range_on_multiples_of_the_step() {
        let t = ticks(0.0, 1.0, 0.2);
        assert_eq!(t.len(), 6);
        for (k, v) in t.iter().enumerate() {
            assert!((v - 0.2 * k as f64).abs() < 1e-12, "{t:?}");
        }
        assert_eq!(ticks(-0.3, 0.3, 0.25), vec![-0.25, 0.0, 0.25]);
        assert!(ticks(0.0, 1.0, 0.0).is_empty());
        let (t, top) = axis_from_zero(1.45, 5);
        assert_eq!((t.len(), top), (4, 1.5));
        let (t, top) = axis_from_zero(37.0, 6);
        assert_eq!((t.first(), top), (Some(&0.0), 40.0));
    }

    #[test]
    fn labels_keep_the_decimals_the_step_needs() {
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(0.025, 0.025), "0.025");
        assert_eq!(tick_label(0.5, 0.5), "0.5");
        assert_eq!(tick_label(20.0, 10.0), "20");
        assert_eq!(tick_label(-1e-17, 0.2), "0.0");
    }

    #[test]
    fn colour_scales_run_between_their_ends() {
        assert_eq!(heat(0.0), "#fffceb");
        assert_eq!(heat(1.0), "#7f0000");
        assert_eq!(heat(0.5), "#fc9254");
        assert_eq!(heat(f64::NAN), heat(0.0));
        assert_eq!(time(0.0), "#440154");
        assert_eq!(time(1.0), "#fde725");
        assert_eq!(time(2.0), time(1.0));
        assert_eq!(series(9), series(1));
        assert_eq!(group(0), "hsl(0,65%,42%)");
    }
}
