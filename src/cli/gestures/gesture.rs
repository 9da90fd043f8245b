//! `crowdtouch gesture classify`: every gesture in recordings, recognised against a
//! gesture library (gesture-driven sections 5 and 7.1), one line each.

use crate::cli::common::output::outln;
use anyhow::{bail, Context, Result};
use crowdtouch::config::{load_recogniser, Config};
use crowdtouch::engine::{search_params, segment_params, tap_thresholds};
use crowdtouch::geom::Vec2;
use crowdtouch::gesture::find::{Found, GestureFinder};
use crowdtouch::gesture::knn::Searcher;
use crowdtouch::gesture::recognise::Recogniser;
use crowdtouch::input::recording::{OnBadFrame, RecordingStream};
use crowdtouch::vocab::Micros;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// `crowdtouch gesture` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum GestureCmd {
    /// Recognise every gesture in recordings (any format the project reads; every
    /// touch is treated as a gesture in open space): one line per gesture with the
    /// file, its start time, its fingers, the recognised class and its weight, and
    /// the K nearest library gestures. Taps and over-long gestures are listed with
    /// why they are not recognised.
    Classify {
        /// Gesture library (default: the config's, else the shipped one).
        #[arg(long)]
        library: Option<PathBuf>,
        /// Config whose `gestures` and `controls` sections to use (default: the
        /// search path, else the embedded default).
        #[arg(long)]
        config: Option<PathBuf>,
        /// One JSON object per line (`file`, `t_us`, `fingers`, `class`, `weight`,
        /// `neighbours`, or `rejected`).
        #[arg(long)]
        json: bool,
        /// Recordings.
        #[arg(required = true)]
        recordings: Vec<PathBuf>,
    },
}

/// Runs a `gesture` subcommand.
pub fn gesture(cmd: GestureCmd, cfg: &Config) -> Result<()> {
    match cmd {
        GestureCmd::Classify {
            library,
            json,
            recordings,
            ..
        } => {
            let rec = recogniser(cfg, library.as_deref())?;
            classify(cfg, &rec, &recordings, json)
        }
    }
}

/// The library to recognise with: `explicit`, else the config's, else the shipped.
pub fn recogniser(cfg: &Config, explicit: Option<&Path>) -> Result<Arc<Recogniser>> {
    let path = explicit.or(cfg.gestures.library.as_deref());
    if path.is_none() {
        if let Some(r) = cfg.gesture_recogniser() {
            return Ok(Arc::clone(r));
        }
    }
    load_recogniser(path, cfg.gestures.band, cfg.gestures.collected).map_err(anyhow::Error::msg)
}

/// The gestures of one recording, read a frame at a time, cut as the daemon cuts
/// them (`gesture::find`), on the recording's glass (its size in mm, else the
/// config's `surface.size_mm`).
pub fn gestures_in(path: &Path, cfg: &Config) -> Result<Vec<Found>> {
    let mut stream = RecordingStream::load(path, OnBadFrame::Stop)
        .with_context(|| format!("{}: cannot read recording", path.display()))?;
    let glass = match stream.surface().size_mm().or(cfg.surface.size_mm) {
        Some((w, h)) => Vec2::new(w, h),
        None => bail!(
            "{}: the recording does not say how large its surface is (no axis \
             resolution); give a config with `surface.size_mm`",
            path.display()
        ),
    };
    // A frame at a time: a recording of any length in the same memory.
    let mut finder = GestureFinder::new(glass, segment_params(cfg), tap_thresholds(cfg));
    let mut last = Micros::ZERO;
    while let Some(f) = stream
        .next_frame()
        .with_context(|| format!("{}: bad recording", path.display()))?
    {
        finder.frame(f);
        last = f.t;
    }
    finder.finish(last);
    Ok(finder.take())
}

fn classify(cfg: &Config, rec: &Recogniser, files: &[PathBuf], json: bool) -> Result<()> {
    let params = search_params(cfg);
    let mut searcher = Searcher::new();
    for file in files {
        let found = gestures_in(file, cfg)?;
        let name = file.display().to_string();
        if found.is_empty() && !json {
            outln!("{name}: no gesture")?;
        }
        for g in found {
            let r = match &g.tracks {
                Ok(tracks) => rec
                    .recognise(tracks, &params, &mut searcher)
                    .map_err(|e| e.to_string()),
                Err(why) => Err(why.to_string()),
            };
            let t_us = g.t.0;
            match (r, json) {
                (Ok(r), true) => {
                    let neighbours: Vec<_> = r
                        .neighbours
                        .iter()
                        .map(|n| {
                            let lg = &rec.library().gestures[n.entry];
                            json!({"class": rec.class_name(lg.class), "distance": n.distance,
                                   "weight": n.weight, "origin": lg.origin})
                        })
                        .collect();
                    outln!(
                        "{}",
                        json!({"file": name, "t_us": t_us, "fingers": g.fingers,
                               "class": rec.class_name(r.class), "weight": r.weight,
                               "neighbours": neighbours})
                    )?;
                }
                (Ok(r), false) => {
                    let near: Vec<String> = r
                        .neighbours
                        .iter()
                        .map(|n| {
                            format!(
                                "{} {:.3} ({:.2})",
                                rec.class_name(rec.class_of(n.entry)),
                                n.distance,
                                n.weight
                            )
                        })
                        .collect();
                    outln!(
                        "{name} t={:.3}s fingers={} class={} weight={:.2} neighbours: {}",
                        t_us as f64 * 1e-6,
                        g.fingers,
                        rec.class_name(r.class),
                        r.weight,
                        near.join(", ")
                    )?;
                }
                (Err(why), true) => outln!(
                    "{}",
                    json!({"file": name, "t_us": t_us, "fingers": g.fingers,
                           "class": null, "weight": 0.0, "rejected": why})
                )?,
                (Err(why), false) => outln!(
                    "{name} t={:.3}s fingers={} not recognised: {why}",
                    t_us as f64 * 1e-6,
                    g.fingers
                )?,
            }
        }
    }
    Ok(())
}
