//! The paper's editing tools on the table (crowd-motion-editing §3–4), in the
//! engine, as a person at the table and a client see them: one person dragged
//! retimes only the people the edit brought into collision; a second control pins
//! points (eq. 6) that stay put; a hull vertex of the last cage can be grabbed; a
//! lasso drawn in open space, or `edit.select`, picks the people the next grab
//! takes (in a time window); `edit.retime` retimes one group (Fig. 14); a release
//! is a preview that `edit.accept` keeps and `edit.undo` drops byte for byte; a
//! touch landing while a release settles is grabbed when it is back; a release
//! keeps the group out of the scene's obstacles.

use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{read_tracks, ReadOptions};
use crowdtouch::crowd::edit::{correct_speeds, detect, samples_in_obstacles, Track, TrackSet};
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{Command, ContactFlags, Event, Micros};
use std::collections::BTreeSet;
use std::path::Path;

mod common;

use common::edit_session::{Session, DOWN, MOVE, UP};

/// A person walking from `from` by `step` every 0.2 s for 10 s.
fn walker(id: u64, from: Vec2, step_per_s: Vec2) -> Track {
    let times: Vec<f64> = (0..=50).map(|k| k as f64 * 0.2).collect();
    Track::linked(
        id,
        times.iter().map(|t| from + step_per_s * *t).collect(),
        times,
    )
}

/// A parade: `rows × cols` people 0.8 m apart walking +x at 1 m/s for 10 s from
/// x = 2 m, y = 2 m; and one person far away standing at (14, 8) (id 999).
fn parade(rows: usize, cols: usize) -> TrackSet {
    let mut tracks = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let p0 = Vec2::new(2.0 + c as f64 * 0.8, 2.0 + r as f64 * 0.8);
            tracks.push(walker((r * cols + c) as u64, p0, Vec2::new(1.0, 0.0)));
        }
    }
    tracks.push(walker(999, Vec2::new(14.0, 8.0), Vec2::zeros()));
    TrackSet {
        tracks,
        step_s: 0.2,
    }
}

/// The ids of the people whose times differ between `a` and `b`.
fn retimed(a: &TrackSet, b: &TrackSet) -> BTreeSet<u64> {
    a.tracks
        .iter()
        .zip(&b.tracks)
        .filter(|(x, y)| x.times_s != y.times_s)
        .map(|(x, _)| x.id)
        .collect()
}

/// The pairs (ids) closer than 0.3 m in `set`.
fn pairs(set: &TrackSet) -> BTreeSet<(u64, u64)> {
    detect(set, 0.3)
        .unwrap()
        .pairs
        .iter()
        .map(|q| (q.id_a.min(q.id_b), q.id_a.max(q.id_b)))
        .collect()
}

/// The people in pairs of `after` that were not pairs in `before` with one of
/// `dragged` (ids): the people the edit brought into collision with them.
fn new_partners(before: &TrackSet, after: &TrackSet, dragged: &BTreeSet<u64>) -> BTreeSet<u64> {
    let old = pairs(before);
    pairs(after)
        .difference(&old)
        .filter_map(
            |&(a, b)| match (dragged.contains(&a), dragged.contains(&b)) {
                (true, false) => Some(b),
                (false, true) => Some(a),
                _ => None,
            },
        )
        .collect()
}

/// The tracks as the drag left them before the release's work: `before` with
/// the places of the last `tracks` message of the held people, speeds corrected
/// as the release corrects them (eq. 9).
fn dragged_tracks(s: &Session, before: &TrackSet) -> (TrackSet, BTreeSet<u64>) {
    let held = s
        .tracks
        .iter()
        .rev()
        .find(|t| !t.full)
        .expect("the held people's tracks while dragged");
    let mut set = before.clone();
    let mut touched = Vec::new();
    for t in &held.tracks {
        let k = set.index_of(t.id).unwrap();
        set.tracks[k].points.clone_from(&t.points);
        touched.push(k);
    }
    correct_speeds(before, &mut set, &touched).unwrap();
    (set, held.tracks.iter().map(|t| t.id).collect())
}

/// The Done-when: one person dragged on the table retimes only the people the
/// edit brought into collision (the person dragged onto a walker's path, or the
/// walker), never the strangers who collided already; undo restores the tracks
/// byte for byte.
#[test]
fn one_person_dragged_retimes_only_the_people_the_edit_brought_into_collision() {
    // 1 walks east along y = 2 m; 2 walks north along x = 7 m, crossing 1's
    // path at t = 0, 5 m ahead of 1; 3 and 4 cross each other at (12, 7) at
    // t = 2 s; 5 walks along y = 8.5 m, alone. At t = 5 s, 1 is at (7, 2) and 2
    // at (7, 4.5): 1 is a group of one. A drag is local (eq. 5): 1's track bends
    // up 2.5 m around where the finger holds it, onto 2's path at t = 5 s.
    let set = TrackSet {
        tracks: vec![
            walker(1, Vec2::new(2.0, 2.0), Vec2::new(1.0, 0.0)),
            walker(2, Vec2::new(7.0, 2.0), Vec2::new(0.0, 0.5)),
            walker(3, Vec2::new(10.0, 7.0), Vec2::new(1.0, 0.0)),
            walker(4, Vec2::new(12.0, 5.0), Vec2::new(0.0, 1.0)),
            walker(5, Vec2::new(1.0, 8.5), Vec2::new(1.0, 0.0)),
        ],
        step_s: 0.2,
    };
    let before_pairs = pairs(&set);
    assert_eq!(
        before_pairs,
        BTreeSet::from([(3, 4)]),
        "only the strangers collide"
    );
    let mut s = Session::new(set);
    s.play_to(5.0);
    let before = s.set();
    let t = s.play_t();
    let held = Vec2::new(2.0 + t, 2.0);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    assert_eq!(s.view().state, "grabbed");
    assert_eq!(s.view().selected, vec![1], "a group of one");
    s.drag(1, held, Vec2::new(0.0, 2.5), &[]);
    let (dragged, people) = dragged_tracks(&s, &before);
    assert_eq!(people, BTreeSet::from([1]));
    let brought = new_partners(&before, &dragged, &people);
    assert_eq!(
        brought,
        BTreeSet::from([2]),
        "the drag brings 1 onto 2's path"
    );
    s.touch(&[(1, held + Vec2::new(0.0, 2.5), UP)]);
    s.ticks(4);
    let v = s.view().clone();
    assert_eq!(v.state, "preview");
    let p = v.preview.clone().expect("a preview");
    let after = s.set();
    // Collision avoidance retimed exactly the people the edit brought into
    // collision with the dragged one, as the preview says: no one else's times
    // changed from the dragged tracks (1's speed correction aside).
    let by_avoidance = retimed(&dragged, &after);
    assert_eq!(
        p.retimed.iter().copied().collect::<BTreeSet<_>>(),
        by_avoidance
    );
    // Avoidance may retime either side of the new pair (section 4.1.2): here
    // the dragged person or the walker, no one else.
    let involved: BTreeSet<u64> = brought.union(&people).copied().collect();
    assert!(
        !by_avoidance.is_empty() && by_avoidance.is_subset(&involved),
        "retimed {by_avoidance:?}, brought into collision {involved:?}"
    );
    for id in [3, 4, 5] {
        let k = after.index_of(id).unwrap();
        assert_eq!(
            after.tracks[k], before.tracks[k],
            "{id} is not the edit's business"
        );
    }
    assert_eq!(
        pairs(&after),
        before_pairs,
        "the new pair is gone, the old one left as it was"
    );
    assert_eq!((p.pairs_before, p.pairs_after), (2, 1));
    assert!(p.pushed.is_empty(), "no scene, no obstacles");
    // Undo drops the preview: the very tracks before the drag, byte for byte.
    s.command(Command::EditUndo);
    assert_eq!(s.view().state, "idle");
    assert!(s.view().preview.is_none());
    let back = s.set();
    assert_eq!(jsonl(&back), jsonl(&before));
    assert!(s.tracks.last().unwrap().full && !s.tracks.last().unwrap().preview);
}

/// The same on a real file (students001, ETH/UCY, 415 people): a person grabbed
/// at the play time and dragged 1.5 m; the release retimes no one outside the
/// dragged group and the people it newly met, and undo restores every track byte
/// for byte.
#[test]
fn on_students001_a_drag_retimes_no_one_the_edit_did_not_bring_into_collision() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/crowd/students001.txt");
    let (set, _) = read_tracks(&path, None, &ReadOptions::default()).expect("students001");
    let mut s = Session::new(set);
    let before = s.set();
    // Someone on the scene at the play time, as a finger sees them.
    let t = s.play_t();
    let (k, at) = before
        .tracks
        .iter()
        .enumerate()
        .find_map(|(k, tr)| tr.position_at(t).map(|p| (k, p)))
        .filter(|(_, p)| p.x > 1.0 && p.y > 1.0 && p.x < 13.0 && p.y < 7.0)
        .expect("someone on the scene inside the table");
    s.touch(&[(1, at, DOWN)]);
    s.ticks(2);
    assert_eq!(s.view().state, "grabbed", "person {k} at {at:?}");
    s.drag(1, at, Vec2::new(1.5, 0.0), &[]);
    let (dragged, people) = dragged_tracks(&s, &before);
    let brought = new_partners(&before, &dragged, &people);
    s.touch(&[(1, at + Vec2::new(1.5, 0.0), UP)]);
    s.ticks(4);
    let p = s.view().preview.clone().expect("a preview");
    let after = s.set();
    let by_avoidance = retimed(&dragged, &after);
    let allowed: BTreeSet<u64> = people.union(&brought).copied().collect();
    assert!(
        by_avoidance.is_subset(&allowed),
        "retimed {by_avoidance:?}, brought into collision {brought:?}, dragged {people:?}"
    );
    for (a, b) in after.tracks.iter().zip(&before.tracks) {
        if !allowed.contains(&a.id) {
            assert_eq!(a, b, "{} is not the edit's business", a.id);
        }
    }
    assert!(p.pairs_after <= p.pairs_before);
    s.command(Command::EditUndo);
    assert_eq!(jsonl(&s.set()), jsonl(&before), "undo, byte for byte");
}

/// The tracks as `edit.save` writes them (JSON Lines).
fn jsonl(set: &TrackSet) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("t.jsonl");
    crowdtouch::crowd::edit::io::write_tracks(
        set,
        &p,
        crowdtouch::crowd::edit::io::Format::Jsonl,
        &ReadOptions::default(),
        false,
    )
    .unwrap();
    std::fs::read(&p).unwrap()
}

/// A second control landing on the grabbed group pins that person's sample
/// (eq. 6): it stays where it was before the grab to 1e-9 m through the drag and
/// the release, and the `edit` message shows the pin and the finger's handle;
/// without the pin the same drag moves it.
#[test]
fn a_second_control_pins_a_point_that_stays_put() {
    let far_corner = |s: &Session| {
        let set = s.set();
        let k = set.index_of(3).unwrap(); // row 0, column 3: (4.4 + t, 2.0)
        (k, set.tracks[k].points.clone())
    };
    let run = |pin: bool| {
        let mut s = Session::new(parade(3, 4));
        let t = s.play_t();
        let held = Vec2::new(2.0 + t, 3.6); // row 2, column 0
        let pinned = Vec2::new(4.4 + t, 2.0);
        s.touch(&[(1, held, DOWN)]);
        s.ticks(12); // past the grouping window: the next finger is a control of its own
        if pin {
            s.touch(&[(1, held, MOVE), (2, pinned, DOWN)]);
            s.ticks(3);
        }
        let also: Vec<(u32, Vec2)> = if pin { vec![(2, pinned)] } else { vec![] };
        s.drag(1, held, Vec2::new(-1.0, 1.5), &also);
        let v = s.view().clone();
        assert_eq!(v.state, "grabbed");
        assert_eq!(v.selected.len(), 12);
        assert_eq!(v.handles.len(), 1, "one finger holds");
        assert!((v.handles[0] - (held + Vec2::new(-1.0, 1.5))).norm() < 0.01);
        let mut last: Vec<(u32, Vec2, ContactFlags)> = vec![(1, held + Vec2::new(-1.0, 1.5), UP)];
        if pin {
            assert_eq!(v.pins.len(), 1, "the pin is shown");
            assert!((v.pins[0] - pinned).norm() < 0.01, "{:?}", v.pins);
            last.push((2, pinned, UP));
        }
        s.touch(&last);
        s.ticks(4);
        assert_eq!(s.view().state, "preview");
        s
    };
    let before = far_corner(&Session::new(parade(3, 4))).1;
    let pinned = run(true);
    let (_, after) = far_corner(&pinned);
    let j = 0; // the sample nearest the play time (0 s) is the pinned one
    assert!(
        (after[j] - before[j]).norm() < 1e-9,
        "pinned: moved {:?}",
        after[j] - before[j]
    );
    let (_, free) = far_corner(&run(false));
    assert!(
        (free[j] - before[j]).norm() > 0.05,
        "without the pin the corner moves: {:?}",
        free[j] - before[j]
    );
}

/// After a release, a touch on a vertex of the hull shown grabs that cage's people
/// by the vertex: the vertex follows the finger, the people move with the cage.
#[test]
fn a_hull_vertex_of_the_last_cage_can_be_grabbed() {
    let mut s = Session::new(parade(2, 3));
    let t = s.play_t();
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    s.drag(1, held, Vec2::new(0.0, 0.5), &[]);
    s.touch(&[(1, held + Vec2::new(0.0, 0.5), UP)]);
    s.ticks(4);
    s.command(Command::EditAccept);
    let hull = s.view().hull.clone();
    assert!(hull.len() >= 3, "the last hull is shown");
    let before = s.set();
    // The hull vertex with the largest x (the far end of the parade's tracks).
    let v = *hull.iter().max_by(|a, b| a.x.total_cmp(&b.x)).unwrap();
    s.touch(&[(3, v, DOWN)]);
    s.ticks(2);
    assert_eq!(s.view().state, "grabbed", "a vertex is something to grab");
    assert_eq!(s.view().selected.len(), 6, "the cage's people");
    s.drag(3, v, Vec2::new(0.0, 1.0), &[]);
    let g = s.view().clone();
    assert_eq!(g.handles.len(), 1);
    let moved = g.handles[0] - v;
    assert!(
        (moved - Vec2::new(0.0, 1.0)).norm() < 0.3,
        "the vertex follows the finger: {moved:?}"
    );
    let during = s.set();
    // The parade's far end moved up with the vertex; the far person did not.
    let k = during.index_of(2).unwrap();
    let end = during.tracks[k].len() - 1;
    let lift = during.tracks[k].points[end].y - before.tracks[k].points[end].y;
    assert!(lift > 0.3, "the tracks' far end went up: {lift}");
    let far = during.index_of(999).unwrap();
    assert_eq!(during.tracks[far], before.tracks[far]);
}

/// `edit.select` by ids and a time window: the next grab on a selected person
/// grabs the selection (not the 2 m group), and only its samples in the window.
#[test]
fn a_selection_with_a_window_is_what_the_next_grab_takes() {
    let mut s = Session::new(parade(3, 4));
    s.command(Command::EditSelect {
        lasso: None,
        window_s: Some([0.0, 4.0]),
        ids: Some(vec![0, 1, 4, 5]),
    });
    let sel = s.view().selection.clone();
    assert_eq!(sel.ids, vec![0, 1, 4, 5]);
    assert_eq!(sel.window_s, Some((0.0, 4.0)));
    let before = s.set();
    let t = s.play_t();
    let held = Vec2::new(2.0 + t, 2.0); // person 0
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    assert_eq!(
        s.view().selected,
        vec![0, 1, 4, 5],
        "the selection, not the parade"
    );
    s.drag(1, held, Vec2::new(0.0, -1.0), &[]);
    s.touch(&[(1, held + Vec2::new(0.0, -1.0), UP)]);
    s.ticks(4);
    let after = s.set();
    for (a, b) in after.tracks.iter().zip(&before.tracks) {
        let selected = [0, 1, 4, 5].contains(&a.id);
        for j in 0..a.len() {
            let moved = (a.points[j] - b.points[j]).norm();
            if !selected || b.times_s[j] > 4.0 {
                assert_eq!(
                    moved, 0.0,
                    "person {} sample {j} is outside the selection",
                    a.id
                );
            }
        }
        if selected {
            assert!(
                (a.points[0] - b.points[0]).norm() > 0.5,
                "person {} moved",
                a.id
            );
        }
    }
    // Cleared with an empty select: the next grab takes the group again.
    s.command(Command::EditAccept);
    s.command(Command::EditSelect {
        lasso: None,
        window_s: None,
        ids: None,
    });
    assert!(s.view().selection.ids.is_empty());
    // Bad selections are refused with a reason.
    for (c, why) in [
        (
            Command::EditSelect {
                lasso: Some(vec![[0.0, 0.0], [1.0, 0.0]]),
                window_s: None,
                ids: None,
            },
            "3 to",
        ),
        (
            Command::EditSelect {
                lasso: None,
                window_s: Some([3.0, 1.0]),
                ids: None,
            },
            "start <= end",
        ),
        (
            Command::EditSelect {
                lasso: None,
                window_s: None,
                ids: Some(vec![77]),
            },
            "no person has id 77",
        ),
    ] {
        let e = s.e.command(&c, Micros(s.now)).unwrap_err().to_string();
        assert!(e.contains(why), "{e}");
    }
}

/// A one-finger loop drawn in open space is a lasso: the people with a sample
/// inside it are selected (its `gesture` event says `lasso`, not a recognition);
/// `edit.select` with a lasso does the same from a client.
#[test]
fn a_lasso_in_open_space_selects_the_people_inside_it() {
    // Two groups: three people walking along y = 2 m, three along y = 7 m.
    let mut tracks = Vec::new();
    for (i, y) in [
        (0u64, 1.6),
        (1, 2.0),
        (2, 2.4),
        (3, 6.6),
        (4, 7.0),
        (5, 7.4),
    ] {
        tracks.push(walker(i, Vec2::new(3.0, y), Vec2::new(0.3, 0.0)));
    }
    let set = TrackSet {
        tracks,
        step_s: 0.2,
    };
    let mut s = Session::new(set);
    // A loop of radius 1.5 m around (5, 7), starting in open space (6.5, 7).
    let centre = Vec2::new(5.0, 7.0);
    let at = |k: usize| {
        let a = std::f64::consts::TAU * k as f64 / 60.0;
        centre + Vec2::new(1.5 * a.cos(), 1.5 * a.sin())
    };
    s.touch(&[(7, at(0), DOWN)]);
    s.tick();
    for k in 1..=60 {
        s.touch(&[(7, at(k), MOVE)]);
        s.tick();
    }
    s.touch(&[(7, at(60), UP)]);
    s.ticks(40); // past the gesture's grace period
    let lasso_end = s
        .events
        .iter()
        .any(|e| matches!(e, Event::GestureEnd { rejected: Some(r), .. } if r == "lasso"));
    assert!(lasso_end, "the gesture ends as a lasso");
    let sel = s.view().selection.clone();
    assert_eq!(
        sel.ids,
        vec![3, 4, 5],
        "the people walking through the loop"
    );
    assert!(sel.lasso.as_ref().is_some_and(|l| l.len() > 10));
    // From a client: a square around the first group's start, in a window when
    // only they are there.
    s.command(Command::EditSelect {
        lasso: Some(vec![[2.5, 1.0], [3.5, 1.0], [3.5, 3.0], [2.5, 3.0]]),
        window_s: Some([0.0, 1.0]),
        ids: None,
    });
    assert_eq!(s.view().selection.ids, vec![0, 1, 2]);
    // A window when they have walked on past the square: no one.
    s.command(Command::EditSelect {
        lasso: Some(vec![[2.5, 1.0], [3.5, 1.0], [3.5, 3.0], [2.5, 3.0]]),
        window_s: Some([5.0, 10.0]),
        ids: None,
    });
    assert!(s.view().selection.ids.is_empty());
    // A retime of an empty selection is refused (it would retime everyone).
    let e =
        s.e.command(
            &Command::EditRetime {
                at_s: 5.0,
                to_s: 6.0,
                ids: None,
            },
            Micros(s.now),
        )
        .unwrap_err();
    assert!(e.to_string().contains("no one to retime"), "{e}");
}

/// `edit.retime` with ids retimes only those people (the paper's Fig. 14: three
/// people of a crowd); with a selection and no ids, the selection; everyone
/// else's times stay.
#[test]
fn a_retime_of_one_group_changes_only_its_times() {
    let mut s = Session::new(parade(3, 4));
    let before = s.set();
    s.command(Command::EditRetime {
        at_s: 5.0,
        to_s: 6.0,
        ids: Some(vec![4, 5, 6]),
    });
    assert_eq!(s.view().state, "preview");
    let after = s.set();
    assert_eq!(
        retimed(&before, &after),
        BTreeSet::from([4, 5, 6]),
        "only the three"
    );
    let k = after.index_of(5).unwrap();
    assert!((after.tracks[k].times_s[25] - 6.0).abs() < 1e-6);
    s.command(Command::EditAccept);
    // With a selection: the selection is retimed.
    s.command(Command::EditSelect {
        lasso: None,
        window_s: None,
        ids: Some(vec![0, 11]),
    });
    let before = s.set();
    s.command(Command::EditRetime {
        at_s: 5.0,
        to_s: 4.5,
        ids: None,
    });
    assert_eq!(retimed(&before, &s.set()), BTreeSet::from([0, 11]));
    let e =
        s.e.command(
            &Command::EditRetime {
                at_s: 5.0,
                to_s: 4.5,
                ids: Some(vec![12345]),
            },
            Micros(s.now),
        )
        .unwrap_err();
    assert!(e.to_string().contains("no person has id 12345"), "{e}");
}

/// With `edit.preview: false` a release applies at once (no preview state).
#[test]
fn without_preview_a_release_applies_at_once() {
    let cfg = Config::from_str(
        &crowdtouch::config::DEFAULT_CONFIG_RON.replace(
            "    pipeline: (",
            "    edit: Some((preview: false)),\n    pipeline: (",
        ),
        Path::new("<test>"),
    )
    .expect("a config with edit.preview");
    assert!(!cfg.edit.as_ref().unwrap().preview);
    let mut s = Session::with(parade(2, 3), cfg, false);
    let t = s.play_t();
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    s.drag(1, held, Vec2::new(0.0, 0.5), &[]);
    s.touch(&[(1, held + Vec2::new(0.0, 0.5), UP)]);
    s.ticks(4);
    assert_eq!(s.view().state, "idle");
    assert!(s.view().preview.is_none());
    assert!(!s.tracks.last().unwrap().preview);
    assert_eq!(s.e.edits_applied(), 1);
}

/// With the jobs on a worker (as in the daemon): a finger landing while the
/// release settles is not dropped: it grabs when the result is back (and keeps
/// the preview: a new grab accepts it); a finger that lifted meanwhile grabs
/// nothing.
#[test]
fn a_touch_during_a_settling_release_is_grabbed_when_it_is_back() {
    let mut s = Session::with(parade(2, 3), Config::embedded_default(), true);
    let t = s.play_t();
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    s.run_jobs();
    s.drag(1, held, Vec2::new(0.0, 0.5), &[]);
    s.touch(&[(1, held + Vec2::new(0.0, 0.5), UP)]);
    s.ticks(2);
    assert_eq!(s.view().state, "settling", "the release is out");
    // A finger on the (moved) parade while it settles.
    let again = Vec2::new(2.0 + t, 2.5);
    s.touch(&[(2, again, DOWN)]);
    s.ticks(2);
    assert_eq!(s.view().state, "settling", "not grabbed yet, not dropped");
    s.run_jobs();
    let v = s.view().clone();
    assert_eq!(v.state, "grabbed", "grabbed when the release is back");
    assert!(v.preview.is_none(), "the new grab accepted the preview");
    assert_eq!(s.e.edits_applied(), 1);
    assert_eq!(v.undo_depth, 1);
    s.touch(&[(2, again, UP)]);
    s.ticks(2);
    s.run_jobs();
    assert_eq!(
        s.view().state,
        "idle",
        "a touch without a move changes nothing"
    );
    // A finger that lands and lifts while a release settles grabs nothing.
    s.touch(&[(3, again, DOWN)]);
    s.ticks(2);
    s.run_jobs();
    s.drag(3, again, Vec2::new(0.5, 0.0), &[]);
    s.touch(&[(3, again + Vec2::new(0.5, 0.0), UP)]);
    s.ticks(2);
    s.touch(&[(4, again, DOWN)]);
    s.ticks(2);
    s.touch(&[(4, again, UP)]);
    s.ticks(2);
    s.run_jobs();
    assert_eq!(
        s.view().state,
        "preview",
        "nothing grabbed by the lifted finger"
    );
}

/// A release keeps the dragged group out of the scene's obstacles (section 4.2):
/// a group dragged so that its tracks run through a block comes out of it (by
/// its cage, then sample by sample), and the preview names the people pushed.
#[test]
fn a_release_keeps_the_group_out_of_the_scenes_obstacles() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("scene.ron"),
        r#"(
    version: 1,
    name: "one block",
    bounds_m: (min: (0.0, 0.0), max: (16.0, 9.0)),
    obstacles: [
        (name: "block", parts: [
            Polygon(vertices_m: [(1.5, 4.2), (4.5, 4.2), (4.5, 5.2), (1.5, 5.2)]),
        ]),
    ],
)"#,
    )
    .unwrap();
    let cfg_path = dir.path().join("crowdtouch.ron");
    std::fs::write(
        &cfg_path,
        crowdtouch::config::DEFAULT_CONFIG_RON.replacen(
            "scene: None",
            "scene: Some(\"scene.ron\")",
            1,
        ),
    )
    .unwrap();
    let cfg = Config::load(&cfg_path).expect("a config with a scene");
    let obstacles = cfg.loaded_scene().expect("the scene").obstacles().to_vec();
    // A parade of 2 × 3 along y = 2.0 and 2.8, walking +x from x = 2 … 3.6:
    // dragged 2 m up where it starts, its tracks run through the block (x 1.5 …
    // 4.5, y 4.2 … 5.2; a drag is local, eq. 5).
    let mut s = Session::with(parade(2, 3), cfg, false);
    let before = s.set();
    let t = s.play_t();
    let held = Vec2::new(2.8 + t, 2.8);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(2);
    s.drag(1, held, Vec2::new(0.0, 2.0), &[]);
    let (dragged, people) = dragged_tracks(&s, &before);
    let group: Vec<usize> = people
        .iter()
        .map(|&id| dragged.index_of(id).unwrap())
        .collect();
    let inside_dragged: usize = samples_in_obstacles(&dragged, &group, &obstacles)
        .iter()
        .sum();
    assert!(
        inside_dragged > 10,
        "the drag put samples in the block: {inside_dragged}"
    );
    s.touch(&[(1, held + Vec2::new(0.0, 2.0), UP)]);
    s.ticks(4);
    let v = s.view().clone();
    let p = v.preview.expect("a preview");
    let after = s.set();
    let everyone: Vec<usize> = (0..after.tracks.len()).collect();
    let inside: usize = samples_in_obstacles(&after, &everyone, &obstacles)
        .iter()
        .sum();
    assert_eq!(inside, 0, "no sample left in the block");
    assert!(!p.pushed.is_empty(), "the preview names the people pushed");
    assert!(p.pushed.iter().all(|id| people.contains(id)));
}

/// A second control on a vertex of the grab's hull (away from anyone) pins the
/// vertex: the `edit` message shows it, and it stays where it was through the
/// rest of the drag.
#[test]
fn a_second_control_on_a_hull_vertex_pins_the_vertex() {
    let mut s = Session::new(parade(2, 3));
    let t = s.play_t();
    let held = Vec2::new(2.0 + t, 2.0);
    s.touch(&[(1, held, DOWN)]);
    s.ticks(12);
    s.drag(1, held, Vec2::new(0.0, 0.2), &[]);
    // The hull vertex farthest from the finger: the far end of the tracks.
    let hull = s.view().hull.clone();
    let v = *hull
        .iter()
        .max_by(|a, b| (*a - held).norm().total_cmp(&(*b - held).norm()))
        .unwrap();
    s.touch(&[(1, held + Vec2::new(0.0, 0.2), MOVE), (2, v, DOWN)]);
    s.ticks(3);
    s.drag(
        1,
        held + Vec2::new(0.0, 0.2),
        Vec2::new(0.0, 1.0),
        &[(2, v)],
    );
    let first = s.view().pins.clone();
    assert_eq!(first.len(), 1, "the vertex is pinned");
    s.drag(
        1,
        held + Vec2::new(0.0, 1.2),
        Vec2::new(-0.5, 0.5),
        &[(2, v)],
    );
    let then = s.view().pins.clone();
    assert_eq!(then.len(), 1);
    assert!(
        (then[0] - first[0]).norm() < 1e-9,
        "the pinned vertex stays: {:?} then {:?}",
        first[0],
        then[0]
    );
    assert!(
        (first[0] - v).norm() < 0.5,
        "near where the finger pinned it"
    );
}
