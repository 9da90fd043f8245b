//! Validation: a parsed [`SceneFile`] checked field by field into a [`Scene`], every
//! problem collected with its field path (the rules are listed in the scene module's
//! documentation).

use super::file::{v, DynamicDef, DynamicKindDef, PartDef, PointM, SceneFile, SCENE_VERSION};
use super::index::PartIndex;
use super::limits::{
    DEFAULT_AGENT_RADIUS_M, LENGTH_TOLERANCE_M, MAX_PARTS, MAX_POLYGON_VERTICES, MAX_SCENE_ITEMS,
    MAX_SPEED_FACTOR, MAX_WAYPOINTS, MIN_PATH_LENGTH_M, MIN_POLYGON_AREA_M2,
};
use super::model::{Checkpoint, Dynamic, DynamicKind, MotionPath, Obstacle, Patch, Scene, Terrain};
use super::problem::Problem;
use super::shape::{self, Circle, ConvexPolygon, Part};
use crate::geom::{Rect, Vec2};
use crate::vocab::MotionType;

/// Collects `(field, problem)` pairs during validation.
struct Problems(Vec<(String, Problem)>);

impl Problems {
    fn push(&mut self, field: impl Into<String>, p: Problem) {
        self.0.push((field.into(), p));
    }
}

fn finite2(p: PointM) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// Validates one part; `Some(part)` when it is usable.
fn build_part(def: &PartDef, field: &str, out: &mut Problems) -> Option<Part> {
    match def {
        PartDef::Polygon { vertices_m } => {
            let f = format!("{field}.vertices_m");
            if vertices_m.len() < 3 {
                out.push(
                    f,
                    Problem::TooFewVertices {
                        count: vertices_m.len(),
                    },
                );
                return None;
            }
            if vertices_m.len() > MAX_POLYGON_VERTICES {
                out.push(
                    f,
                    Problem::TooMany {
                        what: "polygon vertices",
                        count: vertices_m.len(),
                        max: MAX_POLYGON_VERTICES,
                    },
                );
                return None;
            }
            if !vertices_m.iter().all(|&p| finite2(p)) {
                out.push(f, Problem::NonFinite);
                return None;
            }
            let mut pts: Vec<Vec2> = vertices_m.iter().map(|&p| v(p)).collect();
            let twice = shape::signed_twice_area(&pts);
            let area_m2 = 0.5 * twice.abs();
            if area_m2.is_nan() || area_m2 < MIN_POLYGON_AREA_M2 {
                out.push(f, Problem::ZeroArea { area_m2 });
                return None;
            }
            let reversed = twice < 0.0;
            if reversed {
                pts.reverse();
            }
            if let Some(k) = shape::non_convex_vertex(&pts) {
                let vertex = if reversed { pts.len() - 1 - k } else { k };
                out.push(f, Problem::NonConvex { vertex });
                return None;
            }
            match ConvexPolygon::new(pts) {
                Some(p) => Some(Part::Polygon(p)),
                None => {
                    out.push(f, Problem::NonConvex { vertex: 0 });
                    None
                }
            }
        }
        PartDef::Circle { centre_m, radius_m } => {
            if !finite2(*centre_m) {
                out.push(format!("{field}.centre_m"), Problem::NonFinite);
                return None;
            }
            if !radius_m.is_finite() {
                out.push(format!("{field}.radius_m"), Problem::NonFinite);
                return None;
            }
            if *radius_m <= 0.0 {
                out.push(
                    format!("{field}.radius_m"),
                    Problem::NonPositiveRadius {
                        radius_m: *radius_m,
                    },
                );
                return None;
            }
            Some(Part::Circle(Circle {
                centre: v(*centre_m),
                radius_m: *radius_m,
            }))
        }
    }
}

/// The field to report a whole-part problem on (its first field).
fn part_field(def: &PartDef, field: &str) -> String {
    match def {
        PartDef::Polygon { .. } => format!("{field}.vertices_m"),
        PartDef::Circle { .. } => format!("{field}.centre_m"),
    }
}

fn inside_bounds(r: &Rect, b: &Rect) -> bool {
    let t = LENGTH_TOLERANCE_M;
    r.min[0] >= b.min[0] - t
        && r.min[1] >= b.min[1] - t
        && r.max[0] <= b.max[0] + t
        && r.max[1] <= b.max[1] + t
}

fn build_parts(
    defs: &[PartDef],
    field: &str,
    bounds: Option<&Rect>,
    out: &mut Problems,
) -> Vec<Part> {
    if defs.is_empty() {
        out.push(format!("{field}.parts"), Problem::NoParts);
    }
    if defs.len() > MAX_PARTS {
        out.push(
            format!("{field}.parts"),
            Problem::TooMany {
                what: "parts",
                count: defs.len(),
                max: MAX_PARTS,
            },
        );
        return Vec::new();
    }
    let mut parts = Vec::with_capacity(defs.len());
    for (j, d) in defs.iter().enumerate() {
        let pf = format!("{field}.parts[{j}]");
        if let Some(p) = build_part(d, &pf, out) {
            if let Some(b) = bounds {
                if !inside_bounds(&p.aabb(), b) {
                    out.push(part_field(d, &pf), Problem::OutsideBounds);
                }
            }
            parts.push(p);
        }
    }
    parts
}

fn build_terrain(
    motion: MotionType,
    speed_factor: Option<f64>,
    motion_length_m: Option<f64>,
    field: &str,
    out: &mut Problems,
) -> (Terrain, Option<f64>) {
    let speed = speed_factor.unwrap_or_else(|| motion.default_speed_factor());
    let sf = format!("{field}.speed_factor");
    if !speed.is_finite() {
        out.push(sf, Problem::NonFinite);
    } else if speed <= 0.0 {
        out.push(sf, Problem::NonPositiveSpeed { value: speed });
    } else if speed > MAX_SPEED_FACTOR {
        out.push(sf, Problem::SpeedTooHigh { value: speed });
    }
    let lf = format!("{field}.motion_length_m");
    match (motion.is_single_step(), motion_length_m) {
        (true, None) => out.push(
            format!("{field}.motion"),
            Problem::MissingMotionLength {
                motion: motion.as_str(),
            },
        ),
        (false, Some(_)) => out.push(
            lf,
            Problem::MotionLengthNotApplicable {
                motion: motion.as_str(),
            },
        ),
        (true, Some(l)) if !l.is_finite() => out.push(lf, Problem::NonFinite),
        (true, Some(l)) if l <= 0.0 => out.push(lf, Problem::NonPositiveMotionLength { value: l }),
        _ => {}
    }
    (
        Terrain {
            motion,
            speed_factor: speed,
        },
        motion_length_m,
    )
}

fn check_motion_length(
    parts: &[Part],
    defs: &[PartDef],
    len: Option<f64>,
    field: &str,
    out: &mut Problems,
) {
    let Some(l) = len.filter(|l| l.is_finite() && *l > 0.0) else {
        return;
    };
    for (j, (p, d)) in parts.iter().zip(defs).enumerate() {
        let w = p.min_width_m();
        if w > l + LENGTH_TOLERANCE_M {
            out.push(
                part_field(d, &format!("{field}.parts[{j}]")),
                Problem::PatchLongerThanMotion {
                    width_m: w,
                    motion_length_m: l,
                },
            );
        }
    }
}

fn describe(i: usize, name: &str) -> String {
    if name.is_empty() {
        format!("obstacles[{i}]")
    } else {
        format!("obstacles[{i}] {name:?}")
    }
}

impl Scene {
    /// Validates a parsed scene. A non-finite or non-positive `agent_radius_m` is
    /// taken as [`DEFAULT_AGENT_RADIUS_M`].
    ///
    /// # Errors
    /// Every `(field path, problem)` found.
    pub fn from_file(f: &SceneFile, agent_radius_m: f64) -> Result<Scene, Vec<(String, Problem)>> {
        let radius = if agent_radius_m.is_finite() && agent_radius_m > 0.0 {
            agent_radius_m
        } else {
            DEFAULT_AGENT_RADIUS_M
        };
        let min_gap_m = 2.0 * radius;
        let mut out = Problems(Vec::new());
        if f.version != SCENE_VERSION {
            out.push("version", Problem::UnsupportedVersion { found: f.version });
        }
        let b = f.bounds_m;
        let bounds_ok = if !(finite2(b.min) && finite2(b.max)) {
            out.push("bounds_m", Problem::NonFinite);
            false
        } else if !(b.min[0] < b.max[0] && b.min[1] < b.max[1]) {
            out.push("bounds_m", Problem::EmptyBounds);
            false
        } else {
            true
        };
        let bounds = bounds_ok.then_some(&b);
        for (what, count) in [
            ("obstacles", f.obstacles.len()),
            ("patches", f.patches.len()),
            ("dynamic", f.dynamic.len()),
            ("checkpoints", f.checkpoints.len()),
        ] {
            if count > MAX_SCENE_ITEMS {
                out.push(
                    what,
                    Problem::TooMany {
                        what,
                        count,
                        max: MAX_SCENE_ITEMS,
                    },
                );
            }
        }
        if !out.0.is_empty() && f.obstacles.len().max(f.patches.len()) > MAX_SCENE_ITEMS {
            return Err(out.0);
        }

        let obstacles: Vec<Obstacle> = f
            .obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| Obstacle {
                name: o.name.clone(),
                parts: build_parts(&o.parts, &format!("obstacles[{i}]"), bounds, &mut out),
            })
            .collect();
        // Separate obstacles: no overlap, gap at least one agent diameter (section 5).
        let boxes: Vec<Vec<Rect>> = obstacles
            .iter()
            .map(|o| o.parts.iter().map(Part::aabb).collect())
            .collect();
        let near = |a: &Rect, b: &Rect| {
            a.min[0] <= b.max[0] + min_gap_m
                && b.min[0] <= a.max[0] + min_gap_m
                && a.min[1] <= b.max[1] + min_gap_m
                && b.min[1] <= a.max[1] + min_gap_m
        };
        for i in 0..obstacles.len() {
            for k in 0..i {
                let mut worst: Option<Problem> = None;
                'pairs: for (pi, p) in obstacles[i].parts.iter().enumerate() {
                    for (pk, q) in obstacles[k].parts.iter().enumerate() {
                        if !near(&boxes[i][pi], &boxes[k][pk]) {
                            continue;
                        }
                        let other = describe(k, &obstacles[k].name);
                        if p.overlaps(q) {
                            worst = Some(Problem::Overlap { other });
                            break 'pairs;
                        }
                        let gap_m = p.gap_m(q);
                        if gap_m < min_gap_m - LENGTH_TOLERANCE_M {
                            let better = match &worst {
                                Some(Problem::GapTooSmall { gap_m: g, .. }) => gap_m < *g,
                                _ => true,
                            };
                            if better {
                                worst = Some(Problem::GapTooSmall {
                                    other,
                                    gap_m,
                                    min_gap_m,
                                });
                            }
                        }
                    }
                }
                if let Some(p) = worst {
                    out.push(format!("obstacles[{i}].parts"), p);
                }
            }
        }

        let patches: Vec<Patch> = f
            .patches
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let field = format!("patches[{i}]");
                let parts = build_parts(&p.parts, &field, bounds, &mut out);
                let (terrain, motion_length_m) = build_terrain(
                    p.motion,
                    p.speed_factor,
                    p.motion_length_m,
                    &field,
                    &mut out,
                );
                if parts.len() == p.parts.len() {
                    check_motion_length(&parts, &p.parts, motion_length_m, &field, &mut out);
                }
                Patch {
                    name: p.name.clone(),
                    terrain,
                    motion_length_m,
                    parts,
                }
            })
            .collect();

        let dynamic: Vec<Dynamic> = f
            .dynamic
            .iter()
            .enumerate()
            .map(|(i, d)| build_dynamic(i, d, bounds, &mut out))
            .collect();

        let checkpoints: Vec<Checkpoint> = f
            .checkpoints
            .iter()
            .enumerate()
            .filter_map(|(i, c)| {
                let field = format!("checkpoints[{i}]");
                if c.formation.trim().is_empty() {
                    out.push(format!("{field}.formation"), Problem::EmptyFormation);
                }
                let rf = format!("{field}.region");
                let region = build_part(&c.region, &rf, &mut out)?;
                if let Some(b) = bounds {
                    if !inside_bounds(&region.aabb(), b) {
                        out.push(part_field(&c.region, &rf), Problem::OutsideBounds);
                    }
                }
                Some(Checkpoint {
                    name: c.name.clone(),
                    region,
                    formation: c.formation.clone(),
                    formation_at: (0, 0),
                })
            })
            .collect();

        if out.0.is_empty() {
            Ok(Scene {
                name: f.name.clone(),
                bounds: b,
                index: PartIndex::new(
                    b,
                    obstacles.iter().map(|o| &o.parts[..]),
                    patches.iter().map(|p| &p.parts[..]),
                    dynamic.iter().map(|d| &d.parts[..]),
                ),
                obstacles,
                patches,
                dynamic,
                checkpoints,
            })
        } else {
            Err(out.0)
        }
    }
}

fn build_dynamic(i: usize, d: &DynamicDef, bounds: Option<&Rect>, out: &mut Problems) -> Dynamic {
    let field = format!("dynamic[{i}]");
    let parts = build_parts(&d.parts, &field, None, out);
    let kind = match d.kind {
        DynamicKindDef::Obstacle => DynamicKind::Obstacle,
        DynamicKindDef::Patch {
            motion,
            speed_factor,
            motion_length_m,
        } => {
            let kf = format!("{field}.kind");
            let (terrain, len) = build_terrain(motion, speed_factor, motion_length_m, &kf, out);
            if parts.len() == d.parts.len() {
                check_motion_length(&parts, &d.parts, len, &field, out);
            }
            DynamicKind::Patch(terrain)
        }
    };
    let pf = format!("{field}.path");
    let p = &d.path;
    let mut path_ok = true;
    if p.waypoints_m.len() > MAX_WAYPOINTS {
        out.push(
            format!("{pf}.waypoints_m"),
            Problem::TooMany {
                what: "waypoints",
                count: p.waypoints_m.len(),
                max: MAX_WAYPOINTS,
            },
        );
        path_ok = false;
    } else if !p.waypoints_m.iter().all(|&w| finite2(w)) {
        out.push(format!("{pf}.waypoints_m"), Problem::NonFinite);
        path_ok = false;
    } else {
        let len: f64 = p
            .waypoints_m
            .windows(2)
            .map(|w| (v(w[1]) - v(w[0])).norm())
            .sum();
        if p.waypoints_m.len() < 2 || len.is_nan() || len < MIN_PATH_LENGTH_M {
            out.push(format!("{pf}.waypoints_m"), Problem::PathTooShort);
            path_ok = false;
        }
    }
    if !p.speed_m_s.is_finite() || !p.start_s.is_finite() {
        let f = if p.speed_m_s.is_finite() {
            "start_s"
        } else {
            "speed_m_s"
        };
        out.push(format!("{pf}.{f}"), Problem::NonFinite);
        path_ok = false;
    } else if p.speed_m_s <= 0.0 {
        out.push(
            format!("{pf}.speed_m_s"),
            Problem::NonPositiveSpeed { value: p.speed_m_s },
        );
    }
    // Inside the bounds at every waypoint; between waypoints too, by convexity of
    // the bounds (a rotating thing is checked by its reach in every direction).
    if let (Some(b), true) = (bounds, path_ok && parts.len() == d.parts.len()) {
        let outside = p.waypoints_m.iter().any(|&w| {
            let w = v(w);
            parts.iter().any(|part| {
                let r = if p.rotate {
                    let reach = part.reach_m();
                    Rect {
                        min: [w.x - reach, w.y - reach],
                        max: [w.x + reach, w.y + reach],
                    }
                } else {
                    let a = part.aabb();
                    Rect {
                        min: [a.min[0] + w.x, a.min[1] + w.y],
                        max: [a.max[0] + w.x, a.max[1] + w.y],
                    }
                };
                !inside_bounds(&r, b)
            })
        });
        if outside {
            out.push(format!("{pf}.waypoints_m"), Problem::OutsideBounds);
        }
    }
    Dynamic {
        name: d.name.clone(),
        kind,
        parts,
        path: MotionPath::new(p),
    }
}
