//! Colours: the heat ramp, motion types (colour and label) and the fixed fills.

use crowdtouch::vocab::MotionType;

/// The heat ramp at `u ∈ [0, 1]`: near-white (at the goal) through yellow and
/// orange to dark red (far), as mesh-formation-control Fig. 6.
pub fn ramp(u: f64) -> String {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [255.0, 252.0, 235.0]),
        (0.25, [253.0, 219.0, 140.0]),
        (0.5, [252.0, 146.0, 84.0]),
        (0.75, [215.0, 48.0, 31.0]),
        (1.0, [127.0, 0.0, 0.0]),
    ];
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let k = STOPS
        .iter()
        .position(|s| s.0 >= u)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let ((u0, c0), (u1, c1)) = (STOPS[k - 1], STOPS[k]);
    let f = ((u - u0) / (u1 - u0)).clamp(0.0, 1.0);
    let ch = |i: usize| (c0[i] + (c1[i] - c0[i]) * f).round() as u8;
    format!("#{:02x}{:02x}{:02x}", ch(0), ch(1), ch(2))
}

/// Colour of a motion type's patches.
pub fn motion_colour(m: MotionType) -> &'static str {
    match m {
        MotionType::Run => "#7a7a7a",
        MotionType::Crawl => "#8c510a",
        MotionType::Duck => "#1b7837",
        MotionType::Swim => "#2166ac",
        MotionType::Jump => "#c51b7d",
        MotionType::ClimbUp => "#5e3c99",
        MotionType::ClimbDown => "#01857a",
    }
}

pub(super) fn motion_label(m: MotionType) -> &'static str {
    match m {
        MotionType::Run => "run",
        MotionType::Crawl => "crawl",
        MotionType::Duck => "duck",
        MotionType::Swim => "swim",
        MotionType::Jump => "jump",
        MotionType::ClimbUp => "climb up",
        MotionType::ClimbDown => "climb down",
    }
}

pub(super) const BLOCKED_FILL: &str = "#9c9c9c";
pub(super) const UNREACHABLE_FILL: &str = "#d9d4e6";
pub(super) const OBSTACLE_FILL: &str = "#4d4d4d";
pub(super) const MOVING_FILL: &str = "#3f5a8c";
pub(super) const CHECKPOINT_STROKE: &str = "#008b8b";
pub(super) const ROUTE_STROKE: &str = "#1d3f7a";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_runs_from_near_white_to_dark_red() {
        assert_eq!(ramp(0.0), "#fffceb");
        assert_eq!(ramp(1.0), "#7f0000");
        assert_eq!(ramp(-1.0), ramp(0.0));
        assert_eq!(ramp(f64::NAN), ramp(0.0));
        assert_eq!(ramp(0.5), "#fc9254");
    }
}
