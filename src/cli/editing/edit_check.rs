//! `crowdtouch edit check`: people who come closer than a threshold in space-time
//! (crowd-motion-editing section 4.1.1), as text or one JSON object.
//!
//! Collisions are a finding, not a failure: the command exits 0 whether or not
//! there are any (1 only for an unreadable file or bad arguments). Scripts read
//! `pairs` from `--json`.
//!
//! Every colliding pair and event is counted; `--keep N` (default
//! [`DEFAULT_KEEP`]) bounds what is listed: the N closest pairs, the N earliest
//! events and the N largest clusters (people on one identical track, such as a
//! crowd standing at one point, one entry with its size instead of its pairs).

use crate::cli::common::output::outln;
use anyhow::{anyhow, Result};
use crowdtouch::crowd::edit::{detect_keeping, Collisions, Tracks, DEFAULT_KEEP};
use serde_json::json;

/// Events listed in the text report.
const EVENTS_SHOWN: usize = 10;

/// Cluster members listed by id in the reports (the size counts them all).
const CLUSTER_IDS_SHOWN: usize = 16;

/// Runs detection on a loaded track set, keeping `keep` pairs, events and
/// clusters (`None`: [`DEFAULT_KEEP`]), and prints the report.
pub fn run(
    set: &impl Tracks,
    file: &str,
    threshold_m: f64,
    keep: Option<usize>,
    as_json: bool,
) -> Result<()> {
    let c = detect_keeping(set, threshold_m, keep.unwrap_or(DEFAULT_KEEP))
        .map_err(|e| anyhow!("{file}: {e}"))?;
    if as_json {
        outln!("{}", report_json(set, &c))?;
    } else {
        report_text(set, file, &c)?;
    }
    Ok(())
}

fn report_json(set: &impl Tracks, c: &Collisions) -> serde_json::Value {
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
    let clusters: Vec<_> = c
        .clusters
        .iter()
        .map(|k| {
            let ids: Vec<u64> = k
                .members
                .iter()
                .take(CLUSTER_IDS_SHOWN)
                .map(|&m| set.track(m).id)
                .collect();
            json!({
                "kind": if k.identical { "identical" } else { "standing" },
                "size": k.size(),
                "pairs": k.pairs(),
                "ids": ids,
                "start_s": k.start_s,
                "end_s": k.end_s,
                "x": k.place.x,
                "y": k.place.y,
            })
        })
        .collect();
    json!({
        "people": set.people(),
        "samples": set.samples(),
        "start_s": t0,
        "end_s": t1,
        "step_s": set.step_s(),
        "threshold_m": c.threshold_m,
        "pairs": c.pair_total,
        "events_total": c.event_total,
        "clusters_total": c.cluster_total,
        "keep": c.keep,
        "min_distance_m": c.min_distance_m(),
        "events": events,
        "pair_list": pair_list,
        "clusters": clusters,
    })
}

fn report_text(set: &impl Tracks, file: &str, c: &Collisions) -> Result<()> {
    let (t0, t1) = set.span_s();
    outln!("{file}")?;
    outln!("  people              {}", set.people())?;
    outln!(
        "  samples             {} (step {} s)",
        set.samples(),
        set.step_s()
    )?;
    outln!(
        "  time                {t0:.2} – {t1:.2} s ({:.1} s)",
        t1 - t0
    )?;
    outln!(
        "  pairs in collision  {} closer than {} m ({} events{})",
        c.pair_total,
        c.threshold_m,
        c.event_total,
        if c.cluster_total > 0 {
            format!(", {} clusters", c.cluster_total)
        } else {
            String::new()
        }
    )?;
    if !c.clusters.is_empty() {
        outln!("  clusters (people on one track or standing together: every two collide)")?;
        for k in c.clusters.iter().take(EVENTS_SHOWN) {
            outln!(
                "    {:>7} people, {} pairs, {:.2} – {:.2} s at ({:.2}, {:.2}), first {}",
                k.size(),
                k.pairs(),
                k.start_s,
                k.end_s,
                k.place.x,
                k.place.y,
                k.first_id
            )?;
        }
        if c.cluster_total > EVENTS_SHOWN {
            outln!("    … {} more", c.cluster_total - EVENTS_SHOWN)?;
        }
    }
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
        if c.event_total > EVENTS_SHOWN as u64 {
            outln!(
                "    … {} more (--json lists the first {})",
                c.event_total - EVENTS_SHOWN as u64,
                c.events.len()
            )?;
        }
    }
    Ok(())
}
