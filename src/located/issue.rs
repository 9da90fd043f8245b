//! A problem at a place in a text file, and the `file:line:col: what` lines people
//! read.

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
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: field `{}`: {}",
            self.line, self.column, self.field, self.message
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
            write!(f, "{}", self.message)
        } else {
            write!(f, "field `{}`: {}", self.field, self.message)
        }
    }
}

/// One `file:line:col: what` line per issue, in the order given.
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
            What(is)
        ));
    }
    s
}
