//! YAML parser events pulled one at a time from a recording's lines, with the
//! guards that keep the parser's memory and nesting bounded whatever the text:
//! each line at most [`MAX_LINE_BYTES`](super::MAX_LINE_BYTES), nesting within
//! [`MAX_YAML_FLOW_DEPTH`] brackets and [`MAX_YAML_INDENT`] columns, at most
//! [`MAX_YAML_SPAN_BYTES`] read between two events (one scalar, one run of
//! comments) and [`MAX_YAML_ANCHORS`] anchors.

use super::error::RecordingError;
use super::lines::{LineFault, LineReader};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use yaml_rust2::parser::{Event, Parser};

/// Deepest YAML nesting (flow brackets) accepted.
pub(super) const MAX_YAML_FLOW_DEPTH: usize = 64;
/// Widest YAML block indentation (columns of spaces, `-`, `?`, `:`) accepted.
pub(super) const MAX_YAML_INDENT: usize = 256;
/// Most text the parser may read between two events, in bytes (4 MiB).
pub(super) const MAX_YAML_SPAN_BYTES: usize = 4 << 20;
/// Most anchors (`&name`) a text may define.
pub(super) const MAX_YAML_ANCHORS: usize = 1024;

/// Why the characters stopped before the end of the text.
enum Fault {
    Line(LineFault),
    Refused(String),
}

/// What the character source and the event reader share.
#[derive(Default)]
struct Shared {
    /// The lines; taken back by [`YamlEvents::into_lines`].
    lines: Mutex<Option<LineReader>>,
    /// Bytes read since the last event.
    since_event: AtomicUsize,
    faulted: AtomicBool,
    /// The fault and its line.
    fault: Mutex<Option<(usize, Fault)>>,
}

/// The characters of the text, a line at a time, checked line by line.
struct Chars {
    /// The end of the text was reached, or a fault stopped the reading.
    ended: bool,
    line: String,
    pos: usize,
    /// The line break after the current line is still to be given.
    newline: bool,
    flow_depth: usize,
    shared: Arc<Shared>,
}

impl Chars {
    fn stop(&mut self, line: usize, fault: Fault) -> Option<char> {
        self.ended = true;
        self.line.clear();
        self.pos = 0;
        self.newline = false;
        if let Ok(mut f) = self.shared.fault.lock() {
            *f = Some((line, fault));
        }
        self.shared.faulted.store(true, Ordering::Relaxed);
        None
    }

    /// Refuses a line nested deeper than the parser should go.
    fn check_depth(&mut self) -> Result<(), String> {
        let l = self.line.as_str();
        let indent = l
            .bytes()
            .take_while(|b| matches!(b, b' ' | b'\t' | b'-' | b'?' | b':'))
            .count();
        if indent > MAX_YAML_INDENT && !l[indent..].starts_with('#') && indent < l.len() {
            return Err(format!("indentation deeper than {MAX_YAML_INDENT} columns"));
        }
        let code = l.split(" #").next().unwrap_or(l);
        for b in code.bytes() {
            match b {
                b'[' | b'{' => self.flow_depth += 1,
                b']' | b'}' => self.flow_depth = self.flow_depth.saturating_sub(1),
                _ => {}
            }
            if self.flow_depth > MAX_YAML_FLOW_DEPTH {
                return Err(format!("brackets nested deeper than {MAX_YAML_FLOW_DEPTH}"));
            }
        }
        Ok(())
    }
}

impl Iterator for Chars {
    type Item = char;

    fn next(&mut self) -> Option<char> {
        loop {
            if let Some(c) = self.line.get(self.pos..).and_then(|r| r.chars().next()) {
                self.pos += c.len_utf8();
                return Some(c);
            }
            if self.newline {
                self.newline = false;
                return Some('\n');
            }
            if self.ended {
                return None;
            }
            let (got, at) = {
                let Ok(mut slot) = self.shared.lines.lock() else {
                    self.ended = true;
                    return None;
                };
                let Some(lines) = slot.as_mut() else {
                    self.ended = true;
                    return None;
                };
                let got = match lines.next_line() {
                    Ok(Some((_, l))) => {
                        self.line.clear();
                        self.line.push_str(l);
                        Ok(true)
                    }
                    Ok(None) => Ok(false),
                    Err(f) => Err(f),
                };
                (got, lines.line())
            };
            match got {
                Ok(true) => {}
                Ok(false) => {
                    self.line.clear();
                    self.pos = 0;
                    self.ended = true;
                    return None;
                }
                Err(f) => return self.stop(at, Fault::Line(f)),
            }
            self.pos = 0;
            self.newline = true;
            let read = self
                .shared
                .since_event
                .fetch_add(self.line.len() + 1, Ordering::Relaxed);
            if read + self.line.len() + 1 > MAX_YAML_SPAN_BYTES {
                let m = format!(
                    "more than {MAX_YAML_SPAN_BYTES} bytes of YAML without a value ending \
                     (a scalar or a run of comments that long)"
                );
                return self.stop(at, Fault::Refused(m));
            }
            if let Err(m) = self.check_depth() {
                return self.stop(at, Fault::Refused(m));
            }
        }
    }
}

/// A node's kind, as messages say it.
pub(super) fn kind(ev: &Event) -> &'static str {
    match ev {
        Event::Scalar(..) => "a scalar",
        Event::SequenceStart(..) => "a list",
        Event::MappingStart(..) => "a mapping",
        Event::Alias(..) => "an alias",
        _ => "the end of a node",
    }
}

/// YAML events, one at a time, each with its 1-based line.
pub(super) struct YamlEvents {
    parser: Parser<Chars>,
    shared: Arc<Shared>,
    /// The parser panicked; it is not asked again.
    broken: bool,
}

impl YamlEvents {
    pub(super) fn new(lines: LineReader) -> YamlEvents {
        let shared = Arc::new(Shared {
            lines: Mutex::new(Some(lines)),
            ..Shared::default()
        });
        let chars = Chars {
            ended: false,
            line: String::new(),
            pos: 0,
            newline: false,
            flow_depth: 0,
            shared: Arc::clone(&shared),
        };
        YamlEvents {
            parser: Parser::new(chars),
            shared,
            broken: false,
        }
    }

    /// The lines, for reading again from the start.
    pub(super) fn into_lines(self) -> Option<LineReader> {
        let YamlEvents { parser, shared, .. } = self;
        drop(parser);
        let mut slot = shared.lines.lock().ok()?;
        slot.take()
    }

    /// Bytes of text read so far.
    pub(super) fn consumed(&self) -> u64 {
        let slot = self.shared.lines.lock();
        slot.ok()
            .and_then(|s| s.as_ref().map(LineReader::consumed))
            .unwrap_or(0)
    }

    /// The next event and its line.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for text that is not YAML or that the guards
    /// refuse, at its line; [`RecordingError::Io`].
    pub(super) fn next(&mut self, path: &Path) -> Result<(Event, usize), RecordingError> {
        if self.broken {
            return Err(RecordingError::parse(
                path,
                1,
                "invalid YAML (the parser failed)",
            ));
        }
        self.shared.since_event.store(0, Ordering::Relaxed);
        // yaml-rust2 is third-party code: a panic on some odd input must not
        // escape as one from our reader.
        let parser = &mut self.parser;
        let got = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parser.next_token()));
        if let Some(e) = self.fault(path) {
            return Err(e);
        }
        match got {
            Ok(Ok((ev, mark))) => {
                let anchor = match &ev {
                    Event::Scalar(_, _, a, _)
                    | Event::SequenceStart(a, _)
                    | Event::MappingStart(a, _) => *a,
                    _ => 0,
                };
                if anchor > MAX_YAML_ANCHORS {
                    return Err(RecordingError::parse(
                        path,
                        mark.line(),
                        format!("more than {MAX_YAML_ANCHORS} YAML anchors"),
                    ));
                }
                Ok((ev, mark.line()))
            }
            Ok(Err(e)) => Err(RecordingError::parse(
                path,
                e.marker().line(),
                format!("invalid YAML: {}", e.info()),
            )),
            Err(_) => {
                self.broken = true;
                Err(RecordingError::parse(
                    path,
                    1,
                    "invalid YAML (the parser failed)",
                ))
            }
        }
    }

    /// Why the characters stopped early, if they did.
    fn fault(&mut self, path: &Path) -> Option<RecordingError> {
        if !self.shared.faulted.load(Ordering::Relaxed) {
            return None;
        }
        let mut slot = self.shared.fault.lock().ok()?;
        let (line, f) = slot.take()?;
        self.broken = true;
        Some(match f {
            Fault::Line(f) => f.at(path, line),
            Fault::Refused(m) => RecordingError::parse(path, line, m),
        })
    }

    /// Skips the rest of the node `first` begins (nothing for a scalar or alias).
    ///
    /// # Errors
    /// As [`YamlEvents::next`].
    pub(super) fn skip(&mut self, first: &Event, path: &Path) -> Result<(), RecordingError> {
        let mut depth = usize::from(matches!(
            first,
            Event::SequenceStart(..) | Event::MappingStart(..)
        ));
        while depth > 0 {
            match self.next(path)?.0 {
                Event::SequenceStart(..) | Event::MappingStart(..) => depth += 1,
                Event::SequenceEnd | Event::MappingEnd => depth -= 1,
                Event::StreamEnd => {
                    return Err(RecordingError::parse(
                        path,
                        1,
                        "invalid YAML: unclosed node",
                    ))
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Up to five integers of a YAML list: the values, how many items the list
/// holds, and the first item that is not an integer.
pub(super) struct IntList {
    pub(super) values: [i64; 5],
    pub(super) len: usize,
    bad: Option<String>,
}

impl IntList {
    /// The integers, when the list holds a number of them in `len`.
    pub(super) fn check(
        &self,
        field: &str,
        len: std::ops::RangeInclusive<usize>,
    ) -> Result<&[i64], String> {
        if !len.contains(&self.len) {
            return Err(format!(
                "field `{field}`: expected {} to {} integers, found {}",
                len.start(),
                len.end(),
                self.len
            ));
        }
        match &self.bad {
            Some(m) => Err(m.clone()),
            None => Ok(&self.values[..self.len]),
        }
    }
}

/// Reads the list `first` begins as integers, without keeping more than five.
///
/// `Ok(Err(message))` when the node is not a list (it is skipped).
///
/// # Errors
/// As [`YamlEvents::next`].
pub(super) fn int_list(
    ev: &mut YamlEvents,
    first: &Event,
    field: &str,
    path: &Path,
) -> Result<Result<IntList, String>, RecordingError> {
    if !matches!(first, Event::SequenceStart(..)) {
        ev.skip(first, path)?;
        return Ok(Err(format!(
            "field `{field}`: expected a list of integers, found {}",
            kind(first)
        )));
    }
    let mut list = IntList {
        values: [0; 5],
        len: 0,
        bad: None,
    };
    loop {
        let (item, _) = ev.next(path)?;
        if matches!(item, Event::SequenceEnd) {
            return Ok(Ok(list));
        }
        let i = list.len;
        let value = match &item {
            Event::Scalar(s, ..) => s
                .parse::<i64>()
                .map_err(|_| format!("field `{field}[{i}]`: `{s}` is not an integer")),
            other => Err(format!(
                "field `{field}[{i}]`: expected an integer, found {}",
                kind(other)
            )),
        };
        ev.skip(&item, path)?;
        match value {
            Ok(v) if i < list.values.len() => list.values[i] = v,
            Ok(_) => {}
            Err(m) => {
                list.bad.get_or_insert(m);
            }
        }
        list.len = list.len.saturating_add(1);
    }
}
