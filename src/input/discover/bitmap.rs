//! Kernel bitmaps as sysfs prints them (`capabilities/abs`, `properties`).

use std::fmt;

/// Bits per word in the kernel's sysfs bitmaps (a C `long`).
const LONG_BITS: usize = nix::libc::c_long::BITS as usize;

/// A kernel bitmap as sysfs prints it (`capabilities/abs`, `properties`): hex words of
/// a C `long`, most significant first, separated by spaces, leading zero words left
/// out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Bitmap {
    /// Words, least significant first; each holds [`LONG_BITS`] bits.
    words: Vec<u64>,
}

impl Bitmap {
    /// Parses sysfs text.
    ///
    /// # Errors
    /// A short description of what is wrong.
    pub fn parse(text: &str) -> Result<Bitmap, &'static str> {
        let mut words = Vec::new();
        for w in text.split_whitespace().rev() {
            let v = u64::from_str_radix(w, 16).map_err(|_| "hexadecimal words")?;
            if LONG_BITS < 64 && v >> LONG_BITS != 0 {
                return Err("words no wider than a C long");
            }
            words.push(v);
        }
        if words.is_empty() {
            return Err("at least one hexadecimal word");
        }
        Ok(Bitmap { words })
    }

    /// A bitmap with the given bits set.
    pub fn from_bits(bits: &[usize]) -> Bitmap {
        let mut words = vec![0u64; bits.iter().max().map_or(1, |m| m / LONG_BITS + 1)];
        for &b in bits {
            words[b / LONG_BITS] |= 1u64 << (b % LONG_BITS);
        }
        Bitmap { words }
    }

    /// Whether bit `bit` is set.
    pub fn test(&self, bit: usize) -> bool {
        self.words
            .get(bit / LONG_BITS)
            .is_some_and(|w| w >> (bit % LONG_BITS) & 1 == 1)
    }
}

impl fmt::Display for Bitmap {
    /// The kernel's format (`input_print_bitmap`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let top = self.words.iter().rposition(|&w| w != 0);
        match top {
            None => f.write_str("0"),
            Some(top) => {
                for i in (0..=top).rev() {
                    write!(f, "{:x}", self.words[i])?;
                    if i > 0 {
                        f.write_str(" ")?;
                    }
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bitmaps_parse_and_print_in_the_kernel_format() {
        // Dell Canvas ABS: X, Y, MT_SLOT, MT_POSITION_X/Y, MT_TRACKING_ID.
        let b = Bitmap::from_bits(&[0, 1, 0x2f, 0x35, 0x36, 0x39]);
        assert_eq!(b.to_string(), "260800000000003");
        let p = Bitmap::parse("260800000000003\n").unwrap();
        assert_eq!(p, b);
        assert!(p.test(0x35) && p.test(0x36) && !p.test(0x37) && !p.test(1000));
        // Multi-word: bit 64 lives in the second word, printed first.
        let k = Bitmap::from_bits(&[1, 64]);
        assert_eq!(k.to_string(), "1 2");
        assert_eq!(Bitmap::parse("1 2").unwrap(), k);
        assert_eq!(Bitmap::from_bits(&[]).to_string(), "0");
        assert!(Bitmap::parse("").is_err());
        assert!(Bitmap::parse("xyz").is_err());
    }
}
