//! Tracks as CSV: one sample per line, `t,id,x,y` (seconds, a whole-number id,
//! metres), an optional header line `t,id,x,y`, whitespace around fields allowed,
//! blank lines and lines starting with `#` skipped. Rows of different people may
//! interleave; each person's times strictly increase.
//!
//! CSV has no links: two consecutive samples of a person are linked (the person
//! moves linearly between them, crowd-motion-editing section 3.1) when they are at
//! most [`LINK_STEPS`] frame steps apart, else the person is away in between (a
//! gap). The step is the one the caller gives ([`ReadOptions::csv_step_s`](super::ReadOptions::csv_step_s)),
//! else the median of every person's consecutive time differences, else (only
//! single samples) one second.
//!
//! A person with a single sample is kept: present at that instant only.

use super::jsonl::check_order;
use super::text::{clip, whole};
use super::ReadError;
use crate::crowd::edit::flat::{coordinate_problem, time_problem, FlatTracks, MAX_SAMPLES};
use crate::crowd::edit::tracks::TrackSet;
use crate::geom::Vec2;
use std::collections::HashMap;
use std::fmt::Write as _;

/// Consecutive samples at most this many frame steps apart are linked.
pub const LINK_STEPS: f64 = 1.5;
/// The step of a file whose people all have a single sample (seconds).
pub const SINGLE_SAMPLE_STEP_S: f64 = 1.0;
/// The header line (fields compared without surrounding whitespace).
pub const CSV_HEADER: [&str; 4] = ["t", "id", "x", "y"];

/// Reads a CSV track file; `step_s` is the frame step, `None` to take the median.
///
/// # Errors
/// As [`read_csv_flat`].
pub fn read_csv(text: &str, step_s: Option<f64>) -> Result<TrackSet, ReadError> {
    read_csv_flat(text, step_s).map(|f| TrackSet::from(&f))
}

/// One row of a CSV file: time (s), id, position (m).
struct Row {
    t: f64,
    id: u64,
    p: Vec2,
}

/// The rows of a CSV text with their line numbers (from 1), blank lines, comments
/// and the header skipped; each row parsed and checked on its own (fields, numbers,
/// bounds).
fn rows(text: &str) -> impl Iterator<Item = Result<(usize, Row), ReadError>> + '_ {
    let mut first = true;
    text.lines().enumerate().filter_map(move |(i, raw)| {
        let line = i + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            return None;
        }
        // At most five pieces (a fifth means too many fields), without allocating:
        // the reader runs this twice per row.
        let mut pieces = [""; 5];
        let mut n = 0;
        for f in s.splitn(5, ',') {
            pieces[n] = f.trim();
            n += 1;
        }
        let fields = &pieces[..n];
        if std::mem::take(&mut first) && fields == CSV_HEADER {
            return None;
        }
        Some(row(raw, line, fields).map(|r| (line, r)))
    })
}

/// Parses one row's `fields` (`raw` is the line, for columns in errors).
fn row(raw: &str, line: usize, fields: &[&str]) -> Result<Row, ReadError> {
    if fields.len() != 4 {
        return Err(ReadError::at(
            line,
            format!(
                "expected `t,id,x,y`, found {}",
                if fields.len() > 4 {
                    "more than 4 fields".to_string()
                } else {
                    format!("{} field(s)", fields.len())
                }
            ),
        ));
    }
    let number = |k: usize, name: &str| -> Result<f64, ReadError> {
        fields[k].parse::<f64>().map_err(|_| {
            ReadError::at(
                line,
                format!("{name} `{}` is not a number", clip(fields[k])),
            )
        })
    };
    let t = number(0, "t")?;
    let id = match fields[1].parse::<u64>() {
        Ok(id) => id,
        Err(_) => whole(number(1, "id")?).ok_or_else(|| {
            ReadError::at(
                line,
                format!(
                    "id `{}` is not a non-negative whole number",
                    clip(fields[1])
                ),
            )
        })?,
    };
    let (x, y) = (number(2, "x")?, number(3, "y")?);
    // `col: field: what`, so the file's error reads `file:line:col: field: what`.
    let col = |k: usize| {
        let mut at = 0;
        for (n, piece) in raw.split(',').enumerate() {
            if n == k {
                return at + piece.len() - piece.trim_start().len() + 1;
            }
            at += piece.len() + 1;
        }
        1
    };
    for (k, name, problem) in [
        (0, "t", time_problem(t)),
        (2, "x", coordinate_problem(x)),
        (3, "y", coordinate_problem(y)),
    ] {
        if let Some(what) = problem {
            return Err(ReadError::at(
                line,
                format!("{}: {name}: person {id}: {what}", col(k)),
            ));
        }
    }
    Ok(Row {
        t,
        id,
        p: Vec2::new(x, y),
    })
}

/// Reads a CSV track file straight into [`FlatTracks`] (people in order of first
/// appearance); `step_s` is the frame step, `None` to take the median.
///
/// Two passes over the text: the first checks every row and counts each person's
/// samples, the second puts each sample in its place. Besides the text and the
/// result, the reading holds an id map and 4 bytes per row: a million people of
/// two samples each read in about 150 MB with the text, where one vector per
/// person and field would take 270 MB.
///
/// # Errors
/// [`ReadError`] naming the line: not four fields, a field that is not a number, an
/// id that is not a non-negative whole number, a time or position that is not
/// finite, a person seen twice at one time or going back in time, more than
/// [`MAX_SAMPLES`] rows; a given step that is not a positive number of seconds is
/// an error at line 0.
pub fn read_csv_flat(text: &str, step_s: Option<f64>) -> Result<FlatTracks, ReadError> {
    if let Some(s) = step_s {
        if !(s.is_finite() && s > 0.0) {
            return Err(ReadError::at(
                0,
                format!("the CSV step must be a positive number of seconds, not {s}"),
            ));
        }
    }
    // Pass 1: every row checked; per person its id, sample count, and the time
    // and line of its last sample; per row its person.
    let mut index: HashMap<u64, u32> = HashMap::new();
    let mut ids: Vec<u64> = Vec::new();
    let mut count: Vec<u32> = Vec::new();
    let mut last: Vec<(f64, u32)> = Vec::new();
    let mut person_of_row: Vec<u32> = Vec::new();
    for r in rows(text) {
        let (line, Row { t, id, .. }) = r?;
        if person_of_row.len() == MAX_SAMPLES {
            return Err(ReadError::at(line, format!("more than {MAX_SAMPLES} rows")));
        }
        let k = match index.get(&id) {
            Some(&k) => {
                let k = k as usize;
                check_order(id, t, last[k].0, line, last[k].1 as usize)?;
                count[k] += 1;
                k
            }
            None => {
                let k = ids.len();
                index.insert(id, k as u32);
                ids.push(id);
                count.push(1);
                last.push((t, 0));
                k
            }
        };
        last[k] = (t, line as u32);
        person_of_row.push(k as u32);
    }
    drop((index, last));
    // Pass 2: each person's samples together, in file order (their time order).
    let samples = person_of_row.len();
    let mut starts: Vec<u32> = Vec::with_capacity(ids.len() + 1);
    starts.push(0);
    for c in &count {
        starts.push(starts[starts.len() - 1] + c);
    }
    // `count` becomes each person's next free place.
    count.copy_from_slice(&starts[..ids.len()]);
    let mut points = vec![Vec2::zeros(); samples];
    let mut times_s = vec![0.0; samples];
    for (r, k) in rows(text).zip(&person_of_row) {
        let (_, Row { t, p, .. }) = r?;
        let at = &mut count[*k as usize];
        points[*at as usize] = p;
        times_s[*at as usize] = t;
        *at += 1;
    }
    drop((person_of_row, count));
    let mut flat = FlatTracks::from_parts(ids, starts, points, times_s, vec![false; samples], 1.0);
    let step_s = step_s.unwrap_or_else(|| median_step(flat.time_steps()));
    flat.link_within(step_s, LINK_STEPS * step_s);
    Ok(flat)
}

/// The median of every person's consecutive time differences `steps` (the upper
/// median for an even count), or [`SINGLE_SAMPLE_STEP_S`] when there are none.
pub fn median_step(steps: impl Iterator<Item = f64>) -> f64 {
    let mut d: Vec<f64> = steps.filter(|d| d.is_finite() && *d > 0.0).collect();
    if d.is_empty() {
        return SINGLE_SAMPLE_STEP_S;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Writes a track set as CSV: the header `t,id,x,y`, then every sample sorted by
/// time then id. Links are not written: read back, samples more than
/// [`LINK_STEPS`] steps apart are gaps and closer ones linked, whatever the set said.
pub fn write_csv(set: &TrackSet) -> String {
    let mut rows: Vec<(f64, u64, Vec2)> = Vec::with_capacity(set.samples());
    for t in &set.tracks {
        for (p, ts) in t.points.iter().zip(&t.times_s) {
            rows.push((*ts, t.id, *p));
        }
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut out = String::with_capacity(8 + rows.len() * 48);
    out.push_str("t,id,x,y\n");
    for (t, id, p) in rows {
        let _ = writeln!(out, "{t},{id},{},{}", p.x, p.y);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crowd::edit::tracks::Track;

    #[test]
    fn reads_header_whitespace_and_links_by_median_step() {
        let text = " t , id , x , y \n\
                    0.0, 1, 1.0, 2.0\n\
                    0.0,2,5,5\n\
                    # a comment\n\
                    0.4,1,1.5,2.0\n\
                    0.8,1,2.0,2.0\n\
                    2.0,1,2.5,2.0\n";
        let set = read_csv(text, None).unwrap();
        set.validate().unwrap();
        assert_eq!(set.step_s, 0.4, "median of 0.4, 0.4, 1.2");
        let a = &set.tracks[0];
        assert_eq!(a.id, 1);
        assert_eq!(a.times_s, vec![0.0, 0.4, 0.8, 2.0]);
        assert_eq!(a.linked, vec![true, true, false]);
        assert_eq!(set.tracks[1].len(), 1, "a single sample is kept");
    }

    #[test]
    fn a_word_with_control_characters_is_quoted_escaped() {
        let e = read_csv("t,id,x,y\n0,1,\u{1b}[2J,0\n", None).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("`\\u{1b}[2J`"), "{text}");
        assert!(!text.contains('\u{1b}'), "{text:?}");
    }

    #[test]
    fn the_flat_reader_keeps_people_in_order_of_first_appearance() {
        let text = "t,id,x,y\n0,9,0,0\n0,4,1,1\n1,9,0.5,0\n# c\n\n1,4,1,2\n5,9,3,0\n";
        let flat = read_csv_flat(text, None).unwrap();
        let set = read_csv(text, None).unwrap();
        assert_eq!(TrackSet::from(&flat), set);
        assert_eq!(set.tracks.iter().map(|t| t.id).collect::<Vec<_>>(), [9, 4]);
        assert_eq!(set.tracks[0].times_s, [0.0, 1.0, 5.0]);
        assert_eq!(set.tracks[0].linked, [true, false]);
        assert_eq!(set.tracks[1].points[1], Vec2::new(1.0, 2.0));
    }

    #[test]
    fn the_first_bad_line_is_the_one_named() {
        // Line 3 goes back in time; line 4 is not a number: line 3 is reported.
        let e = read_csv("0,1,0,0\n1,1,0,0\n0.5,1,0,0\n2,1,x,0\n", None).unwrap_err();
        assert_eq!(e.line, 3, "{e}");
    }

    #[test]
    fn a_given_step_decides_the_links() {
        let text = "0,1,0,0\n1,1,1,0\n2.6,1,2,0\n";
        let set = read_csv(text, Some(1.0)).unwrap();
        assert_eq!(set.step_s, 1.0);
        assert_eq!(set.tracks[0].linked, vec![true, false]);
        let set = read_csv(text, Some(2.0)).unwrap();
        assert_eq!(set.tracks[0].linked, vec![true, true]);
    }

    #[test]
    fn single_samples_only_take_one_second() {
        let set = read_csv("t,id,x,y\n0,1,0,0\n0,2,1,1\n", None).unwrap();
        assert_eq!(set.step_s, SINGLE_SAMPLE_STEP_S);
        assert_eq!(set.tracks.len(), 2);
        let set = read_csv("", None).unwrap();
        assert!(set.tracks.is_empty());
    }

    #[test]
    fn errors_name_the_line() {
        let bad = [
            ("t,id,x,y\n0,1,2\n", 2, "found 3 field(s)"),
            ("0,1,2,3,4\n", 1, "more than 4 fields"),
            ("0,1,2,x\n", 1, "y `x` is not a number"),
            ("0,1,,3\n", 1, "x `` is not a number"),
            ("0,-1,2,3\n", 1, "id `-1` is not a non-negative whole"),
            ("0,1.5,2,3\n", 1, "id `1.5`"),
            (
                "0,1,2,NaN\n",
                1,
                "7: y: person 1: NaN is not a finite number",
            ),
            (
                "inf,1,2,3\n",
                1,
                "1: t: person 1: inf is not a finite number",
            ),
            (
                "0,1, 1e308,-1e308\n",
                1,
                "6: x: person 1: 1e308 m is beyond the coordinate bound of ±1e6 m",
            ),
            (
                "0,1,0,-1000000.5\n",
                1,
                "7: y: person 1: -1.0000005e6 m is beyond",
            ),
            (
                "2e9,1,0,0\n",
                1,
                "1: t: person 1: 2e9 s is beyond the time bound of ±1e9 s",
            ),
            ("0,1,0,0\n0.0000001,1,0,0\n", 2, "less than 1e-6 s after"),
            ("garbage\n", 1, "found 1 field(s)"),
            ("0,1,2,3\nt,id,x,y\n", 2, "t `t` is not a number"),
            (
                "1,1,2,3\n1,1,2,3\n",
                2,
                "person 1 appears twice at 1 s (also line 1)",
            ),
            (
                "1,1,2,3\n0,2,0,0\n0.5,1,2,3\n",
                3,
                "time 0.5 s comes after 1 s (line 1)",
            ),
        ];
        for (text, line, what) in bad {
            let e = read_csv(text, None).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.to_string().contains(what), "{text:?}: {e}");
        }
        for step in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(read_csv("", Some(step)).unwrap_err().line, 0);
        }
    }

    #[test]
    fn writes_a_header_and_sorted_rows() {
        let set = TrackSet {
            tracks: vec![
                Track::linked(
                    5,
                    vec![Vec2::new(1.0, 2.0), Vec2::new(1.5, 2.0)],
                    vec![0.0, 0.5],
                ),
                Track::linked(1, vec![Vec2::new(-0.25, 0.0)], vec![0.5]),
            ],
            step_s: 0.5,
        };
        assert_eq!(
            write_csv(&set),
            "t,id,x,y\n0,5,1,2\n0.5,1,-0.25,0\n0.5,5,1.5,2\n"
        );
    }
}
