//! Our track format, JSON Lines: a header object on the first line, then one sample
//! per line.
//!
//! ```text
//! {"format":"crowdtouch-tracks","version":1,"step_s":0.1,"source":"tap.jsonl"}
//! {"id":3,"t_s":0.0,"x":6.25,"y":3.5}
//! {"id":4,"t_s":0.0,"x":7.0,"y":3.5}
//! {"id":3,"t_s":0.1,"x":6.3,"y":3.5}
//! {"id":3,"t_s":2.0,"x":9.0,"y":3.5,"gap":true}
//! ```
//!
//! The header gives the frame step (seconds, the `step_s` of [`TrackSet`]) and
//! optionally where the tracks came from. A sample is person `id` at `(x, y)`
//! metres at `t_s` seconds; samples of different people may interleave, but each
//! person's times strictly increase. A sample is linked to the same person's
//! previous one (the person moves linearly between them, crowd-motion-editing
//! section 3.1) unless it carries `"gap":true`: then the person is away between the
//! two. A `gap` on a person's first sample has nothing to separate and is ignored.
//! Blank lines are skipped; unknown keys, a repeated key, a number that is not
//! finite and more than [`MAX_SAMPLES`] samples are errors.

use super::ReadError;
use crate::crowd::edit::flat::{coordinate_problem, time_problem, MAX_SAMPLES, MIN_SAMPLE_STEP_S};
use crate::crowd::edit::tracks::{Track, TrackSet};
use crate::geom::Vec2;
use serde::Deserialize;
use std::collections::HashMap;
use std::fmt::Write as _;

/// The `format` value of the header.
pub const JSONL_FORMAT: &str = "crowdtouch-tracks";
/// The version this reader reads and the writer writes.
pub const JSONL_VERSION: u32 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    format: String,
    version: u32,
    step_s: f64,
    #[serde(default)]
    #[allow(dead_code)]
    source: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Sample {
    id: u64,
    t_s: f64,
    x: f64,
    y: f64,
    #[serde(default)]
    gap: bool,
}

/// Reads a JSON Lines track file.
///
/// # Errors
/// [`ReadError`] naming the line: a missing, malformed or foreign header, another
/// version, a step that is not a positive number of seconds, a sample that is not
/// one JSON object with exactly the fields above, a time or position that is not
/// finite, a person seen twice at one time or going back in time, more than
/// [`MAX_SAMPLES`] samples. An empty file (no header) is an error at line 0.
pub fn read_jsonl(text: &str) -> Result<TrackSet, ReadError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let Some((hline, htext)) = lines.next() else {
        return Err(ReadError::at(
            0,
            format!("empty: expected a `{JSONL_FORMAT}` header line"),
        ));
    };
    let header: Header = object(htext).map_err(|e| {
        ReadError::at(
            hline,
            format!("header: {} (expected {{\"format\":\"{JSONL_FORMAT}\",\"version\":{JSONL_VERSION},\"step_s\":…}})", json_error(&e)),
        )
    })?;
    if header.format != JSONL_FORMAT {
        return Err(ReadError::at(
            hline,
            format!(
                "header: format `{}` is not `{JSONL_FORMAT}`",
                clip(&header.format)
            ),
        ));
    }
    if header.version != JSONL_VERSION {
        return Err(ReadError::at(
            hline,
            format!(
                "header: version {} is not supported (this reader reads version {JSONL_VERSION})",
                header.version
            ),
        ));
    }
    if !(header.step_s.is_finite() && header.step_s > 0.0) {
        return Err(ReadError::at(
            hline,
            format!(
                "header: step_s must be a positive number of seconds, not {}",
                header.step_s
            ),
        ));
    }
    let mut tracks: Vec<Track> = Vec::new();
    // Per person: index in `tracks` and the line of its last sample.
    let mut people: HashMap<u64, (usize, usize)> = HashMap::new();
    let mut samples = 0usize;
    for (line, s) in lines {
        let sample: Sample = object(s).map_err(|e| {
            ReadError::at(
                line,
                format!(
                    "{} (expected {{\"id\":…,\"t_s\":…,\"x\":…,\"y\":…}})",
                    json_error(&e)
                ),
            )
        })?;
        let id = sample.id;
        // `col: field: what`, so the file's error reads `file:line:col: field: what`.
        let col = |key: &str| s.find(&format!("\"{key}\"")).map_or(1, |c| c + 1);
        for (key, problem) in [
            ("t_s", time_problem(sample.t_s)),
            ("x", coordinate_problem(sample.x)),
            ("y", coordinate_problem(sample.y)),
        ] {
            if let Some(what) = problem {
                return Err(ReadError::at(
                    line,
                    format!("{}: {key}: person {id}: {what}", col(key)),
                ));
            }
        }
        samples += 1;
        if samples > MAX_SAMPLES {
            return Err(ReadError::at(
                line,
                format!("more than {MAX_SAMPLES} samples"),
            ));
        }
        let p = Vec2::new(sample.x, sample.y);
        match people.get_mut(&id) {
            None => {
                people.insert(id, (tracks.len(), line));
                tracks.push(Track {
                    id,
                    points: vec![p],
                    times_s: vec![sample.t_s],
                    linked: Vec::new(),
                });
            }
            Some((k, last_line)) => {
                let tr = &mut tracks[*k];
                let last = *tr.times_s.last().unwrap_or(&f64::NEG_INFINITY);
                check_order(id, sample.t_s, last, line, *last_line)?;
                tr.linked.push(!sample.gap);
                tr.points.push(p);
                tr.times_s.push(sample.t_s);
                *last_line = line;
            }
        }
    }
    Ok(TrackSet {
        tracks,
        step_s: header.step_s,
    })
}

/// The error for person `id`'s sample at `t_s` on `line` when its previous sample
/// (at `last_s`, on `last_line`) is not earlier.
pub(super) fn check_order(
    id: u64,
    t_s: f64,
    last_s: f64,
    line: usize,
    last_line: usize,
) -> Result<(), ReadError> {
    if t_s == last_s {
        Err(ReadError::at(
            line,
            format!("person {id} appears twice at {t_s} s (also line {last_line})"),
        ))
    } else if t_s < last_s {
        Err(ReadError::at(
            line,
            format!("person {id}: time {t_s} s comes after {last_s} s (line {last_line}); a person's samples must go forward in time"),
        ))
    } else if t_s - last_s < MIN_SAMPLE_STEP_S {
        Err(ReadError::at(
            line,
            format!("person {id}: time {t_s} s is less than {MIN_SAMPLE_STEP_S:e} s after {last_s} s (line {last_line})"),
        ))
    } else {
        Ok(())
    }
}

/// Writes a track set as JSON Lines: the header (with `source` when given), then
/// every sample sorted by time then id, `"gap":true` on the samples that are not
/// linked to their person's previous one. Numbers are written in their shortest
/// form that reads back to the same `f64`.
pub fn write_jsonl(set: &TrackSet, source: Option<&str>) -> String {
    let mut out = String::with_capacity(80 + set.samples() * 64);
    out.push_str("{\"format\":");
    out.push_str(&json_str(JSONL_FORMAT));
    let _ = write!(
        out,
        ",\"version\":{JSONL_VERSION},\"step_s\":{}",
        num(set.step_s)
    );
    if let Some(s) = source {
        out.push_str(",\"source\":");
        out.push_str(&json_str(s));
    }
    out.push_str("}\n");
    // (time, id, position, gap before it)
    let mut rows: Vec<(f64, u64, Vec2, bool)> = Vec::with_capacity(set.samples());
    for t in &set.tracks {
        for (j, (p, ts)) in t.points.iter().zip(&t.times_s).enumerate() {
            let gap = j > 0 && !t.linked.get(j - 1).copied().unwrap_or(true);
            rows.push((*ts, t.id, *p, gap));
        }
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for (ts, id, p, gap) in rows {
        let _ = write!(
            out,
            "{{\"id\":{id},\"t_s\":{},\"x\":{},\"y\":{}",
            num(ts),
            num(p.x),
            num(p.y)
        );
        out.push_str(if gap { ",\"gap\":true}\n" } else { "}\n" });
    }
    out
}

/// One JSON object into `T` (serde would also take an array of the field values).
fn object<T: serde::de::DeserializeOwned>(s: &str) -> Result<T, serde_json::Error> {
    if s.starts_with('{') {
        serde_json::from_str(s)
    } else {
        Err(serde::de::Error::custom("expected a JSON object"))
    }
}

/// `v` as JSON (`null` when not finite, which a validated set never holds).
fn num(v: f64) -> String {
    serde_json::to_string(&v).unwrap_or_else(|_| "null".into())
}

fn json_str(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

/// serde_json's message without its `at line 1 column N` (every object is parsed
/// from one line), the column given separately.
fn json_error(e: &serde_json::Error) -> String {
    let msg = e.to_string();
    let suffix = format!(" at line {} column {}", e.line(), e.column());
    let msg = msg.strip_suffix(&suffix).unwrap_or(&msg);
    match e.column() {
        0 => msg.to_string(),
        c => format!("column {c}: {msg}"),
    }
}

/// A value of the input as a message shows it: its first 40 characters, control
/// characters escaped.
fn clip(s: &str) -> String {
    let shown: String = s.chars().take(40).collect();
    crate::located::escape(&shown)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = r#"{"format":"crowdtouch-tracks","version":1,"step_s":0.5}"#;

    #[test]
    fn reads_interleaved_people_links_and_gaps() {
        let text = format!(
            "{HEAD}\n\
             {{\"id\":1,\"t_s\":0.0,\"x\":1.0,\"y\":2.0}}\n\
             {{\"id\":2,\"t_s\":0.0,\"x\":5.0,\"y\":5.0}}\n\
             \n\
             {{\"id\":1,\"t_s\":0.5,\"x\":1.5,\"y\":2.0}}\n\
             {{\"id\":1,\"t_s\":2.0,\"x\":2.5,\"y\":2.0,\"gap\":true}}\n\
             {{\"id\":1,\"t_s\":2.5,\"x\":3,\"y\":2,\"gap\":false}}\n"
        );
        let set = read_jsonl(&text).unwrap();
        set.validate().unwrap();
        assert_eq!(set.step_s, 0.5);
        assert_eq!(set.tracks.len(), 2);
        let a = &set.tracks[0];
        assert_eq!(a.id, 1);
        assert_eq!(a.times_s, vec![0.0, 0.5, 2.0, 2.5]);
        assert_eq!(a.linked, vec![true, false, true]);
        assert_eq!(set.tracks[1].len(), 1, "a single sample is kept");
    }

    #[test]
    fn header_with_source_is_read() {
        let text =
            "{\"format\":\"crowdtouch-tracks\",\"version\":1,\"step_s\":0.1,\"source\":\"x\"}\n";
        let set = read_jsonl(text).unwrap();
        assert!(set.tracks.is_empty());
        assert_eq!(set.step_s, 0.1);
    }

    #[test]
    fn errors_name_the_line() {
        let s = |body: &str| format!("{HEAD}\n{body}\n");
        let bad: Vec<(String, usize, &str)> = vec![
            (String::new(), 0, "empty"),
            ("garbage\n".into(), 1, "header: expected a JSON object"),
            ("{garbage\n".into(), 1, "header: column 2"),
            ("{\"format\":\"other\",\"version\":1,\"step_s\":1}".into(), 1, "format `other`"),
            ("{\"format\":\"crowdtouch-tracks\",\"version\":2,\"step_s\":1}".into(), 1, "version 2 is not supported"),
            ("{\"format\":\"crowdtouch-tracks\",\"version\":1,\"step_s\":0}".into(), 1, "step_s must be a positive"),
            ("{\"format\":\"crowdtouch-tracks\",\"version\":1}".into(), 1, "missing field `step_s`"),
            ("{\"format\":\"crowdtouch-tracks\",\"version\":1,\"step_s\":1,\"fps\":2}".into(), 1, "unknown field `fps`"),
            (s("{\"id\":1,\"t_s\":0,\"x\":1}"), 2, "missing field `y`"),
            (s("{\"id\":1,\"t_s\":0,\"x\":1,\"y\":2,\"z\":0}"), 2, "unknown field `z`"),
            (s("{\"id\":1,\"t_s\":0,\"x\":1,\"x\":1,\"y\":2}"), 2, "duplicate field `x`"),
            (s("{\"id\":-1,\"t_s\":0,\"x\":1,\"y\":2}"), 2, "column"),
            (s("{\"id\":1,\"t_s\":0,\"x\":NaN,\"y\":2}"), 2, "column"),
            (s("{\"id\":1,\"t_s\":0,\"x\":1e999,\"y\":2}"), 2, "column"),
            (s("{\"id\":1,\"t_s\":0,\"x\":1e308,\"y\":-1e308}"), 2, "17: x: person 1: 1e308 m is beyond the coordinate bound of ±1e6 m"),
            (s("{\"id\":1,\"t_s\":-5e9,\"x\":1,\"y\":2}"), 2, "9: t_s: person 1: -5e9 s is beyond the time bound"),
            (
                s("{\"id\":1,\"t_s\":1,\"x\":1,\"y\":2}\n{\"id\":1,\"t_s\":1.0000001,\"x\":1,\"y\":2}"),
                3,
                "less than 1e-6 s after 1 s (line 2)",
            ),
            (s("{\"id\":1,\"t_s\":\"0\",\"x\":1,\"y\":2}"), 2, "invalid type"),
            (s("[1,0,1,2]"), 2, "expected a JSON object"),
            (s("not json"), 2, "expected a JSON object"),
            (s("{\"id\":1,"), 2, "column"),
            (
                s("{\"id\":1,\"t_s\":1,\"x\":1,\"y\":2}\n{\"id\":1,\"t_s\":1,\"x\":1,\"y\":2}"),
                3,
                "person 1 appears twice at 1 s (also line 2)",
            ),
            (
                s("{\"id\":1,\"t_s\":1,\"x\":1,\"y\":2}\n{\"id\":2,\"t_s\":0,\"x\":1,\"y\":2}\n{\"id\":1,\"t_s\":0.5,\"x\":1,\"y\":2}"),
                4,
                "person 1: time 0.5 s comes after 1 s (line 2)",
            ),
        ];
        for (text, line, what) in bad {
            let Err(e) = read_jsonl(&text) else {
                panic!("{text:?} was read");
            };
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.to_string().contains(what), "{text:?}: {e}");
        }
    }

    #[test]
    fn writes_sorted_with_gaps_only_where_needed() {
        let set = TrackSet {
            tracks: vec![
                Track {
                    id: 9,
                    points: vec![
                        Vec2::new(0.0, 0.0),
                        Vec2::new(1.0, 0.0),
                        Vec2::new(2.0, 0.5),
                    ],
                    times_s: vec![0.0, 0.5, 3.0],
                    linked: vec![true, false],
                },
                Track::linked(2, vec![Vec2::new(-1.0, 0.25)], vec![0.5]),
            ],
            step_s: 0.5,
        };
        let text = write_jsonl(&set, Some("a \"b\""));
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines,
            vec![
                r#"{"format":"crowdtouch-tracks","version":1,"step_s":0.5,"source":"a \"b\""}"#,
                r#"{"id":9,"t_s":0.0,"x":0.0,"y":0.0}"#,
                r#"{"id":2,"t_s":0.5,"x":-1.0,"y":0.25}"#,
                r#"{"id":9,"t_s":0.5,"x":1.0,"y":0.0}"#,
                r#"{"id":9,"t_s":3.0,"x":2.0,"y":0.5,"gap":true}"#,
            ]
        );
        let again = read_jsonl(&text).unwrap();
        assert_eq!(again.tracks.len(), 2);
        assert_eq!(again.tracks[0], set.tracks[0]);
        assert_eq!(again.tracks[1], set.tracks[1]);
    }
}
