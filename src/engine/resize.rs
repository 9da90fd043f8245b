//! A new crowd size (`set_agent_count`): its slow part — drawing a goal sample per
//! agent on the mesh, seconds at 20,000 agents — is a [`ResizeRequest`] the
//! daemon's formation thread prepares off the control thread (replays prepare it
//! in the command), and [`Engine::apply_resize`] installs it between two ticks.
//!
//! ```text
//!  command ─► request_resize ─► outbox ─► formation thread: prepare ─► apply_resize
//!               (validated,       (newest     (sample_goals,            (agents on the
//!                ticket + 1)       wins)       cancellable)              new goals; Reset event)
//! ```
//!
//! The crowd keeps moving at its old size meanwhile. A later resize supersedes the
//! one out (its ticket changes, so its preparation is cancelled and its result
//! ignored); a result drawn on a mesh that has been replaced since (a formation
//! switch or a reset) is drawn again on the current mesh; a formation switch asked
//! for meanwhile is asked for again at the new size once the resize is in.

use super::error::CommandError;
use super::state::Engine;
use crate::crowd::agents::Agents;
use crate::crowd::assign::Cancel;
use crate::crowd::control::{PreparedResize, ResizeRequest};
use crate::crowd::formation::START;
use crate::geom::Vec2;
use crate::vocab::Micros;
use std::sync::Arc;

impl Engine {
    /// New crowd size: agents are placed on the new goals of the current mesh (a
    /// `reset` event says so). With the formation thread
    /// ([`Engine::set_switch_worker`]) this only asks for it ([`Engine::request_resize`]);
    /// otherwise the goals are drawn here and the crowd has its new size at once.
    ///
    /// # Errors
    /// [`CommandError::AgentCount`] when out of range.
    pub fn set_agent_count(&mut self, count: u32, now: Micros) -> Result<(), CommandError> {
        if self.switch_worker {
            return self.request_resize(count);
        }
        self.request_resize(count)?;
        let r = self.resize.outbox.take().expect("just asked for");
        let p = r.prepare(Cancel::NEVER).expect("never cancelled");
        self.apply_resize(p, now);
        Ok(())
    }

    /// Asks for a new crowd size, prepared by the formation thread
    /// ([`Engine::take_resize_request`], [`ResizeRequest::prepare`], then
    /// [`Engine::apply_resize`]); the newest request wins.
    ///
    /// # Errors
    /// [`CommandError::AgentCount`] when out of range (nothing is asked for then).
    pub fn request_resize(&mut self, count: u32) -> Result<(), CommandError> {
        if count == 0 || count > self.max_agents {
            return Err(CommandError::AgentCount {
                count,
                max: self.max_agents,
            });
        }
        self.resize.ticket += 1;
        self.resize.pending = Some(count);
        self.resize.outbox = Some(ResizeRequest {
            count,
            ticket: self.resize.ticket,
            topology: self.topology,
            mesh: self.direct.mesh().clone(),
            start_mesh: (self.formation_name != START).then(|| Arc::clone(&self.start_mesh)),
        });
        Ok(())
    }

    /// The resize request for the formation thread, if one is waiting.
    pub fn take_resize_request(&mut self) -> Option<ResizeRequest> {
        self.resize.outbox.take()
    }

    /// Whether a resize is being prepared (its `set_agent_count` is acknowledged
    /// once it is applied).
    pub fn resize_pending(&self) -> bool {
        self.resize.pending.is_some()
    }

    /// Identifies the newest resize asked for; a request or result with another
    /// ticket is stale (the formation thread gives up preparing it).
    pub fn resize_ticket(&self) -> u64 {
        self.resize.ticket
    }

    /// Identifies the formation switches that are still wanted; a switch request
    /// with another epoch is stale (a reset or resize came after it).
    pub fn switch_epoch(&self) -> u64 {
        self.switch_epoch
    }

    /// Installs a prepared resize: every agent stands on one of the new goals, a
    /// new crowd generation starts (assignment results for the old crowd are
    /// discarded), a formation switch that was out is asked for again at the new
    /// size, and a `reset` event (hard) says so. Returns whether the crowd has the
    /// new size now. A superseded result is ignored; one drawn on a mesh replaced
    /// since is asked for again on the current mesh. Allocates (a one-off).
    pub fn apply_resize(&mut self, p: PreparedResize, now: Micros) -> bool {
        if p.ticket != self.resize.ticket || self.resize.pending.is_none() {
            return false;
        }
        if p.topology != self.topology {
            let _ = self.request_resize(p.count);
            return false;
        }
        let count = p.count;
        self.resize.pending = None;
        self.direct.set_samples(p.samples);
        self.agents = Agents::new(self.direct.goals());
        self.prev_centroid = None;
        // A switch asked for at the old size is asked for again at the new one.
        let again = self.switch_queued.take().or_else(|| {
            let name = self.switch_pending.take()?;
            Some((name, None, Vec2::new(1.0, 0.0)))
        });
        self.forget_switches();
        self.forget_gestures(now);
        self.drop_transforms(crate::vocab::TransformOutcome::Dropped, now);
        self.start_samples = match p.start_samples {
            Some(s) => s,
            None => self.direct.samples().to_vec(),
        };
        self.goal_of.clear();
        self.goal_of.extend(0..count);
        self.waypoints.clear();
        self.waypoints
            .resize(count as usize, Vec2::repeat(f64::NAN));
        self.terrain.reserve(count as usize);
        self.forget_assignments();
        self.fit_radius();
        self.set_mesh_environment();
        self.queue_reset_event(true, now);
        if let Some((name, checkpoint, heading)) = again {
            let _ = self.request_switch(&name, checkpoint.as_deref(), heading, now);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;
    use crate::vocab::{Command, Event};

    /// An engine as the daemon runs it: switches and resizes prepared elsewhere.
    fn engine(agents: u32) -> Engine {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = agents;
        let mut e = Engine::new(&cfg, None, false);
        e.set_switch_worker(true);
        e
    }

    fn resets(e: &Engine) -> Vec<u32> {
        e.events
            .iter()
            .filter_map(|ev| match ev {
                Event::Reset { agents, .. } => Some(*agents),
                _ => None,
            })
            .collect()
    }

    /// The crowd keeps its size and keeps being published while the resize is
    /// prepared; once applied it has the new size, a new generation and a reset
    /// event.
    #[test]
    fn the_crowd_keeps_ticking_at_its_old_size_until_the_resize_is_applied() {
        let mut e = engine(50);
        e.tick(Micros(0));
        let generation = e.generation();
        e.command(&Command::SetAgentCount { count: 700 }, Micros(1))
            .unwrap();
        assert!(e.resize_pending());
        let r = e
            .take_resize_request()
            .expect("a request for the formation thread");
        assert_eq!(r.count, 700);
        assert!(e.take_resize_request().is_none());
        for k in 1..5 {
            let out = e.tick(Micros(k * 8_000));
            assert_eq!(out.snapshot.agents.len(), 50);
            e.clear_events();
        }
        assert_eq!(e.generation(), generation);
        let p = r.prepare(Cancel::NEVER).unwrap();
        assert!(e.apply_resize(p, Micros(50_000)));
        assert!(!e.resize_pending());
        assert_eq!(resets(&e), [700]);
        assert_ne!(e.generation(), generation);
        assert_eq!(
            (e.agent_count(), e.goals().len(), e.goal_of().len()),
            (700, 700, 700)
        );
        assert_eq!(e.tick(Micros(58_000)).snapshot.agents.len(), 700);
    }

    /// The newest resize wins: an older result is ignored (its preparation would
    /// have been cancelled), and an out-of-range count asks for nothing.
    #[test]
    fn a_later_resize_supersedes_one_being_prepared() {
        let mut e = engine(50);
        e.set_agent_count(900, Micros(0)).unwrap();
        let first = e.take_resize_request().unwrap();
        e.set_agent_count(60, Micros(1)).unwrap();
        let second = e.take_resize_request().unwrap();
        assert_ne!(first.ticket, second.ticket);
        assert_eq!(e.resize_ticket(), second.ticket);
        assert!(e.set_agent_count(0, Micros(2)).is_err());
        assert_eq!(
            e.resize_ticket(),
            second.ticket,
            "a refused count asks for nothing"
        );
        assert!(!e.apply_resize(first.prepare(Cancel::NEVER).unwrap(), Micros(3)));
        assert_eq!(e.agent_count(), 50);
        assert!(e.resize_pending());
        assert!(e.apply_resize(second.prepare(Cancel::NEVER).unwrap(), Micros(4)));
        assert_eq!(e.agent_count(), 60);
        // Once applied, a copy of the same result changes nothing.
        assert_eq!(resets(&e), [60]);
    }

    /// Samples drawn on a mesh that was replaced meanwhile (a formation switch)
    /// are drawn again on the current mesh; a switch asked for while the resize
    /// was out is asked for again at the new size.
    #[test]
    fn a_resize_follows_the_mesh_and_the_switch_asked_for_meanwhile() {
        let mut e = engine(40);
        e.tick(Micros(0));
        e.set_agent_count(120, Micros(1)).unwrap();
        let r = e.take_resize_request().unwrap();
        e.set_formation_by(
            "square",
            Some(crate::vocab::FormationMethod::Mesh),
            None,
            Micros(2),
        )
        .unwrap();
        let s = e.take_switch_request().unwrap();
        assert_eq!(s.agents.len(), 40);
        // The switch lands first: the mesh changes under the resize.
        e.apply_switch(s.prepare(), Micros(3)).unwrap();
        assert_eq!(e.formation(), "square");
        assert!(!e.apply_resize(r.prepare(Cancel::NEVER).unwrap(), Micros(4)));
        assert!(e.resize_pending());
        let again = e
            .take_resize_request()
            .expect("asked for again on the new mesh");
        assert_eq!(again.mesh.vertex_count(), e.direct.mesh().vertex_count());
        assert!(
            again.start_mesh.is_some(),
            "a reset needs the start mesh's samples"
        );
        assert!(e.apply_resize(again.prepare(Cancel::NEVER).unwrap(), Micros(5)));
        assert_eq!(e.agent_count(), 120);
        assert_eq!(e.start_samples.len(), 120);
        // A switch asked for while a resize is out is asked for again after it.
        e.set_agent_count(80, Micros(6)).unwrap();
        let r = e.take_resize_request().unwrap();
        e.set_formation_by(
            "wedge",
            Some(crate::vocab::FormationMethod::Mesh),
            None,
            Micros(7),
        )
        .unwrap();
        let stale = e.take_switch_request().unwrap();
        assert_eq!(stale.agents.len(), 120);
        assert!(e.apply_resize(r.prepare(Cancel::NEVER).unwrap(), Micros(8)));
        assert_ne!(e.switch_epoch(), stale.epoch, "the old request is stale");
        let s = e.take_switch_request().expect("asked for again");
        assert_eq!((s.name.as_str(), s.agents.len()), ("wedge", 80));
        e.apply_switch(s.prepare(), Micros(9)).unwrap();
        assert_eq!((e.formation(), e.agent_count()), ("wedge", 80));
    }

    /// Without the formation thread (replays) the resize happens in the command.
    #[test]
    fn without_the_formation_thread_a_resize_is_immediate() {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = 30;
        let mut e = Engine::new(&cfg, None, false);
        e.set_agent_count(75, Micros(0)).unwrap();
        assert!(!e.resize_pending());
        assert!(e.take_resize_request().is_none());
        assert_eq!(e.agent_count(), 75);
        assert_eq!(resets(&e), [75]);
    }

    #[test]
    fn a_cancelled_preparation_gives_nothing() {
        let mut e = engine(30);
        e.set_agent_count(5_000, Micros(0)).unwrap();
        let r = e.take_resize_request().unwrap();
        let yes = || true;
        assert!(r.prepare(Cancel::new(&yes)).is_none());
        assert_eq!(e.agent_count(), 30);
    }
}
