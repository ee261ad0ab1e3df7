//! Z-buffer benchmarks at 1920x1080: the front end (`prepare`) and the z-buffer
//! separately, on the scenes of the performance targets.
//!
//! - `demo:sphere`: 998,000 small triangles (per-triangle cost);
//! - `demo:city`: 10,000 boxes (medium quads);
//! - `demo:triangles`: 10,000 large overlapping triangles, about 520 million covered
//!   samples (fill rate; throughput reported in elements = covered samples, each of
//!   which the reference depth-tests);
//! - Sponza, when `../shared/data/sponza.obj` (relative to the workspace) exists;
//! - the reference implementation on the city, for comparison.
//!
//! `render` draws a new frame each time (its memory faulted in); `render_into` draws
//! into a kept frame with kept buffers ([`zbuffer::render_into`]).
//!
//! Run: `cargo bench -p obscura --bench zbuffer` (threads: `RAYON_NUM_THREADS=1` for
//! single-thread figures).

use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use obscura::scene::demo;
use obscura::surface::{RenderOptions, zbuffer};
use obscura::{Camera, PrepareOptions, Scene, Viewport, prepare};

fn scenes() -> Vec<(String, Scene, Camera)> {
    let mut out = Vec::new();
    for name in ["sphere", "city", "triangles"] {
        let scene = demo::scene(name).expect("demo scene");
        let cam = *scene.camera().expect("demo scenes carry a camera");
        out.push((name.to_string(), scene, cam));
    }
    let sponza = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/sponza.obj");
    if let Ok(scene) = Scene::load(&sponza) {
        let cam = Camera::perspective(
            DVec3::new(0.0, -10.0, 2.0),
            DVec3::new(0.0, 10.0, 4.0),
            DVec3::Z,
            60.0,
            0.05,
            60.0,
        );
        out.push(("sponza".to_string(), scene, cam));
    }
    out
}

fn bench(c: &mut Criterion) {
    let vp = Viewport::new(1920, 1080).expect("valid size");
    let opts = RenderOptions::default();
    for (name, scene, cam) in scenes() {
        let mut g = c.benchmark_group(format!("zbuffer/{name} 1920x1080"));
        g.sample_size(10);
        g.bench_function("prepare", |b| {
            b.iter(|| prepare(&scene, &cam, vp, &PrepareOptions::default()).expect("prepared"))
        });
        let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).expect("prepared");
        // Throughput in covered samples: the pixels the reference depth-tests one by
        // one (the fast path skips the blocks its occlusion culling proves hidden).
        let (_, stats) = zbuffer::render_reference(&view, &opts).expect("rendered");
        let covered = stats.pixels_tested;
        g.throughput(Throughput::Elements(covered));
        g.bench_function("render", |b| {
            b.iter(|| zbuffer::render(&view, &opts).expect("rendered"))
        });
        // Into a kept frame with kept buffers, as a viewer renders frame after frame.
        let mut frame = zbuffer::render(&view, &opts).expect("rendered").0;
        let mut buffers = zbuffer::Buffers::new();
        g.bench_function("render_into", |b| {
            b.iter(|| {
                zbuffer::render_into(&view, &opts, &mut frame, &mut buffers).expect("rendered")
            })
        });
        if name == "city" {
            g.bench_function("render_reference", |b| {
                b.iter(|| zbuffer::render_reference(&view, &opts).expect("rendered"))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
