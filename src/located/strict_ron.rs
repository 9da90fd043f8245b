//! Strict RON: deserialising with every error placed at its line, column and field,
//! and finding a field's place in the text by its dotted path.

use super::issue::Issue;
use super::ron_words;

/// Deserialises strict RON text (types use `deny_unknown_fields`) into `T`. A
/// syntax or schema error becomes one issue with its line, column and the dotted path
/// of the field it is in; the shared parser for every RON file crowdtouch reads.
///
/// # Errors
/// The first problem the parser meets.
pub fn parse_strict<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, Issue> {
    ron::Options::default()
        .from_str(text)
        .map_err(|e: ron::error::SpannedError| match &e.code {
            ron::error::Error::DuplicateStructField { field, .. } => {
                duplicate_field(text, e.position, field)
            }
            code => {
                let (message, column) = ron_words::message(code, text, e.position);
                Issue {
                    field: field_of_ron_error(code, text, e.position),
                    line: e.position.line,
                    column,
                    message,
                }
            }
        })
}

/// A field given twice: placed at its second occurrence (the one ron stopped at),
/// with the line of the first.
fn duplicate_field(text: &str, pos: ron::error::Position, name: &str) -> Issue {
    let fields = field_positions(text);
    // The last occurrence of the field that starts before the error position.
    let second = fields.iter().rev().find(|(p, l, c)| {
        (p == name || p.ends_with(&format!(".{name}"))) && (*l, *c) < (pos.line, pos.col)
    });
    match second {
        Some((path, line, column)) => {
            let first = fields
                .iter()
                .find(|(p, _, _)| p == path)
                .filter(|(_, l, c)| (l, c) != (line, column));
            Issue {
                field: path.clone(),
                line: *line,
                column: *column,
                message: match first {
                    Some((_, l, _)) => format!("`{name}` is given twice (first on line {l})"),
                    None => format!("`{name}` is given twice"),
                },
            }
        }
        None => Issue {
            field: name.to_string(),
            line: pos.line,
            column: pos.col,
            message: format!("`{name}` is given twice"),
        },
    }
}

/// Best-effort field name for a ron parse error.
fn field_of_ron_error(code: &ron::error::Error, text: &str, pos: ron::error::Position) -> String {
    use ron::error::Error as E;
    match code {
        E::NoSuchStructField { found, .. } => {
            let path = enclosing_path(text, pos.line, pos.col);
            if path == *found || path.ends_with(&format!(".{found}")) {
                path
            } else {
                join_path(&path, found)
            }
        }
        E::MissingStructField { field, .. } => {
            let path = enclosing_path(text, pos.line, pos.col);
            join_path(&path, field)
        }
        _ => enclosing_path(text, pos.line, pos.col),
    }
}

fn join_path(parent: &str, field: &str) -> String {
    if parent.is_empty() {
        field.to_string()
    } else {
        format!("{parent}.{field}")
    }
}

/// A token of the RON text with its position: identifiers followed by `:` open a
/// field, brackets nest.
struct Scanner<'a> {
    text: &'a str,
}

#[derive(Debug, Clone)]
enum Tok {
    Field(String),
    Open(char),
    Close,
    Comma,
    /// The start of any other value: a string, a number, an identifier that is not
    /// a field name (`None`, `Some`, an enum variant).
    Value,
}

impl<'a> Scanner<'a> {
    /// Tokens (fields, brackets, commas, the starts of other values) with 1-based
    /// line/column, skipping comments.
    fn tokens(&self) -> Vec<(Tok, usize, usize)> {
        let mut out = Vec::new();
        let chars: Vec<char> = self.text.chars().collect();
        let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
        fn adv(chars: &[char], i: &mut usize, line: &mut usize, col: &mut usize) {
            let c = chars[*i];
            *i += 1;
            if c == '\n' {
                *line += 1;
                *col = 1;
            } else {
                *col += 1;
            }
        }
        while i < chars.len() {
            let c = chars[i];
            if c == '/' && chars.get(i + 1) == Some(&'/') {
                while i < chars.len() && chars[i] != '\n' {
                    adv(&chars, &mut i, &mut line, &mut col);
                }
                continue;
            }
            if c == '/' && chars.get(i + 1) == Some(&'*') {
                while i < chars.len() && !(chars[i] == '*' && chars.get(i + 1) == Some(&'/')) {
                    adv(&chars, &mut i, &mut line, &mut col);
                }
                for _ in 0..2 {
                    if i < chars.len() {
                        adv(&chars, &mut i, &mut line, &mut col);
                    }
                }
                continue;
            }
            if c == '"' {
                out.push((Tok::Value, line, col));
                adv(&chars, &mut i, &mut line, &mut col);
                while i < chars.len() && chars[i] != '"' {
                    if chars[i] == '\\' {
                        adv(&chars, &mut i, &mut line, &mut col);
                    }
                    if i < chars.len() {
                        adv(&chars, &mut i, &mut line, &mut col);
                    }
                }
                if i < chars.len() {
                    adv(&chars, &mut i, &mut line, &mut col);
                }
                continue;
            }
            if c.is_alphabetic() || c == '_' {
                let (sl, sc) = (line, col);
                let mut ident = String::new();
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    ident.push(chars[i]);
                    adv(&chars, &mut i, &mut line, &mut col);
                }
                let mut j = i;
                while j < chars.len() && (chars[j] == ' ' || chars[j] == '\t') {
                    j += 1;
                }
                if chars.get(j) == Some(&':') {
                    out.push((Tok::Field(ident), sl, sc));
                } else {
                    out.push((Tok::Value, sl, sc));
                }
                continue;
            }
            match c {
                '(' | '[' | '{' => out.push((Tok::Open(c), line, col)),
                ')' | ']' | '}' => out.push((Tok::Close, line, col)),
                ',' => out.push((Tok::Comma, line, col)),
                c if c.is_whitespace() || c == ':' => {}
                // A number or a sign: one token for the run of such characters.
                _ => {
                    out.push((Tok::Value, line, col));
                    while i + 1 < chars.len()
                        && !chars[i + 1].is_whitespace()
                        && !"()[]{},:\"/".contains(chars[i + 1])
                    {
                        adv(&chars, &mut i, &mut line, &mut col);
                    }
                }
            }
            adv(&chars, &mut i, &mut line, &mut col);
        }
        out
    }
}

/// Every field of RON `text` as `(dotted path, line, column)`, in text order
/// (`inputs[0].calibration.matrix`; 1-based positions), and every list item
/// (`inputs[0]`, `inputs[0].files[1]`) at the start of its value.
pub fn field_positions(text: &str) -> Vec<(String, usize, usize)> {
    let toks = Scanner { text }.tokens();
    // Stack of (field name for this nesting level, list index when inside [ ]).
    let mut stack: Vec<(Option<String>, Option<usize>)> = Vec::new();
    let mut pending: Option<String> = None;
    // Whether the current list item has been placed.
    let mut item_placed = false;
    let mut out = Vec::new();
    let path_of = |stack: &[(Option<String>, Option<usize>)]| -> String {
        let mut s = String::new();
        for (name, idx) in stack {
            if let Some(n) = name {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(n);
            }
            if let Some(i) = idx {
                s.push_str(&format!("[{i}]"));
            }
        }
        s
    };
    for (tok, line, col) in toks {
        let in_list = matches!(stack.last(), Some((_, Some(_))));
        if in_list && !item_placed && matches!(tok, Tok::Value | Tok::Open(_)) {
            out.push((path_of(&stack), line, col));
            item_placed = true;
        }
        match tok {
            Tok::Field(name) => {
                let parent = path_of(&stack);
                out.push((join_path(&parent, &name), line, col));
                pending = Some(name);
            }
            Tok::Open(ch) => {
                let idx = if ch == '[' { Some(0) } else { None };
                stack.push((pending.take(), idx));
                item_placed = false;
            }
            Tok::Close => {
                stack.pop();
                pending = None;
                item_placed = true;
            }
            Tok::Comma => {
                pending = None;
                if let Some((_, Some(i))) = stack.last_mut() {
                    *i += 1;
                    item_placed = false;
                }
            }
            Tok::Value => {}
        }
    }
    out
}

/// Line and column of a field given by its dotted path (`crowd.agents`), or of its
/// nearest enclosing field that appears in the text.
pub fn locate_field(text: &str, path: &str) -> Option<(usize, usize)> {
    let fields = field_positions(text);
    let mut p = path.to_string();
    loop {
        if let Some((_, l, c)) = fields.iter().find(|(fp, _, _)| *fp == p) {
            return Some((*l, *c));
        }
        // Strip the last component ("a.b[2].c" -> "a.b[2]" -> "a.b" -> "a").
        if let Some(i) = p.rfind(['.', '[']) {
            p.truncate(i);
        } else {
            return None;
        }
    }
}

/// Dotted path of the innermost field enclosing a position.
fn enclosing_path(text: &str, line: usize, col: usize) -> String {
    let toks = Scanner { text }.tokens();
    let mut stack: Vec<(Option<String>, Option<usize>)> = Vec::new();
    let mut pending: Option<String> = None;
    for (tok, l, c) in toks {
        if (l, c) >= (line, col) {
            break;
        }
        match tok {
            Tok::Field(name) => pending = Some(name),
            Tok::Open(ch) => stack.push((pending.take(), (ch == '[').then_some(0))),
            Tok::Close => {
                stack.pop();
                pending = None;
            }
            Tok::Comma => {
                pending = None;
                if let Some((_, Some(i))) = stack.last_mut() {
                    *i += 1;
                }
            }
            Tok::Value => {}
        }
    }
    let mut s = String::new();
    for (name, idx) in &stack {
        if let Some(n) = name {
            if !s.is_empty() {
                s.push('.');
            }
            s.push_str(n);
        }
        if let Some(i) = idx {
            s.push_str(&format!("[{i}]"));
        }
    }
    if let Some(n) = pending {
        s = join_path(&s, &n);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_finds_nested_fields_and_list_items() {
        let t = "(\n a: (\n  b: 1,\n ),\n l: [\n  X(f: 1),\n  Y(f: 2),\n ],\n)";
        assert_eq!(locate_field(t, "a.b"), Some((3, 3)));
        assert_eq!(locate_field(t, "l[1].f"), Some((7, 5)));
        assert_eq!(locate_field(t, "a.zz"), Some((2, 2)));
        assert_eq!(locate_field(t, "l[1]"), Some((7, 3)));
    }

    #[test]
    fn list_items_are_placed_at_their_values() {
        let t =
            "(\n files: [\"a.jsonl\", // one\n   \"b.jsonl\"],\n cpus: Some([0, -1]),\n e: [],\n)";
        assert_eq!(locate_field(t, "files[0]"), Some((2, 10)));
        assert_eq!(locate_field(t, "files[1]"), Some((3, 4)));
        assert_eq!(locate_field(t, "cpus[1]"), Some((4, 17)));
        assert_eq!(locate_field(t, "e[0]"), Some((5, 2)));
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Inner {
        agents: u32,
        radius: f64,
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Outer {
        crowd: Inner,
    }

    fn issue(text: &str) -> Issue {
        parse_strict::<Outer>(text).unwrap_err()
    }

    #[test]
    fn a_field_given_twice_is_named_once_at_its_second_place() {
        let i = issue("(\n crowd: (\n  agents: 1,\n  radius: 1.0,\n  agents: 2,\n ),\n)");
        assert_eq!(
            (i.field.as_str(), i.line, i.column, i.message.as_str()),
            (
                "crowd.agents",
                5,
                3,
                "`agents` is given twice (first on line 3)"
            )
        );
    }

    #[test]
    fn a_value_of_the_wrong_kind_is_named_with_what_was_written() {
        let i = issue("(crowd: (agents: -5, radius: 1.0))");
        assert_eq!(
            (i.field.as_str(), i.message.as_str()),
            (
                "crowd.agents",
                "expected a whole number of 0 or more, found -5"
            )
        );
        let i = issue("(crowd: (agents: 1.5, radius: 1.0))");
        assert_eq!(
            (i.field.as_str(), i.message.as_str()),
            ("crowd.agents", "expected a whole number, found 1.5")
        );
        let i = issue("(crowd: (agents: 2, radius: \"far\"))");
        assert_eq!(
            (i.field.as_str(), i.message.as_str()),
            (
                "crowd.radius",
                "expected a number, found the string \"far\""
            )
        );
    }
}
