//! One scene, many views: per-view time with every structure built on each call (the
//! old path: `prepare` + `surface::render`) against per-view time with a
//! [`SceneIndex`] (structures built once, `View::new` + `SceneIndex::render_view`,
//! no screen polygons for the algorithms that need none).
//!
//! `cargo bench -p obscura --bench views` (plain timing, not criterion: a build of
//! Sponza's BSP tree takes seconds, so criterion's repetitions would take an hour).
//! Sponza at 640x360, `VIEWS` views (100) on an orbit around the atrium's centre,
//! with `raycast-bvh` and `bsp`; the old path runs the first `VIEWS_OLD` views (10)
//! and the two paths' id images are compared on them. The scene is
//! `../shared/data/sponza.obj` or `$SPONZA`; without it the bench says so and stops.

use std::time::Instant;

use glam::DVec3;
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::view::View;
use obscura::{Camera, PrepareOptions, Scene, SceneIndex, Viewport, prepare};

fn env_count(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `n` cameras on an ellipse around the centre of the scene's box, at its height,
/// looking at the centre (z up, as Sponza is).
fn orbit(scene: &Scene, n: usize) -> Vec<Camera> {
    let b = scene.bounds();
    let (c, e) = ((b.min + b.max) * 0.5, (b.max - b.min) * 0.5);
    (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            let eye = c + DVec3::new(0.3 * e.x * a.cos(), 0.3 * e.y * a.sin(), -0.2 * e.z);
            Camera::perspective(eye, c, DVec3::Z, 60.0, 0.05, 4.0 * e.length())
        })
        .collect()
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return;
    }
    let path = std::env::var("SPONZA").unwrap_or_else(|_| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/sponza.obj"
        )
        .to_string()
    });
    let Ok(scene) = Scene::load(&path) else {
        println!("views: no Sponza at {path}: skipped");
        return;
    };
    let (views, views_old) = (env_count("VIEWS", 100), env_count("VIEWS_OLD", 10));
    let vp = Viewport::new(640, 360).unwrap();
    let cameras = orbit(&scene, views);
    let po = PrepareOptions::default();
    let ro = RenderOptions::default();
    println!(
        "views: Sponza ({} triangles), {}x{}, {views} views on an orbit ({views_old} on the old path)",
        scene.triangle_count(),
        vp.width,
        vp.height,
    );
    for algorithm in [Algorithm::RaycastBvh, Algorithm::Bsp] {
        // The index: the structures built once, timed apart.
        let index = SceneIndex::new(&scene);
        let start = Instant::now();
        match algorithm {
            Algorithm::RaycastBvh => {
                index.bvh();
            }
            _ => {
                let bsp = ro
                    .bsp
                    .with_memory_limit(ro.bsp.memory_limit.or(ro.memory_limit));
                index
                    .bsp(&bsp, &obscura::work::Deadline::NONE)
                    .expect("BSP tree within the budget");
            }
        }
        let build_ms = ms(start);
        let (mut view_ms, mut render_ms) = (0.0, 0.0);
        let mut new_ids = Vec::new();
        for cam in &cameras {
            let t = Instant::now();
            let view = View::new(&scene, cam, vp, &po).expect("valid view");
            view_ms += ms(t);
            let t = Instant::now();
            let (frame, _) = index.render_view(&view, algorithm, &ro).expect("renders");
            render_ms += ms(t);
            if new_ids.len() < views_old {
                new_ids.push(frame.ids);
            }
        }
        let b = index.builds();
        assert!(b.bvh <= 1 && b.bsp <= 1, "built once: {b:?}");
        // The old path: prepare (with the screen polygons) and build on every call.
        let (mut old_prepare, mut old_render) = (0.0, 0.0);
        for (k, cam) in cameras.iter().take(views_old).enumerate() {
            let t = Instant::now();
            let view = prepare(&scene, cam, vp, &po).expect("valid view");
            old_prepare += ms(t);
            let t = Instant::now();
            let (frame, _) = render(algorithm, &view, &ro).expect("renders");
            old_render += ms(t);
            assert!(frame.ids == new_ids[k], "view {k}: the two paths differ");
        }
        let n = views as f64;
        let m = views_old.max(1) as f64;
        println!(
            "{algorithm}: build once {build_ms:.1} ms; index: {:.2} ms a view ({:.2} view decisions + {:.2} render); old: {:.2} ms a view ({:.2} prepare + {:.2} build and render); same ids on {} views",
            (view_ms + render_ms) / n,
            view_ms / n,
            render_ms / n,
            (old_prepare + old_render) / m,
            old_prepare / m,
            old_render / m,
            views_old.min(views)
        );
    }
}
