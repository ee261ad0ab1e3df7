//! Clipping benchmarks.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec4;
use obscura::clip::sutherland_hodgman::clip_polygon_homogeneous;

fn bench(c: &mut Criterion) {
    let tri = [
        DVec4::new(-1.5, 0.2, 0.1, 1.0),
        DVec4::new(0.7, 1.6, -0.3, 1.0),
        DVec4::new(0.2, -0.4, 0.9, 1.0),
    ];
    c.bench_function("sutherland-hodgman/triangle crossing two planes", |b| {
        b.iter(|| clip_polygon_homogeneous(std::hint::black_box(&tri)))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
