//! The engine's state machines without a daemon: commands and their refusals,
//! assignment results that arrive late, pause, formation switches on request, the
//! motion types in a scene.

use super::*;
use crate::config::{Config, MAX_AGENTS};
use crate::vocab::{Command, Event, Micros};

fn engine(agents: u32) -> Engine {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = agents;
    Engine::new(&cfg, None, false)
}

#[test]
fn refused_commands_say_why_in_the_words_clients_read() {
    let mut e = engine(20);
    let err = e
        .command(&Command::SetAgentCount { count: 0 }, Micros(0))
        .unwrap_err();
    assert_eq!(
        err,
        CommandError::AgentCount {
            count: 0,
            max: MAX_AGENTS
        }
    );
    assert_eq!(
        err.to_string(),
        format!("agent count 0 is out of range 1..={MAX_AGENTS}")
    );
    let long = "x".repeat(80);
    let err = e
        .command(
            &Command::SetFormation {
                formation: long.clone(),
                method: None,
                duration: None,
            },
            Micros(0),
        )
        .unwrap_err();
    assert!(matches!(&err, CommandError::UnknownFormation { name, .. } if *name == long));
    assert_eq!(
        err.to_string(),
        format!(
            "no formation is called `{}…`; the config defines start, square, arrow, column, line, wedge, diamond, circle, ring, two_groups, letter_a, heart",
            "x".repeat(64)
        )
    );
    // A name with control characters is quoted escaped (the message is logged).
    let err = e
        .command(
            &Command::SetFormation {
                formation: "ring\u{1b}[2J\u{9b}\u{202e}".into(),
                method: None,
                duration: None,
            },
            Micros(0),
        )
        .unwrap_err();
    assert!(
        err.to_string()
            .starts_with("no formation is called `ring\\u{1b}[2J\\u{9b}\\u{202e}`"),
        "{err}"
    );
    // A refused command changes nothing.
    assert_eq!(e.agent_count(), 20);
    assert_eq!(e.formation(), "start");
}

#[test]
fn an_assignment_solved_before_a_resize_is_stale() {
    let mut e = engine(20);
    e.tick(Micros(0));
    let generation = e.generation();
    let seq = e.seq();
    let identity: Vec<u32> = (0..20).collect();
    assert!(e.apply_assignment(generation, seq, &identity));
    assert_eq!(e.counters().assignments, 1);
    e.command(&Command::SetAgentCount { count: 30 }, Micros(1))
        .unwrap();
    assert_ne!(e.generation(), generation);
    assert!(!e.apply_assignment(generation, seq, &identity));
    assert_eq!(e.counters().stale_assignments, 1);
    assert_eq!(e.goal_of().len(), 30);
    // An older tick's answer than the one in use is stale too.
    let g = e.generation();
    e.tick(Micros(10_000));
    let fresh: Vec<u32> = (0..30).collect();
    assert!(e.apply_assignment(g, e.seq(), &fresh));
    assert!(!e.apply_assignment(g, e.seq() - 1, &fresh));
}

#[test]
fn pause_and_resume_say_so_once_and_hold_the_agents() {
    let mut e = engine(20);
    e.tick(Micros(0));
    e.command(&Command::Pause, Micros(1)).unwrap();
    e.command(&Command::Pause, Micros(2)).unwrap();
    let out = e.tick(Micros(10_000));
    let paused: Vec<_> = out
        .events
        .iter()
        .filter(|ev| matches!(ev, Event::Paused { .. }))
        .collect();
    assert_eq!(paused.len(), 1, "{:?}", out.events);
    assert!(out.snapshot.paused);
    e.clear_events();
    e.command(&Command::Resume, Micros(20_000)).unwrap();
    let out = e.tick(Micros(30_000));
    assert!(!out.snapshot.paused);
    assert!(matches!(out.events, [Event::Paused { paused: false, .. }]));
}

#[test]
fn a_formation_asked_for_is_switched_to_and_announced() {
    let mut e = engine(40);
    e.tick(Micros(0));
    e.clear_events();
    mesh_switch(&mut e, "arrow", Micros(1)).unwrap();
    assert_eq!(e.formation(), "arrow");
    let out = e.tick(Micros(10_000));
    assert!(
        out.events.iter().any(
            |ev| matches!(ev, Event::Formation { name, checkpoint: None, .. } if name == "arrow")
        ),
        "{:?}",
        out.events
    );
    assert_eq!(out.snapshot.goals.len(), 40);
    // Asking for the formation the crowd is in changes nothing.
    let topology = e.mesh_view().topology;
    mesh_switch(&mut e, "arrow", Micros(20_000)).unwrap();
    assert_eq!(e.mesh_view().topology, topology);
}

/// A formation by the mesh switch (mesh-formation-control section 7.3).
fn mesh_switch(e: &mut Engine, name: &str, now: Micros) -> Result<(), CommandError> {
    e.set_formation_by(name, Some(crate::vocab::FormationMethod::Mesh), None, now)
}

/// The config's transform defaults are the crowd-level defaults.
#[test]
fn the_configured_transform_defaults_are_the_models() {
    use crate::crowd::transform::{ApParams, MoveParams};
    let cfg = Config::embedded_default();
    let radius = MoveParams::default().radius_m;
    assert_eq!(
        super::params::move_params(&cfg, radius),
        MoveParams::default()
    );
    assert_eq!(super::params::ap_params(&cfg), Some(ApParams::default()));
}

/// A scene with a static patch (mud) and an obstacle east of the start formation,
/// and `dynamic` (its moving things).
fn mud_scene(dynamic: &str) -> String {
    format!(
        r#"(
    version: 1,
    name: "mud",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    obstacles: [(name: "rock", parts: [Circle(centre_m: (11.0, 4.5), radius_m: 0.4)])],
    patches: [(name: "mud", motion: crawl, speed_factor: Some(0.5),
               parts: [Polygon(vertices_m: [(9.5, 2.0), (13.0, 2.0), (13.0, 7.0), (9.5, 7.0)])])],
    dynamic: [{dynamic}],
)"#
    )
}

/// A raft (a moving patch) crossing the scene back and forth.
const RAFT: &str = r#"(name: "raft", kind: Patch(motion: swim, speed_factor: Some(0.8)),
    parts: [Polygon(vertices_m: [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)])],
    path: (waypoints_m: [(2.0, 4.5), (14.0, 4.5)], speed_m_s: 3.0, mode: ping_pong))"#;

/// Every agent's motion type is the terrain under it at the scene time, after
/// every tick: dragged through the mud (the terrain kept from the step, agents
/// pushed off the rock read again), paused while the raft passes under standing
/// agents (moving patches: nothing kept from the tick before), after a hard
/// reset (teleported), and in a scene without moving patches.
#[test]
fn motions_are_the_terrain_under_every_agent_in_every_mode() {
    use crate::crowd::environment::Scene;
    use crate::vocab::{Contact, ContactFlags, ContactId, MotionType, TouchFrame};
    use std::path::Path;
    use std::sync::Arc;
    let raft = Scene::from_str(&mud_scene(RAFT), Path::new("raft.ron"), 0.15).unwrap();
    let still = Scene::from_str(&mud_scene(""), Path::new("still.ron"), 0.15).unwrap();
    assert!(raft.terrain_moves() && !still.terrain_moves());
    for scene in [raft, still] {
        let scene = Arc::new(scene);
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = 80;
        cfg.set_loaded_scene(Some(Arc::clone(&scene)));
        let mut e = Engine::new(&cfg, None, false);
        let check = |e: &Engine, what: &str| {
            let t = e.scene_time_s();
            let want: Vec<MotionType> = e
                .agent_positions()
                .iter()
                .map(|&p| scene.terrain_at(p, t).motion)
                .collect();
            let moving = scene.terrain_moves();
            assert_eq!(
                e.motions(),
                want,
                "{what} at t {t}, moving patches {moving}"
            );
        };
        let seen = |e: &Engine, m: MotionType| e.motions().iter().filter(|&&x| x == m).count();
        let t = std::cell::Cell::new(0u64);
        let tick = |e: &mut Engine, frame: Option<(f32, ContactFlags)>| {
            t.set(t.get() + 8_333);
            let t = t.get();
            if let Some((x, flags)) = frame {
                let mut f = TouchFrame::new(Micros(t));
                f.push(Contact {
                    id: ContactId(1),
                    x,
                    y: 0.5,
                    flags,
                    ..Contact::default()
                })
                .unwrap();
                e.push_frame(&f);
            }
            drop(e.tick(Micros(t)));
            e.clear_events();
        };
        // One finger on the crowd (its centre, (8, 4.5) m) drags it 3 m east.
        let (mut crawled, mut swam) = (0, 0);
        for k in 0..=300u32 {
            let x = 0.5 + 0.1875 * (k.min(240) as f32 / 240.0);
            let flags = match k {
                0 => ContactFlags::DOWN,
                300 => ContactFlags::UP,
                _ => ContactFlags::NONE,
            };
            tick(&mut e, Some((x, flags)));
            check(&e, "dragged");
            crawled = crawled.max(seen(&e, MotionType::Crawl));
            swam = swam.max(seen(&e, MotionType::Swim));
        }
        assert!(crawled > 10, "{crawled} in the mud");
        e.command(&Command::Pause, Micros(t.get())).unwrap();
        let before = e.agent_positions().to_vec();
        for _ in 0..300 {
            tick(&mut e, None);
            check(&e, "paused");
            swam = swam.max(seen(&e, MotionType::Swim));
        }
        assert_eq!(e.agent_positions(), before, "paused agents stand");
        assert_eq!(swam > 0, scene.terrain_moves(), "{swam} on the raft");
        e.command(&Command::Resume, Micros(t.get())).unwrap();
        e.command(&Command::Reset { hard: true }, Micros(t.get()))
            .unwrap();
        for _ in 0..30 {
            tick(&mut e, None);
            check(&e, "reset");
        }
    }
}
