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
use super::recording_type::{Recording, END_CANCEL_US};
use super::warnings::Warnings;
use crate::input::{AxisRange, SurfaceInfo};
use crate::located::json_kind;
use crate::vocab::Micros;
use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame, MAX_CONTACTS};
use serde_json::{Map, Value};
use std::path::Path;

/// The `format` value of a crowdtouch JSON Lines header.
pub const JSONL_FORMAT: &str = "crowdtouch-touch";
/// The JSON Lines format version this module reads and writes.
pub const JSONL_VERSION: u64 = 1;

fn want_obj<'v>(v: Option<&'v Value>, field: &str) -> Result<&'v Map<String, Value>, String> {
    match v {
        Some(Value::Object(m)) => Ok(m),
        Some(o) => Err(format!(
            "field `{field}`: expected an object, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_f64(v: Option<&Value>, field: &str) -> Result<f64, String> {
    match v {
        Some(Value::Number(n)) => n
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("field `{field}`: {n} is not a finite number")),
        Some(o) => Err(format!(
            "field `{field}`: expected a number, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_u64(v: Option<&Value>, field: &str) -> Result<u64, String> {
    match v {
        Some(Value::Number(n)) => n
            .as_u64()
            .ok_or_else(|| format!("field `{field}`: {n} is not a non-negative integer")),
        Some(o) => Err(format!(
            "field `{field}`: expected a non-negative integer, found {}",
            json_kind(o)
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

fn want_u32(v: Option<&Value>, field: &str) -> Result<u32, String> {
    let n = want_u64(v, field)?;
    u32::try_from(n).map_err(|_| format!("field `{field}`: {n} does not fit 32 bits"))
}

fn parse_json_line(l: &str) -> Result<Map<String, Value>, String> {
    match serde_json::from_str::<Value>(l) {
        Ok(Value::Object(m)) => Ok(m),
        Ok(o) => Err(format!("expected a JSON object, found {}", json_kind(&o))),
        Err(e) => Err(format!("invalid JSON at column {}: {e}", e.column())),
    }
}

fn json_axis(dev: &Map<String, Value>, key: &str) -> Result<AxisRange, String> {
    let f = format!("device.{key}");
    let a = want_obj(dev.get(key), &f)?;
    let min = want_f64(a.get("min"), &format!("{f}.min"))?;
    let max = want_f64(a.get("max"), &format!("{f}.max"))?;
    if max <= min {
        return Err(format!("field `{f}`: empty range (min {min}, max {max})"));
    }
    let resolution = match a.get("resolution") {
        None | Some(Value::Null) => 0.0,
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
    let m = parse_json_line(l)?;
    let Some(format) = m.get("format") else {
        return Err(format!(
            "missing header: the first line must be {{\"format\":\"{JSONL_FORMAT}\",\"version\":1,\"device\":{{…}}}}"
        ));
    };
    if format.as_str() != Some(JSONL_FORMAT) {
        return Err(format!(
            "field `format`: expected \"{JSONL_FORMAT}\", found {format}"
        ));
    }
    let dev = want_obj(m.get("device"), "device")?;
    let name = match dev.get("name") {
        Some(Value::String(s)) => s.clone(),
        Some(o) => {
            return Err(format!(
                "field `device.name`: expected a string, found {}",
                json_kind(o)
            ))
        }
        None => return Err("missing field `device.name`".to_string()),
    };
    let x = json_axis(dev, "x")?;
    let y = json_axis(dev, "y")?;
    let max_contacts = want_u32(dev.get("max_contacts"), "device.max_contacts")?;
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

/// One contact of a JSON Lines frame, still in file terms.
#[derive(Copy, Clone, Debug)]
struct FileContact {
    file_id: u32,
    contact: Contact,
}

/// Parses a frame line into `(t_us, contacts, cancelled ids)`, normalising positions.
fn json_frame(
    l: &str,
    s: &SurfaceInfo,
    contacts: &mut Vec<FileContact>,
    cancelled: &mut Vec<u32>,
    size_dropped: &mut bool,
) -> Result<u64, String> {
    contacts.clear();
    cancelled.clear();
    let m = parse_json_line(l)?;
    if m.contains_key("format") {
        return Err("a second header line".to_string());
    }
    let t_us = want_u64(m.get("t_us"), "t_us")?;
    let list = match m.get("contacts") {
        Some(Value::Array(a)) => a,
        Some(o) => {
            return Err(format!(
                "field `contacts`: expected an array, found {}",
                json_kind(o)
            ))
        }
        None => return Err("missing field `contacts`".to_string()),
    };
    if list.len() > MAX_CONTACTS {
        return Err(format!(
            "field `contacts`: {} contacts, more than the {MAX_CONTACTS} a frame holds",
            list.len()
        ));
    }
    for (i, c) in list.iter().enumerate() {
        let f = |k: &str| format!("contacts[{i}].{k}");
        let o = want_obj(Some(c), &format!("contacts[{i}]"))?;
        let file_id = want_u32(o.get("id"), &f("id"))?;
        if contacts.iter().any(|c| c.file_id == file_id) {
            return Err(format!(
                "field `{}`: id {file_id} appears twice in the frame",
                f("id")
            ));
        }
        let x = want_f64(o.get("x"), &f("x"))?;
        let y = want_f64(o.get("y"), &f("y"))?;
        let opt = |k: &str| -> Result<Option<f64>, String> {
            match o.get(k) {
                None | Some(Value::Null) => Ok(None),
                v => {
                    let x = want_f64(v, &f(k))?;
                    if x < 0.0 {
                        return Err(format!("field `{}`: {x} is negative", f(k)));
                    }
                    Ok(Some(x))
                }
            }
        };
        let pressure = opt("pressure")?;
        if let Some(p) = pressure {
            if p > 1.0 {
                return Err(format!("field `{}`: {p} is outside 0..=1", f("pressure")));
            }
        }
        let to_mm = |v: Option<f64>, dropped: &mut bool| {
            let v = v?;
            if s.x.resolution > 0.0 {
                Some((v / s.x.resolution) as f32)
            } else {
                *dropped = true;
                None
            }
        };
        let major_mm = to_mm(opt("major")?, size_dropped);
        let minor_mm = to_mm(opt("minor")?, size_dropped);
        let palm = match o.get("palm") {
            None | Some(Value::Null) => false,
            Some(Value::Bool(b)) => *b,
            Some(v) => {
                return Err(format!(
                    "field `{}`: expected a boolean, found {}",
                    f("palm"),
                    json_kind(v)
                ))
            }
        };
        let flags = if palm {
            ContactFlags::PALM
        } else {
            ContactFlags::NONE
        };
        contacts.push(FileContact {
            file_id,
            contact: Contact {
                id: ContactId(0),
                x: s.x.normalise(x),
                y: s.y.normalise(y),
                pressure: pressure.map(|p| p as f32),
                major_mm,
                minor_mm,
                flags,
            },
        });
    }
    match m.get("cancelled") {
        None | Some(Value::Null) => {}
        Some(Value::Array(a)) => {
            for (i, v) in a.iter().enumerate() {
                cancelled.push(want_u32(Some(v), &format!("cancelled[{i}]"))?);
            }
        }
        Some(o) => {
            return Err(format!(
                "field `cancelled`: expected an array, found {}",
                json_kind(o)
            ))
        }
    }
    Ok(t_us)
}

/// Reads a crowdtouch JSON Lines text.
pub(super) fn parse_jsonl(
    text: &str,
    path: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    let surface = json_header(header).map_err(|m| perr(hline, m))?;
    let mut warnings = Warnings::default();
    let mut frames: Vec<TouchFrame> = Vec::new();
    // Contacts down after the previous frame: (file id, contact).
    let mut down: Vec<FileContact> = Vec::new();
    let mut cur: Vec<FileContact> = Vec::new();
    let mut cancelled: Vec<u32> = Vec::new();
    let mut next_id: u32 = 1;
    let mut last_t: Option<u64> = None;
    let mut size_dropped = false;
    for (line, l) in lines {
        let parsed =
            json_frame(l, &surface, &mut cur, &mut cancelled, &mut size_dropped).and_then(|t| {
                match last_t {
                    Some(prev) if t < prev => Err(format!(
                        "field `t_us`: {t} is earlier than the previous frame's {prev}"
                    )),
                    _ => Ok(t),
                }
            });
        let t = match parsed {
            Ok(t) => t,
            Err(m) => match on_bad {
                OnBadFrame::Stop => return Err(perr(line, m)),
                OnBadFrame::Skip => {
                    warnings.push(line, format!("{m}; frame skipped"));
                    continue;
                }
            },
        };
        last_t = Some(t);
        let mut frame = TouchFrame::new(Micros(t));
        // Ended first, in the previous frame's order, at their last position.
        for d in &down {
            if !cur.iter().any(|c| c.file_id == d.file_id) {
                let mut c = d.contact;
                c.flags = ContactFlags(c.flags.0 & ContactFlags::PALM.0);
                c.flags.insert(if cancelled.contains(&d.file_id) {
                    ContactFlags::CANCELLED
                } else {
                    ContactFlags::UP
                });
                // At most 2 × MAX_CONTACTS; overflow keeps the first that fit.
                let _ = frame.push(c);
            }
        }
        for c in cur.iter_mut() {
            match down.iter().find(|d| d.file_id == c.file_id) {
                Some(d) => c.contact.id = d.contact.id,
                None => {
                    c.contact.id = ContactId(next_id);
                    next_id = next_id.wrapping_add(1);
                    c.contact.flags.insert(ContactFlags::DOWN);
                }
            }
            let _ = frame.push(c.contact);
            c.contact.flags = ContactFlags(c.contact.flags.0 & ContactFlags::PALM.0);
        }
        std::mem::swap(&mut down, &mut cur);
        frames.push(frame);
    }
    if size_dropped {
        warnings.push(
            0,
            "contact sizes (major/minor) ignored: the X axis resolution is unknown".into(),
        );
    }
    let Some(last) = frames.last().map(|f| f.t) else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    if !down.is_empty() {
        let mut frame = TouchFrame::new(last + Micros(END_CANCEL_US));
        for d in &down {
            let mut c = d.contact;
            c.flags.insert(ContactFlags::CANCELLED);
            let _ = frame.push(c);
        }
        frames.push(frame);
    }
    Ok(Recording {
        surface,
        frames,
        warnings: warnings.finish(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("t.jsonl")
    }

    const HEADER: &str = r#"{"format":"crowdtouch-touch","version":1,"device":{"name":"d","x":{"min":0,"max":1000,"resolution":10},"y":{"min":0,"max":500},"max_contacts":4}}"#;

    #[test]
    fn jsonl_derives_flags() {
        let text = format!(
            "{HEADER}\n# comment\n\n{}\n{}\n{}\n",
            r#"{"t_us":0,"contacts":[{"id":7,"x":100,"y":250}]}"#,
            r#"{"t_us":8333,"contacts":[{"id":7,"x":200,"y":250},{"id":9,"x":0,"y":0,"pressure":0.5}]}"#,
            r#"{"t_us":16666,"contacts":[{"id":9,"x":0,"y":0}]}"#,
        );
        let rec = parse_jsonl(&text, p(), OnBadFrame::Stop).unwrap();
        let fl: Vec<Vec<(u32, ContactFlags)>> = rec
            .frames
            .iter()
            .map(|f| f.contacts().iter().map(|c| (c.id.0, c.flags)).collect())
            .collect();
        assert_eq!(
            fl,
            vec![
                vec![(1, ContactFlags::DOWN)],
                vec![(1, ContactFlags::NONE), (2, ContactFlags::DOWN)],
                vec![(1, ContactFlags::UP), (2, ContactFlags::NONE)],
                vec![(2, ContactFlags::CANCELLED)],
            ]
        );
        assert_eq!(rec.frames[3].t, Micros(16_666 + END_CANCEL_US));
        // The lift is reported at the last position.
        assert!((rec.frames[2].contacts()[0].x - 0.2).abs() < 1e-6);
        assert_eq!(rec.frames[1].contacts()[1].pressure, Some(0.5));
        assert!((rec.frames[0].contacts()[0].y - 0.5).abs() < 1e-6);
    }
}
