//! The slow work of a `library collect` session (see `collect.rs`), run on the
//! formation thread or, in replays, in the tick: a motion synthesised for the crowd
//! to show it, a gesture added to the library and the library saved, the last one
//! removed again.

use super::collect_state::{CollectDone, CollectDoneKind, CollectJob, CollectJobKind, Collector};
use crate::crowd::motion::{play_duration, Placement, Synthesiser};
use crate::gesture::library::{
    read_library_with, validate_with, write_library, LibraryGesture, LoadPolicy,
};
use crate::gesture::resample::prepare_scaled;

impl CollectJob {
    /// Does the slow work; the collector comes back in the result whatever happens.
    pub fn run(self) -> CollectDone {
        let CollectJob {
            mut collector,
            kind,
        } = self;
        let kind = match kind {
            CollectJobKind::Show {
                item,
                motion,
                agents,
                speed_m_s,
                seed,
            } => {
                let synthesis = show(&collector, motion, &agents, speed_m_s, seed);
                CollectDoneKind::Shown { item, synthesis }
            }
            CollectJobKind::Save {
                item,
                motion,
                tracks,
                participant,
                device,
            } => {
                let result = record(&mut collector, motion, &tracks, participant, device);
                CollectDoneKind::Saved { item, result }
            }
            CollectJobKind::Undo { item, gesture } => {
                let result = undo(&mut collector, gesture);
                CollectDoneKind::Undone { item, result }
            }
        };
        CollectDone { collector, kind }
    }
}

/// Library motion `motion` synthesised for `agents` (gesture-driven eq. 16, as a
/// recognised gesture's motion is, without the blend: one library motion).
fn show(
    c: &Collector,
    motion: usize,
    agents: &[crate::geom::Vec2],
    speed_m_s: f64,
    seed: u64,
) -> Result<crate::crowd::motion::Synthesis, String> {
    let features = c
        .library
        .motions
        .get(motion)
        .ok_or_else(|| format!("the library has no motion {motion}"))?;
    let placement = Placement::for_crowd(agents);
    let mut s = Synthesiser::new()
        .synthesise(features, agents, &placement, seed)
        .map_err(|e| e.to_string())?;
    s.duration_s = play_duration(&s, speed_m_s);
    Ok(s)
}

/// Adds the gesture drawn for motion `motion` and saves the library; on any
/// failure the library in memory is as before.
fn record(
    c: &mut Collector,
    motion: usize,
    tracks: &crate::gesture::track::GestureTracks,
    participant: String,
    device: String,
) -> Result<usize, String> {
    let class = c
        .library
        .motions
        .get(motion)
        .map(|m| m.class)
        .ok_or_else(|| format!("the library has no motion {motion}"))?;
    let (gesture, scale_mm) = prepare_scaled(tracks).map_err(|e| e.to_string())?;
    let n = c
        .library
        .gestures
        .iter()
        .filter(|g| g.motion as usize == motion && g.participant == participant)
        .count();
    c.library.gestures.push(LibraryGesture {
        class,
        motion: motion as u32,
        gesture,
        origin: format!("collected from {participant}, motion {motion} #{}", n + 1),
        participant,
        device,
        scale_mm: Some(scale_mm),
    });
    match save(c) {
        Ok(()) => Ok(c.library.gestures.len() - 1),
        Err(e) => {
            c.library.gestures.pop();
            Err(e)
        }
    }
}

/// Removes gesture `gesture` and saves; on failure it is put back.
fn undo(c: &mut Collector, gesture: usize) -> Result<(), String> {
    if gesture >= c.library.gestures.len() {
        return Err(format!("the library has no gesture {gesture}"));
    }
    let g = c.library.gestures.remove(gesture);
    save(c).inspect_err(|_| c.library.gestures.insert(gesture, g))
}

/// Writes the library whole beside its path and renames it into place (a reader,
/// or a session stopped half-way, never sees half a file); the bytes are read
/// back before they are written.
fn save(c: &Collector) -> Result<(), String> {
    let shown = c.path.display().to_string();
    validate_with(&c.library, LoadPolicy::Partial).map_err(|e| e.to_string())?;
    let bytes = write_library(&c.library);
    read_library_with(&bytes, &shown, LoadPolicy::Partial).map_err(|e| e.to_string())?;
    crate::located::place(&bytes, &c.path, true).map_err(|e| format!("{shown}: cannot write: {e}"))
}
