//! The edit mode's fingers (see `edit.rs`): a touch on a person, the group (or
//! the selection) a control grabs at the play time, a touch on a hull vertex of
//! the last cage, a second control pinning points while a grab holds, controls
//! landing while a release settles (queued), the drags sent to the formation
//! thread one at a time with the newest finger positions, and the release when
//! the fingers lift.
//!
//! ```text
//!               control lands                      grab's control lifts
//!   idle ───────────────────────► grabbed ───────────────────────────► settling
//!    ▲  ▲ (preview: accepted first)  │ ▲ another control lands:         │
//!    │  │                            │ └─ pins its points (eq. 6)        │ result back
//!    │  └──── edit.accept / undo ── preview ◄────────── (edit.preview) ──┤
//!    └──────────────────────────────────────────── (no preview) ────────┘
//!   a control landing while settling is queued, and grabbed when the result is
//!   back if its fingers are still down
//! ```

use super::edit_jobs::{nearest_node, shown_position};
use super::edit_state::{
    EditJob, EditJobKind, EditMode, Grab, HoldSpec, GROUP_LINK_M, LOOP_REST_S, MAX_QUEUED_CONTROLS,
};
use super::state::Engine;
use crate::crowd::edit::SampleRef;
use crate::geom::Vec2;
use crate::gesture::segment::Segment;
use crate::vocab::Micros;
use std::sync::Arc;

impl Engine {
    /// Whether a touch at `p` lands on a person, or on a vertex of the hull shown
    /// (edit mode).
    pub(super) fn edit_hits(&self, p: Vec2) -> bool {
        let Some(m) = &self.edits.mode else {
            return false;
        };
        let r2 = self.grab_radius_m * self.grab_radius_m;
        near_vertex(m, p, r2).is_some()
            || m.set
                .tracks
                .iter()
                .any(|t| (shown_position(t, m.play_t_s).0 - p).norm_squared() <= r2)
    }

    /// Slow edit work for the formation thread; run it with [`EditJob::run`] and
    /// hand the result to [`apply_edit`](Self::apply_edit).
    pub fn take_edit_job(&mut self) -> Option<EditJob> {
        self.edits.outbox.pop_front()
    }

    /// One tick of edit mode (instead of the crowd's step): the playback clock, the
    /// fingers' grab and its jobs. Returns false when not editing.
    pub(super) fn step_edit(&mut self, dt: f64, now: Micros, inline: bool) -> bool {
        if self.edits.mode.is_none() {
            return false;
        }
        let paused = self.paused;
        {
            let m = self.edits.mode.as_mut().expect("checked above");
            let (t0, t1) = m.set.span_s();
            if !paused && m.grab.is_none() {
                m.play_t_s += dt;
                if m.play_t_s > t1 + LOOP_REST_S {
                    m.play_t_s = t0;
                }
            }
        }
        self.edit_controls(now);
        if inline {
            while let Some(job) = self.take_edit_job() {
                let done = job.run();
                self.apply_edit(done, now);
            }
        }
        true
    }

    /// Grabs on a control's landing (pins while a grab holds, queued while a
    /// release settles), drags as its fingers move, the release when it lifts.
    fn edit_controls(&mut self, _now: Micros) {
        // In order: a control may land and lift within one tick.
        for k in 0..self.seg_out.len() {
            match self.seg_out[k] {
                Segment::ControlBegin(id) => {
                    let Some(m) = self.edits.mode.as_mut() else {
                        return;
                    };
                    let holding = m.grab.as_ref().map(|g| g.released);
                    match holding {
                        Some(false) => self.edit_pin(id),
                        Some(true) => queue(m, id),
                        None if m.settling => queue(m, id),
                        None => {
                            self.edit_grab(id, false);
                        }
                    }
                }
                Segment::ControlEnd { id, .. } => {
                    if let Some(m) = self.edits.mode.as_mut() {
                        m.queued.retain(|&q| q != id);
                        if let Some(g) = m.grab.as_mut().filter(|g| g.control == id) {
                            g.released = true;
                        }
                    }
                }
                _ => {}
            }
        }
        self.edit_send_drag();
        self.edit_try_release();
    }

    /// After a release or retime came back: the first queued control whose
    /// fingers are still down grabs (the others are forgotten).
    pub(super) fn edit_grab_queued(&mut self) {
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        if m.settling || m.grab.is_some() {
            return;
        }
        let queued = std::mem::take(&mut m.queued);
        for id in queued {
            let down = self
                .segmenter
                .controls()
                .iter()
                .any(|c| c.id == id && c.fingers.iter().any(|f| f.down));
            if down && self.edit_grab(id, true) {
                break;
            }
        }
    }

    /// Grabs what control `control` landed on: a vertex of the hull shown (its
    /// cage's people, by that vertex), else the touched person's selection (when
    /// the person is selected: the selection's samples in its window) or group at
    /// the play time (every sample of its people). Each finger holds a hull vertex
    /// it is on, or its nearest grabbed person's sample nearest the play time.
    /// `from_now`: the fingers hold from where they are now (a queued control),
    /// not from where they landed. A preview shown is accepted first. Returns
    /// whether something was grabbed.
    pub(super) fn edit_grab(&mut self, control: u32, from_now: bool) -> bool {
        let Some(c) = self.segmenter.controls().iter().find(|c| c.id == control) else {
            return false;
        };
        let fingers: Vec<(u64, Vec2)> = c
            .fingers
            .iter()
            .filter(|f| f.down)
            .map(|f| {
                let at = if from_now { f.world } else { f.world_down };
                (u64::from(f.id.0), at)
            })
            .collect();
        let r2 = self.grab_radius_m * self.grab_radius_m;
        let Some(m) = self.edits.mode.as_mut() else {
            return false;
        };
        if fingers.is_empty() {
            return false;
        }
        let t = m.play_t_s;
        let shown: Vec<(Vec2, bool)> = m
            .set
            .tracks
            .iter()
            .map(|tr| shown_position(tr, t))
            .collect();
        let nearest = |p: Vec2, among: Option<&[usize]>| {
            let d2 = |k: usize| (shown[k].0 - p).norm_squared();
            match among {
                Some(ks) => ks.iter().copied().min_by(|&a, &b| d2(a).total_cmp(&d2(b))),
                None => (0..shown.len()).min_by(|&a, &b| d2(a).total_cmp(&d2(b))),
            }
        };
        // A finger is on a vertex when one is within reach and nearer than anyone.
        let vertex_d2 = |p: Vec2| {
            near_vertex(m, p, r2)?;
            let d2 = m
                .hull
                .iter()
                .map(|v| (v - p).norm_squared())
                .fold(f64::INFINITY, f64::min);
            let person =
                nearest(p, None).map_or(f64::INFINITY, |k| (shown[k].0 - p).norm_squared());
            (d2 < person).then_some(d2)
        };
        let on_vertex = fingers.iter().any(|&(_, p)| vertex_d2(p).is_some());
        let (selected, window_s): (Arc<[usize]>, Option<(f64, f64)>) = if on_vertex {
            m.hull_of.clone().expect("near_vertex checked it")
        } else {
            let Some(k) = nearest(fingers[0].1, None) else {
                return false;
            };
            match m
                .selection
                .as_ref()
                .filter(|s| s.tracks.binary_search(&k).is_ok())
            {
                Some(s) => (Arc::clone(&s.tracks), s.window_s),
                None => {
                    let seeds: Vec<usize> = fingers
                        .iter()
                        .filter_map(|&(_, p)| nearest(p, None))
                        .collect();
                    (group_of(&mut self.edits.buffers, &shown, &seeds), None)
                }
            }
        };
        let mut held = Vec::with_capacity(fingers.len());
        for &(_, p) in &fingers {
            let spec = match vertex_d2(p).filter(|_| on_vertex) {
                Some(_) => HoldSpec::NearVertex(p),
                None => {
                    let Some(k) = nearest(p, Some(&selected)) else {
                        return false;
                    };
                    HoldSpec::Sample(sample_in_window(m, k, window_s))
                }
            };
            held.push(spec);
        }
        if m.preview.take().is_some() {
            // A new grab keeps what the preview shows (edit.undo drops it).
            self.edits.edits += 1;
        }
        self.edits.next_grab += 1;
        if !on_vertex {
            m.hull.clear();
        }
        m.grab = Some(Grab {
            id: self.edits.next_grab,
            control,
            base: Arc::clone(&m.set),
            selected,
            window_s,
            fingers,
            cage: None,
            out: false,
            sent: Vec::new(),
            latest: Vec::new(),
            held: held.into(),
            pins: Arc::from([]),
            pins_sent: 0,
            handles_at: Vec::new(),
            pins_at: Vec::new(),
            spare: Vec::new(),
            edited: None,
            released: false,
        });
        self.edits.view_dirty = true;
        true
    }

    /// A second control landed while a grab holds: each of its fingers on a hull
    /// vertex of the grab's cage, or on a person of the grab, pins that point
    /// (eq. 6: held where it was before the grab) for the rest of the grab.
    /// Fingers on nothing of the grab pin nothing.
    fn edit_pin(&mut self, control: u32) {
        let Some(c) = self.segmenter.controls().iter().find(|c| c.id == control) else {
            return;
        };
        let r2 = self.grab_radius_m * self.grab_radius_m;
        let places: Vec<Vec2> = c
            .fingers
            .iter()
            .filter(|f| f.down)
            .map(|f| f.world)
            .collect();
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        let t = m.play_t_s;
        let Some(g) = m.grab.as_ref() else {
            return;
        };
        let mut pins: Vec<HoldSpec> = g.pins.to_vec();
        for p in places {
            // The nearer of the hull's vertices and the grab's people.
            let vertex = m
                .hull
                .iter()
                .map(|v| (v - p).norm_squared())
                .fold(f64::INFINITY, f64::min);
            let person = g
                .selected
                .iter()
                .copied()
                .map(|k| {
                    (
                        k,
                        (shown_position(&m.set.tracks[k], t).0 - p).norm_squared(),
                    )
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .filter(|&(_, d2)| d2 <= r2);
            let spec = match person {
                Some((k, d2)) if d2 <= vertex => {
                    HoldSpec::Sample(sample_in_window(m, k, g.window_s))
                }
                _ if vertex <= r2 => HoldSpec::NearVertex(p),
                _ => {
                    log::info!(
                        "edit: a second control landed on nothing of the grab; nothing pinned"
                    );
                    continue;
                }
            };
            if !pins.contains(&spec) && !g.held.contains(&spec) {
                pins.push(spec);
            }
        }
        if let Some(g) = m.grab.as_mut() {
            if pins.len() != g.pins.len() {
                g.pins = pins.into();
                self.edits.view_dirty = true;
            }
        }
    }

    /// Sends the newest finger displacements when no drag is out and they moved or
    /// a pin was added (after a lift, the displacements the fingers had when they
    /// lifted).
    fn edit_send_drag(&mut self) {
        let epoch = self.edits.epoch;
        let params = self.edits.cage;
        let controls = self.segmenter.controls();
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        let (version, source) = (m.version + 1, Arc::clone(&m.source));
        let Some(g) = m.grab.as_mut() else {
            return;
        };
        if let Some(control) = controls.iter().find(|c| c.id == g.control) {
            g.latest.clear();
            for &(fid, down) in &g.fingers {
                let now_at = control
                    .fingers
                    .iter()
                    .find(|f| u64::from(f.id.0) == fid)
                    .map_or(down, |f| f.world);
                g.latest.push(now_at - down);
            }
        }
        let moved = g.sent.len() != g.latest.len()
            || g.pins_sent != g.pins.len()
            || g.sent
                .iter()
                .zip(&g.latest)
                .any(|(a, b)| (a - b).norm() > STILL_M);
        if g.out || !moved || g.latest.is_empty() {
            return;
        }
        g.out = true;
        g.sent.clone_from(&g.latest);
        g.pins_sent = g.pins.len();
        let mut deltas = std::mem::take(&mut g.spare);
        deltas.clear();
        deltas.extend_from_slice(&g.latest);
        self.edits.outbox.push_back(EditJob {
            epoch,
            grab: g.id,
            kind: EditJobKind::Drag {
                base: Arc::clone(&g.base),
                selected: Arc::clone(&g.selected),
                window_s: g.window_s,
                cage: g.cage.take(),
                params,
                handles: Arc::clone(&g.held),
                deltas,
                pins: Arc::clone(&g.pins),
                version,
                source,
            },
        });
    }

    /// After the fingers lift and the last drag is back: the release job.
    fn edit_try_release(&mut self) {
        let epoch = self.edits.epoch;
        let avoid = self.edits.avoid;
        let obstacles = self.scene.clone();
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        let ready = m.grab.as_ref().is_some_and(|g| {
            g.released && !g.out && g.sent == g.latest && g.pins_sent == g.pins.len()
        });
        if !ready {
            return;
        }
        let g = m.grab.take().expect("checked above");
        m.hull_of = Some((Arc::clone(&g.selected), g.window_s));
        let still = g.sent.iter().all(|d| d.norm() <= STILL_M);
        let Some(edited) = g.edited.filter(|_| !still) else {
            // A touch without a move (pins alone hold points where they are):
            // nothing changed.
            self.edits.view_dirty = true;
            self.edit_grab_queued();
            return;
        };
        m.settling = true;
        Engine::push_undo(m, Arc::clone(&g.base));
        let (version, source) = (m.version + 1, Arc::clone(&m.source));
        self.edits.outbox.push_back(EditJob {
            epoch,
            grab: g.id,
            kind: EditJobKind::Release {
                base: g.base,
                edited,
                selected: g.selected,
                cage: g.cage,
                handles: g.held,
                deltas: g.sent,
                pins: g.pins,
                obstacles,
                avoid,
                version,
                source,
            },
        });
        self.edits.view_dirty = true;
    }
}

/// Fingers that moved less than this from where they landed did not drag (m).
const STILL_M: f64 = 1e-4;

/// Remembers a control that landed while a release settles.
fn queue(m: &mut EditMode, id: u32) {
    if m.queued.len() < MAX_QUEUED_CONTROLS {
        m.queued.push(id);
    } else {
        log::info!("edit: control {id} landed while {MAX_QUEUED_CONTROLS} others wait for a release; it grabs nothing");
    }
}

/// The index of a vertex of the hull shown within `r2` (squared m) of `p`: the
/// grab's cage while a grab holds, else the last grab's, when its people are
/// known (its cage can be built again).
fn near_vertex(m: &EditMode, p: Vec2, r2: f64) -> Option<usize> {
    if m.grab.is_none() {
        m.hull_of.as_ref()?;
    }
    m.hull.iter().position(|v| (v - p).norm_squared() <= r2)
}

/// Person `k`'s sample nearest the play time (within `window_s`, when given:
/// the sample must be in the grab's cage).
fn sample_in_window(m: &EditMode, k: usize, window_s: Option<(f64, f64)>) -> SampleRef {
    let t = window_s.map_or(m.play_t_s, |(a, b)| m.play_t_s.clamp(a, b));
    let tr = &m.set.tracks[k];
    let mut j = nearest_node(tr, t);
    if let Some((a, b)) = window_s {
        // The nearest node may lie just outside the window; step inside.
        if tr.times_s[j] < a && j + 1 < tr.len() {
            j += 1;
        } else if tr.times_s[j] > b && j > 0 {
            j -= 1;
        }
    }
    SampleRef {
        track: k,
        sample: j,
    }
}

/// The group of `seeds`: people linked by being within [`GROUP_LINK_M`] of each
/// other at the play time (those on the scene, found on a neighbour grid; one off
/// it joins only as a seed), joined by union–find. Track indices, ascending.
fn group_of(
    b: &mut super::edit_state::GrabBuffers,
    shown: &[(Vec2, bool)],
    seeds: &[usize],
) -> Arc<[usize]> {
    b.on_idx.clear();
    b.on_pos.clear();
    for (k, &(q, on)) in shown.iter().enumerate() {
        if on {
            b.on_idx.push(k);
            b.on_pos.push(q);
        }
    }
    b.parent.clear();
    b.parent.extend(0..shown.len());
    b.grid.build(&b.on_pos, GROUP_LINK_M);
    let (grid, on_idx, parent) = (&b.grid, &b.on_idx, &mut b.parent);
    grid.for_each_pair_d2(&b.on_pos, GROUP_LINK_M, |i, j, _, _| {
        let (ri, rj) = (root(parent, on_idx[i]), root(parent, on_idx[j]));
        if ri != rj {
            parent[ri.max(rj)] = ri.min(rj);
        }
    });
    let roots: Vec<usize> = seeds.iter().map(|&s| root(parent, s)).collect();
    (0..shown.len())
        .filter(|&k| seeds.contains(&k) || roots.contains(&root(parent, k)))
        .collect()
}

/// The root of `k` in the union–find forest `parent` (paths halved).
fn root(parent: &mut [usize], mut k: usize) -> usize {
    while parent[k] != k {
        parent[k] = parent[parent[k]];
        k = parent[k];
    }
    k
}
