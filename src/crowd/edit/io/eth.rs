//! The raw format of the public pedestrian datasets (ETH and UCY as distributed by
//! trajectory-prediction projects, e.g. the Social-GAN release): one line per
//! (frame, person), `frame id x y` separated by whitespace, positions in metres,
//! sorted by frame, no header. Frames are video frames at `frame_rate_hz`
//! (25 fps by default); people are annotated every `frame_step` frames (10 by
//! default), so two samples of a person `frame_step` apart are linked and a longer
//! gap means the person left the annotation for a while.
//!
//! A person with a single sample is kept: present at that instant only.

use super::text::{clip, whole};
use super::ReadError;
use crate::crowd::edit::flat::{coordinate_problem, time_problem, MAX_SAMPLES, MIN_SAMPLE_STEP_S};
use crate::crowd::edit::tracks::{Track, TrackSet};
use crate::geom::Vec2;
use std::collections::HashMap;
use std::fmt::Write as _;

/// How frames become times.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct EthOptions {
    /// Video frames per second (the datasets' 25).
    pub frame_rate_hz: f64,
    /// Frames between a person's consecutive annotations (the datasets' 10).
    pub frame_step: u32,
}

impl Default for EthOptions {
    fn default() -> Self {
        EthOptions {
            frame_rate_hz: 25.0,
            frame_step: 10,
        }
    }
}

/// Reads an ETH/UCY raw file.
///
/// # Errors
/// [`ReadError`] naming the line: not four numbers, a frame or id that is not a
/// non-negative whole number, a position that is not finite, a person seen twice in
/// one frame, a person's frames going back, more than [`MAX_SAMPLES`] rows, or bad
/// options (line 0).
pub fn read_eth(text: &str, opts: EthOptions) -> Result<TrackSet, ReadError> {
    if !(opts.frame_rate_hz.is_finite() && opts.frame_rate_hz > 0.0) {
        return Err(ReadError::at(
            0,
            format!(
                "frame rate must be a positive number of Hz, not {}",
                opts.frame_rate_hz
            ),
        ));
    }
    if opts.frame_step == 0 {
        return Err(ReadError::at(0, "frame step must be at least 1"));
    }
    let mut tracks: Vec<Track> = Vec::new();
    // Per person: index in `tracks`, last frame and the line it was on.
    let mut people: HashMap<u64, (usize, u64, usize)> = HashMap::new();
    let mut rows = 0usize;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let mut f = [0.0f64; 4];
        let mut fields = s.split_whitespace();
        for (k, name) in ["frame", "id", "x", "y"].iter().enumerate() {
            let Some(word) = fields.next() else {
                return Err(ReadError::at(
                    line,
                    format!("expected `frame id x y`, found {} field(s)", k),
                ));
            };
            f[k] = word.parse::<f64>().map_err(|_| {
                ReadError::at(line, format!("{name} `{}` is not a number", clip(word)))
            })?;
        }
        if let Some(extra) = fields.next() {
            return Err(ReadError::at(
                line,
                format!("expected `frame id x y`, found more (`{}`)", clip(extra)),
            ));
        }
        let frame = whole(f[0]).ok_or_else(|| {
            ReadError::at(
                line,
                format!("frame {} is not a non-negative whole number", f[0]),
            )
        })?;
        let id = whole(f[1]).ok_or_else(|| {
            ReadError::at(
                line,
                format!("id {} is not a non-negative whole number", f[1]),
            )
        })?;
        let t = frame as f64 / opts.frame_rate_hz;
        // `col: field: what`, so the file's error reads `file:line:col: field: what`.
        let col = |k: usize| {
            let mut words = s.split_whitespace();
            let word = words.nth(k).unwrap_or("");
            let lead = raw.len() - raw.trim_start().len();
            lead + (word.as_ptr() as usize - s.as_ptr() as usize) + 1
        };
        for (k, name, problem) in [
            (0, "frame", time_problem(t)),
            (2, "x", coordinate_problem(f[2])),
            (3, "y", coordinate_problem(f[3])),
        ] {
            if let Some(what) = problem {
                return Err(ReadError::at(
                    line,
                    format!("{}: {name}: person {id}: {what}", col(k)),
                ));
            }
        }
        rows += 1;
        if rows > MAX_SAMPLES {
            return Err(ReadError::at(line, format!("more than {MAX_SAMPLES} rows")));
        }
        let p = Vec2::new(f[2], f[3]);
        match people.get_mut(&id) {
            None => {
                people.insert(id, (tracks.len(), frame, line));
                tracks.push(Track {
                    id,
                    points: vec![p],
                    times_s: vec![t],
                    linked: Vec::new(),
                });
            }
            Some((k, last, last_line)) => {
                if frame == *last {
                    return Err(ReadError::at(
                        line,
                        format!(
                            "person {id} appears twice in frame {frame} (also line {last_line})"
                        ),
                    ));
                }
                if frame < *last {
                    return Err(ReadError::at(
                        line,
                        format!("person {id}: frame {frame} comes after frame {last} (line {last_line}); a person's rows must go forward in time"),
                    ));
                }
                let tr = &mut tracks[*k];
                let last_s = *tr.times_s.last().unwrap_or(&f64::NEG_INFINITY);
                if t - last_s < MIN_SAMPLE_STEP_S {
                    return Err(ReadError::at(
                        line,
                        format!("person {id}: frame {frame} is less than {MIN_SAMPLE_STEP_S:e} s after frame {last} (line {last_line}) at {} frames/s", opts.frame_rate_hz),
                    ));
                }
                tr.linked.push(frame - *last <= u64::from(opts.frame_step));
                tr.points.push(p);
                tr.times_s.push(t);
                *last = frame;
                *last_line = line;
            }
        }
    }
    Ok(TrackSet {
        tracks,
        step_s: f64::from(opts.frame_step) / opts.frame_rate_hz,
    })
}

/// Writes a track set as an ETH/UCY raw file (tab-separated, sorted by frame then
/// id). Times become frames at `opts.frame_rate_hz`, rounded to the nearest frame.
pub fn write_eth(set: &TrackSet, opts: EthOptions) -> String {
    let mut rows: Vec<(i64, u64, Vec2)> = Vec::with_capacity(set.samples());
    for t in &set.tracks {
        for (p, ts) in t.points.iter().zip(&t.times_s) {
            rows.push(((ts * opts.frame_rate_hz).round() as i64, t.id, *p));
        }
    }
    rows.sort_by_key(|&(f, id, _)| (f, id));
    let mut out = String::with_capacity(rows.len() * 40);
    for (f, id, p) in rows {
        let _ = writeln!(out, "{f}.0\t{id}.0\t{}\t{}", p.x, p.y);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_people_links_and_gaps() {
        let text = "0\t1\t1.0\t2.0\n0\t2\t5.0\t5.0\n10\t1\t1.5\t2.0\n30\t1\t2.5\t2.0\n";
        let set = read_eth(text, EthOptions::default()).unwrap();
        set.validate().unwrap();
        assert_eq!(set.step_s, 0.4);
        assert_eq!(set.tracks.len(), 2);
        let a = &set.tracks[0];
        assert_eq!(a.id, 1);
        assert_eq!(a.times_s, vec![0.0, 0.4, 1.2]);
        assert_eq!(a.linked, vec![true, false]);
        assert_eq!(set.tracks[1].len(), 1, "a single sample is kept");
    }

    #[test]
    fn errors_name_the_line() {
        let bad = [
            ("0 1 2\n", 1, "found 3"),
            ("0 1 2 3 4\n", 1, "found more"),
            ("0 1 2 x\n", 1, "y `x` is not a number"),
            ("0.5 1 2 3\n", 1, "frame 0.5"),
            ("0 -1 2 3\n", 1, "id -1"),
            (
                "0 1 2 NaN\n",
                1,
                "7: y: person 1: NaN is not a finite number",
            ),
            ("0 1 2e6 0\n", 1, "5: x: person 1: 2e6 m is beyond"),
            (
                "99999999999 1 0 0\n",
                1,
                "1: frame: person 1: 3.99999999996e9 s is beyond",
            ),
            ("0 1 2 3\n0 1 2 3\n", 2, "twice in frame 0 (also line 1)"),
            ("10 1 2 3\n0 1 2 3\n", 2, "frame 0 comes after frame 10"),
        ];
        for (text, line, what) in bad {
            let e = read_eth(text, EthOptions::default()).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            assert!(e.to_string().contains(what), "{text:?}: {e}");
        }
        assert_eq!(
            read_eth(
                "",
                EthOptions {
                    frame_rate_hz: 0.0,
                    frame_step: 10
                }
            )
            .unwrap_err()
            .line,
            0
        );
    }

    #[test]
    fn writes_what_it_reads() {
        let text = "0.0\t1.0\t1.25\t2\n0.0\t2.0\t5\t5\n10.0\t1.0\t1.5\t2\n";
        let set = read_eth(text, EthOptions::default()).unwrap();
        let again = read_eth(
            &write_eth(&set, EthOptions::default()),
            EthOptions::default(),
        )
        .unwrap();
        assert_eq!(set, again);
    }

    #[test]
    fn reads_the_shipped_pedestrian_files() {
        for (name, people) in [("crowds_zara01.txt", 148), ("students001.txt", 415)] {
            let path = format!("{}/tests/fixtures/crowd/{name}", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&path).unwrap();
            let set = read_eth(&text, EthOptions::default()).unwrap();
            set.validate().unwrap();
            assert_eq!(set.tracks.len(), people, "{name}");
        }
    }
}
