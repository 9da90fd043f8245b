//! The publisher: what the control thread sends, queued for every client that wants
//! it. Runs on the output's thread; never touches a socket.
//!
//! A snapshot is encoded once per (format, field set) in use, outside every lock, and
//! the bytes are shared (`Arc`) by the clients' queues. A command's answer goes to
//! the client that asked, and only to it. Plans and a motion's life
//! (`gesture_motion`) go to clients subscribed to `plan` only; a formation transform's
//! progress and summary to clients subscribed to `transform` only; the edit mode's
//! tracks and state to clients subscribed to `edit` only.

use super::hub::Hub;
use super::queue::{ClientShared, EncodedSnapshot};
use super::stats::{lock, PublisherStats};
use crate::publish::protocol::{self, FieldSet, Format};
use crate::publish::Outgoing;
use crate::rt::monotonic_now;
use crate::vocab::{ClientId, Event, MeshView, ScenePoses, SceneView, Snapshot};
use serde_json::Value;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

/// A snapshot encoding, by (format, fields).
type EncodeKey = (Format, FieldSet);

/// The publisher's state between messages (its buffers keep their capacity).
pub(crate) struct Publisher {
    hub: Arc<Hub>,
    /// `socket.client_queue`.
    capacity: usize,
    /// The clients a message goes to (a copy of the hub's list).
    targets: Vec<Arc<ClientShared>>,
    /// Per target that takes the current snapshot, the encoding it takes.
    wanted: Vec<(usize, EncodeKey)>,
    /// The current snapshot's encodings.
    cache: Vec<(EncodeKey, Arc<EncodedSnapshot>)>,
    /// Scratch for `scene_poses` lines.
    poses: Vec<[f64; 3]>,
}

impl Publisher {
    /// A publisher for the hub's clients.
    pub fn new(hub: Arc<Hub>) -> Publisher {
        let capacity = hub.client_queue as usize;
        Publisher {
            hub,
            capacity,
            targets: Vec::new(),
            wanted: Vec::new(),
            cache: Vec::new(),
            poses: Vec::new(),
        }
    }

    /// Queues `msg` for the clients that want it (the caller then wakes the I/O
    /// thread).
    pub fn dispatch(&mut self, msg: Outgoing) {
        match msg {
            Outgoing::Snapshot(s) => self.snapshot(&s),
            Outgoing::Mesh(m) => self.mesh(m),
            Outgoing::Event(e) => {
                if let Event::Reset { agents, .. } = *e {
                    self.hub.agents.store(agents, Ordering::Relaxed);
                }
                // A motion's life goes with the plans it belongs to: a client that did
                // not ask for `plan` sees no message type it did not know.
                if matches!(*e, Event::GestureMotion { .. }) {
                    self.broadcast(|s| s.plan, |out| protocol::encode_event(&e, out));
                } else {
                    self.broadcast(|s| s.events, |out| protocol::encode_event(&e, out));
                }
            }
            Outgoing::Plan(p) => {
                self.broadcast(|s| s.plan, |out| protocol::encode_plan_json(&p, out))
            }
            Outgoing::Transform(t) => self.broadcast(
                |s| s.transform,
                |out| protocol::encode_transform_json(&t, out),
            ),
            Outgoing::TransformEnd(t) => self.broadcast(
                |s| s.transform,
                |out| protocol::encode_transform_end_json(&t, out),
            ),
            Outgoing::Tracks(t) => {
                let mut out = Vec::new();
                protocol::encode_tracks_json(&t, &mut out);
                let json: Arc<[u8]> = out.into();
                // Latest first, then the broadcast (as for `scene`).
                if t.full {
                    self.hub.set_latest_tracks(Arc::clone(&json));
                }
                self.broadcast(|s| s.edit, |o| o.extend_from_slice(&json));
            }
            Outgoing::Edit(e) => {
                let mut out = Vec::new();
                protocol::encode_edit_json(&e, &mut out);
                let json: Arc<[u8]> = out.into();
                self.hub
                    .set_latest_edit(Arc::clone(&json), e.state == "off");
                self.broadcast(|s| s.edit, |o| o.extend_from_slice(&json));
            }
            Outgoing::Scene(sc) => self.scene(&sc),
            Outgoing::ScenePoses(p) => self.poses(&p),
            Outgoing::Stats(r) => {
                self.broadcast(|s| s.stats, |out| protocol::encode_stats(&r, out));
                self.hub.set_latest_stats(r);
            }
            Outgoing::Reply { client, id, result } => self.reply(client, &id, result),
        }
    }

    fn load_targets(&mut self) {
        self.targets.clear();
        self.targets.extend(lock(&self.hub.clients).iter().cloned());
    }

    fn snapshot(&mut self, s: &Snapshot) {
        self.hub.agents.store(
            u32::try_from(s.agents.len()).unwrap_or(u32::MAX),
            Ordering::Relaxed,
        );
        self.load_targets();
        if self.targets.is_empty() {
            return;
        }
        let now = monotonic_now();
        let latency_us = s.input_t.map(|t| now.saturating_since(t).0);
        let stats = &self.hub.stats;
        // Who takes this snapshot, in which encoding.
        self.wanted.clear();
        for (i, c) in self.targets.iter().enumerate() {
            let mut q = c.lock();
            if !q.accepting() || !q.settings.subscriptions.snapshot {
                continue;
            }
            if let Some(period) = q.settings.min_interval_us() {
                if now.0 < q.rate_next_due_us {
                    stats.snapshots_rate_skipped.fetch_add(1, Ordering::Relaxed);
                    continue;
                }
                // Carry up to one period of lateness so jitter does not lower the rate.
                q.rate_next_due_us = q
                    .rate_next_due_us
                    .max(now.0.saturating_sub(period))
                    .saturating_add(period);
            }
            self.wanted
                .push((i, (q.settings.format, q.settings.fields)));
        }
        // Each encoding once, no lock held.
        self.cache.clear();
        for &(_, key) in &self.wanted {
            if !self.cache.iter().any(|(k, _)| *k == key) {
                self.cache
                    .push((key, Arc::new(encode(s, latency_us, key, stats))));
            }
        }
        for &(i, key) in &self.wanted {
            let Some((_, enc)) = self.cache.iter().find(|(k, _)| *k == key) else {
                continue;
            };
            let mut q = self.targets[i].lock();
            if !q.accepting() {
                continue;
            }
            let dropped = q.push_snapshot(Arc::clone(enc), self.capacity);
            drop(q);
            if dropped > 0 {
                stats
                    .snapshots_dropped
                    .fetch_add(dropped, Ordering::Relaxed);
            }
        }
        // The encodings live on in the queues that took them.
        self.cache.clear();
        self.targets.clear();
    }

    fn mesh(&mut self, m: Arc<MeshView>) {
        // Under the list's lock, so a client admitted meanwhile either is in the list
        // or has read this mesh as the latest (io.rs, `admit`).
        let clients = lock(&self.hub.clients);
        self.hub.set_latest_mesh(Arc::clone(&m));
        let mut with: Option<Arc<[u8]>> = None;
        let mut without: Option<Arc<[u8]>> = None;
        for c in clients.iter() {
            let mut q = c.lock();
            if !q.accepting() || !q.settings.subscriptions.mesh {
                continue;
            }
            let replaced_had_triangles = q.take_queued_mesh().unwrap_or(false);
            let tri = replaced_had_triangles || q.mesh_topology != Some(m.topology);
            q.mesh_topology = Some(m.topology);
            let slot = if tri { &mut with } else { &mut without };
            let json = Arc::clone(slot.get_or_insert_with(|| {
                let mut out = Vec::new();
                protocol::encode_mesh_json(&m, tri, &mut out);
                out.into()
            }));
            if let Err(o) = q.push_mesh(json, tri) {
                log::info!("client {}: {o}", c.id);
                q.fail(&o.to_string());
            }
        }
    }

    /// Poses replace a queued older one (a slow reader is not buried in them).
    fn poses(&mut self, p: &ScenePoses) {
        self.load_targets();
        let mut json: Option<Arc<[u8]>> = None;
        for c in &self.targets {
            let mut q = c.lock();
            if !q.accepting() || !q.settings.subscriptions.scene {
                continue;
            }
            let bytes = Arc::clone(json.get_or_insert_with(|| {
                let mut out = Vec::new();
                protocol::encode_scene_poses_json(p, &mut self.poses, &mut out);
                out.into()
            }));
            if let Err(o) = q.push_poses(bytes) {
                log::info!("client {}: {o}", c.id);
                q.fail(&o.to_string());
            }
        }
        self.targets.clear();
    }

    fn scene(&mut self, sc: &SceneView) {
        let mut out = Vec::new();
        protocol::encode_scene_json(sc, &mut out);
        let json: Arc<[u8]> = out.into();
        // Latest first, then the broadcast: a client subscribing meanwhile (under its
        // queue's lock, session.rs `hello`) reads this scene as the latest or is
        // subscribed when the broadcast reaches it (at worst it gets it twice).
        self.hub.set_latest_scene(Arc::clone(&json));
        self.broadcast(|s| s.scene, |o| o.extend_from_slice(&json));
    }

    /// Queues one JSON message, encoded at most once, for every client `wants` it.
    fn broadcast(
        &mut self,
        wants: impl Fn(&protocol::Subscriptions) -> bool,
        encode: impl FnOnce(&mut Vec<u8>),
    ) {
        self.load_targets();
        let mut encode = Some(encode);
        let mut json: Option<Arc<[u8]>> = None;
        for c in &self.targets {
            let mut q = c.lock();
            if !q.accepting() || !wants(&q.settings.subscriptions) {
                continue;
            }
            let bytes = match (&json, encode.take()) {
                (Some(j), _) => Arc::clone(j),
                (None, Some(f)) => {
                    let mut out = Vec::new();
                    f(&mut out);
                    let j: Arc<[u8]> = out.into();
                    json = Some(Arc::clone(&j));
                    j
                }
                (None, None) => continue,
            };
            let framing = q.settings.format;
            if let Err(o) = q.push_message(bytes, framing) {
                log::info!("client {}: {o}", c.id);
                q.fail(&o.to_string());
            }
        }
        self.targets.clear();
    }

    /// The control thread's answer to `client`'s command `id`: into that client's
    /// order of replies, nowhere else.
    fn reply(&mut self, client: ClientId, id: &Value, result: Result<(), String>) {
        let Some(c) = lock(&self.hub.clients)
            .iter()
            .find(|c| c.id == client)
            .cloned()
        else {
            return; // the client left before its answer came
        };
        let mut json = Vec::new();
        match result {
            Ok(()) => protocol::encode_ack(id, &mut json),
            Err(message) => protocol::encode_error(Some(id), &message, false, &mut json),
        }
        let mut q = c.lock();
        if q.accepting() {
            if let Err(o) = q.answer(id, json.into()) {
                log::info!("client {}: {o}", c.id);
                q.fail(&o.to_string());
            }
        }
    }
}

/// Encodes one snapshot for one (format, fields), timing it.
fn encode(
    s: &Snapshot,
    latency_us: Option<u64>,
    (format, fields): EncodeKey,
    stats: &PublisherStats,
) -> EncodedSnapshot {
    let t0 = Instant::now();
    let mut bytes = Vec::new();
    let dropped_at = match format {
        Format::Json => protocol::encode_snapshot_json_shared(s, latency_us, &fields, &mut bytes),
        Format::Binary => {
            protocol::encode_snapshot_binary(s, latency_us, 0, &fields, &mut bytes);
            protocol::BINARY_DROPPED_OFFSET
        }
    };
    let us = u64::try_from(t0.elapsed().as_micros()).unwrap_or(u64::MAX);
    stats.record_encode(us);
    EncodedSnapshot {
        format,
        bytes,
        dropped_at,
        input_t: s.input_t,
    }
}
