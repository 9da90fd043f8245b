//! `crowdtouch edit check`: people who come closer than a threshold in space-time
//! (crowd-motion-editing section 4.1.1), as text or one JSON object.
//!
//! Collisions are a finding, not a failure: the command exits 0 whether or not
//! there are any (1 only for an unreadable file or bad arguments). Scripts read
//! `pairs` from `--json`.

use crate::cli::output::outln;
use anyhow::{anyhow, Result};
use crowdtouch::crowd::edit::{detect, Collisions, TrackSet};
use serde_json::json;

/// Events listed in the text report.
const EVENTS_SHOWN: usize = 10;

/// Runs detection on a loaded track set and prints the report.
pub fn run(set: &TrackSet, file: &str, threshold_m: f64, as_json: bool) -> Result<()> {
    let c = detect(set, threshold_m).map_err(|e| anyhow!("{file}: {e}"))?;
    if as_json {
        outln!("{}", report_json(set, &c))?;
    } else {
        report_text(set, file, &c)?;
    }
    Ok(())
}

fn report_json(set: &TrackSet, c: &Collisions) -> serde_json::Value {
    let (t0, t1) = set.span_s();
    let events: Vec<_> = c
        .events_by_time()
        .iter()
        .map(|e| {
            let p = e.closest.place();
            json!({
                "a": e.id_a,
                "b": e.id_b,
                "t_s": e.closest.t_s,
                "x": p.x,
                "y": p.y,
                "distance_m": e.closest.distance_m,
                "start_s": e.start_s,
                "end_s": e.end_s,
            })
        })
        .collect();
    let pair_list: Vec<_> = c
        .pairs
        .iter()
        .map(|p| {
            json!({
                "a": p.id_a,
                "b": p.id_b,
                "min_distance_m": p.closest.distance_m,
                "t_s": p.closest.t_s,
                "events": p.events,
            })
        })
        .collect();
    json!({
        "people": set.tracks.len(),
        "samples": set.samples(),
        "start_s": t0,
        "end_s": t1,
        "step_s": set.step_s,
        "threshold_m": c.threshold_m,
        "pairs": c.pair_count(),
        "min_distance_m": c.min_distance_m(),
        "events": events,
        "pair_list": pair_list,
    })
}

fn report_text(set: &TrackSet, file: &str, c: &Collisions) -> Result<()> {
    let (t0, t1) = set.span_s();
    outln!("{file}")?;
    outln!("  people              {}", set.tracks.len())?;
    outln!(
        "  samples             {} (step {} s)",
        set.samples(),
        set.step_s
    )?;
    outln!(
        "  time                {t0:.2} – {t1:.2} s ({:.1} s)",
        t1 - t0
    )?;
    outln!(
        "  pairs in collision  {} closer than {} m ({} events)",
        c.pair_count(),
        c.threshold_m,
        c.events.len()
    )?;
    match c.closest() {
        Some(p) => {
            let a = &p.closest;
            let at = a.place();
            outln!(
                "  closest approach    {:.3} m: {} and {} at {:.2} s, ({:.2}, {:.2})",
                a.distance_m,
                p.id_a,
                p.id_b,
                a.t_s,
                at.x,
                at.y
            )?;
        }
        None => outln!(
            "  closest approach    no pair closer than {} m",
            c.threshold_m
        )?,
    }
    let events = c.events_by_time();
    if !events.is_empty() {
        outln!("  first events (time, people, place, distance)")?;
        for e in events.iter().take(EVENTS_SHOWN) {
            let at = e.closest.place();
            outln!(
                "    {:>9.2} s  {:>5} {:>5}  ({:.2}, {:.2})  {:.3} m",
                e.closest.t_s,
                e.id_a,
                e.id_b,
                at.x,
                at.y,
                e.closest.distance_m
            )?;
        }
        if events.len() > EVENTS_SHOWN {
            outln!(
                "    … {} more (--json lists all)",
                events.len() - EVENTS_SHOWN
            )?;
        }
    }
    Ok(())
}
