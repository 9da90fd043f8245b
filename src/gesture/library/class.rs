//! The ten motion classes of gesture-driven section 4 (figure 2).

use std::fmt;
use std::str::FromStr;

/// A class of crowd motion (gesture-driven section 4): six typical ones and four
/// combinations.
#[derive(Copy, Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum MotionClass {
    /// Everyone moves in one direction.
    Translate,
    /// Everyone turns about the crowd's centre.
    Twist,
    /// Everyone moves towards the centre.
    Contract,
    /// Everyone moves away from the centre.
    Expand,
    /// Two groups move towards each other.
    Join,
    /// The crowd splits into two groups moving apart.
    Split,
    /// A split, then both groups move on in one direction.
    SplitThenTranslate,
    /// Everyone moves in one direction, then the two halves join.
    TranslateThenJoin,
    /// Turning while spreading out.
    TwistWhileExpanding,
    /// Turning while drawing in.
    TwistWhileContracting,
}

impl MotionClass {
    /// All ten, in the paper's order (figure 2, a–j).
    pub const ALL: [MotionClass; 10] = [
        MotionClass::Translate,
        MotionClass::Twist,
        MotionClass::Contract,
        MotionClass::Expand,
        MotionClass::Join,
        MotionClass::Split,
        MotionClass::SplitThenTranslate,
        MotionClass::TranslateThenJoin,
        MotionClass::TwistWhileExpanding,
        MotionClass::TwistWhileContracting,
    ];

    /// The six typical classes of the paper's leave-one-out evaluation (section 8.2).
    pub const BASIC: [MotionClass; 6] = [
        MotionClass::Translate,
        MotionClass::Twist,
        MotionClass::Contract,
        MotionClass::Expand,
        MotionClass::Join,
        MotionClass::Split,
    ];

    /// The name used in files, the protocol and the command line (`split_then_translate`).
    pub fn as_str(self) -> &'static str {
        match self {
            MotionClass::Translate => "translate",
            MotionClass::Twist => "twist",
            MotionClass::Contract => "contract",
            MotionClass::Expand => "expand",
            MotionClass::Join => "join",
            MotionClass::Split => "split",
            MotionClass::SplitThenTranslate => "split_then_translate",
            MotionClass::TranslateThenJoin => "translate_then_join",
            MotionClass::TwistWhileExpanding => "twist_while_expanding",
            MotionClass::TwistWhileContracting => "twist_while_contracting",
        }
    }

    /// Index in [`MotionClass::ALL`] (0–9), the class's number in library files.
    pub fn index(self) -> usize {
        MotionClass::ALL
            .iter()
            .position(|&c| c == self)
            .unwrap_or(0)
    }

    /// The class numbered `i` in library files.
    pub fn from_index(i: usize) -> Option<MotionClass> {
        MotionClass::ALL.get(i).copied()
    }

    /// Whether it is one of the six typical classes.
    pub fn is_basic(self) -> bool {
        self.index() < 6
    }
}

impl fmt::Display for MotionClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A name that is not a motion class; names the known ones.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown motion class `{0}` (known: translate, twist, contract, expand, join, split, split_then_translate, translate_then_join, twist_while_expanding, twist_while_contracting)")]
pub struct UnknownClass(pub String);

impl FromStr for MotionClass {
    type Err = UnknownClass;
    fn from_str(s: &str) -> Result<MotionClass, UnknownClass> {
        MotionClass::ALL
            .iter()
            .copied()
            .find(|c| c.as_str() == s)
            .ok_or_else(|| UnknownClass(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_indices_are_the_papers_order() {
        for (i, c) in MotionClass::ALL.iter().enumerate() {
            assert_eq!(c.index(), i);
            assert_eq!(MotionClass::from_index(i), Some(*c));
            assert_eq!(c.as_str().parse::<MotionClass>(), Ok(*c));
        }
        assert_eq!(MotionClass::ALL.iter().filter(|c| c.is_basic()).count(), 6);
        let e = "spin".parse::<MotionClass>().unwrap_err().to_string();
        assert!(
            e.contains("`spin`") && e.contains("twist_while_contracting"),
            "{e}"
        );
    }
}
