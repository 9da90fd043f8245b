//! Building a gesture library (gesture-driven section 4) from our own data: crowd
//! motions from the simulator ([`library_specs`], [`simulate`]) turned into their
//! features ([`features`], eq. 17), each paired with gestures from the generator of
//! human-like multi-touch gestures ([`crate::gesture::synth`], and in turn the
//! independently written [`crate::gesture::style2`]), drawn *for that
//! motion*: the way the paper's participants watched a motion and drew a gesture
//! for it, the generator is pointed the way the motion goes.
//!
//! How a gesture is pointed at its motion (the glass and the world share their
//! axes: x right, y down the table):
//!
//! | class | the gesture takes from the motion |
//! |---|---|
//! | translate | its direction: the crowd centroid's shift |
//! | twist, twist while expanding/contracting | its turning sense: the sign of the crowd's rotation |
//! | join, translate then join | its axis: group 0's starting centroid to group 1's |
//! | split, split then translate | its axis: group 0's final centroid to group 1's |
//! | split then translate, translate then join | the axis is flipped so that the hands' common travel (across the axis) goes the crowd's way |
//! | contract, expand | nothing (no direction) |
//!
//! Everything else of a gesture's style (fingers, size, speed, place, device, jitter,
//! stagger, early lifts, bow) is drawn at random from [`StyleRanges`], so the
//! library holds the variety people bring.

use super::crowd_motion::CrowdMotion;
use super::error::MotionError;
use super::features::{features, FeatureParams};
use super::simulate::{library_specs, measure, simulate, MotionSpec, SimulateError};
use crate::crowd::agents::AgentParams;
use crate::geom::{cross, Vec2};
use crate::gesture::error::GestureError;
use crate::gesture::generator::Generator;
use crate::gesture::library::{ClassId, Library, LibraryGesture, MotionClass};
use crate::gesture::resample::prepare_scaled;
use crate::gesture::style2::{self, Aim};
use crate::gesture::synth::{generate, GestureStyle, StyleRanges};
use crate::rng::SplitMix64;

/// What a library is built from.
#[derive(Clone, Debug)]
pub struct BuildParams {
    /// Seed of everything random (the motions, the styles, the gestures).
    pub seed: u64,
    /// Crowd motions per class (the paper: 150 motions over 10 classes, 15 each).
    pub motions_per_class: usize,
    /// Gestures drawn for each motion.
    pub gestures_per_motion: usize,
    /// The classes to build (all ten by default), in the order of the library's
    /// class table.
    pub classes: Vec<MotionClass>,
    /// FPCA and mixture settings of the motions' features.
    pub features: FeatureParams,
    /// The ranges gesture styles are drawn from (`synth`).
    pub styles: StyleRanges,
    /// The gesture generators, taken in turn gesture by gesture (the shipped
    /// library: `synth`, then `style2`).
    pub generators: Vec<Generator>,
    /// The simulated agents.
    pub agents: AgentParams,
    /// The simulator's time step (s).
    pub dt_s: f64,
}

/// The shipped library's seed.
pub const SHIPPED_SEED: u64 = 2018;

impl Default for BuildParams {
    /// The shipped library: 15 motions per class, 5 gestures each.
    fn default() -> BuildParams {
        BuildParams {
            seed: SHIPPED_SEED,
            motions_per_class: 15,
            gestures_per_motion: 5,
            classes: MotionClass::ALL.to_vec(),
            features: FeatureParams::default(),
            styles: StyleRanges::default(),
            generators: Generator::ALL.to_vec(),
            agents: library_agents(),
            dt_s: 1.0 / 30.0,
        }
    }
}

/// The simulated pedestrians of the library's motions: 0.25 m bodies, 1.4 m/s at
/// most.
pub fn library_agents() -> AgentParams {
    AgentParams {
        radius_m: 0.25,
        max_speed_m_s: 1.4,
        max_accel_m_s2: 3.0,
        kp_per_s2: 8.0,
        kd_per_s: 4.0,
        push_stiffness_per_s2: 60.0,
    }
}

/// Why a library could not be built.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// A motion spec could not be simulated.
    #[error("{class} motion {index}: {source}")]
    Simulate {
        /// The class.
        class: MotionClass,
        /// Its number within the class.
        index: usize,
        /// Why.
        source: SimulateError,
    },
    /// A simulated motion has no features.
    #[error("{class} motion {index}: {source}")]
    Motion {
        /// The class.
        class: MotionClass,
        /// Its number within the class.
        index: usize,
        /// Why.
        source: MotionError,
    },
    /// A generated gesture could not be resampled.
    #[error("{class} motion {index}, gesture {gesture}: {source}")]
    Gesture {
        /// The class.
        class: MotionClass,
        /// The motion's number within the class.
        index: usize,
        /// The gesture's number for that motion.
        gesture: usize,
        /// Why.
        source: GestureError,
    },
}

/// Builds a library (see the module doc). Deterministic: the same parameters give
/// the same library, bit for bit. Its class table is `p.classes`' names in order
/// (with every class, as shipped, class `c` is [`MotionClass::id`]).
///
/// # Errors
/// [`BuildError`] naming the class, motion and gesture that failed.
pub fn build_library(p: &BuildParams) -> Result<Library, BuildError> {
    let mut lib = Library::with_classes(p.classes.iter().map(|c| c.as_str().to_string()).collect());
    let mut rng = SplitMix64::new(p.seed);
    for (k, &class) in p.classes.iter().enumerate() {
        let id = ClassId(k as u16);
        let specs = library_specs(class, p.motions_per_class, rng.next_u64());
        for (index, spec) in specs.iter().enumerate() {
            let sim = simulate(spec, &p.agents, p.dt_s).map_err(|source| BuildError::Simulate {
                class,
                index,
                source,
            })?;
            let motion = CrowdMotion::from_world(&sim.tracks, sim.duration_s)
                .and_then(|m| {
                    let fp = FeatureParams {
                        seed: rng.next_u64(),
                        ..p.features
                    };
                    features(id, &m, &fp)
                })
                .map_err(|source| BuildError::Motion {
                    class,
                    index,
                    source,
                })?;
            let heading = Heading::of(spec, &sim.tracks);
            let motion_id = lib.motions.len() as u32;
            lib.motions.push(motion);
            for g in 0..p.gestures_per_motion {
                let style_seed = rng.next_u64();
                let gesture_seed = rng.next_u64();
                let generator = p
                    .generators
                    .get(g % p.generators.len().max(1))
                    .copied()
                    .unwrap_or(Generator::Synth);
                let tracks = match generator {
                    Generator::Synth => {
                        let mut style = GestureStyle::random(class, style_seed, &p.styles);
                        heading.point(class, &mut style);
                        generate(class, &style, gesture_seed)
                    }
                    Generator::Style2 => {
                        style2::draw(class, gesture_seed, &heading.aim(class)).tracks
                    }
                };
                let (gesture, scale_mm) =
                    prepare_scaled(&tracks).map_err(|source| BuildError::Gesture {
                        class,
                        index,
                        gesture: g,
                        source,
                    })?;
                lib.gestures.push(LibraryGesture {
                    class: id,
                    motion: motion_id,
                    gesture,
                    participant: String::new(),
                    device: String::new(),
                    origin: match generator {
                        Generator::Synth => {
                            format!("generated {class} {index}.{g} seed {gesture_seed:#x}")
                        }
                        g2 => {
                            format!("generated ({g2}) {class} {index}.{g} seed {gesture_seed:#x}")
                        }
                    },
                    scale_mm: Some(scale_mm),
                });
            }
        }
    }
    Ok(lib)
}

/// Which way a simulated motion goes (see the module doc's table).
#[derive(Copy, Clone, Debug)]
struct Heading {
    shift: Vec2,
    rotation_rad: f64,
    axis: Vec2,
}

impl Heading {
    fn of(spec: &MotionSpec, tracks: &[Vec<Vec2>]) -> Heading {
        let m = measure(tracks, &spec.group);
        let at = |group: u8, end: bool| -> Option<Vec2> {
            let pts: Vec<Vec2> = tracks
                .iter()
                .zip(&spec.group)
                .filter(|(_, &g)| g == group)
                .filter_map(|(t, _)| if end { t.last() } else { t.first() }.copied())
                .collect();
            (!pts.is_empty()).then(|| pts.iter().sum::<Vec2>() / pts.len() as f64)
        };
        let at_end = matches!(
            spec.class,
            MotionClass::Split | MotionClass::SplitThenTranslate
        );
        let axis = match (at(0, at_end), at(1, at_end)) {
            (Some(a), Some(b)) => b - a,
            _ => Vec2::new(1.0, 0.0),
        };
        Heading {
            shift: m.centroid_shift,
            rotation_rad: m.rotation_rad,
            axis,
        }
    }

    /// Where `style2` should point a gesture of `class` (the same table as
    /// [`point`](Self::point)).
    fn aim(&self, class: MotionClass) -> Aim {
        let angle = |v: Vec2| v.y.atan2(v.x);
        match class {
            MotionClass::Translate => Aim {
                direction_rad: Some(angle(self.shift)),
                ..Aim::default()
            },
            MotionClass::Twist
            | MotionClass::TwistWhileExpanding
            | MotionClass::TwistWhileContracting => Aim {
                clockwise: Some(self.rotation_rad > 0.0),
                ..Aim::default()
            },
            MotionClass::Join | MotionClass::Split => Aim {
                axis_rad: Some(angle(self.axis)),
                ..Aim::default()
            },
            MotionClass::SplitThenTranslate | MotionClass::TranslateThenJoin => Aim {
                axis_rad: Some(angle(self.axis)),
                direction_rad: Some(angle(self.shift)),
                ..Aim::default()
            },
            MotionClass::Contract | MotionClass::Expand => Aim::default(),
        }
    }

    /// Points `style` the way the motion goes.
    fn point(&self, class: MotionClass, style: &mut GestureStyle) {
        let angle = |v: Vec2| v.y.atan2(v.x);
        match class {
            MotionClass::Translate => style.orientation_rad = angle(self.shift),
            MotionClass::Twist
            | MotionClass::TwistWhileExpanding
            | MotionClass::TwistWhileContracting => style.clockwise = self.rotation_rad > 0.0,
            MotionClass::Join | MotionClass::Split => style.orientation_rad = angle(self.axis),
            MotionClass::SplitThenTranslate | MotionClass::TranslateThenJoin => {
                // The generator's hands travel towards +90° of their axis.
                let flip = cross(self.axis, self.shift) < 0.0;
                style.orientation_rad =
                    angle(self.axis) + if flip { std::f64::consts::PI } else { 0.0 };
            }
            MotionClass::Contract | MotionClass::Expand => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gesture::library::validate;

    #[test]
    fn a_small_library_is_valid_deterministic_and_paired_by_class() {
        let p = BuildParams {
            motions_per_class: 2,
            gestures_per_motion: 2,
            ..BuildParams::default()
        };
        let a = build_library(&p).unwrap();
        assert_eq!(a.motions.len(), 20);
        assert_eq!(a.gestures.len(), 40);
        assert_eq!(a.classes, MotionClass::all_names());
        validate(&a).unwrap();
        for g in &a.gestures {
            assert_eq!(a.motions[g.motion as usize].class, g.class);
        }
        assert_eq!(build_library(&p).unwrap(), a);
        let other = build_library(&BuildParams {
            seed: 7,
            ..p.clone()
        })
        .unwrap();
        assert_ne!(other, a);
        // A subset of the classes is a library of those classes only.
        let two = build_library(&BuildParams {
            classes: vec![MotionClass::Twist, MotionClass::Join],
            ..p
        })
        .unwrap();
        assert_eq!(two.classes, ["twist", "join"]);
        assert_eq!(two.kind(ClassId(1)), Some(MotionClass::Join));
        validate(&two).unwrap();
    }
}
