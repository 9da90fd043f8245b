//! An OSC 1.0 reader for the subset TUIO uses, reading in place: no allocation.
//!
//! A packet is a message or a bundle (`#bundle\0`, an 8-byte time tag, then
//! elements, each an `int32` size and a packet, bundles nesting up to
//! [`MAX_DEPTH`]). A message is an address (`/…`), a type tag string (`,…`) and the
//! arguments it announces, every string NUL-terminated and padded to 4 bytes, every
//! number big-endian. The tags read are `s i f h d t T F N`; any other (blobs `b`,
//! `c`, `r`, `m`, arrays `[ ]` …) is refused naming its byte offset in the packet.
//!
//! [`walk`] checks a whole packet first and only then hands its messages, in order,
//! to a callback: a malformed packet delivers nothing. A [`Message`]'s arguments are
//! decoded on demand from the checked bytes.

/// Deepest bundle nesting read (a bundle in a bundle is depth 2).
pub const MAX_DEPTH: usize = 8;

/// What is wrong with a packet, and at which byte of it.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("byte {offset}: {kind}")]
pub struct OscError {
    /// Byte offset in the packet where the problem is.
    pub offset: usize,
    /// The problem.
    pub kind: OscErrorKind,
}

/// The problems [`walk`] reports.
#[derive(Copy, Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OscErrorKind {
    /// The packet (or an element) is empty.
    #[error("empty packet")]
    Empty,
    /// The bytes end inside a string, a number or an element.
    #[error("packet ends early")]
    Truncated,
    /// A length or a string end that is not a multiple of 4.
    #[error("not aligned to 4 bytes")]
    Unaligned,
    /// A string that is not UTF-8.
    #[error("string is not UTF-8")]
    NotUtf8,
    /// An address that does not start with `/`.
    #[error("address does not start with '/'")]
    BadAddress,
    /// A message without a type tag string (old OSC).
    #[error("message has no type tag string (',')")]
    NoTypeTags,
    /// A type tag outside `s i f h d t T F N`.
    #[error("unknown type tag {0:?}")]
    UnknownTag(char),
    /// A bundle element whose size is negative, unaligned or past the end.
    #[error("bad bundle element size {0}")]
    BadElementSize(i32),
    /// Bundles nested deeper than [`MAX_DEPTH`].
    #[error("bundles nested deeper than {MAX_DEPTH}")]
    TooDeep,
    /// Bytes after the last argument of a message.
    #[error("{0} bytes after the last argument")]
    Trailing(usize),
}

/// One argument of a message.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Arg<'a> {
    /// `i`.
    Int(i32),
    /// `f`.
    Float(f32),
    /// `s`.
    Str(&'a str),
    /// `h`.
    Long(i64),
    /// `d`.
    Double(f64),
    /// `t`: an NTP time tag.
    Time(u64),
    /// `T`.
    True,
    /// `F`.
    False,
    /// `N`.
    Nil,
}

impl<'a> Arg<'a> {
    /// The argument as a number, if it is one (`i f h d`).
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Arg::Int(v) => Some(f64::from(v)),
            Arg::Float(v) => Some(f64::from(v)),
            Arg::Long(v) => Some(v as f64),
            Arg::Double(v) => Some(v),
            _ => None,
        }
    }

    /// The argument as an integer, if it is one (`i h`).
    pub fn as_i64(&self) -> Option<i64> {
        match *self {
            Arg::Int(v) => Some(i64::from(v)),
            Arg::Long(v) => Some(v),
            _ => None,
        }
    }

    /// The argument as a string, if it is one.
    pub fn as_str(self) -> Option<&'a str> {
        match self {
            Arg::Str(s) => Some(s),
            _ => None,
        }
    }
}

/// A checked message: its address and its arguments, decoded on demand.
#[derive(Copy, Clone, Debug)]
pub struct Message<'a> {
    /// The address pattern (`/tuio/2Dcur`).
    pub address: &'a str,
    /// Type tags without the leading `,`.
    tags: &'a [u8],
    /// The argument bytes.
    data: &'a [u8],
}

impl<'a> Message<'a> {
    /// Number of arguments.
    pub fn len(&self) -> usize {
        self.tags.len()
    }

    /// Whether the message has no argument.
    pub fn is_empty(&self) -> bool {
        self.tags.is_empty()
    }

    /// The arguments, in order.
    pub fn args(&self) -> Args<'a> {
        Args {
            tags: self.tags,
            data: self.data,
            pos: 0,
        }
    }

    /// The argument at `i`, if there is one.
    pub fn arg(&self, i: usize) -> Option<Arg<'a>> {
        self.args().nth(i)
    }
}

/// The arguments of a [`Message`].
#[derive(Clone, Debug)]
pub struct Args<'a> {
    tags: &'a [u8],
    data: &'a [u8],
    pos: usize,
}

impl<'a> Iterator for Args<'a> {
    type Item = Arg<'a>;

    fn next(&mut self) -> Option<Arg<'a>> {
        let (&tag, rest) = self.tags.split_first()?;
        self.tags = rest;
        // The bytes were checked by `walk`: a failure here would be a bug; it ends
        // the arguments rather than panicking.
        let (arg, used) = read_arg(tag, self.data, self.pos).ok()?;
        self.pos += used;
        Some(arg)
    }
}

fn err(offset: usize, kind: OscErrorKind) -> OscError {
    OscError { offset, kind }
}

/// Reads `N` bytes at `at`.
fn bytes<const N: usize>(b: &[u8], at: usize) -> Result<[u8; N], OscError> {
    b.get(at..at + N)
        .and_then(|s| s.try_into().ok())
        .ok_or(err(at, OscErrorKind::Truncated))
}

/// Reads a padded string at `at`; returns it and the bytes it takes (padding included).
fn read_str(b: &[u8], at: usize) -> Result<(&str, usize), OscError> {
    let rest = b.get(at..).unwrap_or(&[]);
    let Some(nul) = rest.iter().position(|&c| c == 0) else {
        return Err(err(b.len(), OscErrorKind::Truncated));
    };
    let padded = (nul + 4) & !3;
    if rest.len() < padded {
        return Err(err(b.len(), OscErrorKind::Truncated));
    }
    if rest[nul..padded].iter().any(|&c| c != 0) {
        return Err(err(at + nul, OscErrorKind::Unaligned));
    }
    let s = std::str::from_utf8(&rest[..nul])
        .map_err(|e| err(at + e.valid_up_to(), OscErrorKind::NotUtf8))?;
    Ok((s, padded))
}

/// Reads one argument of type `tag` at `at`; returns it and the bytes it takes.
fn read_arg(tag: u8, b: &[u8], at: usize) -> Result<(Arg<'_>, usize), OscError> {
    Ok(match tag {
        b'i' => (Arg::Int(i32::from_be_bytes(bytes(b, at)?)), 4),
        b'f' => (Arg::Float(f32::from_be_bytes(bytes(b, at)?)), 4),
        b'h' => (Arg::Long(i64::from_be_bytes(bytes(b, at)?)), 8),
        b'd' => (Arg::Double(f64::from_be_bytes(bytes(b, at)?)), 8),
        b't' => (Arg::Time(u64::from_be_bytes(bytes(b, at)?)), 8),
        b's' => {
            let (s, n) = read_str(b, at)?;
            (Arg::Str(s), n)
        }
        b'T' => (Arg::True, 0),
        b'F' => (Arg::False, 0),
        b'N' => (Arg::Nil, 0),
        other => return Err(err(at, OscErrorKind::UnknownTag(char::from(other)))),
    })
}

/// Checks a message occupying all of `b` (which starts at `base` in the packet).
fn check_message(b: &[u8], base: usize) -> Result<Message<'_>, OscError> {
    let at = |o: usize| base + o;
    let (address, n) = read_str(b, 0).map_err(|e| err(at(e.offset), e.kind))?;
    if !address.starts_with('/') {
        return Err(err(at(0), OscErrorKind::BadAddress));
    }
    if b.get(n) != Some(&b',') {
        return Err(err(at(n), OscErrorKind::NoTypeTags));
    }
    let (tags, m) = read_str(b, n).map_err(|e| err(at(e.offset), e.kind))?;
    let tags = &tags.as_bytes()[1..];
    let data = &b[n + m..];
    let mut pos = 0;
    for (i, &tag) in tags.iter().enumerate() {
        if !b"ifhdtsTFN".contains(&tag) {
            return Err(err(
                at(n + 1 + i),
                OscErrorKind::UnknownTag(char::from(tag)),
            ));
        }
        let (_, used) = read_arg(tag, data, pos).map_err(|e| err(at(n + m + e.offset), e.kind))?;
        pos += used;
    }
    if pos != data.len() {
        return Err(err(
            at(n + m + pos),
            OscErrorKind::Trailing(data.len() - pos),
        ));
    }
    Ok(Message {
        address,
        tags,
        data,
    })
}

const BUNDLE: &[u8; 8] = b"#bundle\0";

/// Checks (when `deliver` is None) or delivers the packet `b` at `base`.
fn visit<'a>(
    b: &'a [u8],
    base: usize,
    depth: usize,
    deliver: &mut Option<&mut dyn FnMut(Message<'a>)>,
) -> Result<(), OscError> {
    if b.is_empty() {
        return Err(err(base, OscErrorKind::Empty));
    }
    if b.len() % 4 != 0 {
        return Err(err(base + b.len(), OscErrorKind::Unaligned));
    }
    if !b.starts_with(BUNDLE) {
        let m = check_message(b, base)?;
        if let Some(f) = deliver {
            f(m);
        }
        return Ok(());
    }
    if depth >= MAX_DEPTH {
        return Err(err(base, OscErrorKind::TooDeep));
    }
    if b.len() < 16 {
        return Err(err(base + b.len(), OscErrorKind::Truncated));
    }
    let mut pos = 16;
    while pos < b.len() {
        let size = i32::from_be_bytes(bytes(b, pos).map_err(|e| err(base + e.offset, e.kind))?);
        let start = pos + 4;
        let end = usize::try_from(size)
            .ok()
            .and_then(|s| start.checked_add(s))
            .filter(|&e| e <= b.len() && size % 4 == 0);
        let Some(end) = end else {
            return Err(err(base + pos, OscErrorKind::BadElementSize(size)));
        };
        visit(&b[start..end], base + start, depth + 1, deliver)?;
        pos = end;
    }
    Ok(())
}

/// Checks the packet `b`, then calls `f` with each of its messages in order (those
/// of nested bundles in place). Allocates nothing.
///
/// # Errors
/// The first problem found, at its byte offset; `f` is then not called at all.
///
/// # Complexity
/// Two passes over the bytes; nesting is capped at [`MAX_DEPTH`].
pub fn walk<'a>(b: &'a [u8], f: &mut dyn FnMut(Message<'a>)) -> Result<(), OscError> {
    visit(b, 0, 0, &mut None)?;
    visit(b, 0, 0, &mut Some(f))
}

#[cfg(test)]
#[path = "osc_tests.rs"]
mod tests;
