//! Running time (issue 21, section 3): work that would pass the time limit by estimate
//! is refused before it starts, every loop whose length the input decides stops at the
//! deadline or when the stop flag is raised, and the estimates count what they say.
//! Every input is generated here.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use glam::DVec3;
use obscura::accel::bsp::{BspOptions, BspTraversal, BspTree};
use obscura::scene::{Faces, Scene, Viewport, demo};
use obscura::surface::{self, Algorithm, RenderOptions, estimate, render};
use obscura::{Camera, Error, PrepareOptions, prepare};

/// `k` squares of side 20 around the z axis, one behind the other (from arrays, so
/// that the test runs without the file formats' features).
fn stacked_squares(k: usize) -> Scene {
    let mut positions = Vec::new();
    let (mut offsets, mut indices) = (vec![0u32], Vec::new());
    for i in 0..k {
        let z = -(i as f64) * 0.01;
        for (x, y) in [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)] {
            positions.push([x, y, z]);
        }
        let b = 4 * i as u32;
        indices.extend([b, b + 1, b + 2, b + 3]);
        offsets.push(indices.len() as u32);
    }
    Scene::from_arrays(
        &positions,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )
    .unwrap()
}

/// The scene from its default camera at `w` x `h`, prepared with the default options.
fn default_view(scene: &Scene, w: u64, h: u64) -> obscura::PreparedView<'_> {
    let vp = Viewport::new(w, h).unwrap();
    prepare(
        scene,
        &scene.default_camera(vp.aspect()),
        vp,
        &PrepareOptions::default(),
    )
    .unwrap()
}

/// Looking down -z at the squares: every one covers the whole image.
fn camera() -> Camera {
    Camera::orthographic(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        2.0,
        0.1,
        100.0,
    )
}

#[test]
fn painters_estimate_the_pixels_they_paint() {
    let k = 7;
    let scene = stacked_squares(k);
    let vp = Viewport::new(40, 30).unwrap();
    let view = prepare(&scene, &camera(), vp, &PrepareOptions::default()).unwrap();
    // Each square is clipped to the image: 40 x 30 pixels, k of them.
    let expected = (k * 40 * 30) as f64;
    let back_to_front = RenderOptions::default()
        .with_bsp(BspOptions::default().with_traversal(BspTraversal::BackToFront));
    for (algorithm, options) in [
        (Algorithm::DepthSort, RenderOptions::default()),
        (Algorithm::DepthSortMatrix, RenderOptions::default()),
        (Algorithm::Bsp, back_to_front),
    ] {
        let e = estimate(algorithm, &view, &options).expect("painters have an estimate");
        assert_eq!(e.items, "pixels painted");
        assert!(
            (e.count - expected).abs() < 1e-9 * expected,
            "{algorithm}: {e:?}"
        );
    }
    // A front-to-back BSP writes each pixel once: nothing to estimate.
    assert!(estimate(Algorithm::Bsp, &view, &RenderOptions::default()).is_none());
}

#[test]
fn ray_casters_estimate_their_ray_triangle_tests() {
    let k = 5;
    let scene = stacked_squares(k);
    let vp = Viewport::new(32, 24).unwrap();
    let view = prepare(&scene, &camera(), vp, &PrepareOptions::default()).unwrap();
    let options = RenderOptions::default();
    // Every ray against every triangle: 32 x 24 rays, 2 triangles per square.
    let brute = estimate(Algorithm::Raycast, &view, &options).unwrap();
    assert_eq!(brute.count, (32 * 24 * 2 * k) as f64);
    // The object's box reaches over the whole image: the same count.
    let bounds = estimate(Algorithm::RaycastBounds, &view, &options).unwrap();
    assert_eq!(bounds.count, brute.count);
    // Seen from afar, the box covers a part of the image, and fewer rays meet it.
    let far = Camera::orthographic(
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        80.0,
        0.1,
        100.0,
    );
    let view = prepare(&scene, &far, vp, &PrepareOptions::default()).unwrap();
    let part = estimate(Algorithm::RaycastBounds, &view, &options).unwrap();
    // The box is 20 of 80 units tall and 20 of 80 * 32/24 wide.
    let expected = (24.0 * 20.0 / 80.0) * (32.0 * 20.0 / (80.0 * 32.0 / 24.0)) * (2 * k) as f64;
    assert!(
        (part.count - expected).abs() < 1e-6 * expected,
        "{part:?} vs {expected}"
    );
}

#[test]
fn work_over_the_limit_is_refused_before_it_starts() {
    // 1000 x 1000 rays against 10,000 triangles: 1e10 tests, some 15 s.
    let scene = stacked_squares(5000);
    let vp = Viewport::new(1000, 1000).unwrap();
    let view = prepare(&scene, &camera(), vp, &PrepareOptions::default()).unwrap();
    let options = RenderOptions::default().with_time_limit(Some(Duration::from_secs(10)));
    let start = Instant::now();
    match render(Algorithm::Raycast, &view, &options) {
        Err(Error::TimeLimit {
            work,
            estimate_s: Some(s),
            limit_s,
            option,
            at,
        }) => {
            assert_eq!(at, None, "the library knows no file name");
            assert!(
                work.contains("raycast") && work.contains("1e10 ray-triangle tests"),
                "{work}"
            );
            assert!((s - 15.0).abs() < 1e-6, "{s}");
            assert!(limit_s <= 10.0 && limit_s > 9.0, "{limit_s}");
            assert_eq!(option, "time_limit");
        }
        other => panic!(
            "expected a refusal on the estimate, got {:?}",
            other.map(|_| ())
        ),
    }
    // Refused, not started: far less than the work itself (a bound, not a timing).
    assert!(start.elapsed() < Duration::from_secs(5));
    // Without a limit nothing is estimated or refused (not run here: 15 s).
    assert!(RenderOptions::default().time_limit.is_none());
}

#[test]
fn every_algorithm_stops_at_a_spent_limit() {
    let scene = demo::cube();
    let view = default_view(&scene, 64, 48);
    let options = RenderOptions::default().with_time_limit(Some(Duration::ZERO));
    for algorithm in Algorithm::ALL {
        match render(algorithm, &view, &options) {
            Err(e @ Error::TimeLimit { .. }) => {
                assert!(e.to_string().contains("time_limit"), "{algorithm}: {e}");
            }
            other => panic!("{algorithm}: {:?}", other.map(|_| ())),
        }
    }
}

/// Options whose stop flag is already raised, with the deadline started (as
/// `surface::render` does), for calling an algorithm's own `render`.
fn stopped() -> RenderOptions {
    let flag = Arc::new(AtomicBool::new(true));
    RenderOptions::default().with_stop(flag).started()
}

fn assert_stopped<T>(what: &str, r: obscura::Result<T>) {
    match r {
        Err(Error::Stopped { work }) => assert!(!work.is_empty()),
        Err(e) => panic!("{what}: expected Stopped, got {e}"),
        Ok(_) => panic!("{what}: ran to the end with the stop flag raised"),
    }
}

#[test]
fn the_loops_of_every_algorithm_check_the_stop_flag() {
    // Each algorithm's own entry point: only its loops can see the flag.
    let scene = demo::overlapping_triangles(400, 3);
    let view = default_view(&scene, 96, 64);
    let o = stopped();
    assert_stopped("z-buffer", surface::zbuffer::render(&view, &o));
    assert_stopped("scanline", surface::scanline::render(&view, &o));
    assert_stopped("depth sort", surface::depth_sort::render(&view, &o));
    assert_stopped(
        "depth sort matrix",
        surface::depth_sort::render_matrix(&view, &o),
    );
    assert_stopped("bsp", surface::bsp::render(&view, &o));
    assert_stopped("warnock", surface::warnock::render(&view, &o));
    assert_stopped("octree", surface::octree::render(&view, &o));
    use surface::raycast::Acceleration;
    for acc in [
        Acceleration::BruteForce,
        Acceleration::Bounds(obscura::geom::BoundsKind::Aabb),
        Acceleration::Bvh,
        Acceleration::Grid,
    ] {
        assert_stopped(
            &format!("{acc:?}"),
            surface::raycast::render(&view, acc, &o),
        );
    }
    // The BSP's traversal, on a tree built without a deadline.
    let tree = BspTree::build(&scene, &BspOptions::default()).unwrap();
    assert_stopped("bsp traversal", tree.render(&view, &o));
    // The flag down, the same calls finish.
    let go = RenderOptions::default()
        .with_stop(Arc::new(AtomicBool::new(false)))
        .started();
    assert!(surface::warnock::render(&view, &go).is_ok());
    assert!(tree.render(&view, &go).is_ok());
}

#[test]
fn a_limit_passing_during_the_work_stops_it() {
    // Seconds of work each (5,000 large overlapping triangles at 640x480), stopped at
    // 20 ms: by the estimate or by the loops.
    let scene = demo::overlapping_triangles(5000, 9);
    let view = default_view(&scene, 640, 480);
    let options = RenderOptions::default().with_time_limit(Some(Duration::from_millis(20)));
    for algorithm in [
        Algorithm::DepthSort,
        Algorithm::Warnock,
        Algorithm::Octree,
        Algorithm::Raycast,
    ] {
        match render(algorithm, &view, &options) {
            Err(Error::TimeLimit { .. }) => {}
            other => panic!("{algorithm}: {:?}", other.map(|_| ())),
        }
    }
}
