//! Library file benchmarks: reading (parsing and every check: finiteness, indices,
//! orthonormal bases, symmetric positive definite covariances, the CRC-32) and
//! writing a random valid library of 1,500 gestures (1 to 5 fingers, 3 on average)
//! with 150 or 1,500 crowd motions (15 eigenvectors, 2 Gaussians each); one core.
//! The budget for a load is 100 ms for 1,500 entries.
//!
//! `cargo bench --bench gesture_library -- --warm-up-time 1 --measurement-time 3`

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use crowdtouch::gesture::library::{
    crc32, random_library, read_library, write_library, RandomLibrarySpec,
};

fn spec(motions: usize) -> RandomLibrarySpec {
    RandomLibrarySpec {
        motions,
        gestures: 1500,
        components: 15,
        gmm_components: 2,
        max_fingers: 5,
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("gesture_library");
    g.sample_size(20);
    for motions in [150usize, 1500] {
        let lib = random_library(&spec(motions), 0x11B ^ motions as u64);
        let bytes = write_library(&lib);
        eprintln!(
            "gesture_library: 1500 gestures, {motions} motions: {:.1} MB",
            bytes.len() as f64 / 1e6
        );
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_with_input(BenchmarkId::new("read", motions), &bytes, |b, bytes| {
            b.iter(|| read_library(black_box(bytes), "bench.ctgl").expect("valid"))
        });
        g.bench_with_input(BenchmarkId::new("write", motions), &lib, |b, lib| {
            b.iter(|| write_library(black_box(lib)))
        });
        g.bench_with_input(BenchmarkId::new("crc32", motions), &bytes, |b, bytes| {
            b.iter(|| crc32(black_box(bytes)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
