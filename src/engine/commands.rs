//! What clients may ask of the engine: reset, resize, pause and resume, and
//! formation switches (`switch.rs`).

use super::error::CommandError;
use super::state::Engine;
use crate::config::MAX_AGENTS;
use crate::crowd::agents::Agents;
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
            Command::SetFormation { formation } => self.set_formation(formation, now),
            Command::Pause => {
                if !self.paused {
                    self.paused = true;
                    self.events.push(Event::Paused {
                        paused: true,
                        t: now,
                    });
                }
                Ok(())
            }
            Command::Resume => {
                if self.paused {
                    self.paused = false;
                    self.events.push(Event::Paused {
                        paused: false,
                        t: now,
                    });
                }
                Ok(())
            }
        }
    }

    /// Mesh back to rest in the start formation; controls end. `hard` teleports
    /// agents to their goals.
    pub fn reset(&mut self, hard: bool, now: Micros) {
        self.segmenter.cancel_all(now, &mut self.seg_out);
        self.forget_switches();
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
            self.generation += 1;
            if let Some(a) = &mut self.inline {
                a.forget();
            }
            if let Some(p) = &mut self.planner {
                p.forget();
            }
        }
        self.events.push(Event::Reset {
            agents: self.agents.len() as u32,
            hard,
            t: now,
        });
    }

    /// New crowd size: agents are placed on the new goals of the current mesh.
    ///
    /// # Errors
    /// [`CommandError::AgentCount`] when out of range.
    pub fn set_agent_count(&mut self, count: u32, now: Micros) -> Result<(), CommandError> {
        if count == 0 || count > MAX_AGENTS {
            return Err(CommandError::AgentCount {
                count,
                max: MAX_AGENTS,
            });
        }
        self.direct.set_agent_count(count as usize);
        self.agents = Agents::new(self.direct.goals());
        self.prev_centroid = None;
        self.forget_switches();
        self.start_samples = if self.formation_name == START {
            self.direct.samples().to_vec()
        } else {
            crate::crowd::mesh::sample_goals(&self.start_mesh, count as usize)
        };
        self.goal_of.clear();
        self.goal_of.extend(0..count);
        self.waypoints.clear();
        self.waypoints
            .resize(count as usize, Vec2::repeat(f64::NAN));
        self.generation += 1;
        if let Some(a) = &mut self.inline {
            a.forget();
        }
        if let Some(p) = &mut self.planner {
            p.forget();
        }
        self.fit_radius();
        self.set_mesh_environment();
        self.events.push(Event::Reset {
            agents: count,
            hard: true,
            t: now,
        });
        Ok(())
    }
}
