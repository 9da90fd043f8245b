//! The shipped scenes in `config/scenes/` load and validate, and each shows what its
//! comment says.

use crowdtouch::crowd::environment::{Scene, SceneGrid, DEFAULT_AGENT_RADIUS_M};
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::MotionType;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("config/scenes")
}

fn load(name: &str) -> Scene {
    let p = scenes_dir().join(name);
    Scene::load(&p, DEFAULT_AGENT_RADIUS_M).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_shipped_scene_loads_and_validates() {
    let agent_radius = crowdtouch::config::Config::embedded_default()
        .crowd
        .agent_radius_m;
    let mut names = Vec::new();
    for e in std::fs::read_dir(scenes_dir()).unwrap() {
        let p = e.unwrap().path();
        assert_eq!(
            p.extension().and_then(|e| e.to_str()),
            Some("ron"),
            "{}",
            p.display()
        );
        let s = Scene::load(&p, agent_radius).unwrap_or_else(|e| panic!("{e}"));
        s.sanity_check().unwrap();
        // Every scene leaves the default starting formation free.
        let start = crowdtouch::config::Config::embedded_default()
            .crowd
            .formation;
        for t in [0.0, 1.7, 5.0, 13.3] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
                let q = Vec2::new(
                    start.min[0] + x * start.width(),
                    start.min[1] + y * start.height(),
                );
                assert!(
                    s.obstacle_at(q, t).is_none(),
                    "{}: {q:?} blocked at {t}",
                    p.display()
                );
            }
        }
        let mut g = SceneGrid::for_bounds(s.bounds(), 0.1).unwrap();
        s.rasterize_into(&mut g, 0.0);
        names.push(p.file_name().unwrap().to_string_lossy().into_owned());
    }
    names.sort();
    assert_eq!(
        names,
        [
            "corridor.ron",
            "four_blocks.ron",
            "multiple_paths.ron",
            "obstacle_course.ron",
            "single_block.ron",
            "street.ron",
            "woodland.ron"
        ]
    );
}

#[test]
fn corridor_blocks_all_but_its_corridor_and_switches_formation() {
    let s = load("corridor.ron");
    assert!(!s.visible(Vec2::new(10.0, 1.0), Vec2::new(15.5, 1.0), 0.0));
    assert!(s.visible(Vec2::new(10.0, 4.5), Vec2::new(15.5, 4.5), 0.0));
    let formations: Vec<&str> = s
        .crossed_checkpoints(Vec2::new(8.0, 4.5), Vec2::new(16.0, 4.5))
        .map(|c| c.formation.as_str())
        .collect();
    assert_eq!(formations, ["arrow", "square"]);
}

#[test]
fn multiple_paths_centre_is_short_and_sides_are_slow() {
    let s = load("multiple_paths.ron");
    let mut g = SceneGrid::for_bounds(s.bounds(), 0.1).unwrap();
    s.rasterize_into(&mut g, 0.0);
    let row_speed = |y: f64| -> f64 {
        // Mean speed factor along the route x = 11..15 at height y.
        let r = ((y - g.origin.y) / g.cell_m) as usize;
        let cols = (110..150).map(|c| g.speed_factor[g.index(c, r)]);
        cols.sum::<f64>() / 40.0
    };
    assert!(
        (row_speed(4.5) - 1.0).abs() < 1e-12,
        "centre is open ground"
    );
    assert!(row_speed(0.9) < 0.6, "north path is slower (swim)");
    assert!(row_speed(8.1) < 0.6, "south path is slower (duck)");
    assert_eq!(
        s.terrain_at(Vec2::new(13.0, 8.0), 0.0).motion,
        MotionType::Duck
    );
}

#[test]
fn street_cars_move_and_the_crossing_is_sometimes_clear() {
    let s = load("street.ron");
    assert_eq!(s.dynamic().len(), 4);
    let crossing = (Vec2::new(8.0, 6.9), Vec2::new(8.0, 8.99));
    let clear: Vec<bool> = (0..200)
        .map(|k| s.visible(crossing.0, crossing.1, k as f64 * 0.1))
        .collect();
    assert!(clear.iter().any(|c| *c), "the crossing is never clear");
    assert!(
        clear.iter().any(|c| !*c),
        "no car ever crosses the crossing"
    );
}

#[test]
fn obstacle_course_stations_have_their_motions() {
    let s = load("obstacle_course.ron");
    let at = |x, y| s.terrain_at(Vec2::new(x, y), 0.0);
    assert_eq!(at(2.0, 5.0).motion, MotionType::Swim);
    assert_eq!(at(8.0, 1.3).motion, MotionType::Jump);
    assert_eq!(at(8.0, 2.6).motion, MotionType::ClimbUp);
    assert_eq!(at(8.0, 2.2).motion, MotionType::ClimbDown);
    assert_eq!(at(13.0, 4.0).speed_factor, 0.33);
    assert!(s.obstacle_at(Vec2::new(14.8, 1.2), 0.0).is_some());
}

#[test]
fn woodland_has_dense_trees_with_duck_canopies() {
    let s = load("woodland.ron");
    assert!(s.obstacles().len() >= 30, "{}", s.obstacles().len());
    assert!(s
        .patches()
        .iter()
        .all(|p| p.terrain.motion == MotionType::Duck));
    // Trunks one agent diameter apart at least: a 0.3 m disc fits between any two.
    let mut g = SceneGrid::for_bounds(s.bounds(), 0.25).unwrap();
    s.rasterize_into(&mut g, 0.0);
    let blocked = g.blocked.iter().filter(|b| **b).count();
    assert!(blocked > 20 && blocked < g.len() / 5, "{blocked}");
}
