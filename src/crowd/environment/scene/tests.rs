//! Scene loading, validation and geometry queries.

use super::*;
use crate::geom::{Rect, Vec2};
use crate::vocab::MotionType;
use std::path::Path;

fn scene(text: &str) -> Scene {
    match Scene::from_str(text, Path::new("t.ron"), DEFAULT_AGENT_RADIUS_M) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

fn issues(text: &str) -> Vec<SceneIssue> {
    match Scene::from_str(text, Path::new("t.ron"), DEFAULT_AGENT_RADIUS_M) {
        Err(SceneError::Invalid { issues, .. }) => issues,
        other => panic!("expected invalid, got {other:?}"),
    }
}

/// A scene with the given inner list text (obstacles, patches...).
fn with(body: &str) -> String {
    format!("(\n    version: 1,\n    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),\n{body}\n)\n")
}

const SQUARE_2_2: &str = "Polygon(vertices_m: [(2.0, 2.0), (4.0, 2.0), (4.0, 4.0), (2.0, 4.0)])";

#[test]
fn the_module_example_loads() {
    let text = include_str!("mod.rs")
        .lines()
        .skip_while(|l| !l.starts_with("//! ```ron"))
        .skip(1)
        .take_while(|l| !l.starts_with("//! ```"))
        .map(|l| {
            l.strip_prefix("//!")
                .unwrap_or(l)
                .strip_prefix(' ')
                .unwrap_or("")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let s = scene(&text);
    s.sanity_check().unwrap();
    assert_eq!(s.obstacles().len(), 2);
    assert_eq!(s.patches()[0].terrain.motion, MotionType::Swim);
    assert_eq!(s.patches()[0].terrain.speed_factor, 0.46);
    assert_eq!(s.dynamic().len(), 1);
    assert_eq!(s.checkpoints()[0].formation, "arrow");
}

#[test]
fn table_1_defaults() {
    let expect = [1.0, 0.33, 0.30, 0.46, 1.24, 0.50, 0.48];
    for (m, e) in MotionType::ALL.iter().zip(expect) {
        assert_eq!(m.default_speed_factor(), e, "{m:?}");
    }
    assert!(MotionType::Jump.is_single_step() && !MotionType::Crawl.is_single_step());
}

#[test]
fn a_non_convex_polygon_is_named_with_its_line() {
    let text = with(
        "    obstacles: [\n        (name: \"ok\", parts: [Circle(centre_m: (10.0, 5.0), radius_m: 0.5)]),\n        (name: \"dent\", parts: [\n            Polygon(vertices_m: [(2.0, 2.0), (4.0, 2.0), (3.0, 2.5), (4.0, 4.0), (2.0, 4.0)]),\n        ]),\n    ],",
    );
    let is = issues(&text);
    assert_eq!(is.len(), 1, "{is:?}");
    assert_eq!(is[0].field, "obstacles[1].parts[0].vertices_m");
    assert_eq!(is[0].problem, Problem::NonConvex { vertex: 2 });
    let line = text.lines().position(|l| l.contains("(3.0, 2.5)")).unwrap() + 1;
    assert_eq!(is[0].line, line);
    assert!(is[0].column > 1);
}

#[test]
fn every_problem_is_reported_in_file_order() {
    let text = with(&format!(
        "    obstacles: [
        (name: \"a\", parts: [{SQUARE_2_2}]),
        (name: \"too close\", parts: [Circle(centre_m: (4.2, 3.0), radius_m: 0.1)]),
        (name: \"overlap\", parts: [Circle(centre_m: (2.0, 2.0), radius_m: 0.5)]),
        (name: \"line\", parts: [Polygon(vertices_m: [(8.0, 1.0), (9.0, 1.0), (10.0, 1.0)])]),
        (name: \"two\", parts: [Polygon(vertices_m: [(8.0, 1.0), (9.0, 1.0)])]),
        (name: \"out\", parts: [Circle(centre_m: (15.9, 5.0), radius_m: 0.5)]),
        (name: \"nan\", parts: [Circle(centre_m: (12.0, 5.0), radius_m: NaN)]),
    ],
    patches: [
        (name: \"stop\", motion: crawl, speed_factor: Some(0.0), parts: [Circle(centre_m: (12.0, 2.0), radius_m: 0.5)]),
        (name: \"hop\", motion: jump, parts: [Circle(centre_m: (12.0, 7.0), radius_m: 0.5)]),
        (name: \"long hop\", motion: climb_up, motion_length_m: Some(0.5), parts: [Circle(centre_m: (14.0, 7.0), radius_m: 0.5)]),
    ],
    checkpoints: [(name: \"c\", formation: \"\", region: Circle(centre_m: (1.0, 1.0), radius_m: 0.5))],"
    ));
    let got: Vec<(String, String)> = issues(&text)
        .iter()
        .map(|i| {
            (
                i.field.clone(),
                format!("{:?}", i.problem)
                    .split([' ', '{'])
                    .next()
                    .unwrap()
                    .to_string(),
            )
        })
        .collect();
    let want = [
        ("obstacles[1].parts", "GapTooSmall"),
        ("obstacles[2].parts", "Overlap"),
        ("obstacles[3].parts[0].vertices_m", "ZeroArea"),
        ("obstacles[4].parts[0].vertices_m", "TooFewVertices"),
        ("obstacles[5].parts[0].centre_m", "OutsideBounds"),
        ("obstacles[6].parts[0].radius_m", "NonFinite"),
        ("patches[0].speed_factor", "NonPositiveSpeed"),
        ("patches[1].motion", "MissingMotionLength"),
        ("patches[2].parts[0].centre_m", "PatchLongerThanMotion"),
        ("checkpoints[0].formation", "EmptyFormation"),
    ];
    let want: Vec<(String, String)> = want
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(got, want);
}

#[test]
fn gap_threshold_is_one_agent_diameter() {
    // Two discs 0.35 m apart: fine for radius 0.15 (diameter 0.3), not for 0.2.
    let text = with(
        "    obstacles: [
        (parts: [Circle(centre_m: (4.0, 4.0), radius_m: 1.0)]),
        (parts: [Circle(centre_m: (6.35, 4.0), radius_m: 1.0)]),
    ],",
    );
    assert!(Scene::from_str(&text, Path::new("g"), 0.15).is_ok());
    match Scene::from_str(&text, Path::new("g"), 0.2) {
        Err(SceneError::Invalid { issues, .. }) => match &issues[0].problem {
            Problem::GapTooSmall {
                gap_m, min_gap_m, ..
            } => {
                assert!((gap_m - 0.35).abs() < 1e-9 && (min_gap_m - 0.4).abs() < 1e-12);
            }
            p => panic!("{p:?}"),
        },
        other => panic!("{other:?}"),
    }
}

#[test]
fn parts_of_one_union_may_overlap() {
    // An L: two overlapping bars in one obstacle.
    let text = with(
        "    obstacles: [(name: \"L\", parts: [
        Polygon(vertices_m: [(2.0, 2.0), (3.0, 2.0), (3.0, 6.0), (2.0, 6.0)]),
        Polygon(vertices_m: [(2.0, 5.0), (7.0, 5.0), (7.0, 6.0), (2.0, 6.0)]),
    ])],",
    );
    let s = scene(&text);
    assert_eq!(
        s.obstacle_at(Vec2::new(2.5, 5.5), 0.0),
        Some(ObstacleId::Static(0))
    );
    assert_eq!(s.obstacle_at(Vec2::new(5.0, 3.0), 0.0), None);
}

#[test]
fn syntax_and_unknown_fields_are_located() {
    let text = with("    obstacles: [(name: \"x\", parts: [], colour: 3)],");
    let is = issues(&text);
    assert_eq!(is.len(), 1);
    assert!(matches!(is[0].problem, Problem::Syntax { .. }));
    assert_eq!(is[0].line, 4);
    let e = Scene::from_str(
        "(version: 2, bounds_m: (min: (0.0, 0.0), max: (1.0, 1.0)))",
        Path::new("v.ron"),
        0.15,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("v.ron:1:2: version: version 2 is not supported"),
        "{e}"
    );
}

#[test]
fn signed_distance_nearest_point_and_projection() {
    let s = scene(&with(&format!(
        "    obstacles: [(parts: [{SQUARE_2_2}]), (parts: [Circle(centre_m: (10.0, 5.0), radius_m: 1.0)])],"
    )));
    // 0.25 inside the square's left edge.
    let h = s.nearest_obstacle(Vec2::new(2.25, 3.0), 0.0).unwrap();
    assert_eq!(h.id, ObstacleId::Static(0));
    assert!((h.boundary.signed_distance_m + 0.25).abs() < 1e-12);
    assert!((s.signed_distance(Vec2::new(10.0, 7.0), 0.0) - 1.0).abs() < 1e-12);
    // Projected out of the left side, 0.1 m clear.
    let q = s.project_out(Vec2::new(2.25, 3.0), 0.1, 0.0);
    assert!((q - Vec2::new(1.9, 3.0)).norm() < 1e-12, "{q:?}");
    // Out of the disc radially.
    let q = s.project_out(Vec2::new(10.5, 5.0), 0.2, 0.0);
    assert!((q - Vec2::new(11.2, 5.0)).norm() < 1e-12, "{q:?}");
    // A free point stays put.
    let p = Vec2::new(7.0, 7.0);
    assert_eq!(s.project_out(p, 0.2, 0.0), p);
}

#[test]
fn visibility_through_and_around_obstacles() {
    let s = scene(&with(&format!("    obstacles: [(parts: [{SQUARE_2_2}])],")));
    let (t, id) = s
        .segment_hit(Vec2::new(0.0, 3.0), Vec2::new(8.0, 3.0), 0.0)
        .unwrap();
    assert_eq!(id, ObstacleId::Static(0));
    assert!((t - 0.25).abs() < 1e-12);
    assert!(s.visible(Vec2::new(0.0, 5.0), Vec2::new(8.0, 5.0), 0.0));
}

#[test]
fn terrain_under_a_point_last_patch_wins() {
    let s = scene(&with(
        "    patches: [
        (name: \"pool\", motion: swim, parts: [Polygon(vertices_m: [(1.0, 1.0), (5.0, 1.0), (5.0, 5.0), (1.0, 5.0)])]),
        (name: \"raft lane\", motion: run, speed_factor: Some(1.5), parts: [Circle(centre_m: (3.0, 3.0), radius_m: 0.5)]),
    ],",
    ));
    assert_eq!(s.terrain_at(Vec2::new(1.5, 1.5), 0.0).speed_factor, 0.46);
    assert_eq!(s.terrain_at(Vec2::new(3.0, 3.0), 0.0).speed_factor, 1.5);
    assert_eq!(s.terrain_at(Vec2::new(8.0, 8.0), 0.0), Terrain::OPEN);
}

const CAR: &str = "(name: \"car\", kind: Obstacle,
         parts: [Polygon(vertices_m: [(-1.0, -0.5), (1.0, -0.5), (1.0, 0.5), (-1.0, 0.5)])],
         path: (waypoints_m: [(2.0, 4.0), (12.0, 4.0), (12.0, 6.0)], speed_m_s: 2.0, mode: MODE, rotate: true))";

#[test]
fn ping_pong_and_looped_paths_are_pure_functions_of_time() {
    let pp = scene(&with(&format!(
        "    dynamic: [{}],",
        CAR.replace("MODE", "ping_pong")
    )));
    let d = &pp.dynamic()[0];
    assert_eq!(d.path.period_m(), 24.0);
    assert!((d.at(2.5).position - Vec2::new(7.0, 4.0)).norm() < 1e-12);
    assert!((d.at(5.5).position - Vec2::new(12.0, 5.0)).norm() < 1e-12);
    assert!((d.at(5.5).heading_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // On the way back, 1 m past the corner, heading -x.
    let back = d.at(7.5);
    assert!(
        (back.position - Vec2::new(11.0, 4.0)).norm() < 1e-12,
        "{back:?}"
    );
    assert!((back.heading_rad.abs() - std::f64::consts::PI).abs() < 1e-12);
    assert_eq!(d.at(1.0), d.at(13.0));
    assert_eq!(d.at(-1.0), d.at(11.0));
    assert_eq!(d.at(f64::NAN).position, Vec2::new(2.0, 4.0));
    // The car blocks where it is, not where it was.
    assert!(pp.obstacle_at(Vec2::new(7.0, 4.0), 2.5).is_some());
    assert!(pp.obstacle_at(Vec2::new(7.0, 4.0), 0.0).is_none());
    // Rotated at the corner: 2 m long along y.
    assert!(pp.obstacle_at(Vec2::new(12.0, 5.9), 5.5).is_some());
    assert!(pp.obstacle_at(Vec2::new(12.9, 5.0), 5.5).is_none());

    let lp = scene(&with(&format!(
        "    dynamic: [{}],",
        CAR.replace("MODE", "looped")
    )));
    let d = &lp.dynamic()[0];
    assert!((d.path.period_m() - (12.0 + 104f64.sqrt())).abs() < 1e-12);
    assert!(
        (d.at(6.5).position - Vec2::new(12.0 - 10.0 / 104f64.sqrt(), 6.0 - 2.0 / 104f64.sqrt()))
            .norm()
            < 1e-9
    );
}

#[test]
fn a_car_leaving_the_bounds_is_an_error() {
    let text = with(&format!(
        "    dynamic: [{}],",
        CAR.replace("MODE", "looped")
            .replace("(12.0, 6.0)", "(12.0, 8.8)")
    ));
    let is = issues(&text);
    assert_eq!(is[0].field, "dynamic[0].path.waypoints_m");
    assert_eq!(is[0].problem, Problem::OutsideBounds);
}

#[test]
fn checkpoint_triggers_on_entry_only() {
    let s = scene(&with(
        "    checkpoints: [(name: \"gate\", formation: \"arrow\", region: Polygon(vertices_m: [(5.0, 0.0), (5.2, 0.0), (5.2, 9.0), (5.0, 9.0)]))],",
    ));
    let c = &s.checkpoints()[0];
    assert!(c.crossed(Vec2::new(4.0, 4.0), Vec2::new(5.1, 4.0)));
    // Jumped over the thin gate in one tick: still counts.
    assert!(c.crossed(Vec2::new(4.0, 4.0), Vec2::new(6.0, 4.0)));
    // Already inside, or moving away: no.
    assert!(!c.crossed(Vec2::new(5.1, 4.0), Vec2::new(5.15, 4.0)));
    assert!(!c.crossed(Vec2::new(6.0, 4.0), Vec2::new(7.0, 4.0)));
    assert_eq!(
        s.crossed_checkpoints(Vec2::new(4.0, 4.0), Vec2::new(6.0, 4.0))
            .count(),
        1
    );
}

#[test]
fn grid_rasterises_obstacles_patches_and_cars_and_reuses_buffers() {
    let s = scene(&with(&format!(
        "    obstacles: [(parts: [{SQUARE_2_2}])],
    patches: [(name: \"net\", motion: crawl, parts: [Polygon(vertices_m: [(8.0, 0.0), (10.0, 0.0), (10.0, 2.0), (8.0, 2.0)])])],
    dynamic: [{}],",
        CAR.replace("MODE", "ping_pong")
    )));
    let mut g = SceneGrid::for_bounds(s.bounds(), 0.5).unwrap();
    assert_eq!((g.cols, g.rows), (32, 18));
    s.rasterize_into(&mut g, 0.0);
    let at = |g: &SceneGrid, x: f64, y: f64| {
        g.cell_of(Vec2::new(x, y))
            .map(|(c, r)| g.index(c, r))
            .unwrap()
    };
    let i = at(&g, 3.1, 3.1);
    assert!(g.blocked[i] && g.speed_factor[i] == 0.0 && g.obstacle_distance_m[i] < 0.0);
    let i = at(&g, 9.1, 1.1);
    assert!(!g.blocked[i] && g.speed_factor[i] == 0.33 && g.motion[i] == MotionType::Crawl);
    let i = at(&g, 5.1, 3.1); // centre (5.25, 3.25): 1.25 m right of the square
    assert!((g.obstacle_distance_m[i] - 1.25).abs() < 1e-12);
    assert!(!g.blocked[at(&g, 7.1, 4.1)]);
    let ptr = g.blocked.as_ptr();
    s.rasterize_into(&mut g, 2.5); // the car is now at (7, 4)
    assert!(g.blocked[at(&g, 7.1, 4.1)]);
    assert_eq!(ptr, g.blocked.as_ptr());
    let blocked = g.blocked.iter().filter(|b| **b).count();
    // The square (16 cells) and the car (4 × 2 cells) at 0.5 m.
    assert_eq!(blocked, 16 + 8);
}

#[test]
fn grid_rejects_bad_geometry() {
    assert_eq!(
        SceneGrid::new(0, 3, 1.0, Vec2::zeros()),
        Err(GridError::BadSize)
    );
    assert_eq!(
        SceneGrid::new(3, 3, f64::NAN, Vec2::zeros()),
        Err(GridError::BadGeometry)
    );
    let b = Rect {
        min: [0.0, 0.0],
        max: [1e6, 1e6],
    };
    assert_eq!(SceneGrid::for_bounds(b, 0.01), Err(GridError::BadSize));
}

mod props {
    use super::*;
    use proptest::prelude::*;

    /// A random valid-by-construction scene: one shape per 2 m cell of a 16 × 9 m
    /// world, each inside its cell with a 0.2 m border, so separate obstacles are at
    /// least 0.4 m apart.
    pub(crate) fn grid_scene() -> impl Strategy<Value = SceneFile> {
        proptest::collection::vec((0u8..4, 0.05f64..0.8, 0.05f64..0.8, 0.0f64..1.0), 32).prop_map(
            |cells| {
                let mut f = SceneFile {
                    version: 1,
                    name: String::new(),
                    bounds_m: Rect {
                        min: [0.0, 0.0],
                        max: [16.0, 9.0],
                    },
                    obstacles: vec![],
                    patches: vec![],
                    dynamic: vec![],
                    checkpoints: vec![],
                };
                for (k, (kind, a, b, rot)) in cells.into_iter().enumerate() {
                    let (cx, cy) = (1.0 + 2.0 * (k % 8) as f64, 1.0 + 2.0 * (k / 8) as f64);
                    if cy + 1.0 > 9.0 {
                        continue;
                    }
                    let part = match kind {
                        0 => continue,
                        1 => PartDef::Circle {
                            centre_m: [cx, cy],
                            radius_m: a,
                        },
                        2 => {
                            // A rotated rectangle with half sides a, b.
                            let (c, s) = ((rot * 3.0).cos(), (rot * 3.0).sin());
                            let (a, b) = (a * 0.68, b * 0.68);
                            let pts = [(-a, -b), (a, -b), (a, b), (-a, b)]
                                .map(|(x, y)| [cx + c * x - s * y, cy + s * x + c * y]);
                            PartDef::Polygon {
                                vertices_m: pts.to_vec(),
                            }
                        }
                        _ => {
                            // A triangle.
                            PartDef::Polygon {
                                vertices_m: vec![
                                    [cx - a, cy - b],
                                    [cx + a, cy - b * rot],
                                    [cx, cy + b],
                                ],
                            }
                        }
                    };
                    f.obstacles.push(ObstacleDef {
                        name: format!("o{k}"),
                        parts: vec![part],
                    });
                }
                f
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

        /// Arbitrary text never panics the loader, and errors point inside it.
        #[test]
        fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
            if let Err(SceneError::Invalid { issues, .. }) = Scene::from_str(&text, Path::new("p"), 0.15) {
                prop_assert!(!issues.is_empty());
                for i in issues {
                    prop_assert!(i.line <= text.lines().count() + 1);
                }
            }
        }

        /// A shipped scene with a slice cut out or repeated: an error with a place,
        /// or still a valid scene; never a panic.
        #[test]
        fn mutated_shipped_scene_never_panics(a in 0usize..4000, len in 0usize..60, dup in proptest::bool::ANY) {
            let t = include_str!("../../../../config/scenes/obstacle_course.ron");
            let a = a.min(t.len());
            let b = (a + len).min(t.len());
            if !t.is_char_boundary(a) || !t.is_char_boundary(b) {
                return Ok(());
            }
            let m = if dup { format!("{}{}", &t[..b], &t[a..]) } else { format!("{}{}", &t[..a], &t[b..]) };
            match Scene::from_str(&m, Path::new("m"), 0.15) {
                Ok(s) => prop_assert!(s.sanity_check().is_ok()),
                Err(SceneError::Invalid { issues, .. }) => prop_assert!(!issues.is_empty()),
                Err(e) => prop_assert!(false, "unexpected error kind {e}"),
            }
        }

        /// Random numbers in every slot of a scene never panic validation; valid
        /// results pass the invariant checker.
        #[test]
        fn random_scenes_never_panic(
            pts in proptest::collection::vec((-20.0f64..20.0, -20.0f64..20.0), 0..8),
            r in -1.0f64..3.0, speed in -1.0f64..3.0, len in proptest::option::of(-1.0f64..3.0),
            motion in 0usize..7, rotate in proptest::bool::ANY, agent_r in -0.1f64..0.5,
        ) {
            let v: Vec<PointM> = pts.iter().map(|&(x, y)| [x, y]).collect();
            let m = MotionType::ALL[motion];
            let f = SceneFile {
                version: 1,
                name: "r".into(),
                bounds_m: Rect { min: [-10.0, -10.0], max: [10.0, 10.0] },
                obstacles: vec![
                    ObstacleDef { name: "p".into(), parts: vec![PartDef::Polygon { vertices_m: v.clone() }] },
                    ObstacleDef { name: "c".into(), parts: vec![PartDef::Circle { centre_m: v.first().copied().unwrap_or([0.0, 0.0]), radius_m: r }] },
                ],
                patches: vec![PatchDef { name: "q".into(), motion: m, speed_factor: Some(speed), motion_length_m: len, parts: vec![PartDef::Polygon { vertices_m: v.clone() }] }],
                dynamic: vec![DynamicDef {
                    name: "d".into(),
                    kind: DynamicKindDef::Patch { motion: m, speed_factor: None, motion_length_m: len },
                    parts: vec![PartDef::Circle { centre_m: [0.0, 0.0], radius_m: r }],
                    path: PathDef { waypoints_m: v.clone(), speed_m_s: speed, mode: PathMode::PingPong, start_s: 0.0, rotate },
                }],
                checkpoints: vec![CheckpointDef { name: "k".into(), region: PartDef::Polygon { vertices_m: v }, formation: "f".into() }],
            };
            let text = ron::to_string(&f).unwrap();
            if let Ok(s) = Scene::from_str(&text, Path::new("r"), agent_r) {
                prop_assert!(s.sanity_check().is_ok());
                let _ = s.dynamic()[0].at(speed * 7.0);
                let mut g = SceneGrid::for_bounds(s.bounds(), 1.0).unwrap();
                s.rasterize_into(&mut g, 1.0);
            }
        }

        /// Projection never leaves a point inside an obstacle, and keeps the margin
        /// when the scene allows it (gaps of at least one agent diameter, margin up to
        /// the agent radius).
        #[test]
        fn projected_points_are_never_inside(f in grid_scene(), x in 0.0f64..16.0, y in 0.0f64..9.0, margin in 0.0f64..0.15) {
            let s = Scene::from_file(&f, 0.15).expect("grid scenes are valid");
            let q = s.project_out(Vec2::new(x, y), margin, 0.0);
            prop_assert!(s.obstacle_at(q, 0.0).is_none(), "{q:?} inside");
            prop_assert!(s.signed_distance(q, 0.0) >= margin - 1e-9);
            // The nearest free point: never farther than the depth plus the margin.
            let d = s.signed_distance(Vec2::new(x, y), 0.0);
            if d < margin {
                prop_assert!((q - Vec2::new(x, y)).norm() <= margin - d + 1e-9);
            }
        }
    }
}

/// The index's answers are the full scan's: signed distance and terrain at random
/// points (inside, at the edges and outside the bounds) of every shipped scene, at
/// several times (moving obstacles and patches), and of a scene with overlapping
/// patches (the last one wins) and a wall larger than the index's reach.
#[test]
fn indexed_queries_equal_the_full_scan() {
    use super::index::INDEX_REACH_M;
    use crate::rng::SplitMix64;
    let overlapping = with(&format!(
        "    obstacles: [(name: \"wall\", parts: [Polygon(vertices_m: [(0.0, 1.0), (16.0, 1.0), (16.0, 1.2), (0.0, 1.2)])]),\n\
         (name: \"a\", parts: [{SQUARE_2_2}, Circle(centre_m: (9.0, 7.0), radius_m: 0.3)])],\n\
    patches: [(name: \"mud\", motion: crawl, speed_factor: Some(0.5), parts: [Polygon(vertices_m: [(5.0, 5.0), (9.0, 5.0), (9.0, 8.0), (5.0, 8.0)])]),\n\
         (name: \"ice\", motion: swim, speed_factor: Some(0.8), parts: [Circle(centre_m: (8.0, 6.0), radius_m: 1.5)])],"
    ));
    let mut scenes: Vec<(String, Scene)> = SCENES
        .iter()
        .map(|(n, t)| {
            let s = Scene::from_str(t, Path::new(n), DEFAULT_AGENT_RADIUS_M).unwrap();
            (n.to_string(), s)
        })
        .collect();
    scenes.push(("overlapping".into(), scene(&overlapping)));
    let mut rng = SplitMix64::new(7);
    for (name, s) in &scenes {
        let b = s.bounds();
        for k in 0..6000 {
            let t = (k % 8) as f64 * 1.7;
            let p = if k < 4000 {
                Vec2::new(
                    rng.uniform(b.min[0] - 2.0, b.max[0] + 2.0),
                    rng.uniform(b.min[1] - 2.0, b.max[1] + 2.0),
                )
            } else {
                // On the index's cell lines and corners (its origin is the bounds'
                // corner less the reach, its cells 0.5 m in these scenes).
                let line = |lo: f64, hi: f64, rng: &mut SplitMix64| {
                    let n = ((hi - lo) / 0.5).floor();
                    lo - INDEX_REACH_M + 0.5 * (rng.uniform(0.0, n + 4.0)).floor()
                };
                let (x, y) = (
                    line(b.min[0], b.max[0], &mut rng),
                    line(b.min[1], b.max[1], &mut rng),
                );
                match k % 3 {
                    0 => Vec2::new(x, y),
                    1 => Vec2::new(x, rng.uniform(b.min[1], b.max[1])),
                    _ => Vec2::new(rng.uniform(b.min[0], b.max[0]), y),
                }
            };
            let mut want_d = f64::INFINITY;
            s.for_each_obstacle_part(t, |_, _, part, pl| {
                want_d = want_d.min(part.signed_distance(pl.to_local(p)));
            });
            assert_eq!(s.signed_distance(p, t), want_d, "{name} at {p} t {t}");
            // The nearest part: the first in file order at the least signed distance.
            let mut want_hit: Option<(ObstacleId, usize, Vec2)> = None;
            let mut hit_d = f64::INFINITY;
            s.for_each_obstacle_part(t, |id, j, part, pl| {
                let b = part.boundary_point(pl.to_local(p));
                if want_hit.is_none() || b.signed_distance_m < hit_d {
                    want_hit = Some((id, j, pl.to_world(b.point)));
                    hit_d = b.signed_distance_m;
                }
            });
            let got = s
                .nearest_obstacle(p, t)
                .map(|h| (h.id, h.part, h.boundary.point));
            assert_eq!(got, want_hit, "{name} at {p} t {t}");
            for margin in [0.0, 0.15, 0.3, INDEX_REACH_M, 2.5] {
                let want = want_d < margin;
                assert_eq!(s.closer_than(p, margin, t), want, "{name} at {p} t {t}");
            }
            let mut want_t = Terrain::OPEN;
            for patch in s.patches() {
                if patch.parts.iter().any(|part| part.contains(p)) {
                    want_t = patch.terrain;
                }
            }
            for d in s.dynamic() {
                if let DynamicKind::Patch(terrain) = d.kind {
                    if d.parts
                        .iter()
                        .any(|q| q.contains(d.placement_at(t).to_local(p)))
                    {
                        want_t = terrain;
                    }
                }
            }
            assert_eq!(s.terrain_at(p, t), want_t, "{name} at {p} t {t}");
        }
    }
}

/// A point inside a patch far from its edges is answered without testing a part:
/// its cell is covered by the patch, and only the parts drawn over it remain.
#[test]
fn cells_inside_a_patch_need_no_test() {
    let s = scene(&with(
        "    patches: [(name: \"mud\", motion: crawl, speed_factor: Some(0.5), parts: [Polygon(vertices_m: [(5.0, 5.0), (9.0, 5.0), (9.0, 8.0), (5.0, 8.0)])]),\n\
         (name: \"ice\", motion: swim, speed_factor: Some(0.8), parts: [Circle(centre_m: (8.0, 6.0), radius_m: 1.5)])],",
    ));
    // Inside the mud, clear of the ice's box: covered, nothing left to test.
    assert_eq!(
        s.index.patches_at(Vec2::new(5.7, 7.2)),
        Some((true, &[(0, 0)][..]))
    );
    // Inside both: the ice, drawn later, covers the cell; the mud is dropped.
    assert_eq!(
        s.index.patches_at(Vec2::new(8.1, 6.1)),
        Some((true, &[(1, 0)][..]))
    );
    // On the mud's edge: both parts' boxes meet the cell, neither covers it.
    let (covers, near) = s.index.patches_at(Vec2::new(5.0, 6.0)).unwrap();
    assert!(!covers);
    assert_eq!(near, &[(0, 0)]);
    assert_eq!(s.terrain_at(Vec2::new(5.7, 7.2), 0.0).speed_factor, 0.5);
    assert_eq!(s.terrain_at(Vec2::new(8.1, 6.1), 0.0).speed_factor, 0.8);
}

/// A scene placed once at a time answers as the scene asked at that time, moving
/// obstacles and patches included.
#[test]
fn a_scene_at_a_time_answers_as_the_scene_at_that_time() {
    use crate::rng::SplitMix64;
    let mut rng = SplitMix64::new(11);
    let mut placements = Vec::new();
    for (name, text) in SCENES {
        let s = Scene::from_str(text, Path::new(name), DEFAULT_AGENT_RADIUS_M).unwrap();
        let b = s.bounds();
        let mut point = || {
            Vec2::new(
                rng.uniform(b.min[0] - 1.0, b.max[0] + 1.0),
                rng.uniform(b.min[1] - 1.0, b.max[1] + 1.0),
            )
        };
        for k in 0..10 {
            let t = k as f64 * 2.3;
            let at = s.at(t, &mut placements);
            for _ in 0..300 {
                let (p, q) = (point(), point());
                assert_eq!(at.terrain_at(p), s.terrain_at(p, t), "{name} {p} {t}");
                assert_eq!(at.closer_than(p, 0.15), s.closer_than(p, 0.15, t));
                assert_eq!(at.visible(p, q), s.visible(p, q, t), "{name} {p}–{q} {t}");
                assert_eq!(at.project_out(p, 0.15), s.project_out(p, 0.15, t));
            }
        }
    }
}
