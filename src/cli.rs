//! Command-line interface: the daemon (`run`, `demo`) and its tools.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use common::config::find_config;
use common::output::{self, errln};
use daemon::{check, doctor, unit, DemoArgs, RunArgs};
use editing::edit;
use gestures::{gesture, library, library_collect};
use input::replay::ReplayArgs;
use input::watch::WatchArgs;
use input::{calibrate, devices, hid, record, replay, watch};
use scenes::{formations, scene};
use std::path::{Path, PathBuf};
use transforms::transform;

// Each family imports `common` and nothing of another family or of this file
// (tests/architecture.rs).
mod bench;
mod common;
mod daemon;
mod editing;
mod gestures;
mod input;
mod scenes;
mod transforms;

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
        Cmd::Run(a) => done(daemon::run(a)),
        Cmd::Demo(a) => done(daemon::demo(a)),
        Cmd::Replay(a) => done(replay::replay(a)),
        Cmd::Watch(a) => done(watch::watch(a.socket, a.fps, a.seconds)),
        Cmd::CheckConfig { file } => check::check_config(&file),
        Cmd::Doctor(a) => doctor::doctor(&a),
        Cmd::Man { dir } => done(man(&dir)),
        Cmd::UnitNetwork { config, generator } => {
            unit::unit_network(config.as_deref(), generator.first().map(PathBuf::as_path))
        }
        Cmd::Bench(a) => done(bench::bench(a)),
        Cmd::SynthRecordings { out } => done(replay::synth(&out)),
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
        Cmd::Library(library::LibraryCmd::Collect(a)) => done(library_collect::collect(a)),
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
