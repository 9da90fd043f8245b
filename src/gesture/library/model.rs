//! The library's data: gestures paired with crowd motions (gesture-driven section 4),
//! each crowd motion kept as its features (section 6.2, eq. 17).
//!
//! Plain data, shared by the file format (`format.rs`), recognition (which indexes
//! the gestures' features) and the crowd's synthesis (`crowd::motion`, which blends
//! the motions' features).
//!
//! The classes are data too: [`Library::classes`] names them (any non-empty set,
//! unique names), and every motion and gesture is of one of them ([`ClassId`]).

use super::class::{ClassId, MotionClass};
use crate::geom::Vec2;

/// Samples of a resampled gesture trajectory, `T_H` (gesture-driven section 5.1).
pub const T_H: usize = 64;

/// Samples of a resampled crowd trajectory, `S_H` (gesture-driven section 6.1).
pub const S_H: usize = 64;

/// Length of a serialised crowd trajectory: x and y of each sample (eq. 15).
pub const TRAJ_DIM: usize = 2 * S_H;

/// Most eigenvectors a motion keeps (section 6.2: "the first 15 principal components").
pub const MAX_COMPONENTS: usize = 15;

/// A gesture normalised (eq. 2: translated so its minimum x and y are 0, scaled by
/// `1 / max(d_v, d_h)` of its extent in millimetres of glass) and resampled to
/// [`T_H`] samples per finger (eq. 3).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Resampled {
    /// One trajectory per finger, every point in `[0, 1]²`.
    pub fingers: Vec<[Vec2; T_H]>,
}

/// One Gaussian of a mixture over eigenscores (section 6.2).
#[derive(Clone, Debug, PartialEq)]
pub struct GmmComponent {
    /// Mixing weight (the weights of a mixture sum to 1).
    pub weight: f64,
    /// Mean eigenscore, one value per kept eigenvector.
    pub mean: Vec<f64>,
    /// Covariance, `d × d` row-major (symmetric positive definite).
    pub cov: Vec<f64>,
}

/// A crowd motion's features, `C = [c̄_s, E_V, φ(E_S)]` (gesture-driven eq. 17).
///
/// Trajectories are in *crowd units*: the motion is translated so that the crowd's
/// starting centroid is at the origin and scaled so that the crowd's starting RMS
/// radius is 1; synthesis scales them to the crowd it drives.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionFeatures {
    /// The class the motion belongs to.
    pub class: ClassId,
    /// How long the motion lasts (s), from its first to its last sample.
    pub duration_s: f64,
    /// The mean trajectory `c̄_s`, serialised as in eq. 15 (x, y per sample).
    pub mean: Vec<f64>,
    /// The eigenvectors `E_V` (at most [`MAX_COMPONENTS`]), each [`TRAJ_DIM`] long,
    /// orthonormal.
    pub basis: Vec<Vec<f64>>,
    /// The distribution of the eigenscores `φ(E_S)`: a Gaussian mixture over
    /// `basis.len()` dimensions.
    pub gmm: Vec<GmmComponent>,
}

/// A gesture in the library and the crowd motion it asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct LibraryGesture {
    /// The class of its crowd motion.
    pub class: ClassId,
    /// Index of its crowd motion in [`Library::motions`].
    pub motion: u32,
    /// The gesture, normalised and resampled.
    pub gesture: Resampled,
    /// Where it came from (`generated seed 7`, `recording twist-1.jsonl`, …).
    pub origin: String,
    /// Who drew it (a participant id, for leave-one-participant-out evaluation);
    /// empty when not known (generated gestures, version-1 files).
    pub participant: String,
    /// The device it was drawn on (its name as the recording or the daemon gives
    /// it); empty when not known.
    pub device: String,
    /// Eq. 2's scale: the larger side of the gesture's bounding box on the glass
    /// (mm), which the physical features need (`gesture::physical`); `None` when
    /// unknown (a file of format version 1).
    pub scale_mm: Option<f64>,
}

/// Longest participant id, bytes of UTF-8.
pub const MAX_PARTICIPANT_BYTES: usize = 64;

/// Longest device name, bytes of UTF-8.
pub const MAX_DEVICE_BYTES: usize = 256;

/// The gesture/crowd-motion library (gesture-driven section 4).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Library {
    /// The class names, in the order of their [`ClassId`]s.
    pub classes: Vec<String>,
    /// The crowd motions.
    pub motions: Vec<MotionFeatures>,
    /// The gestures, each naming its motion.
    pub gestures: Vec<LibraryGesture>,
}

/// How many motions and gestures one class has.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct ClassCounts {
    /// Crowd motions of the class.
    pub motions: usize,
    /// Gestures of the class.
    pub gestures: usize,
}

impl Library {
    /// Leaves out the generated gestures (no participant) of every class that has
    /// gestures drawn by people, so those classes are recognised from people's
    /// gestures alone and the others from the generated ones (`gestures.collected:
    /// Replace`). Returns how many were left out.
    pub fn keep_collected_where_drawn(&mut self) -> usize {
        let drawn: Vec<ClassId> = {
            let mut c: Vec<ClassId> = self
                .gestures
                .iter()
                .filter(|g| !g.participant.is_empty())
                .map(|g| g.class)
                .collect();
            c.sort_unstable();
            c.dedup();
            c
        };
        let before = self.gestures.len();
        self.gestures
            .retain(|g| !g.participant.is_empty() || !drawn.contains(&g.class));
        before - self.gestures.len()
    }

    /// An empty library with these classes (no motion, no gesture).
    pub fn with_classes(classes: Vec<String>) -> Library {
        Library {
            classes,
            ..Library::default()
        }
    }

    /// The name of class `id`; `?` for an id the table does not hold (a library
    /// that passed validation has none).
    pub fn class_name(&self, id: ClassId) -> &str {
        self.classes.get(id.index()).map_or("?", String::as_str)
    }

    /// The class called `name`.
    pub fn class_id(&self, name: &str) -> Option<ClassId> {
        self.classes
            .iter()
            .position(|c| c == name)
            .and_then(|i| u16::try_from(i).ok())
            .map(ClassId)
    }

    /// The built-in motion kind class `id` is named after, if any.
    pub fn kind(&self, id: ClassId) -> Option<MotionClass> {
        self.class_name(id).parse().ok()
    }

    /// Every class's motions and gestures, in class order.
    pub fn counts(&self) -> Vec<ClassCounts> {
        let mut out = vec![ClassCounts::default(); self.classes.len()];
        for m in &self.motions {
            if let Some(c) = out.get_mut(m.class.index()) {
                c.motions += 1;
            }
        }
        for g in &self.gestures {
            if let Some(c) = out.get_mut(g.class.index()) {
                c.gestures += 1;
            }
        }
        out
    }

    /// Removes class `id` with its motions and gestures; the classes after it and
    /// the motions after removed ones are renumbered.
    pub fn remove_class(&mut self, id: ClassId) {
        if id.index() >= self.classes.len() {
            return;
        }
        self.classes.remove(id.index());
        let shift = |c: ClassId| {
            if c > id {
                ClassId(c.0 - 1)
            } else {
                c
            }
        };
        // The new index of each kept motion.
        let mut renumber = Vec::with_capacity(self.motions.len());
        let mut kept = 0u32;
        for m in &self.motions {
            renumber.push((m.class != id).then_some(kept));
            kept += u32::from(m.class != id);
        }
        self.motions.retain(|m| m.class != id);
        for m in &mut self.motions {
            m.class = shift(m.class);
        }
        self.gestures.retain(|g| g.class != id);
        for g in &mut self.gestures {
            g.class = shift(g.class);
            // A kept gesture's motion is of its class, so it was kept.
            if let Some(Some(k)) = renumber.get(g.motion as usize) {
                g.motion = *k;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gesture(class: u16, participant: &str) -> LibraryGesture {
        LibraryGesture {
            class: ClassId(class),
            motion: 0,
            gesture: Resampled::default(),
            origin: String::new(),
            participant: participant.into(),
            device: String::new(),
            scale_mm: None,
        }
    }

    #[test]
    fn only_generated_gestures_of_classes_people_drew_are_left_out() {
        let mut lib = Library::with_classes(vec!["a".into(), "b".into(), "c".into()]);
        lib.gestures = vec![
            gesture(0, ""),
            gesture(0, "p1"),
            gesture(1, ""),
            gesture(1, ""),
            gesture(2, "p2"),
            gesture(0, ""),
        ];
        assert_eq!(lib.keep_collected_where_drawn(), 2);
        let left: Vec<(u16, &str)> = lib
            .gestures
            .iter()
            .map(|g| (g.class.0, g.participant.as_str()))
            .collect();
        assert_eq!(left, vec![(0, "p1"), (1, ""), (1, ""), (2, "p2")]);
        assert_eq!(lib.keep_collected_where_drawn(), 0);
    }
}
