//! What clients may ask of the engine: reset, resize (`resize.rs`), pause and resume,
//! formation switches (`switch.rs`) and the edit mode's commands (`edit.rs`).
//!
//! # The events commands cause
//! Events wait in the engine until the next tick publishes them, so a burst of
//! commands between two ticks is folded into what clients need to see:
//! * `paused` is sent on a change only: pausing a paused crowd (or resuming a
//!   running one) sends nothing, and flips within one tick send at most one event,
//!   with the state the tick ends in — none when it ends where it began.
//! * `reset` is sent at most once per tick: a later reset or resize in the same
//!   tick updates the queued event (the crowd size after the last, `hard` if any
//!   was). A reset that changes nothing sends nothing: a soft one of a crowd
//!   already at rest (start formation, mesh at its rest pose, no control, gesture
//!   or switch under way), a hard one of a crowd at rest whose agents also stand
//!   still on their start goals (as the last hard reset left them).
//!
//! Every command is still answered to its sender; only the broadcast is folded.

use super::error::CommandError;
use super::state::Engine;
use crate::crowd::formation::START;
use crate::geom::Vec2;
use crate::vocab::{Command, Event, Micros};

impl Engine {
    /// Applies a client command at `now`.
    ///
    /// # Errors
    /// A message for the client when the command cannot be applied.
    pub fn command(&mut self, cmd: &Command, now: Micros) -> Result<(), CommandError> {
        match cmd {
            Command::Reset { hard } => {
                self.reset(*hard, now);
                Ok(())
            }
            Command::SetAgentCount { count } => self.set_agent_count(*count, now),
            Command::SetFormation {
                formation,
                method,
                duration,
            } => self.set_formation_by(formation, *method, *duration, now),
            Command::Pause => {
                self.set_paused(true, now);
                Ok(())
            }
            Command::Resume => {
                self.set_paused(false, now);
                Ok(())
            }
            Command::EditLoad { entry } => self.edit_load(entry),
            Command::EditUndo => self.edit_undo(),
            Command::EditSave { entry, overwrite } => self.edit_save(entry.as_deref(), *overwrite),
            Command::EditRetime { at_s, to_s, ids } => {
                self.edit_retime(*at_s, *to_s, ids.as_deref())
            }
            Command::EditSelect {
                lasso,
                window_s,
                ids,
            } => self.edit_select(lasso.as_deref(), *window_s, ids.as_deref()),
            Command::EditAccept => self.edit_accept(),
            Command::EditExit => self.edit_exit(now),
            Command::CollectSkip
            | Command::CollectUndo
            | Command::CollectAgain
            | Command::CollectStatus => self.collect_command(cmd, now),
            // Turned into touch frames by the control loop before the engine.
            Command::Touch { .. } => Err(CommandError::NotHere("touch")),
        }
    }

    /// Pauses or resumes; queues a `paused` event only for a change since the last
    /// published state (see the module doc).
    fn set_paused(&mut self, paused: bool, now: Micros) {
        if self.paused == paused {
            return;
        }
        self.paused = paused;
        // A queued `paused` event announces the flip away from the published state;
        // this flip goes back to it, so neither is sent.
        match self
            .events
            .iter()
            .position(|e| matches!(e, Event::Paused { .. }))
        {
            Some(i) => {
                self.events.remove(i);
            }
            None => self.events.push(Event::Paused { paused, t: now }),
        }
    }

    /// Queues a `reset` event for the crowd as it is now, folded into one already
    /// queued this tick (see the module doc).
    pub(super) fn queue_reset_event(&mut self, hard: bool, now: Micros) {
        let agents = self.agents.len() as u32;
        for e in &mut self.events {
            if let Event::Reset {
                agents: a,
                hard: h,
                t,
            } = e
            {
                *a = agents;
                *h |= hard;
                *t = now;
                return;
            }
        }
        self.events.push(Event::Reset {
            agents,
            hard,
            t: now,
        });
    }

    /// Whether every agent stands still on its own start goal with no waypoint, as
    /// a hard reset leaves it (and a crowd at rest keeps it). O(agents).
    fn agents_on_their_goals(&self) -> bool {
        let goals = self.direct.goals();
        self.goal_of
            .iter()
            .enumerate()
            .all(|(i, &g)| g as usize == i)
            && self.agents.positions() == goals
            && self.agents.velocities().iter().all(|v| *v == Vec2::zeros())
            && self.waypoints.iter().all(|w| w.x.is_nan())
    }

    /// Whether a soft reset would change nothing: the start formation at its rest
    /// pose, no control, gesture or formation switch under way.
    fn at_rest(&self) -> bool {
        self.formation_name == START
            && self.switch_pending.is_none()
            && self.switch_queued.is_none()
            && self.switch_outbox.is_none()
            && self.segmenter.controls().is_empty()
            && self.segmenter.gestures().is_empty()
            && !self.gestures.playing()
            && !self.transforms.busy()
            && self.direct.is_at_rest()
    }

    /// Mesh back to rest in the start formation; controls end. `hard` teleports
    /// agents to their goals.
    pub fn reset(&mut self, hard: bool, now: Micros) {
        if self.at_rest() && (!hard || self.agents_on_their_goals()) {
            return;
        }
        self.segmenter.cancel_all(now, &mut self.seg_out);
        self.forget_switches();
        self.forget_gestures(now);
        self.drop_transforms(crate::vocab::TransformOutcome::Dropped, now);
        if self.formation_name != START {
            self.restore_start(now);
        }
        self.direct.reset();
        if hard {
            self.prev_centroid = None;
            self.agents.teleport(self.direct.goals());
            self.goal_of.clear();
            self.goal_of.extend(0..self.agents.len() as u32);
            self.waypoints.fill(Vec2::repeat(f64::NAN));
            self.forget_assignments();
        }
        self.queue_reset_event(hard, now);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame};

    fn engine() -> Engine {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = 20;
        let mut e = Engine::new(&cfg, None, false);
        e.tick(Micros(0));
        e.clear_events();
        e
    }

    /// The events the next tick publishes, then cleared as the pipeline does.
    fn next_tick(e: &mut Engine, now: u64) -> Vec<Event> {
        let events = e.tick(Micros(now)).events.to_vec();
        e.clear_events();
        events
    }

    fn paused_events(events: &[Event]) -> Vec<bool> {
        events
            .iter()
            .filter_map(|ev| match ev {
                Event::Paused { paused, .. } => Some(*paused),
                _ => None,
            })
            .collect()
    }

    fn resets(events: &[Event]) -> Vec<(u32, bool)> {
        events
            .iter()
            .filter_map(|ev| match ev {
                Event::Reset { agents, hard, .. } => Some((*agents, *hard)),
                _ => None,
            })
            .collect()
    }

    /// A finger down on the middle of the crowd (the default formation's centre).
    fn touch_the_crowd(e: &mut Engine, now: u64) {
        let mut f = TouchFrame::new(Micros(now));
        f.push(Contact {
            id: ContactId(1),
            x: 0.5,
            y: 0.5,
            pressure: None,
            major_mm: None,
            minor_mm: None,
            flags: ContactFlags::DOWN,
        })
        .expect("room for one contact");
        e.push_frame(&f);
    }

    #[test]
    fn pausing_a_paused_crowd_sends_nothing() {
        let mut e = engine();
        e.command(&Command::Pause, Micros(1)).unwrap();
        assert_eq!(paused_events(&next_tick(&mut e, 10_000)), vec![true]);
        for t in 0..100 {
            e.command(&Command::Pause, Micros(10_001 + t)).unwrap();
        }
        assert!(paused_events(&next_tick(&mut e, 20_000)).is_empty());
        e.command(&Command::Resume, Micros(20_001)).unwrap();
        e.command(&Command::Resume, Micros(20_002)).unwrap();
        assert_eq!(paused_events(&next_tick(&mut e, 30_000)), vec![false]);
    }

    #[test]
    fn pause_flips_within_a_tick_send_at_most_the_final_change() {
        let mut e = engine();
        // Ends paused: one event, `paused: true`.
        for i in 0..1001u64 {
            let c = if i % 2 == 0 {
                Command::Pause
            } else {
                Command::Resume
            };
            e.command(&c, Micros(1 + i)).unwrap();
        }
        let out = e.tick(Micros(10_000));
        assert!(out.snapshot.paused);
        assert_eq!(paused_events(out.events), vec![true]);
        e.clear_events();
        // Ends where it began (paused): nothing to say.
        for i in 0..1000u64 {
            let c = if i % 2 == 0 {
                Command::Resume
            } else {
                Command::Pause
            };
            e.command(&c, Micros(10_001 + i)).unwrap();
        }
        let out = e.tick(Micros(20_000));
        assert!(out.snapshot.paused);
        assert!(paused_events(out.events).is_empty(), "{:?}", out.events);
    }

    #[test]
    fn resets_within_a_tick_send_one_event_with_the_final_crowd() {
        let mut e = engine();
        touch_the_crowd(&mut e, 5);
        let _ = next_tick(&mut e, 10_000);
        assert!(!e.at_rest(), "a finger holds the crowd");
        for i in 0..500u64 {
            e.command(&Command::Reset { hard: false }, Micros(10_001 + i))
                .unwrap();
        }
        e.command(&Command::SetAgentCount { count: 30 }, Micros(11_000))
            .unwrap();
        e.command(&Command::Reset { hard: false }, Micros(11_001))
            .unwrap();
        // One event: the size after the last resize, hard because one was.
        assert_eq!(resets(&next_tick(&mut e, 20_000)), vec![(30, true)]);
        // A reset of a crowd at rest changes nothing and says nothing.
        assert!(e.at_rest());
        e.command(&Command::Reset { hard: false }, Micros(20_001))
            .unwrap();
        assert!(resets(&next_tick(&mut e, 30_000)).is_empty());
        // Agents that stand on their goals (a resize places them there) are not
        // moved by a hard reset either.
        assert!(e.agents_on_their_goals());
        e.command(&Command::Reset { hard: true }, Micros(30_001))
            .unwrap();
        assert!(resets(&next_tick(&mut e, 40_000)).is_empty());
        // Agents walking back from another formation are: it is announced, once.
        e.set_formation_by(
            "arrow",
            Some(crate::vocab::FormationMethod::Mesh),
            None,
            Micros(40_001),
        )
        .unwrap();
        for k in 1..=10 {
            let _ = next_tick(&mut e, 40_000 + k * 10_000);
        }
        e.command(&Command::Reset { hard: false }, Micros(150_000))
            .unwrap();
        assert_eq!(resets(&next_tick(&mut e, 160_000)), vec![(30, false)]);
        assert!(e.at_rest() && !e.agents_on_their_goals());
        e.command(&Command::Reset { hard: true }, Micros(160_001))
            .unwrap();
        e.command(&Command::Reset { hard: true }, Micros(160_002))
            .unwrap();
        assert_eq!(resets(&next_tick(&mut e, 170_000)), vec![(30, true)]);
        // Now they stand on their goals again: nothing to announce.
        assert!(e.agents_on_their_goals());
        e.command(&Command::Reset { hard: true }, Micros(170_001))
            .unwrap();
        assert!(resets(&next_tick(&mut e, 180_000)).is_empty());
    }

    #[test]
    fn a_reset_out_of_another_formation_is_announced() {
        let mut e = engine();
        e.set_formation_by(
            "arrow",
            Some(crate::vocab::FormationMethod::Mesh),
            None,
            Micros(1),
        )
        .unwrap();
        let _ = next_tick(&mut e, 10_000);
        assert!(!e.at_rest());
        e.command(&Command::Reset { hard: false }, Micros(10_001))
            .unwrap();
        let events = next_tick(&mut e, 20_000);
        assert_eq!(resets(&events), vec![(20, false)]);
        assert!(events
            .iter()
            .any(|ev| matches!(ev, Event::Formation { name, .. } if name == START)));
        assert!(e.at_rest());
    }
}
