//! The crowdtouch JSON Lines reader (`.jsonl`, ours).
//!
//! Line 1 is a header,
//! ```text
//! {"format":"crowdtouch-touch","version":1,"device":{"name":"…",
//!  "x":{"min":0,"max":32767,"resolution":27.08},"y":{…},"max_contacts":10}}
//! ```
//! (`resolution` in units per mm, optional, 0 = unknown), then one frame per line:
//! ```text
//! {"t_us":8333,"contacts":[{"id":1,"x":1234.0,"y":2345.0}, …]}
//! ```
//! `x`, `y` are in device units of the header axes (values outside the range
//! are clamped); optional per contact: `pressure` (normalised, `0..=1`),
//! `major` / `minor` (device units of the X axis, converted to mm with its
//! resolution; ignored with a warning when the resolution is unknown) and
//! `palm` (bool). `t_us` is relative to the start and non-decreasing. The
//! contacts listed are those currently down: an id present in one frame and
//! absent from the next has lifted (reported `UP` at its last position). An
//! optional `"cancelled":[id,…]` lists ids that ended in this frame without a
//! clean lift (`CANCELLED` instead of `UP`). Unknown keys are ignored; blank
//! lines and lines starting with `#` are skipped. File ids are opaque: the
//! reader numbers contacts from 1 in order of appearance, so an id reused
//! after a lift is a new contact.

use super::error::{OnBadFrame, RecordingError};
use super::jsonl_frame::{parse_frame, FrameLine, FrameRules};
use super::jsonl_values::{want_f64, want_u32, FromMap, KeyIn, MapOr, Scalar, Text};
use super::lines::{too_long_message, LineFault, LineReader};
use super::recording_type::END_CANCEL_US;
use super::warnings::Warnings;
use crate::input::{AxisRange, SurfaceInfo};
use crate::vocab::Micros;
use crate::vocab::{ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use serde::de::{Deserialize, IgnoredAny, MapAccess};
use std::path::Path;

/// The `format` value of a crowdtouch JSON Lines header.
pub const JSONL_FORMAT: &str = "crowdtouch-touch";
/// The JSON Lines format version this module reads and writes.
pub const JSONL_VERSION: u64 = 1;

/// An axis of the header, as read.
#[derive(Default)]
struct AxisRaw {
    min: Option<Scalar>,
    max: Option<Scalar>,
    resolution: Option<Scalar>,
}

impl FromMap for AxisRaw {
    fn from_map<'de, A: MapAccess<'de>>(mut map: A) -> Result<Self, A::Error> {
        let mut a = AxisRaw::default();
        while let Some(k) = map.next_key_seed(KeyIn(&["min", "max", "resolution"]))? {
            let v = match k {
                Some(0) => &mut a.min,
                Some(1) => &mut a.max,
                Some(_) => &mut a.resolution,
                None => {
                    map.next_value::<IgnoredAny>()?;
                    continue;
                }
            };
            *v = Some(map.next_value::<Scalar>()?);
        }
        Ok(a)
    }
}

/// The header's `device`, as read.
#[derive(Default)]
struct DeviceRaw {
    name: Option<Text>,
    x: Option<MapOr<AxisRaw>>,
    y: Option<MapOr<AxisRaw>>,
    max_contacts: Option<Scalar>,
}

impl FromMap for DeviceRaw {
    fn from_map<'de, A: MapAccess<'de>>(mut map: A) -> Result<Self, A::Error> {
        let mut d = DeviceRaw::default();
        while let Some(k) = map.next_key_seed(KeyIn(&["name", "x", "y", "max_contacts"]))? {
            match k {
                Some(0) => d.name = Some(map.next_value()?),
                Some(1) => d.x = Some(map.next_value()?),
                Some(2) => d.y = Some(map.next_value()?),
                Some(_) => d.max_contacts = Some(map.next_value()?),
                None => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        Ok(d)
    }
}

/// The header line, as read; unknown keys are skipped unread.
#[derive(Default)]
struct HeaderRaw {
    format: Option<Text>,
    device: Option<MapOr<DeviceRaw>>,
}

impl FromMap for HeaderRaw {
    fn from_map<'de, A: MapAccess<'de>>(mut map: A) -> Result<Self, A::Error> {
        let mut h = HeaderRaw::default();
        while let Some(k) = map.next_key_seed(KeyIn(&["format", "device"]))? {
            match k {
                Some(0) => h.format = Some(map.next_value()?),
                Some(_) => h.device = Some(map.next_value()?),
                None => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        Ok(h)
    }
}

fn want_obj<'v, T>(v: Option<&'v MapOr<T>>, field: &str) -> Result<&'v T, String> {
    match v {
        Some(MapOr::Map(m)) => Ok(m),
        Some(MapOr::Other(o)) => Err(format!(
            "field `{field}`: expected an object, found {}",
            o.kind()
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn json_axis(a: Option<&MapOr<AxisRaw>>, key: &str) -> Result<AxisRange, String> {
    let f = format!("device.{key}");
    let a = want_obj(a, &f)?;
    let min = want_f64(a.min, &format!("{f}.min"))?;
    let max = want_f64(a.max, &format!("{f}.max"))?;
    if max <= min {
        return Err(format!("field `{f}`: empty range (min {min}, max {max})"));
    }
    let resolution = match a.resolution {
        None | Some(Scalar::Null) => 0.0,
        r => want_f64(r, &format!("{f}.resolution"))?,
    };
    if resolution < 0.0 {
        return Err(format!("field `{f}.resolution`: {resolution} is negative"));
    }
    Ok(AxisRange {
        min,
        max,
        resolution,
    })
}

fn json_header(l: &str) -> Result<SurfaceInfo, String> {
    let m = match MapOr::<HeaderRaw>::deserialize(&mut serde_json::Deserializer::from_str(l)) {
        Ok(MapOr::Map(m)) => m,
        Ok(MapOr::Other(o)) => {
            return Err(format!("expected a JSON object, found {}", o.kind()));
        }
        Err(e) => return Err(format!("invalid JSON at column {}: {e}", e.column())),
    };
    let Some(format) = m.format else {
        return Err(format!(
            "missing header: the first line must be {{\"format\":\"{JSONL_FORMAT}\",\"version\":1,\"device\":{{…}}}}"
        ));
    };
    match format {
        Text::Str(s) if s == JSONL_FORMAT => {}
        Text::Str(s) => {
            let shown: String = s.chars().take(40).collect();
            let shown = serde_json::to_string(&shown).unwrap_or_default();
            return Err(format!(
                "field `format`: expected \"{JSONL_FORMAT}\", found {shown}"
            ));
        }
        Text::Other(o) => {
            return Err(format!(
                "field `format`: expected \"{JSONL_FORMAT}\", found {o}"
            ))
        }
    }
    let dev = want_obj(m.device.as_ref(), "device")?;
    let name = match &dev.name {
        Some(Text::Str(s)) => s.clone(),
        Some(Text::Other(o)) => {
            return Err(format!(
                "field `device.name`: expected a string, found {}",
                o.kind()
            ))
        }
        None => return Err("missing field `device.name`".to_string()),
    };
    let x = json_axis(dev.x.as_ref(), "x")?;
    let y = json_axis(dev.y.as_ref(), "y")?;
    let max_contacts = want_u32(dev.max_contacts, &"device.max_contacts")?;
    if max_contacts == 0 {
        return Err("field `device.max_contacts`: must be at least 1".to_string());
    }
    Ok(SurfaceInfo {
        name,
        x,
        y,
        max_contacts,
    })
}

/// Reads a crowdtouch JSON Lines text a frame at a time.
pub(super) struct JsonlReader {
    lines: LineReader,
    on_bad: OnBadFrame,
    rules: FrameRules,
    /// The line being read.
    cur: FrameLine,
    /// Contacts down after the previous frame, with their ids.
    down: FrameLine,
    next_id: u32,
    last_t: Option<u64>,
    size_dropped: bool,
    /// The end was reached (and the last frame handed out).
    ended: bool,
}

impl JsonlReader {
    /// Reads the header (the first line that is not blank or a `#` comment).
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad header, [`RecordingError::Empty`]
    /// when there is none.
    pub(super) fn open(
        mut lines: LineReader,
        path: &Path,
        on_bad: OnBadFrame,
    ) -> Result<(JsonlReader, SurfaceInfo), RecordingError> {
        let surface = loop {
            let (line, l) = match lines.next_line() {
                Ok(Some((n, l))) => (n, l.trim()),
                Ok(None) => {
                    return Err(RecordingError::Empty {
                        path: path.to_path_buf(),
                    })
                }
                Err(f) => return Err(f.at(path, lines.line())),
            };
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            break json_header(l).map_err(|m| RecordingError::parse(path, line, m))?;
        };
        let header_cap = surface.max_contacts as usize;
        let rules = FrameRules {
            x: surface.x,
            y: surface.y,
            cap: header_cap.min(MAX_CONTACTS),
            cap_is_header: header_cap <= MAX_CONTACTS,
        };
        let reader = JsonlReader {
            lines,
            on_bad,
            rules,
            cur: FrameLine::default(),
            down: FrameLine::default(),
            next_id: 1,
            last_t: None,
            size_dropped: false,
            ended: false,
        };
        Ok((reader, surface))
    }

    /// The source, for reading again from the start.
    pub(super) fn into_lines(self) -> LineReader {
        self.lines
    }

    /// Bytes read so far.
    pub(super) fn consumed(&self) -> u64 {
        self.lines.consumed()
    }

    /// The next frame into `out`, and the line it is on; `None` after the last.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad frame with [`OnBadFrame::Stop`] (with
    /// [`OnBadFrame::Skip`] it is skipped and noted in `w`),
    /// [`RecordingError::Empty`] at the end when no frame was read.
    pub(super) fn next(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        loop {
            if self.ended {
                return Ok(None);
            }
            let parsed = match self.lines.next_line() {
                Ok(Some((_, l))) => {
                    let l = l.trim();
                    if l.is_empty() || l.starts_with('#') {
                        continue;
                    }
                    parse_frame(l, &self.rules, &mut self.cur, &mut self.size_dropped)
                }
                Ok(None) => return self.end(path, out, w),
                Err(LineFault::TooLong) => {
                    self.lines
                        .skip_rest()
                        .map_err(|e| LineFault::Io(e).at(path, self.lines.line()))?;
                    Err(too_long_message())
                }
                Err(f) => return Err(f.at(path, self.lines.line())),
            };
            let line = self.lines.line();
            let t = match parsed.and_then(|t| match self.last_t {
                Some(prev) if t < prev => Err(format!(
                    "field `t_us`: {t} is earlier than the previous frame's {prev}"
                )),
                _ => Ok(t),
            }) {
                Ok(t) => t,
                Err(m) => match self.on_bad {
                    OnBadFrame::Stop => return Err(RecordingError::parse(path, line, m)),
                    OnBadFrame::Skip => {
                        w.push(line, format!("{m}; frame skipped"));
                        continue;
                    }
                },
            };
            self.last_t = Some(t);
            self.frame(t, out);
            return Ok(Some(line));
        }
    }

    /// Builds the frame of the line just read into `out`.
    fn frame(&mut self, t: u64, out: &mut TouchFrame) {
        out.clear();
        out.t = Micros(t);
        out.t_queued = Micros::ZERO;
        let cancelled = self.cur.cancelled();
        // Ended first, in the previous frame's order, at their last position.
        for d in self.down.contacts() {
            if !self.cur.contacts().iter().any(|c| c.file_id == d.file_id) {
                let mut c = d.contact;
                c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
                c.flags.insert(if cancelled.contains(&d.file_id) {
                    ContactFlags::CANCELLED
                } else {
                    ContactFlags::UP
                });
                // At most 2 × MAX_CONTACTS; overflow keeps the first that fit.
                let _ = out.push(c);
            }
        }
        for c in self.cur.contacts_mut() {
            match self.down.contacts().iter().find(|d| d.file_id == c.file_id) {
                Some(d) => c.contact.id = d.contact.id,
                None => {
                    c.contact.id = ContactId(self.next_id);
                    self.next_id = self.next_id.wrapping_add(1);
                    c.contact.flags.insert(ContactFlags::DOWN);
                }
            }
            let _ = out.push(c.contact);
            c.contact.flags = ContactFlags(c.contact.flags.0 & ContactFlags::PALM.0);
        }
        std::mem::swap(&mut self.down, &mut self.cur);
    }

    /// The end of the text: the frame cancelling contacts still down, if any.
    fn end(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        self.ended = true;
        if self.size_dropped {
            w.push(
                0,
                "contact sizes (major/minor) ignored: the X axis resolution is unknown".into(),
            );
        }
        let Some(last) = self.last_t else {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            });
        };
        if self.down.contacts().is_empty() {
            return Ok(None);
        }
        out.clear();
        out.t = Micros(last) + Micros(END_CANCEL_US);
        out.t_queued = Micros::ZERO;
        for d in self.down.contacts() {
            let mut c = d.contact;
            c.flags.insert(ContactFlags::CANCELLED);
            let _ = out.push(c);
        }
        self.down.len = 0;
        Ok(Some(self.lines.line()))
    }
}
