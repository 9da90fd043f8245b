//! The TUIO output's work per frame: a snapshot turned into TUIO entities, encoded
//! (rosc) and split into datagrams, TUIO 1.1 (cursors, objects, blobs) and 2.0.
//!
//! `cargo bench --bench tuio_encode -- --warm-up-time 1 --measurement-time 3`
//!
//! Before measuring, it prints each case's datagrams and bytes per frame (and how
//! many agents a frame leaves out when their alive list does not fit a datagram).

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use crowdtouch::geom::{Rect, Vec2};
use crowdtouch::publish::tuio::{Datagrams, Encoder11, Encoder20, Framer, Profiles};
use crowdtouch::rng::SplitMix64;
use crowdtouch::vocab::{AgentView, Micros, Snapshot, TouchView};

const WORLD: Rect = Rect {
    min: [0.0, 0.0],
    max: [8.0, 5.0],
};

fn snapshot(n: usize, seed: u64) -> Snapshot {
    let mut r = SplitMix64::new(seed);
    let mut v = || Vec2::new(r.unit() * 8.0, r.unit() * 5.0);
    Snapshot {
        seq: 1,
        t: Micros(1_000_000),
        agents: (0..n)
            .map(|_| AgentView {
                pos: v(),
                vel: v() * 0.2,
                goal: 0,
            })
            .collect(),
        touches: (0..10)
            .map(|i| TouchView {
                id: i,
                pos: v(),
                control: Some(i / 3),
            })
            .collect(),
        ..Snapshot::default()
    }
}

const ALL: Profiles = Profiles {
    cursors: true,
    objects: true,
    blobs: true,
};

/// One frame: build, encode, split. Returns the agents left out.
fn frame(
    v20: bool,
    framer: &mut Framer,
    e11: &mut Encoder11,
    e20: &mut Encoder20,
    s: &Snapshot,
    max: usize,
    out: &mut Datagrams,
) -> usize {
    out.clear();
    let f = framer.build(s, true, true, true);
    if v20 {
        e20.encode(f, 1, rosc::OscTime::from((0, 1)), max, out)
    } else {
        e11.encode(f, ALL, 1, max, out)
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("tuio_encode");
    for n in [1_000usize, 10_000] {
        let s = snapshot(n, 0x5eed + n as u64);
        for (v20, name) in [(false, "1.1"), (true, "2.0")] {
            for max in [1472usize, 65_507] {
                let mut framer = Framer::new(WORLD);
                let mut e11 = Encoder11::new("crowdtouch@bench");
                let mut e20 = Encoder20::new("crowdtouch@bench", WORLD);
                let mut out = Datagrams::default();
                let cut = frame(v20, &mut framer, &mut e11, &mut e20, &s, max, &mut out);
                eprintln!(
                    "tuio {name}, {n} agents, datagrams ≤ {max} B: {} datagrams, {} bytes per frame, {cut} agents left out",
                    out.len(),
                    out.bytes()
                );
                g.throughput(Throughput::Elements(n as u64));
                g.bench_with_input(
                    BenchmarkId::new(format!("{name}/max{max}"), n),
                    &s,
                    |b, s| {
                        b.iter(|| {
                            black_box(frame(
                                v20,
                                &mut framer,
                                &mut e11,
                                &mut e20,
                                black_box(s),
                                max,
                                &mut out,
                            ))
                        })
                    },
                );
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
