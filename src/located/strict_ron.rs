//! Strict RON: deserialising with every error placed at its line, column and field,
//! and finding a field's place in the text by its dotted path.

use super::issue::Issue;

/// Deserialises strict RON text (types use `deny_unknown_fields`) into `T`. A
/// syntax or schema error becomes one issue with its line, column and the dotted path
/// of the field it is in; the shared parser for every RON file crowdtouch reads.
///
/// # Errors
/// The first problem the parser meets.
pub fn parse_strict<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, Issue> {
    ron::Options::default()
        .from_str(text)
        .map_err(|e: ron::error::SpannedError| Issue {
            field: field_of_ron_error(&e.code, text, e.position),
            line: e.position.line,
            column: e.position.col,
            message: e.code.to_string(),
        })
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
        E::MissingStructField { field, .. } | E::DuplicateStructField { field, .. } => {
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
}

impl<'a> Scanner<'a> {
    /// Tokens (fields, brackets, commas) with 1-based line/column, skipping strings and comments.
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
                }
                continue;
            }
            match c {
                '(' | '[' | '{' => out.push((Tok::Open(c), line, col)),
                ')' | ']' | '}' => out.push((Tok::Close, line, col)),
                ',' => out.push((Tok::Comma, line, col)),
                _ => {}
            }
            adv(&chars, &mut i, &mut line, &mut col);
        }
        out
    }
}

/// Every field of RON `text` as `(dotted path, line, column)`, in text order
/// (`inputs[0].calibration.matrix`; 1-based positions).
pub fn field_positions(text: &str) -> Vec<(String, usize, usize)> {
    let toks = Scanner { text }.tokens();
    // Stack of (field name for this nesting level, list index when inside [ ]).
    let mut stack: Vec<(Option<String>, Option<usize>)> = Vec::new();
    let mut pending: Option<String> = None;
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
        match tok {
            Tok::Field(name) => {
                let parent = path_of(&stack);
                out.push((join_path(&parent, &name), line, col));
                pending = Some(name);
            }
            Tok::Open(ch) => {
                let idx = if ch == '[' { Some(0) } else { None };
                stack.push((pending.take(), idx));
            }
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
    }
}
