//! Classes: a library's own class table is data (its names live in the file, any
//! non-empty set of them; a class is known by its [`ClassId`], its place in that
//! table), and the ten motion kinds of gesture-driven section 4 (figure 2,
//! [`MotionClass`]) are what the crowd simulator and the gesture generators make
//! when `library build` fills a library of its own.

use std::fmt;
use std::str::FromStr;

/// A class of a library: its index in the library's class table
/// ([`Library::classes`](super::Library::classes)), which names it.
///
/// Ids are only meaningful with their library; a library built with the ten
/// [`MotionClass`]es in order (`library build`'s default, and every version-1 file)
/// gives class `c` the id [`MotionClass::id`].
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ClassId(pub u16);

impl ClassId {
    /// Its index in the class table.
    pub fn index(self) -> usize {
        usize::from(self.0)
    }
}

/// Most classes a library holds.
pub const MAX_CLASSES: usize = 1000;

/// Longest class name, bytes.
pub const MAX_CLASS_NAME_BYTES: usize = 64;

/// Why a text is not a class name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ClassNameError {
    /// No characters.
    #[error("a class name cannot be empty")]
    Empty,
    /// More than [`MAX_CLASS_NAME_BYTES`].
    #[error("a class name has at most {MAX_CLASS_NAME_BYTES} bytes, this one {0}")]
    TooLong(usize),
    /// A character other than ASCII letters, digits, `_` and `-`, or a first
    /// character that is not a letter.
    #[error("a class name is an ASCII letter followed by letters, digits, `_` or `-`; `{}` has `{}` at byte {at}", crate::located::Escaped(.name), crate::located::Escaped(.found))]
    BadCharacter {
        /// The name.
        name: String,
        /// Byte offset of the character.
        at: usize,
        /// The character.
        found: String,
    },
}

/// Checks a class name: 1 to [`MAX_CLASS_NAME_BYTES`] bytes, an ASCII letter then
/// ASCII letters, digits, `_` or `-` (names go into file names, configs, the
/// command line and the protocol unquoted).
///
/// # Errors
/// What is wrong with it.
pub fn check_class_name(name: &str) -> Result<(), ClassNameError> {
    if name.is_empty() {
        return Err(ClassNameError::Empty);
    }
    if name.len() > MAX_CLASS_NAME_BYTES {
        return Err(ClassNameError::TooLong(name.len()));
    }
    for (at, ch) in name.char_indices() {
        let ok = if at == 0 {
            ch.is_ascii_alphabetic()
        } else {
            ch.is_ascii_alphanumeric() || ch == '_' || ch == '-'
        };
        if !ok {
            return Err(ClassNameError::BadCharacter {
                name: name.to_string(),
                at,
                found: ch.to_string(),
            });
        }
    }
    Ok(())
}

/// A kind of crowd motion (gesture-driven section 4): six typical ones and four
/// combinations. What the crowd simulator and the gesture generators make; a
/// library names its own classes, which may or may not be these.
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

    /// Its id in a library whose class table is [`MotionClass::ALL`] in order.
    pub const fn id(self) -> ClassId {
        ClassId(self as u16)
    }

    /// The ten names, in order: the class table of a version-1 library file.
    pub fn all_names() -> Vec<String> {
        MotionClass::ALL
            .iter()
            .map(|c| c.as_str().to_string())
            .collect()
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
        for c in MotionClass::ALL {
            assert_eq!(c.id().index(), c.index());
            assert_eq!(check_class_name(c.as_str()), Ok(()));
        }
        let e = "spin".parse::<MotionClass>().unwrap_err().to_string();
        assert!(
            e.contains("`spin`") && e.contains("twist_while_contracting"),
            "{e}"
        );
    }

    #[test]
    fn class_names_are_checked_at_their_byte() {
        assert_eq!(check_class_name("zara-walk_2"), Ok(()));
        assert_eq!(check_class_name(""), Err(ClassNameError::Empty));
        assert_eq!(
            check_class_name(&"a".repeat(65)),
            Err(ClassNameError::TooLong(65))
        );
        let e = check_class_name("2fast").unwrap_err().to_string();
        assert!(e.contains("`2fast` has `2` at byte 0"), "{e}");
        let e = check_class_name("a b").unwrap_err().to_string();
        assert!(e.contains("at byte 1"), "{e}");
        let e = check_class_name("a\x1b").unwrap_err().to_string();
        assert!(!e.contains('\x1b'), "control characters are escaped: {e}");
    }
}
