//! Formation shapes the crowd switches between (mesh-formation-control section 7.3;
//! formation-transform section 3.1).
//!
//! "A set of mesh shapes is registered to define formations that the crowd can switch
//! between", and "the formation is switched when the crowd pass over pre-defined
//! checkpoints embedded in the environment". A [`Formation`] is such a shape in its
//! own frame, `+x` the direction the crowd heads: one or more pieces (a "two groups"
//! shape), each a simple polygon (convex or not) with holes (a ring). It is drawn
//! either as polygons ([`FormationDef::outline`], [`FormationDef::holes`],
//! [`FormationDef::pieces`]) or as an image whose pixels in a colour range are the
//! shape ([`FormationDef::bitmap`], see [`BitmapDef`]; formation-transform eq. 1).
//! Only the shape matters unless a bitmap gives its size in metres: when the crowd
//! switches, the shape is scaled to the crowd's current area (so the density of
//! agents stays), turned to its heading and centred on it ([`Placement`]), then
//! meshed ([`Formation::mesh`]) or sampled ([`Formation::sample`]).
//!
//! ```text
//!   arrow (+x: heading)        ring             two groups
//!        ╲                    ┌──────┐         ┌──┐   ┌──┐
//!     ╲   ╲──▶ tip            │ ┌──┐ │         │  │   │  │
//!     ╱   ╱                   │ └──┘ │         └──┘   └──┘
//!        ╱                    └──────┘
//! ```
//!
//! Definitions are validated ([`Formation::from_def`]): a name; exactly one of a
//! polygon shape and a bitmap; every ring 3 to [`MAX_OUTLINE_VERTICES`] finite
//! vertices, no repeated vertex, no two edges crossing or touching except neighbours
//! at their shared vertex, a non-zero area; holes inside their outline and outside
//! each other; pieces apart. Bitmaps: readable, not too large, selecting some pixels
//! but not all.

use super::bitmap::{self, BitmapDef, ImageError, MAX_IMAGE_SIDE, MAX_PIECES, MAX_TRACED_VERTICES};
use super::region::{self, Piece, Problem, RegionIndex, Ring};
use crate::crowd::mesh::{MeshError, TriMesh};
use crate::geom::{twice_signed_area, Rect, Vec2};
use serde::{Deserialize, Serialize};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// Most vertices in one drawn ring (outline or hole).
pub const MAX_OUTLINE_VERTICES: usize = 256;
/// Most holes, and most pieces, of a drawn shape.
pub const MAX_RINGS: usize = 64;
/// Most shapes in the config's `formations.shapes`.
pub const MAX_FORMATIONS: usize = 64;
/// Most mesh vertices [`Formation::mesh`] is asked for.
pub const MAX_MESH_VERTICES: usize = 40_000;
/// Default `λ` of the least-effort pairing when the formation switches
/// (formation-transform eq. 3: equal weight on travel and on local structure).
pub const DEFAULT_LAMBDA: f64 = 0.5;
/// Name of the formation the crowd starts in (the config's `crowd.formation`
/// rectangle with its `mesh.cols × mesh.rows` grid).
pub const START: &str = "start";
/// Lattice points closer than this fraction of the spacing to the outline are left
/// out, so no triangle is a sliver against the boundary (dimensionless).
const CLEARANCE: f64 = 0.45;
/// A traced bitmap's staircase is simplified to within this many pixels.
const SIMPLIFY_PX: f64 = 0.5;

/// One formation shape as written in the config or in `config/formations/`.
///
/// A polygon shape is `outline` (with its `holes`) and/or `pieces`; a bitmap shape
/// is `bitmap` alone. Units of a polygon are free: it is scaled to the crowd's area.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FormationDef {
    /// Name a scene checkpoint uses.
    pub name: String,
    /// The first piece's outline, a simple polygon in either winding, `+x` the
    /// heading. Empty when the shape is `pieces` alone or a bitmap.
    #[serde(default)]
    pub outline: Vec<(f64, f64)>,
    /// Holes in `outline`, each a simple polygon inside it.
    #[serde(default)]
    pub holes: Vec<Vec<(f64, f64)>>,
    /// Further pieces, apart from `outline` and from each other.
    #[serde(default)]
    pub pieces: Vec<PieceDef>,
    /// The shape as an image instead of polygons.
    #[serde(default)]
    pub bitmap: Option<BitmapDef>,
}

impl FormationDef {
    /// The rectangle `r` as a shape named `name`: its corners counter-clockwise from
    /// the minimum one.
    pub fn rectangle(name: &str, r: Rect) -> FormationDef {
        FormationDef::polygon(
            name,
            &[
                (r.min[0], r.min[1]),
                (r.max[0], r.min[1]),
                (r.max[0], r.max[1]),
                (r.min[0], r.max[1]),
            ],
        )
    }

    /// The polygon `outline` (no holes, one piece) as a shape named `name`.
    pub fn polygon(name: &str, outline: &[(f64, f64)]) -> FormationDef {
        FormationDef {
            name: name.to_string(),
            outline: outline.to_vec(),
            ..FormationDef::default()
        }
    }
}

/// One more piece of a polygon shape.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PieceDef {
    /// Its outline.
    pub outline: Vec<(f64, f64)>,
    /// Its holes.
    #[serde(default)]
    pub holes: Vec<Vec<(f64, f64)>>,
}

/// What is wrong with a formation definition. Rings are named by [`Ring`]
/// (`outline`, `hole 1`, `piece 2's outline`, …); edge `k` runs from vertex `k` to
/// `k + 1`.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FormationError {
    /// The name is empty.
    #[error("a formation needs a name")]
    EmptyName,
    /// The name is the reserved start name.
    #[error("`{START}` is the formation the crowd starts in (crowd.formation); pick another name")]
    ReservedName,
    /// Neither polygons nor a bitmap.
    #[error("a formation needs an outline, pieces or a bitmap")]
    NoShape,
    /// Both polygons and a bitmap.
    #[error("a formation is either polygons (outline, holes, pieces) or a bitmap, not both")]
    BothShapes,
    /// Holes without an outline.
    #[error("holes need an outline to be in")]
    HolesWithoutOutline,
    /// Too many holes or pieces.
    #[error("at most {max} {what}, got {got}", max = MAX_RINGS)]
    TooManyRings {
        /// `holes` or `pieces`.
        what: &'static str,
        /// Given.
        got: usize,
    },
    /// Too few or too many vertices.
    #[error("{at}: a ring needs 3 to {max} vertices, got {got}", max = MAX_OUTLINE_VERTICES)]
    VertexCount {
        /// The ring.
        at: Ring,
        /// Vertices given.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{at}: vertex {vertex} is not finite")]
    NonFinite {
        /// The ring.
        at: Ring,
        /// Index in the ring.
        vertex: usize,
    },
    /// Two vertices are at the same place.
    #[error("{at}: vertices {a} and {b} are at the same place")]
    Repeated {
        /// The ring.
        at: Ring,
        /// First index.
        a: usize,
        /// Second index.
        b: usize,
    },
    /// Two edges of one ring cross or touch.
    #[error("{at}: edges {a} and {b} cross or touch: a ring must be a simple polygon (edge k runs from vertex k to k+1)")]
    SelfIntersecting {
        /// The ring.
        at: Ring,
        /// First edge.
        a: usize,
        /// Second edge.
        b: usize,
    },
    /// Edges of two rings cross or touch.
    #[error("{a} (edge {edge_a}) and {b} (edge {edge_b}) cross or touch")]
    RingsCross {
        /// First ring.
        a: Ring,
        /// Its edge.
        edge_a: usize,
        /// Second ring.
        b: Ring,
        /// Its edge.
        edge_b: usize,
    },
    /// A ring encloses (almost) no area.
    #[error("{at} encloses no area")]
    NoArea {
        /// The ring.
        at: Ring,
    },
    /// A hole is outside its outline.
    #[error("{hole} is outside its outline")]
    HoleOutside {
        /// The hole.
        hole: Ring,
    },
    /// A hole is inside another.
    #[error("{inner} is inside {outer}")]
    HolesNested {
        /// The inner hole.
        inner: Ring,
        /// The one around it.
        outer: Ring,
    },
    /// A piece is inside another.
    #[error("pieces {a} and {b} overlap (one lies inside the other)")]
    PiecesOverlap {
        /// First piece (0: `outline`).
        a: usize,
        /// Second piece.
        b: usize,
    },
    /// The bitmap file could not be read or decoded.
    #[error("bitmap {path}: {message}")]
    Image {
        /// The file as written.
        path: String,
        /// The reader's or decoder's message.
        message: String,
    },
    /// The bitmap is larger than [`MAX_IMAGE_SIDE`] on a side.
    #[error("bitmap {path}: {width}×{height} pixels, at most {max}×{max}", max = MAX_IMAGE_SIDE)]
    ImageTooLarge {
        /// The file.
        path: String,
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// `c_min` above `c_max` in a channel.
    #[error("bitmap {path}: c_min {c_min:?} is above c_max {c_max:?} in a channel")]
    EmptyRange {
        /// The file.
        path: String,
        /// Lowest colour.
        c_min: (u8, u8, u8),
        /// Highest colour.
        c_max: (u8, u8, u8),
    },
    /// The colour range selects no pixel.
    #[error("bitmap {path}: no pixel has a colour in {c_min:?} ..= {c_max:?} (eq. 1), or every such pixel is transparent")]
    NothingSelected {
        /// The file.
        path: String,
        /// Lowest colour.
        c_min: (u8, u8, u8),
        /// Highest colour.
        c_max: (u8, u8, u8),
    },
    /// The colour range selects every pixel.
    #[error("bitmap {path}: the colour range {c_min:?} ..= {c_max:?} selects all {pixels} pixels; the shape would be the whole image")]
    EverythingSelected {
        /// The file.
        path: String,
        /// Lowest colour.
        c_min: (u8, u8, u8),
        /// Highest colour.
        c_max: (u8, u8, u8),
        /// Pixels in the image.
        pixels: usize,
    },
    /// `size_m` is not two finite positive lengths.
    #[error("bitmap {path}: size_m {size:?} must be two finite lengths > 0 (m)")]
    BadSize {
        /// The file.
        path: String,
        /// As given.
        size: (f64, f64),
    },
    /// The traced shape is too detailed.
    #[error("bitmap {path}: {got} {what}; at most {max}")]
    TooDetailed {
        /// The file.
        path: String,
        /// `boundary vertices` or `separate pieces`.
        what: &'static str,
        /// Found.
        got: usize,
        /// Allowed.
        max: usize,
    },
    /// The traced shape is not a valid region (the first problem, in image pixels,
    /// `+y` up from the bottom-left corner).
    #[error("bitmap {path}: the traced shape is not usable: {problem}")]
    BadTrace {
        /// The file.
        path: String,
        /// What is wrong.
        problem: Box<FormationError>,
    },
}

impl FormationError {
    /// The field of [`FormationDef`] the problem is in (`name`, `outline`, `holes`,
    /// `pieces` or `bitmap`).
    pub fn field(&self) -> &'static str {
        use FormationError as E;
        let ring = |r: &Ring| match r {
            Ring::Outline(0) => "outline",
            Ring::Hole(0, _) => "holes",
            _ => "pieces",
        };
        match self {
            E::EmptyName | E::ReservedName => "name",
            E::NoShape | E::BothShapes => "",
            E::HolesWithoutOutline => "holes",
            E::TooManyRings { what, .. } => what,
            E::VertexCount { at, .. }
            | E::NonFinite { at, .. }
            | E::Repeated { at, .. }
            | E::SelfIntersecting { at, .. }
            | E::NoArea { at } => ring(at),
            E::RingsCross { b, .. } => ring(b),
            E::HoleOutside { hole: r } | E::HolesNested { inner: r, .. } => ring(r),
            E::PiecesOverlap { .. } => "pieces",
            _ => "bitmap",
        }
    }
}

impl From<Problem> for FormationError {
    fn from(p: Problem) -> FormationError {
        use FormationError as E;
        match p {
            Problem::Repeated { ring, a, b } => E::Repeated { at: ring, a, b },
            Problem::SelfIntersecting { ring, a, b } => E::SelfIntersecting { at: ring, a, b },
            Problem::NoArea { ring } => E::NoArea { at: ring },
            Problem::RingsCross {
                a,
                edge_a,
                b,
                edge_b,
            } => E::RingsCross {
                a,
                edge_a,
                b,
                edge_b,
            },
            Problem::HoleOutside { hole } => E::HoleOutside { hole },
            Problem::HolesNested { inner, outer } => E::HolesNested { inner, outer },
            Problem::PiecesOverlap { a, b } => E::PiecesOverlap { a, b },
        }
    }
}

/// A validated formation shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Formation {
    name: String,
    /// Outlines counter-clockwise, holes clockwise, centroid at the origin, total
    /// area 1.
    pieces: Vec<Piece>,
    /// The area in m² when the shape has a size of its own (a bitmap with
    /// `size_m`); `None`: laid out at the placement's area.
    fixed_area_m2: Option<f64>,
    /// Inside tests and nearest boundary points on `pieces`.
    pub(super) index: RegionIndex,
}

/// Where and how large a formation is laid out.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Placement {
    /// Where the formation's centroid goes (m).
    pub centre_m: Vec2,
    /// The direction its `+x` axis points (any length > 0; zero or non-finite: `+x`).
    pub heading: Vec2,
    /// Its area (m²); ignored by a formation of fixed size.
    pub area_m2: f64,
}

/// A reader of the files a definition names (bitmaps): the bytes, or a message.
pub type FileReader<'a> = &'a dyn Fn(&str) -> Result<Vec<u8>, String>;

/// The reader [`Formation::new`] uses: it reads nothing.
fn no_files(path: &str) -> Result<Vec<u8>, String> {
    Err(format!(
        "no file reader here to read {path} (bitmaps load with a config or from config/formations)"
    ))
}

fn to_ring(at: Ring, pts: &[(f64, f64)]) -> Result<Vec<Vec2>, FormationError> {
    if !(3..=MAX_OUTLINE_VERTICES).contains(&pts.len()) {
        return Err(FormationError::VertexCount { at, got: pts.len() });
    }
    if let Some(vertex) = pts
        .iter()
        .position(|&(x, y)| !(x.is_finite() && y.is_finite()))
    {
        return Err(FormationError::NonFinite { at, vertex });
    }
    Ok(pts.iter().map(|&(x, y)| Vec2::new(x, y)).collect())
}

/// Validates `pieces` (any scale, any winding) and normalises them: outlines
/// counter-clockwise, holes clockwise, centroid at the origin, area 1. Returns the
/// area before normalising too.
fn normalise(mut pieces: Vec<Piece>) -> Result<(Vec<Piece>, f64), FormationError> {
    // Work relative to the first vertex and in units of the extent, so the exact
    // tests do not depend on where or how large the shape was drawn.
    let o = pieces[0].outline[0];
    let extent = region::rings(&pieces)
        .flat_map(|(_, r)| r.iter().map(|q| (q - o).amax()))
        .fold(0.0f64, f64::max);
    if !(extent > 0.0 && extent.is_finite()) {
        return Err(FormationError::NoArea {
            at: Ring::Outline(0),
        });
    }
    for k in &mut pieces {
        for q in k.outline.iter_mut().chain(k.holes.iter_mut().flatten()) {
            *q = (*q - o) / extent;
        }
    }
    region::check(&pieces)?;
    for k in &mut pieces {
        if twice_signed_area(&k.outline) < 0.0 {
            k.outline.reverse();
        }
        for h in &mut k.holes {
            if twice_signed_area(h) > 0.0 {
                h.reverse();
            }
        }
    }
    let (a2, m) = region::area_and_moment(&pieces);
    if a2.is_nan() || a2 <= 1e-9 {
        return Err(FormationError::NoArea {
            at: Ring::Outline(0),
        });
    }
    let c = m / (3.0 * a2);
    let s = (0.5 * a2).sqrt();
    for k in &mut pieces {
        for q in k.outline.iter_mut().chain(k.holes.iter_mut().flatten()) {
            *q = (*q - c) / s;
        }
    }
    Ok((pieces, 0.5 * a2 * extent * extent))
}

impl Formation {
    /// Validates a polygon definition and normalises it (see [`Formation::from_def`]);
    /// a bitmap definition is refused here as its file cannot be read.
    ///
    /// # Errors
    /// The first [`FormationError`] found.
    pub fn new(def: &FormationDef) -> Result<Formation, FormationError> {
        Formation::from_def(def, &no_files)
    }

    /// Validates a definition, reading a bitmap's file through `read`, and
    /// normalises the shape: outlines counter-clockwise, holes clockwise, centroid
    /// of the whole at the origin, total area 1.
    ///
    /// # Errors
    /// The first [`FormationError`] found.
    pub fn from_def(def: &FormationDef, read: FileReader<'_>) -> Result<Formation, FormationError> {
        if def.name.trim().is_empty() {
            return Err(FormationError::EmptyName);
        }
        if def.name == START {
            return Err(FormationError::ReservedName);
        }
        let polygons = !def.outline.is_empty() || !def.pieces.is_empty() || !def.holes.is_empty();
        match (&def.bitmap, polygons) {
            (Some(_), true) => Err(FormationError::BothShapes),
            (None, false) => Err(FormationError::NoShape),
            (Some(b), false) => {
                let bytes = read(&b.path).map_err(|message| FormationError::Image {
                    path: b.path.clone(),
                    message,
                })?;
                Formation::from_bitmap(&def.name, &bytes, b)
            }
            (None, true) => {
                if def.outline.is_empty() && !def.holes.is_empty() {
                    return Err(FormationError::HolesWithoutOutline);
                }
                if def.holes.len() > MAX_RINGS {
                    return Err(FormationError::TooManyRings {
                        what: "holes",
                        got: def.holes.len(),
                    });
                }
                if def.pieces.len() + 1 > MAX_RINGS {
                    return Err(FormationError::TooManyRings {
                        what: "pieces",
                        got: def.pieces.len(),
                    });
                }
                let first = (!def.outline.is_empty())
                    .then_some((def.outline.as_slice(), def.holes.as_slice()));
                let rest = def
                    .pieces
                    .iter()
                    .map(|p| (p.outline.as_slice(), p.holes.as_slice()));
                let mut pieces = Vec::new();
                // Piece numbers as written: `outline` is piece 0, `pieces[i]` is i + 1.
                let offset = usize::from(first.is_none());
                for (i, (outline, holes)) in first.into_iter().chain(rest).enumerate() {
                    let p = i + offset;
                    if holes.len() > MAX_RINGS {
                        return Err(FormationError::TooManyRings {
                            what: "holes",
                            got: holes.len(),
                        });
                    }
                    let outline = to_ring(Ring::Outline(p), outline)?;
                    let holes = holes
                        .iter()
                        .enumerate()
                        .map(|(h, r)| to_ring(Ring::Hole(p, h), r))
                        .collect::<Result<Vec<_>, _>>()?;
                    pieces.push(Piece { outline, holes });
                }
                let renumber = |e: FormationError| if offset == 0 { e } else { renumber_pieces(e) };
                let (pieces, _) = normalise(pieces).map_err(renumber)?;
                Ok(Formation::from_pieces(def.name.clone(), pieces, None))
            }
        }
    }

    /// A formation from image bytes (PNG or PGM) and its colour range (eq. 1).
    ///
    /// # Errors
    /// An unreadable or too large image, an empty range, no pixel or every pixel
    /// selected, a bad `size_m`, a traced shape too detailed or not valid.
    pub fn from_bitmap(
        name: &str,
        bytes: &[u8],
        b: &BitmapDef,
    ) -> Result<Formation, FormationError> {
        let path = || b.path.clone();
        if b.c_min.0 > b.c_max.0 || b.c_min.1 > b.c_max.1 || b.c_min.2 > b.c_max.2 {
            return Err(FormationError::EmptyRange {
                path: path(),
                c_min: b.c_min,
                c_max: b.c_max,
            });
        }
        if let Some(size) = b.size_m {
            if !(size.0.is_finite() && size.1.is_finite() && size.0 > 0.0 && size.1 > 0.0) {
                return Err(FormationError::BadSize { path: path(), size });
            }
        }
        let img = bitmap::decode(bytes).map_err(|e| match e {
            ImageError::TooLarge { width, height } => FormationError::ImageTooLarge {
                path: path(),
                width,
                height,
            },
            ImageError::Decode(m) => FormationError::Image {
                path: path(),
                message: m,
            },
        })?;
        let mask = bitmap::select(&img, b.c_min, b.c_max);
        let count = mask.iter().filter(|&&m| m).count();
        if count == 0 {
            return Err(FormationError::NothingSelected {
                path: path(),
                c_min: b.c_min,
                c_max: b.c_max,
            });
        }
        if count == mask.len() {
            return Err(FormationError::EverythingSelected {
                path: path(),
                c_min: b.c_min,
                c_max: b.c_max,
                pixels: count,
            });
        }
        let (w, h) = (img.width as usize, img.height as usize);
        let scale = match b.size_m {
            Some((sw, sh)) => (sw / w as f64, sh / h as f64),
            None => (1.0, 1.0),
        };
        let trace = |tol: f64| {
            let pieces = bitmap::pieces_of(&mask, w, h, scale, tol).map_err(|(what, got)| {
                FormationError::TooDetailed {
                    path: path(),
                    what,
                    got,
                    max: if what == "separate pieces" {
                        MAX_PIECES
                    } else {
                        MAX_TRACED_VERTICES
                    },
                }
            })?;
            normalise(pieces).map_err(|e| FormationError::BadTrace {
                path: path(),
                problem: Box::new(e),
            })
        };
        // The simplified staircase when it is still valid, else the staircase.
        let (pieces, area) = match trace(SIMPLIFY_PX) {
            Ok(r) => r,
            Err(FormationError::BadTrace { .. }) => trace(0.0)?,
            Err(e) => return Err(e),
        };
        let fixed = b.size_m.map(|_| area);
        Ok(Formation::from_pieces(name.to_string(), pieces, fixed))
    }

    fn from_pieces(name: String, pieces: Vec<Piece>, fixed_area_m2: Option<f64>) -> Formation {
        let index = RegionIndex::new(&pieces);
        Formation {
            name,
            pieces,
            fixed_area_m2,
            index,
        }
    }

    /// Name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The first piece's normalised outline: counter-clockwise; with the other
    /// pieces and the holes, centroid at the origin and area 1.
    pub fn outline(&self) -> &[Vec2] {
        &self.pieces[0].outline
    }

    /// Every piece, normalised (outlines counter-clockwise, holes clockwise).
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// The area in m² when the shape has a size of its own (a bitmap with
    /// `size_m`).
    pub fn fixed_area_m2(&self) -> Option<f64> {
        self.fixed_area_m2
    }

    /// Vertices in every ring.
    pub fn vertex_count(&self) -> usize {
        region::rings(&self.pieces).map(|(_, r)| r.len()).sum()
    }

    /// Rotation `(cos, sin)` and scale (m per normalised unit) of `place`.
    pub(super) fn frame(&self, place: &Placement) -> (f64, f64, f64) {
        let h = place.heading;
        let n = h.norm();
        let (c, s) = if n > 0.0 && n.is_finite() {
            (h.x / n, h.y / n)
        } else {
            (1.0, 0.0)
        };
        let area = self.fixed_area_m2.unwrap_or(place.area_m2);
        let k = if area.is_finite() && area > 0.0 {
            area.sqrt()
        } else {
            1.0
        };
        (c, s, k)
    }

    /// A normalised point laid out at `place` (world frame, m).
    pub(super) fn to_world(&self, place: &Placement, (c, s, k): (f64, f64, f64), q: Vec2) -> Vec2 {
        place.centre_m + Vec2::new(c * q.x - s * q.y, s * q.x + c * q.y) * k
    }

    fn place_ring(&self, place: &Placement, r: &[Vec2]) -> Vec<Vec2> {
        let f = self.frame(place);
        r.iter().map(|&q| self.to_world(place, f, q)).collect()
    }

    /// The first piece's outline laid out at `place` (world frame, m,
    /// counter-clockwise).
    pub fn placed_outline(&self, place: &Placement) -> Vec<Vec2> {
        self.place_ring(place, self.outline())
    }

    /// Every piece laid out at `place` (world frame, m).
    pub fn placed_pieces(&self, place: &Placement) -> Vec<Piece> {
        self.pieces
            .iter()
            .map(|k| Piece {
                outline: self.place_ring(place, &k.outline),
                holes: k.holes.iter().map(|h| self.place_ring(place, h)).collect(),
            })
            .collect()
    }

    /// A triangle mesh of the formation laid out at `place`, with about `vertices`
    /// vertices (at least the rings'; at most [`MAX_MESH_VERTICES`]). Several
    /// pieces give a mesh of several pieces; no triangle lies in a hole.
    ///
    /// # Method
    /// With `A` the area and `P` the perimeter of every ring, the spacing `h` solves
    /// `A / h² + P / h = vertices` (lattice points inside plus points along the
    /// rings). Every ring edge gets `max(1, round(length / h))` equal pieces;
    /// lattice points of spacing `h` inside the region, at least `0.45 h` from its
    /// boundary, are added; the constrained Delaunay triangulation of all of them
    /// keeps every ring's edges, and its triangles inside the region (an odd number
    /// of ring edges crossed from outside) are the mesh.
    ///
    /// # Complexity
    /// `O(V · e)` for the clearance test (`e` edges near a point, through the
    /// region's cell grid), then `O(V log V)` expected for the triangulation.
    /// Allocates: meant for a formation switch.
    ///
    /// # Errors
    /// A [`MeshError`] when the triangulation does not give a valid mesh (a shape
    /// too thin for the spacing, or a placement that is not finite).
    pub fn mesh(&self, place: &Placement, vertices: usize) -> Result<TriMesh, MeshError> {
        let placed = self.placed_pieces(place);
        let mut vertex = 0;
        for (_, r) in region::rings(&placed) {
            if let Some(i) = r.iter().position(|p| !(p.x.is_finite() && p.y.is_finite())) {
                return Err(MeshError::NonFinite { vertex: vertex + i });
            }
            vertex += r.len();
        }
        let (a2, _) = region::area_and_moment(&placed);
        let area = 0.5 * a2;
        let mut perimeter = 0.0;
        for (_, r) in region::rings(&placed) {
            let n = r.len();
            perimeter += (0..n).map(|i| (r[(i + 1) % n] - r[i]).norm()).sum::<f64>();
        }
        let target = vertices.clamp(vertex, MAX_MESH_VERTICES.max(vertex)) as f64;
        let h = (perimeter + (perimeter * perimeter + 4.0 * target * area).sqrt()) / (2.0 * target);
        if !(h > 0.0 && h.is_finite()) {
            return Err(MeshError::NonFinite { vertex: 0 });
        }
        let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
            ConstrainedDelaunayTriangulation::new();
        let mut count = 0;
        for (_, r) in region::rings(&placed) {
            let n = r.len();
            let mut boundary = Vec::new();
            for i in 0..n {
                let (a, b) = (r[i], r[(i + 1) % n]);
                let pieces = ((b - a).norm() / h).round().max(1.0) as usize;
                boundary.extend((0..pieces).map(|j| a + (b - a) * (j as f64 / pieces as f64)));
            }
            let mut handles = Vec::with_capacity(boundary.len());
            for p in &boundary {
                match cdt.insert(Point2::new(p.x, p.y)) {
                    Ok(v) => handles.push(v),
                    Err(_) => return Err(MeshError::NonFinite { vertex: count }),
                }
                count += 1;
            }
            let m = handles.len();
            for k in 0..m {
                // Rings neither cross nor touch; should rounding make two pieces
                // touch, the edge is left to the plain triangulation.
                let _ = cdt.try_add_constraint(handles[k], handles[(k + 1) % m]);
            }
        }
        let index = RegionIndex::new(&placed);
        let (lo, hi) = index.bounds();
        // The lattice is centred on the placement so a symmetric shape gets a
        // symmetric mesh.
        let c = place.centre_m;
        let i0 = ((lo.x - c.x) / h).floor() as i64;
        let i1 = ((hi.x - c.x) / h).ceil() as i64;
        let j0 = ((lo.y - c.y) / h).floor() as i64;
        let j1 = ((hi.y - c.y) / h).ceil() as i64;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let p = c + Vec2::new(i as f64 * h, j as f64 * h);
                if index.inside(p) && index.nearest_boundary(p).1 >= CLEARANCE * h {
                    if cdt.insert(Point2::new(p.x, p.y)).is_err() {
                        return Err(MeshError::NonFinite { vertex: count });
                    }
                    count += 1;
                }
            }
        }
        let mut rest: Vec<Vec2> = cdt
            .vertices()
            .map(|v| {
                let p = v.position();
                Vec2::new(p.x, p.y)
            })
            .collect();
        let mut triangles = inside_faces(&cdt);
        // A mesh piece has one boundary loop: holes are opened by seams.
        if self.pieces.iter().any(|k| !k.holes.is_empty())
            && !super::seam::cut_holes(&mut rest, &mut triangles)
        {
            return Err(MeshError::BoundaryNotSingleLoop { vertex: 0 });
        }
        TriMesh::from_triangles(rest, triangles)
    }
}

/// `pieces` numbered from 1 in messages (a shape given as `pieces` alone: the
/// first is `pieces[0]`, called piece 1 as when an `outline` comes first).
fn renumber_pieces(e: FormationError) -> FormationError {
    let r = |r: Ring| match r {
        Ring::Outline(p) => Ring::Outline(p + 1),
        Ring::Hole(p, h) => Ring::Hole(p + 1, h),
    };
    use FormationError as E;
    match e {
        E::Repeated { at, a, b } => E::Repeated { at: r(at), a, b },
        E::SelfIntersecting { at, a, b } => E::SelfIntersecting { at: r(at), a, b },
        E::NoArea { at } => E::NoArea { at: r(at) },
        E::RingsCross {
            a,
            edge_a,
            b,
            edge_b,
        } => E::RingsCross {
            a: r(a),
            edge_a,
            b: r(b),
            edge_b,
        },
        E::HoleOutside { hole } => E::HoleOutside { hole: r(hole) },
        E::HolesNested { inner, outer } => E::HolesNested {
            inner: r(inner),
            outer: r(outer),
        },
        E::PiecesOverlap { a, b } => E::PiecesOverlap { a: a + 1, b: b + 1 },
        e => e,
    }
}

/// The triangles of `cdt` inside its constraint rings: a face's side flips each
/// time a path from the outer face crosses a constraint edge, found by a flood fill
/// from the faces on the convex hull. (A centroid test would misjudge the thin
/// faces between collinear outline points that lie outside.)
fn inside_faces(cdt: &ConstrainedDelaunayTriangulation<Point2<f64>>) -> Vec<[u32; 3]> {
    let mut side: Vec<Option<bool>> = vec![None; cdt.num_all_faces()];
    let mut stack = Vec::new();
    for f in cdt.inner_faces() {
        for e in f.adjacent_edges() {
            if e.rev().face().is_outer() {
                let crossing = cdt.is_constraint_edge(e.fix().as_undirected());
                side[f.fix().index()] = Some(crossing);
                stack.push(f.fix());
                break;
            }
        }
    }
    while let Some(fx) = stack.pop() {
        let f = cdt.face(fx);
        let here = side[fx.index()].unwrap_or(false);
        for e in f.adjacent_edges() {
            if let Some(nb) = e.rev().face().as_inner() {
                let k = nb.fix().index();
                if side[k].is_none() {
                    side[k] = Some(here != cdt.is_constraint_edge(e.fix().as_undirected()));
                    stack.push(nb.fix());
                }
            }
        }
    }
    cdt.inner_faces()
        .filter(|f| side[f.fix().index()] == Some(true))
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{cross, segment_distance_squared};
    use proptest::prelude::*;

    /// The shipped shapes, read from `config/formations` (the library embeds the
    /// same files; it is tested in `library.rs`).
    fn shipped() -> Vec<Formation> {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/config/formations");
        let read = |p: &str| std::fs::read(format!("{dir}/{p}")).map_err(|e| e.to_string());
        let mut names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        names.sort();
        names
            .iter()
            .map(|p| {
                let def: FormationDef =
                    ron::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
                Formation::from_def(&def, &read).unwrap()
            })
            .collect()
    }

    fn shipped_get(name: &str) -> Formation {
        shipped().into_iter().find(|f| f.name() == name).unwrap()
    }

    fn segment_distance(a: Vec2, b: Vec2, p: Vec2) -> f64 {
        segment_distance_squared(p, a, b).sqrt()
    }

    fn place(x: f64, y: f64, hx: f64, hy: f64, area: f64) -> Placement {
        Placement {
            centre_m: Vec2::new(x, y),
            heading: Vec2::new(hx, hy),
            area_m2: area,
        }
    }

    /// Every mesh vertex on or inside the placed outline, area as asked, vertex count
    /// near the request, the mesh's own invariants.
    fn check_mesh(f: &Formation, p: &Placement, vertices: usize) -> TriMesh {
        let m = f
            .mesh(p, vertices)
            .unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        m.sanity_check().unwrap();
        let placed = f.placed_pieces(p);
        for (i, v) in m.rest().iter().enumerate() {
            let d = region::rings(&placed)
                .flat_map(|(_, r)| {
                    let n = r.len();
                    (0..n).map(move |k| segment_distance(r[k], r[(k + 1) % n], *v))
                })
                .fold(f64::INFINITY, f64::min);
            let inside = placed.iter().any(|k| {
                region::inside_ring(&k.outline, *v)
                    && !k.holes.iter().any(|h| region::inside_ring(h, *v))
            });
            assert!(
                inside || d < 1e-9 * p.area_m2.sqrt(),
                "{}: vertex {i} {v:?} outside",
                f.name()
            );
        }
        // No triangle's centroid in a hole or outside.
        for t in m.triangles() {
            let c = t.iter().map(|&k| m.rest()[k as usize]).sum::<Vec2>() / 3.0;
            assert!(
                placed.iter().any(|k| region::inside_ring(&k.outline, c)
                    && !k.holes.iter().any(|h| region::inside_ring(h, c))),
                "{}: triangle {t:?} outside the region",
                f.name()
            );
        }
        let rel = (m.area() - p.area_m2).abs() / p.area_m2;
        assert!(
            rel < 1e-9,
            "{}: area {} vs {}",
            f.name(),
            m.area(),
            p.area_m2
        );
        m
    }

    #[test]
    fn shipped_shapes_are_valid_and_mesh_at_the_asked_size_and_place() {
        let all = shipped();
        assert_eq!(all.len(), 11);
        for f in &all {
            let name = f.name();
            let (a2, m) = region::area_and_moment(f.pieces());
            assert!((0.5 * a2 - 1.0).abs() < 1e-12, "{name}");
            assert!(m.norm() < 1e-9, "{name}: centroid moment {m:?}");
            let p = place(8.0, 4.5, 1.0, 0.0, 12.0);
            let m = check_mesh(f, &p, 100);
            let v = m.vertex_count();
            // A traced bitmap's rings alone may have more vertices than asked.
            assert!(
                (60..=140).contains(&v) || (f.vertex_count() > 60 && v < f.vertex_count() + 140),
                "{}: {v} vertices for 100",
                f.name()
            );
            let c = m.rest().iter().sum::<Vec2>() / v as f64;
            assert!((c - p.centre_m).norm() < 0.6, "{}: centre {c:?}", f.name());
        }
    }

    #[test]
    fn the_heading_turns_the_shape() {
        let arrow = &shipped_get("arrow");
        // Heading +y: the tip (the farthest point ahead) is straight above the centre.
        let p = place(0.0, 0.0, 0.0, 2.0, 4.0);
        let poly = arrow.placed_outline(&p);
        let tip = poly
            .iter()
            .copied()
            .max_by(|a, b| a.y.total_cmp(&b.y))
            .unwrap();
        assert!(tip.x.abs() < 1e-12 && tip.y > 1.0, "tip {tip:?}");
        // A column headed along x is four times longer in x than in y.
        let col = &shipped_get("column");
        let m = check_mesh(col, &place(0.0, 0.0, 1.0, 0.0, 4.0), 80);
        let (lo, hi) = m.rest().iter().fold(
            (Vec2::repeat(f64::MAX), Vec2::repeat(f64::MIN)),
            |(l, h), p| (l.inf(p), h.sup(p)),
        );
        let ext = hi - lo;
        assert!((ext.x / ext.y - 4.0).abs() < 1e-9, "{ext:?}");
        // Zero heading: +x.
        let z = arrow.placed_outline(&place(0.0, 0.0, 0.0, 0.0, 1.0));
        let tip = z
            .iter()
            .copied()
            .max_by(|a, b| a.x.total_cmp(&b.x))
            .unwrap();
        assert!(tip.y.abs() < 1e-12);
    }

    #[test]
    fn the_arrows_notch_stays_open() {
        let arrow = shipped_get("arrow");
        let p = place(0.0, 0.0, 1.0, 0.0, 10.0);
        let m = check_mesh(&arrow, &p, 200);
        // The notch vertex (outline vertex 2 of the definition, at the tail) is on
        // the outline and no triangle covers the notch between it and the tail tips.
        let poly = arrow.placed_outline(&p);
        let notch = poly
            .iter()
            .copied()
            .filter(|q| q.y.abs() < 1e-9)
            .min_by(|a, b| a.x.total_cmp(&b.x))
            .unwrap();
        let probe = notch - Vec2::new(0.1, 0.0);
        for t in m.triangles() {
            let [a, b, c] = t.map(|v| m.rest()[v as usize]);
            let o = |p: Vec2, q: Vec2| cross(q - p, probe - p) >= 0.0;
            assert!(
                !(o(a, b) && o(b, c) && o(c, a)),
                "a triangle covers the notch"
            );
        }
    }

    #[test]
    fn bad_definitions_are_named() {
        const O: Ring = Ring::Outline(0);
        let cases: &[(FormationDef, FormationError)] = &[
            (
                FormationDef::polygon("", &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::EmptyName,
            ),
            (
                FormationDef::polygon("start", &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::ReservedName,
            ),
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (1.0, 0.0)]),
                FormationError::VertexCount { at: O, got: 2 },
            ),
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (f64::NAN, 0.0), (0.0, 1.0)]),
                FormationError::NonFinite { at: O, vertex: 1 },
            ),
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (1.0, 0.0), (0.0, 0.0), (0.0, 1.0)]),
                FormationError::Repeated { at: O, a: 0, b: 2 },
            ),
            // A bow tie.
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]),
                FormationError::SelfIntersecting { at: O, a: 0, b: 2 },
            ),
            // Collinear.
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]),
                FormationError::SelfIntersecting { at: O, a: 0, b: 2 },
            ),
            // A spike folding back on its own edge.
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (2.0, 0.0), (1.0, 0.0), (1.0, 1.0)]),
                FormationError::SelfIntersecting { at: O, a: 0, b: 1 },
            ),
            // Scale is free (a tiny triangle is fine), but a sliver has no area.
            (
                FormationDef::polygon("a", &[(0.0, 0.0), (1.0, 0.0), (0.5, 1e-12)]),
                FormationError::NoArea { at: O },
            ),
        ];
        for (d, want) in cases {
            assert_eq!(Formation::new(d).as_ref().err(), Some(want), "{d:?}");
        }
        // Either winding is fine and gives the same shape.
        let cw = Formation::new(&FormationDef::polygon(
            "t",
            &[(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)],
        ))
        .unwrap();
        let ccw = Formation::new(&FormationDef::polygon(
            "t",
            &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)],
        ))
        .unwrap();
        assert!(twice_signed_area(cw.outline()) > 0.0);
        let mut a: Vec<_> = cw.outline().iter().map(|p| (p.x, p.y)).collect();
        let mut b: Vec<_> = ccw.outline().iter().map(|p| (p.x, p.y)).collect();
        a.sort_by(|p, q| p.partial_cmp(q).unwrap());
        b.sort_by(|p, q| p.partial_cmp(q).unwrap());
        for (p, q) in a.iter().zip(&b) {
            assert!((p.0 - q.0).abs() < 1e-12 && (p.1 - q.1).abs() < 1e-12);
        }
    }

    fn sq(c: (f64, f64), r: f64) -> Vec<(f64, f64)> {
        vec![
            (c.0 - r, c.1 - r),
            (c.0 + r, c.1 - r),
            (c.0 + r, c.1 + r),
            (c.0 - r, c.1 + r),
        ]
    }

    fn holed(outline: Vec<(f64, f64)>, holes: Vec<Vec<(f64, f64)>>) -> FormationDef {
        FormationDef {
            name: "h".into(),
            outline,
            holes,
            ..FormationDef::default()
        }
    }

    #[test]
    fn a_ring_meshes_without_a_triangle_in_its_hole_and_two_groups_in_two_pieces() {
        let ring = &shipped_get("ring");
        let p = place(2.0, 1.0, 0.0, 1.0, 30.0);
        let m = check_mesh(ring, &p, 300);
        // The hole's centre (the placement centre) is in no triangle.
        for t in m.triangles() {
            let [a, b, c] = t.map(|v| m.rest()[v as usize]);
            let q = p.centre_m;
            let o = |u: Vec2, v: Vec2| cross(v - u, q - u) >= 0.0;
            assert!(
                !(o(a, b) && o(b, c) && o(c, a)),
                "a triangle covers the hole"
            );
        }
        let two = &shipped_get("two_groups");
        let m = check_mesh(two, &p, 200);
        // No triangle has corners in both groups (their gap is empty): split the
        // vertices by the side of the heading axis.
        let side = |v: Vec2| (v - p.centre_m).x > 0.0;
        for t in m.triangles() {
            let s: Vec<bool> = t.iter().map(|&k| side(m.rest()[k as usize])).collect();
            assert!(
                s.iter().all(|&x| x == s[0]),
                "a triangle bridges the two groups"
            );
        }
        check_mesh(&shipped_get("letter_a"), &p, 250);
        check_mesh(&shipped_get("heart"), &p, 250);
    }

    #[test]
    fn bad_holes_and_pieces_are_named() {
        let big = sq((0.0, 0.0), 2.0);
        let cases: Vec<(FormationDef, FormationError)> = vec![
            (
                holed(big.clone(), vec![sq((5.0, 0.0), 0.5)]),
                FormationError::HoleOutside {
                    hole: Ring::Hole(0, 0),
                },
            ),
            (
                holed(big.clone(), vec![sq((1.8, 0.0), 0.5)]),
                FormationError::RingsCross {
                    a: Ring::Outline(0),
                    edge_a: 1,
                    b: Ring::Hole(0, 0),
                    edge_b: 0,
                },
            ),
            (
                holed(big.clone(), vec![sq((0.0, 0.0), 1.0), sq((0.0, 0.0), 0.5)]),
                FormationError::HolesNested {
                    inner: Ring::Hole(0, 1),
                    outer: Ring::Hole(0, 0),
                },
            ),
            (
                holed(big.clone(), vec![sq((0.0, 0.0), 0.5), sq((0.5, 0.0), 0.5)]),
                FormationError::RingsCross {
                    a: Ring::Hole(0, 0),
                    edge_a: 0,
                    b: Ring::Hole(0, 1),
                    edge_b: 0,
                },
            ),
            (
                holed(
                    big.clone(),
                    vec![vec![(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]],
                ),
                FormationError::SelfIntersecting {
                    at: Ring::Hole(0, 0),
                    a: 0,
                    b: 2,
                },
            ),
            (
                FormationDef {
                    pieces: vec![PieceDef {
                        outline: sq((0.0, 0.0), 0.5),
                        holes: vec![],
                    }],
                    ..holed(big.clone(), vec![])
                },
                FormationError::PiecesOverlap { a: 0, b: 1 },
            ),
            (
                FormationDef {
                    pieces: vec![
                        PieceDef {
                            outline: sq((0.0, 0.0), 1.0),
                            holes: vec![],
                        },
                        PieceDef {
                            outline: sq((5.0, 0.0), 1.0),
                            holes: vec![vec![(4.0, 0.0), (6.0, 0.0), (5.0, 0.0)]],
                        },
                    ],
                    ..FormationDef {
                        name: "p".into(),
                        ..FormationDef::default()
                    }
                },
                FormationError::RingsCross {
                    a: Ring::Outline(2),
                    edge_a: 1,
                    b: Ring::Hole(2, 0),
                    edge_b: 0,
                },
            ),
            (
                holed(vec![], vec![sq((0.0, 0.0), 1.0)]),
                FormationError::HolesWithoutOutline,
            ),
            (holed(vec![], vec![]), FormationError::NoShape),
            (
                FormationDef {
                    bitmap: Some(BitmapDef {
                        path: "x.pgm".into(),
                        c_min: (0, 0, 0),
                        c_max: (9, 9, 9),
                        size_m: None,
                    }),
                    ..holed(big.clone(), vec![])
                },
                FormationError::BothShapes,
            ),
        ];
        for (d, want) in &cases {
            assert_eq!(Formation::new(d).as_ref().err(), Some(want), "{d:?}");
            assert!(!want.to_string().is_empty());
        }
        assert_eq!(cases[0].1.field(), "holes");
        assert_eq!(cases[5].1.field(), "pieces");
        assert_eq!(cases[0].1.to_string(), "hole 0 is outside its outline");
        assert_eq!(
            cases[6].1.to_string(),
            "piece 2's outline (edge 1) and piece 2's hole 0 (edge 0) cross or touch"
        );
    }

    fn pgm(w: usize, h: usize, f: impl Fn(usize, usize) -> u8) -> Vec<u8> {
        let mut b = format!("P5 {w} {h} 255\n").into_bytes();
        for y in 0..h {
            for x in 0..w {
                b.push(f(x, y));
            }
        }
        b
    }

    fn bm(c_min: (u8, u8, u8), c_max: (u8, u8, u8), size_m: Option<(f64, f64)>) -> BitmapDef {
        BitmapDef {
            path: "dir/shape.pgm".into(),
            c_min,
            c_max,
            size_m,
        }
    }

    #[test]
    fn bitmaps_become_shapes_and_bad_ones_are_named() {
        // A dark 20×10 block with a 4×4 hole, on a white 40×20 image.
        let img = pgm(40, 20, |x, y| {
            let block = (10..30).contains(&x) && (5..15).contains(&y);
            let hole = (18..22).contains(&x) && (8..12).contains(&y);
            if block && !hole {
                20
            } else {
                240
            }
        });
        let dark = bm((0, 0, 0), (100, 100, 100), Some((8.0, 4.0)));
        let f = Formation::from_bitmap("b", &img, &dark).unwrap();
        assert_eq!(f.pieces().len(), 1);
        assert_eq!(f.pieces()[0].holes.len(), 1);
        // 200 - 16 pixels of 0.2 m × 0.2 m.
        assert!((f.fixed_area_m2().unwrap() - 184.0 * 0.04).abs() < 1e-9);
        // The fixed size wins over the placement's area.
        let m = f.mesh(&place(0.0, 0.0, 1.0, 0.0, 100.0), 120).unwrap();
        assert!((m.area() - 7.36).abs() < 1e-9, "{}", m.area());
        // Through a reader, as a config does; the path is the one written.
        let d = FormationDef {
            name: "b".into(),
            bitmap: Some(dark.clone()),
            ..FormationDef::default()
        };
        let read = |p: &str| {
            if p == "dir/shape.pgm" {
                Ok(img.clone())
            } else {
                Err(format!("no {p}"))
            }
        };
        assert_eq!(Formation::from_def(&d, &read).unwrap(), f);
        assert_eq!(Formation::new(&d).unwrap_err().field(), "bitmap");
        let path = || "dir/shape.pgm".to_string();
        let cases: Vec<(Vec<u8>, BitmapDef, FormationError)> = vec![
            (
                img.clone(),
                bm((250, 0, 0), (255, 255, 255), None),
                FormationError::NothingSelected {
                    path: path(),
                    c_min: (250, 0, 0),
                    c_max: (255, 255, 255),
                },
            ),
            (
                img.clone(),
                bm((0, 0, 0), (255, 255, 255), None),
                FormationError::EverythingSelected {
                    path: path(),
                    c_min: (0, 0, 0),
                    c_max: (255, 255, 255),
                    pixels: 800,
                },
            ),
            (
                img.clone(),
                bm((9, 0, 0), (8, 255, 255), None),
                FormationError::EmptyRange {
                    path: path(),
                    c_min: (9, 0, 0),
                    c_max: (8, 255, 255),
                },
            ),
            (
                img.clone(),
                bm((0, 0, 0), (9, 9, 9), Some((f64::NAN, 1.0))),
                FormationError::BadSize {
                    path: path(),
                    size: (f64::NAN, 1.0),
                },
            ),
            (
                b"P5 4000 3 255\n".to_vec(),
                dark.clone(),
                FormationError::ImageTooLarge {
                    path: path(),
                    width: 4000,
                    height: 3,
                },
            ),
            (
                img[..30].to_vec(),
                dark.clone(),
                FormationError::Image {
                    path: path(),
                    message: "PGM: 800 bytes of pixels expected, 17 present".into(),
                },
            ),
        ];
        for (bytes, b, want) in &cases {
            let got = Formation::from_bitmap("b", bytes, b).unwrap_err();
            // NaN != NaN: compare the messages.
            assert_eq!(got.to_string(), want.to_string());
            assert_eq!(got.field(), "bitmap");
            assert!(got.to_string().contains("dir/shape.pgm"), "{got}");
        }
        let e = Formation::from_bitmap("b", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", &dark).unwrap_err();
        assert!(matches!(&e, FormationError::Image { .. }), "{e}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// Random star-shaped polygons (simple, often concave), any placement and
        /// size: the mesh is valid, inside the outline and of the right area.
        #[test]
        fn star_shaped_outlines_mesh(
            radii in prop::collection::vec(0.3f64..1.0, 3..24),
            cx in -50.0f64..50.0, cy in -50.0f64..50.0,
            angle in 0.0f64..std::f64::consts::TAU,
            area in 0.05f64..400.0,
            vertices in 3usize..400,
        ) {
            let n = radii.len();
            let outline: Vec<(f64, f64)> = radii.iter().enumerate().map(|(i, r)| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                (r * a.cos(), r * a.sin())
            }).collect();
            let f = Formation::new(&FormationDef::polygon("s", &outline)).unwrap();
            let p = place(cx, cy, angle.cos(), angle.sin(), area);
            check_mesh(&f, &p, vertices);
        }

        /// Arbitrary outlines never panic: either an error or a usable shape.
        #[test]
        fn arbitrary_outlines_never_panic(pts in prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0), 0..12)) {
            if let Ok(f) = Formation::new(&FormationDef::polygon("r", &pts)) {
                let _ = f.mesh(&place(0.0, 0.0, 1.0, 0.0, 2.0), 60);
            }
        }
    }
}
