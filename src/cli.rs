//! Command-line interface: the daemon (`run`, `demo`) and its tools.

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use crowdtouch::config::{self, Config};
use crowdtouch::crowd::edit::{io::write_jsonl, TrackRecorder};
use crowdtouch::engine::{replay_virtual, Engine, VirtualClock};
use crowdtouch::input::recording::{OnBadFrame, RecordingStream};
use crowdtouch::pipeline::{
    preflight, sources_from_config, Daemon, DaemonOptions, Preflight, Severity,
};
use crowdtouch::publish::protocol::{
    encode_event, encode_mesh_json, encode_snapshot_json, FieldSet,
};
use crowdtouch::rt::monotonic_now;
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::StatsReport;
use output::{errln, outln};
use running::Running;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

mod bench;
mod calibrate;
mod check;
mod devices;
mod doctor;
mod doctor_device;
mod edit;
mod edit_path;
mod formations;
mod gesture;
mod hid;
mod journal;
mod library;
mod library_collect;
mod library_eval;
mod output;
mod record;
mod running;
mod scene;
mod scene_render;
mod soak;
mod svg;
mod transform;
mod transform_compare;
mod transform_scenario;
mod transform_setup;
mod transform_svg;
mod unit;
mod watch;

/// crowdtouch — a multi-touch table daemon that drives a crowd.
///
/// Touches on the table are segmented into controls (1 finger: point, 2: line, 3+:
/// area) that deform a mesh over the crowd; agents follow the mesh; renderers read
/// the crowd from a Unix socket (see docs/protocol.md).
#[derive(Parser, Debug)]
#[command(name = "crowdtouch", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand, Debug)]
enum Cmd {
    /// Run the daemon: inputs and socket from the config.
    ///
    /// Without --config the first file found is used: $CROWDTOUCH_CONFIG,
    /// $XDG_CONFIG_HOME/crowdtouch/crowdtouch.ron (~/.config/...),
    /// /etc/crowdtouch/crowdtouch.ron, else the embedded default. SIGHUP reloads the
    /// config (an invalid one is reported and the old one keeps running);
    /// SIGTERM/SIGINT stop cleanly. Under systemd (Type=notify) READY is sent once the
    /// socket is bound and inputs are open, and the watchdog is fed while the
    /// pipeline ticks.
    Run(RunArgs),
    /// The main job on the embedded default: replays the shipped recordings (looped)
    /// through the full daemon, serves the socket, prints a status line every second.
    Demo(DemoArgs),
    /// Play a recording through the engine and write snapshots as JSON Lines.
    ///
    /// Reads our JSON Lines recordings, `evemu-record` text, `libinput record` YAML
    /// and hid-recorder logs.
    /// By default runs on a virtual clock as fast as possible: the same recording and
    /// config give byte-identical output.
    Replay(ReplayArgs),
    /// Draw the crowd live in the terminal from the daemon's socket.
    Watch(WatchArgs),
    /// Validate a config file, and everything `run` would refuse at start-up with it
    /// (the socket path, its directory and group, the recordings); every error is
    /// reported with file:line:column and field. Exit code 0 when `run` would
    /// start (warnings, such as input CPUs this machine lacks, do not change it), 1
    /// when not.
    CheckConfig {
        /// Config file.
        file: PathBuf,
    },
    /// What is wrong with this table, each finding with its fix: the config, the
    /// service user, the device and who may open it, the udev rule, real-time
    /// limits, the socket, each network output, the running daemon's last stats.
    /// Exit code 0 only when nothing is wrong.
    Doctor(doctor::DoctorArgs),
    /// The systemd drop-in that opens to the service exactly the network its config
    /// names (printed; `--generator DIR` writes it, as the package's systemd
    /// generator does at boot and on `systemctl daemon-reload`).
    #[command(hide = true)]
    UnitNetwork {
        /// Config (default: /etc/crowdtouch/crowdtouch.ron).
        #[arg(long, short)]
        config: Option<PathBuf>,
        /// systemd's generator output directories (the first is used).
        #[arg(long, num_args = 1..=3)]
        generator: Vec<PathBuf>,
    },
    /// Write the man pages (roff) into DIR, as the Debian package installs them.
    #[command(hide = true)]
    Man {
        /// Output directory.
        dir: PathBuf,
    },
    /// Measure the standard workloads on this machine (p50/p99/max).
    Bench(bench::BenchArgs),
    /// List the touch devices on this machine (evdev and hidraw) with their ranges,
    /// contact counts and stable ids, and which one `run` would pick.
    Devices {
        /// Config whose Device inputs to resolve (default: the search path).
        #[arg(long, short)]
        config: Option<PathBuf>,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Calibrate a touch device: touch four targets, get the matrix (and write it into
    /// the config with --write).
    Calibrate {
        /// Config with the Device input to calibrate (default: the search path).
        #[arg(long, short)]
        config: Option<PathBuf>,
        /// Index of the input in the config (default: the first Device input).
        #[arg(long)]
        input: Option<usize>,
        /// Write the matrix into the config file (a .bak copy is kept).
        #[arg(long)]
        write: bool,
    },
    /// Record a touch device's raw stream: evdev nodes as evemu, hidraw nodes as
    /// hid-recorder logs. Replays on any machine (`evemu-play`, `hid-replay`,
    /// `crowdtouch replay`); attach it to bug reports.
    Record(record::RecordArgs),
    /// Raw HID digitizer tools.
    #[command(subcommand)]
    Hid(hid::HidCmd),
    /// Scene tools: `scene check FILE` validates a scene (obstacles, patches, moving
    /// things, checkpoints); `scene render FILE -o OUT.svg` draws it with the
    /// travel-time field of a goal and the agents' routes.
    #[command(subcommand)]
    Scene(scene::SceneCmd),
    /// List the formation shapes a config defines (the shipped ones and its
    /// `formations.shapes`), meshed as a checkpoint switch lays them out for its
    /// crowd; `-o OUT.svg` draws them with their goals.
    Formations {
        /// Config (default: the search path above).
        #[arg(long, short)]
        config: Option<PathBuf>,
        /// Write a picture of every formation (SVG).
        #[arg(long, short)]
        output: Option<PathBuf>,
    },
    /// Run a formation transform headless (formation-transform): `--from A --to B`
    /// (formation names or files) on a virtual clock, reporting arrival, contacts,
    /// travel, the paper's measures and step times; `transform compare` runs the
    /// paper's comparisons (pairing costs, feedback off, ORCA, RVO, steering).
    Transform(transform::TransformCmd),
    /// Crowd motion editing (crowd-motion-editing) on track files: `edit check` finds
    /// collisions between people in space-time.
    #[command(subcommand)]
    Edit(edit::EditCmd),
    /// Gesture commands: recognise the gestures of recordings.
    #[command(subcommand)]
    Gesture(gesture::GestureCmd),
    /// The gesture library: build or start one, import motions, add gestures,
    /// remove a class, show, evaluate, make a test set.
    #[command(subcommand)]
    Library(library::LibraryCmd),
    /// Regenerate the shipped recordings (deterministic).
    SynthRecordings {
        /// Output directory.
        #[arg(long, default_value = "config/recordings")]
        out: PathBuf,
    },
}

#[derive(Args, Debug)]
struct RunArgs {
    /// Config file (default: the search path above).
    #[arg(long, short)]
    config: Option<PathBuf>,
    /// Socket path (overrides the config).
    #[arg(long)]
    socket: Option<PathBuf>,
}

#[derive(Args, Debug)]
struct DemoArgs {
    /// Number of agents.
    #[arg(long)]
    agents: Option<u32>,
    /// Socket path (default: $XDG_RUNTIME_DIR/crowdtouch.sock).
    #[arg(long)]
    socket: Option<PathBuf>,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long)]
    seconds: Option<f64>,
    /// Also send the crowd as TUIO 1.1 over UDP to HOST:PORT (touches, agents and
    /// controls: a privileged target, as the demo's touches are synthetic).
    #[arg(long, value_name = "HOST:PORT")]
    tuio: Option<String>,
    /// Also serve the live viewer and the WebSocket stream on ADDR (ip:port),
    /// privileged; beyond loopback only with --token.
    #[arg(long, value_name = "ADDR")]
    http: Option<String>,
    /// The token WebSocket clients must present with --http (16+ characters).
    #[arg(long, requires = "http")]
    token: Option<String>,
    /// A host name the viewer is opened by (`kiosk-7` or `kiosk-7:8080`), besides
    /// the listen address (and `localhost` on loopback); repeatable. Requests
    /// naming any other host are refused (421): the guard against DNS rebinding.
    #[arg(long = "host", value_name = "NAME", requires = "http")]
    hosts: Vec<String>,
    /// Also serve the newest stats as Prometheus text at /metrics beside the
    /// viewer (with --token when one is given).
    #[arg(long, requires = "http")]
    metrics: bool,
}

#[derive(Args, Debug)]
struct ReplayArgs {
    /// Recording (.jsonl, evemu, libinput record YAML, hid-recorder).
    file: PathBuf,
    /// Config (default: the embedded default).
    #[arg(long, short)]
    config: Option<PathBuf>,
    /// Number of agents (overrides the config).
    #[arg(long)]
    agents: Option<u32>,
    /// Play at the recording's own pace instead of as fast as possible.
    #[arg(long)]
    realtime: bool,
    /// Skip bad frames (with a warning naming the line) instead of stopping.
    #[arg(long)]
    skip_bad_frames: bool,
    /// Keep ticking this long after the last frame so the crowd settles (s).
    #[arg(long, default_value_t = 2.0)]
    settle: f64,
    /// Output file (default: stdout).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Also draw the replay (mesh before and after, agent and finger paths) as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Print the decoded touch frames (JSON Lines) instead of running the crowd: the
    /// daemon's own view of a recording, for bug reports.
    #[arg(long)]
    frames: bool,
    /// Also write every agent's track (JSON Lines tracks, docs/tracks.md): its
    /// position every `--track-step` seconds of replay time.
    #[arg(long, conflicts_with = "frames")]
    tracks: Option<PathBuf>,
    /// Time between two samples of the tracks (s).
    #[arg(long, default_value_t = 0.1, requires = "tracks")]
    track_step: f64,
}

#[derive(Args, Debug)]
struct WatchArgs {
    /// Socket path (default: as the daemon resolves it).
    #[arg(long)]
    socket: Option<PathBuf>,
    /// Redraws per second.
    #[arg(long, default_value_t = 20.0)]
    fps: f64,
    /// Stop after this many seconds.
    #[arg(long)]
    seconds: Option<f64>,
}

/// `crowdtouch man DIR`: the man pages (`crowdtouch.1` and one `crowdtouch-CMD.1`
/// per visible command), from the clap definitions above.
fn man(dir: &Path) -> Result<()> {
    use clap::CommandFactory;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    clap_mangen::generate_to(Cli::command(), dir)
        .with_context(|| format!("writing the man pages into {}", dir.display()))?;
    Ok(())
}

/// Entry point; returns the process exit code (see `output` for what a write
/// that fails does to it).
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => return clap_exit(&e),
    };
    let done = |r: Result<()>| r.map(|()| 0);
    let result = match cli.command {
        Cmd::Run(a) => done(run(a)),
        Cmd::Demo(a) => done(demo(a)),
        Cmd::Replay(a) => done(replay(a)),
        Cmd::Watch(a) => done(watch::watch(a.socket, a.fps, a.seconds)),
        Cmd::CheckConfig { file } => check::check_config(&file),
        Cmd::Doctor(a) => doctor::doctor(&a),
        Cmd::Man { dir } => done(man(&dir)),
        Cmd::UnitNetwork { config, generator } => {
            unit::unit_network(config.as_deref(), generator.first().map(PathBuf::as_path))
        }
        Cmd::Bench(a) => done(bench::bench(a)),
        Cmd::SynthRecordings { out } => done(synth(&out)),
        Cmd::Calibrate {
            config,
            input,
            write,
        } => done(
            find_config(config.as_deref())
                .and_then(|(cfg, path)| calibrate::calibrate(&cfg, path.as_deref(), input, write)),
        ),
        Cmd::Record(a) => done(record::record(a)),
        Cmd::Hid(c) => done(hid::hid(c)),
        Cmd::Scene(c) => scene::scene(c),
        Cmd::Gesture(c) => {
            let config = match &c {
                gesture::GestureCmd::Classify { config, .. } => config.clone(),
            };
            done(find_config(config.as_deref()).and_then(|(cfg, _)| gesture::gesture(c, &cfg)))
        }
        Cmd::Library(library::LibraryCmd::Collect(a)) => done(collect(a)),
        Cmd::Library(c) => {
            let config = match &c {
                library::LibraryCmd::Eval { config, .. }
                | library::LibraryCmd::Add { config, .. } => config.clone(),
                _ => None,
            };
            let cfg = match &c {
                // Building and editing need no config (nor a library to load one with).
                library::LibraryCmd::Build { .. }
                | library::LibraryCmd::TestSet { .. }
                | library::LibraryCmd::New { .. }
                | library::LibraryCmd::ImportMotion { .. }
                | library::LibraryCmd::Remove { .. } => Ok(None),
                _ => find_config(config.as_deref()).map(|(cfg, _)| Some(cfg)),
            };
            done(cfg.and_then(|cfg| library::library(c, cfg.as_ref())))
        }
        Cmd::Formations { config, output } => done(
            find_config(config.as_deref())
                .and_then(|(cfg, _)| formations::formations(&cfg, output.as_deref())),
        ),
        Cmd::Transform(c) => done(transform::transform(c)),
        Cmd::Edit(c) => done(edit::edit(c)),
        Cmd::Devices { config, json } => done(
            find_config(config.as_deref())
                .and_then(|(cfg, _)| devices::devices(&cfg, json, Path::new("/"))),
        ),
    };
    output::exit_status(result)
}

/// Writes clap's help, version or usage error and returns its exit code; a write
/// that fails is handled as every command's (`output`).
fn clap_exit(e: &clap::Error) -> i32 {
    let code = e.exit_code();
    match e.print() {
        Ok(()) => code,
        Err(io) if io.kind() == std::io::ErrorKind::BrokenPipe => code,
        Err(io) => {
            let stream = if e.use_stderr() { "stderr" } else { "stdout" };
            let _ = errln!("crowdtouch: error: cannot write to {stream}: {io}");
            code.max(1)
        }
    }
}

/// Logs to stderr at `level` (as journal lines under systemd: `journal.rs`);
/// `RUST_LOG` overrides it. Without `RUST_LOG` the
/// logger passes everything and the level is `log`'s maximum, which a config
/// reload changes (`Daemon::reload`).
fn init_logging(level: config::LogLevel) {
    let mut b = env_logger::Builder::new();
    let spec = std::env::var("RUST_LOG").ok();
    match &spec {
        Some(spec) => {
            b.filter_level(level.filter());
            b.parse_filters(spec);
        }
        None => {
            b.filter_level(log::LevelFilter::Trace);
        }
    }
    b.format_target(false);
    if journal::stderr_is_journal() {
        journal::use_journal_format(&mut b);
    }
    if b.try_init().is_ok() && spec.is_none() {
        log::set_max_level(level.filter());
    }
}

fn find_config(explicit: Option<&Path>) -> Result<(Config, Option<PathBuf>)> {
    find_config_with_text(explicit).map(|(cfg, path, _)| (cfg, path))
}

/// [`find_config`], with the text the config was read from (the embedded
/// default's for none).
fn find_config_with_text(explicit: Option<&Path>) -> Result<(Config, Option<PathBuf>, String)> {
    if let Some(p) = explicit {
        let (cfg, text) = Config::load_with_text(p)?;
        return Ok((cfg, Some(p.to_path_buf()), text));
    }
    for p in config::search_path() {
        if p.exists() {
            let (cfg, text) = Config::load_with_text(&p)?;
            return Ok((cfg, Some(p), text));
        }
    }
    Ok((
        Config::embedded_default(),
        None,
        config::DEFAULT_CONFIG_RON.to_string(),
    ))
}

/// Signal flags of a running daemon.
struct Signals {
    stop: Arc<AtomicBool>,
    reload: Arc<AtomicBool>,
}

fn signals() -> Result<Signals> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let s = Signals {
        stop: Arc::new(AtomicBool::new(false)),
        reload: Arc::new(AtomicBool::new(false)),
    };
    for sig in [SIGINT, SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&s.stop))
            .context("installing signal handlers")?;
    }
    signal_hook::flag::register(SIGHUP, Arc::clone(&s.reload))
        .context("installing SIGHUP handler")?;
    Ok(s)
}

/// The supervisor loop shared by `run` and `demo`: until SIGTERM/SIGINT, `until`,
/// or `on_report` fails (a status line that cannot be written); then stops the
/// daemon and returns that failure.
fn supervise(
    sig: Signals,
    mut daemon: Running,
    config_path: Option<PathBuf>,
    until: Option<Micros>,
    mut on_report: impl FnMut(&StatsReport) -> Result<()>,
) -> Result<()> {
    let mut watchdog_us = 0u64;
    let watchdog = sd_notify::watchdog_enabled(false, &mut watchdog_us);
    let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Ready]);
    let mut last_ping = monotonic_now();
    let mut finished: Option<Micros> = None;
    let mut outcome = Ok(());
    loop {
        if sig.stop.load(Ordering::Relaxed) || until.is_some_and(|u| monotonic_now() >= u) {
            break;
        }
        // A `library collect` session that asked for everything: a second for its
        // last events to reach the clients, then stop.
        if daemon.collect_finished() {
            let now = monotonic_now();
            if now.saturating_since(*finished.get_or_insert(now)) >= Micros(1_000_000) {
                break;
            }
        }
        if sig.reload.swap(false, Ordering::Relaxed) {
            reload_on_sighup(&mut daemon, config_path.as_deref());
        }
        if let Some(r) = daemon.next_report(Duration::from_millis(200)) {
            if let Err(e) = on_report(&r) {
                outcome = Err(e);
                break;
            }
        }
        // Feed the watchdog only while the control thread is ticking.
        if watchdog && monotonic_now().saturating_since(last_ping).0 * 2 >= watchdog_us {
            if daemon.heartbeat_age() < Micros(watchdog_us / 2) {
                let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Watchdog]);
            } else {
                log::error!(
                    "control thread stalled for {} — not feeding the watchdog",
                    daemon.heartbeat_age()
                );
            }
            last_ping = monotonic_now();
        }
    }
    let _ = sd_notify::notify(false, &[sd_notify::NotifyState::Stopping]);
    log::info!("stopping");
    daemon.shutdown();
    outcome
}

/// `library collect`: the daemon on the config's inputs and outputs (and the
/// viewer with `--http`), running a collection session until it has asked for
/// every motion, or until SIGTERM/SIGINT.
fn collect(a: library_collect::CollectArgs) -> Result<()> {
    let sig = signals()?;
    let (mut cfg, path) = find_config(a.config.as_deref())?;
    init_logging(cfg.log_level);
    if let Some(addr) = &a.http {
        cfg.outputs
            .push(demo_websocket(addr, a.token.clone(), &[], false)?);
    }
    let (start, from) = library_collect::starting_library(&a)?;
    let sources = sources_from_config(&cfg)?;
    let before = start
        .gestures
        .iter()
        .filter(|g| g.participant == a.participant.trim())
        .count();
    let plan = library_collect::plan(&a, &sources, start)?;
    let socket_path = a
        .socket
        .clone()
        .unwrap_or_else(|| cfg.socket.resolved_path());
    library_collect::announce(&a, &plan, &from, &socket_path)?;
    let participant = plan.participant.clone();
    let daemon = Running(Some(Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path,
            collect: Some(plan),
        },
    )?));
    supervise(sig, daemon, path, None, |r| {
        log::debug!("{}", status_line(r));
        Ok(())
    })?;
    library_collect::summary(&a.out, &participant, before)
}

/// What a SIGHUP does: reads the config file again and hands it to the daemon; a
/// config that does not load is reported and the running one stays. Returns whether
/// a new config was handed over (`bench soak` counts them).
fn reload_on_sighup(daemon: &mut Daemon, config_path: Option<&Path>) -> bool {
    match config_path {
        Some(p) => match Config::load(p) {
            Ok(c) => {
                log::info!("SIGHUP: reloading {}", p.display());
                daemon.reload(c);
                true
            }
            Err(e) => {
                log::error!(
                    "SIGHUP: new config rejected, the old config and scene keep running:\n{e}"
                );
                false
            }
        },
        None => {
            log::warn!("SIGHUP: running on the embedded default config; nothing to reload");
            false
        }
    }
}

/// Applies `--agents`, checked like the config field.
fn set_agents(cfg: &mut Config, agents: Option<u32>) -> Result<()> {
    if let Some(n) = agents {
        cfg.crowd.agents = n;
        if let Some((field, msg)) = cfg.validate().into_iter().next() {
            bail!("--agents: {field}: {msg}");
        }
    }
    Ok(())
}

/// Reads the config's inputs and starts the daemon on `socket` (or the config's).
fn start_daemon(cfg: Config, socket: Option<PathBuf>) -> Result<Running> {
    let socket_path = socket.unwrap_or_else(|| cfg.socket.resolved_path());
    let sources = sources_from_config(&cfg)?;
    Ok(Running(Some(Daemon::start(
        cfg,
        sources,
        DaemonOptions {
            socket_path,
            collect: None,
        },
    )?)))
}

fn run(a: RunArgs) -> Result<()> {
    // Handlers first: a SIGHUP or SIGTERM during start-up must not kill the process.
    let sig = signals()?;
    let (cfg, path, text) = find_config_with_text(a.config.as_deref())?;
    init_logging(cfg.log_level);
    match &path {
        Some(p) => log::info!("config {}", p.display()),
        None => log::info!(
            "no config file found (looked in {}); using the embedded default",
            config::search_path()
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
    // What check-config reports, at the config's fields. The socket is checked here
    // only when it is the config's (`--socket` is checked when it is bound), and the
    // recordings when they are read next.
    let config_socket = cfg.socket.resolved_path();
    let findings = preflight(
        &cfg,
        &Preflight {
            socket: a.socket.is_none().then_some(config_socket.as_path()),
            recordings: false,
            starting: true,
        },
    );
    let shown = path.clone().unwrap_or_else(|| PathBuf::from("<embedded>"));
    let warnings = check::located_findings(&shown, &text, &findings, Severity::Warning);
    for w in warnings.lines() {
        log::warn!("{w}");
    }
    let errors = check::located_findings(&shown, &text, &findings, Severity::Error);
    if !errors.is_empty() {
        bail!("the config cannot be run:\n{errors}");
    }
    let daemon = start_daemon(cfg, a.socket)?;
    log::info!("listening on {}", daemon.socket_path().display());
    supervise(sig, daemon, path, None, |r| {
        log::debug!("{}", status_line(r));
        Ok(())
    })
}

fn demo(a: DemoArgs) -> Result<()> {
    let sig = signals()?;
    let mut cfg = Config::embedded_default();
    init_logging(cfg.log_level);
    set_agents(&mut cfg, a.agents)?;
    if let Some(target) = &a.tuio {
        cfg.outputs.push(demo_tuio(target));
        if let Some((_, why)) = cfg
            .validate()
            .into_iter()
            .find(|(f, _)| f.starts_with("outputs"))
        {
            anyhow::bail!("--tuio {target}: {why}");
        }
    }
    if let Some(addr) = &a.http {
        cfg.outputs
            .push(demo_websocket(addr, a.token.clone(), &a.hosts, a.metrics)?);
    }
    let daemon = start_daemon(cfg, a.socket)?;
    // From here on, every way out (a line that cannot be written included) stops
    // the daemon and removes its socket.
    let path = daemon.socket_path().display().to_string();
    outln!("crowdtouch demo: serving the crowd on {path}")?;
    if let Some(target) = &a.tuio {
        outln!("  TUIO 1.1:   to {target} (/tuio/2Dcur touches, /tuio/2Dobj agents, /tuio/2Dblb controls)")?;
    }
    if let Some(addr) = &a.http {
        let query = output::token_query(a.token.as_deref());
        outln!("  viewer:     http://{addr}/{query}")?;
        if a.metrics {
            outln!("  metrics:    http://{addr}/metrics")?;
        }
        for h in &a.hosts {
            let port = addr.rsplit_once(':').map_or("", |(_, p)| p);
            let shown = if h.contains(':') && !h.ends_with(']') {
                h.clone()
            } else {
                format!("{h}:{port}")
            };
            outln!("              http://{shown}/{query}")?;
        }
    }
    outln!("  watch it:   crowdtouch watch --socket {path}   (or: cargo run --release -- watch --socket {path})")?;
    outln!("  raw stream: socat - UNIX-CONNECT:{path}")?;
    outln!("  Ctrl-C stops.")?;
    let until = a
        .seconds
        .map(|s| monotonic_now() + Micros::from_secs_f64(s));
    supervise(sig, daemon, None, until, |r| {
        outln!("{}", status_line(r))?;
        Ok(())
    })
}

/// The demo's TUIO output (`demo --tuio HOST:PORT`): TUIO 1.1 with every profile.
fn demo_tuio(target: &str) -> config::OutputConfig {
    config::OutputConfig::Tuio {
        target: target.to_string(),
        version: "1.1".to_string(),
        profiles: vec![
            config::TuioProfile::Cursors,
            config::TuioProfile::Objects,
            config::TuioProfile::Blobs,
        ],
        rate_hz: 60.0,
        max_datagram_bytes: 1472,
        source: None,
        privileged: true,
    }
}

/// `demo --http ADDR [--token T] [--host NAME]...`: a privileged WebSocket output
/// with the viewer.
fn demo_websocket(
    addr: &str,
    token: Option<String>,
    hosts: &[String],
    metrics: bool,
) -> Result<config::OutputConfig> {
    let hosts = hosts
        .iter()
        .map(|h| config::normalize_host(h).map_err(|why| anyhow::anyhow!("--host {h}: {why}")))
        .collect::<Result<Vec<_>>>()?;
    let parsed: std::net::SocketAddr = addr
        .parse()
        .map_err(|_| anyhow::anyhow!("--http {addr}: not ip:port, like 127.0.0.1:8080"))?;
    match &token {
        None if !config::is_loopback(parsed.ip()) => anyhow::bail!(
            "--http {addr} is reachable from other machines, and its clients may steer the \
             crowd: give --token SECRET (16+ characters), or listen on 127.0.0.1"
        ),
        Some(t) if t.len() < 16 || !t.chars().all(|c| c.is_ascii_graphic()) => {
            anyhow::bail!("--token: at least 16 printable ASCII characters, no spaces")
        }
        _ => {}
    }
    Ok(config::OutputConfig::WebSocket {
        listen: addr.to_string(),
        token,
        privileged: true,
        max_clients: 16,
        max_message_bytes: 64 * 1024,
        viewer: true,
        metrics,
        // The viewer is served by this output: its own origin is privileged, as
        // are clients that send no Origin; pages of other sites are refused.
        origins: vec![],
        privileged_origins: vec![],
        hosts,
    })
}

/// One status line: agents, controls, last gesture, latency, drops.
pub fn status_line(r: &StatsReport) -> String {
    let e2e = r
        .stages
        .iter()
        .find(|s| s.stage == "end_to_end")
        .filter(|s| s.count > 0);
    let latency = match e2e {
        Some(s) => format!(
            "p50 {:>5.2} ms p99 {:>5.2} ms",
            s.p50_us as f64 / 1000.0,
            s.p99_us as f64 / 1000.0
        ),
        None => "  - (no client yet)       ".to_string(),
    };
    let assign_per_s = r
        .stages
        .iter()
        .find(|s| s.stage == "assignment")
        .map(|s| s.count)
        .unwrap_or(0) as f64
        / (r.interval_us as f64 * 1e-6);
    format!(
        "agents {:>5} | controls {} | last: {:<28} | latency {latency} | assign {:>4.0}/s | clients {} | dropped snapshots {} touches {}",
        r.agents,
        r.controls,
        r.last_gesture.as_deref().unwrap_or("-"),
        assign_per_s,
        r.clients,
        r.snapshots_dropped,
        r.transitions_lost,
    )
}

fn replay(a: ReplayArgs) -> Result<()> {
    let (mut cfg, _) = match &a.config {
        Some(p) => (Config::load(p)?, Some(p.clone())),
        None => (Config::embedded_default(), None),
    };
    init_logging(cfg.log_level);
    set_agents(&mut cfg, a.agents)?;
    let on_bad = if a.skip_bad_frames {
        OnBadFrame::Skip
    } else {
        OnBadFrame::Stop
    };
    // Read a frame at a time: a recording of any length replays in the same memory.
    let mut stream = RecordingStream::load(&a.file, on_bad)?;
    let file = a.file.display().to_string();
    let warn = |stream: &mut RecordingStream| -> Result<(), output::OutputError> {
        for w in stream.take_warnings() {
            match w.line {
                0 => errln!("{file}: warning: {}", w.message)?,
                l => errln!("{file}:{l}: warning: {}", w.message)?,
            }
        }
        Ok(())
    };
    if a.frames {
        let mut out: Box<dyn Write> = match &a.out {
            Some(p) => Box::new(std::io::BufWriter::new(
                std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
            )),
            None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
        };
        loop {
            let next = stream.next_frame();
            let f = match next {
                Ok(Some(f)) => frame_json(f),
                Ok(None) => break,
                Err(e) => {
                    warn(&mut stream)?;
                    return Err(e.into());
                }
            };
            warn(&mut stream)?;
            writeln!(out, "{f}").context("writing frames")?;
        }
        warn(&mut stream)?;
        out.flush().context("writing frames")?;
        return Ok(());
    }
    let mut out: Box<dyn Write> = match &a.out {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("creating {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let mut engine = Engine::new(&cfg, stream.surface().size_mm(), true);
    let clock = VirtualClock {
        period: Micros((1e6 / cfg.pipeline.tick_hz) as u64),
        settle: Micros::from_secs_f64(a.settle.max(0.0)),
        max_gap: Micros(crowdtouch::input::replay::MAX_GAP_US),
    };
    let mut buf = Vec::with_capacity(1 << 16);
    let start_wall = monotonic_now();
    let realtime = a.realtime;
    let mut sent_topology = 0;
    // Replay time of the tick about to run: the virtual clock less the gaps it
    // skipped, so tracks do not stand still through a skipped gap.
    let played_now = std::cell::Cell::new(Micros::ZERO);
    let pace = |played: Micros| {
        played_now.set(played);
        if realtime {
            let due = start_wall + played;
            let now = monotonic_now();
            if due > now {
                std::thread::sleep(Duration::from_micros((due - now).0));
            }
        }
    };
    let frames = std::iter::from_fn(|| {
        let next = match stream.next_frame() {
            Ok(f) => f.map(|f| Ok(*f)),
            Err(e) => Some(Err(anyhow::Error::from(e))),
        };
        if let Err(e) = warn(&mut stream) {
            return Some(Err(e.into()));
        }
        next
    });
    let mut trace = a.svg.as_ref().map(|_| svg::Trace::default());
    let mut tracks = match &a.tracks {
        Some(_) => Some(TrackRecorder::new(a.track_step).context("--track-step")?),
        None => None,
    };
    let mut positions: Vec<crowdtouch::geom::Vec2> = Vec::new();
    replay_virtual(&mut engine, frames, clock, pace, |o| -> Result<()> {
        if let Some(t) = &mut trace {
            t.tick(&o.snapshot, o.mesh.as_deref());
        }
        if let Some(r) = &mut tracks {
            positions.clear();
            positions.extend(o.snapshot.agents.iter().map(|g| g.pos));
            r.tick(played_now.get().as_secs_f64(), &positions)
                .context("recording tracks")?;
        }
        buf.clear();
        for e in o.events {
            encode_event(e, &mut buf);
        }
        if let Some(m) = &o.mesh {
            encode_mesh_json(m, m.topology != sent_topology, &mut buf);
            sent_topology = m.topology;
        }
        encode_snapshot_json(&o.snapshot, None, 0, &FieldSet::ALL, &mut buf);
        out.write_all(&buf).context("writing snapshots")?;
        Ok(())
    })?;
    out.flush().context("writing snapshots")?;
    if let (Some(path), Some(r)) = (&a.tracks, tracks) {
        let set = r.finish();
        let source = a.file.file_name().map(|n| n.to_string_lossy());
        std::fs::write(path, write_jsonl(&set, source.as_deref()))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let (Some(path), Some(t)) = (&a.svg, &mut trace) {
        let title = a
            .file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        std::fs::write(path, t.render(cfg.surface.world, &title))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// One decoded frame as a JSON object: `t_us` and the contacts (unit-square
/// coordinates, life-cycle state, optional pressure and size).
pub fn frame_json(f: &crowdtouch::vocab::TouchFrame) -> serde_json::Value {
    use crowdtouch::vocab::ContactFlags;
    let contacts: Vec<serde_json::Value> = f
        .contacts()
        .iter()
        .map(|c| {
            let state = if c.flags.contains(ContactFlags::CANCELLED) {
                "cancelled"
            } else if c.flags.contains(ContactFlags::DOWN) && c.flags.contains(ContactFlags::UP) {
                "tap"
            } else if c.flags.contains(ContactFlags::DOWN) {
                "down"
            } else if c.flags.contains(ContactFlags::UP) {
                "up"
            } else {
                "move"
            };
            let mut o = serde_json::json!({
                "id": c.id.0,
                "x": (c.x as f64 * 1e5).round() / 1e5,
                "y": (c.y as f64 * 1e5).round() / 1e5,
                "state": state,
            });
            if let Some(p) = c.pressure {
                o["pressure"] = serde_json::json!((p as f64 * 1e3).round() / 1e3);
            }
            if let Some(m) = c.major_mm {
                o["major_mm"] = serde_json::json!((m as f64 * 10.0).round() / 10.0);
            }
            if let Some(m) = c.minor_mm {
                o["minor_mm"] = serde_json::json!((m as f64 * 10.0).round() / 10.0);
            }
            if c.flags.contains(ContactFlags::PALM) {
                o["palm"] = serde_json::json!(true);
            }
            o
        })
        .collect();
    serde_json::json!({ "t_us": f.t.0, "contacts": contacts })
}

fn synth(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let files = crowdtouch::input::synth::write_shipped(out)
        .with_context(|| format!("writing into {}", out.display()))?;
    for f in files {
        outln!("{}", f.display())?;
    }
    Ok(())
}

/// Reads lines from a Unix socket client, for the tools.
pub fn connect(socket: Option<PathBuf>) -> Result<BufReader<std::os::unix::net::UnixStream>> {
    let path = socket.unwrap_or_else(|| Config::embedded_default().socket.resolved_path());
    let s = std::os::unix::net::UnixStream::connect(&path).with_context(|| {
        format!(
            "connecting to {} (is the daemon running? try `crowdtouch demo`)",
            path.display()
        )
    })?;
    Ok(BufReader::new(s))
}

/// Reads one line; `None` at end of stream.
pub fn read_line(r: &mut impl BufRead, buf: &mut String) -> Result<Option<()>> {
    buf.clear();
    let n = r.read_line(buf).context("reading from the socket")?;
    Ok((n > 0).then_some(()))
}
