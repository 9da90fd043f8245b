//! The output extension point: every consumer of what the control thread publishes.
//!
//! The control thread makes each message once ([`Outgoing`]: snapshots and meshes are
//! `Arc`s, so handing one to several outputs copies a pointer) and gives it to
//! [`Outputs::send`], which puts it on every output's own bounded queue without
//! blocking. Each output runs on a thread of its own ([`Output::run`]), reads its
//! queue, and does its I/O there; a slow or stalled output fills only its own queue,
//! and what it loses is decided by its [`QueuePolicy`].
//!
//! ```text
//!                          ┌─ bounded queue (policy) ─► socket output thread ─► clients
//!  control thread ─send──► ┤
//!                          └─ bounded queue (policy) ─► next output thread ─► ...
//! ```
//!
//! Adding an output is one module implementing [`Output`], one config entry that
//! builds it, and one [`OutputSet::add`] in `pipeline` (ARCHITECTURE.md shows it).

use super::Outgoing;
use crate::vocab::{CommandRequest, OutputCounters};
use crossbeam_channel::{bounded, Receiver, Sender, TrySendError};
use hdrhistogram::Histogram;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;

/// What happens to a message that finds an output's queue full.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Overflow {
    /// The new message is dropped ([`Outputs::send`] says so). For outputs that keep their own
    /// per-client queues and drop policy behind a large queue (the socket): the queue
    /// only fills when the output's thread itself has stalled.
    DropNewest,
    /// The oldest queued message is dropped to make room ([`Outputs::send`] says so). For outputs
    /// that only care about the newest state (a UDP stream of frames).
    DropOldest,
}

/// An output's queue: how many messages it holds and what is dropped when full.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct QueuePolicy {
    /// Messages the queue holds.
    pub capacity: usize,
    /// What a full queue drops.
    pub overflow: Overflow,
}

/// What an output reports to the daemon's `stats` (read by the supervisor thread).
pub trait OutputStats: Send + Sync {
    /// Clients connected now.
    fn clients(&self) -> u32;
    /// Snapshots dropped for slow clients since start.
    fn snapshots_dropped(&self) -> u64;
    /// End-to-end latency (input timestamp → bytes written, µs) since the last call;
    /// resets it.
    fn take_end_to_end(&self) -> Histogram<u64>;
    /// Serialisation time per snapshot encoding (µs) since the last call; resets it.
    fn take_encode(&self) -> Histogram<u64>;
    /// The output's own counters for `stats` (`outputs`), if it has any.
    fn counters(&self) -> Option<OutputCounters> {
        None
    }
}

/// Most clients an output admits at once, changeable while it runs: the output
/// reads it at each new connection, the daemon sets it on a config reload. Lowering
/// it refuses new clients until fewer are connected; none is disconnected.
#[derive(Clone, Debug)]
pub struct ClientLimit(Arc<AtomicU32>);

impl ClientLimit {
    /// A limit of `max` clients.
    pub fn new(max: u32) -> ClientLimit {
        ClientLimit(Arc::new(AtomicU32::new(max)))
    }

    /// The limit now.
    pub fn get(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }

    /// Changes the limit for the connections that come next.
    pub fn set(&self, max: u32) {
        self.0.store(max, Ordering::Relaxed)
    }
}

/// What an output's thread is given.
pub struct OutputContext {
    /// The output's queue.
    pub messages: Receiver<Outgoing>,
    /// Commands from its clients to the control thread (bounded: `try_send`, and
    /// answer "busy" when full; replies come back as [`Outgoing::Reply`]).
    pub commands: Sender<CommandRequest>,
    /// Set when the daemon stops; the output says goodbye to its clients and returns.
    pub stop: Arc<AtomicBool>,
}

/// One output: a consumer of what the control thread publishes.
pub trait Output: Send {
    /// Short name, for its thread (`ct-<name>`) and log lines.
    fn name(&self) -> &'static str;
    /// Its queue's size and drop policy.
    fn queue(&self) -> QueuePolicy;
    /// Which messages go on its queue at all (the default: every one). An output
    /// that uses only some kinds says so, so that the others never take room in its
    /// queue (nor, with [`Overflow::DropOldest`], push out a message it wants).
    fn wants(&self) -> fn(&Outgoing) -> bool {
        every_message
    }
    /// Its counters, shared with the stats reporter.
    fn stats(&self) -> Arc<dyn OutputStats>;
    /// Its client limit, shared with the daemon so a reload can change it
    /// (`socket.max_clients`); `None` for an output without clients.
    fn client_limit(&self) -> Option<ClientLimit> {
        None
    }
    /// The output's thread body: consumes `ctx.messages` until `ctx.stop` is set or
    /// the queue disconnects. Never blocks the control thread.
    fn run(self: Box<Self>, ctx: OutputContext);
}

/// [`Output::wants`]'s default.
pub fn every_message(_: &Outgoing) -> bool {
    true
}

/// An output with the receiving end of its queue, ready for its thread.
pub type Connected = (Box<dyn Output>, Receiver<Outgoing>);

/// The outputs a daemon runs, before they are connected.
#[derive(Default)]
pub struct OutputSet {
    outputs: Vec<Box<dyn Output>>,
}

impl OutputSet {
    /// Registers an output.
    pub fn add(&mut self, output: Box<dyn Output>) {
        self.outputs.push(output);
    }

    /// Every registered output's counters.
    pub fn stats(&self) -> Vec<Arc<dyn OutputStats>> {
        self.outputs.iter().map(|o| o.stats()).collect()
    }

    /// Every registered output's client limit (outputs with clients only).
    pub fn client_limits(&self) -> Vec<ClientLimit> {
        self.outputs
            .iter()
            .filter_map(|o| o.client_limit())
            .collect()
    }

    /// Makes every output's queue: the control side ([`Outputs`]) and each output
    /// with the receiving end of its queue.
    pub fn connect(self) -> (Outputs, Vec<Connected>) {
        let mut queues = Vec::with_capacity(self.outputs.len());
        let mut running = Vec::with_capacity(self.outputs.len());
        for o in self.outputs {
            let policy = o.queue();
            // Output queue: bounded(policy.capacity); the control thread, the
            // supervisor and input threads only try_send (Outputs::send); the output's
            // thread blocks on its own end. A full queue drops by policy.overflow.
            let (tx, rx) = bounded::<Outgoing>(policy.capacity.max(1));
            queues.push(OutputQueue {
                wants: o.wants(),
                tx,
                oldest: (policy.overflow == Overflow::DropOldest).then(|| rx.clone()),
            });
            running.push((o, rx));
        }
        (
            Outputs {
                queues: queues.into(),
            },
            running,
        )
    }
}

struct OutputQueue {
    /// Which messages the output takes ([`Output::wants`]).
    wants: fn(&Outgoing) -> bool,
    tx: Sender<Outgoing>,
    /// With [`Overflow::DropOldest`]: a receiving end to take the oldest message off.
    oldest: Option<Receiver<Outgoing>>,
}

/// The sending side of every output's queue. Cloned into every thread that publishes
/// (control, supervisor, device threads). Sending never blocks; snapshots, meshes,
/// events and stats are `Arc`s, so handing one to several outputs allocates nothing
/// (a command reply is copied per output).
#[derive(Clone)]
pub struct Outputs {
    queues: Arc<[OutputQueue]>,
}

impl Outputs {
    /// Hands `m` to every output's queue. Returns how many outputs dropped a message
    /// (this one or, for [`Overflow::DropOldest`], their oldest) because their queue
    /// was full.
    pub fn send(&self, m: Outgoing) -> usize {
        let mut dropped = 0;
        let Some((last, rest)) = self.queues.split_last() else {
            return 0;
        };
        for q in rest {
            if (q.wants)(&m) {
                dropped += usize::from(!q.push(m.clone()));
            }
        }
        if (last.wants)(&m) {
            dropped += usize::from(!last.push(m));
        }
        dropped
    }
}

impl OutputQueue {
    /// Queues `m`; false when something was dropped.
    fn push(&self, m: Outgoing) -> bool {
        match self.tx.try_send(m) {
            Ok(()) => true,
            Err(TrySendError::Disconnected(_)) => true,
            Err(TrySendError::Full(m)) => {
                if let Some(rx) = &self.oldest {
                    // Make room: the oldest goes, the newest is queued (another sender
                    // may take the room first; then this one is dropped too).
                    let _ = rx.try_recv();
                    let _ = self.tx.try_send(m);
                }
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{Snapshot, StatsReport};
    use hdrhistogram::Histogram;
    use std::sync::Mutex;

    /// An output that only records what its thread would see.
    struct Probe {
        name: &'static str,
        policy: QueuePolicy,
        wants: fn(&Outgoing) -> bool,
    }

    struct NoStats;

    impl OutputStats for NoStats {
        fn clients(&self) -> u32 {
            0
        }
        fn snapshots_dropped(&self) -> u64 {
            0
        }
        fn take_end_to_end(&self) -> Histogram<u64> {
            Histogram::new(3).expect("histogram")
        }
        fn take_encode(&self) -> Histogram<u64> {
            Histogram::new(3).expect("histogram")
        }
    }

    impl Output for Probe {
        fn name(&self) -> &'static str {
            self.name
        }
        fn queue(&self) -> QueuePolicy {
            self.policy
        }
        fn wants(&self) -> fn(&Outgoing) -> bool {
            self.wants
        }
        fn stats(&self) -> Arc<dyn OutputStats> {
            Arc::new(NoStats)
        }
        fn run(self: Box<Self>, _ctx: OutputContext) {}
    }

    fn snapshot(seq: u64) -> Outgoing {
        Outgoing::Snapshot(Arc::new(Snapshot {
            seq,
            ..Snapshot::default()
        }))
    }

    fn seqs(rx: &Receiver<Outgoing>) -> Vec<u64> {
        rx.try_iter()
            .map(|m| match m {
                Outgoing::Snapshot(s) => s.seq,
                _ => u64::MAX,
            })
            .collect()
    }

    fn set(policies: &[(&'static str, usize, Overflow)]) -> OutputSet {
        let mut s = OutputSet::default();
        for &(name, capacity, overflow) in policies {
            s.add(Box::new(Probe {
                name,
                policy: QueuePolicy { capacity, overflow },
                wants: every_message,
            }));
        }
        s
    }

    #[test]
    fn every_output_gets_every_message_and_shares_the_snapshot() {
        let (out, running) = set(&[
            ("a", 8, Overflow::DropNewest),
            ("b", 8, Overflow::DropOldest),
        ])
        .connect();
        let snap = Arc::new(Snapshot::default());
        assert_eq!(out.send(Outgoing::Snapshot(Arc::clone(&snap))), 0);
        // One allocation shared by the caller and both queues.
        assert_eq!(Arc::strong_count(&snap), 3);
        for (_, rx) in &running {
            assert_eq!(rx.len(), 1);
        }
    }

    #[test]
    fn a_full_queue_drops_by_its_own_policy_and_the_others_are_untouched() {
        let (out, running) = set(&[
            ("newest", 2, Overflow::DropNewest),
            ("oldest", 2, Overflow::DropOldest),
            ("roomy", 16, Overflow::DropNewest),
        ])
        .connect();
        let mut dropped = 0;
        for seq in 1..=5 {
            dropped += out.send(snapshot(seq));
        }
        // Three sends found two full queues each.
        assert_eq!(dropped, 6);
        assert_eq!(
            seqs(&running[0].1),
            vec![1, 2],
            "drop-newest keeps the first"
        );
        assert_eq!(
            seqs(&running[1].1),
            vec![4, 5],
            "drop-oldest keeps the last"
        );
        assert_eq!(seqs(&running[2].1), vec![1, 2, 3, 4, 5]);
    }

    #[test]
    fn a_gone_output_is_not_counted_as_dropping() {
        let (out, running) = set(&[("gone", 1, Overflow::DropNewest)]).connect();
        drop(running);
        assert_eq!(out.send(snapshot(1)), 0);
        assert_eq!(out.send(snapshot(2)), 0);
    }

    #[test]
    fn other_message_kinds_reach_every_output() {
        let (out, running) = set(&[
            ("a", 4, Overflow::DropNewest),
            ("b", 4, Overflow::DropNewest),
        ])
        .connect();
        let seen = Mutex::new(Vec::new());
        out.send(Outgoing::Stats(Arc::new(StatsReport::default())));
        out.send(Outgoing::Reply {
            client: 7,
            id: serde_json::json!(1),
            result: Ok(()),
        });
        for (o, rx) in &running {
            for m in rx.try_iter() {
                let kind = match m {
                    Outgoing::Stats(_) => "stats",
                    Outgoing::Reply { .. } => "reply",
                    _ => "other",
                };
                seen.lock().expect("lock").push((o.name(), kind));
            }
        }
        assert_eq!(
            seen.into_inner().expect("lock"),
            vec![
                ("a", "stats"),
                ("a", "reply"),
                ("b", "stats"),
                ("b", "reply")
            ]
        );
    }

    #[test]
    fn an_output_that_wants_snapshots_only_keeps_them_however_much_else_is_sent() {
        let mut s = OutputSet::default();
        s.add(Box::new(Probe {
            name: "frames",
            policy: QueuePolicy {
                capacity: 2,
                overflow: Overflow::DropOldest,
            },
            wants: |m| matches!(m, Outgoing::Snapshot(_)),
        }));
        let (out, running) = s.connect();
        assert_eq!(out.send(snapshot(1)), 0);
        for _ in 0..10 {
            assert_eq!(
                out.send(Outgoing::Stats(Arc::new(StatsReport::default()))),
                0
            );
        }
        assert_eq!(out.send(snapshot(2)), 0);
        assert_eq!(seqs(&running[0].1), vec![1, 2]);
    }
}
