//! How long the edit mode's work off the control thread takes on a real file: the
//! jobs a person at the table causes, run as the daemon's formation thread runs
//! them (`EditJob::run`), timed one by one (docs/motion-editing.md, "On the
//! table").
//!
//! `cargo run --release --example edit_table_costs [-- TRACKS [ROUNDS]]`
//!
//! TRACKS defaults to `tests/fixtures/crowd/students001.txt` (ETH/UCY, 415
//! people), ROUNDS to 5. Each round loads the tracks, grabs the first person on
//! the table at the play time and drags them 1.5 m in ten steps, lifts (the
//! release: speeds, obstacles, collisions the drag brought, the preview), makes
//! two selections by lasso (one over half the table, one around nothing), and
//! retimes three people. Prints each job's milliseconds per round.

use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{read_tracks, ReadOptions};
use crowdtouch::engine::Engine;
use crowdtouch::geom::Vec2;
use crowdtouch::vocab::{Command, Contact, ContactFlags, ContactId, Micros, TouchFrame};
use std::path::PathBuf;
use std::time::Instant;

const TICK_US: u64 = 16_667;

/// Runs every waiting job, timing each under `label` (ms).
fn run(e: &mut Engine, now: u64, label: &'static str, times: &mut Vec<(&'static str, f64)>) {
    while let Some(j) = e.take_edit_job() {
        let t0 = Instant::now();
        let done = j.run();
        times.push((label, t0.elapsed().as_secs_f64() * 1e3));
        e.apply_edit(done, Micros(now));
    }
}

/// One finger at world `p` (the default world is 16 × 9 m on the unit square).
fn frame(t: u64, p: Vec2, flags: ContactFlags) -> TouchFrame {
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
    .expect("one contact fits");
    f
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/crowd/students001.txt"),
        PathBuf::from,
    );
    let rounds: usize = args.next().map_or(Ok(5), |r| r.parse())?;
    let (set, _) = read_tracks(&path, None, &ReadOptions::default())?;
    println!(
        "{}: {} people, {} samples",
        path.display(),
        set.tracks.len(),
        set.samples()
    );
    for round in 0..rounds {
        let cfg = Config::embedded_default();
        let mut e = Engine::new(&cfg, None, false);
        e.set_switch_worker(true);
        let mut now = TICK_US;
        let mut times = Vec::new();
        e.tick(Micros(now));
        e.load_tracks(set.clone(), "tracks", Micros(now));
        e.command(&Command::Pause, Micros(now))?;
        now += TICK_US;
        e.tick(Micros(now));
        run(&mut e, now, "check", &mut times);
        let t = e.edit_play_t_s().ok_or("not editing")?;
        let at = set
            .tracks
            .iter()
            .filter_map(|tr| tr.position_at(t))
            .find(|p| p.x > 1.0 && p.y > 1.0 && p.x < 13.0 && p.y < 8.0)
            .ok_or("no one on the table at the play time")?;
        e.push_frame(&frame(now + 1, at, ContactFlags::DOWN));
        for k in 1..=10 {
            now += TICK_US;
            let p = at + Vec2::new(0.15 * k as f64, 0.0);
            e.push_frame(&frame(now, p, ContactFlags::NONE));
            e.tick(Micros(now));
            e.clear_events();
            run(
                &mut e,
                now,
                if k == 1 { "first drag" } else { "drag" },
                &mut times,
            );
        }
        now += TICK_US;
        e.push_frame(&frame(now, at + Vec2::new(1.5, 0.0), ContactFlags::UP));
        for _ in 0..3 {
            now += TICK_US;
            e.tick(Micros(now));
            e.clear_events();
        }
        run(&mut e, now, "release", &mut times);
        e.command(&Command::EditAccept, Micros(now))?;
        for (label, lasso) in [
            (
                "select half",
                [[0.0, 0.0], [8.0, 0.0], [8.0, 9.0], [0.0, 9.0]],
            ),
            (
                "select none",
                [
                    [-50.0, -50.0],
                    [-49.0, -50.0],
                    [-49.0, -49.0],
                    [-50.0, -49.0],
                ],
            ),
        ] {
            let select = Command::EditSelect {
                lasso: Some(lasso.to_vec()),
                window_s: None,
                ids: None,
            };
            e.command(&select, Micros(now))?;
            now += TICK_US;
            e.tick(Micros(now));
            e.clear_events();
            run(&mut e, now, label, &mut times);
        }
        let clear = Command::EditSelect {
            lasso: None,
            window_s: None,
            ids: None,
        };
        e.command(&clear, Micros(now))?;
        let three: Vec<_> = set
            .tracks
            .iter()
            .filter(|t| t.len() >= 40)
            .take(3)
            .collect();
        let mid = three.first().map_or(0.0, |t| t.times_s[t.len() / 2]);
        let retime = Command::EditRetime {
            at_s: mid,
            to_s: mid + 1.0,
            ids: Some(three.iter().map(|t| t.id).collect()),
        };
        e.command(&retime, Micros(now))?;
        now += TICK_US;
        e.tick(Micros(now));
        e.clear_events();
        run(&mut e, now, "retime 3 people", &mut times);
        let line: Vec<String> = times.iter().map(|(l, ms)| format!("{l} {ms:.2}")).collect();
        println!("round {round} (ms): {}", line.join(", "));
    }
    Ok(())
}
