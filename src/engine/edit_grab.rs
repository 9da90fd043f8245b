//! The edit mode's fingers (see `edit.rs`): a touch on a person, the group a
//! control grabs at the play time, the drags sent to the formation thread one at a
//! time with the newest finger positions, and the release when the fingers lift.

use super::edit_jobs::{nearest_node, shown_position};
use super::edit_state::{EditJob, EditJobKind, Grab, GROUP_LINK_M, LOOP_REST_S};
use super::state::Engine;
use crate::crowd::edit::SampleRef;
use crate::geom::Vec2;
use crate::gesture::segment::Segment;
use crate::vocab::Micros;
use std::sync::Arc;

impl Engine {
    /// Whether a touch at `p` lands on a person (edit mode).
    pub(super) fn edit_hits(&self, p: Vec2) -> bool {
        let Some(m) = &self.edits.mode else {
            return false;
        };
        let r2 = self.grab_radius_m * self.grab_radius_m;
        m.set
            .tracks
            .iter()
            .any(|t| (shown_position(t, m.play_t_s).0 - p).norm_squared() <= r2)
    }

    /// Slow edit work for the formation thread; run it with [`EditJob::run`] and
    /// hand the result to [`apply_edit`](Self::apply_edit).
    pub fn take_edit_job(&mut self) -> Option<EditJob> {
        self.edits.outbox.take()
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

    /// Grabs on a control's landing, drags as its fingers move, the release when it
    /// lifts.
    fn edit_controls(&mut self, _now: Micros) {
        // In order: a control may land and lift within one tick.
        for k in 0..self.seg_out.len() {
            match self.seg_out[k] {
                Segment::ControlBegin(id) => {
                    let holding = self
                        .edits
                        .mode
                        .as_ref()
                        .is_some_and(|m| m.grab.is_some() || m.settling);
                    if !holding {
                        self.edit_grab(id);
                    }
                }
                Segment::ControlEnd { id, .. } => {
                    if let Some(g) = self
                        .edits
                        .mode
                        .as_mut()
                        .and_then(|m| m.grab.as_mut())
                        .filter(|g| g.control == id)
                    {
                        g.released = true;
                    }
                }
                _ => {}
            }
        }
        self.edit_send_drag();
        self.edit_try_release();
    }

    /// The people of the touched person's group at the play time, every sample of
    /// their tracks selected; each finger holds its nearest person's sample nearest
    /// the play time.
    fn edit_grab(&mut self, control: u32) {
        let Some(c) = self.segmenter.controls().iter().find(|c| c.id == control) else {
            return;
        };
        let fingers: Vec<(u64, Vec2)> = c
            .fingers
            .iter()
            .filter(|f| f.down)
            .map(|f| (u64::from(f.id.0), f.world_down))
            .collect();
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        let t = m.play_t_s;
        let shown: Vec<(Vec2, bool)> = m
            .set
            .tracks
            .iter()
            .map(|tr| shown_position(tr, t))
            .collect();
        let mut handles = Vec::with_capacity(fingers.len());
        let mut seeds = Vec::new();
        for &(fid, p) in &fingers {
            let Some((k, _)) = shown
                .iter()
                .enumerate()
                .map(|(k, (q, _))| (k, (q - p).norm_squared()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
            else {
                return;
            };
            let j = nearest_node(&m.set.tracks[k], t);
            handles.push((
                fid,
                SampleRef {
                    track: k,
                    sample: j,
                },
                p,
            ));
            seeds.push(k);
        }
        // The group: people linked by being within GROUP_LINK_M of each other now
        // (those on the scene, found on a neighbour grid; one off it joins only as a
        // seed), joined by union–find.
        let b = &mut self.edits.buffers;
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
        let mut inside = vec![false; shown.len()];
        for &s in &seeds {
            let r = root(parent, s);
            inside[s] = true;
            for (k, f) in inside.iter_mut().enumerate() {
                if root(parent, k) == r {
                    *f = true;
                }
            }
        }
        let selected: Arc<[usize]> = (0..shown.len()).filter(|&i| inside[i]).collect();
        let held: Arc<[SampleRef]> = handles
            .iter()
            .map(|h: &(u64, SampleRef, Vec2)| h.1)
            .collect();
        self.edits.next_grab += 1;
        let hull = Vec::new();
        m.hull = hull;
        m.grab = Some(Grab {
            id: self.edits.next_grab,
            control,
            base: Arc::clone(&m.set),
            selected,
            handles,
            cage: None,
            out: false,
            sent: Vec::new(),
            latest: Vec::new(),
            held,
            spare: Vec::new(),
            edited: None,
            released: false,
        });
        self.edits.view_dirty = true;
    }

    /// Sends the newest finger positions when no drag is out and they moved (after
    /// a lift, the positions the fingers had when they lifted).
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
            for &(fid, s, down) in &g.handles {
                let now_at = control
                    .fingers
                    .iter()
                    .find(|f| u64::from(f.id.0) == fid)
                    .map_or(down, |f| f.world);
                g.latest
                    .push(g.base.tracks[s.track].points[s.sample] + (now_at - down));
            }
        }
        let moved = g.sent.len() != g.latest.len()
            || g.sent
                .iter()
                .zip(&g.latest)
                .any(|(a, b)| (a - b).norm() > 1e-4);
        if g.out || !moved || g.latest.is_empty() {
            return;
        }
        g.out = true;
        g.sent.clone_from(&g.latest);
        let mut targets = std::mem::take(&mut g.spare);
        targets.clear();
        targets.extend_from_slice(&g.latest);
        self.edits.outbox = Some(EditJob {
            epoch,
            grab: g.id,
            kind: EditJobKind::Drag {
                base: Arc::clone(&g.base),
                selected: Arc::clone(&g.selected),
                cage: g.cage.take(),
                params,
                handles: Arc::clone(&g.held),
                targets,
                version,
                source,
            },
        });
    }

    /// After the fingers lift and the last drag is back: the release job.
    fn edit_try_release(&mut self) {
        let epoch = self.edits.epoch;
        let avoid = self.edits.avoid;
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        let ready = m
            .grab
            .as_ref()
            .is_some_and(|g| g.released && !g.out && g.sent == g.latest);
        if !ready || self.edits.outbox.is_some() {
            return;
        }
        let g = m.grab.take().expect("checked above");
        let Some(edited) = g.edited else {
            // A touch without a move: nothing changed.
            self.edits.view_dirty = true;
            return;
        };
        m.settling = true;
        Engine::push_undo(m, Arc::clone(&g.base));
        let (version, source) = (m.version + 1, Arc::clone(&m.source));
        self.edits.outbox = Some(EditJob {
            epoch,
            grab: g.id,
            kind: EditJobKind::Release {
                base: g.base,
                edited,
                selected: g.selected,
                avoid,
                version,
                source,
            },
        });
        self.edits.view_dirty = true;
    }
}

/// The root of `k` in the union–find forest `parent` (paths halved).
fn root(parent: &mut [usize], mut k: usize) -> usize {
    while parent[k] != k {
        parent[k] = parent[parent[k]];
        k = parent[k];
    }
    k
}
