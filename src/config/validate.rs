//! Range checks on a parsed config: every problem as a `(field path, message)` pair.

use super::inputs::{DeviceSelect, InputConfig};
use super::model::{Config, CONFIG_VERSION};
use crate::crowd::environment::MESH_FIELD_RANGE_M;
use crate::geom::Rect;
use crate::vocab::parse_vendor_product;

/// Most agents the daemon accepts with the default budgets: the largest crowd it
/// serves within them on the reference machine (control tick ≤ 1 ms and input →
/// bytes written ≤ 4 ms at p99, in every format and field set; `crowdtouch bench
/// e2e --agents N --format F --fields S`, `crowdtouch bench scale`, figures in
/// docs/benchmarks.md#large-crowds).
pub const MAX_AGENTS: u32 = 10_000;

/// Most agents the daemon accepts when the config's budgets allow a large crowd
/// ([`LARGE_CROWD_BUDGETS`]): at 20,000 agents the control tick takes about 1.6 ms
/// at p50 and 2.5 ms at p99 on the reference machine, input → bytes written 5.5 ms
/// at p99 (docs/benchmarks.md#large-crowds).
pub const MAX_AGENTS_LARGE: u32 = 20_000;

/// The least `(pipeline.budgets.control_us, pipeline.budgets.end_to_end_us)` a config
/// states to run more than [`MAX_AGENTS`] agents (up to [`MAX_AGENTS_LARGE`]).
pub const LARGE_CROWD_BUDGETS: (u64, u64) = (3_000, 8_000);

impl Config {
    /// The most agents this config allows: [`MAX_AGENTS_LARGE`] when its budgets are
    /// at least [`LARGE_CROWD_BUDGETS`], else [`MAX_AGENTS`].
    pub fn max_agents(&self) -> u32 {
        let b = &self.pipeline.budgets;
        if b.control_us >= LARGE_CROWD_BUDGETS.0 && b.end_to_end_us >= LARGE_CROWD_BUDGETS.1 {
            MAX_AGENTS_LARGE
        } else {
            MAX_AGENTS
        }
    }
}

impl Config {
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
        let max = self.max_agents();
        check(
            (1..=max).contains(&c.agents),
            "crowd.agents",
            if max < MAX_AGENTS_LARGE && (max..=MAX_AGENTS_LARGE).contains(&c.agents) {
                format!(
                    "agent count must be 1..={max} with these budgets, got {}; up to \
                     {MAX_AGENTS_LARGE} when pipeline.budgets.control_us ≥ {} and \
                     end_to_end_us ≥ {}",
                    c.agents, LARGE_CROWD_BUDGETS.0, LARGE_CROWD_BUDGETS.1
                )
            } else {
                format!("agent count must be 1..={max}, got {}", c.agents)
            },
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
        check(
            (0.0..=MESH_FIELD_RANGE_M).contains(&m.field_step_m),
            "mesh.field_step_m",
            format!(
                "field step must be in [0, {MESH_FIELD_RANGE_M}] m (the field's range: a \
                 larger step throws vertices past it), got {}",
                m.field_step_m
            ),
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
            k.gesture_span_mm > 0.0 && k.gesture_span_mm.is_finite(),
            "controls.gesture_span_mm",
            format!(
                "gesture span must be positive millimetres, got {}",
                k.gesture_span_mm
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
        for (kind, names) in [
            ("users", &s.privileged.users),
            ("groups", &s.privileged.groups),
        ] {
            for (i, n) in names.iter().enumerate() {
                check(
                    !n.is_empty() && n.len() <= 32 && n.chars().all(|c| c.is_ascii_graphic()),
                    &format!("socket.privileged.{kind}[{i}]"),
                    format!("a user or group is a name or a numeric id (1 ..= 32 printable characters), got {n:?}"),
                );
            }
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
                    for (field, msg) in surface_problems(region.as_ref(), calibration) {
                        check(false, &format!("inputs[{i}].{field}"), msg);
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
                InputConfig::Tuio {
                    listen,
                    region,
                    calibration,
                    timeout_ms,
                    max_sessions_per_frame,
                    max_senders,
                    max_packets_per_s,
                } => {
                    check(
                        listen.parse::<std::net::SocketAddr>().is_ok(),
                        &format!("inputs[{i}].listen"),
                        format!(
                            "listen address must be ip:port, like \"0.0.0.0:3333\", got {listen:?}"
                        ),
                    );
                    for (field, msg) in surface_problems(region.as_ref(), calibration) {
                        check(false, &format!("inputs[{i}].{field}"), msg);
                    }
                    check(
                        (100..=60_000).contains(timeout_ms),
                        &format!("inputs[{i}].timeout_ms"),
                        format!("timeout must be 100..=60000 ms, got {timeout_ms}"),
                    );
                    use super::inputs::{
                        TUIO_MOST_SENDERS, TUIO_MOST_SESSIONS_PER_FRAME, TUIO_PACKETS_PER_S,
                    };
                    check(
                        (1..=TUIO_MOST_SESSIONS_PER_FRAME).contains(max_sessions_per_frame),
                        &format!("inputs[{i}].max_sessions_per_frame"),
                        format!(
                            "sessions per frame must be 1..={TUIO_MOST_SESSIONS_PER_FRAME} \
                             (a touch frame's capacity), got {max_sessions_per_frame}"
                        ),
                    );
                    check(
                        (1..=TUIO_MOST_SENDERS).contains(max_senders),
                        &format!("inputs[{i}].max_senders"),
                        format!("senders must be 1..={TUIO_MOST_SENDERS}, got {max_senders}"),
                    );
                    check(
                        TUIO_PACKETS_PER_S.contains(max_packets_per_s),
                        &format!("inputs[{i}].max_packets_per_s"),
                        format!(
                            "datagrams a second per peer must be {}..={}, got {max_packets_per_s}",
                            TUIO_PACKETS_PER_S.start(),
                            TUIO_PACKETS_PER_S.end()
                        ),
                    );
                }
            }
        }
        if let Some(cpus) = &pl.realtime.input_cpus {
            // Whether each CPU is online is a property of the machine, not of the
            // config: `check-config` and `run` warn about it (pipeline preflight).
            check(
                !cpus.is_empty(),
                "pipeline.realtime.input_cpus",
                "the CPU list is empty (None leaves the input thread unpinned)".to_string(),
            );
            for (k, &c) in cpus.iter().enumerate() {
                check(
                    c < MAX_CPUS,
                    &format!("pipeline.realtime.input_cpus[{k}]"),
                    format!("CPU {c} is not a CPU number: Linux numbers CPUs 0..{MAX_CPUS}"),
                );
            }
        }
        let l = self.formations.lambda;
        check(
            (0.0..=1.0).contains(&l),
            "formations.lambda",
            format!("least-effort weight must be in 0 ..= 1, got {l}"),
        );
        let f = &self.formations;
        super::transform::validate_transform(&f.transform, &f.subgroups, &f.gestures, &mut p);
        let max_speed = self.crowd.max_speed_m_s;
        let max_speed = (max_speed > 0.0 && max_speed <= 50.0).then_some(max_speed);
        self.gestures.validate_into(max_speed, &mut p);
        super::outputs::validate_outputs(&self.outputs, &mut p);

        p
    }
}

/// The problems of a device's or a TUIO input's `region` and `calibration`, as
/// `(field under the input, message)`.
fn surface_problems(
    region: Option<&Rect>,
    calibration: &super::inputs::CalibrationConfig,
) -> Vec<(&'static str, String)> {
    let mut p = Vec::new();
    if let Some(r) = region {
        let inside = r.min[0] >= 0.0 && r.min[1] >= 0.0 && r.max[0] <= 1.0 && r.max[1] <= 1.0;
        if !(finite_rect(r) && inside && r.width() > 0.0 && r.height() > 0.0) {
            p.push((
                "region",
                format!(
                    "region must be a rectangle inside the unit square (table units), got {:?} .. {:?}",
                    r.min, r.max
                ),
            ));
        }
    }
    if !matches!(calibration.rotation, 0 | 90 | 180 | 270) {
        p.push((
            "calibration.rotation",
            format!(
                "rotation must be 0, 90, 180 or 270 degrees, got {}",
                calibration.rotation
            ),
        ));
    }
    if calibration
        .matrix
        .is_some_and(|m| !m.iter().all(|v| v.is_finite()))
    {
        p.push((
            "calibration.matrix",
            "calibration matrix values must be finite".to_string(),
        ));
    }
    p
}

/// CPU numbers a CPU affinity set holds (`CPU_SETSIZE`).
const MAX_CPUS: usize = 1024;

fn finite_rect(r: &Rect) -> bool {
    r.min.iter().chain(r.max.iter()).all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::error::{ConfigIssue, Error};
    use crate::config::load::DEFAULT_CONFIG_RON;
    use crate::config::model::RealtimeConfig;
    use std::path::Path;

    fn issues(text: &str) -> Vec<ConfigIssue> {
        match Config::from_str(text, Path::new("t.ron")) {
            Err(Error::Invalid { issues, .. }) => issues,
            other => panic!("expected invalid, got {other:?}"),
        }
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
    fn a_crowd_above_ten_thousand_needs_the_large_crowd_budgets() {
        let at = |agents: u32, control: u64, e2e: u64| {
            DEFAULT_CONFIG_RON
                .replacen("agents: 100", &format!("agents: {agents}"), 1)
                .replacen("control_us: 1000", &format!("control_us: {control}"), 1)
                .replacen("end_to_end_us: 4000", &format!("end_to_end_us: {e2e}"), 1)
        };
        let ok = |text: &str| Config::from_str(text, Path::new("t.ron")).is_ok();
        assert!(
            ok(&at(MAX_AGENTS, 1000, 4000)),
            "10,000 with the default budgets"
        );
        let is = issues(&at(MAX_AGENTS + 1, 1000, 4000));
        assert_eq!(is[0].field, "crowd.agents");
        assert!(
            is[0]
                .message
                .contains("up to 20000 when pipeline.budgets.control_us ≥ 3000"),
            "{}",
            is[0].message
        );
        // Only one of the two budgets raised is not enough.
        assert!(!ok(&at(MAX_AGENTS_LARGE, 3000, 4000)));
        assert!(!ok(&at(MAX_AGENTS_LARGE, 1000, 8000)));
        assert!(ok(&at(MAX_AGENTS_LARGE, 3000, 8000)));
        let is = issues(&at(MAX_AGENTS_LARGE + 1, 3000, 8000));
        assert!(
            is[0].message.contains("1..=20000, got 20001"),
            "{}",
            is[0].message
        );
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
    fn field_step_is_range_checked_and_defaults_when_absent() {
        let line = "        field_step_m: 0.3,\n";
        assert!(DEFAULT_CONFIG_RON.contains(line));
        let c = Config::from_str(DEFAULT_CONFIG_RON, Path::new("t.ron")).unwrap();
        assert_eq!(c.mesh.field_step_m, crate::config::DEFAULT_FIELD_STEP_M);
        for bad in ["-0.1", "1.5", "NaN", "inf"] {
            let text =
                DEFAULT_CONFIG_RON.replacen(line, &format!("        field_step_m: {bad},\n"), 1);
            let is = issues(&text);
            assert_eq!(is.len(), 1, "{bad}: {is:?}");
            assert_eq!(is[0].field, "mesh.field_step_m");
            let expect_line = text
                .lines()
                .position(|l| l.contains("field_step_m:"))
                .unwrap()
                + 1;
            assert_eq!(is[0].line, expect_line);
            assert!(is[0].message.contains("[0, 1] m"), "{}", is[0].message);
        }
        let zero = DEFAULT_CONFIG_RON.replacen(line, "        field_step_m: 0.0,\n", 1);
        assert_eq!(
            Config::from_str(&zero, Path::new("t.ron"))
                .unwrap()
                .mesh
                .field_step_m,
            0.0
        );
        // Left out (a config written before the field existed): the default.
        let without = DEFAULT_CONFIG_RON.replacen(line, "", 1);
        let c = Config::from_str(&without, Path::new("t.ron")).unwrap();
        assert_eq!(c.mesh.field_step_m, 0.3);
    }

    /// The `gestures` section of `DEFAULT_CONFIG_RON`, from its header to its end.
    fn gestures_section() -> (usize, usize) {
        let a = DEFAULT_CONFIG_RON.find("    gestures: (\n").unwrap();
        let b = a + DEFAULT_CONFIG_RON[a..].find("\n    ),\n").unwrap() + "\n    ),\n".len();
        (a, b)
    }

    #[test]
    fn the_shipped_configs_carry_the_gestures_section_at_its_defaults() {
        let kiosk = include_str!("../../config/kiosk.ron");
        for text in [DEFAULT_CONFIG_RON, kiosk] {
            assert!(text.contains("\n    gestures: (\n"));
            let c = Config::from_str(text, Path::new("t.ron")).unwrap();
            assert_eq!(c.gestures, crate::config::GesturesConfig::default());
        }
        let (a, b) = gestures_section();
        let s = &DEFAULT_CONFIG_RON[a..b];
        for w in [
            "alpha: 0.04",
            "beta: 0.36",
            "gamma: 0.36",
            "delta: 0.24",
            "k: 10",
        ] {
            assert!(s.contains(w), "{w}");
        }
    }

    #[test]
    fn a_config_without_the_gestures_section_loads_with_the_defaults() {
        let (a, b) = gestures_section();
        let without = format!("{}{}", &DEFAULT_CONFIG_RON[..a], &DEFAULT_CONFIG_RON[b..]);
        let c = Config::from_str(&without, Path::new("t.ron")).unwrap();
        assert_eq!(c.gestures, crate::config::GesturesConfig::default());
        // A section with only some fields takes the defaults for the rest.
        let partial = format!(
            "{}    gestures: (k: 3, continuous: Some((window_ms: 800, hold_ms: 200))),\n{}",
            &DEFAULT_CONFIG_RON[..a],
            &DEFAULT_CONFIG_RON[b..]
        );
        let c = Config::from_str(&partial, Path::new("t.ron")).unwrap();
        assert_eq!(c.gestures.k, 3);
        assert_eq!(c.gestures.continuous.map(|c| c.hold_ms), Some(200));
        assert_eq!(c.gestures.gmm_components, 2);
    }

    #[test]
    fn gesture_values_out_of_range_name_their_field_and_line() {
        let cases = [
            ("k: 10,", "k: 0,", "gestures.k"),
            (
                "min_travel_mm: 10.0,",
                "min_travel_mm: -1.0,",
                "gestures.min_travel_mm",
            ),
            (
                "max_duration_s: 60.0,",
                "max_duration_s: 0.1,",
                "gestures.max_duration_s",
            ),
            (
                "max_duration_s: 60.0,",
                "max_duration_s: inf,",
                "gestures.max_duration_s",
            ),
            ("alpha: 0.04,", "alpha: -0.04,", "gestures.weights.alpha"),
            ("delta: 0.24)", "delta: NaN)", "gestures.weights.delta"),
            ("band: None,", "band: Some(65),", "gestures.band"),
            (
                "gmm_components: 2,",
                "gmm_components: 0,",
                "gestures.gmm_components",
            ),
            (
                "auto_components_max: None,",
                "auto_components_max: Some(1),",
                "gestures.auto_components_max",
            ),
            (
                "approach_timeout_s: 3.0,",
                "approach_timeout_s: 0.0,",
                "gestures.approach_timeout_s",
            ),
            (
                "motion_speed_m_s: 1.0,",
                "motion_speed_m_s: 2.0,",
                "gestures.motion_speed_m_s",
            ),
            (
                "collected: Weigh(2.0),",
                "collected: Weigh(0.5),",
                "gestures.collected",
            ),
            ("library: None,", "library: Some(\"\"),", "gestures.library"),
            (
                "continuous: None,",
                "continuous: Some((window_ms: 50, hold_ms: 300)),",
                "gestures.continuous.window_ms",
            ),
        ];
        for (from, to, field) in cases {
            let (a, b) = gestures_section();
            let section = DEFAULT_CONFIG_RON[a..b].replacen(from, to, 1);
            assert_ne!(section, DEFAULT_CONFIG_RON[a..b], "{from}");
            let text = format!(
                "{}{}{}",
                &DEFAULT_CONFIG_RON[..a],
                section,
                &DEFAULT_CONFIG_RON[b..]
            );
            let is = issues(&text);
            assert_eq!(is.len(), 1, "{to}: {is:?}");
            assert_eq!(is[0].field, field, "{to}");
            let key = field.rsplit('.').next().unwrap();
            let line = text
                .lines()
                .enumerate()
                .skip(text[..a].lines().count())
                .find(|(_, l)| !l.trim_start().starts_with("//") && l.contains(&format!("{key}:")))
                .map(|(n, _)| n + 1)
                .unwrap();
            assert_eq!(is[0].line, line, "{to}: {:?}", is[0]);
        }
        // Every weight zero: the sum is reported at the weights.
        let text = DEFAULT_CONFIG_RON.replacen(
            "weights: (alpha: 0.04, beta: 0.36, gamma: 0.36, delta: 0.24)",
            "weights: (alpha: 0.0, beta: 0.0, gamma: 0.0, delta: 0.0)",
            1,
        );
        let is = issues(&text);
        assert_eq!(is.len(), 1, "{is:?}");
        assert_eq!(is[0].field, "gestures.weights");
        assert!(is[0].message.contains("sum to zero"), "{}", is[0].message);
        // An unknown key in the section is refused, with its place.
        let text = DEFAULT_CONFIG_RON.replacen("k: 10,", "kk: 10,", 1);
        let e = Config::from_str(&text, Path::new("t.ron"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("kk"), "{e}");
    }
}
