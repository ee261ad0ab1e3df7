//! Z-buffer benchmarks.

use criterion::{Criterion, criterion_group, criterion_main};
use obscura::scene::demo;
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::{PrepareOptions, Viewport, prepare};

fn bench(c: &mut Criterion) {
    let scene = demo::default_scene();
    let vp = Viewport::new(640, 480).unwrap();
    let cam = scene.default_camera(vp.aspect());
    c.bench_function("zbuffer/default 640x480", |b| {
        b.iter(|| {
            let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
            render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
