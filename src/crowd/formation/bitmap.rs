//! Formations drawn as images (formation-transform section 3.1): a PNG or PGM
//! (P2/P5) file, the shape being the pixels whose colour lies in a range (eq. 1:
//! `c_min ≤ c ≤ c_max` for each of r, g, b; a grey image has r = g = b; a pixel
//! with alpha below 128 is transparent and never selected).
//!
//! The selected pixels are a mask; its boundary is traced along pixel edges into
//! closed rings (outer rings counter-clockwise, holes clockwise, in pixel units with
//! `+y` up, so the image's right is the formation's heading), after two pixels that
//! touch only at a corner are joined by filling a pixel between them (so no two
//! rings share a vertex). Straight runs become single edges and the staircase is
//! simplified (Douglas–Peucker, half a pixel), kept only if the result is still
//! valid. The rings then go through the same validation as a drawn outline.

use super::region::Piece;
use crate::geom::{twice_signed_area, Vec2};
use serde::{Deserialize, Serialize};

/// Widest or tallest image read (pixels).
pub const MAX_IMAGE_SIDE: u32 = 1024;
/// Most boundary vertices a traced image may have (after simplification).
pub const MAX_TRACED_VERTICES: usize = 20_000;
/// Most separate pieces a traced image may have.
pub const MAX_PIECES: usize = 64;
/// Alpha below this is transparent (never selected).
const OPAQUE: u8 = 128;

/// A formation drawn as an image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BitmapDef {
    /// The PNG or PGM file; a relative path is relative to the file naming it.
    pub path: String,
    /// Lowest selected colour `(r, g, b)`, each 0–255 (eq. 1's `c_min`).
    pub c_min: (u8, u8, u8),
    /// Highest selected colour `(r, g, b)` (eq. 1's `c_max`).
    pub c_max: (u8, u8, u8),
    /// The image's width and height in metres; `None`: the shape is scaled to the
    /// crowd's area like a drawn outline.
    #[serde(default)]
    pub size_m: Option<(f64, f64)>,
}

/// An image as 8-bit RGBA, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// `width · height` pixels, row-major.
    pub rgba: Vec<[u8; 4]>,
}

/// Why an image could not be used (the caller adds the path).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// Not a PNG or PGM, or a broken one.
    #[error("cannot decode image: {0}")]
    Decode(String),
    /// Larger than [`MAX_IMAGE_SIDE`].
    #[error("image is {width}×{height} pixels, at most {max}×{max} are read", max = MAX_IMAGE_SIDE)]
    TooLarge {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
}

/// Decodes a PNG (any colour type and depth, reduced to 8-bit RGBA) or a PGM.
///
/// # Errors
/// [`ImageError`]: an unknown format, a corrupt file (the decoder's message), an
/// image larger than [`MAX_IMAGE_SIDE`] (refused before its pixels are read).
pub fn decode(bytes: &[u8]) -> Result<Image, ImageError> {
    if bytes.starts_with(b"\x89PNG") {
        decode_png(bytes)
    } else if bytes.starts_with(b"P2") || bytes.starts_with(b"P5") {
        decode_pgm(bytes)
    } else {
        Err(ImageError::Decode(
            "neither a PNG nor a PGM (P2/P5) file".into(),
        ))
    }
}

fn check_size(width: u32, height: u32) -> Result<(), ImageError> {
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(ImageError::TooLarge { width, height });
    }
    if width == 0 || height == 0 {
        return Err(ImageError::Decode(format!(
            "image is {width}×{height} pixels"
        )));
    }
    Ok(())
}

fn decode_png(bytes: &[u8]) -> Result<Image, ImageError> {
    let e = |e: png::DecodingError| ImageError::Decode(e.to_string());
    let mut dec = png::Decoder::new_with_limits(
        bytes,
        png::Limits {
            bytes: 4 * (MAX_IMAGE_SIDE as usize).pow(2) * 2,
        },
    );
    dec.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = dec.read_info().map_err(e)?;
    let (w, h) = (reader.info().width, reader.info().height);
    check_size(w, h)?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut buf).map_err(e)?;
    let data = &buf[..frame.buffer_size()];
    let n = (w * h) as usize;
    let rgba: Vec<[u8; 4]> = match frame.color_type {
        png::ColorType::Grayscale => data.iter().map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::GrayscaleAlpha => data
            .chunks_exact(2)
            .map(|c| [c[0], c[0], c[0], c[1]])
            .collect(),
        png::ColorType::Rgb => data
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        png::ColorType::Rgba => data
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect(),
        png::ColorType::Indexed => {
            return Err(ImageError::Decode("palette left unexpanded".into()))
        }
    };
    if rgba.len() != n {
        return Err(ImageError::Decode(format!(
            "{} pixels decoded for {w}×{h}",
            rgba.len()
        )));
    }
    Ok(Image {
        width: w,
        height: h,
        rgba,
    })
}

fn decode_pgm(bytes: &[u8]) -> Result<Image, ImageError> {
    let plain = bytes[1] == b'2';
    let mut pos = 2;
    let mut field = |what: &str| -> Result<u32, ImageError> {
        loop {
            match bytes.get(pos) {
                Some(c) if c.is_ascii_whitespace() => pos += 1,
                Some(b'#') => {
                    while bytes.get(pos).is_some_and(|&c| c != b'\n') {
                        pos += 1;
                    }
                }
                _ => break,
            }
        }
        let s = pos;
        while bytes.get(pos).is_some_and(u8::is_ascii_digit) {
            pos += 1;
        }
        std::str::from_utf8(&bytes[s..pos])
            .ok()
            .and_then(|t| t.parse::<u32>().ok())
            .ok_or_else(|| ImageError::Decode(format!("PGM: no {what} at byte {s}")))
    };
    let w = field("width")?;
    let h = field("height")?;
    let max = field("maximum grey value")?;
    check_size(w, h)?;
    if !(1..=65535).contains(&max) {
        return Err(ImageError::Decode(format!(
            "PGM: maximum grey value {max} is not in 1..=65535"
        )));
    }
    let n = (w * h) as usize;
    let scale = |v: u32| -> Result<u8, ImageError> {
        if v > max {
            return Err(ImageError::Decode(format!(
                "PGM: grey value {v} above the maximum {max}"
            )));
        }
        Ok(((v as f64 * 255.0 / max as f64).round()) as u8)
    };
    let mut grey = Vec::with_capacity(n);
    if plain {
        for i in 0..n {
            let v = field(&format!("grey value {i}"))?;
            grey.push(scale(v)?);
        }
    } else {
        // One whitespace byte after the header, then the samples.
        let start = pos + 1;
        let per = if max < 256 { 1 } else { 2 };
        let need = n * per;
        let data = bytes.get(start..start + need).ok_or_else(|| {
            ImageError::Decode(format!(
                "PGM: {need} bytes of pixels expected, {} present",
                bytes.len().saturating_sub(start)
            ))
        })?;
        for c in data.chunks_exact(per) {
            let v = if per == 1 {
                c[0] as u32
            } else {
                (c[0] as u32) << 8 | c[1] as u32
            };
            grey.push(scale(v)?);
        }
    }
    Ok(Image {
        width: w,
        height: h,
        rgba: grey.into_iter().map(|g| [g, g, g, 255]).collect(),
    })
}

/// Eq. 1: whether a pixel is selected by the range (alpha below 128: never).
pub fn selected(px: [u8; 4], c_min: (u8, u8, u8), c_max: (u8, u8, u8)) -> bool {
    px[3] >= OPAQUE
        && (c_min.0..=c_max.0).contains(&px[0])
        && (c_min.1..=c_max.1).contains(&px[1])
        && (c_min.2..=c_max.2).contains(&px[2])
}

/// The mask of selected pixels (row 0 at the top).
pub fn select(img: &Image, c_min: (u8, u8, u8), c_max: (u8, u8, u8)) -> Vec<bool> {
    img.rgba
        .iter()
        .map(|&p| selected(p, c_min, c_max))
        .collect()
}

/// Fills one pixel of every 2×2 block whose selected pixels touch only at a corner,
/// until none is left (each fill re-checks the four blocks around it).
fn join_corners(mask: &mut [bool], w: usize, h: usize) {
    let diagonal = |m: &[bool], x: usize, y: usize| {
        let (a, b, c, d) = (
            m[y * w + x],
            m[y * w + x + 1],
            m[(y + 1) * w + x],
            m[(y + 1) * w + x + 1],
        );
        (a && d && !b && !c) || (b && c && !a && !d)
    };
    if w < 2 || h < 2 {
        return;
    }
    let mut stack: Vec<(usize, usize)> = (0..h - 1)
        .flat_map(|y| (0..w - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| diagonal(mask, x, y))
        .collect();
    while let Some((x, y)) = stack.pop() {
        if !diagonal(mask, x, y) {
            continue;
        }
        let (px, py) = if mask[y * w + x] { (x + 1, y) } else { (x, y) };
        mask[py * w + px] = true;
        for (bx, by) in [
            (px.wrapping_sub(1), py.wrapping_sub(1)),
            (px, py.wrapping_sub(1)),
            (px.wrapping_sub(1), py),
            (px, py),
        ] {
            if bx < w - 1 && by < h - 1 && diagonal(mask, bx, by) {
                stack.push((bx, by));
            }
        }
    }
}

/// The boundary rings of `mask` in pixel units, `+y` up (pixel row `r` spans
/// `y ∈ [h-1-r, h-r]`), the selected side on the left, straight runs merged.
fn trace(mask: &[bool], w: usize, h: usize) -> Vec<Vec<Vec2>> {
    let at = |x: i64, r: i64| {
        x >= 0
            && r >= 0
            && (x as usize) < w
            && (r as usize) < h
            && mask[r as usize * w + x as usize]
    };
    let vw = w + 1;
    let vid = |x: usize, y: usize| y * vw + x;
    const NONE: u32 = u32::MAX;
    let mut next = vec![NONE; vw * (h + 1)];
    for r in 0..h {
        let y = h - 1 - r;
        for x in 0..w {
            if !mask[r * w + x] {
                continue;
            }
            let (xi, ri) = (x as i64, r as i64);
            if !at(xi, ri + 1) {
                next[vid(x, y)] = vid(x + 1, y) as u32; // bottom, going +x
            }
            if !at(xi + 1, ri) {
                next[vid(x + 1, y)] = vid(x + 1, y + 1) as u32; // right, going +y
            }
            if !at(xi, ri - 1) {
                next[vid(x + 1, y + 1)] = vid(x, y + 1) as u32; // top, going -x
            }
            if !at(xi - 1, ri) {
                next[vid(x, y + 1)] = vid(x, y) as u32; // left, going -y
            }
        }
    }
    let pos = |v: usize| Vec2::new((v % vw) as f64, (v / vw) as f64);
    let mut rings = Vec::new();
    for s in 0..next.len() {
        if next[s] == NONE {
            continue;
        }
        let mut ring = Vec::new();
        let mut v = s;
        while next[v] != NONE {
            let n = next[v] as usize;
            next[v] = NONE;
            ring.push(pos(v));
            v = n;
        }
        // Keep corners only.
        let m = ring.len();
        let corners: Vec<Vec2> = (0..m)
            .filter(|&i| {
                let (a, b, c) = (ring[(i + m - 1) % m], ring[i], ring[(i + 1) % m]);
                crate::geom::cross(b - a, c - b) != 0.0
            })
            .map(|i| ring[i])
            .collect();
        rings.push(corners);
    }
    rings
}

/// Douglas–Peucker on a closed ring: split at vertex 0 and the vertex farthest from
/// it; keeps at least those two and one more per side.
fn simplify(ring: &[Vec2], tol: f64) -> Vec<Vec2> {
    let n = ring.len();
    if n <= 4 {
        return ring.to_vec();
    }
    let far = (1..n)
        .max_by(|&a, &b| {
            (ring[a] - ring[0])
                .norm()
                .total_cmp(&(ring[b] - ring[0]).norm())
        })
        .unwrap_or(n / 2);
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[far] = true;
    // The top-level sides keep their farthest vertex whatever its distance.
    let mut stack = vec![(0, far, true), (far, n, true)];
    while let Some((a, b, force)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (pa, pb) = (ring[a], ring[b % n]);
        let (mut k, mut dmax) = (a + 1, -1.0);
        for (i, &q) in ring.iter().enumerate().take(b).skip(a + 1) {
            let d = crate::geom::segment_distance_squared(q, pa, pb).sqrt();
            if d > dmax {
                dmax = d;
                k = i;
            }
        }
        if force || dmax > tol {
            keep[k] = true;
            stack.push((a, k, false));
            stack.push((k, b, false));
        }
    }
    (0..n).filter(|&i| keep[i]).map(|i| ring[i]).collect()
}

/// The traced pieces of a mask, plain and simplified, in pixel units scaled by
/// `(sx, sy)` per pixel. Outer rings become pieces; each hole goes to the smallest
/// outer ring around it.
///
/// # Errors
/// `(what, count)` when there are more than [`MAX_PIECES`] pieces or
/// [`MAX_TRACED_VERTICES`] vertices.
pub(crate) fn pieces_of(
    mask: &[bool],
    w: usize,
    h: usize,
    scale: (f64, f64),
    simplify_tol_px: f64,
) -> Result<Vec<Piece>, (&'static str, usize)> {
    let mut mask = mask.to_vec();
    join_corners(&mut mask, w, h);
    let rings: Vec<Vec<Vec2>> = trace(&mask, w, h)
        .into_iter()
        .map(|r| {
            let r = if simplify_tol_px > 0.0 {
                simplify(&r, simplify_tol_px)
            } else {
                r
            };
            r.into_iter()
                .map(|p| Vec2::new(p.x * scale.0, p.y * scale.1))
                .collect()
        })
        .collect();
    let total: usize = rings.iter().map(Vec::len).sum();
    if total > MAX_TRACED_VERTICES {
        return Err(("boundary vertices", total));
    }
    let (outer, holes): (Vec<_>, Vec<_>) =
        rings.into_iter().partition(|r| twice_signed_area(r) > 0.0);
    if outer.len() > MAX_PIECES {
        return Err(("separate pieces", outer.len()));
    }
    let mut pieces: Vec<Piece> = outer
        .into_iter()
        .map(|outline| Piece {
            outline,
            holes: Vec::new(),
        })
        .collect();
    for hole in holes {
        let owner = pieces
            .iter()
            .enumerate()
            .filter(|(_, k)| super::region::inside_ring(&k.outline, hole[0]))
            .min_by(|a, b| {
                twice_signed_area(&a.1.outline).total_cmp(&twice_signed_area(&b.1.outline))
            })
            .map(|(i, _)| i);
        if let Some(i) = owner {
            pieces[i].holes.push(hole);
        }
    }
    Ok(pieces)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> Image {
        Image {
            width: w,
            height: h,
            rgba: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    #[test]
    fn eq1_selection_matches_a_pixel_loop() {
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut b = || (rng.next_u64() & 0xff) as u8;
        let px: Vec<[u8; 4]> = (0..4096).map(|_| [b(), b(), b(), b()]).collect();
        let im = Image {
            width: 64,
            height: 64,
            rgba: px,
        };
        for (lo, hi) in [
            ((0, 0, 0), (255, 255, 255)),
            ((10, 50, 90), (200, 120, 250)),
            ((128, 0, 0), (128, 255, 255)),
        ] {
            let m = select(&im, lo, hi);
            for (i, p) in im.rgba.iter().enumerate() {
                let mut want = p[3] >= 128;
                for (c, (l, h)) in [
                    (p[0], (lo.0, hi.0)),
                    (p[1], (lo.1, hi.1)),
                    (p[2], (lo.2, hi.2)),
                ] {
                    if c < l || c > h {
                        want = false;
                    }
                }
                assert_eq!(m[i], want, "pixel {i} {p:?}");
            }
        }
    }

    #[test]
    fn pgm_both_forms_decode_and_bad_ones_are_named() {
        let p2 = b"P2\n# a comment\n3 2\n15\n0 15 7\n15 0 3\n";
        let a = decode(p2).unwrap();
        assert_eq!((a.width, a.height), (3, 2));
        assert_eq!(a.rgba[1], [255, 255, 255, 255]);
        assert_eq!(a.rgba[2], [119, 119, 119, 255]);
        let mut p5 = b"P5 3 2 255\n".to_vec();
        p5.extend([0, 255, 119, 255, 0, 51]);
        assert_eq!(decode(&p5).unwrap().rgba[2], [119, 119, 119, 255]);
        assert!(
            matches!(decode(b"P5 3 2 255\n\x00"), Err(ImageError::Decode(m)) if m.contains("6 bytes"))
        );
        assert!(
            matches!(decode(b"P2 2 1 3\n0 9"), Err(ImageError::Decode(m)) if m.contains("above"))
        );
        assert_eq!(
            decode(b"P5 2000 2 255\n"),
            Err(ImageError::TooLarge {
                width: 2000,
                height: 2
            })
        );
        assert!(matches!(decode(b"GIF89a"), Err(ImageError::Decode(_))));
        assert!(matches!(
            decode(b"\x89PNG\r\n\x1a\nbroken"),
            Err(ImageError::Decode(_))
        ));
    }

    #[test]
    fn a_square_with_a_hole_traces_into_one_piece_with_one_hole() {
        // 8×8 filled, 4×4 hole in the middle.
        let im = img(8, 8, |x, y| {
            let hole = (2..6).contains(&x) && (2..6).contains(&y);
            if hole {
                [255, 255, 255, 255]
            } else {
                [0, 0, 0, 255]
            }
        });
        let m = select(&im, (0, 0, 0), (10, 10, 10));
        let p = pieces_of(&m, 8, 8, (1.0, 1.0), 0.5).unwrap();
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].outline.len(), 4);
        assert_eq!(p[0].holes.len(), 1);
        assert!((twice_signed_area(&p[0].outline) - 128.0).abs() < 1e-12);
        assert!((twice_signed_area(&p[0].holes[0]) + 32.0).abs() < 1e-12);
    }

    #[test]
    fn corner_touching_pixels_are_joined() {
        // A checker 2×2: two pixels touching at a corner.
        let mut m = vec![true, false, false, true];
        join_corners(&mut m, 2, 2);
        assert_eq!(m.iter().filter(|&&b| b).count(), 3);
        let p = pieces_of(&[true, false, false, true], 2, 2, (1.0, 1.0), 0.0).unwrap();
        assert_eq!(p.len(), 1);
        super::super::region::check(&p).unwrap();
    }
}
