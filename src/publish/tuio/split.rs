//! Datagram packing: one frame's OSC messages into bundles of at most
//! `max_bytes` each.
//!
//! Every message is encoded once by `rosc`, as a bundle element (its size, then the
//! message: `rosc::encoder::encode_into_tcp` writes exactly that), into one arena.
//! A bundle is rosc's bundle header (`#bundle`, the time tag) followed by elements,
//! so the bundles of one frame are made by concatenating encoded elements:
//!
//! ```text
//! datagram = #bundle ttag | heads… [alive] | items… (as many as fit) | [alive] tails…
//! ```
//!
//! Every bundle of a frame repeats the heads (TUIO 1.1 `source`, TUIO 2.0 `frm`),
//! the tails (`fseq`) and the full alive list, as the TUIO 1.1 reference server does
//! when a frame does not fit one packet; items (the `set`, `tok`, `ptr`, `bnd`
//! messages) are spread over as many bundles as needed.
//!
//! When the alive list itself would leave no room (more entities than one datagram
//! can name), the frame is cut to the first `k` items, `k` the most whose alive list
//! leaves room for [`MIN_ITEMS_PER_BUNDLE`] items beside it: alive and the items
//! sent always agree, and no datagram exceeds the bound. [`Packer::finish`] returns
//! how many items were left out, for the output to count and log.

use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
use std::ops::Range;

/// Items every bundle has room for beside the alive list; fewer, and the frame is
/// cut (see the module doc).
pub const MIN_ITEMS_PER_BUNDLE: usize = 4;

/// The datagrams of one frame, their buffers reused from frame to frame.
#[derive(Debug, Default)]
pub struct Datagrams {
    bufs: Vec<Vec<u8>>,
    len: usize,
}

impl Datagrams {
    /// Forgets the datagrams, keeping their buffers.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// How many datagrams there are.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The datagrams, in sending order.
    pub fn iter(&self) -> impl Iterator<Item = &[u8]> {
        self.bufs[..self.len].iter().map(Vec::as_slice)
    }

    /// Total bytes.
    pub fn bytes(&self) -> usize {
        self.iter().map(<[u8]>::len).sum()
    }

    fn next(&mut self) -> &mut Vec<u8> {
        if self.len == self.bufs.len() {
            self.bufs.push(Vec::new());
        }
        let b = &mut self.bufs[self.len];
        self.len += 1;
        b.clear();
        b
    }
}

/// Where the alive message goes in each bundle.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum AlivePlace {
    /// After the heads (TUIO 1.1: `source`, `alive`, sets…, `fseq`).
    EndOfHeads,
    /// Before the tails (TUIO 2.0: `frm`, components…, `alv`).
    StartOfTails,
}

/// The alive message: its address and leading word (`"alive"` in TUIO 1.1, none in
/// 2.0), followed by the session id of every item sent.
#[derive(Copy, Clone, Debug)]
pub struct Alive<'a> {
    /// OSC address.
    pub addr: &'a str,
    /// A string argument before the ids.
    pub word: Option<&'a str>,
    /// Where it goes.
    pub place: AlivePlace,
}

/// Packs one frame (or one TUIO 1.1 profile of a frame) into datagrams. Reused from
/// frame to frame.
#[derive(Debug, Default)]
pub struct Packer {
    arena: Vec<u8>,
    heads: Vec<Range<usize>>,
    items: Vec<(Range<usize>, i32)>,
    tails: Vec<Range<usize>>,
    alive_msg: Option<OscPacket>,
}

/// Bytes a bundle's header takes (`#bundle\0` and the time tag).
pub const BUNDLE_HEADER_BYTES: usize = 16;

fn pad4(n: usize) -> usize {
    (n + 3) & !3
}

/// Bytes the alive message takes as a bundle element (its size prefix included)
/// with `ids` session ids.
pub fn alive_element_bytes(addr: &str, word: Option<&str>, ids: usize) -> usize {
    let tags = 1 + usize::from(word.is_some()) + ids;
    4 + pad4(addr.len() + 1) + pad4(tags + 1) + word.map_or(0, |w| pad4(w.len() + 1)) + 4 * ids
}

impl Packer {
    /// Starts a new bundle set.
    pub fn reset(&mut self) {
        self.arena.clear();
        self.heads.clear();
        self.items.clear();
        self.tails.clear();
    }

    fn encode(&mut self, msg: &OscPacket) -> Range<usize> {
        let start = self.arena.len();
        // Writing into a Vec cannot fail.
        let _ = rosc::encoder::encode_into_tcp(msg, &mut self.arena);
        start..self.arena.len()
    }

    /// A message every bundle starts with.
    pub fn head(&mut self, msg: &OscPacket) {
        let r = self.encode(msg);
        self.heads.push(r);
    }

    /// A message every bundle ends with.
    pub fn tail(&mut self, msg: &OscPacket) {
        let r = self.encode(msg);
        self.tails.push(r);
    }

    /// One entity's message, with its session id for the alive list.
    pub fn item(&mut self, session: i32, msg: &OscPacket) {
        let r = self.encode(msg);
        self.items.push((r, session));
    }

    /// Packs everything added since [`Packer::reset`] into bundles of at most
    /// `max_bytes`, appended to `out`. Returns how many items were left out
    /// because the alive list of them all would not fit (see the module doc).
    pub fn finish(
        &mut self,
        max_bytes: usize,
        timetag: OscTime,
        alive: Alive<'_>,
        out: &mut Datagrams,
    ) -> usize {
        let len = |r: &Range<usize>| r.end - r.start;
        let fixed = BUNDLE_HEADER_BYTES
            + self.heads.iter().map(len).sum::<usize>()
            + self.tails.iter().map(len).sum::<usize>();
        let largest = self.items.iter().map(|(r, _)| len(r)).max().unwrap_or(0);
        let room = |k: usize| {
            fixed
                + alive_element_bytes(alive.addr, alive.word, k)
                + MIN_ITEMS_PER_BUNDLE.min(k) * largest
                <= max_bytes
        };
        // The most items whose alive list leaves room (room(k) is monotone in k).
        let n = self.items.len();
        let keep = if room(n) {
            n
        } else {
            let (mut lo, mut hi) = (0, n);
            while lo < hi {
                let mid = (lo + hi).div_ceil(2);
                if room(mid) {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
            lo
        };
        // The alive message, encoded once (its args reused from frame to frame).
        let packet = self.alive_msg.get_or_insert_with(|| {
            OscPacket::Message(OscMessage {
                addr: String::new(),
                args: Vec::new(),
            })
        });
        if let OscPacket::Message(msg) = packet {
            msg.addr.clear();
            msg.addr.push_str(alive.addr);
            msg.args.clear();
            if let Some(w) = alive.word {
                msg.args.push(OscType::String(w.to_string()));
            }
            msg.args
                .extend(self.items[..keep].iter().map(|&(_, s)| OscType::Int(s)));
        }
        let start = self.arena.len();
        let _ = rosc::encoder::encode_into_tcp(packet, &mut self.arena);
        let alive_r = start..self.arena.len();

        let mut header = Vec::with_capacity(BUNDLE_HEADER_BYTES);
        let _ = rosc::encoder::encode_into(
            &OscPacket::Bundle(OscBundle {
                timetag,
                content: Vec::new(),
            }),
            &mut header,
        );
        let arena = &self.arena;
        let open = |buf: &mut Vec<u8>| {
            buf.extend_from_slice(&header);
            for r in &self.heads {
                buf.extend_from_slice(&arena[r.clone()]);
            }
            if alive.place == AlivePlace::EndOfHeads {
                buf.extend_from_slice(&arena[alive_r.clone()]);
            }
        };
        let close = |buf: &mut Vec<u8>| {
            if alive.place == AlivePlace::StartOfTails {
                buf.extend_from_slice(&arena[alive_r.clone()]);
            }
            for r in &self.tails {
                buf.extend_from_slice(&arena[r.clone()]);
            }
        };
        let closing = self.tails.iter().map(len).sum::<usize>()
            + if alive.place == AlivePlace::StartOfTails {
                len(&alive_r)
            } else {
                0
            };
        let mut buf = out.next();
        open(buf);
        let mut in_bundle = 0;
        for (r, _) in &self.items[..keep] {
            if in_bundle > 0 && buf.len() + len(r) + closing > max_bytes {
                close(buf);
                buf = out.next();
                open(buf);
                in_bundle = 0;
            }
            buf.extend_from_slice(&arena[r.clone()]);
            in_bundle += 1;
        }
        close(buf);
        n - keep
    }
}

/// The arguments of a message packet, to overwrite in place (a template message is
/// filled for every entity without allocating); empty for a bundle.
pub fn args_mut(p: &mut OscPacket) -> &mut [OscType] {
    match p {
        OscPacket::Message(m) => &mut m.args,
        OscPacket::Bundle(_) => &mut [],
    }
}

/// A message packet to use as a template.
pub fn message(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.to_string(),
        args,
    })
}
