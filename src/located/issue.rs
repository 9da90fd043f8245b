//! A problem at a place in a text file, and the `file:line:col: what` lines people
//! read.

use super::escape::{Escaped, EscapedLines};
use std::fmt;
use std::path::Path;

/// One problem in a text file, found while parsing it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Issue {
    /// Dotted path of the field (`crowd.agents`), or empty for syntax errors.
    pub field: String,
    /// 1-based line, 0 when unknown.
    pub line: usize,
    /// 1-based column, 0 when unknown.
    pub column: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for Issue {
    /// `line:col: field `f`: message`, with the control characters of the field
    /// and the message (which may quote the file) escaped, line feeds kept.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: field `{}`: {}",
            self.line,
            self.column,
            Escaped(&self.field),
            EscapedLines(&self.message)
        )
    }
}

/// A problem with a place in its file.
pub trait Located {
    /// 1-based line, 0 when unknown.
    fn line(&self) -> usize;
    /// 1-based column, 0 when unknown.
    fn column(&self) -> usize;
    /// What is wrong, with the field when known (the place is written before it).
    fn fmt_what(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result;
}

impl Located for Issue {
    fn line(&self) -> usize {
        self.line
    }
    fn column(&self) -> usize {
        self.column
    }
    fn fmt_what(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}", EscapedLines(&self.message))
        } else {
            write!(
                f,
                "field `{}`: {}",
                Escaped(&self.field),
                EscapedLines(&self.message)
            )
        }
    }
}

/// One `file:line:col: what` line per issue, in the order given; the control
/// characters of each `what` (which may quote the file) are escaped, line feeds
/// kept.
pub fn format_issues<T: Located>(path: &Path, issues: &[T]) -> String {
    struct What<'a, T>(&'a T);
    impl<T: Located> fmt::Display for What<'_, T> {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            self.0.fmt_what(f)
        }
    }
    let mut s = String::new();
    for (i, is) in issues.iter().enumerate() {
        if i > 0 {
            s.push('\n');
        }
        s.push_str(&format!(
            "{}:{}:{}: {}",
            path.display(),
            is.line(),
            is.column(),
            EscapedLines(What(is))
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn issues_quoting_control_characters_print_them_escaped() {
        let is = Issue {
            field: "crowd.formation\u{1b}".to_string(),
            line: 3,
            column: 7,
            message: "no formation is called `\u{1b}[2J\u{9b}`\nnext line".to_string(),
        };
        let text = format_issues(Path::new("c.ron"), std::slice::from_ref(&is));
        assert_eq!(
            text,
            "c.ron:3:7: field `crowd.formation\\u{1b}`: no formation is called `\\u{1b}[2J\\u{9b}`\nnext line"
        );
        assert!(!is.to_string().contains('\u{1b}'));
    }
}
