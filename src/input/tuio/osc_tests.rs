use super::*;
use proptest::prelude::*;
use rosc::{OscBundle, OscMessage, OscPacket, OscTime, OscType};

fn encode(p: &OscPacket) -> Vec<u8> {
    rosc::encoder::encode(p).expect("rosc encodes")
}

fn msg(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.to_string(),
        args,
    })
}

/// Our reading of a packet, in an owned form comparable with rosc's.
fn ours(b: &[u8]) -> Result<Vec<(String, Vec<OscType>)>, OscError> {
    let mut out = Vec::new();
    walk(b, &mut |m| {
        let args = m
            .args()
            .map(|a| match a {
                Arg::Int(v) => OscType::Int(v),
                Arg::Float(v) => OscType::Float(v),
                Arg::Str(s) => OscType::String(s.to_string()),
                Arg::Long(v) => OscType::Long(v),
                Arg::Double(v) => OscType::Double(v),
                Arg::Time(v) => OscType::Time(OscTime::from(((v >> 32) as u32, v as u32))),
                Arg::True => OscType::Bool(true),
                Arg::False => OscType::Bool(false),
                Arg::Nil => OscType::Nil,
            })
            .collect();
        out.push((m.address.to_string(), args));
    })?;
    Ok(out)
}

/// The messages of a rosc packet, depth first.
fn flatten(p: &OscPacket, out: &mut Vec<(String, Vec<OscType>)>) {
    match p {
        OscPacket::Message(m) => out.push((m.addr.clone(), m.args.clone())),
        OscPacket::Bundle(b) => b.content.iter().for_each(|c| flatten(c, out)),
    }
}

#[test]
fn a_tuio_bundle_reads_in_order() {
    let p = OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content: vec![
            msg(
                "/tuio/2Dcur",
                vec![
                    OscType::String("source".into()),
                    OscType::String("app@host".into()),
                ],
            ),
            msg(
                "/tuio/2Dcur",
                vec![OscType::String("alive".into()), OscType::Int(3)],
            ),
            msg(
                "/tuio/2Dcur",
                vec![
                    OscType::String("set".into()),
                    OscType::Int(3),
                    OscType::Float(0.25),
                    OscType::Float(0.75),
                    OscType::Float(0.0),
                    OscType::Float(0.0),
                    OscType::Float(0.0),
                ],
            ),
            msg(
                "/tuio/2Dcur",
                vec![OscType::String("fseq".into()), OscType::Int(-1)],
            ),
        ],
    });
    let b = encode(&p);
    let got = ours(&b).unwrap();
    assert_eq!(got.len(), 4);
    assert_eq!(got[2].1[2], OscType::Float(0.25));
    assert_eq!(got[3].1[1], OscType::Int(-1));
}

#[test]
fn an_unknown_tag_is_refused_at_its_byte() {
    // "/a\0\0" ",ib\0" then an int and a blob.
    let mut b = b"/a\0\0,ib\0".to_vec();
    b.extend_from_slice(&7i32.to_be_bytes());
    b.extend_from_slice(&[0, 0, 0, 0]);
    let e = ours(&b).unwrap_err();
    assert_eq!(
        e,
        OscError {
            offset: 6,
            kind: OscErrorKind::UnknownTag('b')
        }
    );
    assert_eq!(e.to_string(), "byte 6: unknown type tag 'b'");
}

#[test]
fn broken_packets_are_refused_and_deliver_nothing() {
    let good = encode(&OscPacket::Bundle(OscBundle {
        timetag: OscTime::from((0, 1)),
        content: vec![
            msg("/x", vec![OscType::Int(1)]),
            msg("/y", vec![OscType::Float(2.0)]),
        ],
    }));
    // Every cut of a good bundle is refused, and no message of it is delivered,
    // except at the end of an element (an empty bundle, or the first message alone).
    let first = 16 + 4 + i32::from_be_bytes(good[16..20].try_into().unwrap()) as usize;
    for cut in (0..good.len()).filter(|&c| c != 16 && c != first) {
        let mut n = 0;
        let r = walk(&good[..cut], &mut |_| n += 1);
        assert!(r.is_err(), "cut at {cut} accepted");
        assert_eq!(n, 0);
    }
    // No type tags, a bad address, trailing bytes.
    assert_eq!(ours(b"/a\0\0").unwrap_err().kind, OscErrorKind::NoTypeTags);
    assert_eq!(
        ours(b"a\0\0\0,\0\0\0").unwrap_err().kind,
        OscErrorKind::BadAddress
    );
    assert_eq!(
        ours(b"/a\0\0,\0\0\0\0\0\0\0").unwrap_err(),
        OscError {
            offset: 8,
            kind: OscErrorKind::Trailing(4)
        }
    );
    // An element size past the end.
    let mut b = b"#bundle\0".to_vec();
    b.extend_from_slice(&[0; 8]);
    b.extend_from_slice(&64i32.to_be_bytes());
    b.extend_from_slice(b"/a\0\0,\0\0\0");
    assert_eq!(
        ours(&b).unwrap_err(),
        OscError {
            offset: 16,
            kind: OscErrorKind::BadElementSize(64)
        }
    );
}

#[test]
fn deep_nesting_is_refused() {
    let mut p = msg("/x", vec![]);
    for _ in 0..MAX_DEPTH + 1 {
        p = OscPacket::Bundle(OscBundle {
            timetag: OscTime::from((0, 1)),
            content: vec![p],
        });
    }
    assert_eq!(ours(&encode(&p)).unwrap_err().kind, OscErrorKind::TooDeep);
}

fn arg() -> impl Strategy<Value = OscType> {
    prop_oneof![
        any::<i32>().prop_map(OscType::Int),
        any::<f32>()
            .prop_filter("NaN != NaN", |f| !f.is_nan())
            .prop_map(OscType::Float),
        "[a-zA-Z0-9 @._/-]{0,12}".prop_map(OscType::String),
        any::<i64>().prop_map(OscType::Long),
        any::<f64>()
            .prop_filter("NaN != NaN", |f| !f.is_nan())
            .prop_map(OscType::Double),
        (any::<u32>(), any::<u32>()).prop_map(|t| OscType::Time(OscTime::from(t))),
        any::<bool>().prop_map(OscType::Bool),
        Just(OscType::Nil),
    ]
}

fn message() -> impl Strategy<Value = OscPacket> {
    (
        "/[a-z0-9]{1,8}(/[a-zA-Z0-9]{1,6}){0,2}",
        prop::collection::vec(arg(), 0..8),
    )
        .prop_map(|(addr, args)| OscPacket::Message(OscMessage { addr, args }))
}

fn packet() -> impl Strategy<Value = OscPacket> {
    message().prop_recursive(3, 24, 5, |inner| {
        (any::<(u32, u32)>(), prop::collection::vec(inner, 0..5)).prop_map(|(t, content)| {
            OscPacket::Bundle(OscBundle {
                timetag: OscTime::from(t),
                content,
            })
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, rng_seed: proptest::test_runner::RngSeed::Fixed(18), ..ProptestConfig::default() })]

    /// Whatever rosc encodes, we read the same messages in the same order.
    #[test]
    fn reads_what_rosc_encodes(p in packet()) {
        let b = encode(&p);
        let mut want = Vec::new();
        flatten(&p, &mut want);
        prop_assert_eq!(ours(&b).unwrap(), want);
    }

    /// Whatever we accept, rosc decodes to the same messages (and bytes we refuse
    /// never panic).
    #[test]
    fn agrees_with_rosc_on_mangled_bytes(p in packet(), flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..4)) {
        let mut b = encode(&p);
        for (i, v) in flips {
            let i = i.index(b.len());
            b[i] = v;
        }
        if let Ok(got) = ours(&b) {
            let (_, theirs) = rosc::decoder::decode_udp(&b).expect("rosc decodes what we accept");
            let mut want = Vec::new();
            flatten(&theirs, &mut want);
            // Debug text: a flipped byte may make a NaN, which is not equal to itself.
            prop_assert_eq!(format!("{got:?}"), format!("{want:?}"));
        }
    }
}
