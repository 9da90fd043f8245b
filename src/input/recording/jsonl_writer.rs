//! Writing crowdtouch JSON Lines: a whole recording ([`write_jsonl`]) or one frame
//! at a time ([`JsonlWriter`]).

use super::jsonl::{JSONL_FORMAT, JSONL_VERSION};
use crate::input::{AxisRange, SurfaceInfo};
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, TouchFrame, MAX_CONTACTS};
use serde::Serialize;

/// Device units are written with this many decimals (1e-3 units).
const WRITE_SCALE: f64 = 1_000.0;

#[derive(Serialize)]
struct AxisOut {
    min: f64,
    max: f64,
    #[serde(skip_serializing_if = "is_zero")]
    resolution: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[derive(Serialize)]
struct DeviceOut<'a> {
    name: &'a str,
    x: AxisOut,
    y: AxisOut,
    max_contacts: u32,
}

#[derive(Serialize)]
struct HeaderOut<'a> {
    format: &'static str,
    version: u64,
    device: DeviceOut<'a>,
}

#[derive(Debug, Serialize)]
struct ContactOut {
    id: u32,
    x: f64,
    y: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pressure: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    major: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minor: Option<f64>,
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    palm: bool,
}

#[derive(Serialize)]
struct FrameOut<'a> {
    t_us: u64,
    contacts: &'a [ContactOut],
    #[serde(skip_serializing_if = "<[u32]>::is_empty")]
    cancelled: &'a [u32],
}

fn axis_out(a: &AxisRange) -> AxisOut {
    AxisOut {
        min: a.min,
        max: a.max,
        resolution: a.resolution,
    }
}

/// Device units for a normalised coordinate, rounded to 1e-3 units.
fn to_device(a: &AxisRange, v: f32) -> f64 {
    let d = a.min + f64::from(v) * (a.max - a.min);
    (d * WRITE_SCALE).round() / WRITE_SCALE
}

/// Writes frames as crowdtouch JSON Lines: the inverse of the reader.
///
/// Positions go back to device units of `rec_surface` (rounded to 1e-3 units);
/// `t_us` is relative to the first frame. Each line lists the contacts down after
/// the frame (`UP`/`CANCELLED` contacts are left out; cancelled ids go in
/// `"cancelled"`), with their [`ContactId`](crate::vocab::ContactId) as file id. Reading the output back
/// gives the same contacts and flags, with ids renumbered from 1 in order of
/// appearance, positions within 1e-6 (relative), and an ended contact at its
/// position in the previous frame. Not representable, and so lost: the position
/// a contact had in the frame it ended in, and contacts that began and ended in
/// the same frame (`DOWN | UP`). `major`/`minor` are written only when the X
/// resolution is known.
///
/// # Errors
/// Whatever `w` returns.
pub fn write_jsonl(
    rec_surface: &SurfaceInfo,
    frames: &[TouchFrame],
    w: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let mut out = JsonlWriter::new(rec_surface, w)?;
    for f in frames {
        out.frame(f)?;
    }
    Ok(())
}

/// Writes our JSON Lines recording one frame at a time, as [`write_jsonl`] does
/// for a whole recording (same bytes): the header at creation, then one line per
/// [`JsonlWriter::frame`]. For recording a live device.
#[derive(Debug)]
pub struct JsonlWriter<'s, W: std::io::Write> {
    surface: &'s SurfaceInfo,
    out: W,
    t0: Option<Micros>,
    contacts: Vec<ContactOut>,
    cancelled: Vec<u32>,
    frames: u64,
}

impl<'s, W: std::io::Write> JsonlWriter<'s, W> {
    /// Writes the header line for a device of surface `rec_surface`.
    ///
    /// # Errors
    /// Whatever `out` returns.
    pub fn new(rec_surface: &'s SurfaceInfo, mut out: W) -> std::io::Result<Self> {
        let header = HeaderOut {
            format: JSONL_FORMAT,
            version: JSONL_VERSION,
            device: DeviceOut {
                name: &rec_surface.name,
                x: axis_out(&rec_surface.x),
                y: axis_out(&rec_surface.y),
                max_contacts: rec_surface.max_contacts,
            },
        };
        serde_json::to_writer(&mut out, &header)?;
        out.write_all(b"\n")?;
        Ok(JsonlWriter {
            surface: rec_surface,
            out,
            t0: None,
            contacts: Vec::with_capacity(MAX_CONTACTS),
            cancelled: Vec::with_capacity(MAX_CONTACTS),
            frames: 0,
        })
    }

    /// Writes one frame; times are relative to the first frame written.
    ///
    /// # Errors
    /// Whatever the writer returns.
    pub fn frame(&mut self, f: &TouchFrame) -> std::io::Result<()> {
        let t0 = *self.t0.get_or_insert(f.t);
        let rec_surface = self.surface;
        let res = rec_surface.x.resolution;
        let size = |mm: Option<f32>| {
            mm.filter(|_| res > 0.0)
                .map(|v| (f64::from(v) * res * WRITE_SCALE).round() / WRITE_SCALE)
        };
        self.contacts.clear();
        self.cancelled.clear();
        for c in f.contacts() {
            if c.flags.ended() {
                if c.flags.contains(ContactFlags::CANCELLED)
                    && !c.flags.contains(ContactFlags::DOWN)
                {
                    self.cancelled.push(c.id.0);
                }
                continue;
            }
            self.contacts.push(ContactOut {
                id: c.id.0,
                x: to_device(&rec_surface.x, c.x),
                y: to_device(&rec_surface.y, c.y),
                pressure: c.pressure,
                major: size(c.major_mm),
                minor: size(c.minor_mm),
                palm: c.flags.contains(ContactFlags::PALM),
            });
        }
        let line = FrameOut {
            t_us: f.t.saturating_since(t0).0,
            contacts: &self.contacts,
            cancelled: &self.cancelled,
        };
        serde_json::to_writer(&mut self.out, &line)?;
        self.out.write_all(b"\n")?;
        self.frames += 1;
        Ok(())
    }

    /// Frames written.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Flushes the writer.
    ///
    /// # Errors
    /// The writer's.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}
