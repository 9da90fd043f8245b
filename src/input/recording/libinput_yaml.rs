//! The `libinput record` YAML reader (version 1), decoded through the shared event
//! stream.
//!
//! `devices[0].evdev.absinfo` maps an axis code to `[min, max, fuzz, flat,
//! resolution]`, and `devices[0].events[*].evdev` lists `[sec, usec, type, code,
//! value]`. Unknown keys are ignored; only the first device is read.

use super::error::{OnBadFrame, RecordingError, UnsupportedReason};
use super::evdev_header::{default_name, AbsInfo, DeviceHeader, HeaderCtx};
use super::event_stream::EventStream;
use super::recording_type::Recording;
use super::warnings::Warnings;
use crate::input::evdev::ABS_MAX;
use std::path::Path;

/// Deepest YAML nesting (flow brackets) accepted before parsing.
const MAX_YAML_FLOW_DEPTH: usize = 64;
/// Widest YAML block indentation (columns of spaces, `-`, `?`, `:`) accepted.
const MAX_YAML_INDENT: usize = 256;

/// A YAML node with the line it starts on.
#[derive(Debug)]
enum Node {
    Scalar(String, usize),
    Seq(Vec<Node>, usize),
    /// Keys and values alternate.
    Map(Vec<Node>, usize),
    Alias(usize),
}

impl Node {
    fn line(&self) -> usize {
        match self {
            Node::Scalar(_, l) | Node::Seq(_, l) | Node::Map(_, l) | Node::Alias(l) => *l,
        }
    }

    fn kind(&self) -> &'static str {
        match self {
            Node::Scalar(..) => "a scalar",
            Node::Seq(..) => "a list",
            Node::Map(..) => "a mapping",
            Node::Alias(..) => "an alias",
        }
    }

    /// The value of `key` in a mapping.
    fn get(&self, key: &str) -> Option<&Node> {
        let Node::Map(kv, _) = self else { return None };
        kv.chunks_exact(2).find_map(|p| match &p[0] {
            Node::Scalar(k, _) if k == key => Some(&p[1]),
            _ => None,
        })
    }

    fn is_null(&self) -> bool {
        matches!(self, Node::Scalar(s, _) if s.is_empty() || s == "~" || s == "null")
    }

    fn as_i64(&self) -> Option<i64> {
        match self {
            Node::Scalar(s, _) => s.parse().ok(),
            _ => None,
        }
    }
}

/// Builds a [`Node`] tree from parser events.
#[derive(Default)]
struct TreeBuilder {
    stack: Vec<Node>,
    root: Option<Node>,
}

impl TreeBuilder {
    fn add(&mut self, node: Node) {
        match self.stack.last_mut() {
            Some(Node::Seq(items, _) | Node::Map(items, _)) => items.push(node),
            _ => {
                if self.root.is_none() {
                    self.root = Some(node);
                }
            }
        }
    }
}

impl yaml_rust2::parser::MarkedEventReceiver for TreeBuilder {
    fn on_event(&mut self, ev: yaml_rust2::Event, mark: yaml_rust2::scanner::Marker) {
        use yaml_rust2::Event;
        let line = mark.line();
        match ev {
            Event::Scalar(s, ..) => self.add(Node::Scalar(s, line)),
            Event::Alias(_) => self.add(Node::Alias(line)),
            Event::SequenceStart(..) => self.stack.push(Node::Seq(Vec::new(), line)),
            Event::MappingStart(..) => self.stack.push(Node::Map(Vec::new(), line)),
            Event::SequenceEnd | Event::MappingEnd => {
                if let Some(n) = self.stack.pop() {
                    self.add(n);
                }
            }
            _ => {}
        }
    }
}

/// Refuses YAML nested deeper than the parser can take without deep recursion.
fn check_yaml_depth(text: &str) -> Result<(), (usize, String)> {
    let mut depth = 0usize;
    for (i, l) in text.lines().enumerate() {
        let indent = l
            .bytes()
            .take_while(|b| matches!(b, b' ' | b'\t' | b'-' | b'?' | b':'))
            .count();
        if indent > MAX_YAML_INDENT && !l[indent..].starts_with('#') && indent < l.len() {
            return Err((
                i + 1,
                format!("indentation deeper than {MAX_YAML_INDENT} columns"),
            ));
        }
        let code = l.split(" #").next().unwrap_or(l);
        for b in code.bytes() {
            match b {
                b'[' | b'{' => depth += 1,
                b']' | b'}' => depth = depth.saturating_sub(1),
                _ => {}
            }
            if depth > MAX_YAML_FLOW_DEPTH {
                return Err((
                    i + 1,
                    format!("brackets nested deeper than {MAX_YAML_FLOW_DEPTH}"),
                ));
            }
        }
    }
    Ok(())
}

/// Reads a libinput record YAML text.
pub(super) fn parse_libinput_yaml(
    text: &str,
    path: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
    check_yaml_depth(text).map_err(|(l, m)| perr(l, m))?;
    let mut tree = TreeBuilder::default();
    // yaml-rust2 is third-party code: a panic on some odd input must not
    // escape as one from our reader.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut parser = yaml_rust2::parser::Parser::new_from_str(text);
        parser.load(&mut tree, false)
    }));
    match parsed {
        Ok(Ok(())) => {}
        Ok(Err(e)) => {
            return Err(perr(
                e.marker().line(),
                format!("invalid YAML: {}", e.info()),
            ))
        }
        Err(_) => return Err(perr(1, "invalid YAML (the parser failed)".to_string())),
    }
    let Some(root) = tree.root else {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
        });
    };
    fn field<'n>(
        parent: &'n Node,
        key: &str,
        what: &str,
        path: &Path,
    ) -> Result<&'n Node, RecordingError> {
        parent.get(key).ok_or_else(|| {
            RecordingError::parse(path, parent.line(), format!("missing field `{what}`"))
        })
    }
    let version = field(&root, "version", "version", path)?;
    match version.as_i64() {
        Some(1) => {}
        Some(v) => {
            return Err(RecordingError::Unsupported {
                path: path.to_path_buf(),
                reason: UnsupportedReason::Version {
                    format: "libinput record",
                    version: v,
                },
            })
        }
        None => {
            return Err(perr(
                version.line(),
                format!(
                    "field `version`: expected an integer, found {}",
                    version.kind()
                ),
            ))
        }
    }
    let devices = field(&root, "devices", "devices", path)?;
    let dev = match devices {
        Node::Seq(items, _) if !items.is_empty() => &items[0],
        other => {
            return Err(perr(
                other.line(),
                format!(
                    "field `devices`: expected a non-empty list, found {}",
                    other.kind()
                ),
            ))
        }
    };
    let mut warnings = Warnings::default();
    if let Node::Seq(items, _) = devices {
        if items.len() > 1 {
            warnings.push(items[1].line(), "only the first device is read".into());
        }
    }
    if !matches!(dev, Node::Map(..)) {
        return Err(perr(
            dev.line(),
            format!(
                "field `devices[0]`: expected a mapping, found {}",
                dev.kind()
            ),
        ));
    }
    let evdev = field(dev, "evdev", "devices[0].evdev", path)?;
    let mut hdr = DeviceHeader::default();
    if let Some(Node::Scalar(s, _)) = evdev.get("name") {
        hdr.name = Some(s.clone());
    }
    let absinfo = field(evdev, "absinfo", "devices[0].evdev.absinfo", path)?;
    let Node::Map(kv, _) = absinfo else {
        return Err(perr(
            absinfo.line(),
            format!(
                "field `devices[0].evdev.absinfo`: expected a mapping, found {}",
                absinfo.kind()
            ),
        ));
    };
    for pair in kv.chunks_exact(2) {
        let (k, v) = (&pair[0], &pair[1]);
        let code = k.as_i64().ok_or_else(|| {
            perr(
                k.line(),
                "field `absinfo`: axis codes must be integers".to_string(),
            )
        })?;
        if !(0..=i64::from(ABS_MAX)).contains(&code) {
            return Err(perr(
                k.line(),
                format!("field `absinfo`: unknown axis code {code} (the highest is {ABS_MAX})"),
            ));
        }
        let f = format!("absinfo.{code}");
        let vals = int_list(v, &f, 4..=5).map_err(|m| perr(v.line(), m))?;
        let get = |i: usize| vals.get(i).copied().unwrap_or(0);
        let to_i32 = |x: i64| {
            i32::try_from(x)
                .map_err(|_| perr(v.line(), format!("field `{f}`: {x} is out of range")))
        };
        if hdr.abs[code as usize].is_some() {
            return Err(perr(
                k.line(),
                format!("field `absinfo`: axis {code} is declared twice"),
            ));
        }
        hdr.abs[code as usize] = Some(AbsInfo {
            min: to_i32(get(0))?,
            max: to_i32(get(1))?,
            resolution: to_i32(get(4))?,
            line: v.line(),
        });
    }
    let ctx = HeaderCtx { path, prefix: "" };
    let (axes, surface) = hdr.mt_axes(&ctx, absinfo.line(), &default_name(path), &mut warnings)?;
    let mut stream = EventStream::new(path, on_bad, axes, surface, &hdr, warnings);
    let events = match dev.get("events") {
        None => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(n) if n.is_null() => {
            return Err(RecordingError::Empty {
                path: path.to_path_buf(),
            })
        }
        Some(Node::Seq(items, _)) => items,
        Some(other) => {
            return Err(perr(
                other.line(),
                format!(
                    "field `devices[0].events`: expected a list, found {}",
                    other.kind()
                ),
            ))
        }
    };
    for (fi, frame) in events.iter().enumerate() {
        let Some(list) = frame.get("evdev") else {
            if !matches!(frame, Node::Map(..)) {
                stream.bad(
                    frame.line(),
                    format!(
                        "field `events[{fi}]`: expected a mapping, found {}",
                        frame.kind()
                    ),
                )?;
            }
            continue; // libinput events and other keys are not needed.
        };
        let Node::Seq(evs, _) = list else {
            stream.bad(
                list.line(),
                format!(
                    "field `events[{fi}].evdev`: expected a list, found {}",
                    list.kind()
                ),
            )?;
            continue;
        };
        for (ei, ev) in evs.iter().enumerate() {
            let f = format!("events[{fi}].evdev[{ei}]");
            match yaml_event(ev, &f) {
                Ok((time, ty, code, value)) => stream.event(ev.line(), time, ty, code, value)?,
                Err(m) => stream.bad(ev.line(), m)?,
            }
        }
    }
    stream.finish()
}

/// A list of integers of a length in `len`.
fn int_list(
    n: &Node,
    field: &str,
    len: std::ops::RangeInclusive<usize>,
) -> Result<Vec<i64>, String> {
    let Node::Seq(items, _) = n else {
        return Err(format!(
            "field `{field}`: expected a list of integers, found {}",
            n.kind()
        ));
    };
    if !len.contains(&items.len()) {
        return Err(format!(
            "field `{field}`: expected {} to {} integers, found {}",
            len.start(),
            len.end(),
            items.len()
        ));
    }
    items
        .iter()
        .enumerate()
        .map(|(i, it)| {
            it.as_i64().ok_or_else(|| match it {
                Node::Scalar(s, _) => format!("field `{field}[{i}]`: `{s}` is not an integer"),
                other => format!(
                    "field `{field}[{i}]`: expected an integer, found {}",
                    other.kind()
                ),
            })
        })
        .collect()
}

/// `[sec, usec, type, code, value]` → `(time_us, type, code, value)`.
fn yaml_event(n: &Node, field: &str) -> Result<(u64, u16, u16, i32), String> {
    let v = int_list(n, field, 5..=5)?;
    let range = |i: usize, what: &str, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(format!(
                "field `{field}[{i}]` ({what}): {} is out of range",
                v[i]
            ))
        }
    };
    range(0, "seconds", v[0] >= 0)?;
    range(1, "microseconds", v[1] >= 0)?;
    range(2, "type", u16::try_from(v[2]).is_ok())?;
    range(3, "code", u16::try_from(v[3]).is_ok())?;
    range(4, "value", i32::try_from(v[4]).is_ok())?;
    let time = (v[0] as u64)
        .checked_mul(1_000_000)
        .and_then(|s| s.checked_add(v[1] as u64))
        .ok_or_else(|| format!("field `{field}`: timestamp out of range"))?;
    Ok((time, v[2] as u16, v[3] as u16, v[4] as i32))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("t.jsonl")
    }

    #[test]
    fn yaml_depth_guard() {
        let deep = "[".repeat(200);
        assert!(check_yaml_depth(&deep).is_err());
        assert!(check_yaml_depth("a:\n  - [1, 2]\n").is_ok());
    }

    #[test]
    fn deep_yaml_is_refused_or_survived() {
        let header = "version: 1\ndevices:\n";
        let dashes = format!("{header}{}x\n", "- ".repeat(100_000));
        assert!(matches!(
            parse_libinput_yaml(&dashes, p(), OnBadFrame::Stop),
            Err(RecordingError::Parse { line: 3, .. })
        ));
        let flow = format!("{header}{}\n", "[".repeat(100_000));
        assert!(parse_libinput_yaml(&flow, p(), OnBadFrame::Stop).is_err());
        // The deepest ladder the guard lets through parses on a test thread's stack.
        let mut ladder = String::from(header);
        for i in 0..MAX_YAML_INDENT {
            ladder.push_str(&" ".repeat(i));
            ladder.push_str("k:\n");
        }
        assert!(parse_libinput_yaml(&ladder, p(), OnBadFrame::Stop).is_err());
    }

    #[test]
    fn yaml_marker_lines_are_one_based() {
        let text = "version: 1\ndevices:\n- evdev:\n    absinfo: 7\n";
        let err = parse_libinput_yaml(text, p(), OnBadFrame::Stop).unwrap_err();
        match err {
            RecordingError::Parse { line, message, .. } => {
                assert_eq!(line, 4, "{message}");
                assert!(message.contains("absinfo"), "{message}");
            }
            e => panic!("{e}"),
        }
    }
}
