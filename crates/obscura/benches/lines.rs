//! Hidden-line benchmarks: exact hidden-line removal (`lines::hlr::draw`) of the issue's
//! meshes at 1920x1080 on one thread, feature edges as `HlrOptions::default()` finds
//! them, the scene index (its structures) built once outside the timing.
//!
//! `cargo bench -p obscura --bench lines`; `cargo bench -p obscura --bench lines --
//! 'hlr/sphere 62x31'` for one case. Sponza needs its file (`SPONZA=path`, else
//! `../shared/data/sponza.obj` beside the repository) and is skipped with a note
//! without it. Each case prints its edges, pieces and pair tests once.

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use obscura::index::SceneIndex;
use obscura::lines::hlr::{self, HlrOptions};
use obscura::scene::{ObjectDesc, demo};
use obscura::view::{PrepareOptions, View};
use obscura::{Camera, Scene, Viewport};

#[path = "common/sponza.rs"]
mod sponza;

fn torus(segments: u32, sides: u32) -> Scene {
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("torus", demo::torus_mesh(1.0, 0.35, segments, sides))
            .with_transform(glam::DMat4::from_rotation_x(0.6))
            .with_closed(true),
    )
    .unwrap();
    s
}

fn sponza() -> Option<(Scene, Camera)> {
    sponza::atrium()
        .map_err(|path| eprintln!("no Sponza at {path}: skipped"))
        .ok()
}

fn hlr_cases(c: &mut Criterion) {
    let vp = Viewport::new(1920, 1080).unwrap();
    let mut cases: Vec<(String, Scene, Option<Camera>)> = vec![
        ("sphere 62x31".into(), demo::sphere(62, 31), None),
        ("torus 62x30".into(), torus(62, 30), None),
        ("sphere 224x224 (100k)".into(), demo::sphere(224, 224), None),
        ("demo:sphere (1M)".into(), demo::sphere(1000, 500), None),
    ];
    if let Some((scene, camera)) = sponza() {
        cases.push(("sponza".into(), scene, Some(camera)));
    }
    #[cfg(feature = "parallel")]
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("hlr");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(5));
    for (name, scene, camera) in &cases {
        let camera = camera.unwrap_or_else(|| scene.default_camera(vp.aspect()));
        let index = SceneIndex::new(scene);
        let _ = index.edge_adjacency();
        let view = View::new(scene, &camera, vp, &PrepareOptions::default()).unwrap();
        let options = HlrOptions::default();
        let run = || hlr::draw(&index, &view, &options).unwrap();
        #[cfg(feature = "parallel")]
        let run = || one.install(run);
        let (_, stats) = run();
        eprintln!(
            "{name}: {} triangles, {} edges ({} in view), {} pieces ({} visible), {} occluders, \
             {} pair tests, {} exact predicates, cell {:.1} px; edges {:.1} ms, occluders {:.1} ms, cut {:.1} ms",
            scene.triangle_count(),
            stats.edges,
            stats.edges_in_view,
            stats.pieces,
            stats.visible_pieces,
            stats.occluders,
            stats.pair_tests,
            stats.exact_predicates,
            stats.cell_pixels,
            stats.edges_ms,
            stats.occluders_ms,
            stats.cut_ms
        );
        g.bench_function(format!("{name} 1920x1080, 1 thread"), |b| b.iter(run));
    }
    g.finish();
}

criterion_group!(benches, hlr_cases);
criterion_main!(benches);
