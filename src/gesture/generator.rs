//! The two gesture generators behind one name, for the commands that draw labelled
//! gestures (`library build`, `library test-set`, `library eval --cross-style`):
//! `synth` (`gesture::synth`, the shipped library's) and `style2`
//! (`gesture::style2`, written independently with other conventions of motion).

use super::library::MotionClass;
use super::style2::{self, Aim};
use super::synth::{generate, GestureStyle, StyleRanges};
use super::track::GestureTracks;

/// A gesture generator.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Generator {
    /// `gesture::synth`.
    Synth,
    /// `gesture::style2`.
    Style2,
}

impl Generator {
    /// Both, in report order.
    pub const ALL: [Generator; 2] = [Generator::Synth, Generator::Style2];

    /// Its name on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Generator::Synth => "synth",
            Generator::Style2 => "style2",
        }
    }
}

impl std::fmt::Display for Generator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A name that is not a generator.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown generator `{0}` (synth or style2)")]
pub struct UnknownGenerator(pub String);

impl std::str::FromStr for Generator {
    type Err = UnknownGenerator;
    fn from_str(s: &str) -> Result<Generator, UnknownGenerator> {
        match s {
            "synth" => Ok(Generator::Synth),
            "style2" => Ok(Generator::Style2),
            other => Err(UnknownGenerator(other.to_string())),
        }
    }
}

/// A gesture drawn by a generator, with its glass.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawnGesture {
    /// The class it was drawn for.
    pub class: MotionClass,
    /// Its tracks (mm of glass).
    pub tracks: GestureTracks,
    /// The glass, width × height, mm.
    pub device_mm: (f64, f64),
}

/// The seed of gesture `i` of `class` in a set seeded `seed`.
pub fn gesture_seed(seed: u64, class: MotionClass, i: usize) -> u64 {
    seed.wrapping_mul(1_000_003)
        .wrapping_add((class.index() * 10_000 + i) as u64)
}

/// Gesture `i` of `class` in a labelled set seeded `seed`: `synth` with `ranges`
/// (its test-set ranges when `None`), `style2` in any direction.
pub fn draw_labelled(
    generator: Generator,
    class: MotionClass,
    seed: u64,
    i: usize,
    ranges: Option<&StyleRanges>,
) -> DrawnGesture {
    let s = gesture_seed(seed, class, i);
    match generator {
        Generator::Synth => {
            let test = StyleRanges::test_set();
            let style = GestureStyle::random(class, s, ranges.unwrap_or(&test));
            DrawnGesture {
                class,
                tracks: generate(class, &style, s ^ 0xa5a5),
                device_mm: style.device_mm,
            }
        }
        Generator::Style2 => {
            let d = style2::draw(class, s, &Aim::default());
            DrawnGesture {
                class,
                tracks: d.tracks,
                device_mm: d.device_mm,
            }
        }
    }
}

/// A labelled set: `per_class` gestures of each of `classes`, class by class.
pub fn labelled_set(
    generator: Generator,
    classes: &[MotionClass],
    per_class: usize,
    seed: u64,
    ranges: Option<&StyleRanges>,
) -> Vec<DrawnGesture> {
    classes
        .iter()
        .flat_map(|&c| (0..per_class).map(move |i| draw_labelled(generator, c, seed, i, ranges)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_sets_are_deterministic() {
        for g in Generator::ALL {
            assert_eq!(g.as_str().parse::<Generator>(), Ok(g));
        }
        assert!("style3".parse::<Generator>().is_err());
        let a = labelled_set(Generator::Style2, &MotionClass::ALL[..2], 3, 5, None);
        assert_eq!(a.len(), 6);
        assert_eq!(
            a,
            labelled_set(Generator::Style2, &MotionClass::ALL[..2], 3, 5, None)
        );
        let b = labelled_set(Generator::Synth, &MotionClass::ALL[..2], 3, 5, None);
        assert_ne!(a[0].tracks, b[0].tracks);
    }
}
