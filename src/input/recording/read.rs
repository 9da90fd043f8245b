//! Reading a recording file: size cap, format detection, and dispatch to the
//! reader of its format.

use super::error::{OnBadFrame, RecordingError};
use super::evemu::{is_evemu_line, parse_evemu};
use super::hid_recorder::read_hid_recorder;
use super::jsonl::parse_jsonl;
use super::libinput_yaml::parse_libinput_yaml;
use super::recording_type::Recording;
use std::io::Read;
use std::path::Path;

/// Largest recording file [`read_recording`] accepts, in bytes (64 MiB).
pub const MAX_RECORDING_BYTES: u64 = 64 * 1024 * 1024;

/// Reads and decodes a recording file, detecting its format.
///
/// # Errors
/// [`RecordingError`]: I/O, size over [`MAX_RECORDING_BYTES`], text that is not
/// UTF-8, and everything [`parse_recording`] reports.
pub fn read_recording(path: &Path, on_bad: OnBadFrame) -> Result<Recording, RecordingError> {
    let text = read_capped(path)?;
    parse_recording(&text, path, on_bad)
}

/// Reads a text file of at most [`MAX_RECORDING_BYTES`].
fn read_capped(path: &Path) -> Result<String, RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io)?;
    let too_large = |size| RecordingError::TooLarge {
        path: path.to_path_buf(),
        size,
        limit: MAX_RECORDING_BYTES,
    };
    if let Ok(meta) = file.metadata() {
        if meta.len() > MAX_RECORDING_BYTES {
            return Err(too_large(meta.len()));
        }
    }
    let mut bytes = Vec::new();
    file.take(MAX_RECORDING_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_RECORDING_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(RecordingError::UnknownFormat {
            path: path.to_path_buf(),
            found: "gzip data; decompress it first".to_string(),
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
        RecordingError::parse(path, line, "the file is not UTF-8 text")
    })
}

/// Which reader a text needs.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Format {
    Jsonl,
    Evemu,
    LibinputYaml,
    HidRecorder,
}

/// Detects the format from the first meaningful line (or the YAML top keys).
fn detect(text: &str) -> Result<Option<Format>, String> {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'));
    let Some(first) = first else {
        return Ok(None);
    };
    if first.starts_with('{') {
        return Ok(Some(Format::Jsonl));
    }
    // hid-recorder writes the descriptor (`R:`) first, after an optional `D:`.
    if first.starts_with("R:") || first.starts_with("D:") {
        return Ok(Some(Format::HidRecorder));
    }
    if is_evemu_line(first) {
        return Ok(Some(Format::Evemu));
    }
    let has_top = |key: &str| text.lines().any(|l| l.starts_with(key));
    if has_top("version:") && has_top("devices:") {
        return Ok(Some(Format::LibinputYaml));
    }
    Err(first.chars().take(40).collect())
}

/// Decodes a recording held in memory; `name` is used in errors.
///
/// # Errors
/// [`RecordingError::Parse`] (with [`OnBadFrame::Stop`]), `UnknownFormat`,
/// `Unsupported` (no multi-touch axes, unknown version) and `Empty`.
pub fn parse_recording(
    text: &str,
    name: &Path,
    on_bad: OnBadFrame,
) -> Result<Recording, RecordingError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    match detect(text) {
        Ok(Some(Format::Jsonl)) => parse_jsonl(text, name, on_bad),
        Ok(Some(Format::Evemu)) => parse_evemu(None, text, name, on_bad),
        Ok(Some(Format::LibinputYaml)) => parse_libinput_yaml(text, name, on_bad),
        Ok(Some(Format::HidRecorder)) => read_hid_recorder(text, name, on_bad),
        Ok(None) => Err(RecordingError::Empty {
            path: name.to_path_buf(),
        }),
        Err(found) => Err(RecordingError::UnknownFormat {
            path: name.to_path_buf(),
            found,
        }),
    }
}
