//! Culling pays for itself (issue 24): the z-buffer alone against each culling method
//! followed by the z-buffer, single thread, 1920x1080.
//!
//! `cargo bench -p obscura --bench culling` (plain timing, not criterion: a table the
//! issue's closing note quotes). Two scenes:
//! - the city demo (10,000 boxes, 60,001 faces) from street level, three views down
//!   and across its streets; target: cull + z-buffer at least 3x faster than the
//!   z-buffer alone for the best method;
//! - Sponza's atrium view (`$SPONZA`, default `../shared/data/sponza.obj` beside the
//!   checkout; the camera of `benches/common`: `--eye 0,-10,2 --target 0,10,4 --up
//!   0,0,1 --fov 60`), one big object culled cluster by cluster; target: cluster
//!   culling + z-buffer at most 15 ms (the z-buffer alone takes about 21-28 ms).
//!   Without the file the bench says so and skips it.
//!
//! Each time is the best of `RUNS` (default 5) after one warm-up; the index (and its
//! clusters) is built before timing, as a viewer builds it once. "cull" is the
//! culling stage ([`obscura::cull::occlusion::CullStats::total_ms`]); "total" is the
//! cull, the view and the z-buffer, measured around [`SceneIndex::render_culled`]. Every run checks
//! that the culled frame equals the plain one (ids), so a figure never comes from a
//! wrong picture.

use std::time::Instant;

use glam::DVec3;
use obscura::cull::occlusion::{CullMethod, CullOptions};
use obscura::scene::demo;
use obscura::{
    Algorithm, Camera, Frame, PrepareOptions, RenderOptions, Scene, SceneIndex, View, Viewport,
};

#[path = "common/sponza.rs"]
mod sponza;

fn env_count(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The best of `runs` timings of `f` (after one warm-up), in milliseconds, and the
/// last result.
fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut out = f();
    let mut best = f64::INFINITY;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        out = f();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    (best, out)
}

/// The plain z-buffer of a view (no culling stage).
fn plain(index: &SceneIndex<'_>, camera: &Camera, vp: Viewport) -> Frame {
    let scene = index.scene();
    let view = View::new(scene, camera, vp, &PrepareOptions::default()).expect("view");
    index
        .render_view(&view, Algorithm::ZBuffer, &RenderOptions::default())
        .expect("z-buffer")
        .0
}

/// Times the z-buffer alone and each method + z-buffer on the views; prints a row per
/// method; returns the best speed-up and the best total (mean over the views, ms).
fn measure(
    name: &str,
    scene: &Scene,
    cameras: &[Camera],
    methods: &[CullMethod],
    runs: usize,
) -> (f64, f64) {
    let vp = Viewport::new(1920, 1080).expect("viewport");
    let index = SceneIndex::new(scene);
    let t = Instant::now();
    let clusters = index.clusters().len();
    println!(
        "{name}: {} objects, {} faces, {clusters} clusters (built in {:.1} ms), {} view(s), \
         1920x1080, 1 thread, best of {runs}",
        scene.objects().len(),
        scene.face_count(),
        t.elapsed().as_secs_f64() * 1e3,
        cameras.len()
    );
    let n = cameras.len() as f64;
    let mut base_ms = 0.0;
    let mut truths = Vec::new();
    for c in cameras {
        let (ms, f) = best(runs, || plain(&index, c, vp));
        base_ms += ms / n;
        truths.push(f);
    }
    println!(
        "  {:<16} {:>9} {:>9} {:>9} {:>8} {:>9}",
        "method", "cull ms", "rest ms", "total ms", "speedup", "faces cul%"
    );
    println!(
        "  {:<16} {:>9} {:>9} {:>9.2} {:>8} {:>9}",
        "z-buffer alone", "-", "-", base_ms, "1.00x", "-"
    );
    let (mut best_speedup, mut best_total) = (0.0f64, f64::INFINITY);
    for &m in methods {
        let opts = CullOptions::with_method(m);
        let (mut total, mut cull, mut culled, mut tested) = (0.0, 0.0, 0u64, 0u64);
        for (c, truth) in cameras.iter().zip(&truths) {
            let (ms, (frame, _, culling)) = best(runs, || {
                index
                    .render_culled(
                        c,
                        vp,
                        &PrepareOptions::default(),
                        &opts,
                        Algorithm::ZBuffer,
                        &RenderOptions::default(),
                    )
                    .expect("render_culled")
            });
            assert!(
                frame.ids == truth.ids,
                "{name}: {} changed the picture: a method culled something visible",
                m.name()
            );
            total += ms / n;
            cull += culling.stats.total_ms / n;
            culled += culling.stats.faces_culled;
            tested += culling.stats.faces_tested;
        }
        let speedup = base_ms / total;
        best_speedup = best_speedup.max(speedup);
        best_total = best_total.min(total);
        println!(
            "  {:<16} {:>9.2} {:>9.2} {:>9.2} {:>7.2}x {:>9.1}",
            m.name(),
            cull,
            total - cull,
            total,
            speedup,
            100.0 * culled as f64 / tested.max(1) as f64
        );
    }
    (best_speedup, best_total)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let runs = env_count("RUNS", 5);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    pool.install(|| {
        let methods = [
            CullMethod::Frustum,
            CullMethod::Portals,
            CullMethod::ScreenPortals,
            CullMethod::Occluders,
            CullMethod::Buffer,
        ];
        // The city: streets lie on whole units (blocks are centred between them).
        let city = demo::city(100, 100, 7);
        let street = |eye: DVec3, target: DVec3| {
            Camera::perspective(eye, target, DVec3::Y, 60.0, 0.05, 300.0)
        };
        let cameras = [
            street(DVec3::new(0.0, 1.5, -49.0), DVec3::new(0.0, 1.5, 49.0)),
            street(DVec3::new(-49.0, 1.2, 10.0), DVec3::new(49.0, 2.0, 10.0)),
            street(DVec3::new(-20.0, 1.7, -20.0), DVec3::new(10.0, 2.5, 5.0)),
        ];
        let (speedup, _) = measure(
            "city demo, street level",
            &city,
            &cameras,
            &methods,
            runs,
        );
        println!(
            "  target: the best method at least 3x faster than the z-buffer alone: {speedup:.2}x {}",
            if speedup >= 3.0 { "(met)" } else { "(NOT met)" }
        );

        let (sponza, camera) = match sponza::atrium() {
            Ok(s) => s,
            Err(path) => {
                println!("sponza: no file at {path} (set SPONZA): skipped");
                return;
            }
        };
        let (_, total) = measure(
            "sponza atrium",
            &sponza,
            &[camera],
            &[CullMethod::Frustum, CullMethod::Occluders, CullMethod::Buffer],
            runs,
        );
        println!(
            "  target: cluster culling + z-buffer at most 15 ms: {total:.2} ms {}",
            if total <= 15.0 { "(met)" } else { "(NOT met)" }
        );
    });
}
