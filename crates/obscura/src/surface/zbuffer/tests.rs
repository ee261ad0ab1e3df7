use glam::DVec3;

use super::*;
use crate::cull::backface::BackfaceMode;
use crate::raster::FillRule;
use crate::rng::SplitMix64;
use crate::scene::demo;
use crate::scene::random::{
    coplanar_grid, interpenetrating_quads, long_thin_triangles, orbit_cameras, random_triangles,
};
use crate::scene::{Camera, MeshBuilder, ObjectDesc, Scene, Viewport};
use crate::view::{PrepareOptions, PreparedView, prepare};

#[test]
fn seed_004_task_picture() {
    let scene = demo::seed_task();
    let vp = Viewport::new(32, 32).unwrap();
    let view = prepare(
        &scene,
        scene.camera().unwrap(),
        vp,
        &PrepareOptions::default(),
    )
    .unwrap();
    let opts = RenderOptions {
        fill_rule: FillRule::Inclusive,
        ..RenderOptions::default()
    };
    for (frame, _) in [
        render(&view, &opts).unwrap(),
        render_reference(&view, &opts).unwrap(),
    ] {
        let ones = frame.ids.iter().filter(|&&i| i == 0).count();
        let twos = frame.ids.iter().filter(|&&i| i == 1).count();
        assert_eq!((ones, twos), (308, 58));
    }
}

/// Convex planar n-gons (3 to 40 vertices) of all sizes in random planes.
fn random_ngons(n: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut b = MeshBuilder::new();
    for k in 0..n {
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let size = [0.002, 0.02, 0.2, 1.5][k % 4] * rng.range(0.5, 1.0);
        let u = DVec3::new(rng.range(-1., 1.), rng.range(-1., 1.), rng.range(-1., 1.));
        let v = DVec3::new(rng.range(-1., 1.), rng.range(-1., 1.), rng.range(-1., 1.));
        let (u, v) = (u.normalize(), u.cross(v).normalize());
        // Mostly 3 to 9 vertices; one in ten with 17 to 40 (beyond the fixed setups).
        let count = if k % 10 == 9 { 17 + k % 24 } else { 3 + k % 7 };
        let mut angles: Vec<f64> = (0..count)
            .map(|_| rng.range(0.0, std::f64::consts::TAU))
            .collect();
        angles.sort_by(f64::total_cmp);
        let base = b.vertex_count() as u32;
        for a in &angles {
            b.push_position(c + (u * a.cos() + v * a.sin()) * size);
        }
        let idx: Vec<u32> = (base..base + count as u32).collect();
        b.push_face(&idx, None).unwrap();
    }
    let mut s = Scene::new();
    s.add(ObjectDesc::new("ngons", b.finish().0).with_closed(false))
        .unwrap();
    s
}

fn scenes() -> Vec<(&'static str, Scene)> {
    vec![
        ("small triangles", random_triangles(400, 1, 1.0, 0.03)),
        ("sub-pixel triangles", random_triangles(600, 2, 1.0, 0.002)),
        ("mixed triangles", random_triangles(150, 3, 1.0, 0.4)),
        ("huge triangles", random_triangles(12, 4, 0.3, 3.0)),
        ("overlapping triangles", demo::overlapping_triangles(80, 12)),
        ("slivers", long_thin_triangles(60, 5, 1.0)),
        ("interpenetrating quads", interpenetrating_quads(20, 6, 1.0)),
        ("coplanar grid", coplanar_grid(12, 9, 7)),
        ("n-gons", random_ngons(200, 8)),
        ("default demo", demo::default_scene()),
        ("city", demo::city(6, 5, 9)),
    ]
}

/// Brute force: whether the two nearest polygons covering pixel `(i, j)` have depth
/// keys (their planes at the sample, in `f64`) within [`KEY_TIE`] of each other, the
/// only pixels where the fast path may keep another polygon than the reference.
fn near_key_tie(view: &PreparedView<'_>, fill: FillRule, i: u32, j: u32) -> bool {
    let vp = view.viewport();
    let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
    let mut keys: Vec<f64> = view
        .polygons()
        .filter(|p| {
            p.coverage(fill, vp.width, vp.height)
                .is_some_and(|c| c.covers(i, j))
        })
        .filter_map(|p| p.depth_plane().map(|d| d.at(px, py)))
        .collect();
    keys.sort_by(|a, b| b.total_cmp(a));
    keys.windows(2)
        .next()
        .is_some_and(|w| (w[0] - w[1]).abs() <= KEY_TIE * w[0].abs())
}

/// The fast path's tolerance (see the module doc): keys within two units of an `f32`.
const KEY_TIE: f64 = 2.0 * f32::EPSILON as f64;

/// Checks a fast frame against the reference's: ids equal but at near ties, depths
/// within [`KEY_TIE`] (relative; a key within a unit gives a depth within about a
/// unit, plus the conversion's rounding), the same polygons drawn and no more pixels
/// tested (occlusion culling skips some). Returns how many ids differ.
fn assert_close(
    a: &(Frame, ZBufferStats),
    b: &(Frame, ZBufferStats),
    view: &PreparedView<'_>,
    fill: FillRule,
    what: &str,
) -> usize {
    let diff = a.0.differences(&b.0);
    for &(i, j, id, ref_id) in &diff {
        assert!(
            near_key_tie(view, fill, i, j),
            "{what}: pixel ({i}, {j}) shows {id}, the reference {ref_id}, and it is no near tie"
        );
    }
    for (k, (&x, &y)) in a.0.depth.iter().zip(&b.0.depth).enumerate() {
        let close = x == y || (f64::from(x) - f64::from(y)).abs() <= KEY_TIE * f64::from(y).abs();
        assert!(close, "{what}: depth {x} at {k}, the reference {y}");
    }
    assert_eq!(a.1.polygons, b.1.polygons, "{what}: polygons");
    assert_eq!(
        a.1.polygons_drawn, b.1.polygons_drawn,
        "{what}: polygons_drawn"
    );
    assert!(
        a.1.pixels_tested <= b.1.pixels_tested,
        "{what}: pixels tested"
    );
    diff.len()
}

/// Checks that two fast frames are identical, bit for bit (kernels, threads and
/// schedules must not change the result).
fn assert_identical(a: &(Frame, ZBufferStats), b: &(Frame, ZBufferStats), what: &str) {
    assert_eq!(a.0.differences(&b.0), Vec::new(), "{what}: ids differ");
    let bits = |f: &Frame| f.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
    assert!(bits(&a.0) == bits(&b.0), "{what}: depths differ");
    // Everything but the phase times, which are measured.
    let counts = |s: &ZBufferStats| {
        let mut s = s.clone();
        let fast = s.fast.as_mut().expect("the fast path's figures");
        fast.setup_and_small_ms = 0.0;
        fast.binning_ms = 0.0;
        fast.tiles_ms = 0.0;
        s
    };
    assert_eq!(counts(&a.1), counts(&b.1), "{what}: stats differ");
}

/// The kernels this processor runs; each one it lacks is reported as skipped (a
/// failure with `OBSCURA_REQUIRE_SIMD=1`).
fn kernels() -> Vec<Kernel> {
    [Kernel::Portable, Kernel::Avx2, Kernel::Avx512]
        .into_iter()
        .filter(|k| {
            if !k.is_available() {
                crate::cpu::simd_test_skipped(&format!("{k:?}"), "the fast z-buffer's kernel");
            }
            k.is_available()
        })
        .collect()
}

#[test]
fn fast_path_equals_reference_on_random_scenes() {
    let (mut covered, mut differing) = (0, 0);
    for (k, (name, scene)) in scenes().into_iter().enumerate() {
        let mut cams = orbit_cameras(&scene, 2, 100 + k as u64);
        if let Some(c) = scene.camera() {
            cams.push(*c);
        }
        for (ci, cam) in cams.iter().enumerate() {
            // Odd sizes, and one tall enough for several bands.
            let (w, h) = if ci % 2 == 0 { (97, 61) } else { (70, 150) };
            let vp = Viewport::new(w, h).unwrap();
            let backface = if k % 2 == 0 {
                BackfaceMode::Closed
            } else {
                BackfaceMode::Off
            };
            let view = prepare(
                &scene,
                cam,
                vp,
                &PrepareOptions::default().with_backface(backface),
            )
            .unwrap();
            for fill in [FillRule::TopLeft, FillRule::Inclusive] {
                let opts = RenderOptions::default().with_fill_rule(fill);
                let reference = render_reference(&view, &opts).unwrap();
                covered += reference.0.covered_pixels();
                let first =
                    render_scheduled(&view, &opts, Kernel::Portable, 1, Schedule::Whole).unwrap();
                let what = format!("{name}, camera {ci}, {fill:?}");
                differing += assert_close(&first, &reference, &view, fill, &what);
                for kernel in kernels() {
                    for threads in [1, 2, 3] {
                        let fast = render_with(&view, &opts, kernel, threads).unwrap();
                        let what = format!("{what}, {kernel:?}, {threads} threads");
                        assert_identical(&fast, &first, &what);
                    }
                    for schedule in [Schedule::Whole, Schedule::Bands] {
                        let fast = render_scheduled(&view, &opts, kernel, 1, schedule).unwrap();
                        let what = format!("{what}, {kernel:?}, {schedule:?}");
                        assert_identical(&fast, &first, &what);
                    }
                }
            }
        }
    }
    assert!(
        covered > 100_000,
        "the scenes must show something: {covered}"
    );
    // Near ties are rare: the tolerance must not hide a systematic difference.
    assert!(differing * 10_000 <= covered, "{differing} of {covered}");
}

#[test]
fn long_spans_cross_powers_of_two_of_the_key() {
    // A floor seen at a grazing angle: along a row the depth key goes through several
    // binades, so spans are cut into several exact runs.
    let mut s = Scene::new();
    s.add(ObjectDesc::new(
        "floor",
        demo::grid_mesh(400.0, 400.0, 3, 3),
    ))
    .unwrap();
    let cam = Camera::perspective(
        DVec3::new(-150.0, 0.5, 0.0),
        DVec3::new(0.0, 0.0, 150.0),
        DVec3::Y,
        80.0,
        0.05,
        1000.0,
    );
    let vp = Viewport::new(640, 200).unwrap();
    let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
    let opts = RenderOptions::default();
    let reference = render_reference(&view, &opts).unwrap();
    assert!(reference.0.covered_pixels() > 30_000);
    let first = render_with(&view, &opts, Kernel::Portable, 1).unwrap();
    assert_close(&first, &reference, &view, opts.fill_rule, "portable");
    for kernel in kernels() {
        for threads in [1, 2] {
            let fast = render_with(&view, &opts, kernel, threads).unwrap();
            assert_identical(&fast, &first, &format!("{kernel:?}, {threads}"));
        }
    }
}

#[test]
fn tiny_images_match_the_reference() {
    // Rows shorter than a vector: every kernel must stay inside its row.
    let scene = random_triangles(300, 21, 1.0, 0.4);
    let cam = orbit_cameras(&scene, 1, 5)[0];
    let mut covered = 0;
    for (w, h) in [(1, 1), (3, 5), (7, 2), (9, 1), (4, 4), (13, 3)] {
        let vp = Viewport::new(w, h).unwrap();
        let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        let opts = RenderOptions::default();
        let reference = render_reference(&view, &opts).unwrap();
        covered += reference.0.covered_pixels();
        let first = render_with(&view, &opts, Kernel::Portable, 1).unwrap();
        assert_close(
            &first,
            &reference,
            &view,
            opts.fill_rule,
            &format!("{w}x{h}"),
        );
        for kernel in kernels() {
            for schedule in [Schedule::Whole, Schedule::Bands] {
                let fast = render_scheduled(&view, &opts, kernel, 1, schedule).unwrap();
                assert_identical(&fast, &first, &format!("{w}x{h} {kernel:?} {schedule:?}"));
            }
        }
    }
    assert!(
        covered > 20,
        "the triangles must reach the tiny images: {covered}"
    );
}

#[test]
fn empty_view_gives_background() {
    let s = Scene::new();
    let cam = Camera::perspective(DVec3::Z, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 10.0);
    let vp = Viewport::new(9, 7).unwrap();
    let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
    for threads in [1, 2] {
        let (f, st) =
            render_with(&view, &RenderOptions::default(), Kernel::detect(), threads).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
        assert!(f.depth.iter().all(|d| *d == f32::INFINITY));
        assert_eq!(st.pixels_tested, 0);
    }
}

#[test]
fn hidden_blocks_of_big_polygons_are_culled_without_changing_the_picture() {
    // Rows of big squares one behind the other, each a little smaller than the one in
    // front, nearest last in face order (so the far ones are not simply overdrawn):
    // the far squares' blocks behind the near ones are skipped; the picture is the
    // reference's.
    let mut b = MeshBuilder::new();
    for k in 0..6 {
        let (z, h) = (-2.0 - f64::from(5 - k), 0.9 - 0.1 * f64::from(k));
        let h = h * (2.0 - z) / 2.0;
        let base = b.vertex_count() as u32;
        for (x, y) in [(-h, -h), (h, -h), (h, h), (-h, h)] {
            b.push_position(DVec3::new(x, y, z));
        }
        b.push_face(&[base, base + 1, base + 2, base + 3], None)
            .unwrap();
    }
    let mut s = Scene::new();
    s.add(ObjectDesc::new("squares", b.finish().0).with_closed(false))
        .unwrap();
    let cam = Camera::perspective(
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::ZERO,
        DVec3::Y,
        60.0,
        0.1,
        100.0,
    );
    let vp = Viewport::new(300, 200).unwrap();
    let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
    let opts = RenderOptions::default();
    let reference = render_reference(&view, &opts).unwrap();
    assert!(reference.0.covered_pixels() > 20_000);
    for kernel in kernels() {
        let fast = render_with(&view, &opts, kernel, 1).unwrap();
        assert_close(
            &fast,
            &reference,
            &view,
            opts.fill_rule,
            &format!("{kernel:?}"),
        );
        let tested = |r: &(Frame, ZBufferStats)| r.1.pixels_tested as f64;
        assert!(
            tested(&fast) < 0.8 * tested(&reference),
            "{kernel:?}: {} of {} pixels tested",
            tested(&fast),
            tested(&reference)
        );
    }
}

#[test]
fn big_polygons_and_phase_times_are_reported() {
    // Polygons of every size, seen whole and across bands.
    let scene = demo::default_scene();
    let vp = Viewport::new(640, 400).unwrap();
    let cam = scene.default_camera(vp.aspect());
    let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let opts = RenderOptions::default();
    // Independently: the polygons whose sample box is wider or taller than BIG pixels.
    let big = view
        .polygons()
        .filter_map(|p| p.coverage(opts.fill_rule, vp.width, vp.height))
        .filter(|c| {
            let r = c.rect();
            r.x1 - r.x0 > BIG || r.y1 - r.y0 > BIG
        })
        .count();
    assert!(big >= 10 && big * 4 < view.polygon_count(), "{big} big");
    for threads in [1, 3] {
        for schedule in [Schedule::Whole, Schedule::Bands] {
            let started = std::time::Instant::now();
            let (_, stats) =
                render_scheduled(&view, &opts, Kernel::detect(), threads, schedule).unwrap();
            let wall_ms = started.elapsed().as_secs_f64() * 1e3;
            let fast = stats.fast.expect("the fast path's figures");
            assert_eq!(fast.big_polygons, big as u64, "{schedule:?}");
            // The phases are measured inside the call and summed over bands: each is a
            // real time, together more than nothing (hundreds of polygons were set up)
            // and at most the call's time on each of its threads.
            let mut total = 0.0;
            for (phase, ms) in [
                ("setup_and_small_ms", fast.setup_and_small_ms),
                ("binning_ms", fast.binning_ms),
                ("tiles_ms", fast.tiles_ms),
            ] {
                assert!(ms.is_finite() && ms >= 0.0, "{phase}: {ms}");
                total += ms;
            }
            // (Several threads run on the global pool, whatever its size.)
            #[cfg(feature = "parallel")]
            let workers = if threads > 1 {
                rayon::current_num_threads()
            } else {
                1
            };
            #[cfg(not(feature = "parallel"))]
            let workers = 1;
            assert!(
                total > 0.0 && total <= wall_ms * workers as f64,
                "{schedule:?}, {threads} threads: phases {total} ms, call {wall_ms} ms"
            );
        }
    }
}

/// A kept frame and buffers ([`render_into`]) give exactly the frame, depths and counts
/// of a fresh render, whatever they held: views of different scenes one after another
/// at sizes growing, shrinking and growing again (within the kept memory and past it),
/// with one and several threads. Between renders the kept frame is also filled with
/// poison (keys nearer than any polygon's, non-zero ids): a pixel read before it is
/// written would show it.
#[test]
fn a_kept_frame_gives_the_fresh_frame_after_any_view_and_size() {
    let scenes = [
        demo::default_scene(),
        demo::city(6, 5, 9),
        random_triangles(150, 3, 1.0, 0.4),
    ];
    let sizes: [(u32, u32); 6] = [
        (97, 61),
        (200, 150),
        (70, 150),
        (33, 17),
        (200, 149),
        (257, 190),
    ];
    for kernel in kernels() {
        for threads in [1, 2] {
            for poison in [false, true] {
                let mut frame = Frame {
                    width: 2,
                    height: 1,
                    ids: vec![7, 8],
                    depth: vec![1e30, 1e30],
                };
                let mut buffers = Buffers::new();
                for (k, &(w, h)) in sizes.iter().enumerate() {
                    let scene = &scenes[k % scenes.len()];
                    let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
                    let cam = orbit_cameras(scene, 1, 40 + k as u64)[0];
                    let view = prepare(scene, &cam, vp, &PrepareOptions::default()).unwrap();
                    let opts = RenderOptions::default();
                    let fresh = render_with(&view, &opts, kernel, threads).unwrap();
                    let stats =
                        render_into_with(&view, &opts, kernel, threads, &mut frame, &mut buffers)
                            .unwrap();
                    let what = format!("{kernel:?}, {threads} threads, poison {poison}, {w}x{h}");
                    assert_eq!((frame.width, frame.height), (w, h), "{what}");
                    assert!(fresh.0.covered_pixels() > 0, "{what}: an empty picture");
                    assert_identical(&(frame.clone(), stats), &fresh, &what);
                    if poison {
                        frame.depth.fill(1e30);
                        frame.ids.fill(3);
                    }
                }
            }
        }
    }
}
