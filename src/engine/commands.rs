//! What clients may ask of the engine: reset, resize (`resize.rs`), pause and resume,
//! and formation switches (`switch.rs`).

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
}
