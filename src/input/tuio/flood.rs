//! The TUIO input's flood cap: a token bucket per peer address, so that one peer
//! sending too fast loses its own datagrams and nobody else's. Pure: given the peer
//! and `now`; no allocation after construction.
//!
//! Each peer (ip:port) followed has a bucket holding up to one second's worth of
//! datagrams ([`TuioLimits::packets_per_s`](super::TuioLimits)), refilled at that
//! rate; a datagram takes a token or is dropped. The table holds
//! [`PEERS_PER_SENDER`] places per sender followed. A new peer takes a free place,
//! or the place of the peer heard least recently when that one has been silent for
//! [`IDLE_US`] (its bucket would be full again, so forgetting it loses nothing).
//! When every place is taken by a peer heard within that second (a flood from many
//! ports), new peers share one more bucket of the same rate: a sender already
//! followed keeps its own bucket and its datagrams.

use crate::vocab::Micros;
use std::net::SocketAddr;

/// Datagrams a second taken from one peer unless the config says otherwise
/// (`max_packets_per_s`): a tracker sends one per camera frame, 30–120 a second.
pub const DEFAULT_MAX_PACKETS_PER_S: u32 = 4_000;

/// Places in the peer table per sender followed (a sender may send from several
/// ports, and a flooding peer takes a place too).
pub const PEERS_PER_SENDER: usize = 2;

/// A peer silent this long (µs) may lose its place: its bucket is full by then.
pub const IDLE_US: u64 = 1_000_000;

/// Tokens are counted in millionths of a datagram, so a bucket refills by exactly
/// `packets_per_s` units per microsecond.
const UNIT: u64 = 1_000_000;

#[derive(Copy, Clone, Debug, Default)]
struct Bucket {
    peer: Option<SocketAddr>,
    /// Millionths of a datagram.
    tokens: u64,
    refilled: Micros,
    heard: Micros,
}

impl Bucket {
    fn fresh(peer: Option<SocketAddr>, capacity: u64, now: Micros) -> Bucket {
        Bucket {
            peer,
            tokens: capacity,
            refilled: now,
            heard: now,
        }
    }

    /// Refills for the time since the last call, then takes one datagram's token.
    fn take(&mut self, rate: u64, capacity: u64, now: Micros) -> bool {
        let dt = now.saturating_since(self.refilled).0;
        self.tokens = self
            .tokens
            .saturating_add(dt.saturating_mul(rate))
            .min(capacity);
        self.refilled = now;
        self.heard = now;
        if self.tokens >= UNIT {
            self.tokens -= UNIT;
            true
        } else {
            false
        }
    }
}

/// Whether a datagram is taken, and from whom it was dropped.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Admit {
    /// Within its peer's rate.
    Take,
    /// Its peer (or, when the table was full, the peers sharing the spare bucket)
    /// sent more than the rate: dropped.
    Drop,
}

/// The token buckets of every peer; see the module doc.
#[derive(Debug)]
pub struct FloodGate {
    buckets: Box<[Bucket]>,
    /// Shared by the peers that found no place.
    spare: Bucket,
    rate: u64,
    capacity: u64,
}

impl FloodGate {
    /// A gate letting `packets_per_s` datagrams a second through from each peer
    /// (at least 1), with places for the peers of `senders` senders.
    pub fn new(packets_per_s: u32, senders: usize) -> FloodGate {
        let rate = u64::from(packets_per_s.max(1));
        let capacity = rate * UNIT;
        FloodGate {
            buckets: vec![Bucket::default(); senders.max(1) * PEERS_PER_SENDER].into_boxed_slice(),
            spare: Bucket::fresh(None, capacity, Micros::ZERO),
            rate,
            capacity,
        }
    }

    /// Whether a datagram from `peer` received at `now` is taken.
    pub fn admit(&mut self, peer: SocketAddr, now: Micros) -> Admit {
        let (rate, capacity) = (self.rate, self.capacity);
        let i = match self.buckets.iter().position(|b| b.peer == Some(peer)) {
            Some(i) => Some(i),
            None => {
                let place = self
                    .buckets
                    .iter()
                    .position(|b| b.peer.is_none())
                    .or_else(|| {
                        (0..self.buckets.len())
                            .min_by_key(|&i| self.buckets[i].heard)
                            .filter(|&i| now.saturating_since(self.buckets[i].heard).0 >= IDLE_US)
                    });
                if let Some(i) = place {
                    self.buckets[i] = Bucket::fresh(Some(peer), capacity, now);
                }
                place
            }
        };
        let bucket = match i {
            Some(i) => &mut self.buckets[i],
            None => &mut self.spare,
        };
        if bucket.take(rate, capacity, now) {
            Admit::Take
        } else {
            Admit::Drop
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peer(port: u16) -> SocketAddr {
        SocketAddr::from(([127, 0, 0, 1], port))
    }

    fn taken(g: &mut FloodGate, port: u16, n: u32, now: Micros) -> u32 {
        (0..n)
            .filter(|_| g.admit(peer(port), now) == Admit::Take)
            .count() as u32
    }

    #[test]
    fn a_peer_gets_one_second_s_worth_then_the_rate() {
        let mut g = FloodGate::new(100, 1);
        assert_eq!(taken(&mut g, 1, 150, Micros(0)), 100);
        // 10 ms later: one more datagram's worth.
        assert_eq!(taken(&mut g, 1, 5, Micros(10_000)), 1);
        // A second later the bucket is full again, not fuller.
        assert_eq!(taken(&mut g, 1, 150, Micros(2_000_000)), 100);
    }

    #[test]
    fn a_flooding_peer_does_not_use_up_another_s_tokens() {
        let mut g = FloodGate::new(100, 2);
        for ms in 0..2_000u64 {
            let now = Micros(ms * 1000);
            taken(&mut g, 1, 50, now);
            if ms % 16 == 0 {
                assert_eq!(g.admit(peer(2), now), Admit::Take, "at {ms} ms");
            }
        }
    }

    #[test]
    fn a_full_table_keeps_the_peers_it_has_and_shares_a_spare_bucket() {
        let mut g = FloodGate::new(10, 1);
        // Two places: peers 1 and 2.
        assert_eq!(taken(&mut g, 1, 1, Micros(0)), 1);
        assert_eq!(taken(&mut g, 2, 1, Micros(0)), 1);
        // Peers 3 and 4 share the spare bucket's 10 tokens.
        assert_eq!(
            taken(&mut g, 3, 8, Micros(1)) + taken(&mut g, 4, 8, Micros(1)),
            10
        );
        // Peer 1 still has its own bucket.
        assert_eq!(taken(&mut g, 1, 20, Micros(2)), 9);
        // Peer 2 silent for a second: its place goes to peer 5, which starts full.
        assert_eq!(taken(&mut g, 1, 1, Micros(1_000_002)), 1);
        assert_eq!(taken(&mut g, 5, 20, Micros(1_000_003)), 10);
    }
}
