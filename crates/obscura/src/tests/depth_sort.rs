//! Depth sort (Newell-Newell-Sancha) and its covering-matrix variant: splits exactly
//! when they must, pieces keep the area, frames equal the z-buffer's, statistics and
//! bad input.

use std::collections::HashMap;

use crate::cull::backface::BackfaceMode;
use crate::geom::polygon_area;
use crate::rng::SplitMix64;
use crate::scene::{Camera, ObjectDesc, Scene, Viewport, demo};
use crate::surface::depth_sort::{self, PaintOrder, paint_order, paint_order_matrix};
use crate::surface::stats::{AlgorithmStats, DepthSortMatrixStats, DepthSortStats};
use crate::surface::{Algorithm, RenderOptions, render};
use crate::{BACKGROUND, PrepareOptions, PreparedView, Stats, prepare};
use glam::DVec3;

use super::hsr_scenes;
use hsr_scenes::{assert_like_zbuffer, polygon_object, random_triangle_objects, view};

const VARIANTS: [Algorithm; 2] = [Algorithm::DepthSort, Algorithm::DepthSortMatrix];

fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64, z: f64) -> [DVec3; 4] {
    [
        DVec3::new(x0, y0, z),
        DVec3::new(x1, y0, z),
        DVec3::new(x1, y1, z),
        DVec3::new(x0, y1, z),
    ]
}

fn front_camera() -> Camera {
    Camera::perspective(
        DVec3::new(0., 0., 10.),
        DVec3::ZERO,
        DVec3::Y,
        30.,
        0.5,
        50.,
    )
}

/// Newell's own figures in the stats of a render.
fn newell(stats: &Stats) -> &DepthSortStats {
    stats.depth_sort().expect("depth sort's stats")
}

/// The covering matrix's own figures in the stats of a render.
fn matrix(stats: &Stats) -> &DepthSortMatrixStats {
    stats
        .depth_sort_matrix()
        .expect("the matrix depth sort's stats")
}

/// The figures both depth sorts report.
struct Shared {
    polygons: u64,
    comparisons: u64,
    decided_coplanar: u64,
    splits: u64,
    unresolved: u64,
    unsorted: u64,
}

/// The figures both depth sorts report, from the stats of either.
fn shared(stats: &Stats) -> Shared {
    match &stats.algorithm {
        AlgorithmStats::DepthSort(s) => Shared {
            polygons: s.polygons,
            comparisons: s.comparisons,
            decided_coplanar: s.decided_coplanar,
            splits: s.splits,
            unresolved: s.unresolved,
            unsorted: s.unsorted,
        },
        AlgorithmStats::DepthSortMatrix(s) => Shared {
            polygons: s.polygons,
            comparisons: s.comparisons,
            decided_coplanar: s.decided_coplanar,
            splits: s.splits,
            unresolved: s.unresolved,
            unsorted: s.unsorted,
        },
        other => panic!("not a depth sort's stats: {other:?}"),
    }
}

/// Renders with `algo` and asserts that at least `min_fraction` of the pixels have
/// the z-buffer's id, printing the differing pixels otherwise. Returns the stats.
fn check(view: &PreparedView<'_>, algo: Algorithm, min_fraction: f64, label: &str) -> Stats {
    let (frame, stats) = render(algo, view, &RenderOptions::default()).unwrap();
    assert_like_zbuffer(&frame, view, min_fraction, &format!("{label} {algo}"));
    stats
}

/// Every piece comes from a view polygon; per view polygon the pieces' eye-space
/// areas add up to its area.
fn assert_pieces_keep_area(view: &PreparedView<'_>, order: &PaintOrder) {
    let mut sum: HashMap<usize, f64> = HashMap::new();
    for p in &order.polygons {
        assert_eq!(view.polygon(p.source).face, p.face);
        let eye: Vec<DVec3> = p.vertices.iter().map(|v| v.eye).collect();
        *sum.entry(p.source).or_default() += polygon_area(&eye);
    }
    for (src, got) in sum {
        let area = polygon_area(&view.polygon(src).eye_points());
        assert!(
            (got - area).abs() <= 1e-9 * area,
            "polygon {src}: {got} vs {area}"
        );
    }
}

/// Three long triangles around the z axis, each lying over the next where they
/// cross (cyclic overlap). Stick `i` runs along the line at 120 i degrees, offset
/// `r = 0.5` from the axis; with `t` the coordinate along the stick and `l` across it,
/// its height is `a t + roll a sqrt(3) l`. Sticks `i` and `i + 1` cross at `t = -0.87`
/// on stick `i` and `t = +0.87` on stick `i + 1`, so stick `i + 1` is `1.73 a`
/// higher there.
///
/// With `roll = 1` each stick lies entirely above the plane of the previous one (the
/// height difference along stick `i + 1` is `a (1.73 + 3.46 l)`, positive for
/// `|l| < 0.5`): every pair has a plane-test order and only the cycle of the three
/// forbids painting them. With `roll = 0` the sticks also cross each other's planes
/// outside their overlap, so tests 3 and 4 fail both ways.
fn cyclic_triple(roll: f64) -> Scene {
    let mut s = Scene::new();
    let (r, half, w, a) = (0.5, 2.0, 0.45, 0.3);
    for i in 0..3 {
        let angle = f64::from(i) * std::f64::consts::TAU / 3.0;
        let d = DVec3::new(angle.cos(), angle.sin(), 0.0);
        let n = DVec3::new(-angle.sin(), angle.cos(), 0.0);
        let c = n * r;
        let at =
            |t: f64, l: f64| c + d * t + n * l + DVec3::Z * (a * t + roll * a * 3f64.sqrt() * l);
        s.add(polygon_object(
            &format!("stick {i}"),
            &[at(half, 0.0), at(-half, w), at(-half, -w)],
        ))
        .unwrap();
    }
    s
}

#[test]
fn cyclic_overlap_is_broken_by_a_split_and_renders_like_the_zbuffer() {
    let scene = cyclic_triple(1.0);
    for cam in [
        front_camera(),
        Camera::orthographic(DVec3::new(0., 0., 10.), DVec3::ZERO, DVec3::Y, 7., 0.5, 50.),
    ] {
        let v = view(&scene, &cam, 160, 160);
        // Each stick hides part of the next one: all three are seen, none whole.
        let (z, _) = render(Algorithm::ZBuffer, &v, &RenderOptions::default()).unwrap();
        for id in 0..3 {
            assert!(z.ids.contains(&id));
        }
        let s = check(&v, Algorithm::DepthSort, 1.0, "cyclic triple");
        assert!(newell(&s).cycles >= 1);
        assert!(shared(&s).splits >= 1);
        assert!(newell(&s).swaps >= 1);
        assert_eq!(shared(&s).unresolved, 0);
        let s = check(&v, Algorithm::DepthSortMatrix, 1.0, "cyclic triple");
        assert!(matrix(&s).cycles_broken >= 1);
        assert!(shared(&s).splits >= 1);
        assert!(matrix(&s).relations >= 3);
        assert_eq!(shared(&s).unresolved, 0);
        let ro = RenderOptions::default();
        for order in [paint_order(&v, &ro), paint_order_matrix(&v, &ro)] {
            assert!(order.polygons.len() > 3);
            assert_pieces_keep_area(&v, &order);
        }
    }
}

#[test]
fn cycle_of_sticks_crossing_each_others_planes_is_found_by_the_overlap_depths() {
    // Without the roll, tests 3 and 4 fail both ways for every pair; the depths over
    // the overlap order each pair, and the cycle is found and split as before.
    let scene = cyclic_triple(0.0);
    let v = view(&scene, &front_camera(), 160, 160);
    let s = check(&v, Algorithm::DepthSort, 1.0, "crossing sticks");
    assert!(newell(&s).swap_overlap_depth >= 1);
    assert!(newell(&s).cycles >= 1);
    assert!(shared(&s).splits >= 1);
    assert_eq!(shared(&s).unresolved, 0);
    let s = check(&v, Algorithm::DepthSortMatrix, 1.0, "crossing sticks");
    assert!(matrix(&s).decided_overlap_depth >= 3);
    assert!(matrix(&s).cycles_broken >= 1);
    assert_eq!(shared(&s).unresolved, 0);
    assert_pieces_keep_area(&v, &paint_order(&v, &RenderOptions::default()));
}

fn interpenetrating_quads() -> Scene {
    let mut s = Scene::new();
    // Two quads crossing along a line, like an X seen from above.
    s.add(polygon_object(
        "a",
        &[
            DVec3::new(-2., -1.3, -1.),
            DVec3::new(2., -1.3, 1.),
            DVec3::new(2., 1.1, 1.),
            DVec3::new(-2., 1.1, -1.),
        ],
    ))
    .unwrap();
    s.add(polygon_object(
        "b",
        &[
            DVec3::new(-1.7, -1., 0.9),
            DVec3::new(1.9, -1., -1.1),
            DVec3::new(1.9, 1.2, -1.1),
            DVec3::new(-1.7, 1.2, 0.9),
        ],
    ))
    .unwrap();
    s
}

#[test]
fn interpenetrating_faces_are_split_and_render_like_the_zbuffer() {
    let scene = interpenetrating_quads();
    for cam in [
        front_camera(),
        Camera::perspective(DVec3::new(3., 2., 6.), DVec3::ZERO, DVec3::Y, 40., 0.5, 50.),
        Camera::orthographic(DVec3::new(-2., 1., 8.), DVec3::ZERO, DVec3::Y, 4., 0.5, 50.),
    ] {
        let v = view(&scene, &cam, 120, 90);
        for algo in VARIANTS {
            let s = check(&v, algo, 1.0, "interpenetrating quads");
            assert!(shared(&s).splits >= 1, "{algo}");
            assert_eq!(shared(&s).unresolved, 0);
        }
        let ro = RenderOptions::default();
        for order in [paint_order(&v, &ro), paint_order_matrix(&v, &ro)] {
            assert!(order.polygons.len() >= 3);
            assert_pieces_keep_area(&v, &order);
        }
    }
}

#[test]
fn farthest_first_is_overturned_by_swaps_without_splits() {
    // Seed 002's example: the initial order P, Q, R (by farthest depth) is
    // overturned. P is steeply tilted (depth 3 to 20) and in front of Q and R (depth
    // 10 and 12) where they overlap, so Q and R must be painted before it.
    let mut s = Scene::new();
    s.add(polygon_object(
        "P",
        &[
            DVec3::new(-2., -1., -3.),
            DVec3::new(2., -1., -3.),
            DVec3::new(2., 1., -20.),
            DVec3::new(-2., 1., -20.),
        ],
    ))
    .unwrap();
    s.add(polygon_object(
        "Q",
        &rectangle(-4.0, -0.9, -1.0, -0.5, -10.),
    ))
    .unwrap();
    s.add(polygon_object("R", &rectangle(1.0, -1.0, 4.0, -0.6, -12.)))
        .unwrap();
    let cam = Camera::perspective(DVec3::ZERO, -DVec3::Z, DVec3::Y, 60., 0.5, 50.);
    let v = view(&s, &cam, 120, 90);
    let (z, _) = render(Algorithm::ZBuffer, &v, &RenderOptions::default()).unwrap();
    let count = |id| z.ids.iter().filter(|&&i| i == id).count();
    assert!(count(1) > 0 && count(2) > 0, "Q and R partly visible");
    let st = check(&v, Algorithm::DepthSort, 1.0, "swap example");
    assert_eq!(newell(&st).swaps, 2);
    assert_eq!(shared(&st).splits, 0);
    let order = paint_order(&v, &RenderOptions::default());
    let faces: Vec<u32> = order.polygons.iter().map(|p| p.face).collect();
    assert_eq!(faces.last(), Some(&0), "P is painted last: {faces:?}");
    let st = check(&v, Algorithm::DepthSortMatrix, 1.0, "swap example");
    assert_eq!(shared(&st).splits, 0);
    assert_eq!(matrix(&st).relations, 2);
}

/// Scenes that have a back-to-front order need no split.
#[test]
fn no_split_when_an_order_exists() {
    let mut rng = SplitMix64(4);
    // Non-overlapping: a row of squares.
    let mut apart = Scene::new();
    for i in 0..6 {
        let x = -3.0 + f64::from(i);
        apart
            .add(polygon_object(
                "sq",
                &rectangle(x, -0.4, x + 0.8, 0.4, rng.range(-1., 1.)),
            ))
            .unwrap();
    }
    // Stacked: overlapping cards at different depths, each tilted a little.
    let mut stacked = Scene::new();
    for i in 0..6 {
        let z = f64::from(i) * 0.5 - 1.5;
        let o = f64::from(i) * 0.2;
        stacked
            .add(polygon_object(
                "card",
                &[
                    DVec3::new(-1. + o, -1., z),
                    DVec3::new(1. + o, -1., z + 0.1),
                    DVec3::new(1. + o, 1. - o, z + 0.1),
                    DVec3::new(-1. + o, 1. - o, z),
                ],
            ))
            .unwrap();
    }
    // Touching: a floor grid of coplanar quads with boxes standing on it and
    // touching each other.
    let mut touching = Scene::new();
    touching
        .add(ObjectDesc::new("floor", demo::grid_mesh(8., 8., 6, 6)))
        .unwrap();
    for (x, h) in [(-1.0, 1.0), (0.0, 1.5), (1.0, 0.7)] {
        touching
            .add(ObjectDesc::new(
                "box",
                demo::box_mesh(DVec3::new(x - 0.5, 0., -0.5), DVec3::new(x + 0.5, h, 0.5)),
            ))
            .unwrap();
    }
    // Separate buildings: their perpendicular walls cross each other's planes, but
    // never each other.
    let city = demo::city(6, 6, 3);
    let city_camera = *city.camera().unwrap();
    let oblique = Camera::perspective(DVec3::new(3., 4., 7.), DVec3::ZERO, DVec3::Y, 45., 0.5, 50.);
    for (name, scene, cam) in [
        ("city", &city, city_camera),
        ("apart", &apart, front_camera()),
        ("stacked", &stacked, front_camera()),
        ("stacked, oblique", &stacked, oblique),
        ("touching", &touching, oblique),
    ] {
        let v = view(scene, &cam, 120, 90);
        for algo in VARIANTS {
            let s = check(&v, algo, 1.0, name);
            assert_eq!(shared(&s).splits, 0, "{name} {algo}");
            assert_eq!(shared(&s).unresolved, 0, "{name} {algo}");
        }
    }
    // A sphere with its back faces kept: the far half overlaps the near half, in an
    // order that the plane tests find without splitting.
    let sphere = {
        let mut s = Scene::new();
        s.add(ObjectDesc::new("sphere", demo::uv_sphere_mesh(1.0, 24, 12)))
            .unwrap();
        s
    };
    let vp = Viewport::new(96, 96).unwrap();
    let options = PrepareOptions::default().with_backface(BackfaceMode::Off);
    let v = prepare(&sphere, &oblique_sphere_camera(), vp, &options).unwrap();
    for algo in VARIANTS {
        let s = check(&v, algo, 1.0, "sphere without culling");
        assert_eq!(shared(&s).splits, 0, "{algo}");
    }
}

fn oblique_sphere_camera() -> Camera {
    Camera::perspective(
        DVec3::new(1., 2., 3.5),
        DVec3::ZERO,
        DVec3::Y,
        50.,
        0.5,
        50.,
    )
}

#[test]
fn coplanar_overlapping_faces_keep_the_lower_id() {
    // Three coplanar squares facing an orthographic camera (equal depth keys in the
    // z-buffer, so the tie rule decides) and one square in front of them.
    let mut s = Scene::new();
    for (i, x) in [0.6, 0.0, -0.6].into_iter().enumerate() {
        s.add(polygon_object(
            &format!("c{i}"),
            &rectangle(x - 1., -1., x + 1., 1., 0.),
        ))
        .unwrap();
    }
    s.add(polygon_object(
        "front",
        &rectangle(-0.3, -0.3, 0.3, 1.5, 0.5),
    ))
    .unwrap();
    let cam = Camera::orthographic(DVec3::new(0., 0., 5.), DVec3::ZERO, DVec3::Y, 4., 0.5, 20.);
    let v = view(&s, &cam, 100, 80);
    for algo in VARIANTS {
        let st = check(&v, algo, 1.0, "coplanar");
        assert!(shared(&st).decided_coplanar >= 1);
        assert_eq!(shared(&st).splits, 0);
    }
    let (frame, _) = render(Algorithm::DepthSort, &v, &RenderOptions::default()).unwrap();
    // The middle of the image is covered by all three squares: face 0 wins, except
    // under the front square (face 3).
    assert_eq!(frame.id(50, 50), 0);
    assert_eq!(frame.id(50, 30), 3);
}

#[test]
fn random_triangles_render_like_the_zbuffer() {
    let scene = random_triangle_objects(120, 17, 4.0, 1.5);
    for cam in [
        Camera::perspective(
            DVec3::new(2., 3., 14.),
            DVec3::ZERO,
            DVec3::Y,
            55.,
            0.5,
            60.,
        ),
        Camera::orthographic(
            DVec3::new(-8., 4., 9.),
            DVec3::ZERO,
            DVec3::Y,
            14.,
            0.5,
            60.,
        ),
    ] {
        let v = view(&scene, &cam, 128, 96);
        for algo in VARIANTS {
            let s = check(&v, algo, 0.999, "random triangles");
            assert!(shared(&s).splits > 0);
            assert_eq!(shared(&s).unresolved, 0);
        }
        assert_pieces_keep_area(&v, &paint_order(&v, &RenderOptions::default()));
    }
}

#[test]
fn demo_scene_and_near_plane_crossings_render_like_the_zbuffer() {
    let scene = demo::default_scene();
    let vp = Viewport::new(128, 96).unwrap();
    let cams = [
        scene.default_camera(vp.aspect()),
        // Low and close: the floor and the panels cross the near plane.
        Camera::perspective(
            DVec3::new(0.2, 0.5, 4.0),
            DVec3::new(0., 0.8, 0.),
            DVec3::Y,
            70.,
            0.5,
            40.,
        ),
        Camera::orthographic(
            DVec3::new(5., 6., 7.),
            DVec3::new(0., 1., 0.),
            DVec3::Y,
            9.,
            0.1,
            40.,
        ),
    ];
    for (i, cam) in cams.iter().enumerate() {
        let v = view(&scene, cam, 128, 96);
        for algo in VARIANTS {
            let s = check(&v, algo, 0.999, &format!("demo camera {i}"));
            assert_eq!(shared(&s).unresolved, 0);
        }
    }
}

#[test]
fn stats_count_every_comparison_once() {
    let scene = demo::default_scene();
    let vp = Viewport::new(96, 72).unwrap();
    let v = view(&scene, &scene.default_camera(vp.aspect()), 96, 72);
    let (_, s) = depth_sort::render(&v, &RenderOptions::default()).unwrap();
    assert_eq!(s.polygons, v.polygon_count() as u64);
    assert!(s.polygons_sorted <= s.polygons);
    // Each comparison is decided by one test, or finds a polygon P may hide, which
    // ends in a swap, a split or (never here) an unresolved conflict.
    let decided = s.decided_depth
        + s.decided_same_face
        + s.decided_test1_x
        + s.decided_test2_y
        + s.decided_test3
        + s.decided_test4
        + s.decided_test5
        + s.decided_coplanar
        + s.decided_overlap_depth;
    assert_eq!(s.comparisons, decided + s.swaps + s.splits + s.unresolved);
    assert!(s.decided_test1_x > 0 && s.decided_test3 + s.decided_test4 > 0);
    // Painted: at most the sorted polygons plus one per split (polygons whose box
    // holds a sample may still cover none).
    let paint = s.paint.expect("painting counts");
    assert!(paint.polygons_painted <= s.polygons_sorted + s.splits);
}

#[test]
fn empty_and_degenerate_input_gives_background() {
    let cam = front_camera();
    let empty = Scene::new();
    let mut one = Scene::new();
    one.add(polygon_object("q", &rectangle(-1., -1., 1., 1., 0.)))
        .unwrap();
    let away = Camera::perspective(
        DVec3::new(0., 0., 5.),
        DVec3::new(0., 0., 10.),
        DVec3::Y,
        50.,
        0.1,
        20.,
    );
    let inside = Camera::perspective(
        DVec3::new(0.1, 0.0, 0.2),
        DVec3::new(0., 0., -1.),
        DVec3::Y,
        60.,
        0.01,
        20.,
    );
    let cube = demo::cube();
    let demo_scene = demo::default_scene();
    for algo in VARIANTS {
        let v = view(&empty, &cam, 16, 12);
        let (f, s) = render(algo, &v, &RenderOptions::default()).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
        assert_eq!(shared(&s).polygons, 0);
        let v = view(&one, &cam, 16, 12);
        check(&v, algo, 1.0, "single face");
        let v = view(&demo_scene, &away, 16, 12);
        let (f, _) = render(algo, &v, &RenderOptions::default()).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
        let v = view(&cube, &inside, 16, 12);
        let (f, _) = render(algo, &v, &RenderOptions::default()).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
        // Faces seen edge-on or smaller than a pixel sample are not painted.
        let mut thin = Scene::new();
        thin.add(polygon_object(
            "edge-on",
            &[
                DVec3::new(-1., -1., 0.),
                DVec3::new(1., -1., 0.),
                DVec3::new(1., 1., 0.),
            ],
        ))
        .unwrap();
        let side =
            Camera::perspective(DVec3::new(5., 0., 0.), DVec3::ZERO, DVec3::Y, 50., 0.1, 20.);
        let v = view(&thin, &side, 16, 12);
        let (f, _) = render(algo, &v, &RenderOptions::default()).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
    }
}

/// Past its split budget, depth sort leaves conflicts unresolved; it then depth-tests
/// every polygon it paints, so the image is still the z-buffer's. Thirty mutually
/// interpenetrating quads need more splits than the budget allows (half the pixels
/// were wrong before the fallback).
#[test]
fn conflicts_left_past_the_split_budget_still_give_the_zbuffer_image() {
    let scene = crate::scene::random::interpenetrating_quads(30, 9, 1.0);
    let v = view(&scene, &scene.default_camera(1.0), 256, 256);
    for algorithm in [Algorithm::DepthSort, Algorithm::DepthSortMatrix] {
        let (frame, stats) = render(algorithm, &v, &RenderOptions::default()).unwrap();
        assert!(shared(&stats).unresolved > 0, "{algorithm:?}: {stats:?}");
        assert_like_zbuffer(&frame, &v, 0.999, &format!("{algorithm:?}"));
    }
}

/// Thousands of long overlapping slivers make the sort quadratic: past its comparison
/// budget the rest is painted depth-tested (this case ran for minutes before).
#[test]
fn thousands_of_slivers_stop_sorting_at_the_comparison_budget() {
    let scene = crate::scene::random::long_thin_triangles(3000, 9, 1.0);
    let v = view(&scene, &scene.default_camera(1.0), 256, 256);
    for algorithm in [Algorithm::DepthSort, Algorithm::DepthSortMatrix] {
        let (frame, stats) = render(algorithm, &v, &RenderOptions::default()).unwrap();
        let budget = 1024.0 * shared(&stats).polygons as f64 + f64::from(1u32 << 24);
        assert!(
            shared(&stats).comparisons as f64 <= budget * 1.01,
            "{algorithm:?}: {stats:?}"
        );
        assert!(shared(&stats).unsorted > 0, "{algorithm:?}: {stats:?}");
        assert_like_zbuffer(&frame, &v, 0.999, &format!("{algorithm:?}"));
    }
}

/// The plane-side tolerance follows the polygons' own coordinates: a vertex that no
/// polygon uses, far away (1e9 here), once widened it enough to call crossing planes
/// touching, and 24 pixels of this scene came out wrong without any split.
#[test]
fn a_far_unused_vertex_does_not_widen_the_tolerance() {
    use crate::scene::MeshBuilder;
    let mesh = |far: f64, tris: &[[[f64; 3]; 3]]| {
        let mut b = MeshBuilder::new();
        b.push_position(DVec3::new(far, 0.0, 0.0));
        for t in tris {
            let base = b.vertex_count() as u32;
            for p in t {
                b.push_position(DVec3::from_array(*p));
            }
            b.push_face(&[base, base + 1, base + 2], None).unwrap();
        }
        b.finish().0
    };
    let t = glam::DMat4::from_cols_array(&[
        0.9999727680099646,
        -0.005958167984862085,
        0.004354706965308926,
        0.0,
        0.005908561344505157,
        0.9999185045106547,
        0.011316944818022109,
        0.0,
        -0.004421780334635023,
        -0.011290906581851721,
        0.999926478940943,
        0.0,
        0.5978408310380372,
        -1.9271348237312762,
        -2.4404521366948857,
        1.0,
    ]);
    let cam = Camera::perspective(
        DVec3::new(
            -0.15734606135647375,
            std::f64::consts::FRAC_1_SQRT_2,
            0.6893781378718103,
        ),
        DVec3::new(
            0.42806842205476164,
            0.2870598657938035,
            0.030058842532047186,
        ),
        DVec3::Y,
        66.05354569594238,
        4.507261604723544e-9,
        45.07261604723544,
    );
    for far in [0.0, 1e9, 1e12] {
        let mut s = Scene::new();
        s.add(ObjectDesc::new(
            "a",
            mesh(
                far,
                &[
                    [
                        [0.6818815980376562, 0.0, 0.6520420265959805],
                        [
                            -0.006031828324683408,
                            0.2118806620657998,
                            0.8895359197906252,
                        ],
                        [0.6964961464947597, 0.4763930646649579, 0.8575022587174899],
                    ],
                    [
                        [0.5530589784280353, 0.9340636184735591, 0.7576291368980399],
                        [0.1201881216451719, 0.5155135606957197, -0.827744200399533],
                        [
                            -0.006031828324683408,
                            0.2118806620657998,
                            0.8895359197906252,
                        ],
                    ],
                ],
            ),
        ))
        .unwrap();
        s.add(
            ObjectDesc::new(
                "b",
                mesh(
                    far,
                    &[
                        [
                            [
                                -0.27770561296281704,
                                -0.6044884216040463,
                                -0.2792874077396015,
                            ],
                            [
                                0.5165426620957756,
                                0.12620966921859678,
                                -0.48315803505238875,
                            ],
                            [0.018722609415762648, 0.9538753772386557, -0.966066176770539],
                        ],
                        [
                            [
                                0.5291522816546834,
                                0.1276453372668913,
                                -0.014696199959240097,
                            ],
                            [
                                -0.27770561296281704,
                                -0.6044884216040463,
                                -0.2792874077396015,
                            ],
                            [0.018722609415762648, 0.9538753772386557, -0.966066176770539],
                        ],
                    ],
                ),
            )
            .with_transform(t),
        )
        .unwrap();
        let opts = PrepareOptions::default().with_backface(BackfaceMode::Off);
        let v = prepare(&s, &cam, Viewport::new(33, 25).unwrap(), &opts).unwrap();
        for algorithm in [Algorithm::DepthSort, Algorithm::DepthSortMatrix] {
            let (frame, _) = render(algorithm, &v, &RenderOptions::default()).unwrap();
            assert_like_zbuffer(
                &frame,
                &v,
                1.0,
                &format!("{algorithm:?}, unused vertex at {far}"),
            );
        }
    }
}

/// Plane tolerances come from the polygons compared, not from the whole view: a ground
/// 2e5 across set a tolerance of 1e-4 for two triangles 1e-4 across seen from 7e-4, so
/// each lay "in" the other's plane and the farther one was painted over the nearer
/// (depth sort, its matrix variant and BSP; found by differential fuzzing).
#[test]
fn a_huge_ground_does_not_widen_the_tolerance_of_small_faces() {
    let ground = [
        DVec3::new(-1e5, -0.5, -1e5),
        DVec3::new(1e5, -0.5, -1e5),
        DVec3::new(0.0, -0.5, 1e5),
    ];
    let a = [
        DVec3::new(-0.3562382818474941, 0.7444809339560193, 0.897653718014897),
        DVec3::new(-0.3561476433140566, 0.7444226130012443, 0.8976613215178887),
        DVec3::new(-0.3561594810059844, 0.7445570117547675, 0.8975611849039358),
    ];
    let b = [
        DVec3::new(-0.35611691114062516, 0.7444356971406771, 0.8976772801954467),
        DVec3::new(-0.356125341694795, 0.7444802894121665, 0.8975457750276025),
        DVec3::new(-0.35615530045644556, 0.7444125918762325, 0.8976907624236481),
    ];
    let mut scene = Scene::new();
    for (name, t) in [("ground", ground), ("a", a), ("b", b)] {
        scene.add(polygon_object(name, &t)).unwrap();
    }
    let cam = Camera::perspective(
        DVec3::new(-0.35554734204734917, 0.7447119824066012, 0.897097151136797),
        DVec3::new(-0.35581145409553216, 0.744716219131852, 0.8972393723594176),
        DVec3::Y,
        69.68723287276187,
        7.928314539492351e-7,
        400000.0,
    );
    let v = view(&scene, &cam, 256, 256);
    let (z, _) = render(Algorithm::ZBuffer, &v, &RenderOptions::default()).unwrap();
    let shown = |id: u32| z.ids.iter().filter(|&&i| i == id).count();
    assert!(
        shown(1) > 0 && shown(2) > 0,
        "both small triangles are seen"
    );
    for a in [
        Algorithm::DepthSort,
        Algorithm::DepthSortMatrix,
        Algorithm::Bsp,
    ] {
        let (f, _) = render(a, &v, &RenderOptions::default()).unwrap();
        assert_like_zbuffer(&f, &v, 1.0, a.name());
    }
}
