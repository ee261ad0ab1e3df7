//! Ray casting against the z-buffer and against itself.
//!
//! Rays come from the camera in world space, the z-buffer from the prepared view's
//! screen polygons: agreement on (nearly) every pixel checks the whole pipeline. The
//! four accelerations run the same exact test on the same triangles, so they must
//! agree with each other bit for bit.

use crate::accel::bvh::packet::{PACKET, PACKET_SIDE, PacketContext, PacketStack, RayPacket};
use crate::accel::bvh::traverse::{Kernel, TraceCounters, TraversalStack};
use crate::accel::bvh::{Bvh, BvhOptions, Slot, WIDTH};
use crate::accel::grid::{GridCounters, GridOptions, Mailbox, UniformGrid};
use crate::accel::triangles::{ClosestHit, PrimaryRays, SceneTriangles, WatertightRay};
use crate::cull::backface::BackfaceMode;
use crate::geom::{Aabb, BoundsKind, Kdop, KdopKind, Obb};
use crate::raster::FillRule;
use crate::scene::{Camera, MeshBuilder, ObjectDesc, demo};
use crate::surface::raycast::{self, Acceleration};
use crate::surface::{Algorithm, AlgorithmStats, RenderOptions, render};
use crate::{BACKGROUND, Frame, PrepareOptions, Scene, Stats, Viewport, prepare};
use glam::{DMat3, DMat4, DVec3};
use proptest::prelude::*;

const VARIANTS: [Algorithm; 4] = [
    Algorithm::Raycast,
    Algorithm::RaycastBounds,
    Algorithm::RaycastBvh,
    Algorithm::RaycastGrid,
];

/// The frame and stats of `algo` in the output of [`frames`] (picked by name, not by
/// position, so reordering the list cannot make a test compare the wrong frames).
fn frame_of(out: &[(Algorithm, Frame, Stats)], algo: Algorithm) -> (&Frame, &Stats) {
    let (_, f, s) = out
        .iter()
        .find(|(a, _, _)| *a == algo)
        .unwrap_or_else(|| panic!("{algo} was not rendered"));
    (f, s)
}

fn frames(
    scene: &Scene,
    cam: &Camera,
    w: u32,
    h: u32,
    backface: BackfaceMode,
    algos: &[Algorithm],
    options: &RenderOptions,
) -> Vec<(Algorithm, Frame, Stats)> {
    let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
    let view = prepare(
        scene,
        cam,
        vp,
        &PrepareOptions::default().with_backface(backface),
    )
    .unwrap();
    algos
        .iter()
        .map(|&a| {
            let (f, s) = render(a, &view, options).unwrap();
            (a, f, s)
        })
        .collect()
}

/// Asserts that `frame` equals the reference on at least `min_fraction` of the pixels,
/// printing the differing pixels otherwise; returns how many differ.
fn assert_agrees(name: &str, reference: &Frame, frame: &Frame, min_fraction: f64) -> usize {
    let diff = reference.differences(frame);
    let total = reference.ids.len();
    let agree = 1.0 - diff.len() as f64 / total as f64;
    if agree < min_fraction {
        let shown: Vec<String> = diff
            .iter()
            .take(40)
            .map(|(x, y, a, b)| format!("({x},{y}): z-buffer {a} vs {b}"))
            .collect();
        panic!(
            "{name}: {} of {total} pixels differ ({:.4}% agree):\n{}",
            diff.len(),
            agree * 100.0,
            shown.join("\n")
        );
    }
    // Where the ids agree the depths must too (to f32 rounding and the z-buffer's
    // interpolation of the depth key).
    for (k, (&a, &b)) in reference.depth.iter().zip(&frame.depth).enumerate() {
        if reference.ids[k] == frame.ids[k] && reference.ids[k] != BACKGROUND {
            assert!(
                (a - b).abs() <= 1e-4 * a.abs().max(1.0),
                "{name}: depth at pixel {k}: {a} vs {b}"
            );
        }
    }
    diff.len()
}

fn assert_identical(name: &str, a: &Frame, b: &Frame) {
    let diff = a.differences(b);
    assert!(
        diff.is_empty(),
        "{name}: {} pixels differ, first {:?}",
        diff.len(),
        &diff[..diff.len().min(20)]
    );
    let depth_diff = a
        .depth
        .iter()
        .zip(&b.depth)
        .position(|(x, y)| x.to_bits() != y.to_bits());
    assert!(
        depth_diff.is_none(),
        "{name}: depth differs at {depth_diff:?}"
    );
}

/// Every variant against the z-buffer (>= 99.9 %) and, when `identical`, against brute
/// force bit for bit.
fn check_scene(name: &str, scene: &Scene, cam: &Camera, w: u32, h: u32, backface: BackfaceMode) {
    let mut algos = vec![Algorithm::ZBuffer];
    algos.extend(VARIANTS);
    let out = frames(
        scene,
        cam,
        w,
        h,
        backface,
        &algos,
        &RenderOptions::default(),
    );
    let reference = frame_of(&out, Algorithm::ZBuffer).0;
    let brute = frame_of(&out, Algorithm::Raycast).0;
    assert!(
        reference.covered_pixels() > 0,
        "{name}: the scene shows nothing"
    );
    for (a, f, _) in out.iter().filter(|(a, _, _)| *a != Algorithm::ZBuffer) {
        let n = assert_agrees(&format!("{name} {a}"), reference, f, 0.999);
        eprintln!(
            "{name} {a}: {n} of {} pixels differ from the z-buffer",
            w * h
        );
        assert_identical(&format!("{name} {a} vs raycast"), brute, f);
    }
}

fn random_triangles(count: usize, seed: u64) -> Scene {
    let mut rng = crate::rng::SplitMix64(seed);
    let mut b = MeshBuilder::new();
    for _ in 0..count {
        let c = DVec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-2.0, 2.0),
            rng.range(-3.0, 3.0),
        );
        let first = b.vertex_count() as u32;
        for _ in 0..3 {
            b.push_position(
                c + DVec3::new(
                    rng.range(-0.8, 0.8),
                    rng.range(-0.8, 0.8),
                    rng.range(-0.8, 0.8),
                ),
            );
        }
        b.push_face(&[first, first + 1, first + 2], None).unwrap();
    }
    let mut s = Scene::new();
    s.add(ObjectDesc::new("soup", b.finish().0)).unwrap();
    s
}

fn generic_camera(eye: DVec3, target: DVec3) -> Camera {
    Camera::perspective(eye, target, DVec3::Y, 50.0, 0.1, 100.0)
}

#[test]
fn demo_default_matches_the_zbuffer() {
    let scene = demo::default_scene();
    let cam = scene.default_camera(160.0 / 120.0);
    check_scene("default", &scene, &cam, 160, 120, BackfaceMode::Closed);
    check_scene(
        "default, no culling",
        &scene,
        &cam,
        160,
        120,
        BackfaceMode::Off,
    );
}

#[test]
fn random_triangles_match_the_zbuffer() {
    let scene = random_triangles(400, 12);
    let cam = generic_camera(DVec3::new(4.3, 3.1, 8.7), DVec3::new(0.2, -0.1, 0.3));
    check_scene(
        "random triangles",
        &scene,
        &cam,
        150,
        110,
        BackfaceMode::Closed,
    );
    // Culling every face (the soup is open, so only `All` culls): about half remain.
    check_scene(
        "random triangles, all culled",
        &scene,
        &cam,
        150,
        110,
        BackfaceMode::All,
    );
}

#[test]
fn dense_sphere_matches_the_zbuffer() {
    let scene = demo::sphere(96, 48);
    let cam = *scene.camera().unwrap();
    check_scene("sphere", &scene, &cam, 160, 90, BackfaceMode::Closed);
}

#[test]
fn objects_crossing_the_near_plane_match_the_zbuffer() {
    // A floor running under and behind the eye, and a box the near plane cuts.
    let mut s = Scene::new();
    s.add(ObjectDesc::new("floor", demo::grid_mesh(40.0, 40.0, 8, 8)))
        .unwrap();
    s.add(
        ObjectDesc::new(
            "box",
            demo::box_mesh(DVec3::new(-0.7, 0.0, -0.6), DVec3::new(0.6, 1.3, 0.7)),
        )
        .with_transform(DMat4::from_rotation_y(0.3)),
    )
    .unwrap();
    let cam = Camera::perspective(
        DVec3::new(0.13, 0.61, 0.97),
        DVec3::new(-0.2, 0.4, -3.0),
        DVec3::Y,
        70.0,
        0.5,
        50.0,
    );
    // The near plane really cuts the box: some of its vertices are nearer than it.
    let (_, _, f) = cam.basis();
    let depths: Vec<f64> = s.objects()[1]
        .world_polygon(0)
        .iter()
        .chain(s.objects()[1].world_polygon(1).iter())
        .map(|p| (*p - cam.eye).dot(f))
        .collect();
    assert!(
        depths.iter().any(|&d| d < 0.5) && depths.iter().any(|&d| d > 0.5),
        "{depths:?}"
    );
    check_scene("near plane", &s, &cam, 140, 100, BackfaceMode::Closed);
}

#[test]
fn orthographic_camera_matches_the_zbuffer() {
    let scene = demo::default_scene();
    let cam = Camera::orthographic(
        DVec3::new(6.1, 5.3, 7.7),
        DVec3::new(0.1, 0.9, -0.2),
        DVec3::Y,
        9.0,
        0.5,
        40.0,
    );
    check_scene("orthographic", &scene, &cam, 150, 100, BackfaceMode::Closed);
}

#[test]
fn bounding_volumes_agree_and_save_tests() {
    let scene = demo::city(6, 6, 3);
    let cam = *scene.camera().unwrap();
    let vp = Viewport::new(96, 64).unwrap();
    let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let (brute, brute_stats) =
        raycast::render(&view, Acceleration::BruteForce, &RenderOptions::default()).unwrap();
    let mut hits_by_kind = Vec::new();
    for kind in BoundsKind::ALL {
        let (f, s) =
            raycast::render(&view, Acceleration::Bounds(kind), &RenderOptions::default()).unwrap();
        assert_identical(&format!("bounds {}", kind.name()), &brute, &f);
        let AlgorithmStats::RaycastBounds(s) = s else {
            panic!("not the bounds variant's stats: {s:?}");
        };
        let rays = u64::from(vp.width * vp.height);
        assert_eq!(s.ray.rays, rays);
        assert_eq!(s.objects, 37);
        assert_eq!(s.bound_tests, rays * 37);
        assert!(s.bound_hits < s.bound_tests, "{kind:?}");
        // Brute force's count is every front triangle for every ray.
        let brute_tests = brute_stats
            .ray()
            .expect("a ray caster's stats")
            .triangle_tests;
        assert_eq!(s.triangle_tests_brute_force, brute_tests);
        assert_eq!(
            s.triangle_tests_saved,
            s.triangle_tests_brute_force - s.ray.triangle_tests
        );
        assert!(
            s.saved_fraction > 0.5,
            "{kind:?} saved {}",
            s.saved_fraction
        );
        hits_by_kind.push((kind, s.bound_hits));
    }
    // The 26-DOP includes the AABB's three slabs: it is inside it, so it is met by no
    // more rays.
    let hits = |k: BoundsKind| hits_by_kind.iter().find(|h| h.0 == k).unwrap().1;
    assert!(hits(BoundsKind::Kdop) <= hits(BoundsKind::Aabb));
}

#[test]
fn grid_accepts_hits_only_inside_the_current_cell() {
    let scene = demo::default_scene();
    let tris = SceneTriangles::new(&scene);
    // A coarse grid makes triangles span many cells, where the rule matters.
    let grid = UniformGrid::build(&tris, &GridOptions::default().with_density(0.05));
    let vp = Viewport::new(80, 60).unwrap();
    let cam = scene.default_camera(vp.aspect());
    let rays = PrimaryRays::new(&cam, vp);
    let ignored = tris.ignored_polygons(&scene, &cam, BackfaceMode::Closed);
    let (mut checked, mut multi_cell) = (0, 0);
    let mut counters = GridCounters::default();
    let mut mailbox = Mailbox::new(&tris);
    for j in 0..vp.height {
        for i in 0..vp.width {
            let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
            let (o, d) = rays.ray(px, py);
            let ctx = rays
                .context(px, py, &ignored, tris.polygon_faces())
                .unwrap();
            let out = grid.closest_hit(&tris, &ctx, rays.far, &mut mailbox, &mut counters);
            let Some(cell) = out.cell else {
                assert!(!out.hit.is_hit());
                continue;
            };
            let (lo, hi) = grid.cell_box(cell);
            let p = o + d * out.hit.t;
            let tol = (hi - lo) * 1e-9;
            assert!(
                p.cmpge(lo - tol).all() && p.cmple(hi + tol).all(),
                "pixel {i},{j}: hit {p:?} outside cell {cell:?} {lo:?}..{hi:?}"
            );
            checked += 1;
            // Count hits on triangles that span several cells (where a hit in a later
            // cell could have been wrongly accepted earlier).
            let spans = {
                let [nx, ny, nz] = grid.resolution();
                let mut n = 0;
                for z in 0..nz {
                    for y in 0..ny {
                        for x in 0..nx {
                            n += usize::from(grid.cell_triangles([x, y, z]).iter().any(|&t| {
                                tris.polygon_faces()[tris.triangle_polygons()[t as usize] as usize]
                                    == out.hit.face
                            }));
                        }
                    }
                }
                n
            };
            multi_cell += usize::from(spans > 1);
        }
    }
    assert!(checked > 1000 && multi_cell > 100, "{checked} {multi_cell}");
    // Triangles spanning cells are met again: the mailbox answers instead of a new test.
    assert!(
        counters.mailbox_hits > counters.triangles / 10,
        "{counters:?}"
    );
    // The renderer checks the same for every pixel and reports it.
    let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let (_, stats) = render(Algorithm::RaycastGrid, &view, &RenderOptions::default()).unwrap();
    let grid = stats.raycast_grid().expect("the grid's stats");
    assert_eq!(grid.hits_outside_cell, 0);
    assert!(grid.cells_per_ray > 1.0);
}

#[test]
fn grid_without_the_cell_rule_would_be_wrong() {
    // Why the rule exists (seed 002): a long triangle A spans cells 0..3 along the ray
    // but is hit far away, in the last cell; a small triangle B in cell 2 is nearer.
    // Accepting A's hit when it is found in cell 0 would show A. The grid must show B.
    let mut b = MeshBuilder::new();
    // A: a long sliver slanted along -z, hit by the ray along -z near its far end.
    for p in [
        DVec3::new(-0.5, -0.5, -0.2),
        DVec3::new(0.5, -0.5, -0.2),
        DVec3::new(0.0, 0.5, -9.8),
    ] {
        b.push_position(p);
    }
    b.push_face(&[0, 1, 2], None).unwrap();
    // B: small, square to the ray, at z = -5.
    for p in [
        DVec3::new(-0.3, -0.3, -5.0),
        DVec3::new(0.3, -0.3, -5.0),
        DVec3::new(0.0, 0.3, -5.0),
    ] {
        b.push_position(p);
    }
    b.push_face(&[3, 4, 5], None).unwrap();
    let mut s = Scene::new();
    s.add(ObjectDesc::new("two", b.finish().0)).unwrap();
    let cam = Camera::perspective(
        DVec3::new(0.0, 0.25, 2.0),
        DVec3::new(0.0, 0.25, -1.0),
        DVec3::Y,
        10.0,
        0.1,
        50.0,
    );
    let tris = SceneTriangles::new(&s);
    let grid = UniformGrid::build(&tris, &GridOptions::default().with_density(0.01));
    let vp = Viewport::new(1, 1).unwrap();
    let rays = PrimaryRays::new(&cam, vp);
    let ignored = vec![false; tris.polygon_count()];
    let ctx = rays
        .context(0.5, 0.5, &ignored, tris.polygon_faces())
        .unwrap();
    let out = grid.closest_hit(
        &tris,
        &ctx,
        rays.far,
        &mut Mailbox::new(&tris),
        &mut GridCounters::default(),
    );
    assert_eq!(out.hit.face, 1);
    assert!((out.hit.t - 7.0).abs() < 1e-9, "{}", out.hit.t);
    // And A is really hit farther along the same ray, from a cell before B's.
    let a = ctx
        .ray
        .intersect_any(&tris.vertices()[0], 0.0, 100.0, &ctx.tie)
        .unwrap();
    assert!(a > 7.0);
}

#[test]
fn bvh_invariants_and_independent_structure_checks() {
    let scene = random_triangles(3000, 5);
    let tris = SceneTriangles::new(&scene);
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    bvh.check_invariants().unwrap();
    // Independently: walk the tree, collect every leaf's triangles, and compare them
    // with the input (by vertices, through the triangle order).
    let mut seen = vec![0u32; tris.len()];
    let nodes = bvh.nodes_with_depth();
    let mut leaves = 0;
    let mut root_box = Aabb::EMPTY;
    for &(i, depth) in &nodes {
        let n = bvh.node(i);
        for k in 0..WIDTH {
            let b = n.slot_box(k);
            if depth == 1 && n.slot(k) != Slot::Empty {
                root_box = root_box.union(b);
            }
            match n.slot(k) {
                Slot::Empty => assert_eq!(n.min[0][k], f32::INFINITY),
                Slot::Leaf { first, count } => {
                    leaves += 1;
                    assert!(count as usize <= BvhOptions::default().max_leaf_size);
                    for t in first..first + count {
                        let original = bvh.triangle_order()[t as usize] as usize;
                        seen[original] += 1;
                        assert_eq!(bvh.triangles()[t as usize], tris.vertices()[original]);
                        for v in tris.vertices()[original] {
                            assert!(b.contains(v), "vertex outside its leaf box");
                        }
                    }
                }
                Slot::Node(c) => {
                    // Every box of the child lies inside the box the parent keeps for it.
                    let child = bvh.node(c);
                    for kk in 0..WIDTH {
                        if child.slot(kk) != Slot::Empty {
                            let cb = child.slot_box(kk);
                            assert!(cb.min.cmpge(b.min).all() && cb.max.cmple(b.max).all());
                        }
                    }
                }
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s == 1),
        "a triangle is in zero or several leaves"
    );
    let s = bvh.stats();
    assert_eq!((s.nodes, s.leaves), (nodes.len(), leaves));
    assert_eq!(s.depth, nodes.iter().map(|n| n.1).max().unwrap());
    // Shallow: far from a list (8-wide: about log8 of the leaves, plus SAH imbalance).
    assert!(s.depth < 20, "depth {}", s.depth);
    // The root's boxes together are the scene's box (rounded outwards to f32).
    let exact = tris.bounds();
    assert!(root_box.contains(exact.min) && root_box.contains(exact.max));
    assert!((root_box.extent() - exact.extent()).abs().max_element() < 1e-5);
}

#[test]
fn bvh_is_reusable_across_views() {
    let scene = demo::default_scene();
    let tris = SceneTriangles::new(&scene);
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    let vp = Viewport::new(64, 48).unwrap();
    for eye in [
        DVec3::new(4.0, 3.0, 7.0),
        DVec3::new(-6.0, 2.0, 1.0),
        DVec3::new(0.5, 9.0, 0.5),
    ] {
        let cam = generic_camera(eye, DVec3::new(0.0, 1.0, 0.0));
        let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        let (a, _) = raycast::render_bvh(&view, &tris, &bvh, &RenderOptions::default()).unwrap();
        let (b, _) = render(Algorithm::Raycast, &view, &RenderOptions::default()).unwrap();
        assert_identical("reused bvh", &b, &a);
    }
}

#[test]
fn bvh_kernels_agree() {
    // The AVX2 build of the traversal (where the CPU has it) and the portable one run
    // the same operations: every hit must be the same, bit for bit.
    let scene = random_triangles(2000, 77);
    let tris = SceneTriangles::new(&scene);
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    let vp = Viewport::new(96, 72).unwrap();
    for cam in [
        generic_camera(DVec3::new(4.3, 3.1, 8.7), DVec3::new(0.2, -0.1, 0.3)),
        Camera::orthographic(
            DVec3::new(-5.0, 4.0, 6.0),
            DVec3::ZERO,
            DVec3::Y,
            7.0,
            0.1,
            40.0,
        ),
    ] {
        let rays = PrimaryRays::new(&cam, vp);
        let ignored = tris.ignored_polygons(&scene, &cam, BackfaceMode::All);
        let mut stack = TraversalStack::default();
        let mut hits = 0;
        for j in 0..vp.height {
            for i in 0..vp.width {
                let ctx = rays
                    .context(
                        f64::from(i) + 0.5,
                        f64::from(j) + 0.5,
                        &ignored,
                        tris.polygon_faces(),
                    )
                    .unwrap();
                let (mut ca, mut cb) = (TraceCounters::default(), TraceCounters::default());
                let a = bvh.closest_hit_with(Kernel::Auto, &ctx, rays.far, &mut stack, &mut ca);
                let b = bvh.closest_hit_with(Kernel::Portable, &ctx, rays.far, &mut stack, &mut cb);
                assert_eq!((a, ca), (b, cb), "pixel {i},{j}");
                hits += usize::from(a.is_hit());
            }
        }
        assert!(hits > 1000, "{hits}");
    }
}

/// Rays grouped into packets, traced with `kernel`, against the same rays traced one by
/// one (portable kernel): every lane must give the single ray's hit, bit for bit;
/// lanes without a ray give no hit. Returns how many rays hit something.
fn check_packets(
    bvh: &Bvh,
    ctx: &PacketContext<'_>,
    far: f64,
    groups: &[Vec<(DVec3, DVec3)>],
) -> usize {
    let mut single = TraversalStack::default();
    let mut stack = PacketStack::default();
    let mut hits = 0;
    // A kernel the processor lacks falls back to the next best: say so, once.
    if !crate::cpu::Avx512::is_available() {
        crate::cpu::simd_test_skipped("AVX-512", "packets traced with AVX-512 lanes");
    }
    if !crate::cpu::Avx2::is_available() {
        crate::cpu::simd_test_skipped("AVX2", "rays traced with the AVX2 build");
    }
    for (g, rays) in groups.iter().enumerate() {
        let expected: Vec<ClosestHit> = rays
            .iter()
            .map(|&(o, d)| match WatertightRay::new(o, d) {
                None => ClosestHit::new(far),
                Some(ray) => bvh.closest_hit_with(
                    Kernel::Portable,
                    &ctx.with_ray(ray),
                    far,
                    &mut single,
                    &mut TraceCounters::default(),
                ),
            })
            .collect();
        hits += expected.iter().filter(|h| h.is_hit()).count();
        let packet = RayPacket::new(rays, bvh.scale());
        for kernel in [Kernel::Auto, Kernel::Portable, Kernel::Avx2, Kernel::Avx512] {
            let out = bvh.closest_hits_with(
                kernel,
                &packet,
                ctx,
                far,
                &mut stack,
                &mut TraceCounters::default(),
            );
            for (r, hit) in out.iter().enumerate() {
                let want = expected.get(r).copied().unwrap_or(ClosestHit::new(far));
                assert_eq!(
                    (hit.t.to_bits(), hit.face),
                    (want.t.to_bits(), want.face),
                    "group {g} lane {r} {kernel:?}: {hit:?} vs {want:?}"
                );
            }
        }
    }
    hits
}

/// The rays of a camera grouped into blocks of 4x4 pixels (fewer at the edges), as the
/// renderer groups them.
fn pixel_blocks(rays: &PrimaryRays, vp: Viewport) -> Vec<Vec<(DVec3, DVec3)>> {
    let mut groups = Vec::new();
    for j0 in (0..vp.height).step_by(PACKET_SIDE) {
        for i0 in (0..vp.width).step_by(PACKET_SIDE) {
            let mut g = Vec::new();
            for j in j0..(j0 + PACKET_SIDE as u32).min(vp.height) {
                for i in i0..(i0 + PACKET_SIDE as u32).min(vp.width) {
                    g.push(rays.ray(f64::from(i) + 0.5, f64::from(j) + 0.5));
                }
            }
            groups.push(g);
        }
    }
    groups
}

#[test]
fn packets_equal_single_rays() {
    // Coherent packets, perspective: a soup, and the default scene with culled back
    // faces.
    for (scene, backface) in [
        (random_triangles(1500, 31), BackfaceMode::All),
        (demo::default_scene(), BackfaceMode::Closed),
    ] {
        let tris = SceneTriangles::new(&scene);
        let bvh = Bvh::build(&tris, &BvhOptions::default());
        let vp = Viewport::new(61, 43).unwrap();
        let cam = generic_camera(DVec3::new(4.3, 3.1, 8.7), DVec3::new(0.2, -0.1, 0.3));
        let rays = PrimaryRays::new(&cam, vp);
        let ignored = tris.ignored_polygons(&scene, &cam, backface);
        let ctx = PacketContext {
            ignored: &ignored,
            faces: tris.polygon_faces(),
            t_min: rays.near,
            tie: rays.tie_rule(),
        };
        let hits = check_packets(&bvh, &ctx, rays.far, &pixel_blocks(&rays, vp));
        assert!(hits > 800, "{hits}");
    }
}

#[test]
fn packets_on_shared_edges_and_vertices_equal_single_rays() {
    // A grid of 18 x 18 quads (fanned into triangles), wider than the view, seen from
    // above by an orthographic camera whose pixel centres fall exactly on the grid's
    // vertices, on the midpoints of its edges and on the quads' diagonals: every ray
    // is decided by the tie rule, each by exactly one triangle (no pixel left empty).
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("grid", demo::grid_mesh(9.0, 9.0, 18, 18))
            .with_transform(DMat4::from_translation(DVec3::new(0.125, 0.0, 0.125))),
    )
    .unwrap();
    let cam = Camera::orthographic(DVec3::Y * 5.0, DVec3::ZERO, DVec3::Z, 8.0, 0.5, 20.0);
    let vp = Viewport::new(32, 32).unwrap();
    let tris = SceneTriangles::new(&s);
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    let rays = PrimaryRays::new(&cam, vp);
    let ignored = tris.ignored_polygons(&s, &cam, BackfaceMode::Off);
    let ctx = PacketContext {
        ignored: &ignored,
        faces: tris.polygon_faces(),
        t_min: rays.near,
        tie: rays.tie_rule(),
    };
    let groups = pixel_blocks(&rays, vp);
    // The pixel centres really are on the grid's lines (from -4.375 by 0.5) or halfway.
    for (o, _) in groups.iter().flatten() {
        assert!(((o.x + 4.375) * 4.0).fract() == 0.0 && ((o.z + 4.375) * 4.0).fract() == 0.0);
    }
    let hits = check_packets(&bvh, &ctx, rays.far, &groups);
    assert_eq!(hits, 32 * 32);
}

#[test]
fn incoherent_packets_and_missing_rays_equal_single_rays() {
    // Random rays from random origins in random directions, sixteen to a packet: most
    // packets mix axis orders (traced ray by ray), some share one with different
    // origins; some lanes hold no ray (a zero or NaN direction) and short packets
    // leave lanes empty.
    let scene = random_triangles(800, 8);
    let tris = SceneTriangles::new(&scene);
    let bvh = Bvh::build(&tris, &BvhOptions::default());
    let cam = generic_camera(DVec3::new(0.0, 0.0, 9.0), DVec3::ZERO);
    let rays = PrimaryRays::new(&cam, Viewport::new(8, 8).unwrap());
    let ignored = vec![false; tris.polygon_count()];
    let ctx = PacketContext {
        ignored: &ignored,
        faces: tris.polygon_faces(),
        t_min: 0.0,
        tie: rays.tie_rule(),
    };
    let mut rng = crate::rng::SplitMix64(21);
    let mut v = |scale: f64| {
        DVec3::new(
            rng.range(-scale, scale),
            rng.range(-scale, scale),
            rng.range(-scale, scale),
        )
    };
    let mut groups: Vec<Vec<(DVec3, DVec3)>> = Vec::new();
    for g in 0..120 {
        let n = if g % 7 == 0 { 1 + g % PACKET } else { PACKET };
        let mut rays: Vec<(DVec3, DVec3)> = (0..n)
            .map(|_| {
                let o = v(6.0);
                // Towards the soup, and in a narrow cone for every third packet so
                // that packets sharing an axis order are common.
                let d = if g % 3 == 0 {
                    DVec3::new(0.0, 0.0, -1.0) + v(0.3)
                } else {
                    v(2.0) - o
                };
                (o, d)
            })
            .collect();
        if g % 5 == 0 {
            rays[0].1 = DVec3::ZERO;
            let last = rays.len() - 1;
            rays[last].1.x = f64::NAN;
        }
        groups.push(rays);
    }
    let hits = check_packets(&bvh, &ctx, 100.0, &groups);
    assert!(hits > 300, "{hits}");
    assert!(
        groups
            .iter()
            .filter(|g| RayPacket::new(g, bvh.scale()).is_coherent())
            .count()
            > 30
    );
}

#[test]
fn empty_scenes_inside_cameras_and_culled_views_give_background() {
    let empty = Scene::new();
    let cam = generic_camera(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO);
    for (a, f, _) in frames(
        &empty,
        &cam,
        16,
        12,
        BackfaceMode::Closed,
        &VARIANTS,
        &RenderOptions::default(),
    ) {
        assert_eq!(f.covered_pixels(), 0, "{a}");
        assert!(f.depth.iter().all(|d| d.is_infinite()), "{a}");
    }
    // Inside a closed box every face is seen from behind: culled, nothing is seen;
    // without culling the box's inside fills the image.
    let mut s = Scene::new();
    s.add(ObjectDesc::new(
        "room",
        demo::box_mesh(DVec3::splat(-2.0), DVec3::splat(2.0)),
    ))
    .unwrap();
    assert!(s.objects()[0].closed);
    let inside = generic_camera(DVec3::new(0.3, 0.2, 0.1), DVec3::new(1.0, 0.5, -3.0));
    let mut algos = vec![Algorithm::ZBuffer];
    algos.extend(VARIANTS);
    for (a, f, _) in frames(
        &s,
        &inside,
        32,
        24,
        BackfaceMode::Closed,
        &algos,
        &RenderOptions::default(),
    ) {
        assert_eq!(f.covered_pixels(), 0, "{a}");
    }
    for (a, f, _) in frames(
        &s,
        &inside,
        32,
        24,
        BackfaceMode::Off,
        &algos,
        &RenderOptions::default(),
    ) {
        assert_eq!(f.covered_pixels(), 32 * 24, "{a}");
    }
    // Looking away from everything.
    let away = generic_camera(DVec3::new(0.0, 0.0, 30.0), DVec3::new(0.0, 0.0, 40.0));
    let scene = demo::default_scene();
    for (a, f, _) in frames(
        &scene,
        &away,
        16,
        12,
        BackfaceMode::Closed,
        &VARIANTS,
        &RenderOptions::default(),
    ) {
        assert_eq!(f.covered_pixels(), 0, "{a}");
    }
}

#[test]
fn depth_is_the_eye_space_distance() {
    // A quad square to the view axis at distance 4 from the eye: every covered pixel
    // has depth 4, in both projections.
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("wall", demo::grid_mesh(20.0, 20.0, 3, 3)).with_transform(
            DMat4::from_translation(DVec3::new(0.0, 0.0, -4.0))
                * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2),
        ),
    )
    .unwrap();
    for cam in [
        Camera::perspective(DVec3::ZERO, -DVec3::Z, DVec3::Y, 60.0, 0.1, 10.0),
        Camera::orthographic(DVec3::ZERO, -DVec3::Z, DVec3::Y, 5.0, 0.1, 10.0),
    ] {
        for (a, f, _) in frames(
            &s,
            &cam,
            20,
            16,
            BackfaceMode::Off,
            &VARIANTS,
            &RenderOptions::default(),
        ) {
            assert_eq!(f.covered_pixels(), 320, "{a}");
            assert!(f.depth.iter().all(|&d| (d - 4.0).abs() < 1e-5), "{a}");
        }
    }
}

/// A ground plane far larger than the objects in view (a sphere on a plain up to 10^7
/// wide, seen from 4 units): the BVH's box test allows for rounding relative to each
/// distance, not to the scene's extent, so the ground costs the traversal about what
/// any other one big polygon does. With a margin from the largest coordinate of the
/// scene, every box near the camera grew by 2^-17 of 10^7 (76 units) and each ray
/// visited most of the sphere's tree.
#[test]
fn a_distant_ground_does_not_slow_the_bvh() {
    let sphere = || {
        ObjectDesc::new("sphere", demo::uv_sphere_mesh(1.0, 96, 48))
            .with_closed(true)
            .with_convex(true)
    };
    let mut alone = Scene::new();
    alone.add(sphere()).unwrap();
    let cam = Camera::perspective(
        DVec3::new(0.0, 1.0, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        0.1,
        100.0,
    );
    let visits = |scene: &Scene| {
        let out = frames(
            scene,
            &cam,
            96,
            72,
            BackfaceMode::Closed,
            &[Algorithm::ZBuffer, Algorithm::RaycastBvh],
            &RenderOptions::default(),
        );
        let (bvh, stats) = frame_of(&out, Algorithm::RaycastBvh);
        assert_agrees(
            "raycast-bvh",
            frame_of(&out, Algorithm::ZBuffer).0,
            bvh,
            1.0,
        );
        stats
            .raycast_bvh()
            .expect("the BVH's stats")
            .node_visits_per_ray
    };
    let base = visits(&alone);
    for width in [1e3, 1e5, 1e7] {
        let mut grounded = Scene::new();
        grounded.add(sphere()).unwrap();
        grounded
            .add(
                ObjectDesc::new("ground", demo::grid_mesh(width, width, 1, 1))
                    .with_transform(DMat4::from_translation(DVec3::new(0.0, -1.5, 0.0))),
            )
            .unwrap();
        let with_ground = visits(&grounded);
        assert!(
            with_ground < 1.5 * base + 2.0,
            "ground {width}: {with_ground} node visits per ray, {base} without it"
        );
    }
}

#[test]
fn stats_report_the_figures_of_each_variant() {
    let scene = demo::default_scene();
    let cam = scene.default_camera(4.0 / 3.0);
    let out = frames(
        &scene,
        &cam,
        40,
        30,
        BackfaceMode::Closed,
        &VARIANTS,
        &RenderOptions::default(),
    );
    // Every figure of every variant, by its field (a missing one does not compile;
    // the CLI's tests check the keys).
    for (a, _, s) in &out {
        let ray = s
            .algorithm
            .ray()
            .unwrap_or_else(|| panic!("{a}: no ray stats"));
        assert_eq!(ray.rays, 1200, "{a}");
        assert!(ray.hits > 0 && ray.hits <= ray.rays, "{a}");
        assert!(ray.triangle_tests > 0, "{a}");
        assert!(ray.trace_ms >= 0.0 && ray.mrays_per_s >= 0.0, "{a}");
        assert!(s.time_ms >= ray.trace_ms, "{a}");
    }
    let bvh = frame_of(&out, Algorithm::RaycastBvh)
        .1
        .raycast_bvh()
        .unwrap();
    assert!(bvh.build_ms >= 0.0 && bvh.nodes >= 1 && bvh.leaves >= 1 && bvh.depth >= 1);
    assert!(bvh.triangle_tests_per_ray > 0.0 && bvh.node_visits_per_ray > 0.0);
    let grid = frame_of(&out, Algorithm::RaycastGrid)
        .1
        .raycast_grid()
        .unwrap();
    assert!(grid.cells >= 1 && grid.refs_per_cell > 0.0 && grid.cells_per_ray > 0.0);
    assert!(grid.build_ms >= 0.0);
    // The accelerations test far fewer triangles than brute force.
    let tests = |a: Algorithm| frame_of(&out, a).1.algorithm.ray().unwrap().triangle_tests as f64;
    let (brute, bvh, grid) = (
        tests(Algorithm::Raycast),
        tests(Algorithm::RaycastBvh),
        tests(Algorithm::RaycastGrid),
    );
    assert!(
        bvh * 20.0 < brute && grid * 5.0 < brute,
        "{brute} {bvh} {grid}"
    );
}

fn points_strategy() -> impl Strategy<Value = Vec<(f64, f64, f64)>> {
    prop::collection::vec((-50.0..50.0f64, -5.0..5.0f64, -0.5..0.5f64), 1..60)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn obb_and_kdop_contain_every_point(raw in points_strategy(), angle in 0.0..6.3f64) {
        let r = DMat3::from_euler(glam::EulerRot::YXZ, angle, angle * 0.7, -angle * 0.3);
        let pts: Vec<DVec3> = raw.iter().map(|&(x, y, z)| r * DVec3::new(x, y, z)).collect();
        let obb = Obb::from_points(&pts).unwrap();
        prop_assert!(pts.iter().all(|&p| obb.contains(p)));
        // Rounding can make a ray through a point exactly on a face miss it: the ray
        // caster grows the volumes by a margin relative to the coordinates, as here.
        let margin = 1e-9 * 100.0;
        let aabb = Aabb::from_points(pts.iter().copied());
        let e = aabb.extent();
        prop_assert!(obb.volume() <= e.x * e.y * e.z * (1.0 + 1e-12) + 1e-12);
        for kind in [KdopKind::K14, KdopKind::K18, KdopKind::K26] {
            let k = Kdop::from_points(&pts, kind).unwrap();
            prop_assert!(pts.iter().all(|&p| k.contains(p)));
            // Every ray through a point of the set meets both volumes, at that point.
            for &p in pts.iter().take(5) {
                let o = p + DVec3::new(3.0, 7.0, -11.0);
                let d = p - o;
                let (t0, t1) = k.expanded(margin).ray_interval(o, d).unwrap();
                prop_assert!(t0 <= 1.0 + 1e-9 && t1 >= 1.0 - 1e-9);
                let (t0, t1) = obb.expanded(margin).ray_interval(o, d).unwrap();
                prop_assert!(t0 <= 1.0 + 1e-9 && t1 >= 1.0 - 1e-9);
            }
        }
    }
}

/// Triangles in the plane z = 0 (`flat`) or in a box, inside `[-1, 1]^3`, scaled by
/// `size` and moved to `centre`; one triangle across the box for `count` 1.
fn scaled_triangles(count: usize, seed: u64, flat: bool, size: f64, centre: DVec3) -> Scene {
    let mut rng = crate::rng::SplitMix64(seed);
    let mut b = MeshBuilder::new();
    if count == 1 {
        // One triangle across the whole box.
        for p in [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, if flat { 0.0 } else { 0.5 }),
        ] {
            b.push_position(centre + p * size);
        }
        b.push_face(&[0, 1, 2], None).unwrap();
    }
    for _ in 0..if count == 1 { 0 } else { count } {
        let c = DVec3::new(
            rng.range(-0.8, 0.8),
            rng.range(-0.8, 0.8),
            if flat { 0.0 } else { rng.range(-0.8, 0.8) },
        );
        let first = b.vertex_count() as u32;
        for _ in 0..3 {
            let p = c + DVec3::new(
                rng.range(-0.2, 0.2),
                rng.range(-0.2, 0.2),
                if flat { 0.0 } else { rng.range(-0.2, 0.2) },
            );
            b.push_position(centre + p * size);
        }
        b.push_face(&[first, first + 1, first + 2], None).unwrap();
    }
    let mut s = Scene::new();
    s.add(ObjectDesc::new("soup", b.finish().0)).unwrap();
    s
}

/// Scenes tiny against their distance from the eye or from the origin, flat or not:
/// the grid's cells are then far finer than the rounding of the rays' parameters, and
/// it must still give brute force's frame bit for bit (it lost up to half the pixels of
/// a flat triangle 1e-10 wide seen from 5 away, or 1 wide seen from 1e11).
#[test]
fn grid_equals_brute_force_on_scenes_tiny_against_their_distance() {
    let vp = Viewport::new(24, 24).unwrap();
    let ro = RenderOptions::default();
    let mut failures = Vec::new();
    let mut far_rays = 0;
    let mut case = 0u64;
    let mut refused = 0u64;
    for &(size, dist, off) in &[
        (1e-10, 5.0, 0.0),
        (1e-12, 5.0, 0.0),
        (1e-14, 5.0, 0.0),
        (1e-9, 5.0, 3.0),
        (1e-12, 5.0, 1.0),
        (1.0, 1e9, 0.0),
        (1.0, 1e11, 0.0),
        (1.0, 1e12, 0.0),
        (1.0, 1e14, 0.0),
        (1e-3, 1e8, 7.0),
        (1e3, 1e15, 1e3),
    ] {
        for flat in [true, false] {
            for count in [1usize, 40] {
                for dir in [DVec3::Z, DVec3::new(0.3, -0.5, 1.0).normalize()] {
                    case += 1;
                    let centre = DVec3::new(off, -off * 0.5, off * 0.25);
                    let scene = scaled_triangles(count, case, flat, size, centre);
                    let eye = centre + dir * dist;
                    let half = (1.25 * size / dist).atan().to_degrees() * 2.0;
                    for (kind, cam) in [
                        (
                            "persp",
                            Camera::perspective(
                                eye,
                                centre,
                                DVec3::Y,
                                half,
                                dist * 0.5,
                                dist * 2.0,
                            ),
                        ),
                        (
                            "ortho",
                            Camera::orthographic(
                                eye,
                                centre,
                                DVec3::Y,
                                2.5 * size,
                                dist * 0.5,
                                dist * 2.0,
                            ),
                        ),
                    ] {
                        let view = match prepare(&scene, &cam, vp, &PrepareOptions::default()) {
                            Ok(view) => view,
                            Err(e) => {
                                // Pixels narrower than directions from the eye
                                // (`Camera::MIN_PIXEL_ANGLE`) or coordinates
                                // (`Camera::validate_window`) resolve: refused.
                                let e = e.to_string();
                                let why = match kind {
                                    "persp" => "field of view",
                                    _ => "orthographic height",
                                };
                                assert!(e.contains(why), "{e}");
                                refused += 1;
                                continue;
                            }
                        };
                        let (brute, _) = render(Algorithm::Raycast, &view, &ro).unwrap();
                        let (grid, _) = render(Algorithm::RaycastGrid, &view, &ro).unwrap();
                        // A grid built without knowing the view: rays too far for its
                        // cells are traced against every triangle.
                        let tris = SceneTriangles::new(&scene);
                        let prebuilt = UniformGrid::build(&tris, &GridOptions::default());
                        let (other, stats) =
                            raycast::render_grid(&view, &tris, &prebuilt, &ro).unwrap();
                        far_rays += stats.far_rays;
                        let name = format!(
                            "size {size:e} dist {dist:e} off {off} flat {flat} n {count} dir {dir:?} {kind}"
                        );
                        for (which, f) in [("grid", &grid), ("prebuilt grid", &other)] {
                            let d = brute.differences(f).len();
                            if d > 0 {
                                failures.push(format!(
                                    "{name} {which}: {d} pixels differ (brute force covers {}, grid {})",
                                    brute.covered_pixels(),
                                    f.covered_pixels()
                                ));
                            }
                        }
                        assert!(brute.covered_pixels() > 0, "{name}");
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(far_rays > 0);
    // Most views are drawn: only the narrowest are refused.
    assert!(
        refused * 4 < case * 2,
        "{refused} of {} views refused",
        case * 2
    );
}

/// The ray casters follow `RenderOptions::fill_rule`: with the inclusive rule, a pixel
/// centre exactly on a triangle's right edge is covered, as the z-buffer covers it (they
/// always applied the top-left rule). Window 2 x 2 over [0, 2]^2; the triangle's right
/// edge is x = 0.5, through the centres of the left column.
#[test]
fn ray_casters_follow_the_fill_rule_on_edges() {
    let mut scene = Scene::new();
    let mut b = MeshBuilder::new();
    for (x, y) in [(-1.0, -1.0), (0.5, -1.0), (0.5, 3.0)] {
        b.push_position(DVec3::new(x, y, 0.0));
    }
    b.push_face(&[0, 1, 2], None).unwrap();
    scene
        .add(ObjectDesc::new("t", b.finish().0).with_closed(false))
        .unwrap();
    let camera = Camera::orthographic(
        DVec3::new(1.0, 1.0, 5.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::Y,
        2.0,
        1.0,
        10.0,
    );
    let view = prepare(
        &scene,
        &camera,
        Viewport::new(2, 2).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap();
    for (fill, covered) in [(FillRule::TopLeft, 0), (FillRule::Inclusive, 2)] {
        let opts = RenderOptions::default().with_fill_rule(fill);
        let (z, _) = render(Algorithm::ZBuffer, &view, &opts).unwrap();
        assert_eq!(z.covered_pixels(), covered, "{fill:?}");
        for a in VARIANTS {
            let (f, _) = render(a, &view, &opts).unwrap();
            assert_eq!(f.ids, z.ids, "{} with {fill:?}", a.name());
        }
    }
}

/// A triangle seen edge-on (its plane holds the eye) covers no sample, also when every
/// edge is inclusive: the rays in its plane meet it only by rounding, with some of the
/// three edge functions exactly zero. The inclusive rule once accepted them and drew a
/// line of 13 pixels where the z-buffer drew nothing (differential fuzzer, seed
/// 51010345; every coordinate dyadic, so the eye lies exactly in the plane).
#[test]
fn an_edge_on_triangle_covers_nothing_with_inclusive_edges() {
    let mut scene = Scene::new();
    let mut b = MeshBuilder::new();
    for p in [
        DVec3::new(10.625, 9.375, 0.0),
        DVec3::new(10.625, 9.5, -2.5),
        DVec3::new(10.5, 9.5, -3.75),
    ] {
        b.push_position(p);
    }
    b.push_face(&[0, 1, 2], None).unwrap();
    scene
        .add(ObjectDesc::new("edge-on", b.finish().0).with_closed(false))
        .unwrap();
    let camera = Camera::perspective(
        DVec3::new(12.5, 9.375, 18.75),
        DVec3::new(12.5, 9.375, 0.0),
        DVec3::Y,
        90.0,
        2.34375,
        45.5,
    );
    let view = prepare(
        &scene,
        &camera,
        Viewport::new(200, 150).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap();
    for fill in [FillRule::TopLeft, FillRule::Inclusive] {
        let opts = RenderOptions::default().with_fill_rule(fill);
        let (z, _) = render(Algorithm::ZBuffer, &view, &opts).unwrap();
        assert_eq!(z.covered_pixels(), 0, "{fill:?}");
        for a in VARIANTS {
            let (f, _) = render(a, &view, &opts).unwrap();
            assert_eq!(f.covered_pixels(), 0, "{} with {fill:?}", a.name());
        }
    }
}
