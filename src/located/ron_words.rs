//! Plain words for the RON parser's terse value errors: what the field wanted and
//! what the text has there (`expected a whole number of 0 or more, found -5` rather
//! than `Expected integer`).

use ron::error::{Error as E, Position};

/// The message for a parse error `code` at `pos` in `text`, and the column it is
/// best reported at: ron's own words at ron's place, unless it is a scalar value of
/// the wrong kind, which is then named with what was written, at its first column.
pub(super) fn message(code: &E, text: &str, pos: Position) -> (String, usize) {
    match value_at(text, pos).and_then(|v| better(code, &v).map(|m| (m, v.column))) {
        Some(better) => better,
        None => (code.to_string(), pos.col),
    }
}

fn better(code: &E, value: &Value<'_>) -> Option<String> {
    let found = describe(value.text);
    let number = as_number(value.text);
    Some(match code {
        E::ExpectedInteger => match number {
            Some(n) if n.negative && n.whole => {
                format!("expected a whole number of 0 or more, found {}", value.text)
            }
            Some(n) if n.whole && value.text.starts_with('+') => {
                format!(
                    "expected a whole number without a `+` sign, found {}",
                    value.text
                )
            }
            _ => format!("expected a whole number, found {found}"),
        },
        // `1.5` where a whole number is wanted: ron reads `1`, then stops at `.`.
        E::ExpectedComma if value.inside && number.is_some_and(|n| !n.whole) => {
            format!("expected a whole number, found {found}")
        }
        E::IntegerOutOfBounds if number.is_some() => {
            format!("{} is out of range for this field", value.text)
        }
        E::ExpectedFloat => format!("expected a number, found {found}"),
        E::ExpectedBoolean => format!("expected true or false, found {found}"),
        E::ExpectedString | E::ExpectedStringEnd if !value.text.starts_with('"') => {
            format!("expected a string in double quotes, found {found}")
        }
        _ => return None,
    })
}

/// The scalar written where a parse error is.
struct Value<'a> {
    /// Its text, trimmed (empty when nothing is written).
    text: &'a str,
    /// Whether the error position is inside it (not at its start).
    inside: bool,
    /// Its first column (1-based, in bytes as ron counts).
    column: usize,
}

/// Characters that end a scalar value in RON.
fn ends_value(c: char) -> bool {
    matches!(c, ',' | ':' | '(' | ')' | '[' | ']' | '{' | '}' | '\n')
}

/// The scalar around `pos` (1-based line, 1-based byte column as ron counts):
/// from the delimiter before it to the delimiter after it. `None` when the position
/// is not inside the text or the value is a string holding a delimiter.
fn value_at(text: &str, pos: Position) -> Option<Value<'_>> {
    let line_start = if pos.line <= 1 {
        0
    } else {
        text.match_indices('\n').nth(pos.line - 2)?.0 + 1
    };
    let mut at = (line_start + pos.col.checked_sub(1)?).min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    // The error may sit on the delimiter right after the value (`-5,` at `,`).
    let probe = match text[at..].chars().next() {
        Some(c) if !ends_value(c) => at + c.len_utf8(),
        _ => at,
    };
    let start = text[..probe]
        .rfind(ends_value)
        .map_or(0, |i| i + 1)
        .min(probe);
    let end = text[start..]
        .find(ends_value)
        .map_or(text.len(), |i| start + i);
    let raw = &text[start..end];
    // A comment after the value is not part of it.
    let raw = raw.find("//").map_or(raw, |i| &raw[..i]);
    let lead = raw.len() - raw.trim_start().len();
    let trimmed = raw.trim();
    if trimmed.starts_with('"') && !(trimmed.len() > 1 && trimmed.ends_with('"')) {
        return None;
    }
    Some(Value {
        text: trimmed,
        inside: at > start + lead && at < start + lead + trimmed.len(),
        column: start + lead - line_start + 1,
    })
}

/// What a number literal is.
#[derive(Clone, Copy)]
struct Number {
    negative: bool,
    whole: bool,
}

fn as_number(s: &str) -> Option<Number> {
    let digits = s.strip_prefix(['-', '+']).unwrap_or(s);
    if !digits.starts_with(|c: char| c.is_ascii_digit()) {
        return None;
    }
    let clean: String = s.chars().filter(|&c| c != '_').collect();
    let whole = clean.parse::<i128>().is_ok();
    if !whole && clean.parse::<f64>().is_err() {
        return None;
    }
    Some(Number {
        negative: s.starts_with('-'),
        whole,
    })
}

/// How a written value is named in a message.
fn describe(s: &str) -> String {
    if s.is_empty() {
        "nothing".to_string()
    } else if s.starts_with('"') {
        format!("the string {s}")
    } else if as_number(s).is_some() {
        s.to_string()
    } else {
        format!("`{s}`")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(text: &str, line: usize, col: usize) -> String {
        value_at(text, Position { line, col })
            .map(|v| format!("{}{}", v.text, if v.inside { "*" } else { "" }))
            .unwrap_or_else(|| "-".to_string())
    }

    #[test]
    fn the_value_around_an_error_is_found_on_its_line() {
        let t = "(\n  a: -5,\n  b: 1.5, // x\n  c: ,\n  d: \"x, y\",\n)";
        assert_eq!(at(t, 2, 6), "-5");
        assert_eq!(at(t, 2, 8), "-5");
        assert_eq!(at(t, 3, 7), "1.5*");
        assert_eq!(at(t, 4, 6), "");
        assert_eq!(at(t, 5, 6), "-");
        assert_eq!(at(t, 99, 1), "-");
    }

    #[test]
    fn scalar_errors_say_what_was_written() {
        let msg =
            |code: E, text: &str, col: usize| message(&code, text, Position { line: 1, col }).0;
        assert_eq!(
            msg(E::ExpectedInteger, "(n: -5)", 5),
            "expected a whole number of 0 or more, found -5"
        );
        assert_eq!(
            msg(E::ExpectedComma, "(n: 1.5)", 6),
            "expected a whole number, found 1.5"
        );
        assert_eq!(
            msg(E::ExpectedInteger, "(n: 1e3)", 8),
            "expected a whole number, found 1e3"
        );
        assert_eq!(
            msg(E::ExpectedInteger, "(n: \"x\")", 5),
            "expected a whole number, found the string \"x\""
        );
        assert_eq!(
            msg(E::ExpectedInteger, "(n: true)", 5),
            "expected a whole number, found `true`"
        );
        assert_eq!(
            msg(E::ExpectedInteger, "(n: ,)", 5),
            "expected a whole number, found nothing"
        );
        assert_eq!(
            msg(E::IntegerOutOfBounds, "(n: 99999999999)", 16),
            "99999999999 is out of range for this field"
        );
        assert_eq!(
            msg(E::ExpectedFloat, "(x: \"a\")", 5),
            "expected a number, found the string \"a\""
        );
        assert_eq!(
            msg(E::ExpectedInteger, "(n: +5)", 5),
            "expected a whole number without a `+` sign, found +5"
        );
        // A comma really missing between two fields keeps ron's words and place.
        let pos = Position { line: 1, col: 7 };
        assert_eq!(
            message(&E::ExpectedComma, "(a: 1 b: 2)", pos),
            ("Expected comma".to_string(), 7)
        );
        // A reworded error is placed at the value's first column.
        let pos = Position { line: 2, col: 8 };
        assert_eq!(message(&E::ExpectedComma, "(\n  n: 1.5)", pos).1, 6);
    }
}
