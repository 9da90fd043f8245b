//! Located errors: problems in the text files people hand the daemon (config, scenes,
//! formation shapes), named by file, line, column and field, and the strict-RON
//! reading those files share, the words parsers use for what they found, and the
//! escaping of input quoted in messages (`escape.rs`). A bottom module: it knows no
//! file kind.

mod escape;
mod issue;
mod json;
mod read;
mod ron_words;
mod strict_ron;

pub use escape::{escape, escape_bytes, needs_escape, Escaped, EscapedBytes, EscapedLines};
pub use issue::{format_issues, Issue, Located};
pub use json::json_kind;
pub use read::{read_capped, ReadError};
pub use strict_ron::{field_positions, locate_field, parse_strict};
