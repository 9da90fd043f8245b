//! `library collect` in the engine (gesture-driven section 4): the daemon shows a
//! library motion, the person draws the gesture they would use for it, the gesture
//! is added to the library with who drew it and on which device, and the next
//! motion is shown.
//!
//! ```text
//!  start ─► Show (worker: synthesise motion m for the crowd) ─► `demo_motion`,
//!           │      the crowd plays it (hard reset first), again every
//!           │      `replay_after` while the item waits; `collect` showing
//!           ▼
//!  a gesture ends ─► Save (worker: add it, write the library beside its path and
//!           │        rename it into place) ─► `collect` recorded ─► next item
//!           │   a tap or too short ─► `collect` refused (the item waits)
//!  collect.skip ─► `collect` skipped ─► next item      collect.again ─► shown again
//!  collect.undo ─► Undo (worker: remove the last recorded, save) ─► `collect`
//!                  undone ─► that item is asked for again
//!  past the last item ─► `collect` finished
//! ```
//!
//! The library and its path (the [`Collector`]) are moved into each job and come
//! back with its result, so the control thread never writes a file and nothing is
//! locked; what is asked for while a job is out waits in order. While a session
//! runs every touch is a gesture (drawing over the crowd does not grab it), the
//! continuous recogniser is off and no gesture is recognised or played.

use super::collect_state::{
    CollectDone, CollectDoneKind, CollectJob, CollectJobKind, CollectPlan, Collecting, Collector,
    Wanted,
};
use super::error::CommandError;
use super::state::Engine;
use crate::crowd::motion::Synthesis;
use crate::gesture::capture::Rejected;
use crate::gesture::library::MAX_PARTICIPANT_BYTES;
use crate::gesture::track::GestureTracks;
use crate::vocab::{CollectState, CollectView, Command, Event, Micros, PlanOrigin};

impl Engine {
    /// Starts a collection session: its first motion is shown at the next tick.
    ///
    /// # Errors
    /// A message for the person: no motions to ask for, a motion the library does
    /// not have, a participant id that is empty or too long.
    pub fn start_collecting(&mut self, plan: CollectPlan) -> Result<(), String> {
        if plan.motions.is_empty() {
            return Err("nothing to collect: no motions were chosen".into());
        }
        if plan.participant.is_empty() || plan.participant.len() > MAX_PARTICIPANT_BYTES {
            return Err(format!(
                "a participant id is 1 to {MAX_PARTICIPANT_BYTES} bytes of UTF-8"
            ));
        }
        let lib = &plan.library;
        let mut items = Vec::with_capacity(plan.motions.len());
        for &m in &plan.motions {
            let f = lib.motions.get(m as usize).ok_or_else(|| {
                format!(
                    "the library has {} motions; there is no motion {m}",
                    lib.motions.len()
                )
            })?;
            items.push((m, lib.class_name(f.class).to_string()));
        }
        self.segmenter.set_all_touches_are_gestures(true);
        self.collect = Some(Box::new(Collecting {
            collector: Some(Box::new(Collector {
                library: plan.library,
                path: plan.path,
            })),
            items,
            participant: plan.participant,
            devices: plan.devices,
            seed: plan.seed,
            replay_after: plan.replay_after,
            item: 0,
            recorded: Vec::new(),
            queued: vec![Wanted::Show],
            outbox: None,
            shown: None,
            demo_plan: None,
            demo_ended: None,
            last_device: 0,
            saving: false,
        }));
        Ok(())
    }

    /// Whether a collection session runs.
    pub fn collecting(&self) -> bool {
        self.collect.is_some()
    }

    /// Whether the session asked for every item and nothing is left to save.
    pub fn collect_finished(&self) -> bool {
        self.collect.as_ref().is_some_and(|c| {
            c.item >= c.items.len() && c.collector.is_some() && c.queued.is_empty()
        })
    }

    /// Gestures recorded by the session (0 without one).
    pub fn collect_recorded(&self) -> usize {
        self.collect.as_ref().map_or(0, |c| c.recorded.len())
    }

    /// A collection job for the formation thread ([`CollectJob::run`], then
    /// [`Engine::apply_collect`]).
    pub fn take_collect_job(&mut self) -> Option<CollectJob> {
        self.collect.as_mut().and_then(|c| c.outbox.take())
    }

    /// Notes which input a frame came from (the device stored with a gesture).
    pub(super) fn collect_note_device(&mut self, device: u16) {
        if let Some(c) = &mut self.collect {
            c.last_device = device;
        }
    }

    /// A gesture ended during a session: it is recorded for the item shown (a
    /// `gesture` event says why no motion is made), or refused. Returns the
    /// gesture's `rejected` reason, or `None` when no session runs.
    pub(super) fn collect_gesture(
        &mut self,
        captured: Result<&GestureTracks, &Rejected>,
        cancelled: bool,
        now: Micros,
    ) -> Option<String> {
        let c = self.collect.as_mut()?;
        if cancelled {
            return Some("cancelled".into());
        }
        match captured {
            Err(r) => {
                let why = r.as_str().to_string();
                // About the item the person is drawing for: past the gestures
                // drawn and still being saved.
                let pending = c
                    .queued
                    .iter()
                    .filter(|w| matches!(w, Wanted::Save { .. }))
                    .count()
                    + usize::from(c.saving);
                let item = (c.item + pending).min(c.items.len().saturating_sub(1));
                let view = c.view(CollectState::Refused, item, Some(why.clone()), now);
                self.events.push(view);
                Some(why)
            }
            Ok(_) if c.item >= c.items.len() => {
                let view = c.view(
                    CollectState::Refused,
                    c.item,
                    Some("the session is finished".into()),
                    now,
                );
                self.events.push(view);
                Some("collect_finished".into())
            }
            Ok(tracks) => {
                let device = match c.devices.get(c.last_device as usize) {
                    Some(name) => name.clone(),
                    None if c.last_device == crate::vocab::CLIENT_DEVICE => {
                        "client touches (viewer or touch commands)".to_string()
                    }
                    None => format!("input {}", c.last_device),
                };
                c.queued.push(Wanted::Save {
                    tracks: Box::new(tracks.clone()),
                    device,
                });
                self.dispatch_collect(now);
                Some("collecting".into())
            }
        }
    }

    /// A `collect.*` command.
    pub(super) fn collect_command(
        &mut self,
        cmd: &Command,
        now: Micros,
    ) -> Result<(), CommandError> {
        let Some(c) = self.collect.as_mut() else {
            return Err(CommandError::Collect(
                "no collection session runs (start one with `crowdtouch library collect`)",
            ));
        };
        let finished = c.item >= c.items.len();
        match cmd {
            Command::CollectStatus => {
                let state = if finished {
                    CollectState::Finished
                } else {
                    CollectState::Showing
                };
                let view = c.view(state, c.item, None, now);
                // The motion shown goes out again too (for `plan` subscribers).
                let shown = c.shown.as_ref().is_some_and(|(i, _)| *i == c.item);
                if shown && self.gestures.plan.is_none() {
                    self.gestures.plan.clone_from(&c.demo_plan);
                }
                self.events.push(view);
                Ok(())
            }
            Command::CollectSkip if finished => Err(CommandError::Collect(
                "the session is finished: nothing to skip",
            )),
            Command::CollectSkip => {
                let view = c.view(CollectState::Skipped, c.item, None, now);
                self.events.push(view);
                self.next_collect_item(now);
                Ok(())
            }
            Command::CollectUndo => {
                let pending_saves = c
                    .queued
                    .iter()
                    .filter(|w| matches!(w, Wanted::Save { .. }))
                    .count();
                let pending_undos = c
                    .queued
                    .iter()
                    .filter(|w| matches!(w, Wanted::Undo))
                    .count();
                // A save still out (the collector is away) counts as recorded.
                let out = usize::from(c.collector.is_none());
                if c.recorded.len() + pending_saves + out <= pending_undos {
                    return Err(CommandError::Collect("nothing recorded to undo"));
                }
                c.queued.push(Wanted::Undo);
                self.dispatch_collect(now);
                Ok(())
            }
            Command::CollectAgain if finished => Err(CommandError::Collect(
                "the session is finished: nothing to show",
            )),
            Command::CollectAgain => {
                self.show_collect_item(now);
                Ok(())
            }
            _ => Err(CommandError::NotHere("collect")),
        }
    }

    /// Uses a finished collection job (from the formation thread, or the tick's).
    pub fn apply_collect(&mut self, done: CollectDone, now: Micros) {
        let Some(c) = self.collect.as_mut() else {
            return;
        };
        c.collector = Some(done.collector);
        c.saving = false;
        match done.kind {
            CollectDoneKind::Shown { item, synthesis } => match synthesis {
                // Skipped meanwhile: the newer item's Show is queued.
                _ if item != c.item => {}
                Ok(s) => {
                    c.shown = Some((item, s.clone()));
                    let view = c.view(CollectState::Showing, item, None, now);
                    self.events.push(view);
                    self.play_collect_demo(item, s, now);
                }
                Err(e) => {
                    log::warn!("collect: motion {item} cannot be shown: {e}");
                    let view = c.view(CollectState::Failed, item, Some(e), now);
                    self.events.push(view);
                }
            },
            CollectDoneKind::Saved { item, result } => match result {
                Ok(gesture) => {
                    c.recorded.push((item, gesture));
                    log::info!(
                        "collect: gesture {} recorded for motion {} ({})",
                        c.recorded.len(),
                        c.items[item].0,
                        c.items[item].1
                    );
                    let view = c.view(CollectState::Recorded, item, None, now);
                    self.events.push(view);
                    if item == c.item {
                        self.next_collect_item(now);
                    }
                }
                Err(e) => {
                    log::error!("collect: the gesture was not recorded: {e}");
                    let view = c.view(CollectState::Failed, item, Some(e), now);
                    self.events.push(view);
                }
            },
            CollectDoneKind::Undone { item, result } => match result {
                Ok(()) => {
                    c.recorded.pop();
                    c.item = item;
                    c.shown = None;
                    let view = c.view(CollectState::Undone, item, None, now);
                    self.events.push(view);
                    self.show_collect_item(now);
                }
                Err(e) => {
                    log::error!("collect: the last gesture was not removed: {e}");
                    let view = c.view(CollectState::Failed, item, Some(e), now);
                    self.events.push(view);
                }
            },
        }
        self.dispatch_collect(now);
    }

    /// Once a tick: queued work goes out when the collector is home; a
    /// demonstration that ended plays again after `replay_after` while nobody
    /// touches the table.
    pub(super) fn poll_collect(&mut self, now: Micros) {
        let quiet = self.segmenter.gestures().is_empty()
            && self.segmenter.controls().is_empty()
            && !self.gestures.playing();
        let Some(c) = self.collect.as_mut() else {
            return;
        };
        let waiting = c.collector.is_some() && c.queued.is_empty() && c.item < c.items.len();
        let shown = c.shown.as_ref().is_some_and(|(i, _)| *i == c.item);
        if !(waiting && shown && quiet) {
            c.demo_ended = None;
        } else {
            match c.demo_ended {
                None => c.demo_ended = Some(now),
                Some(t) if now.saturating_since(t) >= c.replay_after => {
                    c.demo_ended = None;
                    self.show_collect_item(now);
                }
                Some(_) => {}
            }
        }
        self.dispatch_collect(now);
    }

    /// Moves to the next item (or finishes) and shows it.
    fn next_collect_item(&mut self, now: Micros) {
        let Some(c) = self.collect.as_mut() else {
            return;
        };
        c.item = (c.item + 1).min(c.items.len());
        c.shown = None;
        c.queued.retain(|w| !matches!(w, Wanted::Show));
        if c.item >= c.items.len() {
            log::info!(
                "collect: finished, {} gestures recorded from {}",
                c.recorded.len(),
                c.participant
            );
            let view = c.view(CollectState::Finished, c.item, None, now);
            self.events.push(view);
        } else {
            c.queued.push(Wanted::Show);
        }
    }

    /// Shows the item asked for: its synthesis again when it has one, else asks
    /// for one.
    fn show_collect_item(&mut self, now: Micros) {
        let Some(c) = self.collect.as_mut() else {
            return;
        };
        match &c.shown {
            Some((item, s)) if *item == c.item => {
                let (item, s) = (*item, s.clone());
                self.play_collect_demo(item, s, now);
            }
            _ => {
                if !c.queued.iter().any(|w| matches!(w, Wanted::Show)) {
                    c.queued.push(Wanted::Show);
                }
            }
        }
    }

    /// Sends the oldest queued work when the collector is home (runs it at once in
    /// replays).
    fn dispatch_collect(&mut self, now: Micros) {
        let inline = !self.switch_worker;
        loop {
            let (positions, speed_m_s) = (self.agents.positions(), self.gestures.speed_m_s);
            let Some(c) = self.collect.as_mut() else {
                return;
            };
            if c.collector.is_none() || c.queued.is_empty() || c.outbox.is_some() {
                return;
            }
            let wanted = c.queued.remove(0);
            let kind = match wanted {
                Wanted::Show if c.item >= c.items.len() || positions.is_empty() => continue,
                // The crowd copied only for a job that goes out.
                Wanted::Show => CollectJobKind::Show {
                    item: c.item,
                    motion: c.items[c.item].0 as usize,
                    agents: positions.to_vec(),
                    speed_m_s,
                    seed: c.seed ^ (c.item as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                },
                Wanted::Save { tracks, device } => CollectJobKind::Save {
                    item: c.item.min(c.items.len() - 1),
                    motion: c.items[c.item.min(c.items.len() - 1)].0 as usize,
                    tracks,
                    participant: c.participant.clone(),
                    device,
                },
                Wanted::Undo => match c.recorded.last() {
                    Some(&(item, gesture)) => CollectJobKind::Undo { item, gesture },
                    None => continue,
                },
            };
            let Some(collector) = c.collector.take() else {
                return;
            };
            c.saving = matches!(kind, CollectJobKind::Save { .. });
            let job = CollectJob { collector, kind };
            if inline {
                let done = job.run();
                self.apply_collect(done, now);
                return;
            }
            c.outbox = Some(job);
            return;
        }
    }

    /// Plays item `item`'s motion on the crowd from its start formation (a hard
    /// reset first, when nobody touches the table) and publishes it as
    /// `demo_motion`.
    fn play_collect_demo(&mut self, item: usize, s: Synthesis, now: Micros) {
        let Some(c) = self.collect.as_ref() else {
            return;
        };
        let (motion, class) = c.items[item].clone();
        if self.segmenter.gestures().is_empty() && self.segmenter.controls().is_empty() {
            self.reset(true, now);
        }
        if s.trajectories.len() != self.agents.len() {
            // The crowd changed size since: synthesise again.
            if let Some(c) = self.collect.as_mut() {
                c.shown = None;
            }
            self.show_collect_item(now);
            return;
        }
        self.start_motion(
            PlanOrigin::Demo { motion },
            0,
            class,
            s,
            super::gesture_state::Kept::default(),
            now,
        );
        let plan = self.gestures.plan.clone();
        if let Some(c) = self.collect.as_mut() {
            c.demo_plan = plan;
        }
    }
}

impl Collecting {
    /// A `collect` event about item `item`.
    fn view(&self, state: CollectState, item: usize, detail: Option<String>, t: Micros) -> Event {
        let (motion, class) = self
            .items
            .get(item)
            .filter(|_| state != CollectState::Finished)
            .cloned()
            .unwrap_or_default();
        Event::Collect(Box::new(CollectView {
            state,
            item: item as u32,
            of: self.items.len() as u32,
            class,
            motion,
            participant: self.participant.clone(),
            recorded: self.recorded.len() as u32,
            detail,
            t,
        }))
    }
}

#[cfg(test)]
#[path = "collect_tests.rs"]
mod tests;
