//! The engine's state machines without a daemon: commands and their refusals,
//! assignment results that arrive late, pause, formation switches on request.

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
