//! One control tick (segment + ARAP + goals + agent step + snapshot), without the
//! assignment worker, for crowds of 100 to 10,000 agents with a three-finger area
//! control moving. `crowdtouch bench tick` measures the same workload's distribution.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use crowdtouch::config::Config;
use crowdtouch::engine::Engine;
use crowdtouch::input::{Contact, ContactFlags, ContactId, TouchFrame};
use crowdtouch::time::Micros;

const PERIOD_US: u64 = 8_333;

fn frame(k: u64, flags: ContactFlags) -> TouchFrame {
    let fingers = [(0.48f32, 0.45f32), (0.52, 0.45), (0.50, 0.52)];
    let mut f = TouchFrame::new(Micros(k * PERIOD_US));
    // Back and forth, so the crowd stays on the table however long criterion runs.
    let phase = (k % 400) as f32 / 400.0;
    let dx = 0.04 * (1.0 - (2.0 * phase - 1.0).abs());
    for (i, &(x, y)) in fingers.iter().enumerate() {
        let c = Contact {
            id: ContactId(i as u32 + 1),
            x: x + dx,
            y,
            flags,
            ..Contact::default()
        };
        let _ = f.push(c);
    }
    f
}

fn control_tick(c: &mut Criterion) {
    let mut g = c.benchmark_group("control_tick");
    for agents in [100u32, 1000, 5000, 10_000] {
        let mut cfg = Config::embedded_default();
        cfg.crowd.agents = agents;
        let mut engine = Engine::new(&cfg, None, false);
        // The control begins and its grouping window closes before measuring.
        let mut k = 0u64;
        engine.push_frame(&frame(k, ContactFlags::DOWN));
        for _ in 0..60 {
            k += 1;
            engine.push_frame(&frame(k, ContactFlags::NONE));
            drop(engine.tick(Micros(k * PERIOD_US)));
            engine.clear_events();
        }
        g.bench_function(BenchmarkId::from_parameter(agents), |b| {
            b.iter(|| {
                k += 1;
                engine.push_frame(black_box(&frame(k, ContactFlags::NONE)));
                let out = engine.tick(Micros(k * PERIOD_US));
                black_box(&out.snapshot);
                drop(out);
                engine.clear_events();
            })
        });
    }
    g.finish();
}

criterion_group!(benches, control_tick);
criterion_main!(benches);
