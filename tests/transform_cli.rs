//! `crowdtouch transform` and `transform compare` (formation-transform, issue 16
//! items 7–8): the report of a run, formations from files, the pairing costs, the
//! comparison and its plot, and every bad input as a clear error.

use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_crowdtouch"))
}

fn run(args: &[&str]) -> Output {
    bin().arg("transform").args(args).output().unwrap()
}

fn json_of(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "status {:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// Fails with the output unless the command failed cleanly (status 1, one
/// `crowdtouch: error:` line, no panic) with every one of `want` in its message.
fn assert_error(out: &Output, want: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("crowdtouch: error:"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in want {
        assert!(err.contains(w), "missing `{w}` in: {err}");
    }
}

/// Default radius of the embedded config (m).
const RADIUS_M: f64 = 0.15;

#[test]
fn square_to_arrow_reports_every_key_and_a_clean_arrival() {
    let args = [
        "--from", "square", "--to", "arrow", "--agents", "60", "--json",
    ];
    let v = json_of(&run(&args));
    for key in [
        "from",
        "to",
        "cost",
        "agents",
        "radius_m",
        "steps",
        "simulated_s",
        "timed_out",
        "arrived_fraction",
        "min_distance_m",
        "overlapping_pairs",
        "mean_travel_m",
        "max_travel_m",
        "I_d",
        "sigma_min_dis",
        "sigma_curr_eft",
        "step_us_p50",
        "step_us_p99",
        "prepare_ms",
    ] {
        assert!(v.get(key).is_some(), "no `{key}` in {v}");
    }
    let f = |k: &str| v[k].as_f64().unwrap();
    assert_eq!(v["agents"], 60);
    assert_eq!(v["from"], "square");
    assert_eq!(v["cost"], "least-effort");
    assert_eq!(f("radius_m"), RADIUS_M);
    assert_eq!(f("arrived_fraction"), 1.0, "{v}");
    assert_eq!(v["timed_out"], false);
    assert_eq!(v["overlapping_pairs"], 0, "{v}");
    assert!(f("min_distance_m") >= 2.0 * RADIUS_M - 0.005, "{v}");
    assert!(f("I_d") > 0.0 && f("I_d") < 3.0, "{v}");
    assert!(f("sigma_min_dis") > 0.0 && f("sigma_curr_eft") > 0.0, "{v}");
    assert!(
        f("mean_travel_m") > 0.1 && f("max_travel_m") >= f("mean_travel_m"),
        "{v}"
    );
    assert!(f("max_travel_m") < 20.0, "{v}");
    assert!(
        f("simulated_s") > 0.5 && v["steps"].as_u64().unwrap() > 30,
        "{v}"
    );
    assert!(v["step_us_p99"].as_u64().unwrap() >= v["step_us_p50"].as_u64().unwrap());
    // Same seed, same run: everything but the timings.
    let mut w = json_of(&run(&args));
    let mut v = v;
    for m in [&mut v, &mut w] {
        let o = m.as_object_mut().unwrap();
        for k in ["step_us_p50", "step_us_p99", "prepare_ms"] {
            o.remove(k);
        }
    }
    assert_eq!(v, w);
}

#[test]
fn text_report_names_the_measures() {
    let out = run(&["--from", "ring", "--to", "square", "--agents", "30"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t = String::from_utf8_lossy(&out.stdout);
    for w in [
        "ring → square: 30 agents",
        "arrived",
        "pairs overlapped",
        "I_d (eq. 17)",
        "σ_min_dis (eq. 24)",
        "σ_curr_eft (eq. 26)",
        "p50",
    ] {
        assert!(t.contains(w), "missing `{w}`:\n{t}");
    }
}

/// A disc of dark pixels on white, as a plain PGM.
fn disc_pgm(side: usize) -> String {
    let mut s = format!("P2\n{side} {side}\n255\n");
    let c = side as f64 / 2.0;
    for y in 0..side {
        for x in 0..side {
            let d = ((x as f64 + 0.5 - c).powi(2) + (y as f64 + 0.5 - c).powi(2)).sqrt();
            s.push_str(if d < 0.4 * side as f64 { "0 " } else { "255 " });
        }
        s.push('\n');
    }
    s
}

#[test]
fn formations_from_a_bitmap_and_a_polygon_file() {
    let dir = tempfile::tempdir().unwrap();
    let pgm = dir.path().join("disc.pgm");
    std::fs::write(&pgm, disc_pgm(32)).unwrap();
    let ron = dir.path().join("tri.ron");
    std::fs::write(
        &ron,
        "(name: \"tri\", outline: [(0.0, 0.0), (4.0, 0.0), (2.0, 3.0)])\n",
    )
    .unwrap();
    let (p, r) = (pgm.to_str().unwrap(), ron.to_str().unwrap());
    for (a, b) in [(p, r), (r, p)] {
        let v = json_of(&run(&["--from", a, "--to", b, "--agents", "40", "--json"]));
        assert_eq!(v["agents"], 40);
        assert_eq!(v["from"], a);
        assert_eq!(v["arrived_fraction"].as_f64(), Some(1.0), "{v}");
        assert_eq!(v["overlapping_pairs"], 0, "{v}");
    }
}

#[test]
fn euclidean_pairing_spreads_the_effort_more_than_least_effort() {
    // Section 5.2, Table 2: least effort gives the most balanced efforts
    // (σ_curr_eft) of the three costs.
    let go = |cost: &str| {
        json_of(&run(&[
            "--from", "square", "--to", "arrow", "--agents", "60", "--cost", cost, "--json",
        ]))
    };
    let (le, eu) = (go("least-effort"), go("euclidean"));
    assert_eq!(eu["cost"], "euclidean");
    let s = |v: &Value| v["sigma_curr_eft"].as_f64().unwrap();
    assert!(s(&eu) > s(&le), "least effort {le}\neuclidean {eu}");
}

/// Whether `svg` is one `<svg>` element with properly nested tags.
fn well_formed(svg: &str) -> Result<(), String> {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = svg.trim();
    if !rest.starts_with("<svg") {
        return Err("does not start with <svg".into());
    }
    let mut roots = 0;
    while let Some(i) = rest.find('<') {
        let end = rest[i..].find('>').ok_or("unclosed tag")? + i;
        let tag = &rest[i + 1..end];
        if let Some(name) = tag.strip_prefix('/') {
            match stack.pop() {
                Some(open) if open == name.trim() => {}
                other => return Err(format!("</{name}> closes {other:?}")),
            }
        } else if !tag.ends_with('/') {
            let name = tag.split_whitespace().next().unwrap_or("").to_string();
            if stack.is_empty() {
                roots += 1;
            }
            stack.push(name);
        } else if stack.is_empty() {
            return Err("an element outside <svg>".into());
        }
        rest = &rest[end + 1..];
    }
    if !stack.is_empty() || roots != 1 || !rest.trim().is_empty() {
        return Err(format!("open at the end: {stack:?}, roots {roots}"));
    }
    Ok(())
}

#[test]
fn compare_prints_six_variants_and_plots_them() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("cmp.svg");
    let out = bin()
        .args(["transform", "compare", "--from", "square", "--to", "arrow"])
        .args(["--agents", "40", "--svg"])
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let t = String::from_utf8_lossy(&out.stdout);
    for name in [
        "least-effort",
        "travel-only",
        "euclidean",
        "manhattan",
        "no-feedback",
        "orca",
        "I_d",
        "σ_min_dis",
        "σ_curr_eft",
        "swaps",
        "overlaps",
        "95 % confidence interval",
    ] {
        assert!(t.contains(name), "missing `{name}`:\n{t}");
    }
    let text = std::fs::read_to_string(&svg).unwrap();
    well_formed(&text).unwrap();
    for w in [
        "time (s)",
        "I_d (bits)",
        "σ_min_dis (m)",
        "σ_curr_eft (m)",
        "no-feedback",
        "ORCA",
    ] {
        assert!(text.contains(w), "the plot misses `{w}`");
    }
    // The run picture too.
    let pic = dir.path().join("run.svg");
    let out = run(&[
        "--from",
        "square",
        "--to",
        "ring",
        "--agents",
        "30",
        "--svg",
        pic.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&pic).unwrap();
    well_formed(&text).unwrap();
    assert!(text.matches("<polyline").count() >= 30);
}

/// The JSON of `transform compare`: one row per variant, over the seeds, each
/// with its switches as booleans, the exchanges of targets, and every measure as
/// a mean with its 95 % interval; the subgroups' count, convergence and
/// locality. The ORCA row is ORCA as RVO2 runs it (no feedback, no exchanges of
/// targets, no positional contacts, no settling), and the paper preset turns the
/// project's additions off in every row.
#[test]
fn compare_json_has_a_row_per_variant_with_intervals_and_switches() {
    for preset in [None, Some("paper")] {
        let mut cmd = bin();
        cmd.args(["transform", "compare", "--from", "line", "--to", "square"])
            .args(["--agents", "20", "--seeds", "3", "--json"])
            .args(["--variants", "all", "--timeout", "10"]);
        if let Some(p) = preset {
            cmd.args(["--preset", p]);
        }
        let v = json_of(&cmd.output().unwrap());
        assert_eq!(v["seeds"], 3);
        let rows = v["rows"].as_array().unwrap();
        let names: Vec<&str> = rows
            .iter()
            .map(|r| r["variant"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            [
                "least-effort",
                "travel-only",
                "euclidean",
                "manhattan",
                "no-feedback",
                "orca",
                "rvo",
                "steering"
            ]
        );
        for r in rows {
            assert_eq!(r["seeds"], 3, "{r}");
            for k in ["feedback", "exchanges", "contacts", "settling", "fades"] {
                assert!(r[k].is_boolean(), "`{k}` of {r}");
            }
            assert!(
                r["swaps"]["mean"].as_f64().is_some(),
                "no swap count in {r}"
            );
            for k in ["i_d", "sigma_min_dis", "sigma_curr_eft", "arrived_fraction"] {
                assert!(r[k]["mean"].as_f64().is_some(), "`{k}` of {r}");
                assert!(r[k]["ci95"].as_f64().unwrap() >= 0.0, "`{k}` of {r}");
            }
            assert!(r["arrival_s"].get("mean").is_some() && r["arrival_s"].get("ci95").is_some());
            let paper = preset.is_some() || r["mover"] != "social-force";
            for k in ["exchanges", "contacts", "settling", "fades"] {
                assert_eq!(r[k], !paper, "`{k}` of {r}");
            }
            if paper {
                assert_eq!(r["swaps"]["mean"], 0.0, "{r}");
            }
        }
        // The Table 3 baselines: on the least-effort pairing, without feedback,
        // exchanges or any other addition of the project.
        for (row, mover) in [(5, "orca"), (6, "rvo"), (7, "steering")] {
            let b = &rows[row];
            assert_eq!(b["mover"], mover, "{b}");
            assert_eq!(b["cost"], rows[0]["cost"], "{b}");
            assert_eq!(b["feedback"], false, "{b}");
            assert_eq!(b["exchanges"], false, "{b}");
            assert_eq!(b["subgroup_forces"], false, "{b}");
            assert_eq!(b["swaps"]["mean"], 0.0, "{b}");
        }
        assert_eq!(rows[4]["feedback"], false);
        assert_eq!(rows[0]["feedback"], true);
        assert_eq!(rows[1]["lambda"], 1.0);
        let sub = &v["subgroups"];
        assert!(sub["count"]["mean"].as_f64().unwrap() >= 1.0, "{sub}");
        assert!(sub["converged"].is_boolean(), "{sub}");
        let loc = sub["locality"]["mean"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&loc), "{sub}");
        // The common window is no longer than the shortest run.
        assert!(v["window_s"].as_f64().unwrap() > 0.0);
    }
    assert_error(
        &bin()
            .args(["transform", "compare", "--from", "line", "--to", "square"])
            .args(["--seeds", "0"])
            .output()
            .unwrap(),
        &["--seeds must be 1 to 100, got 0"],
    );
}

#[test]
fn bad_input_is_a_clear_error() {
    // An unknown name lists the known ones.
    assert_error(
        &run(&["--from", "squircle", "--to", "arrow"]),
        &["unknown formation `squircle`", "square", "arrow", "heart"],
    );
    // Agent counts out of range.
    assert_error(
        &run(&["--from", "square", "--to", "arrow", "--agents", "0"]),
        &["--agents must be 1 to 10000, got 0"],
    );
    assert_error(
        &run(&["--from", "square", "--to", "arrow", "--agents", "10001"]),
        &["--agents must be 1 to 10000, got 10001"],
    );
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A missing file, a RON file with a syntax error and one with a bad shape,
    // an image that selects nothing: each named, RON ones with line and column.
    let missing = d.join("none.ron");
    assert_error(
        &run(&["--from", missing.to_str().unwrap(), "--to", "arrow"]),
        &["none.ron", "cannot read"],
    );
    let syntax = d.join("syntax.ron");
    std::fs::write(&syntax, "(name: \"s\", outline: [(0.0, 0.0), (1.0 0.0)])\n").unwrap();
    assert_error(
        &run(&["--from", "square", "--to", syntax.to_str().unwrap()]),
        &["--to", "syntax.ron:1:"],
    );
    let bow = d.join("bow.ron");
    std::fs::write(
        &bow,
        "(\n  name: \"bow\",\n  outline: [(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)],\n)\n",
    )
    .unwrap();
    assert_error(
        &run(&["--from", bow.to_str().unwrap(), "--to", "arrow"]),
        &["bow.ron:3:", "outline", "cross"],
    );
    let white = d.join("white.pgm");
    std::fs::write(&white, "P2\n2 2\n255\n255 255 255 255\n").unwrap();
    assert_error(
        &run(&["--from", "square", "--to", white.to_str().unwrap()]),
        &["white.pgm", "no pixel has a colour"],
    );
    let junk = d.join("junk.png");
    std::fs::write(&junk, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    assert_error(
        &run(&["--from", junk.to_str().unwrap(), "--to", "arrow"]),
        &["junk.png"],
    );
    // More agents than a formation of fixed size holds: the sampling's message.
    let cfg_text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/crowdtouch.ron"),
    )
    .unwrap();
    assert!(cfg_text.contains("shapes: [],"));
    std::fs::write(d.join("disc.pgm"), disc_pgm(16)).unwrap();
    let cfg = d.join("small.ron");
    std::fs::write(
        &cfg,
        cfg_text.replace(
            "shapes: [],",
            "shapes: [(name: \"coin\", bitmap: Some((path: \"disc.pgm\", c_min: (0, 0, 0), c_max: (10, 10, 10), size_m: Some((1.0, 1.0)))))],",
        ),
    )
    .unwrap();
    let c = cfg.to_str().unwrap();
    assert_error(
        &run(&[
            "--from", "square", "--to", "coin", "--agents", "60", "--config", c,
        ]),
        &["60 agents do not fit in formation `coin`"],
    );
    assert_error(
        &bin()
            .args(["transform", "compare", "--from", "coin", "--to", "square"])
            .args(["--agents", "60", "--config", c])
            .output()
            .unwrap(),
        &["--from coin", "do not fit"],
    );
}

/// `transform compare` in `scenario` of `from` → `to`, `agents`, one seed, as JSON;
/// checked for what every scenario reports: its name and layout, and in every row
/// the measures (with the heading-change rate) as intervals.
fn scenario_json(scenario: &str, from: &str, to: &str, agents: &str) -> Value {
    let v = json_of(
        &bin()
            .args(["transform", "compare", "--from", from, "--to", to])
            .args(["--agents", agents, "--seeds", "1", "--json"])
            .args(["--scenario", scenario])
            .output()
            .unwrap(),
    );
    assert_eq!(v["scenario"], scenario);
    assert_eq!(v["scenario_layout"]["name"], scenario);
    for key in [
        "from",
        "to",
        "agents",
        "seeds",
        "window_s",
        "rows",
        "subgroups",
    ] {
        assert!(v.get(key).is_some(), "no `{key}` in {v}");
    }
    let rows = v["rows"].as_array().unwrap();
    assert!(rows.len() >= 6, "{v}");
    for r in rows {
        for k in [
            "i_d",
            "sigma_min_dis",
            "sigma_curr_eft",
            "heading_change_rad_s",
            "arrived_fraction",
            "swaps",
        ] {
            let m = r[k]["mean"].as_f64().unwrap_or(f64::NAN);
            assert!(m.is_finite() && m >= 0.0, "`{k}` of {r}");
            assert!(r[k]["ci95"].as_f64().is_some(), "`{k}` of {r}");
        }
        let turn = r["progress"]["heading_change_rad_s"]["mean"].as_f64();
        assert!(turn.is_some_and(f64::is_finite), "{r}");
        assert!(r["arrival_s"].get("mean").is_some(), "{r}");
    }
    v
}

/// The row of `variant`.
fn row<'a>(v: &'a Value, variant: &str) -> &'a Value {
    v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["variant"] == variant)
        .unwrap_or_else(|| panic!("no row `{variant}` in {v}"))
}

#[test]
fn the_direct_scenario_is_the_default_and_path_completes_on_the_way() {
    let direct = scenario_json("direct", "square", "arrow", "40");
    assert!(direct["rows"][0]["scenario"].is_null());
    let plain = json_of(
        &bin()
            .args(["transform", "compare", "--from", "square", "--to", "arrow"])
            .args(["--agents", "40", "--seeds", "1", "--json"])
            .output()
            .unwrap(),
    );
    assert_eq!(plain["scenario"], "direct");
    assert_eq!(plain["rows"][0]["i_d"], direct["rows"][0]["i_d"]);
    assert_eq!(
        plain["rows"][0]["arrival_s"],
        direct["rows"][0]["arrival_s"]
    );

    let path = scenario_json("path", "square", "arrow", "40");
    let layout = &path["scenario_layout"];
    let pts = layout["path_m"].as_array().unwrap();
    assert_eq!(pts.len(), 3, "{layout}");
    let speed = layout["anchor_speed_m_s"].as_f64().unwrap();
    assert!(speed > 0.5, "{layout}");
    // The targets ride on the anchor: no row arrives before it stops (20 m of
    // path), and the project's model arrives then.
    let anchor_s = 20.0 / speed;
    for r in path["rows"].as_array().unwrap() {
        if let Some(t) = r["arrival_s"]["mean"].as_f64() {
            assert!(t >= anchor_s - 1e-6, "{r}");
        }
    }
    let least = row(&path, "least-effort");
    assert_eq!(least["arrived_runs"], 1, "{least}");
    assert!(least["arrival_s"]["mean"].as_f64().unwrap() < anchor_s + 10.0);
}

#[test]
fn in_the_obstacles_scenario_no_agent_enters_the_obstacle() {
    let v = scenario_json("obstacles", "square", "arrow", "40");
    let discs = v["scenario_layout"]["obstacles"].as_array().unwrap();
    assert_eq!(discs.len(), 1, "{v}");
    let d = v["scenario_layout"]["target_offset_m"][0].as_f64().unwrap();
    let x = discs[0]["centre_m"][0].as_f64().unwrap();
    // The disc lies half way along the way to the target, which is 20 m or more
    // ahead.
    assert!(d >= 20.0 && x > 8.0 && x < 8.0 + d, "{v}");
    for r in v["rows"].as_array().unwrap() {
        let s = &r["scenario"];
        assert_eq!(s["agents_entered_obstacle"]["mean"], 0.0, "{r}");
        assert_eq!(s["agents_inside_obstacle_at_end"]["mean"], 0.0, "{r}");
    }
    assert_eq!(row(&v, "least-effort")["arrived_runs"], 1);
}

#[test]
fn in_the_crossing_scenario_both_groups_arrive() {
    let v = scenario_json("crossing", "square", "arrow", "20");
    assert!(v["scenario_layout"]["mirror_x_m"].as_f64().is_some(), "{v}");
    // The project's model (least effort, with its additions) gets both groups
    // to the other side.
    let least = row(&v, "least-effort");
    let s = &least["scenario"];
    assert_eq!(s["both_arrived"], true, "{least}");
    let groups = s["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 2);
    for (g, name) in groups.iter().zip(["a", "b"]) {
        assert_eq!(g["group"], name);
        assert_eq!(g["arrived_fraction"]["mean"], 1.0, "{g}");
        let changed = g["changed_group"]["mean"].as_f64().unwrap();
        assert!((0.0..=20.0).contains(&changed), "{g}");
    }
    // ORCA exchanges no targets: no agent changes group.
    for g in row(&v, "orca")["scenario"]["groups"].as_array().unwrap() {
        assert_eq!(g["changed_group"]["mean"], 0.0, "{g}");
    }
}

#[test]
fn a_bad_scenario_is_a_clear_error() {
    let out = bin()
        .args(["transform", "compare", "--from", "square", "--to", "arrow"])
        .args(["--scenario", "sideways"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("invalid value 'sideways' for '--scenario"),
        "{err}"
    );
    assert!(err.contains("direct, path, obstacles, crossing"), "{err}");
}

/// `compare --lambdas`: a raw and a normalised least-effort row per λ, with the
/// pairing's terms; λ changes the pairing (λ = 0 pairs most agents elsewhere
/// than λ = 1 and travels further) and the measures; at λ = 0 and 1 the raw
/// and normalised costs are the same.
#[test]
fn a_lambda_sweep_changes_the_pairing_and_the_measures() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("sweep.svg");
    let out = bin()
        .args(["transform", "compare", "--from", "square", "--to", "arrow"])
        .args(["--agents", "60", "--lambdas", "0,0.5,1", "--json", "--svg"])
        .arg(&svg)
        .output()
        .unwrap();
    let v = json_of(&out);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "{v}");
    let find = |cost: &str, lambda: f64| {
        rows.iter()
            .find(|r| r["cost"] == cost && r["lambda"].as_f64() == Some(lambda))
            .unwrap_or_else(|| panic!("no {cost} λ {lambda} row: {v}"))
    };
    let mean = |r: &Value, k: &str| r[k]["mean"].as_f64().unwrap();
    let pairing = |r: &Value, k: &str| r["pairing"][k]["mean"].as_f64().unwrap();
    for cost in ["least-effort", "least-effort-normalised"] {
        let (zero, one) = (find(cost, 0.0), find(cost, 1.0));
        assert_eq!(pairing(one, "changed_vs_travel_only"), 0.0, "{one}");
        assert!(pairing(zero, "changed_vs_travel_only") > 0.5, "{zero}");
        assert!(
            pairing(zero, "travel_m2") > 2.0 * pairing(one, "travel_m2"),
            "{zero} {one}"
        );
        assert!(
            pairing(zero, "local_m2") < pairing(one, "local_m2"),
            "{zero} {one}"
        );
        // The measures move with it: local structure alone scatters the
        // efforts less (σ_curr_eft) but the crowd takes longer.
        assert!(
            mean(zero, "sigma_curr_eft") != mean(one, "sigma_curr_eft"),
            "{zero} {one}"
        );
        assert!(
            mean(zero, "finish_s") > mean(one, "finish_s"),
            "{zero} {one}"
        );
    }
    // At the ends the two costs are the same cost.
    for l in [0.0, 1.0] {
        assert_eq!(
            find("least-effort", l)["pairing"],
            find("least-effort-normalised", l)["pairing"]
        );
    }
    // The normalised λ = 0.5 trades travel for local structure; the raw one
    // barely does.
    let (raw, norm, one) = (
        find("least-effort", 0.5),
        find("least-effort-normalised", 0.5),
        find("least-effort", 1.0),
    );
    assert!(
        pairing(norm, "travel_m2") > pairing(raw, "travel_m2")
            && pairing(raw, "travel_m2") < 1.02 * pairing(one, "travel_m2"),
        "{raw} {norm} {one}"
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    well_formed(&text).unwrap();
    assert!(text.contains("λ") && text.contains("normalised"), "{text}");
}

/// `compare --variants` runs the rows named, in the table's order, each as it
/// runs among all of them (the same seeded runs).
#[test]
fn compare_runs_the_rows_named() {
    let compare = |extra: &[&str]| {
        let out = bin()
            .args(["transform", "compare", "--from", "square", "--to", "arrow"])
            .args([
                "--agents",
                "30",
                "--seeds",
                "2",
                "--json",
                "--timeout",
                "20",
            ])
            .args(extra)
            .output()
            .unwrap();
        json_of(&out)
    };
    let some = compare(&["--variants", "orca,least-effort"]);
    let names: Vec<&str> = some["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["variant"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["least-effort", "orca"], "{some}");
    assert_eq!(some["subgroups"]["count"]["n"], 2, "{some}");
    // Without --variants: Table 2's rows and ORCA.
    let all = compare(&[]);
    let rows = all["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "{all}");
    assert_eq!(rows[5]["variant"], "orca", "{all}");
    for r in some["rows"].as_array().unwrap() {
        let same = rows.iter().find(|x| x["variant"] == r["variant"]).unwrap();
        // Per-run figures (the windowed measures depend on every row's length).
        for k in ["finish_s", "arrived_fraction", "swaps", "mean_offset_m"] {
            assert_eq!(r[k], same[k], "{k}: {r} against {same}");
        }
    }
}

#[test]
fn bad_compare_options_are_clear_errors() {
    let compare = |extra: &[&str]| {
        bin()
            .args(["transform", "compare", "--from", "square", "--to", "arrow"])
            .args(["--agents", "20"])
            .args(extra)
            .output()
            .unwrap()
    };
    assert_error(
        &compare(&["--window", "0"]),
        &["--window must be a positive number of seconds, got 0"],
    );
    assert_error(
        &compare(&["--window", "NaN"]),
        &["--window must be a positive number of seconds, got NaN"],
    );
    assert_error(
        &compare(&["--timeout=-3"]),
        &["--timeout must be a positive number of seconds, got -3"],
    );
    let clap_error = |out: &Output, want: &str| {
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(!err.contains("panicked") && err.contains(want), "{err}");
    };
    clap_error(
        &compare(&["--timeout", "soon"]),
        "invalid value 'soon' for '--timeout",
    );
    assert_error(
        &compare(&["--seeds", "0"]),
        &["--seeds must be 1 to 100, got 0"],
    );
    assert_error(
        &compare(&["--lambdas", "0,1.5"]),
        &["--lambdas: each λ must be in [0, 1], got 1.5"],
    );
    clap_error(
        &compare(&["--lambdas", "0,x"]),
        "invalid value 'x' for '--lambdas",
    );
    assert_error(
        &compare(&["--variants", "least-effort,rvo2"]),
        &[
            "--variants: no row \"rvo2\"; the rows are least-effort, travel-only",
            "or all",
        ],
    );
    assert_error(
        &compare(&["--variants", "orca", "--lambdas", "0.5"]),
        &["--variants and --lambdas do not go together"],
    );
    assert_error(
        &bin()
            .args(["transform", "--from", "square", "--to", "arrow"])
            .args(["--timeout", "inf"])
            .output()
            .unwrap(),
        &["--timeout must be a positive number of seconds, got inf"],
    );
}

#[test]
fn subgroup_attraction_as_printed_runs_and_is_reported() {
    let args = ["--from", "square", "--to", "arrow", "--agents", "40"];
    // Eq. 21 as printed holds every group in a heap short of its targets: the
    // runs end at the timeout.
    let args = [&args[..], &["--seed", "1", "--json", "--timeout", "4"]].concat();
    let tail = ["--subgroup-attraction", "as-printed"];
    let one = json_of(&run(&[&args[..], &tail[..]].concat()));
    assert_eq!(one["subgroup_attraction"], "as-printed", "{one}");
    assert!(one["steps"].as_u64().unwrap() > 0, "{one}");
    let cmp = ["compare", "--seeds", "1"];
    let v = json_of(&run(&[&cmp[..], &args[..], &tail[..]].concat()));
    for r in v["rows"].as_array().unwrap() {
        // The baselines (ORCA, RVO, steering) have no subgroup forces.
        let want = if r["subgroup_forces"] == false {
            Value::Null
        } else {
            Value::from("as-printed")
        };
        assert_eq!(r["subgroup_attraction"], want, "{r}");
        let spread = r["subgroup_spread"]["end"]["mean"].as_f64().unwrap();
        assert!(spread.is_finite() && spread > 0.0, "{r}");
    }
    // A bad name is clap's error, with the choices.
    let out = run(&[&args[..], &["--subgroup-attraction", "glue"]].concat());
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("place, as-printed, decaying, dt"), "{err}");
}
