//! Pictures: one way of drawing the project's SVG figures.
//!
//! Every `--svg` and `render` command of the binary (`replay --svg`, `scene render`,
//! `formations -o`, `transform --svg`, `transform compare --svg`, `edit render`)
//! draws through this module, so the figures in `docs/` share one look:
//!
//! * [`Canvas`]: the document, its page background and the primitives (circle,
//!   line, polyline, polygon, path, rect, text), each with a [`Paint`];
//! * [`Frame`]: world metres to page pixels, y down (the table's convention) or
//!   y up (tracks and formations), with a fixed scale;
//! * [`text`]: escaping and the number formats written into a document;
//! * [`scale`]: tick steps and labels, and the colour scales (heat, time,
//!   categorical series, subgroups);
//! * [`style`]: the palette and type sizes every picture uses;
//! * [`elements`]: the things several pictures draw — agents, tracks, hulls,
//!   meshes, obstacles (polygons and discs), metre axes, scale bars, chart axes
//!   and legends.
//!
//! It sits at the bottom beside `geom` (it only knows `Vec2` and `Rect`), so the
//! library's tests can draw with it as well as the binary. Output is a pure
//! function of the input: no clock, no randomness, fixed number formats, so the
//! same input gives the same bytes.

pub mod canvas;
pub mod elements;
pub mod scale;
pub mod style;
pub mod text;

pub use canvas::{Canvas, Frame, Paint, PathData};
