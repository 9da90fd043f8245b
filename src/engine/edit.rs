//! The edit mode (crowd-motion-editing, Zhang et al. 2020): a track file is loaded
//! (`edit.load`, read on the formation thread), its people play as the crowd, and
//! fingers edit their tracks with the same point, line and area controls that
//! move the live crowd.
//!
//! ```text
//!  edit.load ──► file read (formation thread) ──► tracks installed, `tracks` (full)
//!  a control lands on a person ──► the group at the play time is grabbed:
//!      every sample of its people is the selection; each finger holds the
//!      sample of its person nearest the play time
//!  fingers move ──► EditJob::Drag: cage built once per grab (hull, mesh, MVC,
//!      section 3.2), solved for the fingers (eqs. 1–8) ──► `tracks` (changed
//!      people), `edit` (hull)
//!  a second control on the group or its hull ──► pins (eq. 6) for the grab
//!  a touch on a vertex of the last hull ──► that cage's people, by the vertex
//!  fingers lift ──► EditJob::Release: the group kept out of the scene's
//!      obstacles (section 4.2), speeds corrected (eq. 9), collisions avoided by
//!      retiming around the edited people (section 4.1.2) ──► a preview:
//!      `tracks` (full, preview), `edit` (state preview, what it did)
//!      ──► edit.accept keeps it; edit.undo (byte for byte) drops it; a new grab
//!      or retime keeps it
//!  edit.select, or a one-finger lasso in open space ──► EditJob::Select: the
//!      next grab on a selected person grabs the selection (its window)
//!  edit.retime (ids, the selection, or everyone), or a contract / expand
//!      gesture in open space (the selection, or everyone) ──► EditJob::Retime
//!  edit.undo / edit.save / edit.exit
//! ```
//!
//! The control thread never builds or solves a cage: jobs go to the formation
//! thread one at a time (the newest finger positions are sent when the last drag is
//! back; a grab's cage travels with its jobs), and results of an older grab or
//! load are dropped. In replays the jobs run in the tick.
//!
//! | file | what |
//! |---|---|
//! | `edit.rs` | the commands (`edit.load`, `.undo`, `.save`, `.retime`, `.exit`), the config's tracks, a gesture's retime, results of jobs applied, what is published |
//! | `edit_select.rs` | `edit.select`, the lasso drawn on the table, `edit.accept` |
//! | `edit_grab.rs` | fingers: touches on people or hull vertices, a group or selection grabbed, pins, queued touches, drags sent, the release |
//! | `edit_jobs.rs` | [`EditJob::run`]: the slow work (cage, drag, speeds, retiming, collisions), and the tracks' views |
//! | `edit_state.rs` | the state, the jobs and their results |

use super::edit_jobs::{shown_position, tracks_view, velocity_at};
use super::edit_state::{
    EditDone, EditDoneKind, EditFileJob, EditJob, EditJobKind, EditMode, HoldSpec, Settled,
    MAX_UNDO,
};
use super::error::CommandError;
use super::state::Engine;
use crate::crowd::edit::TrackSet;
use crate::geom::Vec2;
use crate::gesture::library::MotionClass;
use crate::vocab::{AgentView, EditView, Micros, SelectionView, TracksView};
use std::sync::Arc;

/// While fingers hold people, their `tracks` message goes out at most this often
/// (µs): a drag is solved faster than renderers need it, and each message carries
/// every sample of the held people.
pub const HELD_TRACKS_PERIOD_US: u64 = 100_000;

/// How far ahead of the play time a `contract` or `expand` gesture retimes (s).
pub const GESTURE_RETIME_S: f64 = 5.0;
/// A `contract` gesture plays that stretch in this fraction of its time (`expand`
/// in its inverse).
pub const GESTURE_FASTER: f64 = 0.8;

impl Engine {
    /// Whether the crowd is a loaded track set's people (edit mode).
    pub fn editing(&self) -> bool {
        self.edits.active()
    }

    /// Edits applied since start (releases and retimes).
    pub fn edits_applied(&self) -> u64 {
        self.edits.edits
    }

    /// The play time of the tracks being edited (s).
    pub fn edit_play_t_s(&self) -> Option<f64> {
        self.edits.mode.as_ref().map(|m| m.play_t_s)
    }

    /// The tracks being edited.
    pub fn edited_tracks(&self) -> Option<&Arc<TrackSet>> {
        self.edits.mode.as_ref().map(|m| &m.set)
    }

    /// The config's `edit` section: the threshold, and its tracks loaded when they
    /// are not the ones it loaded last (at start, or a reload that changed them).
    pub(super) fn configure_edit(&mut self, cfg: &crate::config::Config, now: Micros) {
        self.edits.dir = crate::config::EditConfig::resolved_dir(cfg.edit.as_ref()).map(Arc::from);
        self.edits.allow_overwrite = cfg.edit.as_ref().is_some_and(|e| e.allow_overwrite);
        self.edits.avoid.threshold_m = cfg
            .edit
            .as_ref()
            .map_or(super::edit_state::EDIT_THRESHOLD_M, |e| e.threshold_m);
        self.edits.avoid.preview = cfg.edit.as_ref().is_none_or(|e| e.preview);
        let tracks = cfg.loaded_tracks();
        let same = match (tracks, &self.edits.from_config) {
            (Some(a), Some(b)) => a == b,
            (None, None) => true,
            _ => false,
        };
        if same {
            return;
        }
        self.edits.from_config = tracks.cloned();
        if let (Some(set), Some(edit)) = (tracks, &cfg.edit) {
            let source = edit.tracks.display().to_string();
            self.edits.load_epoch += 1;
            self.load_tracks((**set).clone(), &source, now);
        }
    }

    /// The edit directory, or why `edit.load` and `edit.save` cannot be served.
    fn edit_dir(&self, command: &str) -> Result<Arc<std::path::Path>, CommandError> {
        self.edits.dir.clone().ok_or_else(|| {
            CommandError::Edit(format!(
                "{command}: the daemon has no edit directory (set `edit.dir` in its config)"
            ))
        })
    }

    /// `edit.load`: entry `entry` of the edit directory is read off the control
    /// thread ([`take_edit_file_job`](Self::take_edit_file_job)); the reader checks
    /// the name and refuses anything but a regular file.
    pub(super) fn edit_load(&mut self, entry: &str) -> Result<(), CommandError> {
        if entry.is_empty() {
            return Err(CommandError::Edit(
                "edit.load needs an `entry` (a file of the edit directory)".into(),
            ));
        }
        let dir = self.edit_dir("edit.load")?;
        // A newer load or an exit makes this one stale; the tracks being edited
        // go on until the file is read (a failed load leaves them as they are).
        self.edits.load_epoch += 1;
        self.edits.loading = Some(entry.to_string());
        self.edits.file_out = Some(EditFileJob::Load {
            dir,
            entry: entry.to_string(),
            epoch: self.edits.load_epoch,
        });
        Ok(())
    }

    /// A file job for the formation thread (`edit.load`, `edit.save`).
    pub fn take_edit_file_job(&mut self) -> Option<EditFileJob> {
        self.edits.file_out.take()
    }

    /// The current load epoch (a load asked before a newer one is stale).
    pub fn edit_epoch(&self) -> u64 {
        self.edits.load_epoch
    }

    /// A track file read for `edit.load` at `epoch`: installed unless a newer load
    /// or an `edit.exit` came since. Returns whether it was installed.
    pub fn apply_edit_load(&mut self, epoch: u64, set: TrackSet, entry: &str, now: Micros) -> bool {
        if epoch != self.edits.load_epoch {
            return false;
        }
        self.edits.loading = None;
        self.load_tracks(set, entry, now);
        self.edits.loaded_entry = Some(entry.to_string());
        true
    }

    /// A track file for `edit.load` at `epoch` could not be read: the daemon stays
    /// as it was (the client got the reason).
    pub fn edit_load_failed(&mut self, epoch: u64) {
        if epoch == self.edits.load_epoch && self.edits.loading.take().is_some() {
            self.edits.view_dirty = true;
        }
    }

    /// Enters edit mode with `set` (validated by the reader): the crowd's motion,
    /// gesture and transform stop, the people play from the set's first time.
    pub fn load_tracks(&mut self, set: TrackSet, source: &str, now: Micros) {
        self.segmenter.cancel_all(now, &mut self.seg_out);
        self.forget_switches();
        self.forget_gestures(now);
        self.drop_transforms(crate::vocab::TransformOutcome::Dropped, now);
        // Jobs for the tracks before are stale from here.
        self.edits.epoch += 1;
        self.edits.loaded_entry = None;
        let set = Arc::new(set);
        let (t0, _) = set.span_s();
        self.edits.mode = Some(Box::new(EditMode {
            set,
            source: Arc::from(source),
            version: 1,
            undo: Vec::new(),
            play_t_s: t0,
            grab: None,
            collisions: Vec::new(),
            settling: false,
            hull: Vec::new(),
            hull_of: None,
            selection: None,
            preview: None,
            queued: Vec::new(),
        }));
        self.edits.outbox.clear();
        self.check_collisions();
        self.publish_tracks();
        self.edits.view_dirty = true;
    }

    /// Asks the formation thread for the collisions of the tracks as they are (after
    /// a load or an undo; an edit's job reports its own).
    fn check_collisions(&mut self) {
        let epoch = self.edits.epoch;
        let threshold_m = self.edits.avoid.threshold_m;
        if let Some(m) = &self.edits.mode {
            self.edits.outbox.push_back(EditJob {
                epoch,
                grab: 0,
                kind: EditJobKind::Check {
                    set: Arc::clone(&m.set),
                    threshold_m,
                    version: m.version,
                },
            });
        }
    }

    /// `edit.undo`: the tracks before the last edit come back (the very tracks:
    /// an edit shown as a preview is dropped, byte for byte).
    pub(super) fn edit_undo(&mut self) -> Result<(), CommandError> {
        let m = self.edit_mode_mut()?;
        if m.grab.is_some() || m.settling {
            return Err(CommandError::Edit(
                "an edit is under way; undo when the fingers have lifted".into(),
            ));
        }
        let Some(prev) = m.undo.pop() else {
            return Err(CommandError::Edit("nothing to undo".into()));
        };
        m.set = prev;
        m.version += 1;
        m.preview = None;
        m.hull.clear();
        m.collisions.clear();
        self.check_collisions();
        self.publish_tracks();
        self.edits.view_dirty = true;
        Ok(())
    }

    /// `edit.save`: written off the control thread into entry `entry` of the edit
    /// directory; without an entry, back to the entry the tracks were loaded from.
    /// An existing entry is replaced only with `overwrite` and when the config's
    /// `edit.allow_overwrite` is on.
    pub(super) fn edit_save(
        &mut self,
        entry: Option<&str>,
        overwrite: bool,
    ) -> Result<(), CommandError> {
        if overwrite && !self.edits.allow_overwrite {
            return Err(CommandError::Edit(
                "edit.save may not replace a file: the daemon's `edit.allow_overwrite` is off"
                    .into(),
            ));
        }
        let dir = self.edit_dir("edit.save")?;
        let loaded = self.edits.loaded_entry.clone();
        let m = self.edit_mode_mut()?;
        if m.preview.is_some() {
            return Err(CommandError::Edit(
                "an edit is shown as a preview: edit.accept or edit.undo it before saving".into(),
            ));
        }
        let entry = match (entry, loaded) {
            (Some(e), _) if !e.is_empty() => e.to_string(),
            (_, Some(l)) if overwrite => l,
            (_, None) if overwrite => return Err(CommandError::Edit(
                "edit.save needs an `entry`: the tracks did not come from the edit directory"
                    .into(),
            )),
            _ => return Err(CommandError::Edit(
                "edit.save needs an `entry`, or `overwrite: true` to write back to the loaded entry"
                    .into(),
            )),
        };
        let set = Arc::clone(&m.set);
        self.edits.file_out = Some(EditFileJob::Save {
            set,
            dir,
            entry,
            overwrite,
        });
        Ok(())
    }

    /// `edit.retime`: a temporal edit of the people `ids` (else the selection's,
    /// else everyone), then collisions avoided around them. A preview shown is
    /// accepted first.
    pub(super) fn edit_retime(
        &mut self,
        at_s: f64,
        to_s: f64,
        ids: Option<&[u64]>,
    ) -> Result<(), CommandError> {
        if !at_s.is_finite() || !to_s.is_finite() {
            return Err(CommandError::Edit(
                "edit.retime needs finite `at_s` and `to_s`".into(),
            ));
        }
        let avoid = self.edits.avoid;
        let epoch = self.edits.epoch;
        let m = self.edit_mode_mut()?;
        if m.grab.is_some() || m.settling {
            return Err(CommandError::Edit(
                "an edit is under way; retime when the fingers have lifted".into(),
            ));
        }
        // Empty means everyone to the job: an empty list or selection is refused.
        let people: Arc<[usize]> = match (ids, &m.selection) {
            (Some(ids), _) => super::edit_select::indices_of(&m.set, ids, "edit.retime")?.into(),
            (None, Some(s)) => Arc::clone(&s.tracks),
            (None, None) => Arc::from([]),
        };
        if people.is_empty() && (ids.is_some() || m.selection.is_some()) {
            return Err(CommandError::Edit(
                "edit.retime: no one to retime (the `ids` or the selection are empty)".into(),
            ));
        }
        if m.preview.take().is_some() {
            self.edits.edits += 1;
        }
        let m = self.edit_mode_mut()?;
        m.settling = true;
        let base = Arc::clone(&m.set);
        Engine::push_undo(m, Arc::clone(&base));
        let (version, source) = (m.version + 1, Arc::clone(&m.source));
        self.edits.outbox.push_back(EditJob {
            epoch,
            grab: 0,
            kind: EditJobKind::Retime {
                base,
                people,
                at_s,
                to_s,
                avoid,
                version,
                source,
            },
        });
        self.edits.view_dirty = true;
        Ok(())
    }

    /// A gesture recognised in edit mode (in open space, not on a person): `contract`
    /// plays the next [`GESTURE_RETIME_S`] of the selection's tracks (everyone's
    /// without a selection) faster, `expand` slower
    /// (a temporal edit, section 3.3, dragging each person's node nearest that
    /// horizon by the factor; the first and last times stay), then collisions are
    /// avoided. Other classes (and a library's classes of other names) do nothing
    /// to the tracks.
    pub(super) fn edit_gesture(&mut self, id: u32, class: &str) {
        let factor = match class.parse::<MotionClass>() {
            Ok(MotionClass::Contract) => GESTURE_FASTER,
            Ok(MotionClass::Expand) => 1.0 / GESTURE_FASTER,
            _ => {
                log::info!("gesture {id}: {class} does nothing to tracks (contract and expand retime them)");
                return;
            }
        };
        let Some(play) = self.edits.mode.as_ref().map(|m| m.play_t_s) else {
            return;
        };
        let (at, to) = (play + GESTURE_RETIME_S, play + GESTURE_RETIME_S * factor);
        match self.edit_retime(at, to, None) {
            Ok(()) => {
                log::info!("gesture {id}: {class} retimes the tracks ({at:.1} s → {to:.1} s)")
            }
            Err(e) => log::info!("gesture {id}: {class} cannot retime the tracks: {e}"),
        }
    }

    /// `edit.exit`: the crowd comes back as a hard reset leaves it.
    pub(super) fn edit_exit(&mut self, now: Micros) -> Result<(), CommandError> {
        if self.edits.mode.is_none() && self.edits.loading.is_none() {
            return Err(CommandError::Edit("not in edit mode".into()));
        }
        self.edits.epoch += 1;
        self.edits.load_epoch += 1;
        self.edits.mode = None;
        self.edits.loading = None;
        self.edits.outbox.clear();
        self.segmenter.cancel_all(now, &mut self.seg_out);
        self.reset(true, now);
        self.queue_reset_event(true, now);
        Ok(())
    }

    pub(super) fn edit_mode_mut(&mut self) -> Result<&mut EditMode, CommandError> {
        self.edits
            .mode
            .as_deref_mut()
            .ok_or_else(|| CommandError::Edit("not in edit mode: send edit.load first".into()))
    }

    /// Uses a finished edit job (dropped when a newer load, grab or exit made it
    /// stale).
    pub fn apply_edit(&mut self, done: EditDone, _now: Micros) {
        if done.epoch != self.edits.epoch {
            return;
        }
        let Some(m) = self.edits.mode.as_mut() else {
            return;
        };
        match done.kind {
            EditDoneKind::Dragged {
                cage,
                edited,
                hull,
                deltas,
                handles,
                pins,
                handles_at,
                pins_at,
            } => {
                let Some(g) = m.grab.as_mut().filter(|g| g.id == done.grab) else {
                    return;
                };
                g.out = false;
                g.cage = cage;
                g.spare = deltas;
                // Vertices asked for by place are known now: the later drags and
                // the release hold the same ones.
                if handles.len() == g.held.len() && g.held.iter().any(unresolved) {
                    g.held = handles.into();
                }
                if pins.len() <= g.pins.len() && g.pins[..pins.len()].iter().any(unresolved) {
                    let mut all = pins;
                    all.extend_from_slice(&g.pins[all.len()..]);
                    g.pins = all.into();
                }
                g.handles_at = handles_at;
                g.pins_at = pins_at;
                match edited {
                    Ok((set, view)) => {
                        g.edited = Some(Arc::clone(&set));
                        m.hull = hull;
                        // Shown as edited while the fingers hold it.
                        m.set = set;
                        m.version = view.version;
                        self.edits.tracks_out = Some(view);
                    }
                    Err(e) => {
                        self.counters.deform_errors += 1;
                        if self.counters.deform_errors.is_power_of_two() {
                            log::warn!(
                                "edit: the drag could not be solved ({} times): {e}",
                                self.counters.deform_errors
                            );
                        }
                    }
                }
                self.edits.view_dirty = true;
            }
            EditDoneKind::Checked {
                collisions,
                version,
            } => {
                if m.version == version {
                    m.collisions = collisions;
                    self.edits.view_dirty = true;
                }
            }
            EditDoneKind::Settled { result, release } => {
                m.settling = false;
                match result {
                    Ok(Settled {
                        set,
                        collisions,
                        view,
                        preview,
                    }) => {
                        m.collisions = collisions;
                        m.version = view.version;
                        if self.edits.avoid.preview {
                            m.preview = Some(preview);
                        } else {
                            self.edits.edits += 1;
                        }
                        m.set = set;
                        self.edits.tracks_out = Some(view);
                    }
                    Err(e) => {
                        // The tracks go back to what they were before the edit.
                        log::warn!(
                            "edit: {} could not be applied: {e}",
                            if release { "the drag" } else { "the retime" }
                        );
                        if let Some(before) = m.undo.pop() {
                            m.set = before;
                            m.version += 1;
                            self.publish_tracks();
                        }
                    }
                }
                self.edits.view_dirty = true;
                self.edit_grab_queued();
            }
            EditDoneKind::Selected {
                result,
                request,
                version,
            } => self.apply_selection(result, request, version),
        }
    }

    /// The people at the play time, for the snapshot (a person before their first
    /// sample or after their last stands there, still).
    pub(super) fn edit_agents(&self, agents: &mut Vec<AgentView>, goals: &mut Vec<Vec2>) -> bool {
        let Some(m) = &self.edits.mode else {
            return false;
        };
        agents.clear();
        goals.clear();
        for (i, t) in m.set.tracks.iter().enumerate() {
            let (pos, _) = shown_position(t, m.play_t_s);
            agents.push(AgentView {
                pos,
                vel: velocity_at(t, m.play_t_s),
                goal: i as u32,
            });
            goals.push(*t.points.last().unwrap_or(&pos));
        }
        true
    }

    /// The `edit` message when something changed this tick.
    pub(super) fn take_edit_view(&mut self) -> Option<Arc<EditView>> {
        if !std::mem::take(&mut self.edits.view_dirty) {
            return None;
        }
        let seq = self.seq;
        let threshold_m = self.edits.avoid.threshold_m;
        let Some(m) = &self.edits.mode else {
            return Some(Arc::new(EditView {
                seq,
                state: if self.edits.loading.is_some() {
                    "loading"
                } else {
                    "off"
                },
                threshold_m,
                ..EditView::default()
            }));
        };
        let (state, selected) = match &m.grab {
            Some(g) => (
                "grabbed",
                g.selected.iter().map(|&k| m.set.tracks[k].id).collect(),
            ),
            None if m.settling => ("settling", Vec::new()),
            None if m.preview.is_some() => ("preview", Vec::new()),
            None => ("idle", Vec::new()),
        };
        let (pins, handles) = m.grab.as_ref().map_or((Vec::new(), Vec::new()), |g| {
            (g.pins_at.clone(), g.handles_at.clone())
        });
        let selection = m
            .selection
            .as_ref()
            .map_or_else(SelectionView::default, |s| SelectionView {
                ids: s.ids.clone(),
                window_s: s.window_s,
                lasso: s.lasso.clone(),
            });
        Some(Arc::new(EditView {
            seq,
            version: m.version,
            state,
            play_t_s: m.play_t_s,
            selected,
            hull: m.hull.clone(),
            collisions: m.collisions.clone(),
            threshold_m,
            undo_depth: m.undo.len() as u32,
            pins,
            handles,
            selection,
            preview: m.preview.clone(),
        }))
    }

    /// The `tracks` message of every person (after a load or an undo: rare, so
    /// built here; a drag's or a release's is built on the formation thread).
    fn publish_tracks(&mut self) {
        let Some(m) = &self.edits.mode else {
            return;
        };
        self.edits.tracks_out = Some(Arc::new(tracks_view(&m.set, None, m.version, &m.source)));
    }

    /// The `tracks` message of this tick, if the tracks changed.
    ///
    /// While fingers hold people the message of their tracks goes out at most every
    /// [`HELD_TRACKS_PERIOD_US`] (the newest one then); every person's (after a
    /// load, an undo, a release or a retime) goes out at once.
    pub(super) fn take_tracks(&mut self, now: Micros) -> Option<Arc<TracksView>> {
        let full = self.edits.tracks_out.as_ref()?.full;
        let due = self
            .edits
            .tracks_sent_at
            .is_none_or(|t| now.saturating_since(t).0 >= HELD_TRACKS_PERIOD_US);
        if !full && !due {
            return None;
        }
        self.edits.tracks_sent_at = Some(now);
        self.edits.tracks_out.take()
    }

    /// Pushes the tracks before an edit on the undo stack (called when a release or
    /// retime is sent).
    pub(super) fn push_undo(m: &mut EditMode, before: Arc<TrackSet>) {
        if m.undo.len() == MAX_UNDO {
            m.undo.remove(0);
        }
        m.undo.push(before);
    }
}

/// Whether a handle is a vertex still asked for by place.
fn unresolved(h: &HoldSpec) -> bool {
    matches!(h, HoldSpec::NearVertex(_))
}
