//! Raw HID reports through `HidDecoder`, reports per second (target ≥ 1 million/s).
//!
//! * `wacom_2f`: the real Wacom Intuos Pro touch recording (72 reports, 5 slots per
//!   report, vendor-page layout), replayed in a loop.
//! * `3m_10f`: SYNTHETIC 10-finger parallel reports on the 3M 0596:0500 layout (a
//!   large-format table display), every finger down and moving (seeded).
//! * `3m_hybrid_10f`: the same 10 fingers in hybrid mode: Contact Count 10 in a
//!   first report with 5 valid slots, then a report with Contact Count 0 and 5 more.
//! * `descriptor_3m`: parsing the 3M descriptor (once per device open).
//!
//! `cargo bench --bench hid_decode -- --warm-up-time 1 --measurement-time 3`

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use crowdtouch::input::hid::{touch_collections, HidDecoder, HidField, TouchCollection};
use crowdtouch::input::recording::parse_hid_recorder;
use crowdtouch::input::recording::OnBadFrame;
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::TouchFrame;
use std::path::Path;

/// A small deterministic generator (xorshift64*), so inputs are the same every run.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: u32) -> u32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 32) % u64::from(n)) as u32
    }
}

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/hid")
        .join(name)
}

fn put(b: &mut [u8], f: &HidField, v: u32) {
    for i in 0..u32::from(f.bit_size) {
        let bit = (f.bit_offset + i) as usize;
        if (v >> i) & 1 == 1 {
            b[bit / 8] |= 1 << (bit % 8);
        } else {
            b[bit / 8] &= !(1 << (bit % 8));
        }
    }
}

/// SYNTHETIC 3M reports: 10 fingers moving by small random steps. With `hybrid`,
/// each frame is two reports: Contact Count 10 with fingers 0..5, then 0 with 5..10.
fn reports_3m(c: &TouchCollection, frames: usize, hybrid: bool, seed: u64) -> Vec<Vec<u8>> {
    let r = &c.reports[0];
    let mut rng = Rng(seed);
    let mut pos: Vec<(u32, u32)> = (0..10)
        .map(|i| (2000 + 3000 * i, 3000 + 2000 * i))
        .collect();
    let mut out = Vec::new();
    for _ in 0..frames {
        for p in &mut pos {
            p.0 = (p.0 + rng.below(41)).saturating_sub(20).min(32767);
            p.1 = (p.1 + rng.below(41)).saturating_sub(20).min(32767);
        }
        let parts: &[(u32, std::ops::Range<usize>)] = if hybrid {
            &[(10, 0..5), (0, 5..10)]
        } else {
            &[(10, 0..10)]
        };
        for (count, fingers) in parts {
            let mut b = vec![0u8; r.size_bytes];
            b[0] = r.report_id.unwrap_or(0);
            for (slot, i) in fingers.clone().enumerate() {
                let fg = &r.fingers[slot];
                put(&mut b, &fg.tip.unwrap(), 1);
                if let Some(conf) = fg.confidence {
                    put(&mut b, &conf, 1);
                }
                put(&mut b, &fg.contact_id, i as u32);
                put(&mut b, &fg.x, pos[i].0);
                put(&mut b, &fg.y, pos[i].1);
            }
            put(&mut b, &r.contact_count.unwrap(), *count);
            out.push(b);
        }
    }
    out
}

fn run(dec: &mut HidDecoder, reports: &[Vec<u8>], frame: &mut TouchFrame) -> usize {
    let mut frames = 0;
    for (i, r) in reports.iter().enumerate() {
        frames += usize::from(dec.report(Micros(i as u64), black_box(r), frame));
    }
    frames
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("hid_decode");

    let path = fixture("wacom-intuos-pro-m-pth660.touch.two-finger-vert-in-center.hid");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let log = parse_hid_recorder(&text, &path, OnBadFrame::Stop).expect("log");
    let wacom = touch_collections(&log.descriptor).expect("touch").remove(0);
    let wacom_reports: Vec<Vec<u8>> = log.events().map(|(_, b)| b.to_vec()).collect();

    let rdesc_3m = std::fs::read(fixture("descriptors/3m_0596_0500.rdesc")).expect("fixture");
    let m3 = touch_collections(&rdesc_3m).expect("touch").remove(0);
    let parallel = reports_3m(&m3, 1_000, false, 0x5eed);
    let hybrid = reports_3m(&m3, 500, true, 0x5eed);

    for (name, tc, reports) in [
        ("wacom_2f", &wacom, &wacom_reports),
        ("3m_10f", &m3, &parallel),
        ("3m_hybrid_10f", &m3, &hybrid),
    ] {
        g.throughput(Throughput::Elements(reports.len() as u64));
        let mut frame = TouchFrame::default();
        let mut dec = HidDecoder::new(tc);
        dec.set_max_contacts(10);
        g.bench_with_input(BenchmarkId::new("reports", name), reports, |b, reports| {
            b.iter(|| {
                let n = run(&mut dec, reports, &mut frame);
                dec.cancel_all(Micros(u64::MAX), &mut frame);
                black_box(n)
            })
        });
    }

    g.throughput(Throughput::Elements(1));
    g.bench_function("descriptor_3m", |b| {
        b.iter(|| black_box(touch_collections(black_box(&rdesc_3m)).map(|v| v.len())))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
