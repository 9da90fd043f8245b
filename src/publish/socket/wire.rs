//! One queued message on its way into a client's socket: its bytes as up to four
//! pieces, written without copying the shared encoding, resumed where a partial
//! write stopped.
//!
//! A snapshot is encoded once for every client with the same format and field set
//! (an `Arc`); what differs per client is its `dropped` count, and a `dropped` notice
//! before it. So a frame is: an owned prefix (the notice, a binary frame header), the
//! shared bytes before the count, the count, and the shared bytes after it; `sendmsg`
//! takes them as one vector.

use super::queue::{EncodedSnapshot, Item};
use crate::publish::protocol::{self, Format, FRAME_KIND_JSON};
use crate::vocab::Micros;
use nix::sys::socket::{sendmsg, MsgFlags, UnixAddr};
use std::io::IoSlice;
use std::os::fd::AsRawFd;
use std::os::unix::net::UnixStream;
use std::sync::Arc;

/// The shared bytes of a frame.
#[derive(Debug, Default)]
enum Body {
    /// No frame.
    #[default]
    None,
    /// A snapshot's encoding.
    Snapshot(Arc<EncodedSnapshot>),
    /// A JSON line (event, reply, mesh, ...).
    Json(Arc<[u8]>),
}

impl Body {
    fn bytes(&self) -> &[u8] {
        match self {
            Body::None => &[],
            Body::Snapshot(e) => &e.bytes,
            Body::Json(j) => j,
        }
    }
}

/// The message being written to one client, and how much of it is out.
#[derive(Debug, Default)]
pub(crate) struct Frame {
    /// Owned bytes before the body: a `dropped` notice, a binary frame header.
    prefix: Vec<u8>,
    body: Body,
    /// The body is `body[..split]`, then `middle`, then `body[split + skip..end]`.
    split: usize,
    skip: usize,
    end: usize,
    middle: [u8; 24],
    middle_len: usize,
    /// Bytes written so far, of `len`.
    sent: usize,
    len: usize,
    /// A snapshot, for the counters: its input time.
    snapshot: Option<Option<Micros>>,
}

impl Frame {
    /// Whether a message is being written.
    pub fn active(&self) -> bool {
        self.sent < self.len
    }

    /// Makes `item` the message to write: told of `unnotified` drops first (a
    /// `dropped` notice), with `dropped_total` spliced into a snapshot.
    pub fn load(&mut self, item: Item, unnotified: u64, dropped_total: u64) {
        self.prefix.clear();
        self.middle_len = 0;
        self.skip = 0;
        self.sent = 0;
        self.snapshot = None;
        let framing = match &item {
            Item::Snapshot(e) => e.format,
            Item::Mesh { framing, .. }
            | Item::Poses { framing, .. }
            | Item::Message { framing, .. } => *framing,
        };
        if unnotified > 0 {
            let mut notice = Vec::with_capacity(64);
            protocol::encode_dropped(unnotified, dropped_total, &mut notice);
            match framing {
                Format::Json => self.prefix.extend_from_slice(&notice),
                Format::Binary => protocol::frame_json(&notice, &mut self.prefix),
            }
        }
        match item {
            Item::Snapshot(enc) => {
                self.snapshot = Some(enc.input_t);
                self.end = enc.bytes.len();
                match enc.format {
                    Format::Json => {
                        self.split = enc.dropped_at.min(self.end);
                        let mut digits = itoa::Buffer::new();
                        self.set_middle(digits.format(dropped_total).as_bytes());
                    }
                    Format::Binary => {
                        let at = protocol::BINARY_DROPPED_OFFSET;
                        if self.end >= at + 8 {
                            self.split = at;
                            self.skip = 8;
                            self.set_middle(&dropped_total.to_le_bytes());
                        } else {
                            self.split = self.end;
                        }
                    }
                }
                self.body = Body::Snapshot(enc);
            }
            Item::Mesh { json, framing, .. }
            | Item::Poses { json, framing }
            | Item::Message { json, framing } => {
                self.end = json.len();
                if framing == Format::Binary {
                    // protocol::frame_json's header: length of kind + JSON, the kind.
                    let body = json.strip_suffix(b"\n").unwrap_or(&json);
                    self.end = body.len();
                    let len = u32::try_from(body.len() + 1).unwrap_or(u32::MAX);
                    self.prefix.extend_from_slice(&len.to_le_bytes());
                    self.prefix.push(FRAME_KIND_JSON);
                }
                self.split = self.end;
                self.body = Body::Json(json);
            }
        }
        self.len = self.prefix.len() + self.end - self.skip + self.middle_len;
    }

    fn set_middle(&mut self, bytes: &[u8]) {
        self.middle[..bytes.len()].copy_from_slice(bytes);
        self.middle_len = bytes.len();
    }

    /// The frame's pieces in order.
    fn pieces(&self) -> [&[u8]; 4] {
        let b = self.body.bytes();
        [
            &self.prefix,
            &b[..self.split],
            &self.middle[..self.middle_len],
            &b[self.split + self.skip..self.end],
        ]
    }

    /// What is left to write: the pieces from byte `sent` on, and how many.
    fn remaining(&self) -> ([IoSlice<'_>; 4], usize) {
        let mut skip = self.sent;
        let mut iov: [IoSlice<'_>; 4] = [IoSlice::new(&[]); 4];
        let mut n = 0;
        for piece in self.pieces() {
            if skip >= piece.len() {
                skip -= piece.len();
                continue;
            }
            iov[n] = IoSlice::new(&piece[skip..]);
            skip = 0;
            n += 1;
        }
        (iov, n)
    }

    /// Writes what is left of the frame with one non-blocking `sendmsg`
    /// (`MSG_NOSIGNAL`: a vanished peer is an `EPIPE` error, never a `SIGPIPE`).
    /// Returns the bytes written.
    ///
    /// # Errors
    /// The socket's: `WouldBlock` when its buffer is full.
    pub fn send(&mut self, stream: &UnixStream) -> std::io::Result<usize> {
        let (iov, n) = self.remaining();
        let flags = MsgFlags::MSG_NOSIGNAL | MsgFlags::MSG_DONTWAIT;
        let wrote = sendmsg::<UnixAddr>(stream.as_raw_fd(), &iov[..n], &[], flags, None)
            .map_err(std::io::Error::from)?;
        self.sent += wrote;
        Ok(wrote)
    }

    /// When the frame is fully written: its length, and whether it is a snapshot
    /// with its input time. Releases the shared bytes.
    pub fn finish(&mut self) -> (usize, Option<Option<Micros>>) {
        let done = (self.len, self.snapshot.take());
        self.body = Body::None;
        self.sent = 0;
        self.len = 0;
        // A long notice or header never stays: the prefix is kept small.
        if self.prefix.capacity() > 4096 {
            self.prefix = Vec::new();
        }
        done
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    /// The bytes `frame` writes when every write takes at most `step` bytes.
    fn written(frame: &mut Frame, step: usize) -> Vec<u8> {
        let mut out = Vec::new();
        while frame.active() {
            let (iov, n) = frame.remaining();
            let left: Vec<u8> = iov[..n].iter().flat_map(|s| s.iter().copied()).collect();
            let take = step.min(left.len());
            out.extend_from_slice(&left[..take]);
            frame.sent += take;
        }
        out
    }

    fn json_snapshot() -> Arc<EncodedSnapshot> {
        let mut bytes = Vec::new();
        bytes.extend_from_slice(b"{\"type\":\"snapshot\",\"dropped\":,\"agents\":[]}\n");
        Arc::new(EncodedSnapshot {
            format: Format::Json,
            dropped_at: 30,
            bytes,
            input_t: Some(Micros(5)),
        })
    }

    #[test]
    fn a_json_snapshot_gets_its_notice_and_count() {
        let mut f = Frame::default();
        f.load(Item::Snapshot(json_snapshot()), 2, 7);
        let mut expected = Vec::new();
        protocol::encode_dropped(2, 7, &mut expected);
        protocol::splice_dropped_json(&json_snapshot().bytes, 30, 7, &mut expected);
        for step in [1, 3, 1000] {
            let mut g = Frame::default();
            g.load(Item::Snapshot(json_snapshot()), 2, 7);
            assert_eq!(written(&mut g, step), expected, "step {step}");
        }
        assert_eq!(f.len, expected.len());
        assert_eq!(f.finish(), (expected.len(), Some(Some(Micros(5)))));
        assert!(!f.active());
    }

    #[test]
    fn a_binary_snapshot_gets_its_count_at_its_offset() {
        let mut bytes: Vec<u8> = (0..64).collect();
        bytes[32..40].copy_from_slice(&0u64.to_le_bytes());
        let enc = Arc::new(EncodedSnapshot {
            format: Format::Binary,
            bytes: bytes.clone(),
            dropped_at: protocol::BINARY_DROPPED_OFFSET,
            input_t: None,
        });
        let mut f = Frame::default();
        f.load(Item::Snapshot(enc), 1, 300);
        let mut expected = Vec::new();
        let mut notice = Vec::new();
        protocol::encode_dropped(1, 300, &mut notice);
        protocol::frame_json(&notice, &mut expected);
        bytes[32..40].copy_from_slice(&300u64.to_le_bytes());
        expected.extend_from_slice(&bytes);
        assert_eq!(written(&mut f, 5), expected);
    }

    #[test]
    fn json_messages_are_framed_as_the_stream_is() {
        let json: Arc<[u8]> = Arc::from(&b"{\"type\":\"ack\",\"id\":1}\n"[..]);
        let mut f = Frame::default();
        f.load(
            Item::Message {
                json: Arc::clone(&json),
                framing: Format::Json,
            },
            0,
            0,
        );
        assert_eq!(written(&mut f, 4), json.to_vec());
        f.load(
            Item::Message {
                json: Arc::clone(&json),
                framing: Format::Binary,
            },
            0,
            0,
        );
        let mut expected = Vec::new();
        protocol::frame_json(&json, &mut expected);
        assert_eq!(written(&mut f, 2), expected);
    }

    #[test]
    fn partial_sends_resume_where_they_stopped() {
        // A real socket whose buffer fills: write until WouldBlock, read some, go on.
        let (a, mut b) = UnixStream::pair().unwrap();
        a.set_nonblocking(true).unwrap();
        let big: Vec<u8> = (0..4_000_000u32).map(|i| (i % 251) as u8).collect();
        let mut line = big.clone();
        line.push(b'\n');
        let json: Arc<[u8]> = line.clone().into();
        let mut f = Frame::default();
        f.load(
            Item::Message {
                json,
                framing: Format::Json,
            },
            0,
            0,
        );
        let mut got = Vec::new();
        let mut buf = vec![0u8; 100_000];
        while f.active() {
            match f.send(&a) {
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    let n = b.read(&mut buf).unwrap();
                    got.extend_from_slice(&buf[..n]);
                }
                Err(e) => panic!("{e}"),
            }
        }
        drop(a);
        b.read_to_end(&mut got).unwrap();
        assert_eq!(got.len(), line.len());
        assert!(got == line, "the bytes arrive whole and in order");
    }
}
