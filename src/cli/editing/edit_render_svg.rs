//! The edit picture's layout (margins, scale bounds, how many points are drawn) and
//! the few colours of its own; the rest of its look is `crowdtouch::picture`'s.

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
/// Bands of the time colour scale ([`crowdtouch::picture::scale::time`]).
pub const TIME_BANDS: usize = 12;
/// Tracks as they were before the edit.
pub const BEFORE_GREY: &str = "#b4b4b4";
/// The rim of a collision left after the edit.
pub const COLLISION_DARK: &str = "#7a0000";
/// Edges of a drag's deformation mesh.
pub const MESH_EDGE: &str = "#9aa9c4";
