//! The config model: [`Config`] and its sections (the `inputs` sections are in
//! a file of their own).

use super::gestures::GesturesConfig;
use super::inputs::InputConfig;
use super::outputs::OutputConfig;
use super::transform::{
    GestureFormation, SubgroupsConfig, TransformCost, TransformMoveConfig, DEFAULT_METHOD,
};
use crate::crowd::edit::TrackSet;
use crate::crowd::environment::Scene;
use crate::crowd::formation::{FormationDef, FormationLibrary, DEFAULT_LAMBDA};
use crate::geom::Rect;
use crate::gesture::recognise::Recogniser;
use crate::vocab::FormationMethod;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::sync::Arc;

/// The config format version this build reads.
pub const CONFIG_VERSION: u32 = 1;

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
    /// How far a vertex of the crowd's mesh moves per unit of the environment's
    /// potential field (m): the final mesh is `v + field_step_m × F(v)`, then out
    /// of obstacles (mesh-formation-control sections 5 and 6.1, which leave the
    /// amount open: this is crowdtouch's choice). 0 only projects vertices out of
    /// obstacles. Absent: [`DEFAULT_FIELD_STEP_M`].
    #[serde(default = "default_field_step_m")]
    pub field_step_m: f64,
}

/// The default of [`MeshConfig::field_step_m`] (m).
pub const DEFAULT_FIELD_STEP_M: f64 = 0.3;

fn default_field_step_m() -> f64 {
    DEFAULT_FIELD_STEP_M
}

/// Grouping touches into controls and gestures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlsConfig {
    /// Fingers landing within this window of a control's first finger join it (ms).
    pub group_window_ms: u64,
    /// ...and only if within this distance of one of its fingers on the surface (mm).
    pub hand_span_mm: f64,
    /// A finger landing in open space joins a gesture under way if within this
    /// distance of one of its fingers (mm): a person's two hands make one gesture
    /// (join, split); farther, another person's gesture begins.
    #[serde(default = "default_gesture_span_mm")]
    pub gesture_span_mm: f64,
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

/// Default of `controls.gesture_span_mm` (mm): about a person's reach with both hands.
pub const DEFAULT_GESTURE_SPAN_MM: f64 = 600.0;

fn default_gesture_span_mm() -> f64 {
    DEFAULT_GESTURE_SPAN_MM
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
    /// How a formation request (a checkpoint, `set_formation` without a method, a
    /// mapped gesture) is carried out: `transform`, the paper's full model, or
    /// `mesh`, the mesh switch (mesh-formation-control section 7.3).
    #[serde(default = "default_method")]
    pub method: FormationMethod,
    /// How a transform pairs agents with targets (least effort uses `lambda`).
    #[serde(default)]
    pub cost: TransformCost,
    /// How a transform moves the agents.
    #[serde(default)]
    pub transform: TransformMoveConfig,
    /// Subgroups of a transform (affinity propagation).
    #[serde(default)]
    pub subgroups: SubgroupsConfig,
    /// Recognised gesture classes that start a transform to a formation instead of
    /// their crowd motion.
    #[serde(default)]
    pub gestures: Vec<GestureFormation>,
}

impl Default for FormationsConfig {
    fn default() -> Self {
        FormationsConfig {
            lambda: DEFAULT_LAMBDA,
            shapes: Vec::new(),
            method: DEFAULT_METHOD,
            cost: TransformCost::default(),
            transform: TransformMoveConfig::default(),
            subgroups: SubgroupsConfig::default(),
            gestures: Vec::new(),
        }
    }
}

fn default_method() -> FormationMethod {
    DEFAULT_METHOD
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
    /// CPUs the input threads may run on (`None`: any). Numbers below 1024; CPUs
    /// not online on the machine are left out when pinning (a warning from
    /// `check-config` and at start-up, not an error: one config may serve machines
    /// of several sizes), and none online leaves the threads unpinned.
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
    /// Who is privileged besides root and the daemon's own user: their clients
    /// receive the raw touches and may send commands; everyone else is read-only.
    #[serde(default)]
    pub privileged: PrivilegedPeers,
}

/// The users and groups whose Unix-socket clients are privileged
/// (`socket.privileged`), by name or numeric id, resolved when the socket starts.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrivilegedPeers {
    /// User names or uids (`"kiosk"`, `"1001"`).
    #[serde(default)]
    pub users: Vec<String>,
    /// Group names or gids: a client whose process is in one of them (its group
    /// or a supplementary group).
    #[serde(default)]
    pub groups: Vec<String>,
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
        if let Some(first) = std::env::var_os("RUNTIME_DIRECTORY").and_then(first_systemd_dir) {
            return first.join("crowdtouch.sock");
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
    /// Input sources; may be empty: the touches then come only from clients
    /// (`pipeline::TouchSources`).
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
    pub(super) loaded_scene: Option<Arc<Scene>>,
    /// Formation shapes a scene's checkpoints switch to.
    #[serde(default)]
    pub formations: FormationsConfig,
    /// The shipped shapes and `formations.shapes`, validated with the config.
    #[serde(skip)]
    pub(super) library: Arc<FormationLibrary>,
    /// Gesture commands: recognition and the crowd motions they play (may be left
    /// out: the defaults).
    #[serde(default)]
    pub gestures: GesturesConfig,
    /// The gesture library of `gestures.library` (or the shipped one), loaded and
    /// indexed with the config.
    #[serde(skip)]
    pub(super) recogniser: Option<Arc<Recogniser>>,
    /// Edit mode (crowd-motion-editing): a track file at start whose people play
    /// as the crowd and whose tracks fingers edit, and the directory whose entries
    /// clients load and save. `None`: the crowd at start, the default directory
    /// ([`EditConfig::resolved_dir`]), saving never replaces a file.
    #[serde(default)]
    pub edit: Option<EditConfig>,
    /// The tracks of `edit.tracks`, read and validated with the config.
    #[serde(skip)]
    pub(super) loaded_tracks: Option<Arc<TrackSet>>,
    /// Threads, queues and budgets.
    pub pipeline: PipelineConfig,
    /// The Unix socket.
    pub socket: SocketConfig,
    /// Outputs besides the Unix socket: TUIO targets, WebSocket servers (may be
    /// left out: none).
    #[serde(default)]
    pub outputs: Vec<OutputConfig>,
}

/// `edit`: the edit mode at start, and where clients' `edit.load` and `edit.save`
/// read and write.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EditConfig {
    /// The track file to start with (JSON Lines, CSV `t,id,x,y`, ETH/UCY
    /// `frame id x y`), relative to the config file; empty (the default): start
    /// with the crowd. Set by the operator: a path, unlike what clients give.
    #[serde(default)]
    pub tracks: PathBuf,
    /// The directory whose entries clients name in `edit.load` and `edit.save`
    /// (names only, never paths), relative to the config file; `None`:
    /// [`EditConfig::resolved_dir`]'s default under the state directory. The
    /// daemon creates nothing outside it and does not create it.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// Whether `edit.save` with `overwrite: true` may replace an existing entry
    /// (default false: saving only ever creates new files).
    #[serde(default)]
    pub allow_overwrite: bool,
    /// Two people closer than this collide; avoidance after an edit keeps them
    /// apart (m).
    #[serde(default = "default_edit_threshold_m")]
    pub threshold_m: f64,
    /// Whether a release or a retime is shown as a preview that `edit.accept`
    /// keeps and `edit.undo` drops (default true); `false`: applied at once.
    #[serde(default = "default_edit_preview")]
    pub preview: bool,
}

fn default_edit_threshold_m() -> f64 {
    0.3
}

fn default_edit_preview() -> bool {
    true
}

/// The first directory of a systemd directory variable (`$RUNTIME_DIRECTORY`,
/// `$STATE_DIRECTORY`), which lists one per `RuntimeDirectory=`/`StateDirectory=`
/// entry separated by ':'; `None` when it is empty.
fn first_systemd_dir(list: std::ffi::OsString) -> Option<PathBuf> {
    let list = list.to_string_lossy();
    let first = list.split(':').next().unwrap_or("");
    (!first.is_empty()).then(|| PathBuf::from(first))
}

/// The edit directory's name under the state directory.
pub const EDIT_DIR_NAME: &str = "tracks";

impl EditConfig {
    /// The edit directory this config resolves to in the current environment:
    /// `dir` when set, else `tracks` under the state directory —
    /// `$STATE_DIRECTORY/tracks` under systemd (`StateDirectory=crowdtouch`:
    /// `/var/lib/crowdtouch/tracks`), else `$XDG_STATE_HOME/crowdtouch/tracks`,
    /// else `$HOME/.local/state/crowdtouch/tracks`; `None` when none of those is
    /// set (clients' `edit.load` and `edit.save` are then refused).
    pub fn resolved_dir(cfg: Option<&EditConfig>) -> Option<PathBuf> {
        EditConfig::dir_in(cfg, &|k| std::env::var_os(k))
    }

    /// [`EditConfig::resolved_dir`] with the environment variables of `var`.
    fn dir_in(
        cfg: Option<&EditConfig>,
        var: &dyn Fn(&str) -> Option<std::ffi::OsString>,
    ) -> Option<PathBuf> {
        if let Some(d) = cfg.and_then(|c| c.dir.as_ref()) {
            return Some(d.clone());
        }
        let env = |k: &str| var(k).filter(|v| !v.is_empty());
        if let Some(first) = env("STATE_DIRECTORY").and_then(first_systemd_dir) {
            return Some(first.join(EDIT_DIR_NAME));
        }
        if let Some(d) = env("XDG_STATE_HOME") {
            return Some(PathBuf::from(d).join("crowdtouch").join(EDIT_DIR_NAME));
        }
        env("HOME").map(|h| {
            PathBuf::from(h)
                .join(".local/state/crowdtouch")
                .join(EDIT_DIR_NAME)
        })
    }
}

impl Config {
    /// The tracks of `edit.tracks`, when the config names them.
    pub fn loaded_tracks(&self) -> Option<&Arc<TrackSet>> {
        self.loaded_tracks.as_ref()
    }

    /// The loaded scene (`None` without a `scene` field).
    pub fn loaded_scene(&self) -> Option<&Arc<Scene>> {
        self.loaded_scene.as_ref()
    }

    /// The gesture library, indexed for recognition (`None` when gestures are
    /// disabled).
    pub fn gesture_recogniser(&self) -> Option<&Arc<Recogniser>> {
        self.recogniser.as_ref()
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

    /// Starts in edit mode with `tracks` (tests and tools that build tracks in
    /// memory; `source` names them in messages); `None` leaves edit mode off.
    pub fn set_edit_tracks(&mut self, tracks: Option<(Arc<TrackSet>, PathBuf)>, threshold_m: f64) {
        match tracks {
            Some((set, source)) => {
                let (dir, allow_overwrite, preview) =
                    self.edit.as_ref().map_or((None, false, true), |e| {
                        (e.dir.clone(), e.allow_overwrite, e.preview)
                    });
                self.edit = Some(EditConfig {
                    tracks: source,
                    threshold_m,
                    dir,
                    allow_overwrite,
                    preview,
                });
                self.loaded_tracks = Some(set);
            }
            None => {
                if let Some(e) = &mut self.edit {
                    e.tracks = PathBuf::new();
                }
                self.loaded_tracks = None;
            }
        }
    }
}

#[cfg(test)]
mod edit_dir_tests {
    use super::*;
    use std::ffi::OsString;

    fn with<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<OsString> + 'a {
        move |k| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| OsString::from(v))
        }
    }

    /// `edit.dir` when set; else under systemd's state directory (the first of
    /// several), else the XDG state directory, else `~/.local/state`; else none.
    #[test]
    fn the_edit_directory_defaults_to_the_state_directory() {
        let all = [
            (
                "STATE_DIRECTORY",
                "/var/lib/crowdtouch:/var/lib/crowdtouch/tracks",
            ),
            ("XDG_STATE_HOME", "/home/k/.state"),
            ("HOME", "/home/k"),
        ];
        let set = EditConfig {
            tracks: PathBuf::new(),
            threshold_m: 0.3,
            dir: Some(PathBuf::from("/srv/tracks")),
            allow_overwrite: false,
            preview: true,
        };
        assert_eq!(
            EditConfig::dir_in(Some(&set), &with(&all)),
            Some(PathBuf::from("/srv/tracks"))
        );
        assert_eq!(
            EditConfig::dir_in(None, &with(&all)),
            Some(PathBuf::from("/var/lib/crowdtouch/tracks"))
        );
        assert_eq!(
            EditConfig::dir_in(None, &with(&all[1..])),
            Some(PathBuf::from("/home/k/.state/crowdtouch/tracks"))
        );
        assert_eq!(
            EditConfig::dir_in(None, &with(&all[2..])),
            Some(PathBuf::from("/home/k/.local/state/crowdtouch/tracks"))
        );
        assert_eq!(EditConfig::dir_in(None, &with(&[])), None);
    }
}
