//! Where every reader gets its text: a recording's bytes, read a line at a time
//! into one reused buffer, each line capped at [`MAX_LINE_BYTES`] before it is
//! buffered whole, checked for UTF-8, and rewound to the start to read again.

use super::error::RecordingError;
use std::io::{BufRead, Seek, SeekFrom};
use std::path::Path;

/// Longest line a recording may hold, in bytes (1 MiB). A frame of
/// [`MAX_CONTACTS`](crate::vocab::MAX_CONTACTS) contacts with every optional
/// field takes under 10 KiB; an `R:` descriptor line under 13 KiB.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// What a recording is read from: a file, or bytes in memory.
pub(super) trait Source: BufRead + Seek + Send {}
impl<T: BufRead + Seek + Send> Source for T {}

/// Why a line could not be had.
#[derive(Debug)]
pub(super) enum LineFault {
    /// Longer than [`MAX_LINE_BYTES`]; the rest of it is still unread.
    TooLong,
    /// Not UTF-8.
    NotUtf8,
    /// The read failed.
    Io(std::io::Error),
}

impl LineFault {
    /// The error this fault is at `line` of `path`.
    pub(super) fn at(self, path: &Path, line: usize) -> RecordingError {
        match self {
            LineFault::TooLong => RecordingError::parse(path, line, too_long_message()),
            LineFault::NotUtf8 => RecordingError::parse(path, line, "the file is not UTF-8 text"),
            LineFault::Io(source) => RecordingError::Io {
                path: path.to_path_buf(),
                source,
            },
        }
    }
}

/// What a reader says about a line over [`MAX_LINE_BYTES`].
pub(super) fn too_long_message() -> String {
    format!("the line is longer than {MAX_LINE_BYTES} bytes, the limit for a line of a recording")
}

/// The lines of a recording, one at a time, in a reused buffer.
pub(super) struct LineReader {
    src: Box<dyn Source>,
    buf: Vec<u8>,
    /// 1-based number of the line last read (0 before the first).
    line: usize,
    /// Bytes consumed from the start.
    consumed: u64,
}

impl LineReader {
    pub(super) fn new(src: Box<dyn Source>) -> LineReader {
        LineReader {
            src,
            buf: Vec::new(),
            line: 0,
            consumed: 0,
        }
    }

    /// The 1-based number of the line last read.
    pub(super) fn line(&self) -> usize {
        self.line
    }

    /// Bytes consumed from the start of the text.
    pub(super) fn consumed(&self) -> u64 {
        self.consumed
    }

    /// The first bytes of the text (at most what one buffer fill gives), unconsumed.
    pub(super) fn peek_start(&mut self) -> std::io::Result<&[u8]> {
        self.src.fill_buf()
    }

    /// The next line and its number, without its line break (`\n` or `\r\n`)
    /// and, on line 1, without a byte order mark; `None` at the end of the text.
    ///
    /// # Errors
    /// [`LineFault::TooLong`] as soon as the line passes [`MAX_LINE_BYTES`] (the
    /// rest stays unread: [`LineReader::skip_rest`] discards it),
    /// [`LineFault::NotUtf8`], [`LineFault::Io`]. The line number counts the
    /// faulty line.
    pub(super) fn next_line(&mut self) -> Result<Option<(usize, &str)>, LineFault> {
        self.buf.clear();
        let mut any = false;
        loop {
            let chunk = match self.src.fill_buf() {
                Ok(c) => c,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(LineFault::Io(e)),
            };
            if chunk.is_empty() {
                break;
            }
            if !any {
                any = true;
                self.line += 1;
            }
            let (take, done) = match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => (i, true),
                None => (chunk.len(), false),
            };
            if self.buf.len() + take > MAX_LINE_BYTES {
                let fits = MAX_LINE_BYTES - self.buf.len();
                self.src.consume(fits);
                self.consumed += fits as u64;
                return Err(LineFault::TooLong);
            }
            self.buf.extend_from_slice(&chunk[..take]);
            let used = take + usize::from(done);
            self.src.consume(used);
            self.consumed += used as u64;
            if done {
                break;
            }
        }
        if !any {
            return Ok(None);
        }
        if self.buf.last() == Some(&b'\r') {
            self.buf.pop();
        }
        let mut text = std::str::from_utf8(&self.buf).map_err(|_| LineFault::NotUtf8)?;
        if self.line == 1 {
            text = text.strip_prefix('\u{feff}').unwrap_or(text);
        }
        Ok(Some((self.line, text)))
    }

    /// Discards what is left of a line [`LineFault::TooLong`] refused, without
    /// buffering it.
    ///
    /// # Errors
    /// The read's.
    pub(super) fn skip_rest(&mut self) -> std::io::Result<()> {
        loop {
            let chunk = match self.src.fill_buf() {
                Ok(c) => c,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            if chunk.is_empty() {
                return Ok(());
            }
            let (used, done) = match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (chunk.len(), false),
            };
            self.src.consume(used);
            self.consumed += used as u64;
            if done {
                return Ok(());
            }
        }
    }

    /// Back to the start of the text, at line 0.
    ///
    /// # Errors
    /// The seek's.
    pub(super) fn rewind(&mut self) -> std::io::Result<()> {
        self.src.seek(SeekFrom::Start(0))?;
        self.line = 0;
        self.consumed = 0;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn reader(bytes: &[u8]) -> LineReader {
        LineReader::new(Box::new(std::io::BufReader::with_capacity(
            7,
            Cursor::new(bytes.to_vec()),
        )))
    }

    #[test]
    fn lines_breaks_bom_and_numbers() {
        let mut r = reader("\u{feff}a\r\n\nbc\nlast".as_bytes());
        let mut got = Vec::new();
        while let Some((n, l)) = r.next_line().unwrap() {
            got.push((n, l.to_string()));
        }
        let want = [(1, "a"), (2, ""), (3, "bc"), (4, "last")];
        assert_eq!(got, want.map(|(n, s)| (n, s.to_string())));
        r.rewind().unwrap();
        assert_eq!(r.next_line().unwrap(), Some((1, "a")));
    }

    #[test]
    fn an_over_long_line_is_refused_before_it_is_buffered_and_can_be_skipped() {
        let mut text = vec![b'x'; MAX_LINE_BYTES + 10];
        text.extend_from_slice(b"\nnext\n");
        let mut r = reader(&text);
        assert!(matches!(r.next_line(), Err(LineFault::TooLong)));
        assert_eq!(r.line(), 1);
        assert!(r.buf.capacity() <= MAX_LINE_BYTES * 2);
        r.skip_rest().unwrap();
        assert_eq!(r.next_line().unwrap(), Some((2, "next")));
        // Exactly at the limit is a line.
        let mut text = vec![b'y'; MAX_LINE_BYTES];
        text.push(b'\n');
        let mut r = reader(&text);
        assert_eq!(
            r.next_line().unwrap().map(|(_, l)| l.len()),
            Some(MAX_LINE_BYTES)
        );
    }

    #[test]
    fn bad_utf8_names_its_line() {
        let mut r = reader(b"ok\n\xff\xfe\n");
        assert_eq!(r.next_line().unwrap(), Some((1, "ok")));
        assert!(matches!(r.next_line(), Err(LineFault::NotUtf8)));
        assert_eq!(r.line(), 2);
    }
}
