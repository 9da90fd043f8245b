//! JSON values as the JSON Lines reader needs them, deserialised without building
//! a tree: a [`Scalar`] keeps a number or what kind of value was found (arrays and
//! objects are skipped unread), [`Text`] keeps a string; and the checks that turn
//! them into fields, with messages naming the field.

use serde::de::{self, Deserialize, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// A JSON value reduced to what a field check needs.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) enum Scalar {
    Null,
    Bool(bool),
    U64(u64),
    I64(i64),
    F64(f64),
    String,
    Array,
    Object,
}

impl Scalar {
    /// An integer: [`Scalar::U64`] when it is not negative.
    fn int(v: i64) -> Scalar {
        match u64::try_from(v) {
            Ok(u) => Scalar::U64(u),
            Err(_) => Scalar::I64(v),
        }
    }

    /// What was found, as messages say it.
    pub(super) fn kind(self) -> &'static str {
        match self {
            Scalar::Null => "null",
            Scalar::Bool(_) => "a boolean",
            Scalar::U64(_) | Scalar::I64(_) | Scalar::F64(_) => "a number",
            Scalar::String => "a string",
            Scalar::Array => "an array",
            Scalar::Object => "an object",
        }
    }
}

impl fmt::Display for Scalar {
    /// A number as JSON writes it; other values by kind.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Scalar::U64(n) => write!(f, "{n}"),
            Scalar::I64(n) => write!(f, "{n}"),
            Scalar::F64(x) => match serde_json::Number::from_f64(x) {
                Some(n) => write!(f, "{n}"),
                None => write!(f, "{x}"),
            },
            other => f.write_str(other.kind()),
        }
    }
}

struct ScalarVisitor;

impl<'de> Visitor<'de> for ScalarVisitor {
    type Value = Scalar;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_unit<E>(self) -> Result<Scalar, E> {
        Ok(Scalar::Null)
    }
    fn visit_bool<E>(self, v: bool) -> Result<Scalar, E> {
        Ok(Scalar::Bool(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Scalar, E> {
        Ok(Scalar::U64(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Scalar, E> {
        Ok(Scalar::int(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Scalar, E> {
        Ok(Scalar::F64(v))
    }
    fn visit_str<E>(self, _: &str) -> Result<Scalar, E> {
        Ok(Scalar::String)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Scalar, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(Scalar::Array)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Scalar, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(Scalar::Object)
    }
}

impl<'de> Deserialize<'de> for Scalar {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Scalar, D::Error> {
        d.deserialize_any(ScalarVisitor)
    }
}

/// A JSON value kept whole when it is a string (header fields only: a line is
/// at most [`MAX_LINE_BYTES`](super::MAX_LINE_BYTES)).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Text {
    Str(String),
    Other(Scalar),
}

impl<'de> Deserialize<'de> for Text {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Text, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Text;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("any JSON value")
            }
            fn visit_str<E>(self, v: &str) -> Result<Text, E> {
                Ok(Text::Str(v.to_string()))
            }
            fn visit_unit<E>(self) -> Result<Text, E> {
                Ok(Text::Other(Scalar::Null))
            }
            fn visit_bool<E>(self, v: bool) -> Result<Text, E> {
                Ok(Text::Other(Scalar::Bool(v)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Text, E> {
                Ok(Text::Other(Scalar::U64(v)))
            }
            fn visit_i64<E>(self, v: i64) -> Result<Text, E> {
                Ok(Text::Other(Scalar::int(v)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Text, E> {
                Ok(Text::Other(Scalar::F64(v)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Text, A::Error> {
                ScalarVisitor.visit_seq(seq).map(Text::Other)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Text, A::Error> {
                ScalarVisitor.visit_map(map).map(Text::Other)
            }
        }
        d.deserialize_any(V)
    }
}

/// A JSON object read by `T`, or what else was found.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum MapOr<T> {
    Map(T),
    Other(Scalar),
}

/// A type read from the entries of a JSON object.
pub(super) trait FromMap: Sized {
    fn from_map<'de, A: MapAccess<'de>>(map: A) -> Result<Self, A::Error>;
}

impl<'de, T: FromMap> Deserialize<'de> for MapOr<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<MapOr<T>, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: FromMap> Visitor<'de> for V<T> {
            type Value = MapOr<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("any JSON value")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<MapOr<T>, A::Error> {
                T::from_map(map).map(MapOr::Map)
            }
            fn visit_str<E>(self, _: &str) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::String))
            }
            fn visit_unit<E>(self) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::Null))
            }
            fn visit_bool<E>(self, v: bool) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::Bool(v)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::U64(v)))
            }
            fn visit_i64<E>(self, v: i64) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::int(v)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<MapOr<T>, E> {
                Ok(MapOr::Other(Scalar::F64(v)))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<MapOr<T>, A::Error> {
                ScalarVisitor.visit_seq(seq).map(MapOr::Other)
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

/// The name of a field of a list element, `contacts[2].x`, written only when a
/// message needs it.
#[derive(Copy, Clone, Debug)]
pub(super) struct Element {
    pub(super) list: &'static str,
    pub(super) index: usize,
    /// Empty for the element itself.
    pub(super) key: &'static str,
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}[{}]", self.list, self.index)?;
        if !self.key.is_empty() {
            write!(f, ".{}", self.key)?;
        }
        Ok(())
    }
}

/// A number that must be finite.
pub(super) fn want_f64(v: Option<Scalar>, field: &dyn fmt::Display) -> Result<f64, String> {
    match v {
        Some(Scalar::U64(n)) => Ok(n as f64),
        Some(Scalar::I64(n)) => Ok(n as f64),
        Some(Scalar::F64(x)) if x.is_finite() => Ok(x),
        Some(n @ Scalar::F64(_)) => Err(format!("field `{field}`: {n} is not a finite number")),
        Some(o) => Err(format!(
            "field `{field}`: expected a number, found {}",
            o.kind()
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

/// A non-negative integer.
pub(super) fn want_u64(v: Option<Scalar>, field: &dyn fmt::Display) -> Result<u64, String> {
    match v {
        Some(Scalar::U64(n)) => Ok(n),
        Some(n @ (Scalar::I64(_) | Scalar::F64(_))) => Err(format!(
            "field `{field}`: {n} is not a non-negative integer"
        )),
        Some(o) => Err(format!(
            "field `{field}`: expected a non-negative integer, found {}",
            o.kind()
        )),
        None => Err(format!("missing field `{field}`")),
    }
}

/// A non-negative integer of 32 bits.
pub(super) fn want_u32(v: Option<Scalar>, field: &dyn fmt::Display) -> Result<u32, String> {
    let n = want_u64(v, field)?;
    u32::try_from(n).map_err(|_| format!("field `{field}`: {n} does not fit 32 bits"))
}

/// Deserialises a map key as one of `names` (its index), or `None` for any other
/// key, without allocating for keys written without escapes.
pub(super) struct KeyIn(pub(super) &'static [&'static str]);

impl<'de> de::DeserializeSeed<'de> for KeyIn {
    type Value = Option<usize>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Option<usize>, D::Error> {
        d.deserialize_identifier(self)
    }
}

impl<'de> Visitor<'de> for KeyIn {
    type Value = Option<usize>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a key")
    }
    fn visit_str<E>(self, v: &str) -> Result<Option<usize>, E> {
        Ok(self.0.iter().position(|k| *k == v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scalar(json: &str) -> Scalar {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn scalars_keep_numbers_and_kinds() {
        assert_eq!(scalar("5"), Scalar::U64(5));
        assert_eq!(scalar("-5"), Scalar::I64(-5));
        assert_eq!(scalar("[1,[2,{\"a\":3}]]"), Scalar::Array);
        assert_eq!(scalar("{\"a\":[1]}"), Scalar::Object);
        assert_eq!(scalar("\"s\""), Scalar::String);
        assert_eq!(scalar("null").kind(), "null");
        assert_eq!(Scalar::F64(1.5).to_string(), "1.5");
        assert_eq!(
            want_u64(Some(scalar("1.5")), &"t_us").unwrap_err(),
            "field `t_us`: 1.5 is not a non-negative integer"
        );
        assert_eq!(
            want_f64(Some(Scalar::String), &"x").unwrap_err(),
            "field `x`: expected a number, found a string"
        );
        assert_eq!(
            want_u32(Some(Scalar::U64(1 << 40)), &"n").unwrap_err(),
            "field `n`: 1099511627776 does not fit 32 bits"
        );
        let e = Element {
            list: "contacts",
            index: 2,
            key: "x",
        };
        assert_eq!(e.to_string(), "contacts[2].x");
    }
}
