//! Colours of the scene picture: motion types (colour and label) and the fixed
//! fills; the heat scale is `crowdtouch::picture::scale::heat`.

use crowdtouch::vocab::MotionType;

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
