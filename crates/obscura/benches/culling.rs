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
//! `METHODS=buffer,frustum` times only those methods (names as printed; all by
//! default), for profiling one path. Each time is the best of `RUNS` (default 5) after
//! one warm-up; the index (and its
//! clusters) is built before timing, as a viewer builds it once. Every figure is taken
//! twice: rendering into a kept frame ([`Renderer`], [`SceneIndex::render_into`] and
//! [`SceneIndex::render_culled_into`], as a viewer or an engine renders frame after
//! frame; the main columns), and into a fresh frame per call ([`SceneIndex::render`],
//! [`SceneIndex::render_culled`]; the "fresh" columns, whose time includes the kernel
//! zeroing and faulting in 16.6 MB of new frame). "cull" is the culling stage
//! ([`obscura::cull::occlusion::CullStats::total_ms`]); "zbuf" the z-buffer's render
//! call ([`obscura::surface::Stats::time_ms`]); "view" the rest (the view's decisions
//! and polygons: "total" minus both); "total" is the cull, the view and the z-buffer
//! (each figure is that of the fastest run). `PHASES=1` prints the z-buffer's phases of
//! every run. Every run checks that the culled frame equals the plain one (ids
//! and depths), so a figure never comes from a wrong picture.

use std::time::Instant;

use glam::DVec3;
use obscura::cull::occlusion::{CullMethod, CullOptions};
use obscura::scene::demo;
use obscura::{
    Algorithm, Camera, Frame, PrepareOptions, RenderOptions, Renderer, Scene, SceneIndex, View,
    Viewport,
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
/// result of that run.
fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut out = f();
    let mut best = f64::INFINITY;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let o = f();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if ms < best {
            (best, out) = (ms, o);
        }
    }
    (best, out)
}

/// With `PHASES` set, the z-buffer's phases of a render (for profiling).
fn phases(what: &str, stats: &obscura::surface::Stats) {
    if std::env::var_os("PHASES").is_none() {
        return;
    }
    if let obscura::surface::AlgorithmStats::ZBuffer(z) = &stats.algorithm
        && let Some(f) = &z.fast
    {
        println!(
            "    {what}: z-buffer {:.2} ms: setup and small {:.2}, binning {:.2}, tiles {:.2}; {} big polygons",
            stats.time_ms, f.setup_and_small_ms, f.binning_ms, f.tiles_ms, f.big_polygons
        );
    }
}

/// The prepared view of a camera (no culling stage).
fn plain_view<'s>(
    index: &SceneIndex<'s>,
    camera: &Camera,
    vp: Viewport,
) -> obscura::PreparedView<'s> {
    View::new(index.scene(), camera, vp, &PrepareOptions::default())
        .expect("view")
        .into_prepared()
}

/// The plain z-buffer of a view (no culling stage) in a fresh frame.
fn plain(index: &SceneIndex<'_>, camera: &Camera, vp: Viewport) -> Frame {
    index
        .render(
            &plain_view(index, camera, vp),
            Algorithm::ZBuffer,
            &RenderOptions::default(),
        )
        .expect("z-buffer")
        .0
}

/// The plain z-buffer of a view into the renderer's kept frame; the milliseconds of the
/// z-buffer (the render call).
fn plain_kept(
    index: &SceneIndex<'_>,
    renderer: &mut Renderer,
    camera: &Camera,
    vp: Viewport,
) -> f64 {
    let view = plain_view(index, camera, vp);
    let (_, stats) = index
        .render_into(
            renderer,
            &view,
            Algorithm::ZBuffer,
            &RenderOptions::default(),
        )
        .expect("z-buffer");
    phases("alone", &stats);
    stats.time_ms
}

/// Times the z-buffer alone and each method + z-buffer on the views; prints a row per
/// method; returns the best speed-up and the best total (mean over the views, ms),
/// both into a kept frame.
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
    let mut renderer = Renderer::new();
    let (mut base_ms, mut base_zbuf, mut base_fresh_ms) = (0.0, 0.0, 0.0);
    let mut truths = Vec::new();
    for c in cameras {
        let (ms, f) = best(runs, || plain(&index, c, vp));
        base_fresh_ms += ms / n;
        let (ms, zbuf) = best(runs, || plain_kept(&index, &mut renderer, c, vp));
        assert!(
            *renderer.frame() == f,
            "{name}: the kept frame differs from a fresh one"
        );
        base_ms += ms / n;
        base_zbuf += zbuf / n;
        truths.push(f);
    }
    println!(
        "  {:<16} {:>8} {:>8} {:>8} {:>9} {:>8} {:>9} {:>8} {:>10}",
        "method",
        "cull ms",
        "view ms",
        "zbuf ms",
        "total ms",
        "speedup",
        "fresh ms",
        "speedup",
        "faces cul%"
    );
    println!(
        "  {:<16} {:>8} {:>8.2} {:>8.2} {:>9.2} {:>8} {:>9.2} {:>8} {:>10}",
        "z-buffer alone",
        "-",
        base_ms - base_zbuf,
        base_zbuf,
        base_ms,
        "1.00x",
        base_fresh_ms,
        "1.00x",
        "-"
    );
    let (mut best_speedup, mut best_total) = (0.0f64, f64::INFINITY);
    let chosen = std::env::var("METHODS").ok();
    let chosen = |m: CullMethod| {
        chosen
            .as_deref()
            .is_none_or(|list| list.split(',').any(|n| n.trim() == m.name()))
    };
    for &m in methods.iter().filter(|&&m| chosen(m)) {
        let opts = CullOptions::with_method(m);
        let (mut total, mut fresh, mut cull, mut zbuf) = (0.0, 0.0, 0.0, 0.0);
        let (mut culled, mut tested) = (0u64, 0u64);
        for (c, truth) in cameras.iter().zip(&truths) {
            let (ms, (frame, _, _)) = best(runs, || {
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
                frame == *truth,
                "{name}: {} changed the picture: a method culled something visible",
                m.name()
            );
            fresh += ms / n;
            let (ms, (culling, zbuf_ms)) = best(runs, || {
                let (_, stats, culling) = index
                    .render_culled_into(
                        &mut renderer,
                        c,
                        vp,
                        &PrepareOptions::default(),
                        &opts,
                        Algorithm::ZBuffer,
                        &RenderOptions::default(),
                    )
                    .expect("render_culled_into");
                phases(m.name(), &stats);
                (culling, stats.time_ms)
            });
            // (Every run draws the same frame: the last one is checked.)
            assert!(
                renderer.frame() == truth,
                "{name}: {} changed the picture in a kept frame",
                m.name()
            );
            total += ms / n;
            cull += culling.stats.total_ms / n;
            zbuf += zbuf_ms / n;
            culled += culling.stats.faces_culled;
            tested += culling.stats.faces_tested;
        }
        let speedup = base_ms / total;
        best_speedup = best_speedup.max(speedup);
        best_total = best_total.min(total);
        println!(
            "  {:<16} {:>8.2} {:>8.2} {:>8.2} {:>9.2} {:>7.2}x {:>9.2} {:>7.2}x {:>10.1}",
            m.name(),
            cull,
            total - cull - zbuf,
            zbuf,
            total,
            speedup,
            fresh,
            base_fresh_ms / fresh,
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
