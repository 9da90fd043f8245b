//! Input quoted in a message, made harmless to print: what a file or a client sent
//! (a recording's first line, a command name, an OSC address, a word of a config)
//! can reach a terminal or a log through an error, and a control character in it
//! would drive the terminal (`ESC [ 2 J` clears the screen) or reorder the text
//! around it (the bidirectional overrides).
//!
//! [`Escaped`] and [`EscapedBytes`] write what they wrap with every such character
//! replaced by an escape in Rust's notation:
//!
//! * C0 controls, DEL and C1 controls (U+0000–U+001F, U+007F–U+009F): `\n`, `\r`,
//!   `\t`, `\0`, else `\u{1b}`;
//! * the invisible format characters that reorder or hide text: U+061C, U+200B–U+200F,
//!   U+202A–U+202E, U+2060–U+2069, U+FEFF: `\u{202e}`;
//! * (bytes only) a byte that is not part of valid UTF-8: `\xff`.
//!
//! [`EscapedLines`] does the same to whatever a `Display` writes, except line feeds:
//! for messages of several lines that quote input (a config's list of problems).
//! Everything else, backslashes included, is written as it is. None allocates.

use std::fmt;

/// A string quoted in a message, written with its control characters escaped (see
/// the module doc).
///
/// ```
/// use crowdtouch::located::Escaped;
/// assert_eq!(Escaped("\u{1b}[2Jhi\n").to_string(), "\\u{1b}[2Jhi\\n");
/// assert_eq!(Escaped("naïve").to_string(), "naïve");
/// ```
#[derive(Copy, Clone, Debug)]
pub struct Escaped<'a>(pub &'a str);

/// Bytes quoted in a message: valid UTF-8 written as [`Escaped`] does, every other
/// byte as `\xNN`.
///
/// ```
/// use crowdtouch::located::EscapedBytes;
/// assert_eq!(EscapedBytes(b"ok\xff\x1b").to_string(), "ok\\xff\\u{1b}");
/// ```
#[derive(Copy, Clone, Debug)]
pub struct EscapedBytes<'a>(pub &'a [u8]);

/// Whether `c` is escaped when quoted: a control character, or a format character
/// that reorders or hides text.
pub fn needs_escape(c: char) -> bool {
    c.is_control()
        || matches!(
            c,
            '\u{061c}'
                | '\u{200b}'..='\u{200f}'
                | '\u{202a}'..='\u{202e}'
                | '\u{2060}'..='\u{2069}'
                | '\u{feff}'
        )
}

/// `s` with its control characters escaped, as an owned string (for error fields
/// that keep what they quote).
pub fn escape(s: &str) -> String {
    if s.chars().any(needs_escape) {
        Escaped(s).to_string()
    } else {
        s.to_string()
    }
}

/// `bytes` with control characters and bytes that are not UTF-8 escaped.
pub fn escape_bytes(bytes: &[u8]) -> String {
    EscapedBytes(bytes).to_string()
}

/// What a `Display` writes, with control characters escaped except `\n` (which
/// separates the lines of a message).
///
/// ```
/// use crowdtouch::located::EscapedLines;
/// let text = EscapedLines(format_args!("a:1: `{}`\nb:2: ok", "\u{1b}[2J")).to_string();
/// assert_eq!(text, "a:1: `\\u{1b}[2J`\nb:2: ok");
/// ```
#[derive(Copy, Clone, Debug)]
pub struct EscapedLines<T>(pub T);

impl<T: fmt::Display> fmt::Display for EscapedLines<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        struct Lines<'a, 'b>(&'a mut fmt::Formatter<'b>);
        impl fmt::Write for Lines<'_, '_> {
            fn write_str(&mut self, s: &str) -> fmt::Result {
                write_escaped_but(self.0, s, Some('\n'))
            }
        }
        fmt::write(&mut Lines(f), format_args!("{}", self.0))
    }
}

fn write_escaped(f: &mut fmt::Formatter<'_>, s: &str) -> fmt::Result {
    write_escaped_but(f, s, None)
}

fn write_escaped_but(f: &mut fmt::Formatter<'_>, s: &str, keep: Option<char>) -> fmt::Result {
    let mut start = 0;
    for (i, c) in s.char_indices() {
        if !needs_escape(c) || Some(c) == keep {
            continue;
        }
        f.write_str(&s[start..i])?;
        match c {
            '\n' => f.write_str("\\n")?,
            '\r' => f.write_str("\\r")?,
            '\t' => f.write_str("\\t")?,
            '\0' => f.write_str("\\0")?,
            c => write!(f, "\\u{{{:x}}}", u32::from(c))?,
        }
        start = i + c.len_utf8();
    }
    f.write_str(&s[start..])
}

impl fmt::Display for Escaped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_escaped(f, self.0)
    }
}

impl fmt::Display for EscapedBytes<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for chunk in self.0.utf8_chunks() {
            write_escaped(f, chunk.valid())?;
            for b in chunk.invalid() {
                write!(f, "\\x{b:02x}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_and_reordering_characters_are_escaped() {
        let s = "a\u{1b}[2J\u{7}b\u{7f}\u{9b}c\u{202e}d\re\t";
        let out = Escaped(s).to_string();
        assert_eq!(out, "a\\u{1b}[2J\\u{7}b\\u{7f}\\u{9b}c\\u{202e}d\\re\\t");
        assert!(!out.chars().any(needs_escape), "{out:?}");
        assert_eq!(escape(s), out);
    }

    #[test]
    fn plain_text_is_kept_as_it_is() {
        for s in [
            "",
            "frame `12` is not a number",
            "naïve 東京 😀",
            "C:\\path",
        ] {
            assert_eq!(Escaped(s).to_string(), s);
            assert_eq!(escape(s), s);
            assert_eq!(escape_bytes(s.as_bytes()), s);
        }
    }

    #[test]
    fn lines_keep_their_line_feeds_only() {
        let out = EscapedLines(format_args!("{}\n{}", "x\u{1b}", "y\r\n")).to_string();
        assert_eq!(out, "x\\u{1b}\ny\\r\n");
    }

    #[test]
    fn bytes_that_are_not_utf8_are_written_in_hex() {
        let out = escape_bytes(b"\x1b[31mred\xff\xfe\xc3");
        assert_eq!(out, "\\u{1b}[31mred\\xff\\xfe\\xc3");
        assert!(!out.chars().any(needs_escape));
    }
}
