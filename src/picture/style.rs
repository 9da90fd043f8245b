//! The one look: page and plot backgrounds, inks, type sizes, stroke widths and
//! the colours of the things several pictures draw.

/// Font of every picture.
pub const FONT_FAMILY: &str = "sans-serif";
/// Body text (labels, legends, captions) in px.
pub const BODY_PX: f64 = 13.0;
/// Title line in px.
pub const TITLE_PX: f64 = 15.0;
/// Small print (tick labels, second caption lines) in px.
pub const SMALL_PX: f64 = 12.0;

/// The page behind everything.
pub const PAGE: &str = "#fbfbf8";
/// The plotting area of a chart or a map.
pub const PLOT: &str = "#ffffff";
/// Titles and main labels.
pub const INK: &str = "#222222";
/// Captions and secondary labels.
pub const INK_SOFT: &str = "#555555";
/// Axis lines and tick labels.
pub const AXIS: &str = "#444444";
/// Grid lines.
pub const GRID: &str = "#e6e6e6";
/// Panel outlines.
pub const PANEL_EDGE: &str = "#dddddd";

/// Agents where they are (filled dots) and their routes.
pub const AGENT: &str = "#1d3f7a";
/// Agents where they started (hollow dots), sources, targets.
pub const AGENT_START: &str = "#808080";
/// Target points (where agents are to go).
pub const TARGET: &str = "#c0392b";
/// Paths walked, when not coloured by something else.
pub const PATH: &str = "#555555";
/// Fingers and touches.
pub const TOUCH: &str = "#d33333";
/// Something that went wrong (collisions, unmet targets).
pub const ALERT: &str = "#d62728";
/// Something held in place (fixed points).
pub const FIXED: &str = "#1f4e9c";
/// A deformation cage or handle.
pub const CAGE: &str = "#e07b00";
/// Static obstacles.
pub const OBSTACLE: &str = "#4d4d4d";
/// A mesh as it is now: stroke and fill.
pub const MESH_STROKE: &str = "#4a78c2";
/// A mesh's fill as it is now.
pub const MESH_FILL: &str = "#dbe8f7";
/// A mesh as it was (before a gesture): stroke only.
pub const MESH_BEFORE: &str = "#bbbbbb";
/// A formation's outline.
pub const OUTLINE: &str = "#1f4e8c";

/// Hairlines (grids, mesh edges) in px.
pub const HAIRLINE_PX: f64 = 0.7;
/// Ordinary lines (paths, axes) in px.
pub const LINE_PX: f64 = 1.0;
/// Emphasised lines (curves, outlines) in px.
pub const BOLD_PX: f64 = 2.0;
