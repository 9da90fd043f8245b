#![no_main]
//! Arbitrary datagrams through the TUIO input's flood gate and decoder. Byte 0
//! picks the sender's port, the time step and the limits (sessions per frame,
//! senders, datagrams a second); the rest is a sequence of `len: u16 (LE),
//! bytes[len]` datagrams. Checks the frames' life cycle (every contact begins
//! once, moves only while down, ends once), that no frame holds more sessions down
//! than the limit nor the decoder more senders, and that nothing is left down after
//! cancel_all.
use crowdtouch::input::tuio::{Admit, FloodGate, TuioCounters, TuioDecoder, TuioLimits};
use crowdtouch::vocab::{ContactFlags, Micros, TouchFrame, MAX_CONTACTS};
use libfuzzer_sys::fuzz_target;
use std::collections::HashSet;
use std::net::SocketAddr;
use std::sync::Arc;

struct Check {
    down: HashSet<u32>,
    sessions_per_frame: usize,
}

impl crowdtouch::input::FrameSink for Check {
    fn push(&mut self, f: &TouchFrame) {
        assert!(f.len() <= MAX_CONTACTS);
        let held = f.contacts().iter().filter(|c| !c.flags.ended()).count();
        assert!(held <= self.sessions_per_frame, "{held} sessions in a frame");
        for c in f.contacts() {
            assert!((0.0..=1.0).contains(&c.x) && (0.0..=1.0).contains(&c.y));
            if c.flags.contains(ContactFlags::DOWN) {
                assert!(self.down.insert(c.id.0), "DOWN twice");
            } else {
                assert!(self.down.contains(&c.id.0), "contact without DOWN");
            }
            if c.flags.ended() {
                self.down.remove(&c.id.0);
            }
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, mut rest)) = data.split_first() else {
        return;
    };
    let limits = TuioLimits {
        sessions_per_frame: 1 + usize::from(mode.rotate_left(3)) % MAX_CONTACTS,
        senders: 1 + usize::from(mode >> 6),
        packets_per_s: 10 + u32::from(mode),
    };
    let mut dec =
        TuioDecoder::with_limits(limits, Micros(1_000), Arc::new(TuioCounters::default()));
    let mut gate = FloodGate::new(limits.packets_per_s, limits.senders);
    let mut sink = Check {
        down: HashSet::new(),
        sessions_per_frame: limits.sessions_per_frame,
    };
    let mut t = 0u64;
    let mut k = 0u16;
    while rest.len() >= 2 {
        let len = usize::from(u16::from_le_bytes([rest[0], rest[1]])).min(rest.len() - 2);
        let packet = &rest[2..2 + len];
        rest = &rest[2 + len..];
        k = k.wrapping_add(1);
        let peer = SocketAddr::from(([127, 0, 0, 1], 4000 + (k % (1 + u16::from(mode & 3)))));
        t += u64::from(mode >> 2) * 50;
        if gate.admit(peer, Micros(t)) == Admit::Take {
            let _ = dec.packet(packet, peer, Micros(t), &mut sink);
        }
        assert!(dec.senders() <= limits.senders);
        dec.expire(Micros(t), &mut sink);
    }
    dec.cancel_all(Micros(t + 1), &mut sink);
    assert!(sink.down.is_empty(), "contacts left down after cancel_all");
    assert_eq!(dec.active_contacts(), 0);
});
