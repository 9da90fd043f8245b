//! Reading a report descriptor from a file: raw bytes, a hid-recorder log or a text
//! hex dump.

use std::path::{Path, PathBuf};

/// Why a descriptor file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum DescriptorFileError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// Larger than any descriptor or hid-recorder header could be.
    #[error("{}: {size} bytes is too large for a report descriptor file", path.display())]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Size.
        size: u64,
    },
    /// Text that does not hold a descriptor.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// File.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file is empty.
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// File.
        path: PathBuf,
    },
}

/// Largest descriptor file read: a hid-recorder log with events may be large.
const MAX_DESCRIPTOR_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// Reads a report descriptor from raw bytes (a sysfs `report_descriptor`, an
/// `.rdesc` dump), a hid-recorder file (its first `R:` line) or a text hex dump
/// (`05 0d 09 04 …`, `0x05, 0x0d, …`).
///
/// # Errors
/// [`DescriptorFileError`]: I/O, an empty or oversized file, an `R:` line whose
/// byte count does not match, bad hex.
pub fn read_descriptor_file(path: &Path) -> Result<Vec<u8>, DescriptorFileError> {
    use std::io::Read;
    let io = |source| DescriptorFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    // A regular file only (sysfs' report_descriptor is one): a FIFO or a device
    // is refused at the open.
    let file = crate::located::open_regular(path).map_err(|e| match e {
        crate::located::ReadError::Io { source, .. } => io(source),
        crate::located::ReadError::NotRegular { kind, .. } => io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{kind}, not a regular file"),
        )),
        e => io(std::io::Error::other(e.to_string())),
    })?;
    let mut bytes = Vec::new();
    file.take(MAX_DESCRIPTOR_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_DESCRIPTOR_FILE_BYTES {
        return Err(DescriptorFileError::TooLarge {
            path: path.to_path_buf(),
            size: bytes.len() as u64,
        });
    }
    if bytes.is_empty() {
        return Err(DescriptorFileError::Empty {
            path: path.to_path_buf(),
        });
    }
    let Ok(text) = std::str::from_utf8(&bytes) else {
        return Ok(bytes);
    };
    let perr = |line, message: String| DescriptorFileError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    };
    // hid-recorder: the first R: line.
    for (i, l) in text.lines().enumerate() {
        let l = l.trim();
        if let Some(rest) = l.strip_prefix("R:") {
            return crate::input::hid::hex::parse_r_line(rest).map_err(|m| perr(i + 1, m));
        }
    }
    // A hex dump: only hex byte tokens, commas, `0x` prefixes, comments.
    if let Some(parsed) = parse_hex_dump(text) {
        return parsed.map_err(|(line, m)| perr(line, m));
    }
    Ok(bytes)
}

/// Parses a text hex dump; `None` when the text does not look like one (then it
/// is taken as raw bytes).
fn parse_hex_dump(text: &str) -> Option<Result<Vec<u8>, (usize, String)>> {
    let mut out = Vec::new();
    let mut any = false;
    for (i, l) in text.lines().enumerate() {
        let l = l.split("//").next().unwrap_or("");
        let l = l.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        for tok in l.split(|c: char| c.is_whitespace() || c == ',') {
            if tok.is_empty() {
                continue;
            }
            let hex = tok
                .strip_prefix("0x")
                .or_else(|| tok.strip_prefix("0X"))
                .unwrap_or(tok);
            if hex.is_empty() || hex.len() > 2 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
                if any {
                    let tok = crate::located::Escaped(tok);
                    return Some(Err((i + 1, format!("`{tok}` is not a hex byte"))));
                }
                return None;
            }
            any = true;
            out.push(u8::from_str_radix(hex, 16).ok()?);
        }
    }
    any.then_some(Ok(out))
}
