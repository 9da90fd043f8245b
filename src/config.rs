//! The daemon's configuration: RON, strict, validated, with errors that point.
//!
//! `config/crowdtouch.ron` is the documented default and is embedded in the binary
//! ([`Config::embedded_default`]). Unknown fields are errors; every range is checked;
//! every error names the file, the line and column, and the field. Reads are
//! size-capped ([`MAX_CONFIG_BYTES`]).
//!
//! # Search path (`run` without `--config`)
//! 1. `$CROWDTOUCH_CONFIG`
//! 2. `$XDG_CONFIG_HOME/crowdtouch/crowdtouch.ron` (or `~/.config/crowdtouch/crowdtouch.ron`)
//! 3. `/etc/crowdtouch/crowdtouch.ron`
//! 4. the embedded default.

use crate::crowd::environment::Scene;
use crate::crowd::formation::{FormationDef, FormationLibrary, DEFAULT_LAMBDA};
use crate::geom::{Rect, Vec2};
pub use crate::located::Issue as ConfigIssue;
use crate::located::{
    field_positions, format_issues, locate_field, parse_strict, read_capped, ReadError,
};
use crate::vocab::parse_vendor_product;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The config format version this build reads.
pub const CONFIG_VERSION: u32 = 1;
/// Largest config file read (bytes).
pub const MAX_CONFIG_BYTES: u64 = 1 << 20;
/// Most agents the daemon accepts.
pub const MAX_AGENTS: u32 = 20_000;

/// The embedded default config text (`config/crowdtouch.ron`).
pub const DEFAULT_CONFIG_RON: &str = include_str!("../config/crowdtouch.ron");

/// Why a config could not be used.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be read.
    #[error("{path}: cannot read config: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than [`MAX_CONFIG_BYTES`].
    #[error("{path}: config is {size} bytes, more than the {max} byte limit")]
    TooLarge {
        /// File.
        path: PathBuf,
        /// Its size.
        size: u64,
        /// The limit.
        max: u64,
    },
    /// The text is not a valid config; every problem found is listed.
    #[error("{}", format_issues(.path, .issues))]
    Invalid {
        /// File (or `<embedded>` / `<text>`).
        path: PathBuf,
        /// Problems, in file order.
        issues: Vec<ConfigIssue>,
    },
}

impl From<ReadError> for Error {
    fn from(e: ReadError) -> Error {
        match e {
            ReadError::Io { path, source } => Error::Io { path, source },
            ReadError::TooLarge { path, size, max } => Error::TooLarge { path, size, max },
        }
    }
}

/// Log verbosity.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LogLevel {
    /// Errors only.
    Error,
    /// Warnings and errors.
    Warn,
    /// Normal operation.
    Info,
    /// Developer detail.
    Debug,
    /// Everything.
    Trace,
}

impl LogLevel {
    /// As a `log` filter.
    pub fn filter(self) -> log::LevelFilter {
        match self {
            LogLevel::Error => log::LevelFilter::Error,
            LogLevel::Warn => log::LevelFilter::Warn,
            LogLevel::Info => log::LevelFilter::Info,
            LogLevel::Debug => log::LevelFilter::Debug,
            LogLevel::Trace => log::LevelFilter::Trace,
        }
    }
}

/// One input source.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum InputConfig {
    /// Replay recordings (the recorded-input simulator), through the same thread and
    /// queue a device uses.
    Replay {
        /// Recording files, played in order (relative paths are relative to the config file).
        files: Vec<PathBuf>,
        /// Start again after the last file.
        #[serde(default)]
        looped: bool,
        /// Pause between files (ms).
        #[serde(default = "default_gap_ms")]
        gap_ms: u64,
        /// Reset the crowd (agents walk back) before each file.
        #[serde(default)]
        reset_between: bool,
    },
    /// A touch device (evdev or hidraw), found by discovery, read on a real-time
    /// thread, re-attached when it comes back after an unplug.
    Device {
        /// Which device.
        #[serde(default)]
        select: DeviceSelect,
        /// Through which interface.
        #[serde(default)]
        interface: DeviceInterface,
        /// Take the device exclusively (EVIOCGRAB) so the desktop does not also react.
        /// Applied once every finger has lifted.
        #[serde(default)]
        grab: bool,
        /// The part of the table this device covers, in table units (the unit square);
        /// `None` is the whole table. Several devices make one table this way.
        #[serde(default)]
        region: Option<Rect>,
        /// Rotation, flips and calibration matrix.
        #[serde(default)]
        calibration: CalibrationConfig,
        /// Contacts larger than this (mm, from the reported contact size) are palms:
        /// ignored for control and reported as such. `None` keeps every contact
        /// (firmware palm flags still apply).
        #[serde(default = "default_palm_max_mm")]
        palm_max_mm: Option<f64>,
        /// Physical size of the surface (mm) when the device reports no resolution.
        #[serde(default)]
        size_mm: Option<(f64, f64)>,
    },
}

fn default_gap_ms() -> u64 {
    1000
}

/// Which touch device a `Device` input reads.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceSelect {
    /// The best touch device found: a touchscreen over a touchpad, then the one with
    /// the most contacts, then the largest (`crowdtouch devices` shows the pick).
    #[default]
    Auto,
    /// Name contains this text (case-insensitive), or matches it as a `*` glob.
    Name(String),
    /// USB/HID ids, `"2575:0204"` (hex).
    VendorProduct(String),
    /// A device node, `"/dev/input/event5"` (changes between boots; prefer `Id`).
    Path(PathBuf),
    /// A stable id as `crowdtouch devices` prints it (udev ID_PATH, or vendor:product:serial).
    Id(String),
}

/// Which kernel interface to read a device through.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DeviceInterface {
    /// evdev when the kernel handles the device, else hidraw.
    #[default]
    Any,
    /// `/dev/input/eventN` only.
    Evdev,
    /// `/dev/hidrawN` only (raw HID digitizer reports).
    Hidraw,
}

/// How a device's coordinates are corrected before they reach the table.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    /// Clockwise rotation in degrees: 0, 90, 180 or 270.
    #[serde(default)]
    pub rotation: u16,
    /// Mirror left-right (after rotation).
    #[serde(default)]
    pub flip_x: bool,
    /// Mirror top-bottom (after rotation).
    #[serde(default)]
    pub flip_y: bool,
    /// 2×3 matrix `(a, b, c, d, e, f)` in libinput's LIBINPUT_CALIBRATION_MATRIX
    /// convention (`x' = a·x + b·y + c`, `y' = d·x + e·y + f` on unit coordinates),
    /// applied first. `None` uses the udev property when the device has one.
    /// `crowdtouch calibrate --write` fills this in.
    #[serde(default)]
    pub matrix: Option<[f64; 6]>,
}

/// Default largest contact that still counts as a finger (mm).
pub const DEFAULT_PALM_MAX_MM: f64 = 30.0;

fn default_palm_max_mm() -> Option<f64> {
    Some(DEFAULT_PALM_MAX_MM)
}

/// How the touch surface maps onto the world.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceConfig {
    /// The world rectangle the whole surface shows (m).
    pub world: Rect,
    /// Physical size of the surface (mm), used when the device does not report its
    /// resolution. `None` assumes 1 mm per 1/1000 of the width.
    #[serde(default)]
    pub size_mm: Option<(f64, f64)>,
}

/// The crowd.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrowdConfig {
    /// Number of agents.
    pub agents: u32,
    /// Agent radius (m); agents push each other apart below twice this distance.
    pub agent_radius_m: f64,
    /// Maximum agent speed (m/s).
    pub max_speed_m_s: f64,
    /// Maximum agent acceleration (m/s²).
    pub max_accel_m_s2: f64,
    /// Proportional gain of the PD controller towards the goal (1/s²).
    pub kp_per_s2: f64,
    /// Derivative gain of the PD controller (1/s).
    pub kd_per_s: f64,
    /// Stiffness of the spring-mass push-back between overlapping agents (1/s²).
    pub push_stiffness_per_s2: f64,
    /// Initial formation: rectangle the crowd fills at start and after a reset (m).
    pub formation: Rect,
}

/// The deformable mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshConfig {
    /// Vertices along x.
    pub cols: u32,
    /// Vertices along y.
    pub rows: u32,
    /// Weight of a finger's own vertex in the ARAP solve (hard-ish constraint).
    pub handle_weight: f64,
    /// Weight of supplementary line/area points (soft constraints).
    pub soft_weight: f64,
}

/// Grouping touches into controls and gestures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlsConfig {
    /// Fingers landing within this window of a control's first finger join it (ms).
    pub group_window_ms: u64,
    /// ...and only if within this distance of one of its fingers on the surface (mm).
    pub hand_span_mm: f64,
    /// A touch grabs the crowd if it lands within this distance of the mesh (m).
    pub grab_radius_m: f64,
    /// A gesture ends this long after its last finger lifts (ms).
    pub gesture_grace_ms: u64,
    /// Spacing of check points along a finger's trajectory (m).
    pub checkpoint_spacing_m: f64,
    /// Fastest a constraint may move towards its finger (m/s).
    pub max_constraint_speed_m_s: f64,
    /// Gain of the opposing force that slows constraints while agents lag (1/s):
    /// force = gain × mean agent-to-goal distance, never more than the constraint speed.
    pub opposing_gain_per_s: f64,
}

/// Cost of sending an agent to a goal.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AssignmentCost {
    /// Squared Euclidean distance: stable, crossing-free assignments (default).
    SquaredDistance,
    /// Euclidean distance (the paper's travel length with no scene).
    Distance,
}

/// How often the optimal assignment is refreshed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AssignmentConfig {
    /// Cost function.
    pub cost: AssignmentCost,
    /// Solve on a worker thread; the control thread uses the newest result (true), or
    /// solve inside the tick (false; replays always solve inside the tick).
    pub worker: bool,
}

/// Formations the crowd switches between at a scene's checkpoints
/// (mesh-formation-control section 7.3; see [`crate::crowd::formation`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FormationsConfig {
    /// `λ` of the least-effort pairing of agents to the new formation's goals
    /// (formation-transform eq. 3), in `[0, 1]`: 1 pairs by travel alone.
    #[serde(default = "default_lambda")]
    pub lambda: f64,
    /// Shapes added to the shipped ones (`square`, `arrow`, `column`, `line`,
    /// `wedge`, `diamond`); one with a shipped name replaces it.
    #[serde(default)]
    pub shapes: Vec<FormationDef>,
}

impl Default for FormationsConfig {
    fn default() -> Self {
        FormationsConfig {
            lambda: DEFAULT_LAMBDA,
            shapes: Vec::new(),
        }
    }
}

fn default_lambda() -> f64 {
    DEFAULT_LAMBDA
}

/// Per-stage budgets (µs): overruns are counted, logged at a rate limit and published.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BudgetsConfig {
    /// Kernel timestamp → frame on the queue.
    pub input_us: u64,
    /// Frame on the queue → control thread picks it up.
    pub queue_us: u64,
    /// One control tick (segment + deform + step + snapshot).
    pub control_us: u64,
    /// Serialising a snapshot.
    pub publish_us: u64,
    /// Kernel timestamp → snapshot bytes written to a client.
    pub end_to_end_us: u64,
    /// One assignment solve on the worker.
    pub assignment_us: u64,
}

/// Real-time scheduling of the latency path (input, control, publisher threads).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RealtimeConfig {
    /// SCHED_FIFO priority 1..=99 for the latency-path threads; `None` keeps normal
    /// scheduling. Needs RLIMIT_RTPRIO (the systemd unit grants it); when refused the
    /// daemon logs it once and runs at normal priority.
    #[serde(default)]
    pub priority: Option<u8>,
    /// Lock all memory into RAM (mlockall), so the latency path never page-faults.
    #[serde(default)]
    pub lock_memory: bool,
    /// CPUs the input threads may run on (`None`: any).
    #[serde(default)]
    pub input_cpus: Option<Vec<usize>>,
}

/// Threads and queues.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineConfig {
    /// Control ticks per second when no input arrives (input frames also tick).
    pub tick_hz: f64,
    /// Capacity of the input → control queue (frames).
    pub queue_frames: u32,
    /// Stage budgets.
    pub budgets: BudgetsConfig,
    /// How often `stats` is published (ms).
    pub stats_interval_ms: u64,
    /// Real-time scheduling and memory locking.
    #[serde(default)]
    pub realtime: RealtimeConfig,
}

/// The Unix socket.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SocketConfig {
    /// Socket path; `None` uses `$RUNTIME_DIRECTORY/crowdtouch.sock` under systemd,
    /// else `$XDG_RUNTIME_DIR/crowdtouch.sock`, else `/tmp/crowdtouch-$UID.sock`.
    #[serde(default)]
    pub path: Option<PathBuf>,
    /// File mode of the socket, octal as a string ("0660").
    pub mode: String,
    /// Group owning the socket, `None` to keep the process's group.
    #[serde(default)]
    pub group: Option<String>,
    /// Snapshots queued per client before the oldest are dropped.
    pub client_queue: u32,
    /// Most clients at once.
    pub max_clients: u32,
}

impl SocketConfig {
    /// The socket mode as a number.
    pub fn mode_bits(&self) -> u32 {
        u32::from_str_radix(self.mode.trim_start_matches("0o"), 8).unwrap_or(0o660)
    }

    /// The socket path this config resolves to in the current environment.
    pub fn resolved_path(&self) -> PathBuf {
        if let Some(p) = &self.path {
            return p.clone();
        }
        if let Some(dir) = std::env::var_os("RUNTIME_DIRECTORY") {
            // systemd may list several directories separated by ':'.
            let first = dir
                .to_string_lossy()
                .split(':')
                .next()
                .unwrap_or("")
                .to_string();
            if !first.is_empty() {
                return PathBuf::from(first).join("crowdtouch.sock");
            }
        }
        if let Some(dir) = std::env::var_os("XDG_RUNTIME_DIR") {
            return PathBuf::from(dir).join("crowdtouch.sock");
        }
        PathBuf::from(format!("/tmp/crowdtouch-{}.sock", nix::unistd::getuid()))
    }
}

/// The whole config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// Format version; must be [`CONFIG_VERSION`].
    pub version: u32,
    /// Log verbosity (`RUST_LOG` overrides).
    pub log_level: LogLevel,
    /// Input sources.
    pub inputs: Vec<InputConfig>,
    /// Surface to world mapping.
    pub surface: SurfaceConfig,
    /// The crowd.
    pub crowd: CrowdConfig,
    /// The deformable mesh.
    pub mesh: MeshConfig,
    /// Controls and gestures.
    pub controls: ControlsConfig,
    /// Agent-to-goal assignment.
    pub assignment: AssignmentConfig,
    /// The environment: a scene file (obstacles, travel-speed patches, moving things;
    /// see [`crate::crowd::environment`]), relative to the config file. The shipped scenes
    /// (`config/scenes/<name>.ron`) are also embedded in the binary and found by file
    /// name when the path does not exist. `None`: open ground, no environment.
    /// Loading a config (at start and on every SIGHUP) reads the scene file again.
    #[serde(default)]
    pub scene: Option<PathBuf>,
    /// The scene, loaded and validated with the config.
    #[serde(skip)]
    loaded_scene: Option<Arc<Scene>>,
    /// Formation shapes a scene's checkpoints switch to.
    #[serde(default)]
    pub formations: FormationsConfig,
    /// The shipped shapes and `formations.shapes`, validated with the config.
    #[serde(skip)]
    library: Arc<FormationLibrary>,
    /// Threads, queues and budgets.
    pub pipeline: PipelineConfig,
    /// The Unix socket.
    pub socket: SocketConfig,
}

impl Config {
    /// The embedded default (`config/crowdtouch.ron`).
    pub fn embedded_default() -> Config {
        match Config::from_str(DEFAULT_CONFIG_RON, Path::new("<embedded>")) {
            Ok(c) => c,
            // The shipped file is checked by tests; reaching this is a build defect.
            Err(e) => panic!("embedded default config is invalid: {e}"),
        }
    }

    /// Reads and validates a config file. Relative input paths are resolved against
    /// the file's directory.
    ///
    /// # Errors
    /// [`Error::Io`], [`Error::TooLarge`] or [`Error::Invalid`] with every problem.
    pub fn load(path: &Path) -> Result<Config, Error> {
        let text = read_capped(path, MAX_CONFIG_BYTES).map_err(Error::from)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Config::from_str_at(&text, path, base)
    }

    /// Parses and validates config text; `path` is used in messages only. Relative
    /// paths (recordings, the scene) stay relative to the working directory.
    ///
    /// # Errors
    /// [`Error::Invalid`] listing every problem with line, column and field.
    #[allow(clippy::should_implement_trait)]
    pub fn from_str(text: &str, path: &Path) -> Result<Config, Error> {
        Config::from_str_at(text, path, Path::new(""))
    }

    /// [`Config::from_str`] with relative paths resolved against `base`; the scene
    /// is loaded and validated (its problems are reported at the `scene` field).
    fn from_str_at(text: &str, path: &Path, base: &Path) -> Result<Config, Error> {
        let mut cfg: Config = parse_strict(text).map_err(|issue| Error::Invalid {
            path: path.to_path_buf(),
            issues: vec![issue],
        })?;
        let mut problems = cfg.validate();
        match FormationLibrary::with(&cfg.formations.shapes) {
            Ok(lib) => cfg.library = Arc::new(lib),
            Err(e) => problems.extend(
                e.into_iter()
                    .map(|(f, m)| (format!("formations.shapes{f}"), m)),
            ),
        }
        if problems.is_empty() {
            cfg.resolve_paths(base);
            if let Some(scene_path) = &cfg.scene {
                match crate::crowd::environment::load_scene(scene_path, cfg.crowd.agent_radius_m)
                    .and_then(|s| {
                        s.check_formations(scene_path, &cfg.library.known_names())
                            .map(|()| s)
                    }) {
                    Ok(scene) => cfg.loaded_scene = Some(Arc::new(scene)),
                    Err(e) => {
                        problems.push(("scene".to_string(), format!("scene not usable:\n{e}")))
                    }
                }
            }
        }
        if problems.is_empty() {
            Ok(cfg)
        } else {
            let mut issues: Vec<ConfigIssue> = problems
                .into_iter()
                .map(|(field, message)| {
                    let (line, column) = locate_field(text, &field).unwrap_or((0, 0));
                    ConfigIssue {
                        field,
                        line,
                        column,
                        message,
                    }
                })
                .collect();
            issues.sort_by_key(|i| (i.line, i.column));
            Err(Error::Invalid {
                path: path.to_path_buf(),
                issues,
            })
        }
    }

    /// The loaded scene (`None` without a `scene` field).
    pub fn loaded_scene(&self) -> Option<&Arc<Scene>> {
        self.loaded_scene.as_ref()
    }

    /// The formation shapes: shipped and `formations.shapes`.
    pub fn formation_library(&self) -> &Arc<FormationLibrary> {
        &self.library
    }

    /// Replaces the scene (tests and tools that build a scene in memory); the
    /// `scene` path is left as it is.
    pub fn set_loaded_scene(&mut self, scene: Option<Arc<Scene>>) {
        self.loaded_scene = scene;
    }

    fn resolve_paths(&mut self, base: &Path) {
        if let Some(s) = &mut self.scene {
            if s.is_relative() {
                *s = base.join(&*s);
            }
        }
        for input in &mut self.inputs {
            match input {
                InputConfig::Replay { files, .. } => {
                    for f in files.iter_mut() {
                        if f.is_relative() {
                            *f = base.join(&*f);
                        }
                    }
                }
                InputConfig::Device { .. } => {}
            }
        }
    }

    /// Range checks; returns `(field path, message)` for every problem.
    pub fn validate(&self) -> Vec<(String, String)> {
        let mut p = Vec::new();
        let mut check = |ok: bool, field: &str, msg: String| {
            if !ok {
                p.push((field.to_string(), msg));
            }
        };
        check(
            self.version == CONFIG_VERSION,
            "version",
            format!(
                "version {} is not supported (this build reads version {CONFIG_VERSION})",
                self.version
            ),
        );
        let w = &self.surface.world;
        check(
            finite_rect(w) && w.width() > 0.0 && w.height() > 0.0,
            "surface.world",
            format!(
                "world rectangle must have finite min < max, got {:?} .. {:?}",
                w.min, w.max
            ),
        );
        if let Some((mw, mh)) = self.surface.size_mm {
            check(
                mw.is_finite() && mh.is_finite() && mw > 0.0 && mh > 0.0,
                "surface.size_mm",
                format!("surface size must be positive millimetres, got ({mw}, {mh})"),
            );
        }
        let c = &self.crowd;
        check(
            (1..=MAX_AGENTS).contains(&c.agents),
            "crowd.agents",
            format!("agent count must be 1..={MAX_AGENTS}, got {}", c.agents),
        );
        check(
            c.agent_radius_m > 0.0 && c.agent_radius_m <= 5.0,
            "crowd.agent_radius_m",
            format!("agent radius must be in (0, 5] m, got {}", c.agent_radius_m),
        );
        check(
            c.max_speed_m_s > 0.0 && c.max_speed_m_s <= 50.0,
            "crowd.max_speed_m_s",
            format!("max speed must be in (0, 50] m/s, got {}", c.max_speed_m_s),
        );
        check(
            c.max_accel_m_s2 > 0.0 && c.max_accel_m_s2 <= 1000.0,
            "crowd.max_accel_m_s2",
            format!(
                "max acceleration must be in (0, 1000] m/s², got {}",
                c.max_accel_m_s2
            ),
        );
        check(
            c.kp_per_s2 > 0.0 && c.kp_per_s2.is_finite(),
            "crowd.kp_per_s2",
            format!("kp must be positive, got {}", c.kp_per_s2),
        );
        check(
            c.kd_per_s >= 0.0 && c.kd_per_s.is_finite(),
            "crowd.kd_per_s",
            format!("kd must be zero or positive, got {}", c.kd_per_s),
        );
        check(
            c.push_stiffness_per_s2 >= 0.0 && c.push_stiffness_per_s2.is_finite(),
            "crowd.push_stiffness_per_s2",
            format!(
                "push stiffness must be zero or positive, got {}",
                c.push_stiffness_per_s2
            ),
        );
        let f = &c.formation;
        check(
            finite_rect(f) && f.width() > 0.0 && f.height() > 0.0,
            "crowd.formation",
            format!(
                "formation rectangle must have finite min < max, got {:?} .. {:?}",
                f.min, f.max
            ),
        );
        let m = &self.mesh;
        check(
            (2..=200).contains(&m.cols),
            "mesh.cols",
            format!("mesh columns must be 2..=200, got {}", m.cols),
        );
        check(
            (2..=200).contains(&m.rows),
            "mesh.rows",
            format!("mesh rows must be 2..=200, got {}", m.rows),
        );
        check(
            m.handle_weight > 0.0 && m.handle_weight.is_finite(),
            "mesh.handle_weight",
            format!("handle weight must be positive, got {}", m.handle_weight),
        );
        check(
            m.soft_weight > 0.0 && m.soft_weight.is_finite(),
            "mesh.soft_weight",
            format!("soft weight must be positive, got {}", m.soft_weight),
        );
        let k = &self.controls;
        check(
            k.group_window_ms <= 5_000,
            "controls.group_window_ms",
            format!(
                "group window must be at most 5000 ms, got {}",
                k.group_window_ms
            ),
        );
        check(
            k.hand_span_mm > 0.0 && k.hand_span_mm.is_finite(),
            "controls.hand_span_mm",
            format!(
                "hand span must be positive millimetres, got {}",
                k.hand_span_mm
            ),
        );
        check(
            k.grab_radius_m >= 0.0 && k.grab_radius_m.is_finite(),
            "controls.grab_radius_m",
            format!(
                "grab radius must be zero or positive, got {}",
                k.grab_radius_m
            ),
        );
        check(
            k.gesture_grace_ms <= 10_000,
            "controls.gesture_grace_ms",
            format!(
                "gesture grace must be at most 10000 ms, got {}",
                k.gesture_grace_ms
            ),
        );
        check(
            k.checkpoint_spacing_m > 0.0 && k.checkpoint_spacing_m.is_finite(),
            "controls.checkpoint_spacing_m",
            format!(
                "check point spacing must be positive, got {}",
                k.checkpoint_spacing_m
            ),
        );
        check(
            k.max_constraint_speed_m_s > 0.0 && k.max_constraint_speed_m_s.is_finite(),
            "controls.max_constraint_speed_m_s",
            format!(
                "max constraint speed must be positive, got {}",
                k.max_constraint_speed_m_s
            ),
        );
        check(
            k.opposing_gain_per_s >= 0.0 && k.opposing_gain_per_s.is_finite(),
            "controls.opposing_gain_per_s",
            format!(
                "opposing gain must be zero or positive, got {}",
                k.opposing_gain_per_s
            ),
        );
        let pl = &self.pipeline;
        check(
            pl.tick_hz >= 1.0 && pl.tick_hz <= 2000.0,
            "pipeline.tick_hz",
            format!("tick rate must be 1..=2000 Hz, got {}", pl.tick_hz),
        );
        check(
            (2..=65_536).contains(&pl.queue_frames),
            "pipeline.queue_frames",
            format!("queue must hold 2..=65536 frames, got {}", pl.queue_frames),
        );
        check(
            (100..=3_600_000).contains(&pl.stats_interval_ms),
            "pipeline.stats_interval_ms",
            format!(
                "stats interval must be 100..=3600000 ms, got {}",
                pl.stats_interval_ms
            ),
        );
        if let Some(prio) = pl.realtime.priority {
            check(
                (1..=99).contains(&prio),
                "pipeline.realtime.priority",
                format!("real-time priority must be 1..=99 (or None), got {prio}"),
            );
        }
        let b = &pl.budgets;
        for (name, v) in [
            ("input_us", b.input_us),
            ("queue_us", b.queue_us),
            ("control_us", b.control_us),
            ("publish_us", b.publish_us),
            ("end_to_end_us", b.end_to_end_us),
            ("assignment_us", b.assignment_us),
        ] {
            check(
                v > 0,
                &format!("pipeline.budgets.{name}"),
                "budget must be positive microseconds".to_string(),
            );
        }
        let s = &self.socket;
        check(
            u32::from_str_radix(s.mode.trim_start_matches("0o"), 8)
                .map(|m| m <= 0o777)
                .unwrap_or(false),
            "socket.mode",
            format!("socket mode must be octal like \"0660\", got {:?}", s.mode),
        );
        check(
            (1..=4096).contains(&s.client_queue),
            "socket.client_queue",
            format!(
                "client queue must be 1..=4096 snapshots, got {}",
                s.client_queue
            ),
        );
        check(
            (1..=1024).contains(&s.max_clients),
            "socket.max_clients",
            format!("max clients must be 1..=1024, got {}", s.max_clients),
        );
        if let Some(g) = &s.group {
            check(
                !g.is_empty(),
                "socket.group",
                "group name is empty".to_string(),
            );
        }
        for (i, input) in self.inputs.iter().enumerate() {
            match input {
                InputConfig::Replay { files, .. } => check(
                    !files.is_empty(),
                    &format!("inputs[{i}].files"),
                    "a replay input needs at least one file".to_string(),
                ),
                InputConfig::Device {
                    select,
                    region,
                    calibration,
                    palm_max_mm,
                    size_mm,
                    ..
                } => {
                    match select {
                        DeviceSelect::Name(n) | DeviceSelect::Id(n) => check(
                            !n.trim().is_empty(),
                            &format!("inputs[{i}].select"),
                            "the name or id to select is empty".to_string(),
                        ),
                        DeviceSelect::VendorProduct(vp) => check(
                            parse_vendor_product(vp).is_some(),
                            &format!("inputs[{i}].select"),
                            format!("vendor:product must be two hex numbers like \"2575:0204\", got {vp:?}"),
                        ),
                        DeviceSelect::Path(p) => check(
                            p.is_absolute(),
                            &format!("inputs[{i}].select"),
                            format!("device path must be absolute, got {}", p.display()),
                        ),
                        DeviceSelect::Auto => {}
                    }
                    if let Some(r) = region {
                        check(
                            finite_rect(r) && r.min[0] >= 0.0 && r.min[1] >= 0.0 && r.max[0] <= 1.0 && r.max[1] <= 1.0
                                && r.width() > 0.0 && r.height() > 0.0,
                            &format!("inputs[{i}].region"),
                            format!("region must be a rectangle inside the unit square (table units), got {:?} .. {:?}", r.min, r.max),
                        );
                    }
                    check(
                        matches!(calibration.rotation, 0 | 90 | 180 | 270),
                        &format!("inputs[{i}].calibration.rotation"),
                        format!(
                            "rotation must be 0, 90, 180 or 270 degrees, got {}",
                            calibration.rotation
                        ),
                    );
                    if let Some(m) = calibration.matrix {
                        check(
                            m.iter().all(|v| v.is_finite()),
                            &format!("inputs[{i}].calibration.matrix"),
                            "calibration matrix values must be finite".to_string(),
                        );
                    }
                    if let Some(p) = palm_max_mm {
                        check(
                            p.is_finite() && *p > 0.0,
                            &format!("inputs[{i}].palm_max_mm"),
                            format!("palm size must be positive millimetres, got {p}"),
                        );
                    }
                    if let Some((w, h)) = size_mm {
                        check(
                            w.is_finite() && h.is_finite() && *w > 0.0 && *h > 0.0,
                            &format!("inputs[{i}].size_mm"),
                            format!("size must be positive millimetres, got ({w}, {h})"),
                        );
                    }
                }
            }
        }
        if let Some(cpus) = &pl.realtime.input_cpus {
            let n = std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1024)
                .max(1024);
            check(
                !cpus.is_empty() && cpus.iter().all(|&c| c < n),
                "pipeline.realtime.input_cpus",
                format!("CPU list must be non-empty CPU numbers, got {cpus:?}"),
            );
        }
        let l = self.formations.lambda;
        check(
            (0.0..=1.0).contains(&l),
            "formations.lambda",
            format!("least-effort weight must be in 0 ..= 1, got {l}"),
        );

        p
    }

    /// Metres in the world per millimetre on the surface, per axis.
    pub fn world_per_mm(&self, surface_mm: Option<(f64, f64)>) -> Vec2 {
        let (w_mm, h_mm) = surface_mm.or(self.surface.size_mm).unwrap_or((
            1000.0,
            1000.0 * self.surface.world.height() / self.surface.world.width(),
        ));
        Vec2::new(
            self.surface.world.width() / w_mm,
            self.surface.world.height() / h_mm,
        )
    }
}

fn finite_rect(r: &Rect) -> bool {
    r.min.iter().chain(r.max.iter()).all(|v| v.is_finite())
}

/// Writes a calibration matrix into the config text of input `input` (a `Device`
/// input), keeping every comment and the rest of the text as it is: replaces the
/// value of `inputs[N].calibration.matrix`, or adds the field. The result is
/// validated before it is returned.
///
/// # Errors
/// A message when input `input` is not a `Device` input, the text cannot be edited
/// safely, or the result is not a valid config.
pub fn set_calibration_matrix(text: &str, input: usize, m: [f64; 6]) -> Result<String, String> {
    let value = format!(
        "Some(({}, {}, {}, {}, {}, {}))",
        fmt6(m[0]),
        fmt6(m[1]),
        fmt6(m[2]),
        fmt6(m[3]),
        fmt6(m[4]),
        fmt6(m[5])
    );
    let cfg = Config::from_str(text, Path::new("<config>")).map_err(|e| e.to_string())?;
    if !matches!(cfg.inputs.get(input), Some(InputConfig::Device { .. })) {
        return Err(format!("inputs[{input}] is not a Device input"));
    }
    let fields = field_positions(text);
    let offset = |line: usize, col: usize| -> Option<usize> {
        let mut off = 0;
        for (i, l) in text.split_inclusive('\n').enumerate() {
            if i + 1 == line {
                return l.char_indices().nth(col - 1).map(|(b, _)| off + b);
            }
            off += l.len();
        }
        None
    };
    let find = |path: &str| {
        fields
            .iter()
            .find(|(p, _, _)| p == path)
            .and_then(|(_, l, c)| offset(*l, *c))
    };
    let edited = if let Some(at) = find(&format!("inputs[{input}].calibration.matrix")) {
        // Replace the value after `matrix:` up to the end of `None` or the `Some(...)`.
        let colon = at + text[at..].find(':').ok_or("no ':' after matrix")? + 1;
        let start = colon + (text[colon..].len() - text[colon..].trim_start().len());
        let rest = &text[start..];
        let end = if rest.starts_with("None") {
            start + 4
        } else if rest.starts_with("Some") {
            let open = start + rest.find('(').ok_or("no '(' after Some")?;
            let mut depth = 0usize;
            let mut end = None;
            for (i, ch) in text[open..].char_indices() {
                match ch {
                    '(' | '[' => depth += 1,
                    ')' | ']' => {
                        depth -= 1;
                        if depth == 0 {
                            end = Some(open + i + 1);
                            break;
                        }
                    }
                    _ => {}
                }
            }
            end.ok_or("unbalanced parentheses in matrix")?
        } else {
            return Err("the matrix value is neither None nor Some(...)".into());
        };
        format!("{}{}{}", &text[..start], value, &text[end..])
    } else if let Some(at) = find(&format!("inputs[{input}].calibration")) {
        let open = at + text[at..].find('(').ok_or("no '(' after calibration")? + 1;
        format!("{}matrix: {}, {}", &text[..open], value, &text[open..])
    } else {
        // Neither: add `calibration: (...)` right after `Device(` of that input.
        let inputs_at = find("inputs").ok_or("no inputs field")?;
        let mut idx = 0;
        let mut search = inputs_at;
        let mut pos = None;
        while let Some(rel) = text[search..].find("Device(") {
            let p = search + rel;
            if idx == input {
                pos = Some(p + "Device(".len());
                break;
            }
            idx += 1;
            search = p + 1;
        }
        let p = pos.ok_or("cannot find the Device input in the text")?;
        format!(
            "{}calibration: (matrix: {}), {}",
            &text[..p],
            value,
            &text[p..]
        )
    };
    Config::from_str(&edited, Path::new("<edited>"))
        .map_err(|e| format!("the edited config is invalid: {e}"))?;
    Ok(edited)
}

fn fmt6(v: f64) -> String {
    let s = format!("{v:.6}");
    if s == "-0.000000" {
        "0.000000".into()
    } else {
        s
    }
}

/// Where `run` looks for its config when `--config` is not given, in order.
pub fn search_path() -> Vec<PathBuf> {
    let mut v = Vec::new();
    if let Some(p) = std::env::var_os("CROWDTOUCH_CONFIG") {
        v.push(PathBuf::from(p));
    }
    if let Some(d) = std::env::var_os("XDG_CONFIG_HOME") {
        v.push(PathBuf::from(d).join("crowdtouch/crowdtouch.ron"));
    } else if let Some(h) = std::env::var_os("HOME") {
        v.push(PathBuf::from(h).join(".config/crowdtouch/crowdtouch.ron"));
    }
    v.push(PathBuf::from("/etc/crowdtouch/crowdtouch.ron"));
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn issues(text: &str) -> Vec<ConfigIssue> {
        match Config::from_str(text, Path::new("t.ron")) {
            Err(Error::Invalid { issues, .. }) => issues,
            other => panic!("expected invalid, got {other:?}"),
        }
    }

    #[test]
    fn formation_shapes_and_checkpoint_names_are_checked_where_they_are_written() {
        let shapes = |text: &str| DEFAULT_CONFIG_RON.replace("        shapes: [],", text);
        // A bow tie and a shape given twice, each at its own entry.
        let text = shapes(
            "        shapes: [\n            (name: \"bow\", outline: [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]),\n            (name: \"t\", outline: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]),\n            (name: \"t\", outline: [(0.0, 0.0), (2.0, 0.0), (0.0, 1.0)]),\n        ],",
        );
        let e = Config::from_str(&text, Path::new("f.ron"))
            .unwrap_err()
            .to_string();
        let line = |needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
        assert!(
            e.contains(&format!("f.ron:{}:", line("\"bow\"")))
                && e.contains("field `formations.shapes[0].outline`: edges 0 and 2 cross or touch"),
            "{e}"
        );
        assert!(
            e.contains(&format!("f.ron:{}:", line("(2.0, 0.0)")))
                && e.contains("field `formations.shapes[2].name`: formation `t` is defined twice"),
            "{e}"
        );
        let lambda = DEFAULT_CONFIG_RON.replace("lambda: 0.5", "lambda: 1.5");
        let e = Config::from_str(&lambda, Path::new("l.ron"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "field `formations.lambda`: least-effort weight must be in 0 ..= 1, got 1.5"
            ),
            "{e}"
        );
        // A config without the section gets the shipped shapes; one that adds a
        // shape can use it in a scene.
        let bare: String = {
            let start = DEFAULT_CONFIG_RON.find("    formations: (").unwrap();
            let end = start + DEFAULT_CONFIG_RON[start..].find("    ),\n").unwrap() + 7;
            format!(
                "{}{}",
                &DEFAULT_CONFIG_RON[..start],
                &DEFAULT_CONFIG_RON[end..]
            )
        };
        let c = Config::from_str(&bare, Path::new("b.ron")).unwrap();
        assert!(c.formation_library().knows("arrow") && !c.formation_library().knows("t"));
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("gate.ron"),
            "(version: 1, bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n checkpoints: [(name: \"g\", formation: \"t\", region: Circle(centre_m: (3.0, 3.0), radius_m: 1.0))])",
        )
        .unwrap();
        let with_scene = |t: &str| t.replace("scene: None", "scene: Some(\"gate.ron\")");
        let cfg = dir.path().join("c.ron");
        std::fs::write(&cfg, with_scene(&bare)).unwrap();
        let e = Config::load(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("field `scene`")
                && e.contains("gate.ron:2:")
                && e.contains("checkpoints[0].formation: no formation is called `t`"),
            "{e}"
        );
        std::fs::write(
            &cfg,
            with_scene(&shapes(
                "        shapes: [(name: \"t\", outline: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])],",
            )),
        )
        .unwrap();
        let c = Config::load(&cfg).unwrap();
        assert_eq!(c.loaded_scene().unwrap().checkpoints()[0].formation, "t");
    }

    #[test]
    fn scene_field_loads_shipped_embedded_and_reports_bad_scenes() {
        let with = |scene: &str| DEFAULT_CONFIG_RON.replace("scene: None", scene);
        // No scene: nothing loaded.
        let c = Config::embedded_default();
        assert!(c.scene.is_none() && c.loaded_scene().is_none());
        // A shipped name that does not exist on disk resolves to the embedded copy.
        let c = Config::from_str(
            &with("scene: Some(\"/nonexistent/scenes/single_block.ron\")"),
            Path::new("t.ron"),
        )
        .unwrap();
        assert_eq!(c.loaded_scene().unwrap().name(), "single block");
        // Relative to the config file.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("bad.ron"),
            "(version: 1, bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n obstacles: [(parts: [Circle(centre_m: (4.0, 4.0), radius_m: -1.0)])])",
        )
        .unwrap();
        let cfg = dir.path().join("c.ron");
        std::fs::write(&cfg, with("scene: Some(\"bad.ron\")")).unwrap();
        let e = Config::load(&cfg).unwrap_err().to_string();
        let line = with("scene: Some(\"bad.ron\")")
            .lines()
            .position(|l| l.contains("scene: Some"))
            .unwrap()
            + 1;
        assert!(e.contains(&format!("c.ron:{line}:")), "{e}");
        assert!(e.contains("field `scene`"), "{e}");
        assert!(e.contains("bad.ron:2:"), "{e}");
        // A missing file that is not a shipped name.
        let e = Config::from_str(&with("scene: Some(\"nope.ron\")"), Path::new("t.ron"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("field `scene`") && e.contains("nope.ron"), "{e}");
    }

    #[test]
    fn embedded_default_is_valid() {
        let c = Config::embedded_default();
        assert_eq!(c.crowd.agents, 100);
        assert_eq!(c.controls.group_window_ms, 150);
    }

    #[test]
    fn out_of_range_values_name_field_line_and_column() {
        let text = DEFAULT_CONFIG_RON.replacen("agents: 100", "agents: 0", 1);
        let is = issues(&text);
        assert_eq!(is.len(), 1, "{is:?}");
        assert_eq!(is[0].field, "crowd.agents");
        let expect_line = text.lines().position(|l| l.contains("agents: 0")).unwrap() + 1;
        assert_eq!(is[0].line, expect_line);
        assert!(is[0].column > 1);
        assert!(is[0].message.contains("1..="), "{}", is[0].message);
    }

    #[test]
    fn every_range_problem_is_reported() {
        let text = DEFAULT_CONFIG_RON
            .replacen("agents: 100", "agents: 0", 1)
            .replacen("tick_hz: 120.0", "tick_hz: 0.0", 1)
            .replacen("mode: \"0660\"", "mode: \"rw\"", 1);
        let fields: Vec<String> = issues(&text).into_iter().map(|i| i.field).collect();
        assert_eq!(
            fields,
            vec!["crowd.agents", "pipeline.tick_hz", "socket.mode"]
        );
    }

    #[test]
    fn unknown_field_is_an_error_with_its_place() {
        let text =
            DEFAULT_CONFIG_RON.replacen("agents: 100,", "agents: 100,\n        agnets: 5,", 1);
        let is = issues(&text);
        assert_eq!(is.len(), 1);
        assert_eq!(is[0].field, "crowd.agnets");
        let expect_line = text.lines().position(|l| l.contains("agnets")).unwrap() + 1;
        assert_eq!(is[0].line, expect_line);
        assert!(is[0].message.contains("agnets"), "{}", is[0].message);
    }

    #[test]
    fn realtime_priority_is_range_checked_and_optional() {
        let text = DEFAULT_CONFIG_RON.replacen("priority: Some(20)", "priority: Some(0)", 1);
        let is = issues(&text);
        assert_eq!(is[0].field, "pipeline.realtime.priority");
        let none = DEFAULT_CONFIG_RON.replacen("priority: Some(20)", "priority: None", 1);
        assert!(Config::from_str(&none, Path::new("t.ron")).is_ok());
        // The whole section may be left out: normal scheduling.
        let a = DEFAULT_CONFIG_RON.find("        realtime: (").unwrap();
        let b = a + DEFAULT_CONFIG_RON[a..].find("        ),\n").unwrap() + "        ),\n".len();
        let without = format!("{}{}", &DEFAULT_CONFIG_RON[..a], &DEFAULT_CONFIG_RON[b..]);
        let c = Config::from_str(&without, Path::new("t.ron")).unwrap();
        assert_eq!(c.pipeline.realtime, RealtimeConfig::default());
    }

    #[test]
    fn calibration_matrix_is_written_in_place_keeping_comments() {
        let kiosk = include_str!("../config/kiosk.ron");
        let m = [0.0, -1.0, 1.0, 1.0, 0.0, 0.0];
        let out = set_calibration_matrix(kiosk, 0, m).unwrap();
        let c = Config::from_str(&out, Path::new("k")).unwrap();
        match &c.inputs[0] {
            InputConfig::Device { calibration, .. } => assert_eq!(calibration.matrix, Some(m)),
            _ => panic!("not a device"),
        }
        // Only the value changed: every comment line is still there.
        let comments = |t: &str| {
            t.lines()
                .filter(|l| l.trim_start().starts_with("//"))
                .count()
        };
        assert_eq!(comments(&out), comments(kiosk));
        // Writing again replaces the Some(...) value.
        let again = set_calibration_matrix(&out, 0, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        assert!(again.contains(
            "matrix: Some((1.000000, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000))"
        ));
        // An input without a calibration field gets one.
        let bare = kiosk.replace(
            "            calibration: (rotation: 0, flip_x: false, flip_y: false, matrix: None),\n",
            "",
        );
        let added = set_calibration_matrix(&bare, 0, m).unwrap();
        assert!(Config::from_str(&added, Path::new("k")).is_ok());
        // Replay inputs cannot be calibrated.
        assert!(set_calibration_matrix(DEFAULT_CONFIG_RON, 0, m)
            .unwrap_err()
            .contains("not a Device"));
    }

    #[test]
    fn syntax_error_has_position() {
        let is = issues("(version: 1,, )");
        assert_eq!(is[0].line, 1);
        assert!(is[0].column > 0);
    }

    #[test]
    fn missing_field_is_named() {
        let text = DEFAULT_CONFIG_RON.replacen("max_speed_m_s: 1.5,", "", 1);
        let is = issues(&text);
        assert!(is[0].field.ends_with("max_speed_m_s"), "{is:?}");
        assert!(is[0].message.contains("max_speed_m_s"));
    }

    #[test]
    fn missing_file_names_the_path() {
        let e = Config::load(Path::new("/nonexistent/crowdtouch.ron")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/crowdtouch.ron"), "{e}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]
        /// Arbitrary text never panics the parser, and every error points inside it.
        #[test]
        fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
            if let Err(Error::Invalid { issues, .. }) = Config::from_str(&text, Path::new("p.ron")) {
                let lines = text.lines().count().max(1);
                for i in issues {
                    proptest::prop_assert!(i.line <= lines + 1, "line {} of {}", i.line, lines);
                }
            }
        }

        /// The default config with a slice cut out or repeated: an error with a place,
        /// or (rarely) still a valid config; never a panic.
        #[test]
        fn mutated_default_never_panics(a in 0usize..4000, len in 0usize..80, dup in proptest::bool::ANY) {
            let t = DEFAULT_CONFIG_RON;
            let a = a.min(t.len());
            let b = (a + len).min(t.len());
            if !t.is_char_boundary(a) || !t.is_char_boundary(b) {
                return Ok(());
            }
            let mutated = if dup { format!("{}{}", &t[..b], &t[a..]) } else { format!("{}{}", &t[..a], &t[b..]) };
            match Config::from_str(&mutated, Path::new("m.ron")) {
                Ok(_) => {}
                Err(Error::Invalid { issues, .. }) => proptest::prop_assert!(!issues.is_empty()),
                Err(e) => proptest::prop_assert!(false, "unexpected error kind {e}"),
            }
        }
    }

    #[test]
    fn garbage_never_panics() {
        for t in [
            "",
            "(",
            ")",
            "((((",
            "\"",
            "/*",
            "(version: \"x\")",
            "[1,2",
            "\u{0}",
        ] {
            assert!(Config::from_str(t, Path::new("g")).is_err());
        }
    }
}
