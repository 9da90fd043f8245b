//! The edit mode in the engine, as a client sees it: tracks loaded play as the
//! crowd; fingers on a group grab its tracks, drag them (the held person's sample
//! follows the finger exactly, the group's other tracks follow smoothly, people
//! outside the group stay), and the release corrects speeds and avoids collisions;
//! undo brings back the tracks before the edit; retime moves time nodes; exit
//! brings the crowd back.

use crowdtouch::config::Config;
use crowdtouch::crowd::edit::{detect, Track, TrackSet};
use crowdtouch::engine::Engine;
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{Command, Contact, ContactFlags, ContactId, Micros, TouchFrame};
use std::sync::Arc;

mod common;

use common::edit_session::{Session, TICK_US};

/// A parade: `rows × cols` people 0.8 m apart walking +x at 1 m/s for 10 s,
/// sampled every 0.2 s, starting at x = 2 m; and one person far away (id 999).
fn parade(rows: usize, cols: usize) -> TrackSet {
    let mut tracks = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let id = (r * cols + c) as u64;
            let p0 = Vec2::new(2.0 + c as f64 * 0.8, 2.0 + r as f64 * 0.8);
            let times: Vec<f64> = (0..=50).map(|k| k as f64 * 0.2).collect();
            let points = times.iter().map(|t| p0 + Vec2::new(*t, 0.0)).collect();
            tracks.push(Track::linked(id, points, times));
        }
    }
    let times: Vec<f64> = (0..=50).map(|k| k as f64 * 0.2).collect();
    tracks.push(Track::linked(
        999,
        times.iter().map(|_| Vec2::new(14.0, 8.0)).collect(),
        times,
    ));
    TrackSet {
        tracks,
        step_s: 0.2,
    }
}

#[test]
fn the_crowd_plays_the_loaded_people() {
    let mut s = Session::playing(parade(3, 4));
    assert!(s.e.editing());
    let first = s.tracks.first().expect("a tracks message at load");
    assert!(first.full);
    assert_eq!(first.tracks.len(), 13);
    let a0 = s.agents();
    assert_eq!(a0.len(), 13, "one agent per person");
    s.ticks(60);
    let a1 = s.agents();
    let moved = a1[0].x - a0[0].x;
    assert!(
        (moved - 62.0 * TICK_US as f64 / 1e6).abs() < 0.05,
        "people walk at their tracks' 1 m/s: {moved}"
    );
    assert_eq!(a1[12], Vec2::new(14.0, 8.0));
}

#[test]
fn a_drag_moves_the_held_person_with_the_finger_and_the_group_with_them() {
    let mut s = Session::playing(parade(3, 4));
    s.e.command(&Command::Pause, Micros(s.now)).unwrap();
    s.tick();
    let before = s.set();
    // The person at row 1, column 1 stands at (2.8 + t, 2.8) at play time t.
    let t = s.views.last().map_or(0.0, |v| v.play_t_s);
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, ContactFlags::DOWN)]);
    s.ticks(3);
    let grabbed = s
        .views
        .iter()
        .rev()
        .find(|v| v.state == "grabbed")
        .expect("grabbed")
        .clone();
    assert_eq!(
        grabbed.selected.len(),
        12,
        "the whole parade, not the far person: {:?}",
        grabbed.selected
    );
    let lift = Vec2::new(0.0, 1.5);
    for k in 1..=10 {
        s.touch(&[(1, held + lift * (k as f64 / 10.0), ContactFlags::NONE)]);
        s.ticks(2);
    }
    let during = s.set();
    let k = during.index_of(5).unwrap();
    // The held sample: the one nearest the play time.
    let j = during.tracks[k]
        .times_s
        .iter()
        .position(|&ts| (ts - t).abs() <= 0.1 + 1e-9)
        .unwrap();
    let d = during.tracks[k].points[j] - before.tracks[k].points[j];
    assert!(
        (d - lift).norm() < 1e-6,
        "the held sample moved with the finger: {d:?}"
    );
    assert!(
        !s.tracks.last().unwrap().full,
        "while held, only the group's tracks are sent"
    );
    let far = during.index_of(999).unwrap();
    assert_eq!(
        during.tracks[far], before.tracks[far],
        "a person outside the group stays"
    );
    s.touch(&[(1, held + lift, ContactFlags::UP)]);
    s.ticks(10);
    let after = s.set();
    let last = s.views.last().unwrap();
    assert_eq!(last.state, "preview", "the release is shown as a preview");
    assert_eq!(last.undo_depth, 1);
    assert!(s.tracks.last().unwrap().full);
    assert!(s.tracks.last().unwrap().preview);
    s.e.command(&Command::EditAccept, Micros(s.now)).unwrap();
    s.tick();
    let last = s.views.last().unwrap();
    assert_eq!(last.state, "idle", "accepted");
    assert!(last.preview.is_none());
    assert_eq!(s.e.edits_applied(), 1);
    assert!(
        s.e.command(&Command::EditAccept, Micros(s.now)).is_err(),
        "nothing left to accept"
    );
    // Speeds corrected (eq. 9): every segment within 1 % of its speed before.
    for (a, b) in after.tracks.iter().zip(&before.tracks) {
        for jj in 0..a.len() - 1 {
            let (va, vb) = (a.segment_speed(jj), b.segment_speed(jj));
            if vb > 0.0 {
                assert!(
                    (va / vb - 1.0).abs() < 0.01,
                    "person {} segment {jj}: {va} vs {vb}",
                    a.id
                );
            }
        }
    }
    assert!(
        detect(after.as_ref(), 0.3).unwrap().pairs.is_empty(),
        "no one closer than 0.3 m after the release"
    );
    s.e.command(&Command::EditUndo, Micros(s.now)).unwrap();
    s.tick();
    assert_eq!(
        *s.set(),
        *before,
        "undo brings back the tracks before the drag"
    );
}

#[test]
fn retime_moves_time_nodes_and_exit_brings_the_crowd_back() {
    let mut s = Session::playing(parade(2, 2));
    let before = s.set();
    s.e.command(
        &Command::EditRetime {
            at_s: 5.0,
            to_s: 7.0,
            ids: None,
        },
        Micros(s.now),
    )
    .unwrap();
    s.ticks(2);
    let after = s.set();
    let j = before.tracks[0]
        .times_s
        .iter()
        .position(|&t| (t - 5.0).abs() < 1e-9)
        .unwrap();
    assert!((after.tracks[0].times_s[j] - 7.0).abs() < 1e-6);
    assert_eq!(
        after.tracks[0].points, before.tracks[0].points,
        "a retime keeps the places"
    );
    assert!(s
        .e
        .command(
            &Command::EditSave {
                entry: None,
                overwrite: false
            },
            Micros(s.now)
        )
        .is_err());
    s.e.command(&Command::EditExit, Micros(s.now)).unwrap();
    s.tick();
    assert!(!s.e.editing());
    let n = s.agents().len();
    assert_eq!(
        n,
        Config::embedded_default().crowd.agents as usize,
        "the crowd is back"
    );
    assert!(
        s.e.command(&Command::EditUndo, Micros(s.now)).is_err(),
        "not in edit mode"
    );
}

/// Two people walking into each other's path at the same time: the load reports the
/// collision; a retime ends with them kept apart (section 4.1.2), places kept.
#[test]
fn a_retime_keeps_colliding_people_apart() {
    let times: Vec<f64> = (0..=40).map(|k| k as f64 * 0.25).collect();
    let east = Track::linked(
        1,
        times.iter().map(|t| Vec2::new(2.0 + *t, 4.0)).collect(),
        times.clone(),
    );
    let north = Track::linked(
        2,
        times.iter().map(|t| Vec2::new(7.0, -1.0 + *t)).collect(),
        times.clone(),
    );
    let set = TrackSet {
        tracks: vec![east, north],
        step_s: 0.25,
    };
    assert_eq!(
        detect(&set, 0.3).unwrap().pairs.len(),
        1,
        "they meet at (7, 4) at t = 5 s"
    );
    let mut s = Session::playing(set.clone());
    let v = s.views.last().expect("an edit view at load").clone();
    assert_eq!(v.collisions.len(), 1, "the collision is published at load");
    s.e.command(
        &Command::EditRetime {
            at_s: 2.0,
            to_s: 2.0,
            ids: None,
        },
        Micros(s.now),
    )
    .unwrap();
    s.ticks(2);
    let after = s.set();
    assert!(
        detect(after.as_ref(), 0.3).unwrap().pairs.is_empty(),
        "kept apart by retiming"
    );
    for (a, b) in after.tracks.iter().zip(&set.tracks) {
        assert_eq!(a.points, b.points, "retiming keeps the places");
    }
    let v = s.views.last().unwrap();
    assert!(v.collisions.is_empty());
    assert_eq!(v.undo_depth, 1);
}

/// A `contract` gesture in open space retimes every person: the next five seconds
/// play faster (the node nearest play + 5 s comes 1 s sooner), places kept.
#[test]
fn a_contract_gesture_in_open_space_plays_the_tracks_faster() {
    use crowdtouch::gesture::library::MotionClass;
    use crowdtouch::gesture::synth::{generate, to_frames, GestureStyle};
    let glass = (1210.0, 680.0);
    let cfg = Config::embedded_default();
    let mut e = Engine::new(&cfg, Some(glass), true);
    e.tick(Micros(TICK_US));
    let before = parade(2, 3);
    e.load_tracks(before.clone(), "parade", Micros(TICK_US));
    e.command(&Command::Pause, Micros(TICK_US)).unwrap();
    let style = GestureStyle {
        fingers: vec![3],
        duration_s: 1.0,
        size_mm: 150.0,
        placement: Vec2::new(0.8, 0.75),
        orientation_rad: 0.0,
        jitter_mm: 0.3,
        device_mm: glass,
        rate_hz: 120.0,
        stagger_ms: 30.0,
        early_lifts: 0,
        bow: 0.0,
        spacing_mm: 20.0,
        clockwise: false,
    };
    let frames = to_frames(
        &generate(MotionClass::Contract, &style, 3),
        glass,
        Micros(100_000),
    );
    let mut class = None;
    let mut tick = |e: &mut Engine, t: u64| {
        for ev in e.tick(Micros(t)).events {
            if let crowdtouch::vocab::Event::GestureEnd {
                recognition: Some(r),
                ..
            } = ev
            {
                class = Some(r.class.clone());
            }
        }
        e.clear_events();
    };
    let mut now = 0;
    for f in &frames {
        e.push_frame(f);
        now = f.t.0;
        tick(&mut e, now);
    }
    // A second more: the recognition comes after the gesture's grace period.
    for _ in 0..60 {
        now += TICK_US;
        tick(&mut e, now);
    }
    assert_eq!(class.as_deref(), Some("contract"));
    let after = Arc::clone(e.edited_tracks().unwrap());
    let k = 25; // t = 5 s, the node nearest the play time (≈ 0) + 5 s
    for (a, b) in after
        .tracks
        .iter()
        .zip(&before.tracks)
        .filter(|(a, _)| a.id != 999)
    {
        assert!(
            (a.times_s[k] - 4.0).abs() < 0.05,
            "person {}: {} s",
            a.id,
            a.times_s[k]
        );
        assert_eq!(a.points, b.points);
        assert_eq!(a.times_s[0], b.times_s[0]);
        assert!(
            (a.times_s[50] - b.times_s[50]).abs() < 1e-9,
            "the last time stays"
        );
    }
}

/// With the jobs on a worker (as in the daemon): an `edit.load` asked while a drag
/// is out, whose file then cannot be read, leaves the drag and the tracks as they
/// were; a load that is read replaces them and drops the old drag's result.
#[test]
fn a_load_while_a_drag_is_out_drops_nothing_until_it_is_read() {
    let cfg = Config::embedded_default();
    let mut e = Engine::new(&cfg, None, false);
    e.set_switch_worker(true);
    e.tick(Micros(TICK_US));
    e.load_tracks(parade(2, 3), "parade", Micros(TICK_US));
    let mut now = TICK_US;
    let run_jobs = |e: &mut Engine, now: u64| {
        while let Some(j) = e.take_edit_job() {
            let done = j.run();
            e.apply_edit(done, Micros(now));
        }
    };
    now += TICK_US;
    e.tick(Micros(now));
    run_jobs(&mut e, now);
    e.command(&Command::Pause, Micros(now)).unwrap();
    let frame = |t: u64, p: Vec2, flags: ContactFlags| {
        let mut f = TouchFrame::new(Micros(t));
        f.push(Contact {
            id: ContactId(1),
            x: (p.x / 16.0) as f32,
            y: (p.y / 9.0) as f32,
            pressure: None,
            major_mm: None,
            minor_mm: None,
            flags,
        })
        .unwrap();
        f
    };
    let held = Vec2::new(2.8, 2.8);
    e.push_frame(&frame(now + 1, held, ContactFlags::DOWN));
    for k in 1..=20 {
        now += TICK_US;
        e.push_frame(&frame(
            now,
            held + Vec2::new(0.0, 0.05 * k as f64),
            ContactFlags::NONE,
        ));
        e.tick(Micros(now));
    }
    let job = e.take_edit_job().expect("a drag is out");
    // The load is asked while the drag is out; its file cannot be read.
    e.command(
        &Command::EditLoad {
            entry: "nonexistent.jsonl".into(),
        },
        Micros(now),
    )
    .unwrap();
    let file = e.take_edit_file_job().expect("a file job");
    let epoch = e.edit_epoch();
    drop(file);
    e.apply_edit(job.run(), Micros(now));
    e.edit_load_failed(epoch);
    let after = Arc::clone(e.edited_tracks().unwrap());
    let k = after.index_of(4).unwrap();
    // The drag out was the first (0.05 m): the next waits for it.
    assert!(
        (after.tracks[k].points[0].y - 2.85).abs() < 1e-5,
        "the drag's result was used: {:?}",
        after.tracks[k].points[0]
    );
    // The drag goes on after the failed load.
    now += TICK_US;
    e.push_frame(&frame(now, held + Vec2::new(0.0, 1.5), ContactFlags::NONE));
    e.tick(Micros(now));
    let next = e.take_edit_job().expect("the next drag is sent");
    // A load that is read replaces the tracks; the old drag's result is dropped.
    e.command(
        &Command::EditLoad {
            entry: "other.jsonl".into(),
        },
        Micros(now),
    )
    .unwrap();
    let _ = e.take_edit_file_job();
    assert!(e.apply_edit_load(e.edit_epoch(), parade(1, 3), "other.jsonl", Micros(now)));
    e.apply_edit(next.run(), Micros(now));
    assert_eq!(
        e.edited_tracks().unwrap().tracks.len(),
        4,
        "the new tracks stay"
    );
}

/// 5,000 people at one point (issue 27, finding 4: the load stored their 12.5
/// million pairs and published every one in each `edit` message): the load
/// publishes one collision for the crowd; with 300 walkers crossing it (45,150
/// more pairs), at most 256.
#[test]
fn a_crowd_at_one_point_is_published_as_one_collision() {
    let mut tracks: Vec<Track> = (0..5_000)
        .map(|id| Track::linked(id, vec![Vec2::new(5.0, 5.0); 2], vec![0.0, 1.0]))
        .collect();
    let s = Session::playing(TrackSet {
        tracks: tracks.clone(),
        step_s: 1.0,
    });
    let v = s.views.last().expect("an edit view at load");
    assert_eq!(
        v.collisions.len(),
        1,
        "{:?}",
        &v.collisions[..3.min(v.collisions.len())]
    );
    let c = &v.collisions[0];
    assert_eq!((c.a, c.b, c.distance_m), (0, 1, 0.0));
    assert_eq!(c.place, Vec2::new(5.0, 5.0));
    // Many distinct collisions: the list is bounded.
    for k in 0..300u64 {
        let y = 5.0 + k as f64 * 0.0005;
        tracks.push(Track::linked(
            10_000 + k,
            vec![Vec2::new(0.0, y), Vec2::new(10.0, y)],
            vec![0.0, 1.0],
        ));
    }
    let s = Session::playing(TrackSet {
        tracks,
        step_s: 1.0,
    });
    let v = s.views.last().expect("an edit view at load");
    assert_eq!(v.collisions.len(), 256);
    assert_eq!(v.collisions[0].distance_m, 0.0, "the crowd first");
}

#[test]
fn a_release_retimes_no_stranger_who_collided_already() {
    // The parade and two strangers who cross each other at (12, 7) at t = 2 s,
    // far from it. Dragging the parade brings no one into collision: the release
    // retimes no one outside it, the strangers' collision stays as it was (it is
    // not the edit's), and undo brings back every track byte for byte.
    let mut set = parade(3, 4);
    let times: Vec<f64> = (0..=50).map(|k| k as f64 * 0.2).collect();
    for (id, from, dir) in [
        (500, Vec2::new(10.0, 7.0), Vec2::new(1.0, 0.0)),
        (501, Vec2::new(12.0, 5.0), Vec2::new(0.0, 1.0)),
    ] {
        set.tracks.push(Track::linked(
            id,
            times.iter().map(|t| from + dir * *t).collect(),
            times.clone(),
        ));
    }
    let strangers = detect(&set, 0.3).unwrap();
    assert_eq!(strangers.pair_count(), 1, "the strangers collide");
    let mut s = Session::playing(set);
    s.e.command(&Command::Pause, Micros(s.now)).unwrap();
    s.tick();
    let before = s.set();
    let t = s.views.last().map_or(0.0, |v| v.play_t_s);
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, ContactFlags::DOWN)]);
    s.ticks(3);
    for k in 1..=10 {
        s.touch(&[(
            1,
            held + Vec2::new(0.0, 1.0) * (k as f64 / 10.0),
            ContactFlags::NONE,
        )]);
        s.ticks(2);
    }
    s.touch(&[(1, held + Vec2::new(0.0, 1.0), ContactFlags::UP)]);
    s.ticks(10);
    assert_eq!(s.views.last().unwrap().state, "preview");
    let after = s.set();
    for id in [500, 501, 999] {
        let k = after.index_of(id).unwrap();
        assert_eq!(
            after.tracks[k], before.tracks[k],
            "person {id}, outside the drag, is not retimed"
        );
    }
    let left = detect(after.as_ref(), 0.3).unwrap();
    assert_eq!(left.pair_count(), 1);
    let q = &left.pairs[0];
    assert_eq!((q.id_a, q.id_b), (500, 501));
    s.e.command(&Command::EditUndo, Micros(s.now)).unwrap();
    s.tick();
    assert_eq!(*s.set(), *before, "undo restores every track");
}
