//! The control thread: takes frames, commands and reloads, ticks the engine, hands
//! slow work to the workers and publishes every tick's snapshot to the outputs.

use super::client_touch::ClientTouches;
use super::queue::InputCounters;
use super::timing::StageTimer;
use super::workers::{AssignJob, FormationDone, FormationJob, Freshness};
use crate::config::Config;
use crate::crowd::environment::Planner;
use crate::engine::Engine;
use crate::publish::{Outgoing, Outputs};
use crate::rt::monotonic_now;
use crate::vocab::{
    ClientId, Command, CommandRequest, Event, Micros, TouchFrame, TransformSummary,
};
use crossbeam_channel::{never, select, Receiver, Sender, TryRecvError, TrySendError};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// The "client" id of commands the daemon sends itself (replay resets).
pub const INTERNAL_CLIENT: u64 = 0;

/// Most `set_agent_count` commands waiting for their resize to be applied; a
/// further one is refused as busy until the resize is in.
pub const MAX_RESIZE_WAITERS: usize = 64;

/// Budget of the abandonment of a stale job (µs): from the command that made it
/// stale to the worker giving it up.
pub const ABANDON_BUDGET_US: u64 = 50_000;

/// Budget of a gesture command on the worker: recognition, blending, synthesis
/// and assignment (µs; issue figure: 20 ms at 1,000 agents).
pub const GESTURE_BUDGET_US: u64 = 20_000;

/// Budget of preparing a formation transform on the formation thread: sampling,
/// triangulations, pairing and subgroups (µs; issue 16 figure: 300 ms at 2,000
/// agents).
pub const TRANSFORM_PREPARE_BUDGET_US: u64 = 300_000;

/// The control thread's figures for one stats interval.
#[derive(Clone, Debug, Default)]
pub struct ControlStats {
    /// When.
    pub t: Micros,
    /// Stages timed on the control thread, with their histograms for the interval.
    pub stages: Vec<StageTimer>,
    /// Ticks since start.
    pub ticks: u64,
    /// Assignments applied since start.
    pub assignments: u64,
    /// Agents.
    pub agents: u32,
    /// Live controls.
    pub controls: u32,
    /// Most recent control or gesture.
    pub last_gesture: Option<String>,
    /// The formation the crowd is in.
    pub formation: String,
    /// Formation switches at checkpoints since start.
    pub formation_switches: u64,
    /// Messages to the publisher dropped because its queue was full.
    pub publish_overflow: u64,
    /// Formation transforms started since start.
    pub transforms: u64,
    /// The last transform that ended, summarised.
    pub last_transform: Option<TransformSummary>,
}

/// A reload on its way to the control thread: the config, and what was prepared
/// for its scene off the control thread.
pub(super) struct Reload {
    pub(super) cfg: Config,
    /// With inline assignment and a changed scene: the new scene's planner.
    pub(super) planner: Option<Planner>,
    /// `crowd.agents` when the reload changed it: the crowd is resized as the
    /// `set_agent_count` command does.
    pub(super) agents: Option<u32>,
}

pub(super) struct ControlChannels {
    pub(super) frames: Receiver<TouchFrame>,
    pub(super) commands: Receiver<CommandRequest>,
    pub(super) reload: Receiver<Box<Reload>>,
    pub(super) out: Outputs,
    pub(super) stats: Sender<ControlStats>,
    pub(super) jobs: Sender<Box<AssignJob>>,
    pub(super) results: Receiver<Box<AssignJob>>,
    pub(super) formation: Sender<FormationJob>,
    pub(super) prepared: Receiver<FormationDone>,
}

pub(super) struct ControlLoop {
    engine: Engine,
    ch: ControlChannels,
    stop: Arc<AtomicBool>,
    heartbeat_us: Arc<AtomicU64>,
    period: Micros,
    stats_interval: Micros,
    worker: bool,
    idle_job: Option<Box<AssignJob>>,
    /// A formation switch request the formation thread had no room for yet.
    switch_out: Option<FormationJob>,
    /// A resize request the formation thread had no room for yet.
    resize_out: Option<FormationJob>,
    /// Gesture work the formation thread had no room for yet.
    gesture_out: Option<FormationJob>,
    /// A transform (or the mesh after one) the formation thread had no room for yet.
    transform_out: Option<FormationJob>,
    /// An edit job (a drag, a release) waiting for room on the formation queue.
    edit_out: Option<FormationJob>,
    /// An edit file job (`edit.load`, `edit.save`) waiting for room.
    edit_file_out: Option<FormationJob>,
    /// A `library collect` job waiting for room.
    collect_out: Option<FormationJob>,
    /// Set once a `library collect` session has finished.
    collect_finished: Arc<AtomicBool>,
    /// `set_agent_count` commands acknowledged once their resize is applied.
    resize_waiters: Vec<(ClientId, serde_json::Value)>,
    /// What the workers poll to give up stale jobs.
    fresh: Arc<Freshness>,
    t_input: StageTimer,
    t_queue: StageTimer,
    t_control: StageTimer,
    t_assign: StageTimer,
    t_abandon: StageTimer,
    t_gesture: StageTimer,
    t_transform: StageTimer,
    last_stats: Micros,
    last_gesture: Option<String>,
    publish_overflow: u64,
    /// Touches sent by clients (`touch` commands).
    client_touches: ClientTouches,
}

impl ControlLoop {
    pub(super) fn new(
        cfg: &Config,
        engine: Engine,
        ch: ControlChannels,
        stop: Arc<AtomicBool>,
        heartbeat_us: Arc<AtomicU64>,
        fresh: Arc<Freshness>,
        input_counters: Arc<InputCounters>,
    ) -> ControlLoop {
        let b = &cfg.pipeline.budgets;
        let n = engine.agent_count();
        let job = AssignJob {
            agents: Vec::with_capacity(n),
            goals: Vec::with_capacity(n),
            goal_of: Vec::with_capacity(n),
            waypoints: Vec::with_capacity(n),
            ..AssignJob::default()
        };
        ControlLoop {
            engine,
            ch,
            stop,
            heartbeat_us,
            period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
            stats_interval: Micros(cfg.pipeline.stats_interval_ms * 1000),
            worker: cfg.assignment.worker,
            idle_job: Some(Box::new(job)),
            switch_out: None,
            resize_out: None,
            gesture_out: None,
            transform_out: None,
            edit_out: None,
            edit_file_out: None,
            collect_out: None,
            collect_finished: Arc::new(AtomicBool::new(false)),
            resize_waiters: Vec::with_capacity(MAX_RESIZE_WAITERS),
            fresh,
            t_input: StageTimer::new("input", b.input_us),
            t_queue: StageTimer::new("queue", b.queue_us),
            t_control: StageTimer::new("control", b.control_us),
            t_assign: StageTimer::new("assignment", b.assignment_us),
            t_abandon: StageTimer::new("abandon", ABANDON_BUDGET_US),
            t_gesture: StageTimer::new("gesture", GESTURE_BUDGET_US),
            t_transform: StageTimer::new("transform_prepare", TRANSFORM_PREPARE_BUDGET_US),
            last_stats: monotonic_now(),
            last_gesture: None,
            publish_overflow: 0,
            client_touches: ClientTouches::new(input_counters),
        }
    }

    /// Where the loop says that a `library collect` session has finished.
    pub(super) fn with_collect_flag(mut self, flag: Arc<AtomicBool>) -> ControlLoop {
        self.collect_finished = flag;
        self
    }

    pub(super) fn run(mut self) {
        let mut frames = self.ch.frames.clone();
        let mut next_tick = monotonic_now() + self.period;
        while !self.stop.load(Ordering::Relaxed) {
            let timeout = next_tick.saturating_since(monotonic_now());
            let mut input = false;
            select! {
                recv(frames) -> msg => match msg {
                    Ok(f) => { self.take_frame(&f); input = true; }
                    // Every input has ended: keep ticking on the timer.
                    Err(_) => frames = never(),
                },
                recv(self.ch.commands) -> msg => if let Ok(c) = msg { self.command(c) },
                recv(self.ch.reload) -> msg => if let Ok(r) = msg { self.reconfigure(*r) },
                default(Duration::from_micros(timeout.0)) => {}
            }
            loop {
                match frames.try_recv() {
                    Ok(f) => {
                        self.take_frame(&f);
                        input = true;
                    }
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => {
                        frames = never();
                        break;
                    }
                }
            }
            while let Ok(c) = self.ch.commands.try_recv() {
                self.command(c);
            }
            let now = monotonic_now();
            let engine = &mut self.engine;
            self.client_touches
                .expire(now, &mut |f| engine.push_frame(f));
            if input || now >= next_tick {
                self.tick(now);
                next_tick = now + self.period;
            }
            self.publish_freshness();
        }
        // Shutdown: end every control and publish the final state.
        let now = monotonic_now();
        self.engine.reset(false, now);
        self.tick(now);
    }

    fn take_frame(&mut self, f: &TouchFrame) {
        let now = monotonic_now();
        self.t_input.record(f.t_queued.saturating_since(f.t).0);
        self.t_queue.record(now.saturating_since(f.t_queued).0);
        self.engine.push_frame(f);
    }

    /// Tells the workers what is current, so they give up stale jobs.
    fn publish_freshness(&self) {
        self.fresh.update(
            self.engine.generation(),
            self.engine.switch_epoch(),
            self.engine.resize_ticket(),
            self.engine.transform_epoch(),
        );
    }

    fn command(&mut self, req: CommandRequest) {
        if let Command::Touch { contacts } = &req.command {
            let engine = &mut self.engine;
            let result =
                self.client_touches
                    .touch(req.client, contacts, monotonic_now(), &mut |f| {
                        engine.push_frame(f)
                    });
            // Sent by the socket for a client that left: nobody to answer.
            if req.id.is_null() {
                return;
            }
            self.send(Outgoing::Reply {
                client: req.client,
                id: req.id,
                result,
            });
            return;
        }
        let resize = matches!(req.command, Command::SetAgentCount { .. });
        if resize && self.resize_waiters.len() >= MAX_RESIZE_WAITERS {
            self.send(Outgoing::Reply {
                client: req.client,
                id: req.id,
                result: Err(format!(
                    "busy: {MAX_RESIZE_WAITERS} resizes are waiting to be applied; try again"
                )),
            });
            return;
        }
        let file = matches!(
            req.command,
            Command::EditLoad { .. } | Command::EditSave { .. }
        );
        if file && self.edit_file_out.is_some() {
            self.send(Outgoing::Reply {
                client: req.client,
                id: req.id,
                result: Err("busy: a track file is still being read or written; try again".into()),
            });
            return;
        }
        let result = self.engine.command(&req.command, monotonic_now());
        // edit.load and edit.save are answered when their file is read or written.
        if result.is_ok() {
            if let Some(job) = self.engine.take_edit_file_job() {
                self.edit_file_out = Some(FormationJob::EditFile {
                    job,
                    client: req.client,
                    id: req.id,
                });
                return;
            }
        }
        if req.client == INTERNAL_CLIENT {
            if let Err(e) = result {
                log::warn!("{:?} refused: {e}", req.command);
            }
            return;
        }
        if resize && result.is_ok() && self.engine.resize_pending() {
            // Resizes still waiting were superseded by this one: they will not be
            // applied.
            let count = match req.command {
                Command::SetAgentCount { count } => count,
                _ => 0,
            };
            self.answer_resize_waiters(Err(format!(
                "superseded: a later set_agent_count ({count}) replaced it before it was applied"
            )));
            // Acknowledged when applied (`tick`), a few ticks from now.
            self.resize_waiters.push((req.client, req.id));
            return;
        }
        self.send(Outgoing::Reply {
            client: req.client,
            id: req.id,
            // The client reads the refusal's message in its `error` reply.
            result: result.map_err(|e| e.to_string()),
        });
    }

    /// Answers every `set_agent_count` waiting for its resize (keeps the list's
    /// capacity).
    fn answer_resize_waiters(&mut self, result: Result<(), String>) {
        let mut waiters = std::mem::take(&mut self.resize_waiters);
        for (client, id) in waiters.drain(..) {
            self.send(Outgoing::Reply {
                client,
                id,
                result: result.clone(),
            });
        }
        self.resize_waiters = waiters;
    }

    /// Applies a reload's config (the daemon kept its restart fields at their
    /// running values, so the engine ignores none) and logs nothing: the
    /// supervisor's line says what the reload did.
    fn reconfigure(&mut self, reload: Reload) {
        let Reload {
            cfg,
            planner,
            agents,
        } = reload;
        let cfg = &cfg;
        let ignored = self.engine.reconfigure_with(cfg, planner);
        if !ignored.is_empty() {
            log::error!(
                "internal bug: a reload reached the engine with restart fields changed: {}",
                ignored.join(", ")
            );
        }
        let b = &cfg.pipeline.budgets;
        self.t_input.set_budget(b.input_us);
        self.t_queue.set_budget(b.queue_us);
        self.t_control.set_budget(b.control_us);
        self.t_assign.set_budget(b.assignment_us);
        self.period = Micros((1e6 / cfg.pipeline.tick_hz) as u64);
        self.stats_interval = Micros(cfg.pipeline.stats_interval_ms * 1000);
        if let Some(count) = agents {
            // The path a client's `set_agent_count` takes.
            self.command(CommandRequest {
                client: INTERNAL_CLIENT,
                id: serde_json::Value::Null,
                command: Command::SetAgentCount { count },
            });
        }
    }

    fn send(&mut self, m: Outgoing) {
        for _ in 0..self.ch.out.send(m) {
            self.publish_overflow += 1;
            if self.publish_overflow.is_power_of_two() {
                log::warn!("publisher queue full: {} messages dropped (internal: publisher thread stalled)", self.publish_overflow);
            }
        }
    }

    fn tick(&mut self, now: Micros) {
        let start = monotonic_now();
        while let Ok(job) = self.ch.results.try_recv() {
            if job.ok {
                self.engine
                    .apply_plan(job.generation, job.seq, &job.goal_of, &job.waypoints);
            }
            if job.abandoned {
                self.t_abandon.record(job.abandon_us);
            } else {
                self.t_assign.record(job.solve_us);
            }
            self.idle_job = Some(job);
        }
        while let Ok(done) = self.ch.prepared.try_recv() {
            match done {
                // A switch that could not be built is logged and counted by the engine.
                FormationDone::Switch(p) => {
                    let _ = self.engine.apply_switch(*p, now);
                }
                FormationDone::Resize(p) => {
                    if self.engine.apply_resize(*p, now) && !self.engine.resize_pending() {
                        self.answer_resize_waiters(Ok(()));
                    }
                }
                FormationDone::Gesture(p, us) => {
                    self.t_gesture.record(us);
                    self.engine.apply_gesture(*p, us, now);
                }
                FormationDone::Remesh(p) => self.engine.apply_remesh(*p, now),
                FormationDone::Window(p) => self.engine.apply_window(*p, now),
                FormationDone::Transform(p, us) => {
                    self.t_transform.record(us);
                    // One that could not be prepared is logged and counted by the engine.
                    let _ = self.engine.apply_transform(*p, now);
                }
                FormationDone::TransformRemesh(p) => self.engine.apply_transform_remesh(*p, now),
                FormationDone::Edit(d) => self.engine.apply_edit(*d, now),
                FormationDone::Collected(d) => self.engine.apply_collect(*d, now),
                FormationDone::EditLoaded {
                    epoch,
                    result,
                    entry,
                    client,
                    id,
                } => {
                    let result = result.map(|set| {
                        let _ = self.engine.apply_edit_load(epoch, *set, &entry, now);
                    });
                    if result.is_err() {
                        self.engine.edit_load_failed(epoch);
                    }
                    self.send(Outgoing::Reply { client, id, result });
                }
                FormationDone::EditSaved { result, client, id } => {
                    self.send(Outgoing::Reply { client, id, result });
                }
                FormationDone::Abandoned(us) => {
                    self.t_abandon.record(us);
                }
            }
        }
        let out = self.engine.tick(now);
        let snapshot = out.snapshot;
        let mesh = out.mesh;
        let plan = out.plan;
        let transform = out.transform;
        let transform_end = out.transform_end;
        let out_tracks = out.tracks;
        let out_edit = out.edit;
        let scene = out.scene;
        let scene_poses = out.scene_poses;
        let mut describe = None;
        let events: Vec<Arc<Event>> = out.events.iter().cloned().map(Arc::new).collect();
        for e in &events {
            if let Some(d) = describe_event(e) {
                describe = Some(d);
            }
        }
        self.engine.clear_events();
        if let Some(d) = describe {
            self.last_gesture = Some(d);
        }
        for e in events {
            self.send(Outgoing::Event(e));
        }
        if let Some(m) = mesh {
            self.send(Outgoing::Mesh(m));
        }
        if let Some(p) = plan {
            self.send(Outgoing::Plan(p));
        }
        if let Some(t) = transform {
            self.send(Outgoing::Transform(t));
        }
        if let Some(t) = transform_end {
            self.send(Outgoing::TransformEnd(t));
        }
        if let Some(t) = out_tracks {
            self.send(Outgoing::Tracks(t));
        }
        if let Some(e) = out_edit {
            self.send(Outgoing::Edit(e));
        }
        if let Some(s) = scene {
            self.send(Outgoing::Scene(s));
        }
        if let Some(p) = scene_poses {
            self.send(Outgoing::ScenePoses(p));
        }
        self.send(Outgoing::Snapshot(snapshot));
        // What is current goes out before any job does: a worker that takes a job
        // sees it as current unless something superseded it since.
        self.publish_freshness();
        // A formation switch or resize asked for by this tick or a command before
        // it (a newer one replaces one still waiting here).
        if let Some(r) = self.engine.take_switch_request() {
            self.switch_out = Some(FormationJob::Switch(Box::new(r)));
        }
        if let Some(r) = self.engine.take_resize_request() {
            self.resize_out = Some(FormationJob::Resize(Box::new(r)));
        }
        if self.gesture_out.is_none() {
            self.gesture_out = self
                .engine
                .take_gesture_job()
                .map(|j| FormationJob::Gesture(Box::new(j)));
        }
        // A newer transform request replaces one still waiting here (the mesh after
        // a run is asked for after its run's request was taken).
        if let Some(r) = self.engine.take_transform_request() {
            self.transform_out = Some(FormationJob::Transform(Box::new(r)));
        } else if self.transform_out.is_none() {
            self.transform_out = self
                .engine
                .take_transform_remesh()
                .map(|r| FormationJob::TransformRemesh(Box::new(r)));
        }
        if self.edit_out.is_none() {
            self.edit_out = self
                .engine
                .take_edit_job()
                .map(|j| FormationJob::Edit(Box::new(j)));
        }
        if self.collect_out.is_none() {
            self.collect_out = self
                .engine
                .take_collect_job()
                .map(|j| FormationJob::Collect(Box::new(j)));
        }
        if self.engine.collect_finished() && self.collect_out.is_none() {
            self.collect_finished.store(true, Ordering::Relaxed);
        }
        for slot in [
            &mut self.collect_out,
            &mut self.edit_file_out,
            &mut self.edit_out,
            &mut self.transform_out,
            &mut self.gesture_out,
            &mut self.switch_out,
            &mut self.resize_out,
        ] {
            if let Some(job) = slot.take() {
                if let Err(TrySendError::Full(job)) = self.ch.formation.try_send(job) {
                    *slot = Some(job);
                }
            }
        }
        // While a transform drives the agents its pairing is theirs: no solve.
        // In edit mode the crowd is the tracks' people: nothing to assign.
        if self.worker && !self.engine.transform_running() && !self.engine.editing() {
            if let Some(mut job) = self.idle_job.take() {
                job.generation = self.engine.generation();
                job.seq = self.engine.seq();
                job.t_scene_s = self.engine.scene_time_s();
                let params = self.engine.planner_params();
                match (self.engine.scene(), &mut job.environment) {
                    // The same scene as the last job: no reference count traffic.
                    (Some(s), Some((js, jp))) if Arc::ptr_eq(s, js) => *jp = params,
                    (s, env) => *env = s.map(|s| (Arc::clone(s), params)),
                }
                job.agents.clear();
                job.agents.extend_from_slice(self.engine.agent_positions());
                job.goals.clear();
                job.goals.extend_from_slice(self.engine.goals());
                match self.ch.jobs.try_send(job) {
                    Ok(()) => {}
                    Err(TrySendError::Full(j)) | Err(TrySendError::Disconnected(j)) => {
                        self.idle_job = Some(j)
                    }
                }
            }
        }
        let end = monotonic_now();
        self.t_control.record(end.saturating_since(start).0);
        self.heartbeat_us.store(end.0, Ordering::Relaxed);
        if end.saturating_since(self.last_stats) >= self.stats_interval {
            self.last_stats = end;
            let c = self.engine.counters();
            let cs = ControlStats {
                t: end,
                // Once per interval: the histograms are copied (an allocation the
                // control thread allows itself at this rate) and restarted.
                stages: [
                    &mut self.t_input,
                    &mut self.t_queue,
                    &mut self.t_control,
                    &mut self.t_assign,
                    &mut self.t_abandon,
                    &mut self.t_gesture,
                    &mut self.t_transform,
                ]
                .into_iter()
                .map(|t| {
                    let copy = t.clone();
                    t.take();
                    copy
                })
                .collect(),
                ticks: c.ticks,
                assignments: c.assignments,
                agents: self.engine.agent_count() as u32,
                controls: self.engine.control_count() as u32,
                last_gesture: self.last_gesture.clone(),
                formation: self.engine.formation().to_string(),
                formation_switches: c.formation_switches,
                publish_overflow: self.publish_overflow,
                transforms: self.engine.transforms_started(),
                last_transform: self.engine.last_transform().map(|s| (**s).clone()),
            };
            let _ = self.ch.stats.try_send(cs);
        }
    }
}

fn describe_event(e: &Event) -> Option<String> {
    match e {
        Event::ControlBegin { kind, fingers, .. } | Event::ControlUpdate { kind, fingers, .. } => {
            Some(format!(
                "{} control, {} finger{}",
                kind.as_str(),
                fingers.len(),
                if fingers.len() == 1 { "" } else { "s" }
            ))
        }
        Event::GestureEnd {
            fingers,
            duration_us,
            ..
        } => Some(format!(
            "gesture, {} finger{}, {:.1} s",
            fingers,
            if *fingers == 1 { "" } else { "s" },
            *duration_us as f64 * 1e-6
        )),
        _ => None,
    }
}
