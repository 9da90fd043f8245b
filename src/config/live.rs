//! What a reload (SIGHUP) does with each config field: applied to the running
//! daemon, or kept at its running value until a restart.
//!
//! [`FIELDS`] is the table: every field of [`Config`] by its dotted path, with its
//! [`ReloadClass`] and, for a restart field, why it cannot change live. A path names
//! a whole value (`inputs`, `crowd.formation`) or a leaf of a section; the walk over
//! a serialised config stops at the first path the table names, so a field added to
//! a section without a row is found by the tests below (and, at run time, treated as
//! needing a restart).
//!
//! [`plan_reload`] compares the running config with a newly loaded one: the fields
//! that differ ([`FieldChange`]) and the config in effect after the reload (the new
//! one with every restart field kept at its running value), which is what the next
//! reload is compared with. A restart field therefore stays listed until the daemon
//! restarts or the file goes back to the running value.

use super::model::Config;
use serde_json::{Map, Value};

/// How a reload treats a field.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ReloadClass {
    /// Applied to the running daemon by the reload.
    Live,
    /// Read once at start: the running value stays until the daemon restarts.
    Restart,
}

/// One row of [`FIELDS`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct FieldClass {
    /// Dotted path of the field in the config file (`socket.max_clients`).
    pub path: &'static str,
    /// What a reload does with it.
    pub class: ReloadClass,
    /// For a restart field, why it cannot change live; for a live one, how it
    /// takes effect.
    pub how: &'static str,
}

const fn live(path: &'static str, how: &'static str) -> FieldClass {
    FieldClass {
        path,
        class: ReloadClass::Live,
        how,
    }
}

const fn restart(path: &'static str, how: &'static str) -> FieldClass {
    FieldClass {
        path,
        class: ReloadClass::Restart,
        how,
    }
}

/// Every config field and what a reload does with it, in file order.
pub const FIELDS: &[FieldClass] = &[
    live("version", "only the supported version loads"),
    live(
        "log_level",
        "from the next log line (unless RUST_LOG is set)",
    ),
    restart(
        "inputs",
        "input threads open their devices and recordings at start",
    ),
    restart(
        "surface.world",
        "the crowd, its mesh and every client's hello are in world coordinates fixed at start",
    ),
    restart(
        "surface.size_mm",
        "the glass size is fixed when the inputs start",
    ),
    live(
        "crowd.agents",
        "the crowd is resized as `set_agent_count` does (a hard reset)",
    ),
    live("crowd.agent_radius_m", "from the next tick"),
    live("crowd.max_speed_m_s", "from the next tick"),
    live("crowd.max_accel_m_s2", "from the next tick"),
    live("crowd.kp_per_s2", "from the next tick"),
    live("crowd.kd_per_s", "from the next tick"),
    live("crowd.push_stiffness_per_s2", "from the next tick"),
    restart(
        "crowd.formation",
        "the crowd's mesh is built in this rectangle at start",
    ),
    restart(
        "mesh.cols",
        "the mesh and its deformation solver are built at start",
    ),
    restart(
        "mesh.rows",
        "the mesh and its deformation solver are built at start",
    ),
    live("mesh.handle_weight", "from the next touch"),
    live("mesh.soft_weight", "from the next touch"),
    live("mesh.field_step_m", "from the next tick"),
    live("controls.group_window_ms", "from the next touch"),
    live("controls.hand_span_mm", "from the next touch"),
    live("controls.gesture_span_mm", "from the next touch"),
    live("controls.grab_radius_m", "from the next touch"),
    live("controls.gesture_grace_ms", "from the next touch"),
    live("controls.checkpoint_spacing_m", "from the next touch"),
    live("controls.max_constraint_speed_m_s", "from the next tick"),
    live("controls.opposing_gain_per_s", "from the next tick"),
    restart(
        "assignment.cost",
        "the assignment worker is started with its cost",
    ),
    restart(
        "assignment.worker",
        "the worker thread is started, or not, at start",
    ),
    live(
        "scene",
        "the scene file is read again and swapped in from the next tick",
    ),
    live(
        "edit",
        "the track file is read again; tracks that changed are loaded (unsaved edits are dropped), the threshold and `preview` apply from the next edit, `dir` and `allow_overwrite` from the next edit.load or edit.save",
    ),
    live("formations.lambda", "from the next switch"),
    live("formations.shapes", "from the next switch"),
    live("formations.method", "from the next formation request"),
    live("formations.cost", "from the next transform"),
    live(
        "formations.transform",
        "from the next transform; a running one keeps its settings",
    ),
    live(
        "formations.subgroups",
        "from the next transform; a running one keeps its subgroups",
    ),
    live("formations.gestures", "from the next recognised gesture"),
    live(
        "gestures.enabled",
        "from the next gesture; a motion playing plays to its end",
    ),
    live(
        "gestures.library",
        "the library is read again and swapped in for the next gesture; one that does \
         not load leaves the running library",
    ),
    live(
        "gestures.disabled",
        "from the next recognised gesture; a motion playing plays to its end",
    ),
    live(
        "gestures.all_touches_are_gestures",
        "from the next touch; touches already down keep what they are",
    ),
    live("gestures.min_duration_ms", "from the next gesture's end"),
    live("gestures.min_travel_mm", "from the next gesture's end"),
    live("gestures.max_duration_s", "from the next gesture's end"),
    live("gestures.k", "from the next recognition"),
    live("gestures.weights", "from the next recognition"),
    live("gestures.band", "from the next recognition"),
    live(
        "gestures.gmm_components",
        "read when a library is built (`library build --config`); a loaded library \
         keeps the mixtures it was built with",
    ),
    live(
        "gestures.auto_components_max",
        "read when a library is built (`library build --config`); a loaded library \
         keeps the mixtures it was built with",
    ),
    live("gestures.seed", "from the next synthesis"),
    live("gestures.approach_timeout_s", "from the next motion"),
    live("gestures.motion_speed_m_s", "from the next motion"),
    live("gestures.apply", "from the next motion; a motion under way plays on as it began"),
    live("gestures.min_piece_agents", "from the next mesh rebuilt after a motion"),
    live(
        "gestures.collected",
        "the library is indexed again and swapped in for the next gesture",
    ),
    live(
        "gestures.continuous",
        "from the next gesture; a gesture under way keeps its recogniser",
    ),
    live("pipeline.tick_hz", "from the next tick"),
    restart(
        "pipeline.queue_frames",
        "the input queue is allocated at start",
    ),
    live("pipeline.budgets.input_us", "from the next tick"),
    live("pipeline.budgets.queue_us", "from the next tick"),
    live("pipeline.budgets.control_us", "from the next tick"),
    live("pipeline.budgets.publish_us", "from the next stats"),
    live("pipeline.budgets.end_to_end_us", "from the next stats"),
    live("pipeline.budgets.assignment_us", "from the next tick"),
    live("pipeline.stats_interval_ms", "from the next stats"),
    restart(
        "pipeline.realtime.priority",
        "threads take their scheduling when they start",
    ),
    restart("pipeline.realtime.lock_memory", "memory is locked at start"),
    restart(
        "pipeline.realtime.input_cpus",
        "input threads are pinned when they start",
    ),
    restart("socket.path", "the socket is bound at start"),
    live(
        "socket.mode",
        "the socket file's mode is changed; it applies to new connections",
    ),
    live(
        "socket.group",
        "the socket file's group is changed; it applies to new connections",
    ),
    restart(
        "socket.client_queue",
        "every client's queue depth is announced in its hello",
    ),
    live(
        "socket.max_clients",
        "checked at each new connection; connected clients stay",
    ),
    restart(
        "socket.privileged.users",
        "user names are resolved to ids when the socket starts",
    ),
    restart(
        "socket.privileged.groups",
        "group names are resolved to ids when the socket starts",
    ),
    restart(
        "outputs",
        "each output binds its address and starts its thread at start",
    ),
];

/// The row of `path`, if the table has one.
pub fn field_class(path: &str) -> Option<&'static FieldClass> {
    FIELDS.iter().find(|f| f.path == path)
}

/// One field that differs between the running config and a new one.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldChange {
    /// Dotted path.
    pub path: String,
    /// What the reload does with it (a field without a row counts as a restart).
    pub class: ReloadClass,
    /// The running value, as JSON.
    pub old: Value,
    /// The new file's value, as JSON.
    pub new: Value,
}

impl FieldChange {
    /// `path old → new`, values as in the file (strings quoted, `None` for none),
    /// long values shortened.
    pub fn describe(&self) -> String {
        format!(
            "{} {} → {}",
            self.path,
            show_value(&self.old),
            show_value(&self.new)
        )
    }
}

/// Longest value rendering [`show_value`] writes whole (characters).
const MAX_SHOWN_CHARS: usize = 60;

/// A JSON value as a person reads it in a log line: `null` as `None`, anything
/// longer than `MAX_SHOWN_CHARS` cut with `…`.
pub fn show_value(v: &Value) -> String {
    let s = match v {
        Value::Null => "None".to_string(),
        other => other.to_string(),
    };
    match s.char_indices().nth(MAX_SHOWN_CHARS) {
        Some((at, _)) => format!("{}…", &s[..at]),
        None => s,
    }
}

/// What a reload changes.
#[derive(Clone, Debug)]
pub struct ReloadPlan {
    /// Fields that differ, in file order.
    pub changes: Vec<FieldChange>,
    /// The config in effect after the reload: the new one with every restart field
    /// at its running value.
    pub in_effect: Config,
}

impl ReloadPlan {
    /// The changes of one class.
    pub fn of(&self, class: ReloadClass) -> impl Iterator<Item = &FieldChange> {
        self.changes.iter().filter(move |c| c.class == class)
    }

    /// Whether the field at `path` is among the live changes.
    pub fn applies(&self, path: &str) -> bool {
        self.of(ReloadClass::Live).any(|c| c.path == path)
    }
}

/// Compares the running config with a newly loaded one (see the module doc).
pub fn plan_reload(running: &Config, new: Config) -> ReloadPlan {
    let (old_v, mut new_v) = (to_value(running), to_value(&new));
    let mut changes = Vec::new();
    walk("", &old_v, &new_v, &mut |path, old, new| {
        if old != new {
            changes.push(FieldChange {
                path: path.to_string(),
                class: field_class(path).map_or(ReloadClass::Restart, |f| f.class),
                old: old.clone(),
                new: new.clone(),
            });
        }
    });
    let restarts: Vec<&FieldChange> = changes
        .iter()
        .filter(|c| c.class == ReloadClass::Restart)
        .collect();
    let in_effect = if restarts.is_empty() {
        new
    } else {
        for c in &restarts {
            set_at(&mut new_v, &c.path, c.old.clone());
        }
        match serde_json::from_value::<Config>(new_v) {
            Ok(mut merged) => {
                merged.loaded_scene = new.loaded_scene.clone();
                merged.library = new.library.clone();
                merged.recogniser = new.recogniser.clone();
                merged
            }
            // Every value came from a config of this build, so it reads back; if it
            // ever did not, the running config stays whole.
            Err(e) => {
                log::error!("internal bug: the reloaded config does not read back: {e}");
                running.clone()
            }
        }
    };
    ReloadPlan { changes, in_effect }
}

/// The dotted paths of `cfg`'s serialised fields that [`FIELDS`] does not cover.
pub fn unclassified_fields(cfg: &Config) -> Vec<String> {
    let v = to_value(cfg);
    let mut out = Vec::new();
    walk("", &v, &v, &mut |path, _, _| {
        if field_class(path).is_none() {
            out.push(path.to_string());
        }
    });
    out
}

fn to_value(cfg: &Config) -> Value {
    // A config of plain numbers, strings, paths and options always serialises.
    serde_json::to_value(cfg).unwrap_or(Value::Null)
}

/// Calls `leaf(path, old, new)` for every value the table names or, where it names
/// none, for every value that is not an object on both sides (a section present on
/// one side only is compared whole).
fn walk(prefix: &str, old: &Value, new: &Value, leaf: &mut dyn FnMut(&str, &Value, &Value)) {
    let empty = Map::new();
    let (o, n) = (
        old.as_object().unwrap_or(&empty),
        new.as_object().unwrap_or(&empty),
    );
    let keys = o.keys().chain(n.keys().filter(|k| !o.contains_key(*k)));
    for k in keys {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let (ov, nv) = (
            o.get(k).unwrap_or(&Value::Null),
            n.get(k).unwrap_or(&Value::Null),
        );
        if field_class(&path).is_none() && ov.is_object() && nv.is_object() {
            walk(&path, ov, nv, leaf);
        } else {
            leaf(&path, ov, nv);
        }
    }
}

/// Sets the value at a dotted path of objects.
fn set_at(root: &mut Value, path: &str, value: Value) {
    let mut at = root;
    let mut parts = path.split('.').peekable();
    while let Some(part) = parts.next() {
        let Some(obj) = at.as_object_mut() else {
            return;
        };
        if parts.peek().is_none() {
            obj.insert(part.to_string(), value);
            return;
        }
        match obj.get_mut(part) {
            Some(next) => at = next,
            None => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::InputConfig;
    use std::path::PathBuf;

    fn default() -> Config {
        Config::embedded_default()
    }

    /// A config with every optional field set, so no field hides behind a `None`.
    fn everything_set() -> Config {
        let mut c = default();
        c.log_level = crate::config::LogLevel::Debug;
        c.surface.size_mm = Some((800.0, 450.0));
        c.scene = Some(PathBuf::from("/nonexistent/room.ron"));
        c.edit = Some(crate::config::EditConfig {
            tracks: PathBuf::from("/nonexistent/parade.jsonl"),
            threshold_m: 0.4,
            dir: Some(PathBuf::from("/nonexistent/tracks")),
            allow_overwrite: true,
            preview: false,
        });
        c.pipeline.realtime.priority = Some(30);
        c.pipeline.realtime.input_cpus = Some(vec![0]);
        c.socket.path = Some(PathBuf::from("/tmp/x.sock"));
        c.socket.group = Some("video".to_string());
        c.gestures.library = Some(PathBuf::from("/nonexistent/mine.ctgl"));
        c.gestures.band = Some(8);
        c.gestures.auto_components_max = Some(4);
        c.gestures.continuous = Some(crate::config::ContinuousConfig {
            window_ms: 1000,
            hold_ms: 300,
        });
        c.inputs.push(InputConfig::Device {
            select: Default::default(),
            interface: Default::default(),
            grab: true,
            region: None,
            calibration: Default::default(),
            palm_max_mm: None,
            size_mm: None,
        });
        c
    }

    #[test]
    fn every_config_field_has_a_reload_class() {
        for cfg in [default(), everything_set()] {
            let missing = unclassified_fields(&cfg);
            assert!(
                missing.is_empty(),
                "config fields without a row in config::live::FIELDS (applied live, or \
                 needing a restart?): {missing:?}"
            );
        }
    }

    #[test]
    fn every_row_names_a_field_that_exists() {
        let v = to_value(&everything_set());
        for f in FIELDS {
            let found = f
                .path
                .split('.')
                .try_fold(&v, |at, part| at.as_object().and_then(|o| o.get(part)));
            assert!(
                found.is_some(),
                "FIELDS names `{}`, which the config has not",
                f.path
            );
        }
        let mut paths: Vec<&str> = FIELDS.iter().map(|f| f.path).collect();
        paths.sort_unstable();
        paths.dedup();
        assert_eq!(paths.len(), FIELDS.len(), "a path is listed twice");
    }

    #[test]
    fn the_same_config_changes_nothing() {
        let plan = plan_reload(&default(), default());
        assert!(plan.changes.is_empty(), "{:?}", plan.changes);
        assert_eq!(plan.in_effect, default());
    }

    #[test]
    fn a_live_field_is_applied() {
        let mut new = default();
        new.crowd.agents = 40;
        new.socket.max_clients = 2;
        new.crowd.max_speed_m_s = 2.5;
        let plan = plan_reload(&default(), new.clone());
        let live: Vec<String> = plan.of(ReloadClass::Live).map(|c| c.describe()).collect();
        assert_eq!(
            live,
            vec![
                "crowd.agents 100 → 40",
                "crowd.max_speed_m_s 1.5 → 2.5",
                "socket.max_clients 32 → 2"
            ]
        );
        assert_eq!(plan.of(ReloadClass::Restart).count(), 0);
        assert!(plan.applies("crowd.agents"));
        assert_eq!(plan.in_effect, new);
    }

    #[test]
    fn a_restart_field_keeps_its_running_value_and_stays_listed() {
        let running = default();
        let mut new = default();
        new.socket.path = Some(PathBuf::from("/tmp/b.sock"));
        new.mesh.cols = 12;
        new.crowd.kp_per_s2 = 20.0;
        let plan = plan_reload(&running, new);
        let restart: Vec<String> = plan
            .of(ReloadClass::Restart)
            .map(|c| c.describe())
            .collect();
        assert_eq!(
            restart,
            vec!["mesh.cols 10 → 12", "socket.path None → \"/tmp/b.sock\""]
        );
        assert!(plan.applies("crowd.kp_per_s2"));
        // In effect: the live change, and the running values of the others.
        let e = &plan.in_effect;
        assert_eq!(
            (e.crowd.kp_per_s2, e.mesh.cols, e.socket.path.as_ref()),
            (20.0, 10, None)
        );
        // The next reload of the same file reports the restart fields again, and
        // only them.
        let mut same = running.clone();
        same.socket.path = Some(PathBuf::from("/tmp/b.sock"));
        same.mesh.cols = 12;
        same.crowd.kp_per_s2 = 20.0;
        let again = plan_reload(e, same);
        let paths: Vec<&str> = again.changes.iter().map(|c| c.path.as_str()).collect();
        assert_eq!(paths, vec!["mesh.cols", "socket.path"]);
        // The file back at the running values: nothing is pending.
        let mut back = running;
        back.crowd.kp_per_s2 = 20.0;
        assert!(plan_reload(e, back).changes.is_empty());
    }

    #[test]
    fn whole_values_are_compared_whole() {
        let mut new = default();
        new.crowd.formation.max[0] += 1.0;
        if let Some(InputConfig::Replay { looped, .. }) = new.inputs.first_mut() {
            *looped = !*looped;
        }
        let plan = plan_reload(&default(), new);
        let paths: Vec<&str> = plan.changes.iter().map(|c| c.path.as_str()).collect();
        assert_eq!(paths, vec!["inputs", "crowd.formation"]);
        assert!(plan.of(ReloadClass::Live).next().is_none());
        assert_eq!(plan.in_effect, default());
    }

    #[test]
    fn long_values_are_shortened() {
        let long = Value::String("x".repeat(200));
        let s = show_value(&long);
        assert_eq!(s.chars().count(), MAX_SHOWN_CHARS + 1);
        assert!(s.ends_with('…'));
        assert_eq!(show_value(&Value::Null), "None");
    }

    #[test]
    fn every_restart_field_is_in_the_configuration_reference() {
        let doc = include_str!("../../docs/configuration.md");
        let section = doc
            .split("## Reloading")
            .nth(1)
            .expect("docs/configuration.md has a \"Reloading\" section");
        for f in FIELDS.iter().filter(|f| f.class == ReloadClass::Restart) {
            assert!(
                section.contains(&format!("`{}`", f.path)),
                "docs/configuration.md (Reloading) does not list `{}`",
                f.path
            );
        }
    }
}
