//! Formation transforms in the engine (formation-transform, Xu et al. 2015): a
//! formation request with method `transform` samples targets in the new shape,
//! pairs agents with them (least effort, eq. 3, or a distance) and clusters
//! subgroups — on the formation thread, or in the tick for replays — then a
//! [`TransformRun`] drives the agents every tick until all arrived (or the
//! timeout); the direct-control mesh is then rebuilt on the targets and touch
//! control resumes on the new shape.
//!
//! ```text
//!  set_formation / checkpoint / mapped gesture
//!        │ TransformRequest (epoch)
//!        ▼
//!  TransformRequest::prepare        (formation thread; in the tick for replays)
//!  sample · pair · subgroups
//!        │ PreparedTransform
//!        ▼
//!  TransformRun::step every tick ──► `transform` message (progress, measures)
//!        │ all arrived / timeout            │ a touch on the crowd
//!        ▼                                  ▼
//!  `transform_end`, hold on the targets    `transform_end` (touched), hold where they are
//!        │ RemeshRequest (mesh_around)      │
//!        ▼                                  ▼
//!  install: goal i = agent i; `formation` event; assignment takes over
//! ```
//!
//! While a transform runs its pairing is the agents' goals: the snapshot's goals
//! are the targets, each agent's goal index its own (identity), assignment results
//! are discarded and the inline solve is skipped, so nothing overwrites it. A
//! newer request starts from where the agents are; a reset or resize drops it.
//! Nothing here allocates in a steady tick: requests, runs and summaries are built
//! once per transform, progress messages are recycled.

use super::error::{CommandError, SwitchError};
use super::state::Engine;
use super::switch::shift_inside;
use super::transform_state::{PendingTransform, Remeshing, RunningTransform, MIN_TRANSFORM_STEP_S};
use crate::config::MAX_DESIRED_SPEED_M_S;
use crate::crowd::formation::{Formation, FormationDef, Placement, SampleParams, START};
use crate::crowd::motion::{PreparedRemesh, RemeshRequest};
use crate::crowd::transform::{
    PreparedTransform, RunSummary, StepReport, TransformPlan, TransformRequest, TransformRun,
};
use crate::geom::Vec2;
use crate::vocab::{
    FormationMethod, Micros, TransformMeasures, TransformOutcome, TransformSummary,
};
use std::sync::Arc;

/// Longest `set_formation` duration (s).
pub const MAX_DURATION_S: f64 = 600.0;
/// Slowest desired speed a duration may set (m/s): a longer duration than the
/// distance allows at this speed takes longer.
pub const MIN_DESIRED_SPEED_M_S: f64 = 0.05;
/// Iterations of the force-based relaxation of sampled targets.
pub const SAMPLE_RELAX_ITERATIONS: u32 = 30;
/// Targets are sampled at least this many agent radii apart.
pub const SAMPLE_SPACING_RADII: f64 = 2.0;

impl Engine {
    /// Goes into formation `name` by `method` (`None`: `formations.method`);
    /// `duration_s` sets a transform's desired speed so that it takes about that
    /// long. The crowd is unaffected by a refused request.
    ///
    /// # Errors
    /// [`CommandError::UnknownFormation`] naming the known formations;
    /// [`CommandError::Duration`] for a duration that is not in `(0, 600]` s;
    /// without the formation thread, [`CommandError::FormationNotBuilt`].
    pub fn set_formation_by(
        &mut self,
        name: &str,
        method: Option<FormationMethod>,
        duration_s: Option<f64>,
        now: Micros,
    ) -> Result<(), CommandError> {
        if !self.formations.knows(name) {
            return Err(CommandError::UnknownFormation {
                name: name.to_string(),
                known: self.formations.names_list(),
            });
        }
        if let Some(d) = duration_s {
            if !(d.is_finite() && d > 0.0 && d <= MAX_DURATION_S) {
                return Err(CommandError::Duration {
                    duration_s: d,
                    max_s: MAX_DURATION_S,
                });
            }
        }
        let heading = self.crowd_heading();
        let method = method.unwrap_or(self.transforms.settings.method);
        self.request_formation(name, None, method, duration_s, heading, now)
            .map_err(|why| CommandError::FormationNotBuilt {
                name: name.to_string(),
                why,
            })
    }

    /// The way the crowd moves (`+x` when it stands still).
    pub(super) fn crowd_heading(&self) -> Vec2 {
        let n = self.agents.len().max(1) as f64;
        let v = self.agents.velocities().iter().sum::<Vec2>() / n;
        if v.norm() > 1e-3 {
            v
        } else {
            Vec2::new(1.0, 0.0)
        }
    }

    /// Asks for formation `name` by `method`: a transform, or a mesh switch (which
    /// ends a running transform where the agents are).
    pub(super) fn request_formation(
        &mut self,
        name: &str,
        checkpoint: Option<&str>,
        method: FormationMethod,
        duration_s: Option<f64>,
        heading: Vec2,
        now: Micros,
    ) -> Result<(), SwitchError> {
        match method {
            FormationMethod::Mesh => {
                if self.transforms.busy() {
                    self.drop_transforms(TransformOutcome::Superseded, now);
                }
                self.request_switch(name, checkpoint, heading, now)
            }
            FormationMethod::Transform => {
                self.request_transform(name, checkpoint, duration_s, heading, now)
            }
        }
    }

    /// The formation the crowd is in or going to: a transform's, a switch's, or the
    /// current one.
    pub(super) fn formation_target(&self) -> &str {
        self.transforms
            .target()
            .or(self.switch_pending.as_deref())
            .unwrap_or(&self.formation_name)
    }

    /// Asks for a transform to formation `name`, laid out as a switch would be
    /// ([`Engine::request_switch`]): the user mesh's area, centred where the crowd
    /// is, `+x` along `heading`, shifted inside the world. Asking for the
    /// formation the crowd is in or going to changes nothing (unless a duration is
    /// given). A request replaces one being prepared; a running transform goes on
    /// until the new one is ready, which starts from where the agents are then.
    pub(super) fn request_transform(
        &mut self,
        name: &str,
        checkpoint: Option<&str>,
        duration_s: Option<f64>,
        heading: Vec2,
        now: Micros,
    ) -> Result<(), SwitchError> {
        if duration_s.is_none() && name == self.formation_target() {
            return Ok(());
        }
        if self.agents.is_empty() {
            return Ok(());
        }
        let centre = if self.transforms.active() {
            let p = self.agents.positions();
            p.iter().sum::<Vec2>() / p.len() as f64
        } else {
            self.user_centroid()
        };
        let (formation, mut place) = if name == START {
            let r = self.formation;
            // `start` is reserved for the library's names; the shape itself is the
            // `crowd.formation` rectangle (the request keeps the name `start`).
            let def = FormationDef::rectangle("crowd.formation", r);
            let Ok(f) = Formation::new(&def) else {
                let why = SwitchError::NotInLibrary;
                self.formation_failed(name, &why);
                return Err(why);
            };
            let area = r.width() * r.height();
            (
                f,
                Placement {
                    centre_m: centre,
                    heading: Vec2::new(1.0, 0.0),
                    area_m2: area,
                },
            )
        } else {
            let Some(f) = self.formations.get(name) else {
                let why = SwitchError::NotInLibrary;
                self.formation_failed(name, &why);
                return Err(why);
            };
            (
                f.clone(),
                Placement {
                    centre_m: centre,
                    heading,
                    area_m2: self.user_mesh_area(),
                },
            )
        };
        place.centre_m += shift_inside(&formation.placed_outline(&place), self.world);
        // The last request wins: a switch or gesture motion under way is dropped.
        self.forget_switches();
        self.cancel_gesture_motion(now);
        let t = &mut self.transforms;
        t.epoch += 1;
        t.pending = Some(PendingTransform {
            name: name.to_string(),
            checkpoint: checkpoint.map(str::to_string),
            duration_s,
        });
        let req = TransformRequest {
            name: name.to_string(),
            epoch: t.epoch,
            formation,
            placement: place,
            agents: self.agents.positions().to_vec(),
            cost: t.settings.cost,
            subgroups: t.settings.ap,
            sample: SampleParams {
                min_spacing_m: SAMPLE_SPACING_RADII * self.agent_params.radius_m,
                relax_iterations: SAMPLE_RELAX_ITERATIONS,
            },
            seed: 0x7a5f_0e11 ^ t.started.wrapping_mul(0x9e37_79b9_7f4a_7c15),
        };
        if t.inline {
            match req.prepare(crate::crowd::assign::Cancel::default()) {
                Some(p) => self.apply_transform(p, now),
                None => Ok(()),
            }
        } else {
            t.outbox = Some(req);
            Ok(())
        }
    }

    /// The transform request for the formation thread, if one is waiting
    /// ([`TransformRequest::prepare`] it, then [`Engine::apply_transform`]).
    pub fn take_transform_request(&mut self) -> Option<TransformRequest> {
        self.transforms.outbox.take()
    }

    /// The mesh to rebuild after a transform, if one is waiting
    /// ([`RemeshRequest::prepare`] it, then [`Engine::apply_transform_remesh`]).
    pub fn take_transform_remesh(&mut self) -> Option<RemeshRequest> {
        self.transforms.remesh_outbox.take()
    }

    /// The transform epoch: a request or rebuilt mesh of another is stale.
    pub fn transform_epoch(&self) -> u64 {
        self.transforms.epoch
    }

    /// Whether a transform drives the agents (or its mesh is being rebuilt).
    pub fn transform_running(&self) -> bool {
        self.transforms.active()
    }

    /// Transforms started since start.
    pub fn transforms_started(&self) -> u64 {
        self.transforms.started
    }

    /// The last transform that ended, summarised.
    pub fn last_transform(&self) -> Option<&Arc<TransformSummary>> {
        self.transforms.last.as_ref()
    }

    /// The running transform's targets: agent `i`'s is `[i]` (m).
    pub fn transform_targets(&self) -> Option<&[Vec2]> {
        self.transforms.running.as_ref().map(|r| r.run.targets())
    }

    /// Starts a prepared transform (a running one is superseded and the new one
    /// starts from where the agents are). A stale one (another epoch, another crowd
    /// size) is dropped; one that could not be prepared is logged and counted, and
    /// the crowd goes on as it was.
    ///
    /// # Errors
    /// [`SwitchError::Transform`] when it could not be prepared.
    pub fn apply_transform(
        &mut self,
        p: PreparedTransform,
        now: Micros,
    ) -> Result<(), SwitchError> {
        if p.epoch != self.transforms.epoch {
            return Ok(());
        }
        let Some(pending) = self.transforms.pending.take() else {
            return Ok(());
        };
        match p.plan {
            Err(e) => {
                let why = SwitchError::Transform(e);
                self.formation_failed(&pending.name, &why);
                Err(why)
            }
            Ok(plan) if plan.targets_m.len() != self.agents.len() => Ok(()),
            Ok(plan) => {
                self.start_transform(&plan, pending, now);
                Ok(())
            }
        }
    }

    fn start_transform(&mut self, plan: &TransformPlan, pending: PendingTransform, now: Micros) {
        if self.transforms.running.is_some() {
            self.end_transform(TransformOutcome::Superseded, now);
        }
        self.transforms.remeshing = None;
        self.transforms.remesh_outbox = None;
        let s = &self.transforms.settings;
        let mut params = s.moves.clone().with_radius(self.agent_params.radius_m);
        if let Some(d) = pending.duration_s {
            let far = self
                .agents
                .positions()
                .iter()
                .zip(&plan.targets_m)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            params.desired_speed_m_s =
                (far / d).clamp(MIN_DESIRED_SPEED_M_S, MAX_DESIRED_SPEED_M_S);
            params.timeout_s = params.timeout_s.max(3.0 * d);
        }
        let seed = 0x5eed_7a45 ^ self.transforms.started;
        let run = TransformRun::new(plan, &params, seed);
        log::info!(
            "transform to `{}`: {} agents, {} cost, {} subgroups, {:.2} m/s",
            pending.name,
            plan.targets_m.len(),
            s.cost_name,
            plan.subgroups.count(),
            params.desired_speed_m_s
        );
        self.transforms.running = Some(RunningTransform {
            name: Arc::from(pending.name.as_str()),
            checkpoint: pending.checkpoint,
            run,
            subgroups: plan.subgroups.count() as u32,
            agent_subgroups: Arc::new(plan.subgroups.group_of.clone()),
            cost_name: s.cost_name,
            speed_m_s: params.desired_speed_m_s,
            last: StepReport::default(),
            owed_s: 0.0,
        });
        self.transforms.started += 1;
        // The pairing is the goals now: identity over the targets; assignment
        // results for the old goals are stale.
        self.goal_of.clear();
        self.goal_of.extend(0..self.agents.len() as u32);
        self.waypoints.fill(Vec2::repeat(f64::NAN));
        self.forget_assignments();
        self.assignment_seq = self.seq;
    }

    /// One tick of a transform: the run steps the agents and a progress message is
    /// made; at its end the summary goes out and the mesh is asked for. After a
    /// run, agents hold while the mesh is rebuilt. Returns false when no transform
    /// drives the agents.
    pub(super) fn step_transform(&mut self, dt: f64, now: Micros) -> bool {
        if let Some(rm) = &self.transforms.remeshing {
            if !self.paused {
                match &self.scene {
                    Some(scene) => {
                        let scene = scene.at(self.scene_t_s, &mut self.scene_placements);
                        self.agents.step_over(
                            &rm.hold,
                            &mut self.terrain,
                            |x| scene.terrain_at(x),
                            |g| g.speed_factor,
                            dt,
                            &self.agent_params,
                        );
                    }
                    None => self
                        .agents
                        .step_towards(&rm.hold, |_| 1.0, dt, &self.agent_params),
                }
            }
            return true;
        }
        let Some(r) = &mut self.transforms.running else {
            return false;
        };
        if !self.paused && dt > 0.0 {
            r.owed_s += dt;
            if r.owed_s >= MIN_TRANSFORM_STEP_S {
                let scene = self.scene.as_deref().map(|s| (s, self.scene_t_s));
                let (pos, vel) = self.agents.state_mut();
                r.last = r.run.step(pos, vel, r.owed_s, scene);
                r.owed_s = 0.0;
            }
        }
        let mut view = self.transforms.views.acquire();
        {
            let v = Arc::make_mut(&mut view);
            v.formation = Arc::clone(&r.name);
            v.method = FormationMethod::Transform.as_str();
            v.cost = r.cost_name;
            v.seq = self.seq;
            v.progress = r.last.arrived_fraction;
            v.elapsed_s = r.run.elapsed_s();
            v.measures = measures(&r.last.measures);
            v.min_distance_m = r.last.min_distance_m;
            v.overlapping_pairs = r.last.overlapping_pairs as u32;
            v.subgroups = r.subgroups;
            v.agent_subgroups = Arc::clone(&r.agent_subgroups);
            v.speed_m_s = r.speed_m_s;
        }
        self.transforms.views.keep(&view);
        self.transforms.view = Some(view);
        if r.run.done() {
            let outcome = if r.run.summary().timed_out {
                TransformOutcome::TimedOut
            } else {
                TransformOutcome::Arrived
            };
            self.end_transform(outcome, now);
        }
        true
    }

    /// Ends the running transform: its summary goes out with this tick; after an
    /// arrival or the timeout the agents hold on their targets and the mesh is
    /// rebuilt there, after a touch where they are; when superseded or dropped
    /// nothing more.
    pub(super) fn end_transform(&mut self, outcome: TransformOutcome, now: Micros) {
        let Some(r) = self.transforms.running.take() else {
            return;
        };
        let summary = Arc::new(summary(&r, &r.run.summary(), outcome));
        log::info!(
            "transform to `{}` {}: {:.0} % arrived in {:.1} s, min distance {:.3} m",
            r.name,
            outcome.as_str(),
            100.0 * summary.arrived_fraction,
            summary.simulated_s,
            summary.min_distance_m
        );
        self.transforms.ended = Some(Arc::clone(&summary));
        self.transforms.last = Some(summary);
        let (hold, announce) = match outcome {
            TransformOutcome::Arrived | TransformOutcome::TimedOut => (
                r.run.targets().to_vec(),
                Some((r.name.to_string(), r.checkpoint)),
            ),
            TransformOutcome::Touched => {
                // In no library formation from now on: any formation may be asked for.
                self.formation_name.clear();
                self.formation_name.push_str(TOUCHED_FORMATION);
                (self.agents.positions().to_vec(), None)
            }
            TransformOutcome::Superseded | TransformOutcome::Dropped => return,
        };
        let req = RemeshRequest {
            epoch: self.transforms.epoch,
            agents: hold.clone(),
            parts: Vec::new(),
            radius_m: self.agent_params.radius_m,
            min_piece_agents: 0,
        };
        self.transforms.remeshing = Some(Remeshing { announce, hold });
        if self.transforms.inline {
            self.apply_transform_remesh(req.prepare(), now);
        } else {
            self.transforms.remesh_outbox = Some(req);
        }
    }

    /// Installs the mesh rebuilt after a transform: agent `i`'s goal is its own
    /// vertex (its target, or where a touch stopped it), a `formation` event says
    /// the crowd is in the new formation, and the running assignment takes over.
    pub fn apply_transform_remesh(&mut self, p: PreparedRemesh, now: Micros) {
        if p.epoch != self.transforms.epoch || self.transforms.remeshing.is_none() {
            return;
        }
        let Some(rm) = self.transforms.remeshing.take() else {
            return;
        };
        match p.built {
            Ok((mesh, samples)) if samples.len() == self.agents.len() => {
                let identity: Vec<u32> = (0..self.agents.len() as u32).collect();
                self.install(mesh, samples, &identity);
                if let Some((name, checkpoint)) = rm.announce {
                    if checkpoint.is_some() {
                        self.counters.formation_switches += 1;
                    }
                    self.switched(name, checkpoint, now);
                }
            }
            Ok(_) => log::warn!("transform: the crowd changed size; the mesh stays"),
            Err(e) => log::warn!("transform: no mesh around the crowd ({e}); the mesh stays"),
        }
    }

    /// A touch landed on the crowd during a transform: the run ends and direct
    /// control resumes from where the agents are.
    pub(super) fn touch_transform(&mut self, now: Micros) {
        if self.transforms.running.is_some() {
            self.end_transform(TransformOutcome::Touched, now);
        }
    }

    /// Drops transforms asked for, running or being rebuilt (a reset, a resize, a
    /// mesh switch): a running one ends with `outcome`.
    pub(super) fn drop_transforms(&mut self, outcome: TransformOutcome, now: Micros) {
        self.end_transform(outcome, now);
        let t = &mut self.transforms;
        t.epoch += 1;
        t.pending = None;
        t.outbox = None;
        t.remesh_outbox = None;
        t.remeshing = None;
    }

    /// The formation a recognised gesture class starts (`formations.gestures`).
    pub(super) fn gesture_formation(&self, class: &str) -> Option<String> {
        self.transforms
            .settings
            .gestures
            .iter()
            .find(|(c, _)| c == class)
            .map(|(_, f)| f.clone())
    }

    /// The goals the snapshot shows while a transform drives the agents.
    pub(super) fn transform_goals(&self) -> Option<&[Vec2]> {
        let t = &self.transforms;
        match (&t.running, &t.remeshing) {
            (Some(r), _) => Some(r.run.targets()),
            (None, Some(rm)) => Some(&rm.hold),
            (None, None) => None,
        }
    }
}

/// The formation name after a touch ended a transform: the crowd is in no library
/// formation.
pub const TOUCHED_FORMATION: &str = "touched";

fn measures(m: &crate::crowd::transform::Measures) -> TransformMeasures {
    TransformMeasures {
        i_d: m.i_d,
        sigma_min_dis_m: m.sigma_min_dis_m,
        sigma_curr_eft_m: m.sigma_curr_eft_m,
    }
}

fn summary(r: &RunningTransform, s: &RunSummary, outcome: TransformOutcome) -> TransformSummary {
    TransformSummary {
        formation: r.name.to_string(),
        cost: r.cost_name.to_string(),
        outcome,
        agents: s.agents as u32,
        steps: s.steps,
        simulated_s: s.simulated_s,
        arrived_fraction: s.arrived_fraction,
        min_distance_m: s.min_distance_m,
        overlapping_pairs: s.overlapping_pairs as u64,
        swaps: s.swaps,
        mean_travel_m: s.mean_travel_m,
        max_travel_m: s.max_travel_m,
        mean: measures(&s.mean),
        subgroups: r.subgroups,
        speed_m_s: r.speed_m_s,
    }
}
