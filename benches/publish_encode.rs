//! Snapshot serialisation, the publisher's share of the latency path.
//!
//! `cargo bench --bench publish_encode -- --warm-up-time 1 --measurement-time 3`

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use crowdtouch::geom::Vec2;
use crowdtouch::publish::protocol::{encode_snapshot_binary, encode_snapshot_json, FieldSet};
use crowdtouch::vocab::Micros;
use crowdtouch::vocab::{AgentView, Snapshot, TouchView};

/// A small deterministic generator (xorshift64*), so inputs are the same every run.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn snapshot(n: usize, seed: u64) -> Snapshot {
    let mut r = Rng(seed);
    let mut v = || Vec2::new(r.unit() * 8.0, r.unit() * 5.0);
    let agents: Vec<AgentView> = (0..n)
        .map(|i| AgentView {
            pos: v(),
            vel: v() * 0.2,
            goal: (n - 1 - i) as u32,
        })
        .collect();
    let goals = (0..n).map(|_| v()).collect();
    let touches = (0..10)
        .map(|i| TouchView {
            id: i,
            pos: v(),
            control: (i % 2 == 0).then_some(i),
        })
        .collect();
    Snapshot {
        seq: 123_456,
        t: Micros(9_876_543_210),
        input_t: Some(Micros(9_876_540_000)),
        agents,
        goals,
        assignment_seq: 123_450,
        touches,
        paused: false,
        motions: Vec::new(),
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("publish_encode");
    for n in [100usize, 1_000, 10_000] {
        let s = snapshot(n, 0x5eed + n as u64);
        g.throughput(Throughput::Elements(n as u64));
        let mut out = Vec::new();
        g.bench_with_input(BenchmarkId::new("json", n), &s, |b, s| {
            b.iter(|| {
                out.clear();
                encode_snapshot_json(black_box(s), Some(1234), 0, &FieldSet::ALL, &mut out);
                black_box(out.len())
            })
        });
        let positions = FieldSet {
            positions: true,
            ..FieldSet::NONE
        };
        g.bench_with_input(BenchmarkId::new("json_positions_only", n), &s, |b, s| {
            b.iter(|| {
                out.clear();
                encode_snapshot_json(black_box(s), Some(1234), 0, &positions, &mut out);
                black_box(out.len())
            })
        });
        g.bench_with_input(BenchmarkId::new("binary", n), &s, |b, s| {
            b.iter(|| {
                out.clear();
                encode_snapshot_binary(black_box(s), Some(1234), 0, &FieldSet::ALL, &mut out);
                black_box(out.len())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
