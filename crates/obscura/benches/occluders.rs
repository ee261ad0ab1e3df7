//! Occluders from a point (`--cull occluders`): what the culling costs and what it
//! saves, single thread, 1920x1080.
//!
//! `cargo bench -p obscura --bench occluders` (plain timing: each figure is the
//! minimum of `RUNS` runs, default 10). Two cases:
//! - the city demo (`demo::city(16, 16, 7)`) from `VIEWS` (default 8) street-level
//!   cameras (eye 1.5-2 high in a street, looking along it): the cull time, the
//!   z-buffer alone (`View::new` + `render_view`), and cull plus the culled view plus
//!   the z-buffer; the pictures are compared;
//! - Sponza's atrium view (`$SPONZA`, default `../shared/data/sponza.obj` beside the
//!   checkout; the camera of `benches/common`): the same figures; without the file the
//!   case says so and is skipped.

use std::time::Instant;

use glam::DVec3;
use obscura::cull::occlusion::{CullMethod, CullOptions};
use obscura::scene::demo;
use obscura::surface::Algorithm;
use obscura::{Camera, PrepareOptions, RenderOptions, SceneIndex, View, Viewport};

#[path = "common/sponza.rs"]
mod sponza;

fn env_count(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        out = Some(r);
    }
    (best, out.expect("one run"))
}

/// Prints the figures of one view; returns (cull, z-buffer alone, cull + z-buffer) ms.
fn measure(
    name: &str,
    index: &SceneIndex<'_>,
    camera: &Camera,
    vp: Viewport,
    runs: usize,
) -> (f64, f64, f64) {
    let scene = index.scene();
    let p = PrepareOptions::default();
    let o = RenderOptions::default();
    let options = CullOptions::with_method(CullMethod::Occluders);
    // Warm the index (candidates, clusters, hierarchy) outside the timing.
    let _ = index.cull(camera, vp, &options).expect("cull");
    let (cull_ms, culling) = best(runs, || index.cull(camera, vp, &options).expect("cull"));
    let (plain_ms, plain) = best(runs, || {
        let v = View::new(scene, camera, vp, &p).expect("view");
        index
            .render_view(&v, Algorithm::ZBuffer, &o)
            .expect("render")
            .0
    });
    let (both_ms, culled) = best(runs, || {
        let c = index.cull(camera, vp, &options).expect("cull");
        let v = View::new_culled(scene, camera, vp, &p, c).expect("view");
        index
            .render_view(&v, Algorithm::ZBuffer, &o)
            .expect("render")
            .0
    });
    let same = plain.ids == culled.ids && plain.depth == culled.depth;
    let s = &culling.stats;
    println!(
        "{name}: cull {cull_ms:.3} ms ({} occluders; objects {}/{} culled ({} by occluders), clusters {}/{} ({} by occluders), faces {}/{}); z-buffer {plain_ms:.2} ms; cull + z-buffer {both_ms:.2} ms ({:.2}x){}",
        culling.occluders.len(),
        s.objects_culled,
        s.objects_tested,
        s.objects_by_reason.occluder,
        s.clusters_culled,
        s.clusters_tested,
        s.clusters_by_reason.occluder,
        s.faces_culled,
        s.faces_tested,
        plain_ms / both_ms,
        if same { "" } else { "  PICTURES DIFFER" }
    );
    (cull_ms, plain_ms, both_ms)
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let runs = env_count("RUNS", 10);
    let views = env_count("VIEWS", 8);
    let vp = Viewport::new(1920, 1080).expect("viewport");

    let city = demo::city(16, 16, 7);
    let index = SceneIndex::new(&city);
    let t = Instant::now();
    let _ = index.occluder_candidates();
    let _ = index.cluster_bvh();
    println!(
        "city 16x16: {} objects, {} candidates, hierarchy of {} nodes built in {:.2} ms",
        city.objects().len(),
        index.occluder_candidates().len(),
        index.cluster_bvh().node_count(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let (mut sum_plain, mut sum_both, mut sum_cull) = (0.0, 0.0, 0.0);
    for v in 0..views {
        // Streets lie on the integer lines x = k - 8 (z = k - 8): no building reaches them.
        let k = (v * 5 % 15) as f64 + 1.0 - 8.0;
        let a = v as f64 * 0.7;
        let eye = DVec3::new(k, 1.5 + 0.5 * (v % 2) as f64, -6.0 + (v % 4) as f64 * 3.0);
        let dir = if v % 2 == 0 {
            DVec3::new(0.15 * a.sin(), -0.12, 1.0)
        } else {
            DVec3::new(1.0, -0.12, 0.15 * a.cos())
        };
        let camera = Camera::perspective(eye, eye + dir, DVec3::Y, 60.0, 0.05, 60.0);
        let (c, p, b) = measure(&format!("city street view {v}"), &index, &camera, vp, runs);
        sum_cull += c;
        sum_plain += p;
        sum_both += b;
    }
    println!(
        "city, {views} street views: mean cull {:.3} ms, z-buffer {:.2} ms, cull + z-buffer {:.2} ms: {:.2}x",
        sum_cull / views as f64,
        sum_plain / views as f64,
        sum_both / views as f64,
        sum_plain / sum_both
    );

    let (scene, camera) = match sponza::atrium() {
        Ok(s) => s,
        Err(path) => {
            println!("sponza: no scene at {path}: skipped");
            return;
        }
    };
    let index = SceneIndex::new(&scene);
    let t = Instant::now();
    let _ = index.occluder_candidates();
    let _ = index.cluster_bvh();
    println!(
        "sponza: {} candidates of {} found, {} clusters, hierarchy of {} nodes, built in {:.0} ms",
        index.occluder_candidates().len(),
        index.occluder_candidates().found(),
        index.clusters().len(),
        index.cluster_bvh().node_count(),
        t.elapsed().as_secs_f64() * 1e3
    );
    measure("sponza atrium", &index, &camera, vp, runs);
}
