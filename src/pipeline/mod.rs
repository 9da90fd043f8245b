//! Threads and queues: input → control → publisher, and the assignment worker.
//!
//! ```text
//!  input thread ──FrameQueue──► control thread ──Outgoing──► publisher thread ──► clients
//!  (one per source)  bounded      (Engine::tick)   bounded      (publish::Server)
//!                                    │  ▲
//!                          AssignJob │  │ AssignJob (solved)
//!                                    ▼  │
//!                              assignment worker
//! ```
//! The supervisor (the thread that called [`Daemon::start`]) merges the stage
//! statistics once per interval, publishes `stats`, reloads the config and feeds the
//! systemd watchdog from the control thread's heartbeat.
//!
//! Every channel states its policy where it is created.

use crate::config::{Config, InputConfig};
use crate::crowd::assign::Assigner;
use crate::crowd::environment::Scene;
use crate::crowd::environment::{Planner, PlannerParams};
use crate::crowd::formation::{PreparedSwitch, SwitchRequest};
use crate::engine::Engine;
use crate::geom::Vec2;
use crate::input::recording::{OnBadFrame, RecordingError};
use crate::input::replay::{Pacing, ReplayItem, ReplaySource};
use crate::input::FrameSink;
use crate::publish::Outgoing;
use crate::publish::{HelloInfo, PublisherStats, Server};
use crate::stats::StageTimer;
use crate::vocab::TouchFrame;
use crate::vocab::{monotonic_now, Micros};
use crate::vocab::{Command, CommandRequest, Event, StageStats, StatsReport};
pub mod device;

use crossbeam_channel::{bounded, never, select, Receiver, Sender, TryRecvError, TrySendError};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// Frames the input thread holds back while the queue is full (its own memory,
/// allocated once).
pub const BACKLOG_FRAMES: usize = 256;
/// Messages the control thread may have in flight to the publisher.
pub const OUTGOING_CAPACITY: usize = 1024;
/// Commands in flight from clients to the control thread.
pub const COMMAND_CAPACITY: usize = 64;
/// The "client" id of commands the daemon sends itself (replay resets).
pub const INTERNAL_CLIENT: u64 = 0;

/// Why the daemon could not start.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A recording named in the config could not be read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The socket could not be set up.
    #[error(transparent)]
    Publish(#[from] crate::publish::Error),
    /// A thread could not be started.
    #[error("cannot start the {name} thread: {source}")]
    Thread {
        /// Which thread.
        name: &'static str,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The config has no input.
    #[error("the config has no inputs: add a Replay(...) input")]
    NoInputs,
}

/// Counters of the input side, shared lock-free with the control thread.
#[derive(Debug, Default)]
pub struct InputCounters {
    /// Frames handed to the queue (or merged into one that was).
    pub frames: AtomicU64,
    /// Motion-only frames merged into a held-back frame because the queue was full.
    pub coalesced: AtomicU64,
    /// Touch-downs or lifts that could not be delivered (frame overflow while
    /// merging); the design keeps this at zero.
    pub transitions_lost: AtomicU64,
    /// Times the queue was found full.
    pub queue_full: AtomicU64,
    /// Contacts that appeared without a touch-down (a source bug); given fresh ids.
    pub contacts_without_down: AtomicU64,
    /// The last contact id handed out; ids are unique across every source and never
    /// reused while the daemon runs.
    pub last_contact_id: AtomicU32,
}

/// The input side of the input → control queue: a [`FrameSink`] for one source.
///
/// Channel policy: `bounded(queue_frames)`, input thread only `try_send`s, control
/// thread `recv`s. When the queue is full, frames wait in a fixed backlog on the
/// input thread; a frame that only moves contacts is merged into the newest held-back
/// frame, and when the backlog is full every new frame is merged into its newest
/// entry. Merging keeps every touch-down and lift (see [`TouchFrame::merge_later`]),
/// so transitions are never lost; only intermediate positions are.
///
/// The queue also gives contacts their daemon-wide ids: a source numbers its contacts
/// as it likes (unique while they are down); each touch-down gets the next id from
/// [`InputCounters::last_contact_id`], so ids are unique across devices, re-plugs and
/// replay loops, and never reused while the daemon runs.
pub struct FrameQueue {
    tx: Sender<TouchFrame>,
    ring: Vec<TouchFrame>,
    head: usize,
    len: usize,
    device: u16,
    counters: Arc<InputCounters>,
    /// Source id → daemon id of the contacts down, in a fixed table.
    ids: [(u32, u32); ID_MAP_CAPACITY],
    ids_len: usize,
}

/// Contacts one source may have down at once (twice a frame's capacity: ends and
/// begins of one frame).
const ID_MAP_CAPACITY: usize = 2 * crate::vocab::MAX_CONTACTS;

impl FrameQueue {
    /// A sink for device index `device` feeding `tx`.
    pub fn new(tx: Sender<TouchFrame>, device: u16, counters: Arc<InputCounters>) -> FrameQueue {
        FrameQueue {
            tx,
            ring: vec![TouchFrame::default(); BACKLOG_FRAMES],
            head: 0,
            len: 0,
            device,
            counters,
            ids: [(0, 0); ID_MAP_CAPACITY],
            ids_len: 0,
        }
    }

    fn fresh_id(&self) -> u32 {
        self.counters
            .last_contact_id
            .fetch_add(1, Ordering::Relaxed)
            .wrapping_add(1)
    }

    /// Rewrites the frame's contact ids into daemon-wide ids.
    fn map_ids(&mut self, f: &mut TouchFrame) {
        for c in f.contacts_mut() {
            let local = c.id.0;
            let found = self.ids[..self.ids_len]
                .iter()
                .position(|&(l, _)| l == local);
            let begins = c.flags.contains(crate::vocab::ContactFlags::DOWN);
            let slot = match (found, begins) {
                (Some(i), false) => i,
                (found, _) => {
                    if !begins {
                        self.counters
                            .contacts_without_down
                            .fetch_add(1, Ordering::Relaxed);
                    }
                    let id = self.fresh_id();
                    match found {
                        // A source reusing an id for a new touch: the old one has ended.
                        Some(i) => {
                            self.ids[i].1 = id;
                            i
                        }
                        None if self.ids_len < ID_MAP_CAPACITY => {
                            self.ids[self.ids_len] = (local, id);
                            self.ids_len += 1;
                            self.ids_len - 1
                        }
                        None => {
                            // Table full (a source that never ends its contacts): drop
                            // the oldest mapping to stay allocation-free.
                            self.ids.copy_within(1..ID_MAP_CAPACITY, 0);
                            self.ids[ID_MAP_CAPACITY - 1] = (local, id);
                            ID_MAP_CAPACITY - 1
                        }
                    }
                }
            };
            c.id = crate::vocab::ContactId(self.ids[slot].1);
            if c.flags.ended() {
                self.ids.copy_within(slot + 1..self.ids_len, slot);
                self.ids_len -= 1;
            }
        }
    }

    /// Frames currently held back.
    pub fn backlog(&self) -> usize {
        self.len
    }

    /// Tries to hand held-back frames on; returns whether the backlog is empty.
    pub fn flush(&mut self) -> bool {
        while self.len > 0 {
            match self.tx.try_send(self.ring[self.head]) {
                Ok(()) => {
                    self.head = (self.head + 1) % BACKLOG_FRAMES;
                    self.len -= 1;
                }
                Err(TrySendError::Full(_)) => return false,
                Err(TrySendError::Disconnected(_)) => {
                    self.len = 0;
                    return true;
                }
            }
        }
        true
    }

    fn newest(&mut self) -> &mut TouchFrame {
        let i = (self.head + self.len - 1) % BACKLOG_FRAMES;
        &mut self.ring[i]
    }

    fn hold(&mut self, f: &TouchFrame) {
        if self.len > 0 && (!f.has_transitions() || self.len == BACKLOG_FRAMES) {
            self.counters.coalesced.fetch_add(1, Ordering::Relaxed);
            if self.newest().merge_later(f).is_err() {
                self.counters
                    .transitions_lost
                    .fetch_add(1, Ordering::Relaxed);
            }
            return;
        }
        let i = (self.head + self.len) % BACKLOG_FRAMES;
        self.ring[i] = *f;
        self.len += 1;
    }
}

impl FrameSink for FrameQueue {
    fn flush(&mut self) -> bool {
        FrameQueue::flush(self)
    }

    fn push(&mut self, frame: &TouchFrame) {
        let mut f = *frame;
        self.map_ids(&mut f);
        f.device = self.device;
        f.t_queued = monotonic_now();
        self.counters.frames.fetch_add(1, Ordering::Relaxed);
        if self.flush() {
            match self.tx.try_send(f) {
                Ok(()) | Err(TrySendError::Disconnected(_)) => (),
                Err(TrySendError::Full(back)) => {
                    self.counters.queue_full.fetch_add(1, Ordering::Relaxed);
                    self.hold(&back);
                }
            }
        } else {
            self.counters.queue_full.fetch_add(1, Ordering::Relaxed);
            self.hold(&f);
        }
    }
}

/// An assignment request and, once solved, its answer. Two of these circulate
/// between the control thread and the worker, so nothing is allocated per solve.
#[derive(Clone, Debug, Default)]
pub struct AssignJob {
    /// Crowd generation the state belongs to.
    pub generation: u64,
    /// Tick whose state this is.
    pub seq: u64,
    /// Agent positions (m).
    pub agents: Vec<Vec2>,
    /// Goal positions (m).
    pub goals: Vec<Vec2>,
    /// Scene time of the tick (s): where moving obstacles are.
    pub t_scene_s: f64,
    /// The scene the tick ran in and the planner parameters for it (`None`: no
    /// scene, Euclidean costs). The worker plans over exactly this scene, building
    /// a new planner when it differs from the last job's.
    pub environment: Option<(Arc<Scene>, PlannerParams)>,
    /// Answer: goal index per agent.
    pub goal_of: Vec<u32>,
    /// Answer with a scene: each agent's waypoint around obstacles (NaN: none).
    pub waypoints: Vec<Vec2>,
    /// Whether the solve succeeded.
    pub ok: bool,
    /// Solve time (µs).
    pub solve_us: u64,
}

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
}

/// An input source the daemon runs.
pub enum SourceSpec {
    /// Recordings replayed in real time.
    Replay {
        /// The files, parsed.
        items: Vec<ReplayItem>,
        /// Play forever.
        looped: bool,
        /// Pause between files.
        gap: Micros,
        /// Reset the crowd before each file.
        reset_between: bool,
        /// Surface size (mm) from the first recording, if known.
        glass_mm: Option<(f64, f64)>,
    },
    /// A touch device found by discovery and re-attached after unplugging.
    Device {
        /// Index of the input in the config.
        input: u16,
        /// Which device, and through which interface.
        select: crate::config::DeviceSelect,
        /// evdev, hidraw or either.
        interface: crate::config::DeviceInterface,
        /// Exclusive grab.
        grab: bool,
        /// Calibration, region and palm settings applied to its frames.
        transform: device::TransformSettings,
    },
    /// Frames handed in by the embedding program through a channel: a virtual
    /// device for tests, benchmarks and tools. Frames keep the time stamp they were
    /// given (stamp them with [`monotonic_now`] when sent to measure latency). The
    /// source ends when the sender is dropped.
    Channel {
        /// Where the frames come from.
        rx: Receiver<TouchFrame>,
        /// Surface size (mm), if known.
        glass_mm: Option<(f64, f64)>,
    },
}

/// Reads the recordings a config names.
///
/// # Errors
/// [`Error::Recording`] naming the file and line; [`Error::NoInputs`].
pub fn sources_from_config(cfg: &Config) -> Result<Vec<SourceSpec>, Error> {
    if cfg.inputs.is_empty() {
        return Err(Error::NoInputs);
    }
    let mut out = Vec::new();
    for (i, input) in cfg.inputs.iter().enumerate() {
        match input {
            InputConfig::Replay {
                files,
                looped,
                gap_ms,
                reset_between,
            } => {
                let mut items = Vec::new();
                let mut glass = None;
                for f in files {
                    let rec = crate::input::recording::load_recording(f, OnBadFrame::Stop)?;
                    if glass.is_none() {
                        glass = rec.surface.size_mm();
                    }
                    items.push(ReplayItem {
                        name: display_name(f),
                        frames: rec.frames,
                    });
                }
                out.push(SourceSpec::Replay {
                    items,
                    looped: *looped,
                    gap: Micros(gap_ms * 1000),
                    reset_between: *reset_between,
                    glass_mm: glass,
                });
            }
            InputConfig::Device {
                select,
                interface,
                grab,
                region,
                calibration,
                palm_max_mm,
                size_mm,
            } => {
                out.push(SourceSpec::Device {
                    input: i as u16,
                    select: select.clone(),
                    interface: *interface,
                    grab: *grab,
                    transform: device::TransformSettings {
                        calibration: calibration.clone(),
                        region: *region,
                        palm_max_mm: *palm_max_mm,
                        size_mm: size_mm.or(cfg.surface.size_mm),
                    },
                });
            }
        }
    }
    Ok(out)
}

fn display_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// Options of a daemon run.
pub struct DaemonOptions {
    /// Socket path (already resolved).
    pub socket_path: PathBuf,
}

/// The running daemon: its threads and the handles the supervisor needs.
pub struct Daemon {
    stop: Arc<AtomicBool>,
    input_stop: Arc<AtomicBool>,
    threads: Vec<(&'static str, JoinHandle<()>)>,
    socket_path: PathBuf,
    publisher: Arc<PublisherStats>,
    input_counters: Arc<InputCounters>,
    heartbeat_us: Arc<AtomicU64>,
    control_stats: Receiver<ControlStats>,
    out: Sender<Outgoing>,
    reload: Sender<Box<Reload>>,
    scene: Option<Arc<Scene>>,
    planner_params: PlannerParams,
    inline_assignment: bool,
    e2e: StageTimer,
    encode: StageTimer,
    totals: Vec<StageTimer>,
    interval_us: u64,
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

impl Daemon {
    /// Binds the socket and starts every thread.
    ///
    /// # Errors
    /// Socket problems ([`Error::Publish`]) and thread creation.
    pub fn start(
        cfg: Config,
        sources: Vec<SourceSpec>,
        opts: DaemonOptions,
    ) -> Result<Daemon, Error> {
        if sources.is_empty() {
            return Err(Error::NoInputs);
        }
        let glass = sources.iter().find_map(|s| match s {
            SourceSpec::Replay { glass_mm, .. } | SourceSpec::Channel { glass_mm, .. } => *glass_mm,
            SourceSpec::Device { transform, .. } => transform.size_mm,
        });
        let mut engine = Engine::new(&cfg, glass, !cfg.assignment.worker);
        engine.set_switch_worker(true);
        let hello = HelloInfo {
            world: cfg.surface.world,
            agents: engine.agent_count() as u32,
            agent_radius_m: engine.agent_radius_m(),
        };
        let server = Server::bind(&cfg.socket, &opts.socket_path, hello)?;
        let socket_path = server.path().to_path_buf();
        let publisher = server.stats();
        let stop = Arc::new(AtomicBool::new(false));
        let input_stop = Arc::new(AtomicBool::new(false));
        let heartbeat_us = Arc::new(AtomicU64::new(monotonic_now().0));
        let input_counters = Arc::new(InputCounters::default());

        // Input → control: bounded(queue_frames); inputs try_send (FrameQueue policy),
        // control blocks in select with a tick timeout.
        let (frame_tx, frame_rx) = bounded::<TouchFrame>(cfg.pipeline.queue_frames as usize);
        // Control → publisher: bounded(OUTGOING_CAPACITY); control try_sends and counts
        // overflow; publisher blocks. Also used by the supervisor for stats.
        let (out_tx, out_rx) = bounded::<Outgoing>(OUTGOING_CAPACITY);
        // Clients → control: bounded(COMMAND_CAPACITY); the publisher try_sends and
        // answers "busy" when full; control drains with try_recv.
        let (cmd_tx, cmd_rx) = bounded::<CommandRequest>(COMMAND_CAPACITY);
        // Control ↔ worker: bounded(1) each way, exactly one job in flight; neither
        // side blocks on the other (control try_sends / try_recvs).
        let (job_tx, job_rx) = bounded::<Box<AssignJob>>(1);
        let (res_tx, res_rx) = bounded::<Box<AssignJob>>(1);
        // Control ⇄ formation thread: switch requests and results; the control side
        // only try_sends / try_recvs, the formation thread blocks on its own side.
        let (switch_tx, switch_job_rx) = bounded::<Box<SwitchRequest>>(2);
        let (switch_res_tx, switch_rx) = bounded::<Box<PreparedSwitch>>(2);
        // Control → supervisor: bounded(4) stats once per interval, try_send.
        let (cstats_tx, cstats_rx) = bounded::<ControlStats>(4);
        // Supervisor → control: bounded(1) config reloads, try_send.
        let (reload_tx, reload_rx) = bounded::<Box<Reload>>(1);

        let rt = cfg.pipeline.realtime.clone();
        if rt.lock_memory && crate::rt::lock_memory() {
            log::info!("memory locked");
        }
        let prio = rt.priority;
        let realtime = move |thread: &str| {
            if let Some(p) = prio {
                crate::rt::make_realtime(p, thread);
            }
        };
        let mut threads = Vec::new();
        {
            let stop = Arc::clone(&stop);
            let cmd_tx = cmd_tx.clone();
            let server = server.with_realtime(prio);
            threads.push(spawn("publisher", move || {
                realtime("publisher");
                server.run(out_rx, cmd_tx, stop)
            })?);
        }
        if cfg.assignment.worker {
            let cost = cfg.assignment.cost;
            threads.push(spawn("assign", move || {
                assignment_worker(cost, job_rx, res_tx)
            })?);
        }
        threads.push(spawn("formation", move || {
            formation_worker(switch_job_rx, switch_res_tx)
        })?);
        {
            let ctl = ControlLoop::new(
                &cfg,
                engine,
                ControlChannels {
                    frames: frame_rx,
                    commands: cmd_rx,
                    reload: reload_rx,
                    out: out_tx.clone(),
                    stats: cstats_tx,
                    jobs: job_tx,
                    results: res_rx,
                    switches: switch_tx,
                    switched: switch_rx,
                },
                Arc::clone(&stop),
                Arc::clone(&heartbeat_us),
            );
            threads.push(spawn("control", move || {
                realtime("control");
                ctl.run()
            })?);
        }
        for (i, source) in sources.into_iter().enumerate() {
            let mut queue =
                FrameQueue::new(frame_tx.clone(), i as u16, Arc::clone(&input_counters));
            let stop = Arc::clone(&input_stop);
            let cmd_tx = cmd_tx.clone();
            match source {
                SourceSpec::Replay {
                    items,
                    looped,
                    gap,
                    reset_between,
                    ..
                } => {
                    let mut src = ReplaySource::new(items, looped, gap, Pacing::RealTime);
                    threads.push(spawn("input", move || {
                        realtime("input");
                        let mut on_item = |i: usize| {
                            if reset_between && i > 0 {
                                let _ = cmd_tx.try_send(CommandRequest {
                                    client: INTERNAL_CLIENT,
                                    id: serde_json::Value::Null,
                                    command: Command::Reset { hard: false },
                                });
                            }
                        };
                        src.run(&mut queue, &stop, &mut on_item);
                        drain_backlog(&mut queue, &stop);
                    })?);
                }
                SourceSpec::Device {
                    input,
                    select,
                    interface,
                    grab,
                    transform,
                } => {
                    let out = out_tx.clone();
                    let cpus = rt.input_cpus.clone();
                    threads.push(spawn("input", move || {
                        realtime("input");
                        if let Some(cpus) = &cpus {
                            crate::rt::pin_to_cpus(cpus, "input");
                        }
                        let mut env = device::SystemEnv::new(std::path::Path::new("/"), grab);
                        let mut sink = device::TransformSink::new(queue, transform);
                        let mut notify = |n: device::DeviceNotice| {
                            let info = n.info.as_ref();
                            let ev = Event::Device {
                                input,
                                state: n.state,
                                name: info.map(|i| i.name.clone()).unwrap_or_default(),
                                node: info
                                    .map(|i| i.node.display().to_string())
                                    .unwrap_or_default(),
                                stable_id: info.map(|i| i.stable_id.clone()).unwrap_or_default(),
                                message: n.message,
                                t: n.t,
                            };
                            let _ = out.try_send(Outgoing::Event(Arc::new(ev)));
                        };
                        device::supervise(
                            &mut env,
                            &select,
                            interface,
                            &mut sink,
                            &stop,
                            &mut notify,
                        );
                        drain_backlog(sink.queue(), &stop);
                    })?);
                }
                SourceSpec::Channel { rx, .. } => {
                    threads.push(spawn("input", move || {
                        realtime("input");
                        while !stop.load(Ordering::Relaxed) {
                            let wait_ms = if queue.flush() { 50 } else { 1 };
                            match rx.recv_timeout(Duration::from_millis(wait_ms)) {
                                Ok(f) => queue.push(&f),
                                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
                            }
                        }
                        drain_backlog(&mut queue, &stop);
                    })?);
                }
            }
        }
        drop(frame_tx);
        let b = &cfg.pipeline.budgets;
        let scene = cfg.loaded_scene().cloned();
        let planner_params = crate::engine::planner_params(&cfg);
        let inline_assignment = !cfg.assignment.worker;
        Ok(Daemon {
            stop,
            input_stop,
            threads,
            socket_path,
            publisher,
            input_counters,
            heartbeat_us,
            control_stats: cstats_rx,
            out: out_tx,
            reload: reload_tx,
            scene,
            planner_params,
            inline_assignment,
            e2e: StageTimer::new("end_to_end", b.end_to_end_us),
            encode: StageTimer::new("publish", b.publish_us),
            totals: Vec::new(),
            interval_us: cfg.pipeline.stats_interval_ms * 1000,
            last_report: monotonic_now(),
        })
    }

    /// The socket path clients connect to.
    pub fn socket_path(&self) -> &Path {
        &self.socket_path
    }

    /// Publisher counters.
    pub fn publisher_stats(&self) -> &Arc<PublisherStats> {
        &self.publisher
    }

    /// Input counters.
    pub fn input_counters(&self) -> &Arc<InputCounters> {
        &self.input_counters
    }

    /// Time since the control thread last ticked.
    pub fn heartbeat_age(&self) -> Micros {
        monotonic_now().saturating_since(Micros(self.heartbeat_us.load(Ordering::Relaxed)))
    }

    /// Hands a new config to the control thread (already validated, its scene
    /// loaded: [`Config::load`] reads and checks the scene file, so a broken scene
    /// never gets here and the running one stays).
    ///
    /// Everything heavy about a new scene happens here, on the caller's thread,
    /// not on the control thread: comparing it with the running one (an unchanged
    /// scene keeps the running one, so nothing is swapped) and, with inline
    /// assignment, building its planner (rasterised scene, fast-marching
    /// workspaces). The assignment worker builds its own planner when its first
    /// job in the new scene arrives. The control thread only swaps the prepared
    /// parts in, between two ticks.
    pub fn reload(&mut self, mut cfg: Config) {
        self.e2e.set_budget(cfg.pipeline.budgets.end_to_end_us);
        self.encode.set_budget(cfg.pipeline.budgets.publish_us);
        let same = crate::engine::same_scene(cfg.loaded_scene(), self.scene.as_ref());
        if same {
            cfg.set_loaded_scene(self.scene.clone());
        }
        let params = crate::engine::planner_params(&cfg);
        let planner = if self.inline_assignment && (!same || params != self.planner_params) {
            cfg.loaded_scene()
                .and_then(|s| crate::engine::planner_for(s, params))
        } else {
            None
        };
        let scene = cfg.loaded_scene().cloned();
        let change = (!same).then(|| describe_scene_change(&cfg, self.scene.as_deref()));
        match self.reload.try_send(Box::new(Reload { cfg, planner })) {
            Ok(()) => {
                if let Some(c) = change {
                    log::info!("{c}");
                }
                self.scene = scene;
                self.planner_params = params;
            }
            Err(_) => {
                log::warn!("config reload skipped: the previous reload is still being applied")
            }
        }
    }

    /// Waits up to `timeout` for the control thread's interval figures, merges them
    /// with the publisher's and publishes `stats`. Returns the report when one was made.
    pub fn next_report(&mut self, timeout: Duration) -> Option<Arc<StatsReport>> {
        let cs = self.control_stats.recv_timeout(timeout).ok()?;
        let now = monotonic_now();
        self.e2e.absorb(&self.publisher.take_end_to_end());
        self.encode.absorb(&self.publisher.take_encode());
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
        let interval_us = now.saturating_since(self.last_report).0.max(1);
        self.last_report = now;
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
            assignment_hz: 0.0,
            snapshots_dropped: self.publisher.snapshots_dropped(),
            clients: self.publisher.clients(),
            agents: cs.agents,
            controls: cs.controls,
            rss_bytes: crate::stats::rss_bytes(),
            last_gesture: cs.last_gesture,
            formation: cs.formation,
            formation_switches: cs.formation_switches,
        });
        let _ = self.out.try_send(Outgoing::Stats(Arc::clone(&report)));
        Some(report)
    }

    /// Stops every thread: inputs first (their touches are cancelled), then the
    /// control thread publishes a final snapshot, then the publisher says `bye`.
    pub fn shutdown(mut self) {
        self.input_stop.store(true, Ordering::SeqCst);
        let (inputs, rest): (Vec<_>, Vec<_>) =
            self.threads.drain(..).partition(|(n, _)| *n == "input");
        for (_, h) in inputs {
            let _ = h.join();
        }
        // Let the control thread take the final frames before it stops.
        std::thread::sleep(Duration::from_millis(20));
        self.stop.store(true, Ordering::SeqCst);
        drop(self.out);
        for (name, h) in rest {
            if h.join().is_err() {
                log::error!("internal bug: the {name} thread panicked");
            }
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

/// Hands on whatever an input thread still holds back before its sink goes away.
fn drain_backlog(queue: &mut FrameQueue, stop: &AtomicBool) {
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
        "publish" => " — snapshot encoding (internal)",
        "end_to_end" => " — whole path (system load or a slow client)",
        _ => "",
    }
}

/// A reload on its way to the control thread: the config, and what was prepared
/// for its scene off the control thread.
struct Reload {
    cfg: Config,
    /// With inline assignment and a changed scene: the new scene's planner.
    planner: Option<Planner>,
}

struct ControlChannels {
    frames: Receiver<TouchFrame>,
    commands: Receiver<CommandRequest>,
    reload: Receiver<Box<Reload>>,
    out: Sender<Outgoing>,
    stats: Sender<ControlStats>,
    jobs: Sender<Box<AssignJob>>,
    results: Receiver<Box<AssignJob>>,
    switches: Sender<Box<SwitchRequest>>,
    switched: Receiver<Box<PreparedSwitch>>,
}

struct ControlLoop {
    engine: Engine,
    ch: ControlChannels,
    stop: Arc<AtomicBool>,
    heartbeat_us: Arc<AtomicU64>,
    period: Micros,
    stats_interval: Micros,
    worker: bool,
    idle_job: Option<Box<AssignJob>>,
    /// A formation switch request the formation thread had no room for yet.
    switch_out: Option<Box<SwitchRequest>>,
    t_input: StageTimer,
    t_queue: StageTimer,
    t_control: StageTimer,
    t_assign: StageTimer,
    last_stats: Micros,
    last_gesture: Option<String>,
    publish_overflow: u64,
}

impl ControlLoop {
    fn new(
        cfg: &Config,
        engine: Engine,
        ch: ControlChannels,
        stop: Arc<AtomicBool>,
        heartbeat_us: Arc<AtomicU64>,
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
            t_input: StageTimer::new("input", b.input_us),
            t_queue: StageTimer::new("queue", b.queue_us),
            t_control: StageTimer::new("control", b.control_us),
            t_assign: StageTimer::new("assignment", b.assignment_us),
            last_stats: monotonic_now(),
            last_gesture: None,
            publish_overflow: 0,
        }
    }

    fn run(mut self) {
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
            if input || now >= next_tick {
                self.tick(now);
                next_tick = now + self.period;
            }
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

    fn command(&mut self, req: CommandRequest) {
        let result = self.engine.command(&req.command, monotonic_now());
        if req.client != INTERNAL_CLIENT {
            self.send(Outgoing::Reply {
                client: req.client,
                id: req.id,
                result,
            });
        }
    }

    fn reconfigure(&mut self, reload: Reload) {
        let Reload { cfg, planner } = reload;
        let cfg = &cfg;
        let ignored = self.engine.reconfigure_with(cfg, planner);
        let b = &cfg.pipeline.budgets;
        self.t_input.set_budget(b.input_us);
        self.t_queue.set_budget(b.queue_us);
        self.t_control.set_budget(b.control_us);
        self.t_assign.set_budget(b.assignment_us);
        self.period = Micros((1e6 / cfg.pipeline.tick_hz) as u64);
        if ignored.is_empty() {
            log::info!("config reloaded");
        } else {
            log::warn!(
                "config reloaded; these changes need a restart: {}",
                ignored.join(", ")
            );
        }
    }

    fn send(&mut self, m: Outgoing) {
        if let Err(TrySendError::Full(_)) = self.ch.out.try_send(m) {
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
            self.t_assign.record(job.solve_us);
            self.idle_job = Some(job);
        }
        while let Ok(p) = self.ch.switched.try_recv() {
            // A switch that could not be built is logged and counted by the engine.
            let _ = self.engine.apply_switch(*p, now);
        }
        let out = self.engine.tick(now);
        let snapshot = out.snapshot;
        let mesh = out.mesh;
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
        self.send(Outgoing::Snapshot(snapshot));
        // A formation switch asked for by this tick or a command before it.
        if let Some(r) = self.engine.take_switch_request() {
            self.switch_out = Some(Box::new(r));
        }
        if let Some(r) = self.switch_out.take() {
            if let Err(TrySendError::Full(r)) = self.ch.switches.try_send(r) {
                self.switch_out = Some(r);
            }
        }
        if self.worker {
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

/// The assignment worker: Euclidean costs ([`Assigner`]) without a scene, travel
/// costs and waypoints ([`Planner`]) with one. It plans over the scene each job
/// names, building a new planner here (not on the control thread) when the scene or
/// its parameters differ from the last job's, so a reloaded scene is planned for
/// from the first job solved in it.
fn assignment_worker(
    cost: crate::config::AssignmentCost,
    jobs: Receiver<Box<AssignJob>>,
    results: Sender<Box<AssignJob>>,
) {
    crate::rt::make_background("assignment worker");
    let mut assigner = Assigner::new(cost);
    let mut environment: Option<(Arc<Scene>, PlannerParams)> = None;
    let mut planner: Option<Planner> = None;
    let mut generation = u64::MAX;
    let mut failures = 0u64;
    for mut job in jobs.iter() {
        let t0 = monotonic_now();
        let same = match (&job.environment, &environment) {
            (Some((a, pa)), Some((b, pb))) => Arc::ptr_eq(a, b) && pa == pb,
            (None, None) => true,
            _ => false,
        };
        if !same {
            environment.clone_from(&job.environment);
            planner = environment
                .as_ref()
                .and_then(|(scene, params)| crate::engine::planner_for(scene, *params));
            generation = u64::MAX;
        }
        if job.generation != generation {
            assigner.forget();
            if let Some(p) = &mut planner {
                p.forget();
            }
            generation = job.generation;
        }
        let AssignJob {
            agents,
            goals,
            goal_of,
            waypoints,
            t_scene_s,
            ..
        } = &mut *job;
        let solved = match &mut planner {
            Some(p) => p
                .plan(agents, goals, *t_scene_s, goal_of, waypoints)
                .map_err(|e| e.to_string()),
            None => {
                waypoints.clear();
                assigner
                    .solve(agents, goals, goal_of)
                    .map_err(|e| e.to_string())
            }
        };
        job.ok = match solved {
            Ok(()) => true,
            Err(e) => {
                failures += 1;
                if failures.is_power_of_two() {
                    log::warn!("internal: assignment failed ({failures} times): {e}");
                }
                false
            }
        };
        job.solve_us = monotonic_now().saturating_since(t0).0;
        if results.send(job).is_err() {
            break;
        }
    }
}

/// The formation thread: prepares formation switches (the new mesh, its goal
/// samples, the least-effort pairing; [`SwitchRequest::prepare`]) so the control
/// thread never does that slow work. At nice 10, like the assignment worker.
fn formation_worker(requests: Receiver<Box<SwitchRequest>>, done: Sender<Box<PreparedSwitch>>) {
    crate::rt::make_background("formation");
    for r in requests.iter() {
        if done.send(Box::new(r.prepare())).is_err() {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{Contact, ContactFlags, ContactId};

    fn frame(t: u64, contacts: &[(u32, f32, ContactFlags)]) -> TouchFrame {
        let mut f = TouchFrame::new(Micros(t));
        for &(id, x, flags) in contacts {
            f.push(Contact {
                id: ContactId(id),
                x,
                y: 0.5,
                flags,
                ..Contact::default()
            })
            .unwrap();
        }
        f
    }

    /// Reconstructs which contacts went down and up from delivered frames.
    fn transitions(frames: &[TouchFrame]) -> (Vec<u32>, Vec<u32>) {
        let (mut downs, mut ups) = (vec![], vec![]);
        for f in frames {
            for c in f.contacts() {
                if c.flags.contains(ContactFlags::DOWN) {
                    downs.push(c.id.0);
                }
                if c.flags.ended() {
                    ups.push(c.id.0);
                }
            }
        }
        (downs, ups)
    }

    #[test]
    fn full_queue_coalesces_motion_but_keeps_every_transition() {
        let (tx, rx) = bounded(2);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        let mut sent = vec![];
        // 50 contacts, each: down, 20 moves, up — 1100 frames into a queue of 2 that
        // nobody reads until the end.
        let mut t = 0;
        for id in 1..=50u32 {
            sent.push(frame(t, &[(id, 0.0, ContactFlags::DOWN)]));
            for k in 0..20 {
                t += 1;
                sent.push(frame(t, &[(id, k as f32 / 20.0, ContactFlags::NONE)]));
            }
            t += 1;
            sent.push(frame(t, &[(id, 1.0, ContactFlags::UP)]));
        }
        for f in &sent {
            q.push(f);
        }
        let mut got: Vec<TouchFrame> = vec![];
        loop {
            while let Ok(f) = rx.try_recv() {
                got.push(f);
            }
            if q.flush() {
                break;
            }
        }
        while let Ok(f) = rx.try_recv() {
            got.push(f);
        }
        let (downs, ups) = transitions(&got);
        assert_eq!(downs, (1..=50).collect::<Vec<_>>());
        assert_eq!(ups, (1..=50).collect::<Vec<_>>());
        assert!(got.len() < sent.len(), "motion should have been coalesced");
        assert!(counters.coalesced.load(Ordering::Relaxed) > 0);
        assert_eq!(counters.transitions_lost.load(Ordering::Relaxed), 0);
        // Time order is kept.
        assert!(got.windows(2).all(|w| w[0].t <= w[1].t));
    }

    #[test]
    fn contact_ids_are_unique_across_sources_and_reuse() {
        let (tx, rx) = bounded(64);
        let counters = Arc::new(InputCounters::default());
        let mut a = FrameQueue::new(tx.clone(), 0, Arc::clone(&counters));
        let mut b = FrameQueue::new(tx, 1, Arc::clone(&counters));
        // Both sources call their first contact 1, and reuse 1 after a lift.
        for q in [&mut a, &mut b] {
            q.push(&frame(0, &[(1, 0.1, ContactFlags::DOWN)]));
            q.push(&frame(1, &[(1, 0.2, ContactFlags::NONE)]));
            q.push(&frame(2, &[(1, 0.2, ContactFlags::UP)]));
            q.push(&frame(3, &[(1, 0.3, ContactFlags::DOWN)]));
            q.push(&frame(4, &[(1, 0.3, ContactFlags::CANCELLED)]));
        }
        let got: Vec<TouchFrame> = rx.try_iter().collect();
        let ids: Vec<(u16, u32)> = got
            .iter()
            .map(|f| (f.device, f.contacts()[0].id.0))
            .collect();
        assert_eq!(
            ids,
            vec![
                (0, 1),
                (0, 1),
                (0, 1),
                (0, 2),
                (0, 2),
                (1, 3),
                (1, 3),
                (1, 3),
                (1, 4),
                (1, 4)
            ]
        );
        assert_eq!(counters.contacts_without_down.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn backlog_overflow_merges_transitions_instead_of_dropping_them() {
        let (tx, rx) = bounded(1);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        // The backlog holds BACKLOG_FRAMES frames; later frames merge into its newest
        // entry, which holds up to MAX_CONTACTS contacts.
        let n = (BACKLOG_FRAMES / 2 + 40) as u32;
        for id in 1..=n {
            q.push(&frame(id as u64 * 2, &[(id, 0.5, ContactFlags::DOWN)]));
            q.push(&frame(id as u64 * 2 + 1, &[(id, 0.5, ContactFlags::UP)]));
        }
        let mut got = vec![];
        loop {
            while let Ok(f) = rx.try_recv() {
                got.push(f);
            }
            if q.flush() {
                break;
            }
        }
        while let Ok(f) = rx.try_recv() {
            got.push(f);
        }
        let (downs, ups) = transitions(&got);
        assert_eq!(downs.len() as u32, n);
        assert_eq!(ups.len() as u32, n);
        assert_eq!(counters.transitions_lost.load(Ordering::Relaxed), 0);
    }

    /// Found by the hardware-in-the-loop overload scenario: after a burst filled the
    /// queue, the last frame (a lift) stayed in the backlog until the next touch,
    /// because the reader only flushed when it pushed. A waiting reader now retries
    /// the backlog at `FLUSH_RETRY_US` and only then blocks for `STOP_CHECK_US`.
    #[test]
    fn a_waiting_reader_hands_on_held_frames_without_new_input() {
        use crate::input::{reader_timeout_ms, FrameSink, FLUSH_RETRY_US, STOP_CHECK_US};
        let (tx, rx) = bounded(1);
        let counters = Arc::new(InputCounters::default());
        let mut q = FrameQueue::new(tx, 0, Arc::clone(&counters));
        q.push(&frame(1, &[(1, 0.5, ContactFlags::DOWN)]));
        q.push(&frame(2, &[(1, 0.5, ContactFlags::UP)]));
        assert_eq!(q.backlog(), 1, "the lift waits behind a full queue");
        // The consumer is still busy: the reader waits only briefly.
        assert_eq!(u64::from(reader_timeout_ms(&mut q)), FLUSH_RETRY_US / 1000);
        let first = rx.try_recv().unwrap();
        assert!(first.contacts()[0].flags.contains(ContactFlags::DOWN));
        // The consumer took a frame: the next wait hands the lift on by itself.
        assert_eq!(u64::from(reader_timeout_ms(&mut q)), STOP_CHECK_US / 1000);
        assert_eq!(q.backlog(), 0);
        let lift = rx
            .try_recv()
            .expect("the held lift reaches the control thread");
        assert!(lift.contacts()[0].flags.ended());
        assert!(FrameSink::flush(&mut q));
    }
}
