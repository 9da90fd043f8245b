//! `crowdtouch edit apply`: an edit script (`--ops EDIT.ron`, [`crowdtouch::crowd::edit::Script`])
//! run on a track file, optionally followed by obstacle avoidance by the cage
//! (section 4.2) and collision avoidance by retiming (section 4.1.2); the result is
//! written to `-o OUT` (never over an existing file without `--force`) with a report:
//! collisions before and after, the speed change, each drag's hull-shape error.

use super::track_file::{load, TrackFileArgs};
use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::crowd::edit::io::{self, EthOptions, Format, ReadOptions};
use crowdtouch::crowd::edit::{
    avoid, avoid_obstacles, correct_speeds, crowd_width_at, detect, detect_keeping, parse_script,
    push_samples_out, run_script, samples_in_obstacles, ApplyParams, ApplyReport, AvoidParams,
    AvoidReport, Cage, CageParams, Collisions, ObstacleParams, ObstacleReport, Script, ScriptError,
    Selection, SelectionQuery, TrackSet,
};
use crowdtouch::crowd::environment::{load_scene, Scene, DEFAULT_AGENT_RADIUS_M};
use crowdtouch::geom::Rect;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The largest edit script read (bytes).
pub const MAX_SCRIPT_BYTES: u64 = 16 << 20;

/// What `edit apply` and `edit render` both run: the tracks, the script and the
/// optional avoidance steps.
#[derive(clap::Args, Debug)]
pub struct EditArgs {
    /// The tracks.
    #[command(flatten)]
    pub tracks: TrackFileArgs,
    /// The edit script (RON: `(ops: [Select(...), Fix(...), Drag(...), Retime(...)])`);
    /// without it only the avoidance steps asked for run.
    #[arg(long)]
    pub ops: Option<PathBuf>,
    /// After the script, keep the crowd out of this scene's obstacles by adjusting
    /// the cage of every person (section 4.2); a file or a shipped scene's name.
    #[arg(long, value_name = "SCENE")]
    pub avoid_obstacles: Option<PathBuf>,
    /// Then retime people so no two come closer than `--threshold` (section 4.1.2).
    #[arg(long)]
    pub avoid_collisions: bool,
    /// Two people closer than this collide (metres).
    #[arg(long, default_value_t = 0.3)]
    pub threshold: f64,
    /// The most collision avoidance may move anyone's times from the input
    /// (seconds).
    #[arg(long, default_value_t = AvoidParams::default().max_shift_s,
          value_parser = parse_positive_seconds, allow_hyphen_values = true)]
    pub max_shift: f64,
    /// Drags must end inside `x0,y0,x1,y1` (metres); default: the tracks' bounding
    /// box grown by half its size and at least 10 m.
    #[arg(long, value_parser = parse_rect)]
    pub world: Option<Rect>,
}

/// `edit apply`.
#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// The tracks, the script and the avoidance steps.
    #[command(flatten)]
    pub edit: EditArgs,
    /// Where to write the edited tracks (format from the extension: `.jsonl`,
    /// `.csv`, `.txt`/`.eth`).
    #[arg(long, short)]
    pub output: PathBuf,
    /// Replace `-o` if it exists (also when it is the input file).
    #[arg(long)]
    pub force: bool,
    /// One JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The result of [`run`]: the tracks before and after and what each step did.
pub struct Outcome {
    /// The tracks as read.
    pub before: TrackSet,
    /// The tracks after the script and the avoidance steps.
    pub after: TrackSet,
    /// The input file's format.
    pub format: Format,
    /// The script as parsed.
    pub script: Script,
    /// What the script did.
    pub report: ApplyReport,
    /// The scene of `--avoid-obstacles` and what keeping out of it did.
    pub obstacles: Option<(Scene, ObstacleReport, ObstacleDetail)>,
    /// What collision avoidance did.
    pub avoided: Option<AvoidReport>,
    /// Collisions of the input.
    pub collisions_before: Collisions,
    /// Collisions of the result.
    pub collisions_after: Collisions,
    /// Slowest and fastest segment relative to the input ([`speed_change`]).
    pub speed: (f64, f64),
}

/// Loads the tracks, runs the script, then obstacle and collision avoidance as
/// asked; errors in the script name `file:line`.
pub fn run(a: &EditArgs) -> Result<Outcome> {
    if !(a.threshold.is_finite() && a.threshold > 0.0) {
        bail!(
            "--threshold must be a positive number of metres, not {}",
            a.threshold
        );
    }
    let (mut set, format) = load(&a.tracks)?;
    let shown = a
        .ops
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let script = match &a.ops {
        Some(ops) => {
            let text = crowdtouch::located::read_text(ops, MAX_SCRIPT_BYTES)
                .map_err(|e| anyhow!("{e}"))?;
            parse_script(&text).map_err(|e| match e {
                ScriptError::Syntax(i) => {
                    anyhow!("{shown}:{}:{}: {}", i.line, i.column, located_what(&i))
                }
                ScriptError::Op { line, what } => anyhow!("{shown}:{line}: {what}"),
            })?
        }
        None => Script { ops: Vec::new() },
    };
    let before = set.clone();
    let world = a.world.unwrap_or_else(|| default_world(&set));
    let params = ApplyParams {
        world: Some(world),
        ..ApplyParams::default()
    };
    let collisions_before = detect(&set, a.threshold).map_err(|e| anyhow!("{e}"))?;
    let report = run_script(&mut set, &script, &params).map_err(|e| match e {
        ScriptError::Op { line, what } => anyhow!("{shown}:{line}: {what}"),
        ScriptError::Syntax(i) => anyhow!("{shown}: {i}"),
    })?;
    let obstacles = match &a.avoid_obstacles {
        Some(scene) => Some(keep_out_of_obstacles(&mut set, scene, world)?),
        None => None,
    };
    let avoided = if a.avoid_collisions {
        let params = AvoidParams {
            threshold_m: a.threshold,
            max_shift_s: a.max_shift,
            ..AvoidParams::default()
        };
        Some(avoid(&mut set, &params).map_err(|e| anyhow!("collision avoidance: {e}"))?)
    } else {
        None
    };
    let collisions_after = detect(&set, a.threshold).map_err(|e| anyhow!("{e}"))?;
    let speed = speed_change(&before, &set);
    Ok(Outcome {
        before,
        after: set,
        format,
        script,
        report,
        obstacles,
        avoided,
        collisions_before,
        collisions_after,
        speed,
    })
}

/// Runs `edit apply`.
pub fn apply(a: ApplyArgs) -> Result<()> {
    if a.output.exists() && !a.force {
        bail!("{} exists; give --force to replace it", a.output.display());
    }
    let Outcome {
        before: _,
        after: set,
        format,
        script,
        report,
        obstacles,
        avoided,
        collisions_before,
        collisions_after,
        speed,
    } = run(&a.edit)?;
    let obstacles = obstacles.map(|(_, r, d)| (r, d));
    let avoided = avoided.as_ref().map(avoid_json);
    let e = &a.edit;
    let out_format = output_format(&a.output).unwrap_or(format);
    let opts = ReadOptions {
        eth: EthOptions {
            frame_rate_hz: e.tracks.frame_rate,
            frame_step: e.tracks.frame_step,
        },
        csv_step_s: e.tracks.step,
    };
    io::write_tracks(&set, &a.output, out_format, &opts, a.force)
        .map_err(|e| anyhow!(e))
        .with_context(|| "writing the edited tracks")?;
    let j = json!({
        "file": e.tracks.file.display().to_string(),
        "output": a.output.display().to_string(),
        "people": set.tracks.len(),
        "samples": set.samples(),
        "threshold_m": e.threshold,
        "ops": script.ops.len(),
        "drags": drags_json(&report),
        "retimes": report.retimes,
        "retimed_samples": report.retimed_samples,
        "touched": report.touched.len(),
        "obstacles": obstacles.as_ref().map(|(r, d)| obstacles_json((r, d))),
        "avoidance": avoided,
        "collisions_before": collisions_before.pair_count(),
        "collisions_after": collisions_after.pair_count(),
        "min_distance_before_m": collisions_before.min_distance_m(),
        "min_distance_after_m": collisions_after.min_distance_m(),
        "speed_ratio": {"min": speed.0, "max": speed.1},
    });
    if a.json {
        outln!("{j}")?;
        return Ok(());
    }
    outln!(
        "{} → {}: {} people, {} samples",
        j["file"].as_str().unwrap_or(""),
        j["output"].as_str().unwrap_or(""),
        set.tracks.len(),
        set.samples()
    )?;
    for d in &report.drags {
        outln!(
            "  line {}: drag of {} by {:.2} m; hull shape error {:.1} % (edges), {:.3} rad (angles); speeds {:.0}–{:.0} % before correction, {:.0}–{:.0} % after",
            d.line,
            d.handle,
            d.distance_m,
            100.0 * d.shape_edge_rms,
            d.shape_angle_rms_rad,
            100.0 * d.speed_ratio_edited.0,
            100.0 * d.speed_ratio_edited.1,
            100.0 * d.speed_ratio_corrected.0,
            100.0 * d.speed_ratio_corrected.1
        )?;
    }
    if report.retimes > 0 {
        outln!(
            "  {} retime(s), {} samples re-timed",
            report.retimes,
            report.retimed_samples
        )?;
    }
    if let Some((o, d)) = &obstacles {
        outln!(
            "  obstacles: {} samples inside before, {} after ({} groups, {} cage rounds, {} samples moved out one by one)",
            o.samples_inside_before,
            o.samples_inside_after,
            d.groups.len(),
            o.rounds,
            d.pushed_samples
        )?;
        for (name, b, a) in d.per_obstacle.iter().filter(|x| x.1 + x.2 > 0) {
            outln!("    {name}: {b} samples inside before, {a} after")?;
        }
    }
    if let Some(v) = j["avoidance"].as_object() {
        outln!(
            "  collision avoidance: {} pairs before, {} after ({} of them companions), {} shifts and {} retimings in {} rounds; {} of {} people in a collision retimed, by {:.2} s (median) and at most {:.2} s (bound {} s); speeds changed by at most {:.1} %",
            v["pairs_before"], v["pairs_after"], v["companions"], v["shifts"], v["retimings"], v["iterations"],
            v["retimed_people"], v["people_in_collision"],
            v["median_shift_s"].as_f64().unwrap_or(f64::NAN),
            v["max_shift_s"].as_f64().unwrap_or(f64::NAN),
            v["max_shift_bound_s"],
            v["max_speed_change_pct"].as_f64().unwrap_or(f64::NAN)
        )?;
        for r in v["remaining"].as_array().into_iter().flatten() {
            outln!(
                "    still closer than the threshold: {} and {} ({:.3} m at {:.1} s, {})",
                r["a"],
                r["b"],
                r["distance_m"].as_f64().unwrap_or(f64::NAN),
                r["t_s"].as_f64().unwrap_or(f64::NAN),
                r["why"].as_str().unwrap_or("")
            )?;
        }
    }
    outln!(
        "  pairs closer than {} m: {} before, {} after; speeds {:.0}–{:.0} % of the originals",
        e.threshold,
        collisions_before.pair_count(),
        collisions_after.pair_count(),
        100.0 * speed.0,
        100.0 * speed.1
    )?;
    Ok(())
}

fn located_what(i: &crowdtouch::located::Issue) -> String {
    if i.field.is_empty() {
        i.message.clone()
    } else {
        format!("field `{}`: {}", i.field, i.message)
    }
}

/// The tracks' bounding box grown by half its size, and by at least 10 m.
fn default_world(set: &TrackSet) -> Rect {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in set.tracks.iter().flat_map(|t| &t.points) {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    let grow = |a: f64, b: f64| ((b - a) * 0.5).max(10.0);
    let (gx, gy) = (grow(lo[0], hi[0]), grow(lo[1], hi[1]));
    Rect {
        min: [lo[0] - gx, lo[1] - gy],
        max: [hi[0] + gx, hi[1] + gy],
    }
}

/// A finite, positive number of seconds (`--max-shift`).
fn parse_positive_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(_) => Err(format!("`{s}` is not a positive, finite number of seconds")),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

fn parse_rect(s: &str) -> Result<Rect, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|w| {
            w.trim()
                .parse::<f64>()
                .map_err(|_| format!("`{w}` is not a number"))
        })
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x0, y0, x1, y1] if v.iter().all(|x| x.is_finite()) && x0 < x1 && y0 < y1 => Ok(Rect {
            min: [x0, y0],
            max: [x1, y1],
        }),
        _ => Err("expected x0,y0,x1,y1 with x0 < x1 and y0 < y1".into()),
    }
}

fn output_format(p: &Path) -> Option<Format> {
    match p.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "jsonl" | "json" => Some(Format::Jsonl),
        "csv" => Some(Format::Csv),
        "txt" | "eth" => Some(Format::Eth),
        _ => None,
    }
}

/// People who come within this distance of each other at the same time walk
/// together (metres): each such group gets a cage of its own for obstacle
/// avoidance (section 4.2: a cage encloses one crowd; one cage around two groups
/// apart encloses the space, and the walls, between them).
const GROUP_DISTANCE_M: f64 = 1.0;

/// Sample pushes per sample at most (a push may land in another part).
const PUSH_ROUNDS: usize = 4;

/// What keeping out of obstacles did beyond the cages' own report.
#[derive(Clone, Debug, Default)]
pub struct ObstacleDetail {
    /// Per group: its people, its width across its motion (eq. 29, the largest
    /// at its sample times, m), its cage's hull vertices or edges still in an
    /// obstacle after the cage's rounds, and its samples still inside an obstacle
    /// after its cage (an obstacle inside the cage: the hull is clear, the
    /// people are not).
    pub groups: Vec<(usize, f64, usize, usize)>,
    /// Per obstacle: its name and the samples inside it before and after.
    pub per_obstacle: Vec<(String, usize, usize)>,
    /// Samples the cages left inside and that were moved out one by one.
    pub pushed_samples: usize,
}

/// The people of `set` in groups: connected by coming within
/// [`GROUP_DISTANCE_M`] of each other at the same time (each group's indices
/// sorted; groups by first index).
fn groups_of(set: &TrackSet) -> Result<Vec<Vec<usize>>> {
    let n = set.tracks.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    let near = detect_keeping(set, GROUP_DISTANCE_M, usize::MAX).map_err(|e| anyhow!("{e}"))?;
    let links = near.pairs.iter().map(|q| (q.a, q.b)).chain(
        near.clusters
            .iter()
            .flat_map(|c| c.members.windows(2).map(|w| (w[0], w[1]))),
    );
    for (a, b) in links {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    for k in 0..n {
        let r = root(&mut parent, k);
        if slot[r] == usize::MAX {
            slot[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[slot[r]].push(k);
    }
    Ok(groups)
}

/// The largest width of a group across its motion (eq. 29) at its people's
/// sample times (metres).
fn group_width(set: &TrackSet, group: &[usize]) -> f64 {
    let mut times: Vec<f64> = group
        .iter()
        .flat_map(|&k| set.tracks[k].times_s.iter().copied())
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup();
    let stride = (times.len() / 200).max(1);
    times
        .iter()
        .step_by(stride)
        .filter_map(|&t| crowd_width_at(set, group, t))
        .fold(0.0, f64::max)
}

/// Each group's cage kept out of the scene's obstacles (section 4.2, one cage
/// per group of people walking together), then every sample still inside an
/// obstacle moved out on its own and reported, then speeds corrected (eq. 9).
fn keep_out_of_obstacles(
    set: &mut TrackSet,
    scene: &Path,
    world: Rect,
) -> Result<(Scene, ObstacleReport, ObstacleDetail)> {
    let file = super::edit_path::scene_file(scene);
    let scene = load_scene(&file, DEFAULT_AGENT_RADIUS_M).map_err(|e| anyhow!("{e}"))?;
    let before = set.clone();
    let obstacles = scene.obstacles();
    let everyone: Vec<usize> = (0..set.tracks.len()).collect();
    let inside_before = samples_in_obstacles(set, &everyone, obstacles);
    let params = CageParams {
        world: Some(world),
        ..CageParams::default()
    };
    let mut report = ObstacleReport {
        targets: Vec::new(),
        rounds: 0,
        hull_violations: 0,
        samples_inside_before: inside_before.iter().sum(),
        samples_inside_after: 0,
    };
    let mut detail = ObstacleDetail::default();
    for group in groups_of(set)? {
        let width_m = group_width(set, &group);
        if samples_in_obstacles(set, &group, obstacles)
            .iter()
            .all(|&c| c == 0)
        {
            detail.groups.push((group.len(), width_m, 0, 0));
            continue;
        }
        let ids: Vec<u64> = group.iter().map(|&k| set.tracks[k].id).collect();
        let sel = Selection::select(set, &SelectionQuery::default().ids(&ids))
            .map_err(|e| anyhow!("{}: {e}", file.display()))?;
        let mut cage = Cage::new(set, &sel, &params).map_err(|e| anyhow!("a group's cage: {e}"))?;
        let r = avoid_obstacles(&mut cage, obstacles, &[], &ObstacleParams::default())
            .map_err(|e| anyhow!("keeping out of the obstacles of {}: {e}", file.display()))?;
        cage.apply(set).map_err(|e| anyhow!("{e}"))?;
        report.targets.extend(r.targets.iter().copied());
        report.rounds = report.rounds.max(r.rounds);
        report.hull_violations += r.hull_violations;
        let left: usize = samples_in_obstacles(set, &group, obstacles).iter().sum();
        detail
            .groups
            .push((group.len(), width_m, r.hull_violations, left));
    }
    detail.pushed_samples = push_samples_out(
        set,
        &everyone,
        obstacles,
        ObstacleParams::default().clearance_m,
        PUSH_ROUNDS,
    );
    correct_speeds(&before, set, &everyone).map_err(|e| anyhow!("{e}"))?;
    let inside_after = samples_in_obstacles(set, &everyone, obstacles);
    report.samples_inside_after = inside_after.iter().sum();
    detail.per_obstacle = obstacles
        .iter()
        .zip(inside_before.iter().zip(&inside_after))
        .map(|(o, (&b, &a))| (o.name.clone(), b, a))
        .collect();
    Ok((scene, report, detail))
}

fn avoid_json(r: &AvoidReport) -> Value {
    json!({
        "iterations": r.iterations,
        "pairs_before": r.pairs_before,
        "pairs_after": r.pairs_after,
        "retimings": r.retimings,
        "total_abs_dt_s": r.total_abs_dt_s,
        "max_speed_change_pct": r.max_speed_change_pct,
        "people_in_collision": r.people_in_collision,
        "retimed_people": r.retimed_people,
        "median_shift_s": r.median_shift_s,
        "max_shift_s": r.max_shift_s,
        "max_shift_bound_s": r.max_shift_bound_s,
        "shifts": r.shifts,
        "companions": r.companions,
        "undone": r.undone,
        "closest_before_m": r.closest_before_m,
        "closest_after_m": r.closest_after_m,
        "reverted": r.reverted,
        "remaining": r.remaining.iter().map(|x| json!({
            "a": x.pair.id_a,
            "b": x.pair.id_b,
            "distance_m": x.pair.closest.distance_m,
            "t_s": x.pair.closest.t_s,
            "why": x.why.as_str(),
        })).collect::<Vec<_>>(),
    })
}

fn obstacles_json((o, d): (&ObstacleReport, &ObstacleDetail)) -> Value {
    json!({
        "rounds": o.rounds,
        "moved_hull_vertices": o.targets.len(),
        "samples_inside_before": o.samples_inside_before,
        "samples_inside_after": o.samples_inside_after,
        "hull_violations": o.hull_violations,
        "pushed_samples": d.pushed_samples,
        "groups": d.groups.iter().map(|(people, width_m, hull, left)| json!({
            "people": people, "width_m": width_m, "hull_violations": hull,
            "samples_inside_after_cage": left,
        })).collect::<Vec<_>>(),
        "per_obstacle": d.per_obstacle.iter().map(|(name, b, a)| json!({
            "name": name, "samples_inside_before": b, "samples_inside_after": a,
        })).collect::<Vec<_>>(),
    })
}

fn drags_json(r: &ApplyReport) -> Value {
    Value::Array(
        r.drags
            .iter()
            .map(|d| {
                json!({
                    "line": d.line,
                    "handle": d.handle,
                    "distance_m": d.distance_m,
                    "hull_shape_error": {"edge_length_rms": d.shape_edge_rms, "angle_rms_rad": d.shape_angle_rms_rad},
                    "speed_ratio_edited": [d.speed_ratio_edited.0, d.speed_ratio_edited.1],
                    "speed_ratio_corrected": [d.speed_ratio_corrected.0, d.speed_ratio_corrected.1],
                })
            })
            .collect(),
    )
}

/// The slowest and fastest linked segment of the result relative to the same
/// segment of the input (people and samples matched by index; segments that did not
/// move before are left out). `(1, 1)` when none compares.
pub fn speed_change(before: &TrackSet, after: &TrackSet) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (b, a) in before.tracks.iter().zip(&after.tracks) {
        if a.len() != b.len() {
            continue;
        }
        for j in b.segments() {
            let vb = b.segment_speed(j);
            if vb > 1e-9 {
                let r = a.segment_speed(j) / vb;
                lo = lo.min(r);
                hi = hi.max(r);
            }
        }
    }
    if lo > hi {
        (1.0, 1.0)
    } else {
        (lo, hi)
    }
}
