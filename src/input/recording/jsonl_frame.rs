//! One frame line of a crowdtouch JSON Lines recording, deserialised in place:
//! its contacts go into a fixed array, refused past the cap (the header's
//! `max_contacts`, at most [`MAX_CONTACTS`]) before anything is allocated, and
//! the values of unknown keys are skipped unread.

use super::jsonl_values::{want_f64, want_u32, want_u64, Element, KeyIn, Scalar};
use crate::input::AxisRange;
use crate::vocab::{Contact, ContactFlags, ContactId, MAX_CONTACTS};
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// One contact of a frame, still in file terms.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct FileContact {
    pub(super) file_id: u32,
    pub(super) contact: Contact,
}

/// The contacts and cancelled ids of one frame line; reused from line to line.
#[derive(Clone, Debug)]
pub(super) struct FrameLine {
    pub(super) contacts: [FileContact; MAX_CONTACTS],
    pub(super) len: usize,
    pub(super) cancelled: [u32; MAX_CONTACTS],
    pub(super) cancelled_len: usize,
}

impl Default for FrameLine {
    fn default() -> Self {
        FrameLine {
            contacts: [FileContact::default(); MAX_CONTACTS],
            len: 0,
            cancelled: [0; MAX_CONTACTS],
            cancelled_len: 0,
        }
    }
}

impl FrameLine {
    pub(super) fn contacts(&self) -> &[FileContact] {
        &self.contacts[..self.len]
    }

    pub(super) fn contacts_mut(&mut self) -> &mut [FileContact] {
        &mut self.contacts[..self.len]
    }

    pub(super) fn cancelled(&self) -> &[u32] {
        &self.cancelled[..self.cancelled_len]
    }
}

/// What a frame line is read against: the header's axes and contact cap.
#[derive(Copy, Clone, Debug)]
pub(super) struct FrameRules {
    pub(super) x: AxisRange,
    pub(super) y: AxisRange,
    /// Most contacts a frame may list.
    pub(super) cap: usize,
    /// Whether the cap is the header's `device.max_contacts` (else [`MAX_CONTACTS`]).
    pub(super) cap_is_header: bool,
}

/// Reads a frame line into `out`, returning its `t_us`; `size_dropped` is set
/// when a contact size had to be dropped (unknown X resolution).
///
/// # Errors
/// What is wrong and in which field (`contacts[1].x`), or `invalid JSON at
/// column …` for text that is not JSON.
pub(super) fn parse_frame(
    line: &str,
    rules: &FrameRules,
    out: &mut FrameLine,
    size_dropped: &mut bool,
) -> Result<u64, String> {
    out.len = 0;
    out.cancelled_len = 0;
    let mut ctx = Ctx {
        rules,
        out,
        size_dropped,
        err: None,
    };
    let mut de = serde_json::Deserializer::from_str(line);
    let r = FrameSeed(&mut ctx)
        .deserialize(&mut de)
        .and_then(|t| de.end().map(|()| t));
    r.map_err(|e| {
        ctx.err
            .take()
            .unwrap_or_else(|| format!("invalid JSON at column {}: {e}", e.column()))
    })
}

/// The state a line's visitors share; `err` holds the message of a field problem
/// (the serde error then only unwinds).
struct Ctx<'a> {
    rules: &'a FrameRules,
    out: &'a mut FrameLine,
    size_dropped: &'a mut bool,
    err: Option<String>,
}

impl Ctx<'_> {
    fn fail<E: de::Error>(&mut self, message: String) -> E {
        self.err = Some(message);
        E::custom("field")
    }
}

/// Checks a field value, recording its message as the line's error.
fn check<T, E: de::Error>(ctx: &mut Ctx<'_>, r: Result<T, String>) -> Result<T, E> {
    r.map_err(|m| ctx.fail(m))
}

/// The `visit_*` methods of a seed that only names the kind of value it did not
/// expect, through the seed's own `kind_error`.
macro_rules! kind_errors {
    () => {
        fn visit_unit<E: de::Error>(self) -> Result<Self::Value, E> {
            Err(self.kind_error("null"))
        }
        kind_errors!(not_null);
    };
    (not_null) => {
        fn visit_str<E: de::Error>(self, _: &str) -> Result<Self::Value, E> {
            Err(self.kind_error("a string"))
        }
        fn visit_u64<E: de::Error>(self, _: u64) -> Result<Self::Value, E> {
            Err(self.kind_error("a number"))
        }
        fn visit_i64<E: de::Error>(self, _: i64) -> Result<Self::Value, E> {
            Err(self.kind_error("a number"))
        }
        fn visit_f64<E: de::Error>(self, _: f64) -> Result<Self::Value, E> {
            Err(self.kind_error("a number"))
        }
        fn visit_bool<E: de::Error>(self, _: bool) -> Result<Self::Value, E> {
            Err(self.kind_error("a boolean"))
        }
    };
}

struct FrameSeed<'a, 'b>(&'a mut Ctx<'b>);

const FRAME_KEYS: &[&str] = &["t_us", "contacts", "cancelled", "format"];

impl<'de> DeserializeSeed<'de> for FrameSeed<'_, '_> {
    type Value = u64;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<u64, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for FrameSeed<'_, '_> {
    type Value = u64;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON object")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<u64, A::Error> {
        let ctx = self.0;
        let mut t_us = None;
        let mut has_contacts = false;
        while let Some(key) = map.next_key_seed(KeyIn(FRAME_KEYS))? {
            match key {
                Some(0) => t_us = Some(map.next_value::<Scalar>()?),
                Some(1) => {
                    ctx.out.len = 0;
                    map.next_value_seed(ContactsSeed(&mut *ctx))?;
                    has_contacts = true;
                }
                Some(2) => {
                    ctx.out.cancelled_len = 0;
                    map.next_value_seed(CancelledSeed(&mut *ctx))?;
                }
                Some(_) => return Err(ctx.fail("a second header line".to_string())),
                None => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        let t = check(ctx, want_u64(t_us, &"t_us"))?;
        if !has_contacts {
            return Err(ctx.fail("missing field `contacts`".to_string()));
        }
        Ok(t)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, _: A) -> Result<u64, A::Error> {
        Err(self.kind_error("an array"))
    }
    kind_errors!();
}

impl FrameSeed<'_, '_> {
    fn kind_error<E: de::Error>(self, kind: &str) -> E {
        self.0.fail(format!("expected a JSON object, found {kind}"))
    }
}

struct ContactsSeed<'a, 'b>(&'a mut Ctx<'b>);

impl<'de> DeserializeSeed<'de> for ContactsSeed<'_, '_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for ContactsSeed<'_, '_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an array of contacts")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let ctx = self.0;
        loop {
            let i = ctx.out.len;
            if i == ctx.rules.cap {
                // One more element would not fit: refuse before reading it.
                if seq.next_element::<IgnoredAny>()?.is_none() {
                    return Ok(());
                }
                let m = if ctx.rules.cap_is_header {
                    format!(
                        "field `contacts`: more than the {} contacts the header's \
                         `device.max_contacts` allows",
                        ctx.rules.cap
                    )
                } else {
                    format!("field `contacts`: more than the {MAX_CONTACTS} contacts a frame holds")
                };
                return Err(ctx.fail(m));
            }
            match seq.next_element_seed(ContactSeed { ctx: &mut *ctx, i })? {
                Some(c) => {
                    ctx.out.contacts[i] = c;
                    ctx.out.len += 1;
                }
                None => return Ok(()),
            }
        }
    }
    fn visit_map<A: MapAccess<'de>>(self, _: A) -> Result<(), A::Error> {
        Err(self.kind_error("an object"))
    }
    kind_errors!();
}

impl ContactsSeed<'_, '_> {
    fn kind_error<E: de::Error>(self, kind: &str) -> E {
        self.0
            .fail(format!("field `contacts`: expected an array, found {kind}"))
    }
}

struct ContactSeed<'a, 'b> {
    ctx: &'a mut Ctx<'b>,
    i: usize,
}

const CONTACT_KEYS: &[&str] = &["id", "x", "y", "pressure", "major", "minor", "palm"];

impl<'de> DeserializeSeed<'de> for ContactSeed<'_, '_> {
    type Value = FileContact;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<FileContact, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for ContactSeed<'_, '_> {
    type Value = FileContact;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a contact object")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<FileContact, A::Error> {
        let (ctx, i) = (self.ctx, self.i);
        let f = |key: &'static str| Element {
            list: "contacts",
            index: i,
            key,
        };
        let mut v: [Option<Scalar>; 7] = [None; 7];
        while let Some(key) = map.next_key_seed(KeyIn(CONTACT_KEYS))? {
            match key {
                Some(k) => v[k] = Some(map.next_value::<Scalar>()?),
                None => {
                    map.next_value::<IgnoredAny>()?;
                }
            }
        }
        let file_id = check(ctx, want_u32(v[0], &f("id")))?;
        if ctx.out.contacts().iter().any(|c| c.file_id == file_id) {
            let m = format!(
                "field `{}`: id {file_id} appears twice in the frame",
                f("id")
            );
            return Err(ctx.fail(m));
        }
        let x = check(ctx, want_f64(v[1], &f("x")))?;
        let y = check(ctx, want_f64(v[2], &f("y")))?;
        let opt = |k: usize| -> Result<Option<f64>, String> {
            match v[k] {
                None | Some(Scalar::Null) => Ok(None),
                s => {
                    let x = want_f64(s, &f(CONTACT_KEYS[k]))?;
                    if x < 0.0 {
                        return Err(format!("field `{}`: {x} is negative", f(CONTACT_KEYS[k])));
                    }
                    Ok(Some(x))
                }
            }
        };
        let pressure = check(ctx, opt(3))?;
        if let Some(p) = pressure {
            if p > 1.0 {
                let m = format!("field `{}`: {p} is outside 0..=1", f("pressure"));
                return Err(ctx.fail(m));
            }
        }
        let major = check(ctx, opt(4))?;
        let minor = check(ctx, opt(5))?;
        let resolution = ctx.rules.x.resolution;
        // A size in mm needs the X resolution; without it sizes are dropped.
        let to_mm =
            |v: Option<f64>| v.map(|v| (resolution > 0.0).then_some((v / resolution) as f32));
        let (major_mm, minor_mm) = (to_mm(major), to_mm(minor));
        if major_mm == Some(None) || minor_mm == Some(None) {
            *ctx.size_dropped = true;
        }
        let (major_mm, minor_mm) = (major_mm.flatten(), minor_mm.flatten());
        let palm = match v[6] {
            None | Some(Scalar::Null) => false,
            Some(Scalar::Bool(b)) => b,
            Some(o) => {
                let m = format!(
                    "field `{}`: expected a boolean, found {}",
                    f("palm"),
                    o.kind()
                );
                return Err(ctx.fail(m));
            }
        };
        Ok(FileContact {
            file_id,
            contact: Contact {
                id: ContactId(0),
                x: ctx.rules.x.normalise(x),
                y: ctx.rules.y.normalise(y),
                pressure: pressure.map(|p| p as f32),
                major_mm,
                minor_mm,
                flags: if palm {
                    ContactFlags::PALM
                } else {
                    ContactFlags::NONE
                },
            },
        })
    }
    fn visit_seq<A: SeqAccess<'de>>(self, _: A) -> Result<FileContact, A::Error> {
        Err(self.kind_error("an array"))
    }
    kind_errors!();
}

impl ContactSeed<'_, '_> {
    fn kind_error<E: de::Error>(self, kind: &str) -> E {
        let m = format!(
            "field `contacts[{}]`: expected an object, found {kind}",
            self.i
        );
        self.ctx.fail(m)
    }
}

struct CancelledSeed<'a, 'b>(&'a mut Ctx<'b>);

impl<'de> DeserializeSeed<'de> for CancelledSeed<'_, '_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for CancelledSeed<'_, '_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("an array of ids")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let ctx = self.0;
        loop {
            let i = ctx.out.cancelled_len;
            let Some(v) = seq.next_element::<Scalar>()? else {
                return Ok(());
            };
            if i == MAX_CONTACTS {
                let m = format!("field `cancelled`: more than {MAX_CONTACTS} ids");
                return Err(ctx.fail(m));
            }
            let field = Element {
                list: "cancelled",
                index: i,
                key: "",
            };
            ctx.out.cancelled[i] = check(ctx, want_u32(Some(v), &field))?;
            ctx.out.cancelled_len += 1;
        }
    }
    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(self, _: A) -> Result<(), A::Error> {
        Err(self.kind_error("an object"))
    }
    kind_errors!(not_null);
}

impl CancelledSeed<'_, '_> {
    fn kind_error<E: de::Error>(self, kind: &str) -> E {
        self.0.fail(format!(
            "field `cancelled`: expected an array, found {kind}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rules(cap: usize) -> FrameRules {
        let axis = AxisRange {
            min: 0.0,
            max: 100.0,
            resolution: 0.0,
        };
        FrameRules {
            x: axis,
            y: axis,
            cap,
            cap_is_header: true,
        }
    }

    fn parse(line: &str, cap: usize) -> Result<(u64, FrameLine), String> {
        let mut out = FrameLine::default();
        let mut dropped = false;
        parse_frame(line, &rules(cap), &mut out, &mut dropped).map(|t| (t, out))
    }

    #[test]
    fn a_frame_line_reads_into_the_fixed_array() {
        let (t, f) = parse(
            r#"{"t_us":7,"note":{"deep":[1,[2,3]]},"contacts":[{"id":4,"x":50,"y":25,"palm":true,"extra":[1]}],"cancelled":[9]}"#,
            2,
        )
        .unwrap();
        assert_eq!(t, 7);
        assert_eq!(f.contacts().len(), 1);
        assert_eq!(f.contacts()[0].file_id, 4);
        assert_eq!(f.contacts()[0].contact.flags, ContactFlags::PALM);
        assert!((f.contacts()[0].contact.x - 0.5).abs() < 1e-6);
        assert_eq!(f.cancelled(), &[9]);
    }

    #[test]
    fn field_problems_name_the_field() {
        let cases = [
            (
                r#"{"t_us":1,"contacts":[{"id":1,"x":1,"y":1},{"id":2,"x":1,"y":1},{"id":3,"x":1,"y":1}]}"#,
                "max_contacts",
            ),
            (
                r#"{"t_us":1,"contacts":[{"id":1,"x":1,"y":1,"palm":3}]}"#,
                "contacts[0].palm",
            ),
            (
                r#"{"t_us":1,"contacts":[5]}"#,
                "field `contacts[0]`: expected an object, found a number",
            ),
            (
                r#"{"t_us":1,"contacts":{}}"#,
                "field `contacts`: expected an array, found an object",
            ),
            (
                r#"{"t_us":1,"contacts":[],"cancelled":"x"}"#,
                "field `cancelled`",
            ),
            (
                r#"{"t_us":1,"contacts":[],"cancelled":[-1]}"#,
                "cancelled[0]",
            ),
            (
                r#"{"t_us":1,"contacts":[{"id":1,"x":1,"y":1,"major":-2}]}"#,
                "is negative",
            ),
            (r#"{"contacts":[]}"#, "missing field `t_us`"),
            (r#"{"format":"crowdtouch-touch"}"#, "a second header line"),
            (r#"[1,2]"#, "expected a JSON object, found an array"),
            (r#"{"t_us":1,"contacts":[]} x"#, "invalid JSON at column"),
        ];
        for (line, want) in cases {
            let err = parse(line, 2).unwrap_err();
            assert!(err.contains(want), "{line}: {err}");
        }
    }
}
