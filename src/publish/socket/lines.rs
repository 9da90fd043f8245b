//! What a client sends, read without blocking: lines assembled across reads under
//! the line-length cap, and the per-client budget of lines per second.

use crate::vocab::Micros;
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

/// Lines a client may send per second, sustained.
pub const LINES_PER_SECOND: u64 = 200;
/// Lines a client may send at once after a quiet spell.
pub const LINE_BURST: u64 = 50;
/// Credit one line costs (µs).
const LINE_COST_US: u64 = 1_000_000 / LINES_PER_SECOND;

/// A client's budget of lines: [`LINE_BURST`] at once, [`LINES_PER_SECOND`] sustained
/// (a token bucket counted in microseconds of credit).
#[derive(Debug)]
pub(crate) struct LineRate {
    credit_us: u64,
    last: Micros,
}

impl LineRate {
    /// A full budget at `now`.
    pub fn new(now: Micros) -> LineRate {
        LineRate {
            credit_us: LINE_BURST * LINE_COST_US,
            last: now,
        }
    }

    /// Takes one line's credit at `now`; false when there is none.
    pub fn take(&mut self, now: Micros) -> bool {
        let earned = now.saturating_since(self.last).0;
        self.last = self.last.max(now);
        self.credit_us = (self.credit_us + earned).min(LINE_BURST * LINE_COST_US);
        if self.credit_us >= LINE_COST_US {
            self.credit_us -= LINE_COST_US;
            true
        } else {
            false
        }
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

    #[test]
    fn the_line_rate_allows_a_burst_then_the_sustained_rate() {
        let t0 = Micros(1_000_000);
        let mut r = LineRate::new(t0);
        let burst = (0..1000).take_while(|_| r.take(t0)).count() as u64;
        assert_eq!(burst, LINE_BURST);
        // One second later: one second's worth, no more.
        let t1 = Micros(t0.0 + 1_000_000);
        let more = (0..1000).take_while(|_| r.take(t1)).count() as u64;
        assert_eq!(more, LINES_PER_SECOND.min(LINE_BURST));
        // Then one line per line's cost.
        let steps = (1..=100u64)
            .filter(|k| r.take(Micros(t1.0 + k * LINE_COST_US)))
            .count();
        assert_eq!(steps, 100);
        assert!(!r.take(Micros(t1.0 + 100 * LINE_COST_US)));
        // A long quiet spell refills only up to the burst.
        let t2 = Micros(t1.0 + 3_600_000_000);
        let after = (0..1000).take_while(|_| r.take(t2)).count() as u64;
        assert_eq!(after, LINE_BURST);
        // Time going backwards (it cannot, on CLOCK_MONOTONIC) earns nothing.
        assert!(!r.take(t0));
    }
}
