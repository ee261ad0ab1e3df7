//! Feature edges, intersection lines and the sampling oracle, one thread.
//!
//! `cargo bench -p obscura --bench lines_edges`; the Sponza group needs the file
//! (`SPONZA=path`, default `../shared/data/sponza.obj` from the workspace). Criterion
//! reports the time per call. Feature edges are per view (the index's adjacency and
//! intersection lines are built before timing, as for a second view); intersection
//! lines are timed alone from a built BVH (they are computed once per scene).

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec2;
use obscura::lines::check::{CheckOptions, check};
use obscura::lines::edges::{EdgeOptions, feature_edges, intersect};
use obscura::lines::{Drawing, EdgeKinds, Piece};
use obscura::scene::demo;
use obscura::{Camera, PrepareOptions, Scene, SceneIndex, View, Viewport};

/// A pool of one thread: the figures are single-threaded.
fn one_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
}

fn measure(c: &mut Criterion, name: &str, scene: &Scene, camera: &Camera, kinds: EdgeKinds) {
    let vp = Viewport::new(1920, 1080).unwrap();
    let view = View::new(scene, camera, vp, &PrepareOptions::default()).unwrap();
    let index = SceneIndex::new(scene);
    let options = EdgeOptions::default().with_kinds(kinds);
    let edges = feature_edges(&index, &view, &options).unwrap();
    eprintln!(
        "{name}: {} triangles, {} edges ({} intersection segments)",
        scene.triangle_count(),
        edges.len(),
        index.intersection_lines().len()
    );
    let mut drawing = Drawing::new(vp.width, vp.height);
    drawing.pieces = (0..edges.len() as u32)
        .map(|edge| Piece {
            edge,
            t: [0.0, 1.0],
            points: [DVec2::ZERO; 2],
            invisibility: 0,
        })
        .collect();
    drawing.edges = edges;
    let mut g = c.benchmark_group(format!("lines/{name}"));
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(3));
    let pool = one_thread();
    g.bench_function("feature edges (per view)", |b| {
        b.iter(|| pool.install(|| feature_edges(&index, &view, &options).unwrap()))
    });
    g.bench_function("intersection lines (per scene)", |b| {
        b.iter(|| pool.install(|| intersect::intersection_lines(index.bvh())))
    });
    g.bench_function("check, 3 samples a piece", |b| {
        b.iter(|| pool.install(|| check(&index, &view, &drawing, &CheckOptions::default())))
    });
    g.finish();
}

fn spheres(c: &mut Criterion) {
    // 3,744 and 100,000 triangles.
    for (segments, rings) in [(48, 40), (250, 201)] {
        let scene = demo::sphere(segments, rings);
        let camera = scene.default_camera(16.0 / 9.0);
        let name = format!("sphere {}", scene.triangle_count());
        measure(c, &name, &scene, &camera, EdgeKinds::default());
    }
}

fn sponza(c: &mut Criterion) {
    let path = std::env::var("SPONZA").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/sponza.obj"
        )
        .to_string()
    });
    let Ok(scene) = Scene::load(&path) else {
        eprintln!("no Sponza at {path}: skipped");
        return;
    };
    let camera = Camera::perspective(
        glam::DVec3::new(0.0, -10.0, 2.0),
        glam::DVec3::new(0.0, 10.0, 4.0),
        glam::DVec3::Z,
        60.0,
        0.05,
        100.0,
    );
    measure(c, "sponza", &scene, &camera, EdgeKinds::default());
}

criterion_group!(benches, spheres, sponza);
criterion_main!(benches);
