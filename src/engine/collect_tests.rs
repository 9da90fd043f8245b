//! `library collect` in the engine: motions shown in order, gestures recorded to
//! the file with who drew them, taps refused, undo and skip, the end.

use super::*;
use crate::config::Config;
use crate::geom::Vec2;
use crate::gesture::library::{read_library, shipped, Library, MotionClass};
use crate::gesture::synth::{generate, to_frames, GestureStyle};
use crate::vocab::{CollectState, Command, Event, Micros, PlanOrigin};

const GLASS_MM: (f64, f64) = (1210.0, 680.0);
const TICK_US: u64 = 1_000_000 / 60;

struct Session {
    e: Engine,
    now: u64,
    events: Vec<Event>,
    demos: Vec<(u32, String, usize)>,
    path: std::path::PathBuf,
    _dir: tempfile::TempDir,
    start_gestures: usize,
}

fn first_motion(lib: &Library, class: MotionClass) -> u32 {
    let id = lib.class_id(class.as_str()).unwrap();
    lib.motions.iter().position(|m| m.class == id).unwrap() as u32
}

fn session(classes: &[MotionClass]) -> Session {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 30;
    cfg.pipeline.tick_hz = 60.0;
    let mut e = Engine::new(&cfg, Some(GLASS_MM), true);
    let library = shipped().unwrap();
    let start_gestures = library.gestures.len();
    let motions = classes.iter().map(|&c| first_motion(&library, c)).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("collected.ctlib");
    e.start_collecting(CollectPlan {
        library,
        path: path.clone(),
        participant: "p07".into(),
        motions,
        devices: vec!["test table".into()],
        seed: 3,
        replay_after: Micros(2_000_000),
    })
    .unwrap();
    let mut s = Session {
        e,
        now: 1_000_000,
        events: vec![],
        demos: vec![],
        path,
        _dir: dir,
        start_gestures,
    };
    s.run_for(0.5);
    s
}

impl Session {
    fn tick(&mut self) {
        let o = self.e.tick(Micros(self.now));
        self.events.extend(o.events.iter().cloned());
        if let Some(p) = &o.plan {
            if let PlanOrigin::Demo { motion } = p.origin {
                self.demos.push((motion, p.class.clone(), p.agents()));
            }
        }
        self.e.clear_events();
    }

    fn run_for(&mut self, s: f64) {
        let end = self.now + (s * 1e6) as u64;
        while self.now < end {
            self.now += TICK_US;
            self.tick();
        }
    }

    /// Draws a generated gesture of `class` left of the crowd, then waits for it
    /// to end.
    fn draw(&mut self, class: MotionClass, seed: u64) {
        let style = GestureStyle {
            fingers: vec![2],
            duration_s: 0.8,
            size_mm: 150.0,
            placement: Vec2::new(0.17, 0.5),
            orientation_rad: 0.0,
            jitter_mm: 0.3,
            device_mm: GLASS_MM,
            rate_hz: 120.0,
            stagger_ms: 20.0,
            early_lifts: 0,
            bow: 0.0,
            spacing_mm: 20.0,
            clockwise: false,
        };
        let frames = to_frames(&generate(class, &style, seed), GLASS_MM, Micros(self.now));
        for f in &frames {
            while self.now + TICK_US <= f.t.0 {
                self.now += TICK_US;
                self.tick();
            }
            self.e.push_frame(f);
        }
        self.run_for(1.0);
    }

    fn tap(&mut self) {
        use crate::vocab::{Contact, ContactFlags, ContactId, TouchFrame};
        let contact = |flags| Contact {
            id: ContactId(9),
            x: 0.1,
            y: 0.5,
            pressure: None,
            major_mm: None,
            minor_mm: None,
            flags,
        };
        let mut f = TouchFrame::new(Micros(self.now));
        f.push(contact(ContactFlags::DOWN)).unwrap();
        self.e.push_frame(&f);
        self.now += 40_000;
        let mut up = TouchFrame::new(Micros(self.now));
        up.push(contact(ContactFlags::UP)).unwrap();
        self.e.push_frame(&up);
        self.run_for(1.0);
    }

    fn states(&self) -> Vec<(CollectState, u32)> {
        self.events
            .iter()
            .filter_map(|e| match e {
                Event::Collect(c) => Some((c.state, c.item)),
                _ => None,
            })
            .collect()
    }

    fn saved(&self) -> Library {
        read_library(&std::fs::read(&self.path).unwrap(), "collected").unwrap()
    }
}

#[test]
fn each_motion_is_shown_and_the_gesture_drawn_for_it_is_saved_with_who_drew_it() {
    use CollectState::*;
    let classes = [
        MotionClass::Translate,
        MotionClass::Contract,
        MotionClass::Twist,
    ];
    let mut s = session(&classes);
    assert_eq!(s.states(), vec![(Showing, 0)]);
    let lib = shipped().unwrap();
    let m0 = first_motion(&lib, MotionClass::Translate);
    assert_eq!(s.demos, vec![(m0, "translate".to_string(), 30)]);
    for (k, &c) in classes.iter().enumerate() {
        s.draw(c, 40 + k as u64);
    }
    assert_eq!(
        s.states(),
        vec![
            (Showing, 0),
            (Recorded, 0),
            (Showing, 1),
            (Recorded, 1),
            (Showing, 2),
            (Recorded, 2),
            (Finished, 3)
        ]
    );
    assert!(s.e.collect_finished());
    let saved = s.saved();
    assert_eq!(saved.gestures.len(), s.start_gestures + 3);
    for (g, &c) in saved.gestures[s.start_gestures..].iter().zip(&classes) {
        assert_eq!(saved.class_name(g.class), c.as_str());
        assert_eq!(g.motion, first_motion(&lib, c));
        assert_eq!(g.participant, "p07");
        assert_eq!(g.device, "test table");
        assert!(g.scale_mm.is_some_and(|mm| mm > 50.0), "{:?}", g.scale_mm);
        assert_eq!(g.gesture.fingers.len(), 2);
    }
    // No gesture was recognised or played while collecting: every gesture event
    // says it was collected.
    let reasons: Vec<_> = s
        .events
        .iter()
        .filter_map(|e| match e {
            Event::GestureEnd {
                rejected,
                recognition,
                ..
            } => {
                assert!(recognition.is_none());
                rejected.clone()
            }
            _ => None,
        })
        .collect();
    assert_eq!(reasons, vec!["collecting"; 3]);
}

#[test]
fn a_tap_is_refused_and_undo_and_skip_move_through_the_items() {
    use CollectState::*;
    let classes = [MotionClass::Translate, MotionClass::Expand];
    let mut s = session(&classes);
    s.tap();
    assert_eq!(s.states(), vec![(Showing, 0), (Refused, 0)]);
    assert!(!s.path.exists(), "nothing was saved for a tap");
    s.draw(MotionClass::Translate, 1);
    assert_eq!(s.saved().gestures.len(), s.start_gestures + 1);
    s.e.command(&Command::CollectUndo, Micros(s.now)).unwrap();
    s.run_for(0.2);
    assert_eq!(s.saved().gestures.len(), s.start_gestures);
    s.e.command(&Command::CollectSkip, Micros(s.now)).unwrap();
    s.run_for(0.2);
    let err =
        s.e.command(&Command::CollectUndo, Micros(s.now))
            .unwrap_err();
    assert_eq!(err.to_string(), "nothing recorded to undo");
    s.draw(MotionClass::Expand, 2);
    assert_eq!(
        s.states(),
        vec![
            (Showing, 0),
            (Refused, 0),
            (Recorded, 0),
            (Showing, 1),
            (Undone, 0),
            (Showing, 0),
            (Skipped, 0),
            (Showing, 1),
            (Recorded, 1),
            (Finished, 2)
        ]
    );
    let saved = s.saved();
    assert_eq!(saved.gestures.len(), s.start_gestures + 1);
    assert_eq!(
        saved.class_name(saved.gestures.last().unwrap().class),
        "expand"
    );
    let err =
        s.e.command(&Command::CollectSkip, Micros(s.now))
            .unwrap_err();
    assert_eq!(err.to_string(), "the session is finished: nothing to skip");
}

#[test]
fn a_demonstration_plays_again_while_its_item_waits_and_status_says_where_the_session_is() {
    let mut s = session(&[MotionClass::Twist]);
    // The twist plays (a few seconds), ends, and plays again 2 s later.
    s.run_for(20.0);
    assert!(s.demos.len() >= 2, "{:?}", s.demos);
    assert!(s.demos.iter().all(|d| d.1 == "twist"));
    s.events.clear();
    let shown = s.demos.len();
    s.e.command(&Command::CollectStatus, Micros(s.now)).unwrap();
    s.tick();
    assert_eq!(s.states(), vec![(CollectState::Showing, 0)]);
    // The motion shown goes out again for a client that just connected.
    assert_eq!(s.demos.len(), shown + 1);
}

#[test]
fn collect_commands_without_a_session_are_refused() {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 10;
    let mut e = Engine::new(&cfg, None, true);
    let err = e.command(&Command::CollectSkip, Micros(0)).unwrap_err();
    assert!(
        err.to_string().starts_with("no collection session runs"),
        "{err}"
    );
}

#[test]
fn a_session_without_motions_or_participant_does_not_start() {
    let mut cfg = Config::embedded_default();
    cfg.crowd.agents = 10;
    let mut e = Engine::new(&cfg, None, true);
    let plan = |motions: Vec<u32>, participant: &str| CollectPlan {
        library: shipped().unwrap(),
        path: "/nonexistent/x".into(),
        participant: participant.into(),
        motions,
        devices: vec![],
        seed: 0,
        replay_after: Micros(1),
    };
    assert!(e
        .start_collecting(plan(vec![], "p"))
        .unwrap_err()
        .contains("no motions"));
    assert!(e
        .start_collecting(plan(vec![0], ""))
        .unwrap_err()
        .contains("participant"));
    let err = e.start_collecting(plan(vec![99_999], "p")).unwrap_err();
    assert!(err.contains("there is no motion 99999"), "{err}");
}

#[test]
fn a_save_that_fails_loses_nothing_and_the_item_still_waits() {
    let mut s = session(&[MotionClass::Translate]);
    // The library's directory goes away: the save fails, the gesture stays out.
    let dir = s.path.parent().unwrap().to_path_buf();
    s.path = dir.join("gone/collected.ctlib");
    if let Some(c) = s.e.collect.as_mut() {
        if let Some(col) = c.collector.as_mut() {
            col.path = s.path.clone();
        }
    }
    s.draw(MotionClass::Translate, 5);
    let last = s.events.iter().rev().find_map(|e| match e {
        Event::Collect(c) => Some(c.clone()),
        _ => None,
    });
    let last = last.unwrap();
    assert_eq!(last.state, CollectState::Failed);
    assert!(last.detail.unwrap().contains("cannot write"));
    assert_eq!(s.e.collect_recorded(), 0);
    assert!(!s.e.collect_finished());
}
