//! Decoding evdev events into touch frames: the input thread's work per event.
//!
//! Inputs are real recordings (tests/fixtures), read once outside the timed
//! loop; each iteration decodes every event of the recording from a fresh
//! decoder. Throughput is in events.
//!
//! `cargo bench --bench input_decode -- --warm-up-time 1 --measurement-time 3`

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use crowdtouch::input::evdev::{parse_input_events, INPUT_EVENT_BYTES};
use crowdtouch::input::evdev::{MtDecoder, RawEvent};
use crowdtouch::input::recording::read_evemu_raw;
use crowdtouch::vocab::TouchFrame;
use std::path::Path;

fn fixture(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    std::fs::read_to_string(p).expect("fixture")
}

/// A decoder for the recording's device and its events.
fn load(desc: Option<&str>, events: &str) -> (MtDecoder, Vec<RawEvent>) {
    let text = match desc {
        Some(d) => format!("{}\n{}", fixture(d), fixture(events)),
        None => fixture(events),
    };
    let (caps, evs) = read_evemu_raw(&text, Path::new(events)).expect("evemu");
    let s = caps.decoder_setup().expect("touch device");
    (MtDecoder::with_protocol(s.axes, s.protocol, 1), evs)
}

/// Decodes all events; returns the contacts reported (so nothing is optimised away).
fn decode(template: &MtDecoder, evs: &[RawEvent]) -> usize {
    let mut d = template.clone();
    let mut f = TouchFrame::default();
    let mut n = 0;
    for e in evs {
        if d.feed(black_box(e), &mut f) {
            n += f.len();
        }
    }
    n
}

/// The bytes `read(2)` would return for `evs`.
fn to_bytes(evs: &[RawEvent]) -> Vec<u8> {
    let w = std::mem::size_of::<std::ffi::c_long>();
    let mut b = Vec::with_capacity(evs.len() * INPUT_EVENT_BYTES);
    for e in evs {
        let (sec, usec) = ((e.t.0 / 1_000_000) as i64, (e.t.0 % 1_000_000) as i64);
        b.extend_from_slice(&sec.to_ne_bytes()[..w]);
        b.extend_from_slice(&usec.to_ne_bytes()[..w]);
        b.extend_from_slice(&e.ev_type.to_ne_bytes());
        b.extend_from_slice(&e.code.to_ne_bytes());
        b.extend_from_slice(&e.value.to_ne_bytes());
    }
    b
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("input_decode");

    // Dell Canvas 27: 5363 events, 450 frames, up to 5 contacts (type B).
    let (dec_b, evs_b) = load(None, "dell-canvas-27-touch.evemu");
    g.throughput(Throughput::Elements(evs_b.len() as u64));
    g.bench_function("evdev_protocol_b", |b| {
        b.iter(|| black_box(decode(&dec_b, &evs_b)))
    });
    // The same from raw input_event bytes, as the device shell reads them.
    let bytes = to_bytes(&evs_b);
    g.bench_function("evdev_protocol_b_from_bytes", |b| {
        b.iter(|| {
            let mut d = dec_b.clone();
            let mut f = TouchFrame::default();
            let mut n = 0;
            for e in parse_input_events(black_box(&bytes)) {
                if d.feed(&e, &mut f) {
                    n += f.len();
                }
            }
            black_box(n)
        })
    });

    // N-Trig: 2203 events, 219 frames, 1-2 anonymous contacts (type A).
    let (dec_a, evs_a) = load(
        Some("ntrig-multitouch.desc"),
        "ntrig-multitouch.2-fingers-touch-release.events",
    );
    g.throughput(Throughput::Elements(evs_a.len() as u64));
    g.bench_function("evdev_protocol_a", |b| {
        b.iter(|| black_box(decode(&dec_a, &evs_a)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
