//! What a client sends, read without blocking: lines assembled across reads under
//! the line-length cap.

use std::io::{ErrorKind, Read};
use std::ops::Range;

/// Bytes read from a socket in one `read`.
const READ_CHUNK: usize = 8 * 1024;
/// A line buffer larger than this is given back once it is empty (after a long line).
const KEEP_CAPACITY: usize = 16 * 1024;

/// A client's unread bytes: complete lines first, then the start of the next one.
#[derive(Debug, Default)]
pub(crate) struct LineBuf {
    buf: Vec<u8>,
    /// Start of the first line not yet taken.
    start: usize,
    /// `buf[start..scanned]` holds no newline.
    scanned: usize,
}

/// The next line, if one is complete.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Next {
    /// `bytes()[range]` is a line (newline removed); [`LineBuf::consume`] takes it.
    Line(Range<usize>),
    /// No complete line yet.
    Partial,
    /// The line passed the cap: at least this many bytes without a newline.
    TooLong(usize),
}

impl LineBuf {
    /// The buffer's bytes (index with a [`Next::Line`] range).
    pub fn bytes(&self) -> &[u8] {
        &self.buf
    }

    /// The next complete line of at most `max` bytes, without taking it.
    pub fn peek(&mut self, max: usize) -> Next {
        match self.buf[self.scanned..].iter().position(|&c| c == b'\n') {
            Some(i) => {
                let end = self.scanned + i;
                self.scanned = end;
                if end - self.start > max {
                    Next::TooLong(end - self.start)
                } else {
                    Next::Line(self.start..end)
                }
            }
            None => {
                self.scanned = self.buf.len();
                let len = self.buf.len() - self.start;
                if len > max {
                    Next::TooLong(len)
                } else {
                    Next::Partial
                }
            }
        }
    }

    /// Takes the line [`LineBuf::peek`] returned.
    pub fn consume(&mut self) {
        self.start = (self.scanned + 1).min(self.buf.len());
        self.scanned = self.start;
    }

    /// Reads once from `r` (at most `max` bytes): `Ok(0)` at end of stream.
    ///
    /// # Errors
    /// `r`'s, `WouldBlock` included.
    pub fn fill(&mut self, mut r: impl Read, max: usize) -> std::io::Result<usize> {
        if self.start == self.buf.len() {
            self.buf.clear();
            if self.buf.capacity() > KEEP_CAPACITY {
                self.buf = Vec::new();
            }
        } else if self.start > 0 {
            self.buf.drain(..self.start);
        }
        self.scanned -= self.start;
        self.start = 0;
        let old = self.buf.len();
        let want = max.clamp(1, READ_CHUNK);
        self.buf.resize(old + want, 0);
        let got = loop {
            match r.read(&mut self.buf[old..]) {
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                other => break other,
            }
        };
        self.buf.truncate(old + *got.as_ref().unwrap_or(&0));
        got
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(lb: &mut LineBuf, max: usize) -> Vec<Result<Vec<u8>, usize>> {
        let mut out = Vec::new();
        loop {
            match lb.peek(max) {
                Next::Line(r) => {
                    out.push(Ok(lb.bytes()[r].to_vec()));
                    lb.consume();
                }
                Next::Partial => return out,
                Next::TooLong(n) => {
                    out.push(Err(n));
                    return out;
                }
            }
        }
    }

    #[test]
    fn lines_are_assembled_across_reads() {
        let mut lb = LineBuf::default();
        let data = b"abc\nde".to_vec();
        assert_eq!(lb.fill(&data[..], 100).unwrap(), 6);
        assert_eq!(lines(&mut lb, 8), vec![Ok(b"abc".to_vec())]);
        assert_eq!(lb.fill(&b"fgh\n\nxy"[..], 100).unwrap(), 7);
        assert_eq!(
            lines(&mut lb, 8),
            vec![Ok(b"defgh".to_vec()), Ok(Vec::new())]
        );
        assert_eq!(lb.fill(&b""[..], 100).unwrap(), 0, "end of stream");
        // One byte at a time gives the same lines.
        let mut lb = LineBuf::default();
        let mut got = Vec::new();
        for b in b"one\ntwo\n" {
            lb.fill(&[*b][..], 100).unwrap();
            got.extend(lines(&mut lb, 8));
        }
        assert_eq!(got, vec![Ok(b"one".to_vec()), Ok(b"two".to_vec())]);
    }

    #[test]
    fn lines_are_capped() {
        let mut lb = LineBuf::default();
        lb.fill(&b"abcd\nabcde\n"[..], 100).unwrap();
        assert_eq!(lines(&mut lb, 4), vec![Ok(b"abcd".to_vec()), Err(5)]);
        // A line without its newline is refused as soon as it passes the cap.
        let mut lb = LineBuf::default();
        lb.fill(&b"abc"[..], 100).unwrap();
        assert_eq!(lines(&mut lb, 4), vec![]);
        lb.fill(&b"de"[..], 100).unwrap();
        assert_eq!(lines(&mut lb, 4), vec![Err(5)]);
    }

    #[test]
    fn reads_are_bounded() {
        let mut lb = LineBuf::default();
        let data = vec![b'x'; 3 * READ_CHUNK];
        assert_eq!(lb.fill(&data[..], usize::MAX).unwrap(), READ_CHUNK);
        assert_eq!(lb.fill(&data[..], 10).unwrap(), 10);
    }
}
