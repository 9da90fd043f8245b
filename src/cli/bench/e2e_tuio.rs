//! `bench e2e --tuio`'s UDP reader: counts the TUIO 1.1 output's datagrams and the
//! distinct frame numbers (`fseq`) they carry.

use crowdtouch::rt::monotonic_now;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// What the TUIO reader received.
#[derive(Default)]
pub struct TuioRead {
    pub datagrams: u64,
    pub bytes: u64,
    /// Distinct `fseq` frame numbers seen.
    pub frames: std::collections::HashSet<i32>,
    /// Datagrams that are not an OSC bundle holding an `fseq`.
    pub unreadable: u64,
    /// When the first and the last datagram arrived (µs, monotonic).
    first_us: u64,
    last_us: u64,
}

impl TuioRead {
    /// Seconds between the first datagram and the last.
    pub fn span_s(&self) -> f64 {
        (self.last_us.saturating_sub(self.first_us) as f64 / 1e6).max(1e-6)
    }
}

/// Reads datagrams on `socket` until `done`.
pub fn read_tuio(socket: UdpSocket, done: Arc<AtomicBool>) -> TuioRead {
    let mut out = TuioRead::default();
    let mut buf = vec![0u8; 65536];
    while !done.load(Ordering::Relaxed) {
        let Ok(n) = socket.recv(&mut buf) else {
            continue;
        };
        let now = monotonic_now().0;
        if out.datagrams == 0 {
            out.first_us = now;
        }
        out.last_us = now;
        out.datagrams += 1;
        out.bytes += n as u64;
        match bundle_fseq(&buf[..n]) {
            Some(f) => {
                out.frames.insert(f);
            }
            None => out.unreadable += 1,
        }
    }
    out
}

/// An OSC string at `at`: its bytes and the offset after its padding.
fn osc_str(b: &[u8], at: usize) -> Option<(&[u8], usize)> {
    let len = b.get(at..)?.iter().position(|&c| c == 0)?;
    Some((&b[at..at + len], at + (len + 4) / 4 * 4))
}

/// The frame number of a TUIO bundle: the int after `"fseq"` in the first
/// message whose arguments start with the string `fseq` (a small OSC walk over
/// the bundle's elements, not a full decoder). `None` for anything else.
fn bundle_fseq(b: &[u8]) -> Option<i32> {
    const HEAD: &[u8] = b"#bundle\0";
    if !b.starts_with(HEAD) {
        return None;
    }
    let mut at = HEAD.len() + 8;
    while at < b.len() {
        let size = u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize;
        let el = b.get(at + 4..(at + 4).checked_add(size)?)?;
        at += 4 + size;
        let Some((_addr, t)) = osc_str(el, 0) else {
            continue;
        };
        let Some((tags, a)) = osc_str(el, t) else {
            continue;
        };
        if !tags.starts_with(b",si") {
            continue;
        }
        let Some((first, i)) = osc_str(el, a) else {
            continue;
        };
        if first == b"fseq" {
            return Some(i32::from_be_bytes(el.get(i..i + 4)?.try_into().ok()?));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TUIO 1.1 bundle as the output sends it: `alive`, then `fseq`.
    fn bundle(fseq: i32) -> Vec<u8> {
        use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
        let msg = |args: Vec<OscType>| {
            OscPacket::Message(OscMessage {
                addr: "/tuio/2Dobj".into(),
                args,
            })
        };
        rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
            timetag: OscTime::from((0, 1)),
            content: vec![
                msg(vec![OscType::String("alive".into()), OscType::Int(3)]),
                msg(vec![OscType::String("fseq".into()), OscType::Int(fseq)]),
            ],
        }))
        .unwrap()
    }

    #[test]
    fn the_tuio_reader_finds_the_frame_number_and_refuses_the_rest() {
        assert_eq!(bundle_fseq(&bundle(4812)), Some(4812));
        let b = bundle(7);
        assert_eq!(bundle_fseq(&b[..b.len() - 2]), None);
        assert_eq!(bundle_fseq(b"/tuio/2Dobj\0,s\0\0fseq\0\0\0\0"), None);
    }

    proptest::proptest! {
        #[test]
        fn the_tuio_reader_never_panics(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..200), cut in 0usize..200) {
            let _ = bundle_fseq(&bytes);
            let mut b = bundle(1);
            b.truncate(cut.min(b.len()));
            b.extend_from_slice(&bytes);
            let _ = bundle_fseq(&b);
        }
    }
}
