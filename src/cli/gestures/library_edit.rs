//! The `library` commands that change a library of one's own: `new`,
//! `import-motion` (a crowd motion from a track file), `remove` (a class) and `add`
//! (a person's gestures from recordings, each paired with a motion of its class).

use super::classes::class_of;
use super::gesture::gestures_in;
use super::library_file::{load_with, save};
use crate::cli::common::output::outln;
use anyhow::{anyhow, bail, Context, Result};
use crowdtouch::config::Config;
use crowdtouch::crowd::edit::io::{read_tracks, ReadOptions};
use crowdtouch::crowd::motion::{import_motion, FeatureParams, ImportWindow, PersonSamples};
use crowdtouch::engine::search_params;
use crowdtouch::gesture::dtw::{gesture_distance, Dtw};
use crowdtouch::gesture::features::GestureFeatures;
use crowdtouch::gesture::library::{
    check_class_name, ClassId, Library, LibraryGesture, LoadPolicy, MAX_CLASSES,
};
use crowdtouch::gesture::resample::prepare_scaled;
use crowdtouch::input::recording::{OnBadFrame, RecordingStream};
use std::path::{Path, PathBuf};

pub fn new(out: &Path, classes: Vec<String>, force: bool) -> Result<()> {
    if out.exists() && !force {
        bail!("{}: exists; give --force to replace it", out.display());
    }
    let lib = Library::with_classes(classes);
    if lib.classes.len() > MAX_CLASSES {
        bail!(
            "{} classes; a library holds at most {MAX_CLASSES}",
            lib.classes.len()
        );
    }
    save(&lib, out)?;
    outln!(
        "{}: a new library of {} class{}{}{}",
        out.display(),
        lib.classes.len(),
        if lib.classes.len() == 1 { "" } else { "es" },
        if lib.classes.is_empty() { "" } else { ": " },
        lib.classes.join(", ")
    )?;
    Ok(())
}

pub fn remove(library: Option<&Path>, class: &str, out: &Path) -> Result<()> {
    let mut lib = load_with(library, LoadPolicy::Partial)?;
    let id = class_of(&lib, class)?;
    let c = lib.counts()[id.index()];
    lib.remove_class(id);
    let bytes = save(&lib, out)?;
    outln!(
        "{}: class {class} removed with {} motions and {} gestures; {} classes, {} motions, {} gestures, {bytes} bytes",
        out.display(),
        c.motions,
        c.gestures,
        lib.classes.len(),
        lib.motions.len(),
        lib.gestures.len()
    )?;
    Ok(())
}

pub fn import(
    library: Option<&Path>,
    class: &str,
    tracks: &Path,
    window: &ImportWindow,
    fp: &FeatureParams,
    out: &Path,
) -> Result<()> {
    check_class_name(class).with_context(|| format!("--class {class:?}"))?;
    let mut lib = load_with(library, LoadPolicy::Partial)?;
    let (set, format) = read_tracks(tracks, None, &ReadOptions::default())
        .map_err(|e| anyhow!("cannot read tracks: {e}"))?;
    let people: Vec<PersonSamples<'_>> = set
        .tracks
        .iter()
        .map(|t| PersonSamples {
            id: t.id,
            times_s: &t.times_s,
            points: &t.points,
            linked: &t.linked,
        })
        .collect();
    let (id, added) = match lib.class_id(class) {
        Some(id) => (id, false),
        None => {
            if lib.classes.len() >= MAX_CLASSES {
                bail!("the library holds {MAX_CLASSES} classes already");
            }
            lib.classes.push(class.to_string());
            (ClassId((lib.classes.len() - 1) as u16), true)
        }
    };
    let m = import_motion(&people, set.step_s, window, id, fp)
        .with_context(|| format!("{}: no crowd motion", tracks.display()))?;
    let index = lib.motions.len();
    lib.motions.push(m.features);
    let bytes = save(&lib, out)?;
    outln!(
        "{}: motion {index} of class {class}{}: {} people of {} ({:?}) from {:.2} s to {:.2} s; {} classes, {} motions, {} gestures, {bytes} bytes",
        out.display(),
        if added { " (a new class)" } else { "" },
        m.people.len(),
        tracks.display(),
        format,
        m.from_s,
        m.to_s,
        lib.classes.len(),
        lib.motions.len(),
        lib.gestures.len()
    )?;
    Ok(())
}

pub fn add(
    cfg: &Config,
    library: Option<&Path>,
    name: &str,
    motion: Option<u32>,
    out: &Path,
    files: &[PathBuf],
    (participant, device): (Option<String>, Option<String>),
) -> Result<()> {
    let mut lib = load_with(library, LoadPolicy::Partial)?;
    let class = class_of(&lib, name)?;
    let participant = participant.unwrap_or_default();
    let mut added = 0;
    for f in files {
        let device = match &device {
            Some(d) => d.clone(),
            None => RecordingStream::load(f, OnBadFrame::Stop)
                .with_context(|| format!("{}: cannot read recording", f.display()))?
                .surface()
                .name
                .clone(),
        };
        for g in gestures_in(f, cfg)? {
            let tracks = match g.tracks {
                Ok(t) => t,
                Err(why) => {
                    outln!(
                        "{}: gesture at {:.3} s skipped: {why}",
                        f.display(),
                        g.t.as_secs_f64()
                    )?;
                    continue;
                }
            };
            let (gesture, scale_mm) = prepare_scaled(&tracks).with_context(|| {
                format!("{}: gesture at {:.3} s", f.display(), g.t.as_secs_f64())
            })?;
            let motion = match motion {
                Some(m) => match lib.motions.get(m as usize) {
                    Some(mf) if mf.class == class => m,
                    Some(mf) => bail!(
                        "motion {m} is a {} motion, not {name}",
                        lib.class_name(mf.class)
                    ),
                    None => bail!("motion {m}: the library has {} motions", lib.motions.len()),
                },
                None => nearest_motion(&lib, class, &GestureFeatures::of(&gesture), cfg)?,
            };
            lib.gestures.push(LibraryGesture {
                class,
                motion,
                gesture,
                origin: format!("recording {} t={:.3}s", f.display(), g.t.as_secs_f64()),
                participant: participant.clone(),
                device: device.clone(),
                scale_mm: Some(scale_mm),
            });
            added += 1;
        }
    }
    save(&lib, out)?;
    outln!(
        "{}: {added} {name} gestures added; {} gestures, {} motions",
        out.display(),
        lib.gestures.len(),
        lib.motions.len()
    )?;
    Ok(())
}

/// The motion of `class` whose library gestures are nearest to `f` (eq. 12).
fn nearest_motion(lib: &Library, class: ClassId, f: &GestureFeatures, cfg: &Config) -> Result<u32> {
    // The nearest library gesture of the class (eq. 12; the first of equals).
    let p = search_params(cfg);
    let mut dtw = Dtw::new();
    let mut best: Option<(f64, u32)> = None;
    for g in lib.gestures.iter().filter(|g| g.class == class) {
        let d = gesture_distance(
            &mut dtw,
            f,
            &GestureFeatures::of(&g.gesture),
            &p.weights,
            p.band,
        );
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, g.motion));
        }
    }
    match (best, lib.motions.iter().position(|m| m.class == class)) {
        (Some((_, motion)), _) => Ok(motion),
        (None, Some(m)) => Ok(m as u32),
        (None, None) => bail!(
            "the library has no {} motion to pair the gesture with (import one with `library import-motion --class {}`)",
            lib.class_name(class),
            lib.class_name(class)
        ),
    }
}
