//! The daemon: starts every thread with its queues, supervises them (stats, reloads,
//! the watchdog's heartbeat) and stops them in order.

use super::control::{ControlChannels, ControlLoop, ControlStats, Reload, INTERNAL_CLIENT};
use super::device;
use super::error::Error;
use super::outputs::{register_outputs, Registered};
use super::queue::{FrameQueue, InputCounters};
use super::reload;
use super::report::{self, DeviceBoard};
use super::sources::SourceSpec;
use super::timing::StageTimer;
use super::workers::{
    assignment_worker, formation_worker, AssignJob, FormationDone, FormationJob, Freshness,
};
use crate::config::Config;
use crate::crowd::environment::{PlannerParams, Scene};
use crate::engine::Engine;
use crate::input::replay::{Pacing, ReplaySource};
use crate::input::FrameSink;
use crate::publish::{ClientLimit, PublisherStats};
use crate::publish::{HelloInfo, Outgoing, OutputContext, OutputSet, OutputStats, Outputs};
use crate::rt::monotonic_now;
use crate::vocab::{
    Command, CommandRequest, Event, Micros, RestartPending, StageStats, StatsReport, TouchFrame,
};
use crossbeam_channel::{bounded, Receiver, Sender};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// Commands in flight from clients to the control thread.
pub const COMMAND_CAPACITY: usize = 64;

/// Longest [`Daemon::shutdown`] waits for its threads (ms). Every thread of the
/// daemon stops well within it (workers give up their job at once, inputs check
/// their stop flag at least every 100 ms); one that has not is named in the log and
/// left to the process exit, so a SIGTERM is answered within a second in any state.
pub const SHUTDOWN_BUDGET_MS: u64 = 700;

/// Options of a daemon run.
pub struct DaemonOptions {
    /// Socket path (already resolved).
    pub socket_path: PathBuf,
    /// A `library collect` session to run instead of gesture commands.
    pub collect: Option<crate::engine::CollectPlan>,
}

/// The running daemon: its threads and the handles the supervisor needs.
pub struct Daemon {
    stop: Arc<AtomicBool>,
    input_stop: Arc<AtomicBool>,
    /// What the workers poll to give up their job (stale or stopping).
    fresh: Arc<Freshness>,
    threads: Vec<(&'static str, JoinHandle<()>)>,
    socket_path: PathBuf,
    publisher: Arc<PublisherStats>,
    /// Every output's counters (the socket's among them).
    outputs: Vec<Arc<dyn OutputStats>>,
    input_counters: Arc<InputCounters>,
    /// Every TUIO input's counters, with the address it listens on (`stats`).
    tuio_inputs: Vec<(String, Arc<crate::input::tuio::TuioCounters>)>,
    /// Every `Device` input's last state (`stats`).
    devices: Arc<DeviceBoard>,
    /// Assignments applied at the previous report (`assignment_hz`).
    last_assignments: u64,
    heartbeat_us: Arc<AtomicU64>,
    /// Set by the control thread once a `library collect` session has finished.
    collect_finished: Arc<AtomicBool>,
    control_stats: Receiver<ControlStats>,
    out: Outputs,
    reload: Sender<Box<Reload>>,
    /// The config in effect: the last one loaded, with restart fields at the values
    /// the daemon started with. A reload is compared with it.
    config: Config,
    /// Restart fields whose file value differs from the running one (`stats`).
    restart_pending: Vec<RestartPending>,
    /// Every output's client limit (`socket.max_clients`).
    client_limits: Vec<ClientLimit>,
    scene: Option<Arc<Scene>>,
    planner_params: PlannerParams,
    inline_assignment: bool,
    e2e: StageTimer,
    encode: StageTimer,
    totals: Vec<StageTimer>,
    interval_us: u64,
    /// When the control thread made the figures of the previous report.
    last_report: Micros,
}

fn spawn(
    name: &'static str,
    f: impl FnOnce() + Send + 'static,
) -> Result<(&'static str, JoinHandle<()>), Error> {
    std::thread::Builder::new()
        .name(format!("ct-{name}"))
        .spawn(f)
        .map(|h| (name, h))
        .map_err(|source| Error::Thread { name, source })
}

/// What every thread is started with: the stop flags and the thread settings.
struct Start {
    threads: Vec<(&'static str, JoinHandle<()>)>,
    stop: Arc<AtomicBool>,
    input_stop: Arc<AtomicBool>,
    /// SCHED_FIFO priority for the latency-path threads (`None`: normal scheduling).
    priority: Option<u8>,
    input_cpus: Option<Vec<usize>>,
}

impl Drop for Start {
    /// A start that failed after some threads were started: stops and joins them,
    /// so nothing runs on and the socket (dropped with the publisher thread's
    /// `Server`) is removed. A start that succeeded has handed its threads on.
    fn drop(&mut self) {
        if self.threads.is_empty() {
            return;
        }
        self.input_stop.store(true, Ordering::SeqCst);
        self.stop.store(true, Ordering::SeqCst);
        for (_, h) in self.threads.drain(..) {
            let _ = h.join();
        }
    }
}

impl Start {
    fn spawn(
        &mut self,
        name: &'static str,
        f: impl FnOnce() + Send + 'static,
    ) -> Result<(), Error> {
        self.threads.push(spawn(name, f)?);
        Ok(())
    }

    /// Makes the calling thread real-time when configured.
    fn realtime(priority: Option<u8>, thread: &str) {
        if let Some(p) = priority {
            crate::rt::make_realtime(p, thread);
        }
    }
}

impl Daemon {
    /// Binds the socket and starts every thread: one input thread per source.
    /// With no source at all the daemon runs on its clients' touches (the
    /// socket's and the WebSocket outputs' `touch` commands): nothing reads a
    /// device.
    ///
    /// # Errors
    /// Socket problems ([`Error::Publish`]) and thread creation.
    pub fn start(
        cfg: Config,
        sources: Vec<SourceSpec>,
        opts: DaemonOptions,
    ) -> Result<Daemon, Error> {
        let glass = sources.iter().find_map(|s| match s {
            SourceSpec::Replay { glass_mm, .. } | SourceSpec::Channel { glass_mm, .. } => *glass_mm,
            SourceSpec::Device { transform, .. } | SourceSpec::Tuio { transform, .. } => {
                transform.size_mm
            }
        });
        let mut engine = Engine::new(&cfg, glass, !cfg.assignment.worker);
        engine.set_switch_worker(true);
        if let Some(plan) = opts.collect {
            engine.start_collecting(plan).map_err(Error::Collect)?;
        }
        let collect_finished = Arc::new(AtomicBool::new(false));
        let hello = HelloInfo {
            world: cfg.surface.world,
            agents: engine.agent_count() as u32,
            agent_radius_m: engine.agent_radius_m(),
        };
        let Registered {
            outputs,
            socket_path,
            publisher,
        } = register_outputs(&cfg, &opts.socket_path, hello)?;
        let output_stats = outputs.stats();
        let client_limits = outputs.client_limits();
        let rt = &cfg.pipeline.realtime;

        let mut start = Start {
            threads: Vec::new(),
            stop: Arc::new(AtomicBool::new(false)),
            input_stop: Arc::new(AtomicBool::new(false)),
            priority: rt.priority,
            input_cpus: rt.input_cpus.clone(),
        };
        let heartbeat_us = Arc::new(AtomicU64::new(monotonic_now().0));
        let input_counters = Arc::new(InputCounters::default());

        // Input → control: bounded(queue_frames); inputs try_send (FrameQueue policy),
        // control blocks in select with a tick timeout.
        let (frame_tx, frame_rx) = bounded::<TouchFrame>(cfg.pipeline.queue_frames as usize);
        // Clients → control: bounded(COMMAND_CAPACITY); outputs try_send and answer
        // "busy" when full; control drains with try_recv.
        let (cmd_tx, cmd_rx) = bounded::<CommandRequest>(COMMAND_CAPACITY);
        // Control ↔ worker: bounded(1) each way, exactly one job in flight; neither
        // side blocks on the other (control try_sends / try_recvs).
        let (job_tx, job_rx) = bounded::<Box<AssignJob>>(1);
        let (res_tx, res_rx) = bounded::<Box<AssignJob>>(1);
        // Control ⇄ formation thread: switch and resize requests, and what was made
        // of them, bounded(2) each way; the control side only try_sends (a request
        // that finds no room waits in the control loop, the newest of each kind
        // replacing an older one) and try_recvs; the formation thread blocks on its
        // own side.
        let (formation_tx, formation_rx) = bounded::<FormationJob>(2);
        let (prepared_tx, prepared_rx) = bounded::<FormationDone>(2);
        // Control → workers (and the shutdown → workers): what is current, polled
        // by the workers to give up stale jobs; atomics, nobody waits.
        let fresh = Arc::new(Freshness::default());
        // Control → supervisor: bounded(4) stats once per interval, try_send.
        let (cstats_tx, cstats_rx) = bounded::<ControlStats>(4);
        // Supervisor → control: bounded(1) config reloads, try_send.
        let (reload_tx, reload_rx) = bounded::<Box<Reload>>(1);

        if rt.lock_memory && crate::rt::lock_memory() {
            log::info!("memory locked");
        }
        // Control, supervisor and device threads → each output: its own bounded
        // queue and drop policy (publish::output); nobody blocks on an output.
        let out = start.spawn_outputs(outputs, &cmd_tx)?;
        if cfg.assignment.worker {
            let cost = crate::engine::point_metric(cfg.assignment.cost);
            let f = Arc::clone(&fresh);
            start.spawn("assign", move || assignment_worker(cost, job_rx, res_tx, f))?;
        }
        let f = Arc::clone(&fresh);
        start.spawn("formation", move || {
            formation_worker(formation_rx, prepared_tx, f)
        })?;
        let ctl = ControlLoop::new(
            &cfg,
            engine,
            ControlChannels {
                frames: frame_rx,
                commands: cmd_rx,
                reload: reload_rx,
                out: out.clone(),
                stats: cstats_tx,
                jobs: job_tx,
                results: res_rx,
                formation: formation_tx,
                prepared: prepared_rx,
            },
            Arc::clone(&start.stop),
            Arc::clone(&heartbeat_us),
            Arc::clone(&fresh),
            Arc::clone(&input_counters),
        )
        .with_collect_flag(Arc::clone(&collect_finished));
        let priority = start.priority;
        start.spawn("control", move || {
            Start::realtime(priority, "control");
            ctl.run()
        })?;
        let tuio_inputs: Vec<_> = sources
            .iter()
            .filter_map(|s| match s {
                SourceSpec::Tuio { source, .. } => Some((
                    source
                        .local_addr()
                        .map(|a| a.to_string())
                        .unwrap_or_default(),
                    source.counters(),
                )),
                _ => None,
            })
            .collect();
        let devices = Arc::new(DeviceBoard::new(sources.iter().filter_map(|s| match s {
            SourceSpec::Device { input, .. } => Some(*input),
            _ => None,
        })));
        for (i, source) in sources.into_iter().enumerate() {
            let queue = FrameQueue::new(frame_tx.clone(), i as u16, Arc::clone(&input_counters));
            start.spawn_input(source, queue, &cmd_tx, &out, &devices)?;
        }
        drop(frame_tx);
        let b = &cfg.pipeline.budgets;
        let scene = cfg.loaded_scene().cloned();
        let planner_params = crate::engine::planner_params(&cfg);
        let inline_assignment = !cfg.assignment.worker;
        let (e2e, encode) = (
            StageTimer::new("end_to_end", b.end_to_end_us),
            StageTimer::new("publish", b.publish_us),
        );
        let interval_us = cfg.pipeline.stats_interval_ms * 1000;
        Ok(Daemon {
            stop: Arc::clone(&start.stop),
            input_stop: Arc::clone(&start.input_stop),
            fresh,
            threads: std::mem::take(&mut start.threads),
            socket_path,
            publisher,
            outputs: output_stats,
            input_counters,
            tuio_inputs,
            devices,
            last_assignments: 0,
            heartbeat_us,
            collect_finished,
            control_stats: cstats_rx,
            out,
            reload: reload_tx,
            config: cfg,
            restart_pending: Vec::new(),
            client_limits,
            scene,
            planner_params,
            inline_assignment,
            e2e,
            encode,
            totals: Vec::new(),
            interval_us,
            last_report: monotonic_now(),
        })
    }

    /// The socket path clients connect to.
    pub fn socket_path(&self) -> &Path {
        &self.socket_path
    }

    /// The socket output's counters.
    pub fn publisher_stats(&self) -> &Arc<PublisherStats> {
        &self.publisher
    }

    /// Input counters.
    pub fn input_counters(&self) -> &Arc<InputCounters> {
        &self.input_counters
    }

    /// Whether a `library collect` session has asked for every motion and saved
    /// what was drawn.
    pub fn collect_finished(&self) -> bool {
        self.collect_finished.load(Ordering::Relaxed)
    }

    /// Time since the control thread last ticked.
    pub fn heartbeat_age(&self) -> Micros {
        monotonic_now().saturating_since(Micros(self.heartbeat_us.load(Ordering::Relaxed)))
    }

    /// Applies a newly loaded config (already validated, its scene loaded:
    /// [`Config::load`] reads and checks the scene file, so a broken scene never
    /// gets here and the running one stays) and logs one line saying what it did.
    ///
    /// The new config is compared with the one in effect
    /// ([`crate::config::plan_reload`]): live fields are applied — on the control
    /// thread (tunables, budgets, tick rate, the scene, `crowd.agents` as
    /// `set_agent_count` does), on the outputs (`socket.max_clients`) and here (the
    /// socket file's mode and group, the log level, the stats interval); restart
    /// fields keep their running values, are named in the log line with old → new,
    /// and are published in `stats` as `restart_pending` until the daemon restarts
    /// or the file goes back.
    ///
    /// Everything heavy about a new scene happens here, on the caller's thread,
    /// not on the control thread: comparing it with the running one (an unchanged
    /// scene keeps the running one, so nothing is swapped) and, with inline
    /// assignment, building its planner (rasterised scene, fast-marching
    /// workspaces). The assignment worker builds its own planner when its first
    /// job in the new scene arrives. The control thread only swaps the prepared
    /// parts in, between two ticks.
    pub fn reload(&mut self, cfg: Config) {
        let mut plan = crate::config::plan_reload(&self.config, cfg);
        let same = crate::engine::same_scene(plan.in_effect.loaded_scene(), self.scene.as_ref());
        if same {
            plan.in_effect.set_loaded_scene(self.scene.clone());
        }
        let cfg = &plan.in_effect;
        let params = crate::engine::planner_params(cfg);
        let planner = if self.inline_assignment && (!same || params != self.planner_params) {
            cfg.loaded_scene()
                .and_then(|s| crate::engine::planner_for(s, params))
        } else {
            None
        };
        let scene = cfg.loaded_scene().cloned();
        let change = (!same).then(|| describe_scene_change(cfg, self.scene.as_deref()));
        let agents = plan.applies("crowd.agents").then_some(cfg.crowd.agents);
        let reload = Reload {
            cfg: cfg.clone(),
            planner,
            agents,
        };
        if self.reload.try_send(Box::new(reload)).is_err() {
            log::warn!("config reload skipped: the previous reload is still being applied");
            return;
        }
        if let Some(c) = change {
            log::info!("{c}");
        }
        self.scene = scene;
        self.planner_params = params;
        let failed = reload::apply_socket_access(
            &self.socket_path,
            &self.config.socket,
            &mut plan.in_effect.socket,
        );
        let cfg = &plan.in_effect;
        for limit in &self.client_limits {
            limit.set(cfg.socket.max_clients);
        }
        reload::apply_log_level(cfg.log_level);
        self.e2e.set_budget(cfg.pipeline.budgets.end_to_end_us);
        self.encode.set_budget(cfg.pipeline.budgets.publish_us);
        self.interval_us = cfg.pipeline.stats_interval_ms * 1000;
        let path_changed = plan.changes.iter().any(|c| c.path == "scene");
        let (level, line) =
            reload::summary(&plan, &failed, !same && !path_changed, &self.socket_path);
        log::log!(level, "{line}");
        self.restart_pending = reload::pending(&plan, &self.socket_path);
        self.config = plan.in_effect;
    }

    /// Config fields changed in the file that wait for a restart (what `stats`
    /// publishes as `restart_pending`).
    pub fn restart_pending(&self) -> &[RestartPending] {
        &self.restart_pending
    }

    /// Waits up to `timeout` for the control thread's interval figures, merges them
    /// with the publisher's and publishes `stats`. Returns the report when one was made.
    pub fn next_report(&mut self, timeout: Duration) -> Option<Arc<StatsReport>> {
        let cs = self.control_stats.recv_timeout(timeout).ok()?;
        let now = monotonic_now();
        for o in &self.outputs {
            self.e2e.absorb(&o.take_end_to_end());
            self.encode.absorb(&o.take_encode());
        }
        let mut timers = cs.stages;
        timers.push(self.encode.clone());
        timers.push(self.e2e.clone());
        self.encode.take();
        self.e2e.take();
        for t in &timers {
            match self.totals.iter_mut().find(|x| x.name() == t.name()) {
                Some(total) => total.absorb(t.histogram()),
                None => self.totals.push(t.clone()),
            }
        }
        let stages: Vec<StageStats> = timers.iter().map(StageTimer::peek).collect();
        // The control thread's figures cover the time since its previous ones,
        // however late the supervisor reads them.
        let interval_us = cs.t.saturating_since(self.last_report).0.max(1);
        self.last_report = cs.t;
        let assignment_hz = report::rate_hz(cs.assignments, self.last_assignments, interval_us);
        self.last_assignments = cs.assignments;
        for s in &stages {
            if s.overruns > 0 {
                log::warn!(
                    "{} over its {} µs budget {} times in the last {:.1} s (p99 {} µs, max {} µs){}",
                    s.stage,
                    s.budget_us,
                    s.overruns,
                    interval_us as f64 * 1e-6,
                    s.p99_us,
                    s.max_us,
                    blame(&s.stage)
                );
            }
        }
        let report = Arc::new(StatsReport {
            t: now,
            interval_us,
            stages,
            frames: self.input_counters.frames.load(Ordering::Relaxed),
            frames_coalesced: self.input_counters.coalesced.load(Ordering::Relaxed),
            transitions_lost: self.input_counters.transitions_lost.load(Ordering::Relaxed),
            ticks: cs.ticks,
            assignments: cs.assignments,
            assignment_hz,
            snapshots_dropped: self.outputs.iter().map(|o| o.snapshots_dropped()).sum(),
            clients: self.outputs.iter().map(|o| o.clients()).sum(),
            agents: cs.agents,
            controls: cs.controls,
            rss_bytes: crate::pipeline::timing::rss_bytes(),
            last_gesture: cs.last_gesture,
            formation: cs.formation,
            formation_switches: cs.formation_switches,
            transforms: cs.transforms,
            last_transform: cs.last_transform,
            restart_pending: self.restart_pending.clone(),
            outputs: self
                .outputs
                .iter()
                .filter_map(|o| o.counters())
                .chain(self.tuio_inputs.iter().map(|(a, c)| c.report(a)))
                .collect(),
            touches: u64::from(self.input_counters.last_contact_id.load(Ordering::Relaxed)),
            devices: self.devices.snapshot(),
            histograms: self.totals.iter().map(report::stage_histogram).collect(),
        });
        self.out.send(Outgoing::Stats(Arc::clone(&report)));
        Some(report)
    }

    /// Stops every thread: the workers give up their job at once, then the inputs
    /// stop (their touches are cancelled), the control thread publishes a final
    /// snapshot, and the publisher says `bye`. Waits at most
    /// [`SHUTDOWN_BUDGET_MS`] in all; a thread still running then is named in the
    /// log and left behind (the process exit ends it).
    pub fn shutdown(mut self) {
        let t0 = monotonic_now();
        let deadline = t0 + Micros(SHUTDOWN_BUDGET_MS * 1000);
        self.fresh.stop();
        self.input_stop.store(true, Ordering::SeqCst);
        let (inputs, rest): (Vec<_>, Vec<_>) =
            self.threads.drain(..).partition(|(n, _)| *n == "input");
        let inputs_joined = join_by(inputs, deadline);
        // Let the control thread take the final frames before it stops.
        std::thread::sleep(Duration::from_micros(
            deadline.saturating_since(monotonic_now()).0.min(20_000),
        ));
        self.stop.store(true, Ordering::SeqCst);
        drop(self.out);
        if join_by(rest, deadline) && inputs_joined {
            log::info!(
                "shutdown: every thread stopped in {:.1} ms",
                monotonic_now().saturating_since(t0).0 as f64 / 1000.0
            );
        } else {
            // The publisher removes its socket file when it ends; one left running
            // past the budget must not leave the file behind for the next start.
            remove_socket_file(&self.socket_path);
        }
    }

    /// Every stage's figures since start (p50/p99/max over the whole run).
    pub fn totals(&self) -> Vec<StageStats> {
        self.totals.iter().map(StageTimer::peek).collect()
    }

    /// Stats interval (µs).
    pub fn interval_us(&self) -> u64 {
        self.interval_us
    }
}

/// One log line for a reload whose scene differs from the running `old` one.
fn describe_scene_change(cfg: &Config, old: Option<&Scene>) -> String {
    let old = match old {
        Some(o) => format!("scene \"{}\"", o.name()),
        None => "open ground".to_string(),
    };
    match (cfg.loaded_scene(), &cfg.scene) {
        (Some(new), path) => format!(
            "scene \"{}\" loaded{} ({} obstacles, {} patches, {} moving); it replaces {old} from the next tick",
            new.name(),
            path.as_ref()
                .map_or(String::new(), |p| format!(" from {}", p.display())),
            new.obstacles().len(),
            new.patches().len(),
            new.dynamic().len(),
        ),
        (None, _) => format!("no scene in the new config: open ground replaces {old} from the next tick"),
    }
}

/// Removes the socket file at `path` if a socket is there (nothing else is touched).
fn remove_socket_file(path: &Path) {
    use std::os::unix::fs::FileTypeExt;
    let is_socket = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_socket());
    if is_socket {
        if let Err(e) = std::fs::remove_file(path) {
            log::warn!("shutdown: could not remove {}: {e}", path.display());
        }
    }
}

/// Joins `threads` as they finish, until `deadline`; those still running then are
/// logged by name and detached. Returns whether every one was joined.
fn join_by(mut threads: Vec<(&'static str, JoinHandle<()>)>, deadline: Micros) -> bool {
    loop {
        let (done, running): (Vec<_>, Vec<_>) =
            threads.into_iter().partition(|(_, h)| h.is_finished());
        for (name, h) in done {
            if h.join().is_err() {
                log::error!("internal bug: the {name} thread panicked");
            }
        }
        if running.is_empty() {
            return true;
        }
        if monotonic_now() >= deadline {
            for (name, _) in &running {
                log::warn!(
                    "shutdown: the {name} thread did not stop within {SHUTDOWN_BUDGET_MS} ms; leaving it to the process exit"
                );
            }
            return false;
        }
        threads = running;
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Hands on whatever an input thread still holds back before its sink goes away.
pub(super) fn drain_backlog(queue: &mut FrameQueue, stop: &AtomicBool) {
    while !queue.flush() && !stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn blame(stage: &str) -> &'static str {
    match stage {
        "input" => " — input thread or device timestamps (device)",
        "queue" => " — control thread busy (internal: crowd too large for the budget?)",
        "control" => " — control tick (internal: crowd or mesh too large for the budget?)",
        "assignment" => " — assignment solver (internal: refresh rate drops, results stay exact)",
        "abandon" => " — a worker slow to give up a stale job (internal: system load, or a solve phase that does not poll)",
        "publish" => " — snapshot encoding (internal)",
        "end_to_end" => " — whole path (system load or a slow client)",
        _ => "",
    }
}

impl Start {
    /// One thread per output, reading its own queue; returns the sending side.
    fn spawn_outputs(
        &mut self,
        outputs: OutputSet,
        commands: &Sender<CommandRequest>,
    ) -> Result<Outputs, Error> {
        let (out, running) = outputs.connect();
        for (output, messages) in running {
            let ctx = OutputContext {
                messages,
                commands: commands.clone(),
                stop: Arc::clone(&self.stop),
            };
            let name = output.name();
            let priority = self.priority;
            self.spawn(name, move || {
                Start::realtime(priority, name);
                output.run(ctx)
            })?;
        }
        Ok(out)
    }

    /// The thread of one input source, handing frames to `queue`.
    fn spawn_input(
        &mut self,
        source: SourceSpec,
        mut queue: FrameQueue,
        commands: &Sender<CommandRequest>,
        out: &Outputs,
        board: &Arc<DeviceBoard>,
    ) -> Result<(), Error> {
        let stop = Arc::clone(&self.input_stop);
        let priority = self.priority;
        match source {
            SourceSpec::Replay {
                items,
                looped,
                gap,
                reset_between,
                ..
            } => {
                let mut src = ReplaySource::new(items, looped, gap, Pacing::RealTime);
                let cmd_tx = commands.clone();
                self.spawn("input", move || {
                    Start::realtime(priority, "input");
                    // Between any two items, the last and the first of a loop too.
                    let mut first = true;
                    let mut on_item = |_: usize| {
                        if reset_between && !std::mem::take(&mut first) {
                            let _ = cmd_tx.try_send(CommandRequest {
                                client: INTERNAL_CLIENT,
                                id: serde_json::Value::Null,
                                command: Command::Reset { hard: false },
                            });
                        }
                    };
                    src.run(&mut queue, &stop, &mut on_item);
                    drain_backlog(&mut queue, &stop);
                })
            }
            SourceSpec::Device {
                input,
                select,
                interface,
                grab,
                transform,
            } => {
                let out = out.clone();
                let board = Arc::clone(board);
                let cpus = self.input_cpus.clone();
                self.spawn("input", move || {
                    Start::realtime(priority, "input");
                    if let Some(cpus) = &cpus {
                        crate::rt::pin_to_cpus(cpus, "input");
                    }
                    let mut env = device::SystemEnv::new(Path::new("/"), grab);
                    let mut sink = device::TransformSink::new(queue, transform);
                    let mut notify = |n: device::DeviceNotice| {
                        let info = n.info.as_ref();
                        let node = info
                            .map(|i| i.identity.node.display().to_string())
                            .unwrap_or_default();
                        board.set(input, n.state, &node, n.message.as_deref());
                        let ev = Event::Device {
                            input,
                            state: n.state,
                            name: info.map(|i| i.identity.name.clone()).unwrap_or_default(),
                            node,
                            stable_id: info.map(|i| i.stable_id.clone()).unwrap_or_default(),
                            message: n.message,
                            t: n.t,
                        };
                        out.send(Outgoing::Event(Arc::new(ev)));
                    };
                    device::supervise(&mut env, &select, interface, &mut sink, &stop, &mut notify);
                    drain_backlog(sink.queue(), &stop);
                })
            }
            SourceSpec::Tuio {
                mut source,
                transform,
            } => {
                let cpus = self.input_cpus.clone();
                let who = match source.local_addr() {
                    Some(a) => format!("TUIO input on {a}"),
                    None => "TUIO input".to_string(),
                };
                log::info!("{who}: listening");
                self.spawn("input", move || {
                    Start::realtime(priority, "input");
                    if let Some(cpus) = &cpus {
                        crate::rt::pin_to_cpus(cpus, "input");
                    }
                    let mut sink = device::TransformSink::fixed(queue, transform, &who);
                    source.run(&mut sink, &stop);
                    drain_backlog(sink.queue(), &stop);
                })
            }
            SourceSpec::Channel { rx, .. } => self.spawn("input", move || {
                Start::realtime(priority, "input");
                while !stop.load(Ordering::Relaxed) {
                    let wait_ms = if queue.flush() { 50 } else { 1 };
                    match rx.recv_timeout(Duration::from_millis(wait_ms)) {
                        Ok(f) => queue.push(&f),
                        Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                        Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
                    }
                }
                drain_backlog(&mut queue, &stop);
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_start_that_fails_after_binding_stops_its_threads_and_removes_the_socket() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.sock");
        let cfg = Config::embedded_default();
        let hello = HelloInfo {
            world: cfg.surface.world,
            agents: 1,
            agent_radius_m: cfg.crowd.agent_radius_m,
        };
        let Registered { outputs, .. } = register_outputs(&cfg, &path, hello).unwrap();
        let mut start = Start {
            threads: Vec::new(),
            stop: Arc::new(AtomicBool::new(false)),
            input_stop: Arc::new(AtomicBool::new(false)),
            priority: None,
            input_cpus: None,
        };
        let (cmd_tx, _cmd_rx) = bounded::<CommandRequest>(1);
        let out = start.spawn_outputs(outputs, &cmd_tx).unwrap();
        assert!(path.exists());
        // What `?` does when a later thread cannot be started.
        drop(out);
        drop(start);
        assert!(!path.exists(), "the socket file outlived a failed start");
    }
}
