//! TUIO cursor sessions into touch frames: the state of every sender, fed one OSC
//! packet at a time. Pure: given the bytes, the peer and `now`; no allocation.
//!
//! # Profiles
//!
//! * TUIO 1.1 `/tuio/2Dcur`: `source name@host`, `alive s…`, `set s x y X Y m`,
//!   `fseq f`. A frame is complete at `fseq`; `fseq -1` means "apply now" (no
//!   order). A large set split over several bundles repeats `alive` and `fseq`:
//!   a bundle with the same `fseq` as the last one applied is applied too.
//! * TUIO 2.0: `/tuio2/frm f time dim source` starts a frame, `/tuio2/ptr s tu c
//!   x y …` are its pointers, `/tuio2/alv s…` ends it (and lists every session
//!   alive, tokens and bounds too).
//! * Objects, blobs, tokens, bounds and the other profiles (`/tuio/2Dobj`,
//!   `/tuio/2Dblb`, `/tuio/25D…`, `/tuio/3D…`, `/tuio2/tok`, `/tuio2/bnd`, …) are
//!   ignored and counted; an address outside `/tuio/` and `/tuio2/` is counted
//!   as unknown and logged.
//!
//! # Senders
//!
//! A sender is a peer address and a source name (the `source` of TUIO 1.1, the
//! `frm` source of 2.0; empty when not sent): two trackers behind one address,
//! or one tracker sending from two ports, stay apart. Each sender's frame ids are
//! ordered on their own: a frame older than the last one applied (UDP reorders)
//! is dropped, unless it is more than [`REORDER_WINDOW`] older, which is a sender
//! that started again. At most [`TuioLimits::senders`] senders are followed (the
//! config's `max_senders`, [`DEFAULT_MAX_SENDERS`] unless set); a frame of another
//! sender is refused, counted in `senders_refused` and logged at a falling rate,
//! unless a followed sender has nothing down, whose place it then takes. A sender
//! silent for the timeout has its sessions ended (`CANCELLED`) and its place freed.
//!
//! # Sessions
//!
//! A session seen in a `set`/`ptr` (and in the frame's alive list, when it has
//! one) begins with `DOWN`; it moves while it stays alive; it ends with `UP` in
//! the first frame whose alive list lacks it. Contacts get ids from one counter
//! of the decoder, so they are unique across senders; positions are the TUIO
//! unit square ((0,0) top-left), clamped. Frames are stamped with `now`, the
//! receipt time. Each sender's frame lists all its sessions down, plus those
//! that ended.
//!
//! A sender has at most [`TuioLimits::sessions_per_frame`] sessions down (the
//! config's `max_sessions_per_frame`, at most a touch frame's [`MAX_CONTACTS`]);
//! every further session in each of its frames is refused, counted in
//! `sessions_refused` and logged at a falling rate. A frame lists at most
//! [`MAX_ALIVE`] sessions; the `set`/`ptr` messages past that many are refused too.
//!
//! # Memory
//!
//! Every buffer is sized when the decoder is made (the sender table from the
//! limits); reading a datagram allocates nothing.

use super::osc::{walk, Message, OscError};
use crate::input::FrameSink;
use crate::vocab::{Contact, ContactFlags, ContactId, Micros, TouchFrame, MAX_CONTACTS};
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};

/// Senders followed at once unless the config says otherwise (`max_senders`).
pub const DEFAULT_MAX_SENDERS: usize = 8;

/// The most senders a decoder may be told to follow (each holds a touch frame's
/// worth of sessions, about 2 KiB).
pub const MOST_SENDERS: usize = 64;

/// The limits of a TUIO input, from its config entry (`Tuio(max_sessions_per_frame:
/// …, max_senders: …, max_packets_per_s: …)`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct TuioLimits {
    /// Sessions one sender may have down, that is cursors in one of its frames;
    /// 1 ..= [`MAX_CONTACTS`].
    pub sessions_per_frame: usize,
    /// Senders followed at once; 1 ..= [`MOST_SENDERS`].
    pub senders: usize,
    /// Datagrams taken from one peer address (ip:port) per second, in a token
    /// bucket holding one second's worth; further ones are dropped and counted in
    /// `flood_dropped` (see the source).
    pub packets_per_s: u32,
}

impl Default for TuioLimits {
    /// 64 sessions a frame (a touch frame's capacity), 8 senders, 4,000 datagrams
    /// a second from each peer.
    fn default() -> Self {
        TuioLimits {
            sessions_per_frame: MAX_CONTACTS,
            senders: DEFAULT_MAX_SENDERS,
            packets_per_s: super::flood::DEFAULT_MAX_PACKETS_PER_S,
        }
    }
}

/// A frame id this much older than the last one applied is a sender that started
/// again, not a reordered datagram.
pub const REORDER_WINDOW: i64 = 256;

/// Sessions listed in one alive message that are kept (TUIO 2.0 lists tokens and
/// bounds too); further ones are ignored and counted as malformed. Also the most
/// `set`/`ptr` messages kept from one frame.
pub const MAX_ALIVE: usize = 256;

/// Bytes of a source name kept (longer names are cut).
const NAME_BYTES: usize = 64;

/// What the TUIO input counted since it started; read lock-free by anyone.
#[derive(Debug, Default)]
pub struct TuioCounters {
    /// Datagrams received.
    pub packets: AtomicU64,
    /// Frames applied (complete at `fseq` or `alv`).
    pub frames: AtomicU64,
    /// Datagrams that are not valid OSC, or TUIO messages with bad arguments.
    pub malformed: AtomicU64,
    /// Frames dropped for being older than the last one of their sender.
    pub stale_frames: AtomicU64,
    /// Cursor messages never completed by an `fseq` (1.1) or `alv` (2.0).
    pub without_fseq: AtomicU64,
    /// Messages of profiles this input does not use (objects, blobs, tokens, …).
    pub ignored: AtomicU64,
    /// Messages outside TUIO, or unknown 2Dcur commands.
    pub unknown: AtomicU64,
    /// Frames of a new sender refused because [`TuioLimits::senders`] were
    /// followed, each with something down.
    pub senders_refused: AtomicU64,
    /// Sessions not begun because their sender already had
    /// [`TuioLimits::sessions_per_frame`] down (counted in every frame that lists
    /// them), or because the frame listed more than [`MAX_ALIVE`].
    pub sessions_refused: AtomicU64,
    /// Senders that went silent with sessions down.
    pub timeouts: AtomicU64,
    /// Datagrams dropped because their peer sent more than
    /// [`TuioLimits::packets_per_s`] (see the source).
    pub flood_dropped: AtomicU64,
}

impl TuioCounters {
    /// The counts for `stats` (its `outputs` list, as `tuio-input` at `address`).
    pub fn report(&self, address: &str) -> crate::vocab::OutputCounters {
        let counts = [
            ("packets", &self.packets),
            ("frames", &self.frames),
            ("malformed", &self.malformed),
            ("stale_frames", &self.stale_frames),
            ("without_fseq", &self.without_fseq),
            ("ignored", &self.ignored),
            ("unknown", &self.unknown),
            ("senders_refused", &self.senders_refused),
            ("sessions_refused", &self.sessions_refused),
            ("timeouts", &self.timeouts),
            ("flood_dropped", &self.flood_dropped),
        ];
        crate::vocab::OutputCounters {
            output: "tuio-input".to_string(),
            address: address.to_string(),
            counts: counts
                .iter()
                .map(|(k, v)| (k.to_string(), v.load(Ordering::Relaxed)))
                .collect(),
        }
    }
}

fn bump(c: &AtomicU64) -> u64 {
    c.fetch_add(1, Ordering::Relaxed) + 1
}

/// Adds `n` to `c`; the new count when a power of two lies in the counts passed
/// (time to log, as [`log_rare`] would for one at a time).
fn bump_by(c: &AtomicU64, n: u64) -> Option<u64> {
    if n == 0 {
        return None;
    }
    let old = c.fetch_add(n, Ordering::Relaxed);
    let new = old.saturating_add(n);
    (1u64 << new.ilog2() > old).then_some(new)
}

/// Logs a problem with a sender at a falling rate: the 1st, 2nd, 4th, 8th … time.
pub(super) fn log_rare(count: u64, peer: SocketAddr, what: &dyn std::fmt::Display) {
    if count.is_power_of_two() {
        log::warn!("tuio from {peer}: {what} (seen {count} times)");
    }
}

#[derive(Copy, Clone, Debug, Default)]
struct Session {
    tuio: i64,
    local: u32,
    x: f32,
    y: f32,
    /// Began in the frame being built.
    new: bool,
}

#[derive(Clone, Debug)]
struct Sender {
    used: bool,
    peer: Option<SocketAddr>,
    name: [u8; NAME_BYTES],
    name_len: usize,
    sessions: [Session; MAX_CONTACTS],
    len: usize,
    last_frame: Option<i64>,
    last_heard: Micros,
}

impl Default for Sender {
    fn default() -> Self {
        Sender {
            used: false,
            peer: None,
            name: [0; NAME_BYTES],
            name_len: 0,
            sessions: [Session::default(); MAX_CONTACTS],
            len: 0,
            last_frame: None,
            last_heard: Micros::ZERO,
        }
    }
}

impl Sender {
    fn is(&self, peer: SocketAddr, name: &[u8]) -> bool {
        self.used && self.peer == Some(peer) && &self.name[..self.name_len] == name
    }
}

/// The frame being gathered from one datagram.
#[derive(Clone, Debug)]
struct Pending {
    /// A cursor message came since the last complete frame.
    started: bool,
    name: [u8; NAME_BYTES],
    name_len: usize,
    alive: [i64; MAX_ALIVE],
    alive_len: usize,
    alive_seen: bool,
    sets: [(i64, f32, f32); MAX_ALIVE],
    sets_len: usize,
    /// `set`/`ptr` messages past the first [`MAX_ALIVE`] sessions of the frame (not
    /// kept: refused at the commit).
    sets_over: usize,
    /// TUIO 2.0: the `frm` frame id.
    frame: Option<i64>,
}

impl Default for Pending {
    fn default() -> Self {
        Pending {
            started: false,
            name: [0; NAME_BYTES],
            name_len: 0,
            alive: [0; MAX_ALIVE],
            alive_len: 0,
            alive_seen: false,
            sets: [(0, 0.0, 0.0); MAX_ALIVE],
            sets_len: 0,
            sets_over: 0,
            frame: None,
        }
    }
}

impl Pending {
    fn clear(&mut self) {
        self.started = false;
        self.name_len = 0;
        self.alive_len = 0;
        self.alive_seen = false;
        self.sets_len = 0;
        self.sets_over = 0;
        self.frame = None;
    }

    fn set_name(&mut self, s: &str) {
        let n = s.len().min(NAME_BYTES);
        self.name[..n].copy_from_slice(&s.as_bytes()[..n]);
        self.name_len = n;
    }

    fn alive(&self, id: i64) -> bool {
        !self.alive_seen || self.alive[..self.alive_len].contains(&id)
    }
}

/// What a message said that is not cursor data.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Problem {
    BadArgs(&'static str),
    Unknown,
    Ignored,
}

/// Every TUIO sender's sessions, fed datagrams; see the module doc.
#[derive(Debug)]
pub struct TuioDecoder {
    /// [`TuioLimits::senders`] places, made at construction.
    senders: Box<[Sender]>,
    limits: TuioLimits,
    pending: Pending,
    out: TouchFrame,
    next_local: u32,
    timeout: Micros,
    counters: std::sync::Arc<TuioCounters>,
}

impl TuioDecoder {
    /// A decoder with the default [`TuioLimits`], ending the sessions of a sender
    /// silent for `timeout`.
    pub fn new(timeout: Micros, counters: std::sync::Arc<TuioCounters>) -> TuioDecoder {
        TuioDecoder::with_limits(TuioLimits::default(), timeout, counters)
    }

    /// A decoder holding to `limits` (sessions per frame clamped to 1 ..=
    /// [`MAX_CONTACTS`], senders to 1 ..= [`MOST_SENDERS`]), ending the sessions of
    /// a sender silent for `timeout`. Allocates its sender table here, once.
    pub fn with_limits(
        limits: TuioLimits,
        timeout: Micros,
        counters: std::sync::Arc<TuioCounters>,
    ) -> TuioDecoder {
        let limits = TuioLimits {
            sessions_per_frame: limits.sessions_per_frame.clamp(1, MAX_CONTACTS),
            senders: limits.senders.clamp(1, MOST_SENDERS),
            packets_per_s: limits.packets_per_s,
        };
        TuioDecoder {
            senders: (0..limits.senders).map(|_| Sender::default()).collect(),
            limits,
            pending: Pending::default(),
            out: TouchFrame::default(),
            next_local: 1,
            timeout,
            counters,
        }
    }

    /// The limits it holds to.
    pub fn limits(&self) -> TuioLimits {
        self.limits
    }

    /// The counters.
    pub fn counters(&self) -> &TuioCounters {
        &self.counters
    }

    /// Sessions down, over every sender.
    pub fn active_contacts(&self) -> usize {
        self.senders.iter().filter(|s| s.used).map(|s| s.len).sum()
    }

    /// Senders followed.
    pub fn senders(&self) -> usize {
        self.senders.iter().filter(|s| s.used).count()
    }

    /// Reads one datagram from `peer`, received at `now`, and hands every frame it
    /// completes to `sink`.
    ///
    /// # Errors
    /// The OSC problem when the datagram is not a valid OSC packet (counted and
    /// logged; nothing of it is applied). Bad TUIO content is counted and logged,
    /// not returned.
    pub fn packet(
        &mut self,
        bytes: &[u8],
        peer: SocketAddr,
        now: Micros,
        sink: &mut dyn FrameSink,
    ) -> Result<(), OscError> {
        bump(&self.counters.packets);
        self.pending.clear();
        let r = walk(bytes, &mut |m| {
            if let Err(p) = self.message(&m, peer, now, sink) {
                let address = crate::located::Escaped(m.address);
                let (counter, what): (&AtomicU64, &dyn std::fmt::Display) = match p {
                    Problem::BadArgs(what) => (&self.counters.malformed, &Bad(address, what)),
                    Problem::Unknown => (&self.counters.unknown, &Unknown(address)),
                    Problem::Ignored => {
                        bump(&self.counters.ignored);
                        return;
                    }
                };
                log_rare(bump(counter), peer, what);
            }
        });
        if let Err(e) = r {
            log_rare(bump(&self.counters.malformed), peer, &Malformed(e));
            return Err(e);
        }
        if self.pending.started {
            let n = bump(&self.counters.without_fseq);
            log_rare(
                n,
                peer,
                &"cursor messages without an fseq (1.1) or alv (2.0): not applied",
            );
        }
        self.pending.clear();
        Ok(())
    }

    fn message(
        &mut self,
        m: &Message<'_>,
        peer: SocketAddr,
        now: Micros,
        sink: &mut dyn FrameSink,
    ) -> Result<(), Problem> {
        let p = &mut self.pending;
        match m.address {
            "/tuio/2Dcur" => {
                let cmd = m.arg(0).and_then(|a| a.as_str());
                match cmd {
                    Some("source") => {
                        let name = m.arg(1).and_then(|a| a.as_str());
                        p.set_name(name.ok_or(Problem::BadArgs("source without a name"))?);
                        p.started = true;
                    }
                    Some("alive") => {
                        read_alive(p, m.args().skip(1))?;
                        p.started = true;
                    }
                    Some("set") => {
                        let s = m.arg(1).and_then(|a| a.as_i64());
                        let x = m.arg(2).and_then(|a| a.as_f64());
                        let y = m.arg(3).and_then(|a| a.as_f64());
                        let (Some(s), Some(x), Some(y)) = (s, x, y) else {
                            return Err(Problem::BadArgs("set needs s (int), x and y (numbers)"));
                        };
                        push_set(p, s, x, y)?;
                        p.started = true;
                    }
                    Some("fseq") => {
                        let f = m.arg(1).and_then(|a| a.as_i64());
                        let f = f.ok_or(Problem::BadArgs("fseq without a frame number"))?;
                        self.commit(peer, (f != -1).then_some(f), now, sink);
                    }
                    _ => return Err(Problem::Unknown),
                }
            }
            "/tuio2/frm" => {
                let f = m.arg(0).and_then(|a| a.as_i64());
                let f = f.ok_or(Problem::BadArgs("frm without a frame id"))?;
                p.clear();
                if let Some(name) = m.arg(3).and_then(|a| a.as_str()) {
                    p.set_name(name);
                }
                p.frame = Some(f);
                p.started = true;
            }
            "/tuio2/ptr" => {
                let s = m.arg(0).and_then(|a| a.as_i64());
                let x = m.arg(3).and_then(|a| a.as_f64());
                let y = m.arg(4).and_then(|a| a.as_f64());
                let (Some(s), Some(x), Some(y)) = (s, x, y) else {
                    return Err(Problem::BadArgs(
                        "ptr needs s_id, tu_id, c_id (ints), x and y (numbers)",
                    ));
                };
                push_set(p, s, x, y)?;
                p.started = true;
            }
            "/tuio2/alv" => {
                let Some(f) = p.frame else {
                    p.clear();
                    return Err(Problem::BadArgs("alv without a frm before it"));
                };
                read_alive(p, m.args())?;
                self.commit(peer, Some(f), now, sink);
            }
            a if a.starts_with("/tuio/") || a.starts_with("/tuio2/") => {
                return Err(Problem::Ignored)
            }
            _ => return Err(Problem::Unknown),
        }
        Ok(())
    }

    /// Applies the pending frame of `peer` (`frame` None: apply whatever the order).
    fn commit(
        &mut self,
        peer: SocketAddr,
        frame: Option<i64>,
        now: Micros,
        sink: &mut dyn FrameSink,
    ) {
        let p = &self.pending;
        let name = &p.name[..p.name_len];
        let idx = match self.senders.iter().position(|s| s.is(peer, name)) {
            Some(i) => i,
            None => {
                // A free place, else one whose sender has nothing down.
                let free = self.senders.iter().position(|s| !s.used).or_else(|| {
                    (0..self.senders.len())
                        .filter(|&i| self.senders[i].len == 0)
                        .min_by_key(|&i| self.senders[i].last_heard)
                });
                let Some(i) = free else {
                    log_rare(
                        bump(&self.counters.senders_refused),
                        peer,
                        &format_args!(
                            "a new sender while {} (max_senders) hold touches down: its frame is refused",
                            self.senders.len()
                        ),
                    );
                    self.pending.clear();
                    return;
                };
                let s = &mut self.senders[i];
                s.used = true;
                s.peer = Some(peer);
                s.name[..name.len()].copy_from_slice(name);
                s.name_len = name.len();
                s.len = 0;
                s.last_frame = None;
                i
            }
        };
        let s = &mut self.senders[idx];
        s.last_heard = now;
        if let (Some(f), Some(last)) = (frame, s.last_frame) {
            if f < last && last - f <= REORDER_WINDOW {
                bump(&self.counters.stale_frames);
                self.pending.clear();
                return;
            }
        }
        if frame.is_some() {
            s.last_frame = frame;
        }
        bump(&self.counters.frames);
        let out = &mut self.out;
        out.clear();
        out.t = now;
        // Ends first: sessions missing from the alive list.
        let mut i = 0;
        while i < s.len {
            let sess = s.sessions[i];
            if p.alive(sess.tuio) {
                s.sessions[i].new = false;
                i += 1;
                continue;
            }
            let _ = out.push(contact(&sess, ContactFlags::UP));
            s.len -= 1;
            s.sessions[i] = s.sessions[s.len];
        }
        let limit = self.limits.sessions_per_frame;
        let mut refused = p.sets_over as u64;
        for &(id, x, y) in &p.sets[..p.sets_len] {
            if !p.alive(id) {
                continue;
            }
            if let Some(sess) = s.sessions[..s.len].iter_mut().find(|v| v.tuio == id) {
                sess.x = x;
                sess.y = y;
            } else if s.len < limit && out.len() + s.len < MAX_CONTACTS {
                s.sessions[s.len] = Session {
                    tuio: id,
                    local: self.next_local,
                    x,
                    y,
                    new: true,
                };
                s.len += 1;
                self.next_local = self.next_local.wrapping_add(1).max(1);
            } else {
                refused += 1;
            }
        }
        if let Some(n) = bump_by(&self.counters.sessions_refused, refused) {
            log::warn!(
                "tuio from {peer}: a frame with more sessions than {limit} (max_sessions_per_frame): \
                 {refused} refused (seen {n} times)"
            );
        }
        for sess in &s.sessions[..s.len] {
            let flags = if sess.new {
                ContactFlags::DOWN
            } else {
                ContactFlags::NONE
            };
            let _ = out.push(contact(sess, flags));
        }
        self.pending.clear();
        if !self.out.is_empty() {
            sink.push(&self.out);
        }
    }

    /// Ends (`CANCELLED`) the sessions of every sender silent for longer than the
    /// timeout at `now`, and forgets those senders.
    pub fn expire(&mut self, now: Micros, sink: &mut dyn FrameSink) {
        for i in 0..self.senders.len() {
            let s = &self.senders[i];
            if s.used && now.saturating_since(s.last_heard) > self.timeout {
                if s.len > 0 {
                    let n = bump(&self.counters.timeouts);
                    if let Some(peer) = s.peer {
                        log_rare(n, peer, &"sender went silent: its touches are lifted");
                    }
                }
                self.end_sender(i, now, sink);
            }
        }
    }

    /// Ends (`CANCELLED`) every session of every sender (the source stops).
    pub fn cancel_all(&mut self, now: Micros, sink: &mut dyn FrameSink) {
        for i in 0..self.senders.len() {
            if self.senders[i].used {
                self.end_sender(i, now, sink);
            }
        }
    }

    fn end_sender(&mut self, i: usize, now: Micros, sink: &mut dyn FrameSink) {
        let s = &mut self.senders[i];
        self.out.clear();
        self.out.t = now;
        for sess in &s.sessions[..s.len] {
            let _ = self.out.push(contact(sess, ContactFlags::CANCELLED));
        }
        s.used = false;
        s.len = 0;
        s.last_frame = None;
        if !self.out.is_empty() {
            sink.push(&self.out);
        }
    }
}

fn contact(s: &Session, flags: ContactFlags) -> Contact {
    Contact {
        id: ContactId(s.local),
        x: s.x,
        y: s.y,
        flags,
        ..Contact::default()
    }
}

fn read_alive<'a>(
    p: &mut Pending,
    args: impl Iterator<Item = super::osc::Arg<'a>>,
) -> Result<(), Problem> {
    p.alive_len = 0;
    p.alive_seen = true;
    for a in args {
        let id = a.as_i64().ok_or(Problem::BadArgs(
            "alive lists a session id that is not an int",
        ))?;
        if p.alive_len == MAX_ALIVE {
            return Err(Problem::BadArgs("alive lists more sessions than are kept"));
        }
        p.alive[p.alive_len] = id;
        p.alive_len += 1;
    }
    Ok(())
}

fn push_set(p: &mut Pending, id: i64, x: f64, y: f64) -> Result<(), Problem> {
    if !x.is_finite() || !y.is_finite() {
        return Err(Problem::BadArgs("position is not finite"));
    }
    let (x, y) = (x.clamp(0.0, 1.0) as f32, y.clamp(0.0, 1.0) as f32);
    if let Some(s) = p.sets[..p.sets_len].iter_mut().find(|s| s.0 == id) {
        *s = (id, x, y);
    } else if p.sets_len < MAX_ALIVE {
        p.sets[p.sets_len] = (id, x, y);
        p.sets_len += 1;
    } else {
        // Refused at the commit (counted in `sessions_refused`).
        p.sets_over += 1;
    }
    Ok(())
}

struct Bad<'a>(crate::located::Escaped<'a>, &'static str);
impl std::fmt::Display for Bad<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}: ignored", self.0, self.1)
    }
}

struct Unknown<'a>(crate::located::Escaped<'a>);
impl std::fmt::Display for Unknown<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: not a TUIO cursor message this input knows: ignored",
            self.0
        )
    }
}

struct Malformed(OscError);
impl std::fmt::Display for Malformed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "not a valid OSC packet: {}: dropped", self.0)
    }
}

#[cfg(test)]
#[path = "decode_tests.rs"]
mod tests;
