use super::*;
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};
use std::sync::Arc;

fn peer(port: u16) -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], port))
}

fn m(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    })
}

fn s(v: &str) -> OscType {
    OscType::String(v.into())
}

fn bundle(content: Vec<OscPacket>) -> Vec<u8> {
    rosc::encoder::encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content,
    }))
    .unwrap()
}

/// A TUIO 1.1 cursor bundle: `source`, `alive`, a `set` per cursor, `fseq`.
fn cur(source: Option<&str>, cursors: &[(i32, f32, f32)], fseq: i32) -> Vec<u8> {
    let mut c = Vec::new();
    if let Some(name) = source {
        c.push(m("/tuio/2Dcur", vec![s("source"), s(name)]));
    }
    let mut alive = vec![s("alive")];
    alive.extend(cursors.iter().map(|k| OscType::Int(k.0)));
    c.push(m("/tuio/2Dcur", alive));
    for &(id, x, y) in cursors {
        let mut set = vec![
            s("set"),
            OscType::Int(id),
            OscType::Float(x),
            OscType::Float(y),
        ];
        set.extend([0.0f32, 0.0, 0.0].map(OscType::Float));
        c.push(m("/tuio/2Dcur", set));
    }
    c.push(m("/tuio/2Dcur", vec![s("fseq"), OscType::Int(fseq)]));
    bundle(c)
}

/// A TUIO 2.0 frame: `frm`, a `ptr` per pointer, `alv`.
fn tuio2(frame: i32, ptrs: &[(i32, f32, f32)], also_alive: &[i32]) -> Vec<u8> {
    let mut c = vec![m(
        "/tuio2/frm",
        vec![
            OscType::Int(frame),
            OscType::Time(OscTime::from((1, 0))),
            OscType::Int((640 << 16) | 480),
            s("sim@host"),
        ],
    )];
    for &(id, x, y) in ptrs {
        let mut p = vec![
            OscType::Int(id),
            OscType::Int(0),
            OscType::Int(0),
            OscType::Float(x),
            OscType::Float(y),
        ];
        p.extend([0.0f32, 0.0, 0.0, 1.0].map(OscType::Float));
        c.push(m("/tuio2/ptr", p));
    }
    let mut alv: Vec<OscType> = ptrs.iter().map(|k| OscType::Int(k.0)).collect();
    alv.extend(also_alive.iter().map(|&i| OscType::Int(i)));
    c.push(m("/tuio2/alv", alv));
    bundle(c)
}

struct Rig {
    dec: TuioDecoder,
    out: Vec<TouchFrame>,
}

impl Rig {
    fn new() -> Rig {
        Rig {
            dec: TuioDecoder::new(Micros(1_000_000), Arc::new(TuioCounters::default())),
            out: Vec::new(),
        }
    }
    fn feed(&mut self, b: &[u8], port: u16, t: u64) {
        self.dec
            .packet(b, peer(port), Micros(t), &mut self.out)
            .unwrap();
    }
    /// (id, x, y, flags) of the last frame.
    fn last(&self) -> Vec<(u32, f32, f32, ContactFlags)> {
        let f = self.out.last().expect("a frame");
        f.contacts()
            .iter()
            .map(|c| (c.id.0, c.x, c.y, c.flags))
            .collect()
    }
    fn count(&self, c: impl Fn(&TuioCounters) -> &AtomicU64) -> u64 {
        c(self.dec.counters()).load(Ordering::Relaxed)
    }
}

#[test]
fn a_cursor_appears_moves_and_lifts() {
    let mut r = Rig::new();
    r.feed(&cur(Some("app@host"), &[(7, 0.25, 0.5)], 1), 4000, 10);
    assert_eq!(r.last(), vec![(1, 0.25, 0.5, ContactFlags::DOWN)]);
    assert_eq!(r.out[0].t, Micros(10), "stamped at receipt");
    r.feed(&cur(Some("app@host"), &[(7, 0.3, 0.6)], 2), 4000, 20);
    assert_eq!(r.last(), vec![(1, 0.3, 0.6, ContactFlags::NONE)]);
    // Gone from alive: lifted where it was last.
    r.feed(&cur(Some("app@host"), &[], 3), 4000, 30);
    assert_eq!(r.last(), vec![(1, 0.3, 0.6, ContactFlags::UP)]);
    assert_eq!(r.dec.active_contacts(), 0);
    // An empty alive with nothing down emits nothing.
    r.feed(&cur(Some("app@host"), &[], 4), 4000, 40);
    assert_eq!(r.out.len(), 3);
    assert_eq!(r.count(|c| &c.frames), 4);
}

#[test]
fn a_set_without_a_change_in_alive_keeps_the_others_where_they_are() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 0.1, 0.1), (2, 0.9, 0.9)], 1), 1, 0);
    // Only cursor 2 moved: 1.1 senders may send `set` for changed cursors only.
    let b = bundle(vec![
        m(
            "/tuio/2Dcur",
            vec![s("alive"), OscType::Int(1), OscType::Int(2)],
        ),
        m(
            "/tuio/2Dcur",
            vec![
                s("set"),
                OscType::Int(2),
                OscType::Float(0.8),
                OscType::Float(0.7),
                OscType::Float(0.0),
                OscType::Float(0.0),
                OscType::Float(0.0),
            ],
        ),
        m("/tuio/2Dcur", vec![s("fseq"), OscType::Int(2)]),
    ]);
    r.feed(&b, 1, 1);
    assert_eq!(
        r.last(),
        vec![
            (1, 0.1, 0.1, ContactFlags::NONE),
            (2, 0.8, 0.7, ContactFlags::NONE)
        ]
    );
}

#[test]
fn an_older_frame_is_dropped_and_minus_one_applies_now() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 0.1, 0.1)], 1000), 1, 0);
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1002), 1, 1);
    // Frame 1001 arrives late: dropped, the cursor stays at frame 1002's place.
    r.feed(&cur(None, &[(1, 0.2, 0.2)], 1001), 1, 2);
    assert_eq!(r.out.len(), 2);
    assert_eq!(r.count(|c| &c.stale_frames), 1);
    // fseq -1 is applied whatever the order.
    r.feed(&cur(None, &[(1, 0.6, 0.6)], -1), 1, 3);
    assert_eq!(r.last(), vec![(1, 0.6, 0.6, ContactFlags::NONE)]);
    // A sender that starts again (fseq far back) is followed again.
    r.feed(&cur(None, &[(1, 0.7, 0.7)], 0), 1, 4);
    assert_eq!(r.last(), vec![(1, 0.7, 0.7, ContactFlags::NONE)]);
}

#[test]
fn a_silent_sender_has_its_touches_lifted() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 0.4, 0.4), (2, 0.6, 0.6)], 1), 1, 0);
    r.dec.expire(Micros(900_000), &mut r.out);
    assert_eq!(r.out.len(), 1, "not silent long enough");
    r.dec.expire(Micros(1_000_001), &mut r.out);
    let flags: Vec<_> = r.last().iter().map(|c| c.3).collect();
    assert_eq!(flags, vec![ContactFlags::CANCELLED; 2]);
    assert_eq!(r.out.last().unwrap().t, Micros(1_000_001));
    assert_eq!(r.dec.active_contacts(), 0);
    assert_eq!(r.dec.senders(), 0);
    assert_eq!(r.count(|c| &c.timeouts), 1);
}

#[test]
fn two_senders_are_kept_apart() {
    let mut r = Rig::new();
    // Same session id 1, different peers; then a second source name on one peer.
    r.feed(&cur(Some("a@x"), &[(1, 0.1, 0.1)], 100), 1, 0);
    r.feed(&cur(Some("b@y"), &[(1, 0.9, 0.9)], 5), 2, 1);
    r.feed(&cur(Some("c@x"), &[(1, 0.5, 0.5)], 1), 1, 2);
    assert_eq!(r.dec.senders(), 3);
    let ids: Vec<u32> = r.out.iter().map(|f| f.contacts()[0].id.0).collect();
    assert_eq!(
        ids,
        vec![1, 2, 3],
        "each sender's session is its own contact"
    );
    // Sender b's empty alive lifts only its own.
    r.feed(&cur(Some("b@y"), &[], 6), 2, 3);
    assert_eq!(r.last(), vec![(2, 0.9, 0.9, ContactFlags::UP)]);
    assert_eq!(r.dec.active_contacts(), 2);
    // Frame order is per sender: a's 101 is not old next to b's numbers.
    r.feed(&cur(Some("a@x"), &[(1, 0.2, 0.2)], 101), 1, 4);
    assert_eq!(r.last(), vec![(1, 0.2, 0.2, ContactFlags::NONE)]);
}

#[test]
fn tuio2_pointers_become_touches_and_tokens_are_ignored() {
    let mut r = Rig::new();
    // A token (session 50) is alive too; its tok message is ignored.
    let mut b = tuio2(1, &[(3, 0.25, 0.75)], &[50]);
    r.feed(&b, 9, 0);
    assert_eq!(r.last(), vec![(1, 0.25, 0.75, ContactFlags::DOWN)]);
    let tok = m(
        "/tuio2/tok",
        vec![
            OscType::Int(50),
            OscType::Int(0),
            OscType::Int(4),
            OscType::Float(0.5),
            OscType::Float(0.5),
            OscType::Float(0.0),
        ],
    );
    b = bundle(vec![
        m(
            "/tuio2/frm",
            vec![
                OscType::Int(2),
                OscType::Time(OscTime::from((1, 0))),
                OscType::Int(0),
                s("sim@host"),
            ],
        ),
        tok,
        m("/tuio2/alv", vec![OscType::Int(50)]),
    ]);
    r.feed(&b, 9, 1);
    assert_eq!(r.last(), vec![(1, 0.25, 0.75, ContactFlags::UP)]);
    assert_eq!(r.count(|c| &c.ignored), 1);
    // Reordered 2.0 frames are dropped too.
    r.feed(&tuio2(1, &[(4, 0.1, 0.1)], &[]), 9, 2);
    assert_eq!(r.count(|c| &c.stale_frames), 1);
    assert_eq!(r.dec.active_contacts(), 0);
}

#[test]
fn objects_blobs_and_bad_bundles_change_nothing() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 1, 0);
    let n = r.out.len();
    // A 2Dobj bundle (its own alive and fseq) is ignored as a whole.
    let obj = bundle(vec![
        m("/tuio/2Dobj", vec![s("alive")]),
        m("/tuio/2Dobj", vec![s("fseq"), OscType::Int(2)]),
    ]);
    r.feed(&obj, 1, 1);
    // Cursor messages without fseq: not applied.
    let no_fseq = bundle(vec![m("/tuio/2Dcur", vec![s("alive")])]);
    r.feed(&no_fseq, 1, 2);
    // Not TUIO at all; a NaN position; an alive of strings.
    r.feed(&bundle(vec![m("/other/thing", vec![])]), 1, 3);
    let nan = bundle(vec![
        m("/tuio/2Dcur", vec![s("alive"), OscType::Int(1)]),
        m(
            "/tuio/2Dcur",
            vec![
                s("set"),
                OscType::Int(1),
                OscType::Float(f32::NAN),
                OscType::Float(0.1),
            ],
        ),
        m("/tuio/2Dcur", vec![s("fseq"), OscType::Int(3)]),
    ]);
    r.feed(&nan, 1, 4);
    // Not OSC.
    assert!(r
        .dec
        .packet(b"hello", peer(1), Micros(5), &mut r.out)
        .is_err());
    assert_eq!(r.count(|c| &c.ignored), 2);
    assert_eq!(r.count(|c| &c.without_fseq), 1);
    assert_eq!(r.count(|c| &c.unknown), 1);
    assert_eq!(r.count(|c| &c.malformed), 2);
    // The NaN frame still applied its alive: the cursor stays where it was.
    assert!(r.out[n..].iter().all(|f| f
        .contacts()
        .iter()
        .all(|c| c.x == 0.5 && c.flags == ContactFlags::NONE)));
    assert_eq!(r.dec.active_contacts(), 1);
}

#[test]
fn positions_are_clamped_and_a_full_sender_table_refuses_more() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 1.5, -0.5)], 1), 1, 0);
    assert_eq!(r.last(), vec![(1, 1.0, 0.0, ContactFlags::DOWN)]);
    for p in 2..=DEFAULT_MAX_SENDERS as u16 {
        r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), p, 0);
    }
    let n = r.out.len();
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 999, 0);
    assert_eq!(r.out.len(), n);
    assert_eq!(r.count(|c| &c.senders_refused), 1);
    // Once a sender lifts everything its place may be taken.
    r.feed(&cur(None, &[], 2), 1, 1);
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 999, 2);
    assert_eq!(r.last()[0].3, ContactFlags::DOWN);
}

#[test]
fn cancel_all_ends_every_session() {
    let mut r = Rig::new();
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 1, 0);
    r.feed(&tuio2(1, &[(2, 0.5, 0.5)], &[]), 2, 0);
    r.dec.cancel_all(Micros(5), &mut r.out);
    let ended: usize = r.out[2..]
        .iter()
        .map(|f| {
            f.contacts()
                .iter()
                .filter(|c| c.flags == ContactFlags::CANCELLED)
                .count()
        })
        .sum();
    assert_eq!(ended, 2);
    assert_eq!(r.dec.active_contacts(), 0);
}

#[test]
fn sessions_over_the_limit_are_refused_and_counted_in_every_frame() {
    let limits = TuioLimits {
        sessions_per_frame: 10,
        ..TuioLimits::default()
    };
    let mut r = Rig::new();
    r.dec = TuioDecoder::with_limits(limits, Micros(1_000_000), Arc::new(TuioCounters::default()));
    let many: Vec<(i32, f32, f32)> = (1..=25).map(|i| (i, 0.5, 0.5)).collect();
    r.feed(&cur(None, &many, 1), 1, 0);
    assert_eq!(r.last().len(), 10);
    assert_eq!(r.count(|c| &c.sessions_refused), 15);
    // The same frame again: the 10 move, the 15 are refused again.
    r.feed(&cur(None, &many, 2), 1, 1);
    assert_eq!(r.last().len(), 10);
    assert!(r.last().iter().all(|c| c.3 == ContactFlags::NONE));
    assert_eq!(r.count(|c| &c.sessions_refused), 30);
    // One lifts: a place for one more.
    r.feed(&cur(None, &many[1..], 3), 1, 2);
    assert_eq!(r.dec.active_contacts(), 10);
    assert_eq!(r.count(|c| &c.sessions_refused), 44);
}

#[test]
fn a_frame_of_many_sessions_keeps_the_limit_and_one_too_long_is_refused() {
    let mut r = Rig::new();
    // TUIO 2.0 with 250 pointers: the 64 first begin, 186 are refused.
    let ptrs: Vec<(i32, f32, f32)> = (1..=250).map(|i| (i, 0.5, 0.5)).collect();
    r.feed(&tuio2(1, &ptrs, &[]), 1, 0);
    assert_eq!(r.dec.active_contacts(), MAX_CONTACTS);
    assert_eq!(r.count(|c| &c.sessions_refused), 186);
    // An alive list longer than MAX_ALIVE: the frame is malformed, not applied.
    let ptrs: Vec<(i32, f32, f32)> = (1..=300).map(|i| (i, 0.5, 0.5)).collect();
    let n = r.out.len();
    r.feed(&tuio2(2, &ptrs, &[]), 1, 1);
    assert_eq!(r.out.len(), n);
    assert_eq!(r.count(|c| &c.malformed), 1);
    // TUIO 1.1 without an alive list: the sets past MAX_ALIVE are refused too.
    let mut c = Vec::new();
    for id in 1..=300 {
        let mut set = vec![
            s("set"),
            OscType::Int(id),
            OscType::Float(0.5),
            OscType::Float(0.5),
        ];
        set.extend([0.0f32, 0.0, 0.0].map(OscType::Float));
        c.push(m("/tuio/2Dcur", set));
    }
    c.push(m("/tuio/2Dcur", vec![s("fseq"), OscType::Int(1)]));
    r.feed(&bundle(c), 2, 2);
    assert_eq!(r.dec.active_contacts(), 2 * MAX_CONTACTS);
    assert_eq!(
        r.count(|c| &c.sessions_refused),
        186 + 300 - MAX_CONTACTS as u64
    );
}

#[test]
fn the_sender_table_is_as_large_as_the_limit() {
    let limits = TuioLimits {
        senders: 2,
        ..TuioLimits::default()
    };
    let mut r = Rig::new();
    r.dec = TuioDecoder::with_limits(limits, Micros(1_000_000), Arc::new(TuioCounters::default()));
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 1, 0);
    r.feed(&cur(Some("b@h"), &[(1, 0.5, 0.5)], 1), 1, 0);
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 1), 3, 0);
    r.feed(&cur(None, &[(1, 0.5, 0.5)], 2), 3, 0);
    assert_eq!(r.dec.senders(), 2);
    assert_eq!(r.dec.active_contacts(), 2);
    assert_eq!(r.count(|c| &c.senders_refused), 2);
    // Out-of-range limits are clamped.
    let d = TuioDecoder::with_limits(
        TuioLimits {
            sessions_per_frame: 0,
            senders: 1_000,
            packets_per_s: 1,
        },
        Micros(1),
        Arc::new(TuioCounters::default()),
    );
    assert_eq!(d.limits().sessions_per_frame, 1);
    assert_eq!(d.limits().senders, MOST_SENDERS);
}

#[test]
fn an_address_with_control_characters_is_logged_escaped() {
    let text = Unknown(crate::located::Escaped("/x\u{1b}[2J")).to_string();
    assert!(!text.contains('\u{1b}'), "{text:?}");
    assert!(text.starts_with("/x\\u{1b}[2J"), "{text:?}");
}
