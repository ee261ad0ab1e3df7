//! Ray casting benchmarks: the four accelerations on the default demo scene, the BVH and
//! grid builds, and BVH tracing alone (built once, as for many views).
//!
//! `cargo bench -p obscura --bench raycast`; the Sponza group needs the file (see
//! [`sponza`]). Criterion reports the time per frame (or
//! build) and the throughput in rays (or triangles) per second. The figures of the
//! brief (1920x1080, one thread) come from the CLI's `--stats-json`: `trace_ms`,
//! `mrays_per_s`, `build_ms`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use obscura::accel::bvh::{Bvh, BvhOptions};
use obscura::accel::grid::{GridOptions, UniformGrid};
use obscura::accel::triangles::SceneTriangles;
use obscura::geom::BoundsKind;
use obscura::scene::demo;
use obscura::surface::raycast::{self, Acceleration};
use obscura::{PrepareOptions, RenderOptions, Viewport, prepare};

fn variants(c: &mut Criterion) {
    let scene = demo::default_scene();
    let vp = Viewport::new(160, 120).unwrap();
    let cam = scene.default_camera(vp.aspect());
    let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let mut g = c.benchmark_group("raycast/default 160x120");
    g.throughput(Throughput::Elements(vp.pixel_count() as u64));
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(4));
    for (name, acc) in [
        ("brute-force", Acceleration::BruteForce),
        ("bounds-sphere", Acceleration::Bounds(BoundsKind::Sphere)),
        ("bounds-aabb", Acceleration::Bounds(BoundsKind::Aabb)),
        ("bounds-obb", Acceleration::Bounds(BoundsKind::Obb)),
        ("bounds-kdop", Acceleration::Bounds(BoundsKind::Kdop)),
        ("bvh (with build)", Acceleration::Bvh),
        ("grid (with build)", Acceleration::Grid),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| raycast::render(&view, acc, &RenderOptions::default()).unwrap())
        });
    }
    g.finish();
}

fn builds(c: &mut Criterion) {
    let mut g = c.benchmark_group("raycast/build");
    g.sample_size(10);
    for (name, scene) in [
        ("city 60x60", demo::city(60, 60, 7)),
        ("sphere 400x200", demo::sphere(400, 200)),
    ] {
        let tris = SceneTriangles::new(&scene);
        g.throughput(Throughput::Elements(tris.len() as u64));
        g.bench_with_input(BenchmarkId::new("bvh", name), &tris, |b, t| {
            b.iter(|| Bvh::build(black_box(t), &BvhOptions::default()))
        });
        g.bench_with_input(BenchmarkId::new("grid", name), &tris, |b, t| {
            b.iter(|| UniformGrid::build(black_box(t), &GridOptions::default()))
        });
    }
    g.finish();
}

fn bvh_trace(c: &mut Criterion) {
    let mut g = c.benchmark_group("raycast/bvh trace 640x360");
    g.sample_size(10);
    let vp = Viewport::new(640, 360).unwrap();
    g.throughput(Throughput::Elements(vp.pixel_count() as u64));
    for (name, scene) in [
        ("city 60x60", demo::city(60, 60, 7)),
        ("sphere 400x200", demo::sphere(400, 200)),
    ] {
        let tris = SceneTriangles::new(&scene);
        let bvh = Bvh::build(&tris, &BvhOptions::default());
        let cam = scene.default_camera(vp.aspect());
        let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        g.bench_function(name, |b| {
            b.iter(|| raycast::render_bvh(&view, &tris, &bvh, &RenderOptions::default()).unwrap())
        });
    }
    g.finish();
}

/// Sponza's atrium at 1920x1080 (the figures), when the file is there:
/// `SPONZA=path`, else `../shared/data/sponza.obj` beside the repository.
fn sponza(c: &mut Criterion) {
    let path = std::env::var("SPONZA").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/sponza.obj"
        )
        .to_string()
    });
    let Ok(scene) = obscura::Scene::load(&path) else {
        eprintln!("no Sponza at {path}: skipped");
        return;
    };
    let vp = Viewport::new(1920, 1080).unwrap();
    let cam = obscura::Camera::perspective(
        glam::DVec3::new(0.0, -10.0, 2.0),
        glam::DVec3::new(0.0, 10.0, 4.0),
        glam::DVec3::Z,
        60.0,
        0.05,
        100.0,
    );
    let tris = SceneTriangles::new(&scene);
    let mut g = c.benchmark_group("raycast/sponza");
    g.sample_size(10);
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("bvh build", |b| {
        b.iter(|| Bvh::build(black_box(&tris), &BvhOptions::default()))
    });
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    g.throughput(Throughput::Elements(vp.pixel_count() as u64));
    // One thread, as the figures.
    let trace = || raycast::render_bvh(&view, &tris, &bvh, &RenderOptions::default()).unwrap();
    #[cfg(feature = "parallel")]
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    g.bench_function("bvh trace 1920x1080, 1 thread", |b| {
        #[cfg(feature = "parallel")]
        b.iter(|| one.install(trace));
        #[cfg(not(feature = "parallel"))]
        b.iter(trace);
    });
    g.finish();
}

criterion_group!(benches, variants, builds, bvh_trace, sponza);
criterion_main!(benches);
