//! The `libinput record` YAML reader (version 1), decoded through the shared event
//! stream, a frame at a time.
//!
//! `devices[0].evdev.absinfo` maps an axis code to `[min, max, fuzz, flat,
//! resolution]`, and `devices[0].events[*].evdev` lists `[sec, usec, type, code,
//! value]`. Unknown keys are ignored (skipped without being kept); only the first
//! device is read.
//!
//! The text is read twice, as a stream of YAML events: once for the header (up to
//! where `devices[0].events` begins, in the order libinput writes them), and
//! again for the events, one frame at a time. Nothing but the header is kept.

use super::error::{OnBadFrame, RecordingError, UnsupportedReason};
use super::evdev_header::{default_name, AbsInfo, DeviceHeader, HeaderCtx};
use super::event_stream::EventStream;
use super::lines::LineReader;
use super::warnings::Warnings;
use super::yaml_events::{int_list, kind, YamlEvents};
use crate::input::evdev::ABS_MAX;
use crate::input::SurfaceInfo;
use crate::vocab::TouchFrame;
use std::path::Path;
use yaml_rust2::parser::Event;

/// Where a node starts and what it is.
#[derive(Copy, Clone, Debug)]
struct Found {
    line: usize,
    /// As messages say it.
    kind: &'static str,
    map: bool,
    list: bool,
    /// A null scalar (empty, `~`, `null`).
    null: bool,
}

impl Found {
    fn of(ev: &Event, line: usize) -> Found {
        Found {
            line,
            kind: kind(ev),
            map: matches!(ev, Event::MappingStart(..)),
            list: matches!(ev, Event::SequenceStart(..)),
            null: matches!(ev, Event::Scalar(s, ..) if s.is_empty() || s == "~" || s == "null"),
        }
    }
}

/// What the first pass learns of the header.
#[derive(Default)]
struct HeaderScan {
    root_line: usize,
    version: Option<(Found, Option<i64>)>,
    devices: Option<Found>,
    device: Option<Found>,
    evdev: Option<Found>,
    name: Option<String>,
    absinfo: Option<Found>,
    /// The first problem among the axes.
    axis_error: Option<RecordingError>,
    hdr: DeviceHeader,
    events: Option<Found>,
}

/// A key of a mapping: its text (`None` for a key that is not a scalar, which
/// is skipped), or `None` at the end of the mapping.
fn next_key(ev: &mut YamlEvents, path: &Path) -> Result<Option<Option<String>>, RecordingError> {
    let (k, _) = ev.next(path)?;
    match k {
        Event::MappingEnd => Ok(None),
        Event::Scalar(s, ..) => Ok(Some(Some(s))),
        other => {
            ev.skip(&other, path)?;
            Ok(Some(None))
        }
    }
}

/// Opens the document: `StreamStart`, `DocumentStart`, and the root node.
fn open_document(ev: &mut YamlEvents, path: &Path) -> Result<(Event, usize), RecordingError> {
    loop {
        let (e, line) = ev.next(path)?;
        match e {
            Event::StreamStart | Event::DocumentStart | Event::Nothing => {}
            Event::StreamEnd => {
                return Err(RecordingError::Empty {
                    path: path.to_path_buf(),
                })
            }
            root => return Ok((root, line)),
        }
    }
}

impl HeaderScan {
    /// Reads the header, stopping where `devices[0].events` begins once the
    /// version and `devices[0].evdev` are known.
    fn read(ev: &mut YamlEvents, path: &Path) -> Result<HeaderScan, RecordingError> {
        let mut h = HeaderScan::default();
        let (root, line) = open_document(ev, path)?;
        h.root_line = line;
        if !matches!(root, Event::MappingStart(..)) {
            return Ok(h);
        }
        while let Some(key) = next_key(ev, path)? {
            let (v, line) = ev.next(path)?;
            match key.as_deref() {
                Some("version") if h.version.is_none() => {
                    let n = match &v {
                        Event::Scalar(s, ..) => s.parse().ok(),
                        _ => None,
                    };
                    h.version = Some((Found::of(&v, line), n));
                    ev.skip(&v, path)?;
                }
                Some("devices") if h.devices.is_none() => {
                    h.devices = Some(Found::of(&v, line));
                    if matches!(v, Event::SequenceStart(..)) {
                        if h.devices(ev, path)? {
                            return Ok(h);
                        }
                    } else {
                        ev.skip(&v, path)?;
                    }
                }
                _ => ev.skip(&v, path)?,
            }
        }
        Ok(h)
    }

    /// The list of devices; `true` when the scan can stop.
    fn devices(&mut self, ev: &mut YamlEvents, path: &Path) -> Result<bool, RecordingError> {
        let mut first = true;
        loop {
            let (item, line) = ev.next(path)?;
            if matches!(item, Event::SequenceEnd) {
                return Ok(false);
            }
            if first && matches!(item, Event::MappingStart(..)) {
                self.device = Some(Found::of(&item, line));
                if self.device(ev, path)? {
                    return Ok(true);
                }
            } else {
                if first {
                    self.device = Some(Found::of(&item, line));
                }
                ev.skip(&item, path)?;
            }
            first = false;
        }
    }

    /// The first device's mapping; `true` when the scan can stop.
    fn device(&mut self, ev: &mut YamlEvents, path: &Path) -> Result<bool, RecordingError> {
        while let Some(key) = next_key(ev, path)? {
            let (v, line) = ev.next(path)?;
            match key.as_deref() {
                Some("evdev") if self.evdev.is_none() => {
                    self.evdev = Some(Found::of(&v, line));
                    if matches!(v, Event::MappingStart(..)) {
                        self.evdev(ev, path)?;
                    } else {
                        ev.skip(&v, path)?;
                    }
                }
                Some("events") if self.events.is_none() => {
                    self.events = Some(Found::of(&v, line));
                    if self.version.is_some() && self.evdev.is_some() {
                        return Ok(true);
                    }
                    ev.skip(&v, path)?;
                }
                _ => ev.skip(&v, path)?,
            }
        }
        Ok(false)
    }

    /// `devices[0].evdev`: the name and the axes.
    fn evdev(&mut self, ev: &mut YamlEvents, path: &Path) -> Result<(), RecordingError> {
        while let Some(key) = next_key(ev, path)? {
            let (v, line) = ev.next(path)?;
            match (key.as_deref(), &v) {
                (Some("name"), Event::Scalar(s, ..)) if self.name.is_none() => {
                    self.name = Some(s.clone());
                }
                (Some("absinfo"), _) if self.absinfo.is_none() => {
                    self.absinfo = Some(Found::of(&v, line));
                    if matches!(v, Event::MappingStart(..)) {
                        self.absinfo(ev, path)?;
                        continue;
                    }
                    ev.skip(&v, path)?;
                }
                _ => ev.skip(&v, path)?,
            }
        }
        Ok(())
    }

    /// The `absinfo` mapping; the first problem is kept for later.
    fn absinfo(&mut self, ev: &mut YamlEvents, path: &Path) -> Result<(), RecordingError> {
        let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
        loop {
            let (k, kline) = ev.next(path)?;
            if matches!(k, Event::MappingEnd) {
                return Ok(());
            }
            let code = match &k {
                Event::Scalar(s, ..) => s.parse::<i64>().ok(),
                _ => None,
            };
            ev.skip(&k, path)?;
            let (v, vline) = ev.next(path)?;
            let Some(code) = code else {
                ev.skip(&v, path)?;
                self.axis_error.get_or_insert(perr(
                    kline,
                    "field `absinfo`: axis codes must be integers".to_string(),
                ));
                continue;
            };
            if !(0..=i64::from(ABS_MAX)).contains(&code) {
                ev.skip(&v, path)?;
                self.axis_error.get_or_insert(perr(
                    kline,
                    format!("field `absinfo`: unknown axis code {code} (the highest is {ABS_MAX})"),
                ));
                continue;
            }
            let f = format!("absinfo.{code}");
            let list = int_list(ev, &v, &f, path)?;
            if self.axis_error.is_some() {
                continue;
            }
            let axis = list
                .and_then(|l| {
                    let vals = l.check(&f, 4..=5)?;
                    let get = |i: usize| vals.get(i).copied().unwrap_or(0);
                    let to_i32 = |x: i64| {
                        i32::try_from(x).map_err(|_| format!("field `{f}`: {x} is out of range"))
                    };
                    Ok(AbsInfo {
                        min: to_i32(get(0))?,
                        max: to_i32(get(1))?,
                        resolution: to_i32(get(4))?,
                        line: vline,
                    })
                })
                .map_err(|m| perr(vline, m));
            match axis {
                Err(e) => self.axis_error = Some(e),
                Ok(_) if self.hdr.abs[code as usize].is_some() => {
                    self.axis_error = Some(perr(
                        kline,
                        format!("field `absinfo`: axis {code} is declared twice"),
                    ));
                }
                Ok(a) => self.hdr.abs[code as usize] = Some(a),
            }
        }
    }

    /// What the header says, checked in order: the version, the device, its
    /// axes, its events.
    fn check(
        mut self,
        path: &Path,
        w: &mut Warnings,
    ) -> Result<(DeviceHeader, crate::input::evdev::MtAxes, SurfaceInfo), RecordingError> {
        let perr = |line: usize, message: String| RecordingError::parse(path, line, message);
        let missing = |line: usize, what: &str| perr(line, format!("missing field `{what}`"));
        match self.version {
            None => return Err(missing(self.root_line, "version")),
            Some((_, Some(1))) => {}
            Some((_, Some(v))) => {
                return Err(RecordingError::Unsupported {
                    path: path.to_path_buf(),
                    reason: UnsupportedReason::Version {
                        format: "libinput record",
                        version: v,
                    },
                })
            }
            Some((f, None)) => {
                return Err(perr(
                    f.line,
                    format!("field `version`: expected an integer, found {}", f.kind),
                ))
            }
        }
        let devices = self
            .devices
            .ok_or_else(|| missing(self.root_line, "devices"))?;
        let Some(dev) = self.device else {
            return Err(perr(
                devices.line,
                format!(
                    "field `devices`: expected a non-empty list, found {}",
                    devices.kind
                ),
            ));
        };
        if !dev.map {
            return Err(perr(
                dev.line,
                format!("field `devices[0]`: expected a mapping, found {}", dev.kind),
            ));
        }
        let evdev = self
            .evdev
            .ok_or_else(|| missing(dev.line, "devices[0].evdev"))?;
        self.hdr.name = self.name.take();
        let absinfo = self
            .absinfo
            .ok_or_else(|| missing(evdev.line, "devices[0].evdev.absinfo"))?;
        if !absinfo.map {
            return Err(perr(
                absinfo.line,
                format!(
                    "field `devices[0].evdev.absinfo`: expected a mapping, found {}",
                    absinfo.kind
                ),
            ));
        }
        if let Some(e) = self.axis_error.take() {
            return Err(e);
        }
        let ctx = HeaderCtx { path, prefix: "" };
        let (axes, surface) = self
            .hdr
            .mt_axes(&ctx, absinfo.line, &default_name(path), w)?;
        match self.events {
            Some(e) if e.list => Ok((self.hdr, axes, surface)),
            Some(e) if !e.null => Err(perr(
                e.line,
                format!(
                    "field `devices[0].events`: expected a list, found {}",
                    e.kind
                ),
            )),
            _ => Err(RecordingError::Empty {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Where the events pass is.
#[derive(Copy, Clone, Debug)]
enum Pos {
    /// In `events`, before item `fi`.
    Items {
        fi: usize,
    },
    /// In the mapping of item `fi`, before a key; `seen` once its `evdev` was read.
    Item {
        fi: usize,
        seen: bool,
    },
    /// In `events[fi].evdev`, before event `ei`.
    Evdev {
        fi: usize,
        ei: usize,
    },
    /// After the events: the rest of the document.
    Tail,
    Done,
}

/// Reads libinput record YAML a frame at a time.
pub(super) struct YamlReader {
    ev: YamlEvents,
    stream: EventStream,
    pos: Pos,
}

impl YamlReader {
    /// Reads the header, then goes back to where the events begin.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a malformed header or text that is not
    /// YAML, [`RecordingError::Unsupported`] for an unknown version or a device
    /// without multi-touch axes, [`RecordingError::Empty`] without events.
    pub(super) fn open(
        mut lines: LineReader,
        path: &Path,
        on_bad: OnBadFrame,
        w: &mut Warnings,
    ) -> Result<(YamlReader, SurfaceInfo), RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.to_path_buf(),
            source,
        };
        lines.rewind().map_err(io)?;
        let mut ev = YamlEvents::new(lines);
        let scan = HeaderScan::read(&mut ev, path)?;
        let (hdr, axes, surface) = scan.check(path, w)?;
        let mut lines = ev.into_lines().ok_or_else(|| lost(path))?;
        lines.rewind().map_err(io)?;
        let mut ev = YamlEvents::new(lines);
        seek_events(&mut ev, path)?;
        let reader = YamlReader {
            ev,
            stream: EventStream::new(on_bad, axes, &hdr),
            pos: Pos::Items { fi: 0 },
        };
        Ok((reader, surface))
    }
}

impl YamlReader {
    /// The source, for reading again from the start.
    pub(super) fn into_lines(self) -> Option<LineReader> {
        self.ev.into_lines()
    }

    /// Bytes read so far.
    pub(super) fn consumed(&self) -> u64 {
        self.ev.consumed()
    }

    /// The next frame into `out`, and the line of the event that closed it;
    /// `None` after the last.
    ///
    /// # Errors
    /// [`RecordingError::Parse`] for a bad event with [`OnBadFrame::Stop`] and
    /// for text that is not YAML; [`RecordingError::Empty`] at the end when no
    /// frame was decoded.
    pub(super) fn next(
        &mut self,
        path: &Path,
        out: &mut TouchFrame,
        w: &mut Warnings,
    ) -> Result<Option<usize>, RecordingError> {
        loop {
            match self.pos {
                Pos::Items { fi } => {
                    let (item, line) = self.ev.next(path)?;
                    self.pos = match item {
                        Event::SequenceEnd => Pos::Tail,
                        Event::MappingStart(..) => Pos::Item { fi, seen: false },
                        other => {
                            let m = format!(
                                "field `events[{fi}]`: expected a mapping, found {}",
                                kind(&other)
                            );
                            self.stream.bad(path, line, m, w)?;
                            self.ev.skip(&other, path)?;
                            Pos::Items { fi: fi + 1 }
                        }
                    };
                }
                Pos::Item { fi, seen } => {
                    let Some(key) = next_key(&mut self.ev, path)? else {
                        self.pos = Pos::Items { fi: fi + 1 };
                        continue;
                    };
                    let (v, line) = self.ev.next(path)?;
                    // libinput events and other keys are not needed.
                    if seen || key.as_deref() != Some("evdev") {
                        self.ev.skip(&v, path)?;
                        continue;
                    }
                    if matches!(v, Event::SequenceStart(..)) {
                        self.pos = Pos::Evdev { fi, ei: 0 };
                    } else {
                        let m = format!(
                            "field `events[{fi}].evdev`: expected a list, found {}",
                            kind(&v)
                        );
                        self.stream.bad(path, line, m, w)?;
                        self.ev.skip(&v, path)?;
                        self.pos = Pos::Item { fi, seen: true };
                    }
                }
                Pos::Evdev { fi, ei } => {
                    let (e, line) = self.ev.next(path)?;
                    if matches!(e, Event::SequenceEnd) {
                        self.pos = Pos::Item { fi, seen: true };
                        continue;
                    }
                    self.pos = Pos::Evdev { fi, ei: ei + 1 };
                    let f = format!("events[{fi}].evdev[{ei}]");
                    match int_list(&mut self.ev, &e, &f, path)?
                        .and_then(|l| yaml_event(l.check(&f, 5..=5)?, &f))
                    {
                        Ok(event) => {
                            if self.stream.event(path, line, event, out, w)? {
                                return Ok(Some(line));
                            }
                        }
                        Err(m) => self.stream.bad(path, line, m, w)?,
                    }
                }
                Pos::Tail => {
                    let line = finish_document(&mut self.ev, path, w)?;
                    self.pos = Pos::Done;
                    if self.stream.finish(path, out, w)? {
                        return Ok(Some(line));
                    }
                }
                Pos::Done => return Ok(None),
            }
        }
    }
}

/// Goes to the first item of `devices[0].events` (the first `devices`, the
/// first `events`, as the header pass read them).
fn seek_events(ev: &mut YamlEvents, path: &Path) -> Result<(), RecordingError> {
    let changed = |line| {
        RecordingError::parse(
            path,
            line,
            "the recording changed while it was read (devices[0].events moved)",
        )
    };
    let (root, line) = open_document(ev, path)?;
    if !matches!(root, Event::MappingStart(..)) {
        return Err(changed(line));
    }
    let mut depth = 0;
    loop {
        let Some(key) = next_key(ev, path)? else {
            return Err(changed(line));
        };
        let (v, vline) = ev.next(path)?;
        let wanted = if depth == 0 { "devices" } else { "events" };
        if key.as_deref() != Some(wanted) {
            ev.skip(&v, path)?;
            continue;
        }
        match (depth, v) {
            (0, Event::SequenceStart(..)) => match ev.next(path)? {
                (Event::MappingStart(..), _) => depth = 1,
                (_, l) => return Err(changed(l)),
            },
            (1, Event::SequenceStart(..)) => return Ok(()),
            (_, _) => return Err(changed(vline)),
        }
    }
}

/// Reads the rest of the document after `devices[0].events`, noting a second
/// device; returns the last line read.
fn finish_document(
    ev: &mut YamlEvents,
    path: &Path,
    w: &mut Warnings,
) -> Result<usize, RecordingError> {
    // Inside: the root mapping, `devices`, `devices[0]`.
    let mut depth = 3usize;
    let mut noted = false;
    loop {
        let (e, line) = ev.next(path)?;
        match e {
            Event::DocumentEnd | Event::StreamEnd => return Ok(line),
            Event::SequenceEnd | Event::MappingEnd => depth = depth.saturating_sub(1),
            e => {
                if depth == 2 && !noted {
                    w.push(line, "only the first device is read".into());
                    noted = true;
                }
                if matches!(e, Event::SequenceStart(..) | Event::MappingStart(..)) {
                    depth += 1;
                }
            }
        }
    }
}

/// The source was lost (a poisoned lock): reported as an I/O error.
fn lost(path: &Path) -> RecordingError {
    RecordingError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other("the YAML reader lost its source"),
    }
}

/// `[sec, usec, type, code, value]` → `(time_us, type, code, value)`.
fn yaml_event(v: &[i64], field: &str) -> Result<(u64, u16, u16, i32), String> {
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
