//! A client line read into a JSON value that refuses a key repeated in one object,
//! at any depth. serde_json's own `Value` keeps the last of duplicate keys, so
//! `{"x":0.5,"x":0.9}` would be read as `x = 0.9` by the daemon and perhaps as
//! `x = 0.5` by a proxy or a logger in front of it (RFC 8259 §4: names SHOULD be
//! unique; behaviour with duplicates is unpredictable). This reader builds the same
//! `Value` and stops at the second occurrence of a key, naming it.
//!
//! # Complexity
//! Linear in the line: one pass of serde_json's parser, a hashed lookup per key
//! (the map keeps insertion order with an index). Nesting is capped by serde_json's
//! recursion limit (128), as for its own `Value`.

use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};
use std::cell::RefCell;
use std::fmt;

/// Why a line could not be read.
#[derive(Debug)]
pub(super) enum ReadError {
    /// `key` appears twice in one object; `column` (1-based, bytes) is where the
    /// parser stopped, just past the second occurrence.
    Duplicate {
        /// The key.
        key: String,
        /// 1-based byte column.
        column: usize,
    },
    /// Not JSON (serde_json's error).
    Json(serde_json::Error),
}

/// Reads `line` as one JSON value, refusing duplicate keys.
///
/// # Errors
/// [`ReadError::Duplicate`] naming the first key repeated; [`ReadError::Json`] for
/// anything serde_json refuses.
pub(super) fn from_slice_unique(line: &[u8]) -> Result<Value, ReadError> {
    let dup = RefCell::new(None);
    let mut de = serde_json::Deserializer::from_slice(line);
    let read = Seed { dup: &dup }
        .deserialize(&mut de)
        .and_then(|v| de.end().map(|()| v));
    match read {
        Ok(v) => Ok(v),
        Err(e) => match dup.into_inner() {
            Some(key) => Err(ReadError::Duplicate {
                key,
                column: e.column().max(1),
            }),
            None => Err(ReadError::Json(e)),
        },
    }
}

/// Reads one value; `dup` receives the first duplicate key found.
#[derive(Copy, Clone)]
struct Seed<'a> {
    dup: &'a RefCell<Option<String>>,
}

impl<'de> DeserializeSeed<'de> for Seed<'_> {
    type Value = Value;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Seed<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        // As serde_json's own Value: JSON has no non-finite numbers.
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }

    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }

    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        self.deserialize(d)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::new();
        while let Some(v) = seq.next_element_seed(self)? {
            out.push(v);
        }
        Ok(Value::Array(out))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                let e = de::Error::custom(format_args!(
                    "duplicate key `{}`",
                    crate::located::Escaped(&key)
                ));
                *self.dup.borrow_mut() = Some(key);
                return Err(e);
            }
            let v = map.next_value_seed(self)?;
            out.insert(key, v);
        }
        Ok(Value::Object(out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dup(line: &str) -> Option<String> {
        match from_slice_unique(line.as_bytes()) {
            Err(ReadError::Duplicate { key, .. }) => Some(key),
            _ => None,
        }
    }

    #[test]
    fn reads_what_serde_json_reads() {
        for line in [
            r#"{"a":1,"b":[1,-2,3.5,1e300,null,true,"s\n"],"c":{"d":{}}}"#,
            r#"[{"x":0.5},{"x":0.9}]"#,
            "12",
            r#""just a string""#,
            r#"{"big":18446744073709551615,"neg":-9223372036854775808}"#,
        ] {
            let ours = from_slice_unique(line.as_bytes()).unwrap();
            let theirs: Value = serde_json::from_str(line).unwrap();
            assert_eq!(ours, theirs, "{line}");
        }
    }

    #[test]
    fn a_key_twice_in_one_object_is_refused_at_any_depth() {
        assert_eq!(dup(r#"{"x":0.5,"x":0.9}"#).as_deref(), Some("x"));
        assert_eq!(
            dup(r#"{"contacts":[{"id":1,"x":0.5,"y":0.1,"x":0.9}]}"#).as_deref(),
            Some("x")
        );
        assert_eq!(dup(r#"{"a":{"b":{"c":1,"c":2}}}"#).as_deref(), Some("c"));
        // The same key written two ways is the same key.
        assert_eq!(dup(r#"{"x":1,"\u0078":2}"#).as_deref(), Some("x"));
        // The same key in two objects is fine.
        assert!(from_slice_unique(br#"[{"x":1},{"x":2}]"#).is_ok());
    }

    #[test]
    fn syntax_errors_stay_serde_json_s() {
        assert!(matches!(
            from_slice_unique(b"{\"a\":1,"),
            Err(ReadError::Json(_))
        ));
        assert!(matches!(
            from_slice_unique(b"{\"a\":1} trailing"),
            Err(ReadError::Json(_))
        ));
    }
}
