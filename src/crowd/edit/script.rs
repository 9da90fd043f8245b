//! Edit scripts: the edits of `crowdtouch edit apply`, written down as a RON file so
//! an installation's authored crowd scene can be rebuilt from its source tracks.
//!
//! ```ron
//! (
//!     ops: [
//!         // The people to edit: any of ids, a rectangle, a lasso, a time window.
//!         Select(ids: Some([1, 2, 3]), time_s: Some((0.0, 30.0))),
//!         // Held still by the next drags (the selected sample nearest each place).
//!         Fix(at: [(2.0, 5.0)]),
//!         // The selected sample (or hull vertex) nearest `from` is dragged to `to`
//!         // (section 3.2, eqs. 1–8); speeds are corrected after it (eq. 9).
//!         Drag(from: (4.0, 5.0), to: (4.5, 6.0)),
//!         // Time nodes of the selected people nearest `at_s` move to `to_s`
//!         // (section 3.3, eqs. 10–12); nodes nearest `fixed_s` stay.
//!         Retime(at_s: 12.0, to_s: 14.0, fixed_s: [0.0]),
//!     ],
//! )
//! ```
//!
//! Parsing checks the file's syntax and each operation's numbers; names of people
//! are checked against the tracks when the script runs, and every error carries the
//! operation's line.

use crate::geom::Vec2;
use crate::located::{field_positions, parse_strict, Issue};
use serde::Deserialize;
use thiserror::Error;

/// The most operations a script may hold (a longer one is refused before it is
/// deserialised, naming the line of the first operation over the cap).
pub const MAX_OPS: usize = 10_000;
/// The most ids, lasso points or places in one operation.
pub const MAX_LIST: usize = 100_000;

/// Which people (and which of their samples) the next edits act on. The parts given
/// are combined: a sample is selected when it passes every part given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SelectSpec {
    /// People by id.
    pub ids: Option<Vec<u64>>,
    /// Samples inside the rectangle `((x0, y0), (x1, y1))`, metres.
    pub rect: Option<((f64, f64), (f64, f64))>,
    /// Samples inside the polygon, metres.
    pub lasso: Option<Vec<(f64, f64)>>,
    /// Samples in the time window `(from, to)`, seconds.
    pub time_s: Option<(f64, f64)>,
}

/// One operation as written.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum OpDef {
    /// The people to edit next (see [`SelectSpec`]).
    Select {
        /// People by id.
        #[serde(default)]
        ids: Option<Vec<u64>>,
        /// Samples inside the rectangle `((x0, y0), (x1, y1))`, metres.
        #[serde(default)]
        rect: Option<((f64, f64), (f64, f64))>,
        /// Samples inside the polygon, metres.
        #[serde(default)]
        lasso: Option<Vec<(f64, f64)>>,
        /// Samples in the time window `(from, to)`, seconds.
        #[serde(default)]
        time_s: Option<(f64, f64)>,
    },
    /// Samples held still by the next drags.
    Fix {
        /// Places (metres); the selected sample nearest each is held.
        at: Vec<(f64, f64)>,
    },
    /// Nothing is held any more.
    Unfix,
    /// A spatial drag.
    Drag {
        /// Where the dragged handle is (metres): the nearest selected sample or hull vertex.
        from: (f64, f64),
        /// Where it goes (metres).
        to: (f64, f64),
        /// Re-time the edited tracks so their speeds are what they were (eq. 9).
        #[serde(default = "yes")]
        correct_speeds: bool,
    },
    /// A temporal drag.
    Retime {
        /// The time node nearest this time, of every selected person, is dragged (s).
        at_s: f64,
        /// To this time (s).
        to_s: f64,
        /// Time nodes nearest these times stay (s).
        #[serde(default)]
        fixed_s: Vec<f64>,
    },
}

fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScriptFile {
    ops: Vec<OpDef>,
}

/// A parsed script: its operations with the line each starts on.
#[derive(Clone, Debug, PartialEq)]
pub struct Script {
    /// `(operation, 1-based line)`.
    pub ops: Vec<(Op, usize)>,
}

/// One checked operation (places as [`Vec2`], metres; times in seconds).
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// See [`OpDef::Select`].
    Select(SelectSpec),
    /// See [`OpDef::Fix`].
    Fix(Vec<Vec2>),
    /// See [`OpDef::Unfix`].
    Unfix,
    /// See [`OpDef::Drag`].
    Drag {
        /// From (m).
        from: Vec2,
        /// To (m).
        to: Vec2,
        /// Correct speeds after (eq. 9).
        correct_speeds: bool,
    },
    /// See [`OpDef::Retime`].
    Retime {
        /// The node nearest this time (s).
        at_s: f64,
        /// Goes to this time (s).
        to_s: f64,
        /// Nodes nearest these stay (s).
        fixed_s: Vec<f64>,
    },
}

/// A script that cannot be used, with the line of the operation at fault.
#[derive(Debug, Error, PartialEq)]
pub enum ScriptError {
    /// Not valid RON for a script.
    #[error("{0}")]
    Syntax(Issue),
    /// An operation is wrong.
    #[error("line {line}: {what}")]
    Op {
        /// 1-based line of the operation (0 when unknown).
        line: usize,
        /// What is wrong.
        what: String,
    },
}

/// Parses a script.
///
/// # Errors
/// [`ScriptError::Syntax`] with line, column and field for a file that is not a
/// script; [`ScriptError::Op`] with the operation's line for a number that is not
/// finite, a time window or rectangle given backwards, a lasso of fewer than three
/// points, more than [`MAX_OPS`] operations or [`MAX_LIST`] list items.
///
/// # Complexity
/// Linear in the text: the operations' lines come from one scan of it.
pub fn parse_script(text: &str) -> Result<Script, ScriptError> {
    let lines = op_lines(text);
    if lines.len() > MAX_OPS {
        return Err(ScriptError::Op {
            line: lines[MAX_OPS],
            what: format!(
                "a script holds at most {MAX_OPS} operations; this one has {}",
                lines.len()
            ),
        });
    }
    let file: ScriptFile = parse_strict(text).map_err(ScriptError::Syntax)?;
    if file.ops.len() > MAX_OPS {
        return Err(ScriptError::Op {
            line: 0,
            what: format!(
                "a script holds at most {MAX_OPS} operations; this one has {}",
                file.ops.len()
            ),
        });
    }
    let mut ops = Vec::with_capacity(file.ops.len());
    for (i, def) in file.ops.into_iter().enumerate() {
        let line = lines.get(i).copied().unwrap_or(0);
        let bad = |what: String| ScriptError::Op { line, what };
        let op = match def {
            OpDef::Select {
                ids,
                rect,
                lasso,
                time_s,
            } => {
                let s = SelectSpec {
                    ids,
                    rect,
                    lasso,
                    time_s,
                };
                if s.ids.is_none() && s.rect.is_none() && s.lasso.is_none() && s.time_s.is_none() {
                    return Err(bad("Select names no ids, rect, lasso or time_s".into()));
                }
                if let Some(ids) = &s.ids {
                    if ids.is_empty() || ids.len() > MAX_LIST {
                        return Err(bad(format!("Select: {} ids (1 to {MAX_LIST})", ids.len())));
                    }
                }
                if let Some(((x0, y0), (x1, y1))) = s.rect {
                    finite(&[x0, y0, x1, y1], "Select: rect").map_err(bad)?;
                    if x1 < x0 || y1 < y0 {
                        return Err(bad(
                            "Select: rect's second corner must be above and right of its first"
                                .into(),
                        ));
                    }
                }
                if let Some(l) = &s.lasso {
                    if l.len() < 3 || l.len() > MAX_LIST {
                        return Err(bad(format!(
                            "Select: a lasso needs 3 to {MAX_LIST} points, not {}",
                            l.len()
                        )));
                    }
                    for &(x, y) in l {
                        finite(&[x, y], "Select: lasso").map_err(bad)?;
                    }
                }
                if let Some((a, b)) = s.time_s {
                    finite(&[a, b], "Select: time_s").map_err(bad)?;
                    if b < a {
                        return Err(bad(format!(
                            "Select: time window ({a}, {b}) ends before it starts"
                        )));
                    }
                }
                Op::Select(s)
            }
            OpDef::Fix { at } => {
                if at.is_empty() || at.len() > MAX_LIST {
                    return Err(bad(format!(
                        "Fix: 1 to {MAX_LIST} places, not {}",
                        at.len()
                    )));
                }
                let mut v = Vec::with_capacity(at.len());
                for (x, y) in at {
                    finite(&[x, y], "Fix").map_err(bad)?;
                    v.push(Vec2::new(x, y));
                }
                Op::Fix(v)
            }
            OpDef::Unfix => Op::Unfix,
            OpDef::Drag {
                from,
                to,
                correct_speeds,
            } => {
                finite(&[from.0, from.1, to.0, to.1], "Drag").map_err(bad)?;
                Op::Drag {
                    from: Vec2::new(from.0, from.1),
                    to: Vec2::new(to.0, to.1),
                    correct_speeds,
                }
            }
            OpDef::Retime {
                at_s,
                to_s,
                fixed_s,
            } => {
                finite(&[at_s, to_s], "Retime").map_err(bad)?;
                finite(&fixed_s, "Retime: fixed_s").map_err(bad)?;
                if fixed_s.len() > MAX_LIST {
                    return Err(bad(format!("Retime: more than {MAX_LIST} fixed times")));
                }
                Op::Retime {
                    at_s,
                    to_s,
                    fixed_s,
                }
            }
        };
        ops.push((op, line));
    }
    Ok(Script { ops })
}

fn finite(v: &[f64], what: &str) -> Result<(), String> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{what}: {x} is not a finite number")),
        None => Ok(()),
    }
}

/// The line of every operation (`ops[i]`), in order, from one scan of the text
/// (before, each operation's line was searched for from the start: quadratic).
fn op_lines(text: &str) -> Vec<usize> {
    let mut lines = Vec::new();
    for (path, line, _) in field_positions(text) {
        let Some(i) = path
            .strip_prefix("ops[")
            .and_then(|r| r.strip_suffix(']'))
            .and_then(|r| r.parse::<usize>().ok())
        else {
            continue;
        };
        if i == lines.len() {
            lines.push(line);
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"(
    ops: [
        Select(ids: Some([1, 2])),
        Fix(at: [(0.0, 1.0)]),
        Drag(from: (1.0, 1.0), to: (2.0, 1.5)),
        Unfix,
        Retime(at_s: 3.0, to_s: 4.0),
    ],
)"#;

    #[test]
    fn reads_every_operation_with_its_line() {
        let s = parse_script(GOOD).unwrap();
        let lines: Vec<usize> = s.ops.iter().map(|(_, l)| *l).collect();
        assert_eq!(lines, vec![3, 4, 5, 6, 7]);
        assert!(matches!(
            s.ops[2].0,
            Op::Drag {
                correct_speeds: true,
                ..
            }
        ));
        assert_eq!(
            s.ops[4].0,
            Op::Retime {
                at_s: 3.0,
                to_s: 4.0,
                fixed_s: vec![]
            }
        );
    }

    #[test]
    fn bad_operations_name_their_line() {
        let cases = [
            ("(ops: [\n Select(),\n])", 2, "names no ids"),
            (
                "(ops: [\n Unfix,\n Select(rect: Some(((2.0, 0.0), (1.0, 1.0)))),\n])",
                3,
                "second corner",
            ),
            (
                "(ops: [\n Select(lasso: Some([(0.0, 0.0), (1.0, 0.0)])),\n])",
                2,
                "3 to",
            ),
            (
                "(ops: [\n Select(time_s: Some((5.0, 1.0))),\n])",
                2,
                "ends before",
            ),
            ("(ops: [\n Fix(at: []),\n])", 2, "Fix"),
            (
                "(ops: [\n Drag(from: (1.0, inf), to: (0.0, 0.0)),\n])",
                2,
                "not a finite",
            ),
        ];
        for (text, line, what) in cases {
            match parse_script(text) {
                Err(ScriptError::Op { line: l, what: w }) => {
                    assert_eq!(l, line, "{text}: {w}");
                    assert!(w.contains(what), "{text}: {w}");
                }
                other => panic!("{text}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_script_over_the_cap_is_refused_at_its_first_extra_operation() {
        let mut text = String::from("(ops: [\n");
        for _ in 0..=MAX_OPS {
            text.push_str(" Unfix,\n");
        }
        text.push_str("])\n");
        match parse_script(&text) {
            Err(ScriptError::Op { line, what }) => {
                assert_eq!(line, MAX_OPS + 2, "{what}");
                assert!(what.contains("at most 10000 operations"), "{what}");
                assert!(what.contains("10001"), "{what}");
            }
            other => panic!("{other:?}"),
        }
        // At the cap it is read, every operation with its line.
        let at_cap = text.replacen(" Unfix,\n", "", 1);
        let s = parse_script(&at_cap).unwrap();
        assert_eq!(s.ops.len(), MAX_OPS);
        assert_eq!(s.ops[MAX_OPS - 1].1, MAX_OPS + 1);
    }

    #[test]
    fn syntax_errors_are_placed() {
        let Err(ScriptError::Syntax(i)) = parse_script("(ops: [\n Jump(x: 1),\n])") else {
            panic!("an unknown operation is a syntax error");
        };
        assert_eq!(i.line, 2, "{i}");
        assert!(parse_script("(ops: [], extra: 1)").is_err());
    }
}
