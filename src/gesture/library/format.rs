//! The library file (`config/gestures/*.ctgl`): a versioned little-endian binary
//! format, and its reader, which refuses anything malformed with the file, the byte
//! offset and the item at fault, never panics and never allocates more than the
//! file's remaining bytes justify.
//!
//! # Layout (version 2, written)
//!
//! ```text
//! header     "CTGL"  version:u32 (2)  classes:u32 (0..=1000)  motions:u32  gestures:u32
//! class      name_len:u32 (1..=64)  name:[u8; name_len] (an ASCII letter, then
//!            letters, digits, `_`, `-`; unique)
//! motion     class:u32 (< classes)  basis:u32 (d, 0..=15)  gmm:u32 (1..=32)
//!            duration_s:f64  mean:[f64; 128]  basis × [f64; 128]
//!            gmm × { weight:f64  mean:[f64; d]  cov:[f64; d·d] (row-major) }
//! gesture    class:u32  motion:u32  fingers:u32 (1..=10)  origin_len:u32 (0..=1024)
//!            participant_len:u32 (0..=64)  device_len:u32 (0..=256)
//!            scale_mm:f64 (eq. 2's extent on the glass; 0 when unknown)
//!            fingers × 64 × { x:f64  y:f64 }  origin:[u8; origin_len]
//!            participant:[u8; participant_len]  device:[u8; device_len] (UTF-8)
//! trailer    crc32:u32   (CRC-32/IEEE of every byte before it)
//! ```
//!
//! # Version 1 (read, migrated)
//!
//! No class table: the classes are the ten [`MotionClass`]es in the paper's order,
//! and a record's class is an index into them. The header is
//! `"CTGL" version:u32 (1) motions:u32 gestures:u32`, and a gesture record has no
//! participant, device and scale (they read as empty and unknown: recognition
//! leaves the features that need millimetres out for such a gesture). Everything
//! else is as in version 2.
//! A version-1 file reads as the library it holds; writing it gives version 2.
//!
//! Numbers are f64, not f32: the model holds f64, so a library written and read
//! back is the same library bit for bit (a file rewritten by `library add` does not
//! drift), and eigenvectors keep the orthonormality the reader checks. The cost is
//! size: 1,500 three-finger gestures and 150 motions take 7.7 MB; parsing it is a
//! copy of little-endian words and stays far inside the 100 ms load budget
//! (`benches/gesture_library.rs`).
//!
//! The checksum makes a flipped bit an error rather than a slightly different
//! library. The structure is parsed before the checksum is compared, so a file cut
//! short or with a bad count is reported where it breaks, not as a mere mismatch.

use super::class::{ClassId, MotionClass, MAX_CLASSES, MAX_CLASS_NAME_BYTES};
use super::error::{Item, LibraryError, Problem};
use super::model::{
    GmmComponent, Library, LibraryGesture, MotionFeatures, Resampled, MAX_DEVICE_BYTES,
    MAX_PARTICIPANT_BYTES, TRAJ_DIM, T_H,
};
use super::validate::{self, LoadPolicy, MAX_GMM_COMPONENTS, MAX_ORIGIN_BYTES};
use crate::geom::Vec2;

/// The first four bytes of a library file.
pub const MAGIC: [u8; 4] = *b"CTGL";

/// The format version this build writes, the newest it reads.
pub const FORMAT_VERSION: u32 = 2;

/// The oldest format version this build reads (migrated on read).
pub const OLDEST_VERSION: u32 = 1;

/// Largest library file a caller should read into memory (bytes): 1,500 motions
/// with 15 eigenvectors and 32 components take about 60 MB.
pub const MAX_LIBRARY_BYTES: usize = 256 << 20;

const HEADER_BYTES: usize = 20;
const MOTION_HEAD_BYTES: usize = 12;
/// A version-2 gesture head: six `u32`s and `scale_mm`.
const GESTURE_HEAD_BYTES: usize = 32;
const FINGER_BYTES: usize = T_H * 16;
/// The smallest class record: a one-byte name.
const MIN_CLASS_BYTES: usize = 4 + 1;
/// The smallest motion record: no eigenvector, one component (its weight).
const MIN_MOTION_BYTES: usize = MOTION_HEAD_BYTES + 8 + TRAJ_DIM * 8 + 8;
const CHECKSUM_BYTES: usize = 4;

/// The sizes that differ between versions.
#[derive(Copy, Clone)]
struct Layout {
    version: u32,
    gesture_head_bytes: usize,
}

impl Layout {
    fn of(version: u32) -> Layout {
        if version == 1 {
            Layout {
                version,
                gesture_head_bytes: 16,
            }
        } else {
            Layout {
                version,
                gesture_head_bytes: GESTURE_HEAD_BYTES,
            }
        }
    }

    /// The smallest gesture record: one finger, no text.
    fn min_gesture_bytes(self) -> usize {
        self.gesture_head_bytes + FINGER_BYTES
    }
}

/// Serialises a library (layout in the module doc).
///
/// Writes any library as it is; one that [`validate`](fn@super::validate) refuses is
/// written faithfully and refused by [`read_library`].
pub fn write_library(lib: &Library) -> Vec<u8> {
    let size = HEADER_BYTES
        + lib.classes.iter().map(|c| 4 + c.len()).sum::<usize>()
        + lib.motions.iter().map(motion_bytes).sum::<usize>()
        + lib.gestures.iter().map(gesture_bytes).sum::<usize>()
        + CHECKSUM_BYTES;
    let mut out = Vec::with_capacity(size);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    put_u32(&mut out, lib.classes.len());
    put_u32(&mut out, lib.motions.len());
    put_u32(&mut out, lib.gestures.len());
    for c in &lib.classes {
        put_u32(&mut out, c.len());
        out.extend_from_slice(c.as_bytes());
    }
    for m in &lib.motions {
        put_u32(&mut out, m.class.index());
        put_u32(&mut out, m.basis.len());
        put_u32(&mut out, m.gmm.len());
        put_f64s(&mut out, &[m.duration_s]);
        put_f64s(&mut out, &m.mean);
        for e in &m.basis {
            put_f64s(&mut out, e);
        }
        for c in &m.gmm {
            put_f64s(&mut out, &[c.weight]);
            put_f64s(&mut out, &c.mean);
            put_f64s(&mut out, &c.cov);
        }
    }
    for g in &lib.gestures {
        put_u32(&mut out, g.class.index());
        out.extend_from_slice(&g.motion.to_le_bytes());
        put_u32(&mut out, g.gesture.fingers.len());
        put_u32(&mut out, g.origin.len());
        put_u32(&mut out, g.participant.len());
        put_u32(&mut out, g.device.len());
        put_f64s(&mut out, &[g.scale_mm.unwrap_or(0.0)]);
        for finger in &g.gesture.fingers {
            for p in finger {
                put_f64s(&mut out, &[p.x, p.y]);
            }
        }
        out.extend_from_slice(g.origin.as_bytes());
        out.extend_from_slice(g.participant.as_bytes());
        out.extend_from_slice(g.device.as_bytes());
    }
    seal(&mut out);
    out
}

fn gesture_bytes(g: &LibraryGesture) -> usize {
    GESTURE_HEAD_BYTES
        + g.gesture.fingers.len() * FINGER_BYTES
        + g.origin.len()
        + g.participant.len()
        + g.device.len()
}

fn motion_bytes(m: &MotionFeatures) -> usize {
    MOTION_HEAD_BYTES
        + 8
        + 8 * m.mean.len()
        + 8 * m.basis.iter().map(Vec::len).sum::<usize>()
        + 8 * m
            .gmm
            .iter()
            .map(|c| 1 + c.mean.len() + c.cov.len())
            .sum::<usize>()
}

/// Lengths beyond `u32` are written as `u32::MAX`, which the reader refuses.
fn put_u32(out: &mut Vec<u8>, v: usize) {
    out.extend_from_slice(&u32::try_from(v).unwrap_or(u32::MAX).to_le_bytes());
}

fn put_f64s(out: &mut Vec<u8>, vs: &[f64]) {
    for v in vs {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// Appends the CRC-32 of `out` (written by [`write_library`]).
fn seal(out: &mut Vec<u8>) {
    let crc = crc32(out);
    out.extend_from_slice(&crc.to_le_bytes());
}

/// Rewrites the trailing checksum of a file so it matches the bytes before it.
///
/// For tests and fuzzing, which change a file's content and want the reader's other
/// checks to see it. Does nothing to a file shorter than a checksum.
pub fn reseal(bytes: &mut [u8]) {
    if let Some(n) = bytes.len().checked_sub(CHECKSUM_BYTES) {
        let crc = crc32(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
    }
}

/// Reads a library file and checks it under [`LoadPolicy::Complete`] (what the
/// daemon loads).
///
/// `name` is the file's name in error messages.
///
/// # Errors
/// The first problem, with the byte offset and the item: bad magic, a version this
/// build does not read (named), a count the file cannot hold, a bad or repeated
/// class name, a NaN, an index out of range, a class with gestures but no motion,
/// a basis that is not orthonormal, a checksum mismatch, trailing bytes; a library
/// without classes, motions or gestures (offset of the end of the records).
pub fn read_library(bytes: &[u8], name: &str) -> Result<Library, LibraryError> {
    read_library_with(bytes, name, LoadPolicy::Complete)
}

/// Reads a library file and checks it under `policy`.
///
/// # Errors
/// As [`read_library`]; [`LoadPolicy::Partial`] accepts a library without
/// classes, motions or gestures.
pub fn read_library_with(
    bytes: &[u8],
    name: &str,
    policy: LoadPolicy,
) -> Result<Library, LibraryError> {
    let mut r = Reader {
        bytes,
        pos: 0,
        name,
    };
    let lib = r.library()?;
    // The library-wide problems are reported where the records end.
    let end = r.pos - CHECKSUM_BYTES;
    validate::check_whole(&lib, policy).map_err(|(item, problem)| r.error(end, item, problem))?;
    Ok(lib)
}

struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    name: &'a str,
}

impl<'a> Reader<'a> {
    fn error(&self, offset: usize, item: Item, problem: Problem) -> LibraryError {
        LibraryError {
            file: self.name.to_string(),
            offset: Some(offset),
            item,
            problem,
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// The next `n` bytes, or `Truncated` naming `what`.
    fn take(
        &mut self,
        n: usize,
        what: &'static str,
        item: &Item,
    ) -> Result<&'a [u8], LibraryError> {
        if n > self.remaining() {
            return Err(self.error(
                self.pos,
                item.clone(),
                Problem::Truncated {
                    what,
                    needed: n as u64,
                    remaining: self.remaining() as u64,
                },
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn u32(&mut self, what: &'static str, item: &Item) -> Result<u32, LibraryError> {
        let b = self.take(4, what, item)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// `n` finite f64s; a NaN or infinity is reported at its own offset as
    /// `field(k)`.
    fn f64s(
        &mut self,
        n: usize,
        what: &'static str,
        item: &Item,
        field: impl Fn(usize) -> String,
    ) -> Result<Vec<f64>, LibraryError> {
        let start = self.pos;
        let b = self.take(n * 8, what, item)?;
        let mut out = Vec::with_capacity(n);
        for (k, w) in b.chunks_exact(8).enumerate() {
            let v = f64::from_le_bytes([w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]]);
            validate::finite(|| field(k), v)
                .map_err(|p| self.error(start + 8 * k, item.clone(), p))?;
            out.push(v);
        }
        Ok(out)
    }

    /// A class index into a table of `classes`.
    fn class(
        &self,
        offset: usize,
        raw: u32,
        classes: usize,
        item: &Item,
    ) -> Result<ClassId, LibraryError> {
        let id = ClassId(u16::try_from(raw).unwrap_or(u16::MAX));
        validate::check_motion_class(id, classes)
            .map(|()| id)
            .map_err(|p| self.error(offset, item.clone(), p))
    }

    /// `n` bytes of UTF-8 text called `what`.
    fn text(&mut self, n: usize, what: &'static str, item: &Item) -> Result<String, LibraryError> {
        let at = self.pos;
        let raw = self.take(n, what, item)?;
        std::str::from_utf8(raw).map(str::to_string).map_err(|e| {
            self.error(
                at + e.valid_up_to(),
                item.clone(),
                Problem::NotUtf8 {
                    what,
                    at: e.valid_up_to(),
                },
            )
        })
    }

    /// A count in `min..=max` whose records of at least `each` bytes fit in what is
    /// left after `reserve` bytes.
    #[allow(clippy::too_many_arguments)]
    fn count(
        &self,
        offset: usize,
        item: &Item,
        what: &'static str,
        raw: u32,
        (min, max): (usize, usize),
        each: usize,
        reserve: usize,
    ) -> Result<usize, LibraryError> {
        let n = raw as usize;
        if n < min || n > max {
            return Err(self.error(
                offset,
                item.clone(),
                Problem::BadCount {
                    what,
                    count: u64::from(raw),
                    min: min as u64,
                    max: max as u64,
                },
            ));
        }
        let needed = (n as u64) * (each as u64) + reserve as u64;
        if needed > self.remaining() as u64 {
            return Err(self.error(
                offset,
                item.clone(),
                Problem::Truncated {
                    what,
                    needed,
                    remaining: self.remaining() as u64,
                },
            ));
        }
        Ok(n)
    }

    fn library(&mut self) -> Result<Library, LibraryError> {
        let h = Item::Header;
        let magic = self.bytes.get(..4).unwrap_or(self.bytes);
        if magic != MAGIC {
            return Err(self.error(
                0,
                h,
                Problem::BadMagic {
                    found: magic.to_vec(),
                },
            ));
        }
        self.pos = 4;
        let version = self.u32("version", &h)?;
        if !(OLDEST_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(self.error(
                4,
                h,
                Problem::UnsupportedVersion {
                    found: version,
                    supported: FORMAT_VERSION,
                },
            ));
        }
        let layout = Layout::of(version);
        let raw_c = if version == 1 {
            None
        } else {
            Some(self.u32("class count", &h)?)
        };
        let counts_at = self.pos;
        let raw_m = self.u32("motion count", &h)?;
        let raw_g = self.u32("gesture count", &h)?;
        let n_c = match raw_c {
            Some(raw) => self.count(
                8,
                &h,
                "class",
                raw,
                (0, MAX_CLASSES),
                MIN_CLASS_BYTES,
                CHECKSUM_BYTES,
            )?,
            None => 0,
        };
        let n_m = self.count(
            counts_at,
            &h,
            "motions",
            raw_m,
            (0, u32::MAX as usize),
            MIN_MOTION_BYTES,
            n_c * MIN_CLASS_BYTES + CHECKSUM_BYTES,
        )?;
        let n_g = self.count(
            counts_at + 4,
            &h,
            "gestures",
            raw_g,
            (0, u32::MAX as usize),
            layout.min_gesture_bytes(),
            n_c * MIN_CLASS_BYTES + n_m * MIN_MOTION_BYTES + CHECKSUM_BYTES,
        )?;
        let classes = match raw_c {
            None => MotionClass::all_names(),
            Some(_) => {
                let mut classes = Vec::with_capacity(n_c);
                for i in 0..n_c {
                    let left = (n_c - 1 - i) * MIN_CLASS_BYTES
                        + n_m * MIN_MOTION_BYTES
                        + n_g * layout.min_gesture_bytes()
                        + CHECKSUM_BYTES;
                    let c = self.class_record(i, &classes, left)?;
                    classes.push(c);
                }
                classes
            }
        };
        let mut motions = Vec::with_capacity(n_m);
        for i in 0..n_m {
            let left = (n_m - 1 - i) * MIN_MOTION_BYTES
                + n_g * layout.min_gesture_bytes()
                + CHECKSUM_BYTES;
            motions.push(self.motion(i, classes.len(), left)?);
        }
        let mut gestures = Vec::with_capacity(n_g);
        for i in 0..n_g {
            let left = (n_g - 1 - i) * layout.min_gesture_bytes() + CHECKSUM_BYTES;
            gestures.push(self.gesture(i, layout, &classes, &motions, left)?);
        }
        let body = self.pos;
        let stored = self.u32("checksum", &Item::Checksum)?;
        let computed = crc32(&self.bytes[..body]);
        if stored != computed {
            return Err(self.error(
                body,
                Item::Checksum,
                Problem::ChecksumMismatch { stored, computed },
            ));
        }
        if self.remaining() > 0 {
            return Err(self.error(
                self.pos,
                Item::Checksum,
                Problem::TrailingBytes {
                    count: self.remaining(),
                },
            ));
        }
        Ok(Library {
            classes,
            motions,
            gestures,
        })
    }

    /// Class `i` of the table, after `earlier`; `left` bytes must remain after it.
    fn class_record(
        &mut self,
        i: usize,
        earlier: &[String],
        left: usize,
    ) -> Result<String, LibraryError> {
        let item = Item::Class(i);
        let start = self.pos;
        let raw = self.u32("class name length", &item)?;
        let n = self.count(
            start,
            &item,
            "class name byte",
            raw,
            (1, MAX_CLASS_NAME_BYTES),
            1,
            left,
        )?;
        let name = self.text(n, "class name", &item)?;
        validate::check_class(&name, earlier).map_err(|p| self.error(start + 4, item, p))?;
        Ok(name)
    }

    /// Motion `i` of a library of `classes` classes; `left` bytes must remain after
    /// it for the records that follow.
    fn motion(
        &mut self,
        i: usize,
        classes: usize,
        left: usize,
    ) -> Result<MotionFeatures, LibraryError> {
        let item = Item::Motion(i);
        let start = self.pos;
        let raw_class = self.u32("motion class", &item)?;
        let class = self.class(start, raw_class, classes, &item)?;
        let raw_d = self.u32("eigenvector count", &item)?;
        let raw_k = self.u32("gmm component count", &item)?;
        let d = self.count(
            start + 4,
            &item,
            "eigenvector",
            raw_d,
            (0, super::MAX_COMPONENTS),
            8 * TRAJ_DIM,
            0,
        )?;
        let k = self.count(
            start + 8,
            &item,
            "gmm component",
            raw_k,
            (1, MAX_GMM_COMPONENTS),
            8,
            0,
        )?;
        let body = 8 * (1 + TRAJ_DIM + d * TRAJ_DIM + k * (1 + d + d * d));
        if body + left > self.remaining() {
            return Err(self.error(
                start,
                item,
                Problem::Truncated {
                    what: "motion record",
                    needed: (body + left) as u64,
                    remaining: self.remaining() as u64,
                },
            ));
        }
        let duration_s = self.f64s(1, "duration", &item, |_| "duration_s".into())?[0];
        let mean = self.f64s(TRAJ_DIM, "mean", &item, |k| format!("mean[{k}]"))?;
        let mut basis = Vec::with_capacity(d);
        for a in 0..d {
            let it = Item::Basis {
                motion: i,
                vector: a,
            };
            basis.push(self.f64s(TRAJ_DIM, "eigenvector", &it, |k| format!("value {k}"))?);
        }
        let mut gmm = Vec::with_capacity(k);
        for c in 0..k {
            let it = Item::Component {
                motion: i,
                component: c,
            };
            let weight = self.f64s(1, "weight", &it, |_| "weight".into())?[0];
            let mean = self.f64s(d, "gmm mean", &it, |k| format!("mean[{k}]"))?;
            let cov = self.f64s(d * d, "covariance", &it, |k| {
                format!("cov[{}][{}]", k / d, k % d)
            })?;
            gmm.push(GmmComponent { weight, mean, cov });
        }
        let m = MotionFeatures {
            class,
            duration_s,
            mean,
            basis,
            gmm,
        };
        validate::check_motion(i, &m).map_err(|(item, p)| self.error(start, item, p))?;
        Ok(m)
    }

    /// Gesture `i`; `left` bytes must remain after it for the records that follow.
    fn gesture(
        &mut self,
        i: usize,
        layout: Layout,
        classes: &[String],
        motions: &[MotionFeatures],
        left: usize,
    ) -> Result<LibraryGesture, LibraryError> {
        let item = Item::Gesture(i);
        let start = self.pos;
        let raw_class = self.u32("gesture class", &item)?;
        let class = self.class(start, raw_class, classes.len(), &item)?;
        let motion = self.u32("motion index", &item)?;
        let raw_f = self.u32("finger count", &item)?;
        let raw_o = self.u32("origin length", &item)?;
        let (raw_p, raw_d) = if layout.version == 1 {
            (0, 0)
        } else {
            (
                self.u32("participant length", &item)?,
                self.u32("device length", &item)?,
            )
        };
        let scale_mm = if layout.version >= 2 {
            let at = self.pos;
            let s = self.f64s(1, "scale", &item, |_| "scale_mm".into())?[0];
            // -0 is refused with the negatives: a file reads back to its own bytes.
            if s.is_sign_negative() {
                return Err(self.error(at, item, Problem::NegativeScale(s)));
            }
            (s > 0.0).then_some(s)
        } else {
            None
        };
        validate::check_gesture_head(class, u64::from(motion), raw_f as usize, classes, motions)
            .map_err(|p| self.error(start, item.clone(), p))?;
        let n_f = raw_f as usize;
        let n_p = self.count(
            start + 16,
            &item,
            "participant byte",
            raw_p,
            (0, MAX_PARTICIPANT_BYTES),
            1,
            n_f * FINGER_BYTES + left,
        )?;
        let n_d = self.count(
            start + 20,
            &item,
            "device byte",
            raw_d,
            (0, MAX_DEVICE_BYTES),
            1,
            n_f * FINGER_BYTES + n_p + left,
        )?;
        let n_o = self.count(
            start + 12,
            &item,
            "origin byte",
            raw_o,
            (0, MAX_ORIGIN_BYTES),
            1,
            n_f * FINGER_BYTES + n_p + n_d + left,
        )?;
        let mut fingers = Vec::with_capacity(n_f);
        for f in 0..n_f {
            let base = self.pos;
            let b = self.take(FINGER_BYTES, "finger", &item)?;
            let mut pts = [Vec2::zeros(); T_H];
            for (s, (p, w)) in pts.iter_mut().zip(b.chunks_exact(16)).enumerate() {
                let word = |k: usize| {
                    f64::from_le_bytes([
                        w[k],
                        w[k + 1],
                        w[k + 2],
                        w[k + 3],
                        w[k + 4],
                        w[k + 5],
                        w[k + 6],
                        w[k + 7],
                    ])
                };
                let (x, y) = (word(0), word(8));
                for (k, axis, v) in [(0, "x", x), (8, "y", y)] {
                    validate::check_coordinate(axis, v).map_err(|pr| {
                        let it = Item::Sample {
                            gesture: i,
                            finger: f,
                            sample: s,
                        };
                        self.error(base + 16 * s + k, it, pr)
                    })?;
                }
                *p = Vec2::new(x, y);
            }
            fingers.push(pts);
        }
        let origin = self.text(n_o, "origin", &item)?;
        let participant = self.text(n_p, "participant", &item)?;
        let device = self.text(n_d, "device", &item)?;
        Ok(LibraryGesture {
            class,
            motion,
            gesture: Resampled { fingers },
            origin,
            participant,
            device,
            scale_mm,
        })
    }
}

/// CRC-32/IEEE (reflected, polynomial 0xEDB88320, initial and final xor
/// 0xFFFFFFFF: zlib's `crc32`), eight bytes at a time.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    let mut chunks = bytes.chunks_exact(8);
    for c in &mut chunks {
        let lo = u32::from_le_bytes([c[0], c[1], c[2], c[3]]) ^ crc;
        let hi = u32::from_le_bytes([c[4], c[5], c[6], c[7]]);
        crc = CRC_TABLES[7][(lo & 0xff) as usize]
            ^ CRC_TABLES[6][((lo >> 8) & 0xff) as usize]
            ^ CRC_TABLES[5][((lo >> 16) & 0xff) as usize]
            ^ CRC_TABLES[4][(lo >> 24) as usize]
            ^ CRC_TABLES[3][(hi & 0xff) as usize]
            ^ CRC_TABLES[2][((hi >> 8) & 0xff) as usize]
            ^ CRC_TABLES[1][((hi >> 16) & 0xff) as usize]
            ^ CRC_TABLES[0][(hi >> 24) as usize];
    }
    for &b in chunks.remainder() {
        crc = CRC_TABLES[0][((crc ^ u32::from(b)) & 0xff) as usize] ^ (crc >> 8);
    }
    !crc
}

/// Slicing-by-8 tables: `[0]` is the byte-wise table, `[k][i]` advances `[k-1][i]`
/// by one zero byte.
static CRC_TABLES: [[u32; 256]; 8] = crc_tables();

const fn crc_tables() -> [[u32; 256]; 8] {
    let mut t = [[0u32; 256]; 8];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[0][i] = c;
        i += 1;
    }
    let mut k = 1;
    while k < 8 {
        let mut i = 0;
        while i < 256 {
            let prev = t[k - 1][i];
            t[k][i] = (prev >> 8) ^ t[0][(prev & 0xff) as usize];
            i += 1;
        }
        k += 1;
    }
    t
}

#[cfg(test)]
#[path = "format_tests.rs"]
mod tests;
