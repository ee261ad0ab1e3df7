//! BSP tree: the order invariants of the traversal checked node by node from many
//! viewpoints, frames equal to the z-buffer's, one tree serving many views, options,
//! statistics and bad input.

use crate::accel::bsp::{BspOptions, BspTraversal, BspTree, Viewpoint};
use crate::geom::polygon_area;
use crate::rng::SplitMix64;
use crate::scene::{Camera, MeshBuilder, ObjectDesc, Scene, Viewport, demo};
use crate::surface::{RenderOptions, bsp};
use crate::{BACKGROUND, PreparedView};
use glam::{DMat4, DVec3};

use super::hsr_scenes;
use hsr_scenes::{assert_like_zbuffer, polygon_object, random_triangle_objects, view};

fn options(traversal: BspTraversal) -> RenderOptions {
    RenderOptions::default().with_bsp(BspOptions::default().with_traversal(traversal))
}

fn both_traversals(view: &PreparedView<'_>, min_fraction: f64, label: &str) {
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let (frame, _) = bsp::render(view, &options(t)).unwrap();
        assert_like_zbuffer(&frame, view, min_fraction, &format!("{label} {}", t.name()));
    }
}

/// For every node: from a viewpoint on its front side, every fragment of the back
/// subtree comes before the node's fragments, which come before the front subtree's;
/// the reverse from behind. Nodes whose plane holds the viewpoint are not constrained.
fn check_order_invariants(tree: &BspTree, vp: Viewpoint) -> usize {
    let order = tree.paint_order(vp, BspTraversal::BackToFront);
    let total: usize = (0..tree.node_count() as u32)
        .map(|n| tree.node_fragments(n).len())
        .sum();
    assert_eq!(order.len(), total, "every fragment is painted once");
    let mut pos = vec![usize::MAX; order.iter().max().map_or(0, |&m| m as usize + 1)];
    for (i, &f) in order.iter().enumerate() {
        assert_eq!(pos[f as usize], usize::MAX, "fragment {f} painted twice");
        pos[f as usize] = i;
    }
    // Subtree position ranges, children first (children have larger indices).
    let n = tree.node_count();
    let mut range = vec![(usize::MAX, 0usize); n];
    let mut own = vec![(usize::MAX, 0usize); n];
    let merge = |a: (usize, usize), b: (usize, usize)| (a.0.min(b.0), a.1.max(b.1));
    for i in (0..n).rev() {
        let node = tree.node(i as u32);
        for &f in tree.node_fragments(i as u32) {
            own[i] = merge(own[i], (pos[f as usize], pos[f as usize]));
        }
        let mut r = own[i];
        for c in [node.front, node.back].into_iter().flatten() {
            assert!(c as usize > i);
            r = merge(r, range[c as usize]);
        }
        range[i] = r;
    }
    let mut checked = 0;
    // Node planes are in the tree's frame.
    let local = vp.relative_to(tree.origin());
    for (i, own) in own.iter().enumerate() {
        let node = tree.node(i as u32);
        let side = local.side(&node.plane);
        if side == 0.0 {
            continue;
        }
        let (first, last) = if side > 0.0 {
            (node.back, node.front)
        } else {
            (node.front, node.back)
        };
        let empty = (usize::MAX, 0usize);
        let groups = [
            first.map_or(empty, |c| range[c as usize]),
            *own,
            last.map_or(empty, |c| range[c as usize]),
        ];
        for a in 0..3 {
            for b in a + 1..3 {
                let (ga, gb) = (groups[a], groups[b]);
                if ga != empty && gb != empty {
                    assert!(
                        ga.1 < gb.0,
                        "node {i}: group {a} (far subtree, node, near subtree) not before group {b}"
                    );
                }
            }
        }
        checked += 1;
    }
    checked
}

#[test]
fn traversal_order_holds_from_both_sides_of_every_node() {
    for (scene, views) in [
        (random_triangle_objects(300, 11, 5.0, 1.5), 6),
        (demo::default_scene(), 4),
    ] {
        let tree = BspTree::build(&scene, &BspOptions::default()).unwrap();
        assert!(tree.stats().splits > 0);
        let scale = scene.bounds().extent().max_element();
        let mut rng = SplitMix64(99);
        let mut viewpoints = Vec::new();
        for _ in 0..views {
            let p = scene.bounds().center()
                + DVec3::new(rng.range(-1., 1.), rng.range(-1., 1.), rng.range(-1., 1.)) * scale;
            viewpoints.push(Viewpoint::Point(p));
            viewpoints.push(Viewpoint::Direction(p - scene.bounds().center()));
        }
        // Just in front of and just behind node planes, at a point of the node's
        // polygon (or of the plane, for an axis-aligned node without polygons). The
        // planes are in the tree's frame, world minus its origin.
        let origin = tree.origin();
        let step = (tree.node_count() / 40).max(1);
        for i in (0..tree.node_count()).step_by(step) {
            let node = tree.node(i as u32);
            let c = match tree.node_fragments(i as u32).first() {
                Some(&f) => {
                    let pts = tree.fragment_points(f);
                    pts.iter().sum::<DVec3>() / pts.len() as f64 - origin
                }
                None => {
                    let o = scene.bounds().center() - origin;
                    o - node.plane.normal * node.plane.signed_distance(o)
                }
            };
            let delta = node.plane.normal * (1e-6 * scale);
            for p in [c + delta, c - delta] {
                let vp = Viewpoint::Point(p + origin);
                assert!(vp.relative_to(origin).side(&node.plane) != 0.0);
                viewpoints.push(vp);
            }
        }
        for vp in viewpoints {
            let checked = check_order_invariants(&tree, vp);
            assert!(checked > 0);
            // Front to back is exactly the reverse.
            let mut b2f = tree.paint_order(vp, BspTraversal::BackToFront);
            b2f.reverse();
            assert_eq!(b2f, tree.paint_order(vp, BspTraversal::FrontToBack));
        }
    }
}

#[test]
fn fragments_lie_on_their_side_of_every_ancestor_and_keep_the_area() {
    let scene = random_triangle_objects(200, 5, 5.0, 1.5);
    let tree = BspTree::build(&scene, &BspOptions::default()).unwrap();
    // Walk down, remembering the planes above with the side taken.
    let mut stack = vec![(0u32, Vec::<(usize, bool)>::new())];
    let mut area_by_face = std::collections::HashMap::<u32, f64>::new();
    while let Some((n, above)) = stack.pop() {
        let node = tree.node(n);
        for &f in tree.node_fragments(n) {
            let pts = tree.fragment_points(f);
            *area_by_face.entry(tree.fragment(f).face).or_default() += polygon_area(&pts);
            for &(a, front) in &above {
                let anc = tree.node(a as u32);
                for p in &pts {
                    let d = anc.plane.signed_distance(*p - tree.origin());
                    assert!(if front { d >= -anc.eps } else { d <= anc.eps }, "{d}");
                }
            }
        }
        for (c, front) in [(node.front, true), (node.back, false)] {
            if let Some(c) = c {
                let mut a = above.clone();
                a.push((n as usize, front));
                stack.push((c, a));
            }
        }
    }
    for (k, o) in scene.objects().iter().enumerate() {
        let area = polygon_area(&o.world_polygon(0));
        let got = area_by_face[&o.first_face];
        assert!(
            (got - area).abs() <= 1e-9 * area.max(1.0),
            "object {k}: {got} vs {area}"
        );
    }
    let s = tree.stats();
    assert_eq!(s.fragments, s.input_polygons - s.degenerate + s.splits);
}

#[test]
fn frames_equal_the_zbuffer_on_the_demo_scene() {
    let scene = demo::default_scene();
    let vp = Viewport::new(160, 120).unwrap();
    let v = view(&scene, &scene.default_camera(vp.aspect()), 160, 120);
    both_traversals(&v, 0.999, "demo:default");
}

/// The demo scene shrunk and moved far from the world's origin gives the frame it gives
/// at the origin: the tree works relative to the scene's centre. (Its tolerance used to
/// be 1e-9 of the largest world coordinate: 1 cm at x = 1e7, so the faces of 2 cm
/// solids all counted as lying on every plane, and a sphere was painted in front of
/// the box that hides it.) Also a single triangle 1e-6 across at 2.8e7, which was not
/// drawn at all.
#[test]
fn small_scenes_far_from_the_world_origin() {
    let base = demo::default_scene();
    let vp = Viewport::new(96, 64).unwrap();
    let cam = base.default_camera(vp.aspect());
    for (offset, size) in [
        (DVec3::new(1e7, 0.0, 0.0), 1e-2),
        (DVec3::new(1e5, -1e5, 1e5), 1e-4),
        (DVec3::new(-1.0, -2.8e7, -9.0), 1e-3),
    ] {
        let t = DMat4::from_translation(offset) * DMat4::from_scale(DVec3::splat(size));
        let mut scene = Scene::new();
        for o in base.objects() {
            scene
                .add(ObjectDesc {
                    name: o.name.clone(),
                    mesh: o.mesh.clone(),
                    transform: t * o.transform,
                    color: o.color,
                    closed: Some(o.closed),
                    convex: Some(o.convex),
                })
                .unwrap();
        }
        let mut c = cam;
        (c.eye, c.target) = (t.transform_point3(cam.eye), t.transform_point3(cam.target));
        (c.near, c.far) = (cam.near * size, cam.far * size);
        let v = view(&scene, &c, 96, 64);
        let label = format!("demo scene x {size} at {offset}");
        let (frame, _) = bsp::render(&v, &options(BspTraversal::FrontToBack)).unwrap();
        assert!(
            frame.ids.iter().filter(|&&id| id != BACKGROUND).count() > 96 * 64 / 4,
            "{label}: the view shows the scene"
        );
        both_traversals(&v, 0.999, &label);
    }
    // One triangle about 1e-6 across, seen from 2.5e-6 away through a 0.01 degree lens.
    let pts = [
        DVec3::new(-1.0881345882763804, -28445167.884648286, -9.053658067727412),
        DVec3::new(-1.0881349587793903, -28445167.884647336, -9.053658071095338),
        DVec3::new(-1.088134970934279, -28445167.884647254, -9.053658061236582),
    ];
    let mut scene = Scene::new();
    scene.add(polygon_object("far triangle", &pts)).unwrap();
    let (eye, target) = (
        DVec3::new(-1.0881370947148006, -28445167.88464797, -9.053658388443672),
        DVec3::new(-1.0881346323800591, -28445167.884647682, -9.053658042449834),
    );
    let d = eye.distance(target);
    let c = Camera::perspective(eye, target, DVec3::Z, 0.01, d / 100.0, d * 100.0);
    let v = view(&scene, &c, 64, 48);
    let (z, _) = crate::surface::zbuffer::render(&v, &RenderOptions::default()).unwrap();
    assert!(
        z.ids.iter().all(|&id| id == 0),
        "the triangle fills the view"
    );
    both_traversals(&v, 1.0, "far triangle");
}

#[test]
fn one_tree_serves_many_views_including_orthographic_and_near_plane_crossings() {
    let scene = demo::default_scene();
    let tree = BspTree::build(&scene, &BspOptions::default()).unwrap();
    let cams = [
        Camera::perspective(
            DVec3::new(6., 4., 8.),
            DVec3::new(0., 1., 0.),
            DVec3::Y,
            45.,
            0.5,
            40.,
        ),
        Camera::perspective(
            DVec3::new(-7., 2., -3.),
            DVec3::new(0., 1., 0.),
            DVec3::Y,
            60.,
            0.1,
            40.,
        ),
        // Low over the floor, close to the panels: the floor and panels cross the near plane.
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
        Camera::orthographic(
            DVec3::new(0., 10., 0.01),
            DVec3::ZERO,
            DVec3::Y,
            12.,
            0.1,
            40.,
        ),
    ];
    for (i, cam) in cams.iter().enumerate() {
        let v = view(&scene, cam, 96, 72);
        for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
            let (frame, _) = tree.render(&v, &options(t)).unwrap();
            assert_like_zbuffer(&frame, &v, 0.999, &format!("camera {i} {}", t.name()));
        }
    }
}

#[test]
fn frames_equal_the_zbuffer_on_random_triangles() {
    let scene = random_triangle_objects(150, 3, 5.0, 1.5);
    let cam = Camera::perspective(
        DVec3::new(3., 4., 16.),
        DVec3::ZERO,
        DVec3::Y,
        55.,
        0.5,
        60.,
    );
    let v = view(&scene, &cam, 128, 96);
    both_traversals(&v, 0.999, "random triangles");
    let cam = Camera::orthographic(
        DVec3::new(-9., 5., 9.),
        DVec3::ZERO,
        DVec3::Y,
        16.,
        0.5,
        60.,
    );
    let v = view(&scene, &cam, 128, 96);
    both_traversals(&v, 0.999, "random triangles, orthographic");
}

#[test]
fn interpenetrating_quads_and_coplanar_ties() {
    let mut s = Scene::new();
    // Two quads crossing along x = 0.3.
    s.add(polygon_object(
        "a",
        &[
            DVec3::new(-1., -1., -1.),
            DVec3::new(1.6, -1., 1.),
            DVec3::new(1.6, 1., 1.),
            DVec3::new(-1., 1., -1.),
        ],
    ))
    .unwrap();
    s.add(polygon_object(
        "b",
        &[
            DVec3::new(-1., -0.8, 1.),
            DVec3::new(1.6, -0.8, -1.),
            DVec3::new(1.6, 0.8, -1.),
            DVec3::new(-1., 0.8, 1.),
        ],
    ))
    .unwrap();
    // Two coplanar overlapping squares facing the camera: the lower id (2) must win.
    for (name, x) in [("c", -3.0), ("d", -2.5)] {
        s.add(polygon_object(
            name,
            &[
                DVec3::new(x, -0.5, 0.),
                DVec3::new(x + 1., -0.5, 0.),
                DVec3::new(x + 1., 0.5, 0.),
                DVec3::new(x, 0.5, 0.),
            ],
        ))
        .unwrap();
    }
    let cam = Camera::orthographic(DVec3::new(0., 0., 5.), DVec3::ZERO, DVec3::Y, 3.0, 0.1, 20.);
    let v = view(&s, &cam, 120, 60);
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let (frame, stats) = bsp::render(&v, &options(t)).unwrap();
        assert!(stats.bsp_splits >= 1);
        assert_like_zbuffer(&frame, &v, 1.0, t.name());
        // Both squares and both crossing quads are visible.
        for id in 0..4 {
            assert!(frame.ids.contains(&id), "{id} not seen");
        }
    }
}

#[test]
fn front_to_back_stops_once_the_image_is_full() {
    // A wall filling the view in front of 100 random triangles.
    let mut scene = random_triangle_objects(100, 8, 5.0, 1.5);
    scene
        .add(polygon_object(
            "wall",
            &[
                DVec3::new(-50., -50., 7.),
                DVec3::new(50., -50., 7.),
                DVec3::new(50., 50., 7.),
                DVec3::new(-50., 50., 7.),
            ],
        ))
        .unwrap();
    let cam = Camera::perspective(
        DVec3::new(0., 0., 12.),
        DVec3::ZERO,
        DVec3::Y,
        50.,
        0.5,
        60.,
    );
    let v = view(&scene, &cam, 64, 48);
    let (f2b, s) = bsp::render(&v, &options(BspTraversal::FrontToBack)).unwrap();
    assert!(s.early_exit);
    assert!(s.visited_fraction < 1.0);
    assert!(f2b.ids.iter().all(|&id| id == 100));
    let (_, s) = bsp::render(&v, &options(BspTraversal::BackToFront)).unwrap();
    assert!(!s.early_exit);
    assert_eq!(s.visited_fraction, 1.0);
}

#[test]
fn split_weight_trades_splits_for_balance() {
    let scene = random_triangle_objects(400, 21, 5.0, 1.5);
    let few = BspOptions::default()
        .with_weights(100.0, 0.0)
        .with_score_sample(0);
    let balanced = BspOptions::default()
        .with_weights(0.0, 1.0)
        .with_score_sample(0);
    let a = *BspTree::build(&scene, &few).unwrap().stats();
    let b = *BspTree::build(&scene, &balanced).unwrap().stats();
    assert!(a.splits < b.splits, "{} vs {}", a.splits, b.splits);
    assert!(a.depth > b.depth, "{} vs {}", a.depth, b.depth);
    // More candidates can only find better-scoring planes at the root.
    let one = BspOptions::default().with_candidates(1);
    let c = BspTree::build(&scene, &one).unwrap();
    assert_eq!(c.stats().input_polygons, 400);
    // Same seed, same tree; another seed, another tree.
    let d1 = BspTree::build(&scene, &BspOptions::default()).unwrap();
    let d2 = BspTree::build(&scene, &BspOptions::default()).unwrap();
    assert_eq!(d1.stats().splits, d2.stats().splits);
    assert_eq!(d1.stats().nodes, d2.stats().nodes);
}

#[test]
fn stats_are_consistent() {
    let scene = demo::default_scene();
    let vp = Viewport::new(80, 60).unwrap();
    let v = view(&scene, &scene.default_camera(vp.aspect()), 80, 60);
    let started = std::time::Instant::now();
    let (_, s) = bsp::render(&v, &options(BspTraversal::BackToFront)).unwrap();
    let wall_ms = started.elapsed().as_secs_f64() * 1e3;
    assert_eq!(s.bsp_fragments, scene.polygon_count() as u64 + s.bsp_splits);
    assert!(
        s.bsp_depth as f64 >= (s.bsp_nodes as f64).log2().floor() && s.bsp_depth <= s.bsp_nodes
    );
    assert_eq!(s.fragments_visited, s.bsp_fragments);
    assert!(s.fragments_painted <= s.fragments_visited - s.fragments_culled);
    // About half the faces of the closed solids are back faces.
    assert!(s.fragments_culled as f64 > 0.3 * s.bsp_fragments as f64);
    // The build time is a measurement inside the render: more than nothing (the tree
    // has nodes) and no more than the whole call took.
    assert!(s.bsp_nodes > 0);
    assert!(
        s.build_ms > 0.0 && s.build_ms <= wall_ms,
        "build_ms {} outside 0..{wall_ms}",
        s.build_ms
    );
}

#[test]
fn bad_and_degenerate_input_gives_background() {
    let cam = Camera::perspective(DVec3::new(0., 0., 5.), DVec3::ZERO, DVec3::Y, 50., 0.1, 20.);
    // Empty scene.
    let empty = Scene::new();
    let v = view(&empty, &cam, 16, 12);
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let (f, _) = bsp::render(&v, &options(t)).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
    }
    // A single face.
    let mut one = Scene::new();
    one.add(polygon_object(
        "q",
        &[
            DVec3::new(-1., -1., 0.),
            DVec3::new(1., -1., 0.),
            DVec3::new(1., 1., 0.),
            DVec3::new(-1., 1., 0.),
        ],
    ))
    .unwrap();
    let v = view(&one, &cam, 16, 12);
    let (f, s) = bsp::render(&v, &RenderOptions::default()).unwrap();
    assert_eq!(s.bsp_nodes, 1);
    assert_like_zbuffer(&f, &v, 1.0, "single face");
    // Everything behind the camera.
    let away = Camera::perspective(
        DVec3::new(0., 0., 5.),
        DVec3::new(0., 0., 10.),
        DVec3::Y,
        50.,
        0.1,
        20.,
    );
    let scene = demo::default_scene();
    let v = view(&scene, &away, 16, 12);
    let (f, _) = bsp::render(&v, &RenderOptions::default()).unwrap();
    assert!(f.ids.iter().all(|&i| i == BACKGROUND));
    // Inside a closed cube: every face is a back face.
    let cube = demo::cube();
    let inside = Camera::perspective(
        DVec3::new(0.1, 0.0, 0.2),
        DVec3::new(0., 0., -1.),
        DVec3::Y,
        60.,
        0.01,
        20.,
    );
    let v = view(&cube, &inside, 16, 12);
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let (f, _) = bsp::render(&v, &options(t)).unwrap();
        assert!(f.ids.iter().all(|&i| i == BACKGROUND));
    }
    // A mirrored object keeps its front faces.
    let mut m = Scene::new();
    m.add(
        ObjectDesc::new(
            "mirrored",
            demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
        )
        .with_transform(DMat4::from_scale(DVec3::new(-1., 1., 1.))),
    )
    .unwrap();
    let v = view(
        &m,
        &Camera::perspective(
            DVec3::new(2., 1.5, 3.),
            DVec3::ZERO,
            DVec3::Y,
            50.,
            0.1,
            20.,
        ),
        40,
        30,
    );
    let (f, _) = bsp::render(&v, &RenderOptions::default()).unwrap();
    assert!(f.covered_pixels() > 100);
    assert_like_zbuffer(&f, &v, 1.0, "mirrored");
    // A tree of another scene is refused.
    let tree = BspTree::build(&one, &BspOptions::default()).unwrap();
    let v = view(&scene, &cam, 16, 12);
    assert!(bsp::render_with_tree(&tree, &v, &RenderOptions::default()).is_err());
}

#[test]
fn axis_planes_keep_the_tree_of_a_convex_object_shallow() {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("sphere", demo::uv_sphere_mesh(1.0, 48, 24)))
        .unwrap();
    // 48 x 22 planar quads (two coplanar triangles each) and 2 x 48 pole triangles.
    let planes = 48 * 22 + 2 * 48;
    assert_eq!(s.face_count(), 48 * 22 * 2 + 2 * 48);
    // Every face's plane has the whole sphere behind it: the autopartition is a chain
    // of one plane per node, without a split.
    let chain = BspTree::build(&s, &BspOptions::default().with_axis_planes(false)).unwrap();
    assert_eq!(chain.stats().splits, 0);
    assert_eq!(chain.stats().depth, planes);
    let n = planes;
    let tree = BspTree::build(&s, &BspOptions::default()).unwrap();
    assert!(tree.stats().depth < n / 10, "depth {}", tree.stats().depth);
    let empty_nodes = (0..tree.node_count() as u32)
        .filter(|&i| tree.node_fragments(i).is_empty())
        .count();
    assert!(empty_nodes > 0);
    for vp in [
        Viewpoint::Point(DVec3::new(0.3, 2.0, 2.5)),
        Viewpoint::Point(DVec3::new(0.1, -0.2, 0.3)),
        Viewpoint::Direction(DVec3::new(-1.0, 0.5, 0.2)),
    ] {
        assert!(check_order_invariants(&tree, vp) > 0);
    }
    let cam = Camera::perspective(
        DVec3::new(0.5, 1.5, 3.0),
        DVec3::ZERO,
        DVec3::Y,
        50.,
        0.1,
        20.,
    );
    let v = view(&s, &cam, 80, 60);
    both_traversals(&v, 1.0, "sphere");
}

#[test]
fn front_to_back_skips_hidden_and_offscreen_subtrees_without_changing_the_frame() {
    // A street view of a city: near buildings hide most of the others.
    let scene = demo::city(24, 24, 5);
    let cam = Camera::perspective(
        DVec3::new(0.2, 0.6, 13.0),
        DVec3::new(0.0, 0.8, 0.0),
        DVec3::Y,
        60.,
        0.1,
        80.,
    );
    let v = view(&scene, &cam, 160, 90);
    let (f2b, s) = bsp::render(&v, &options(BspTraversal::FrontToBack)).unwrap();
    assert!(s.subtrees_hidden > 0);
    assert!(s.subtrees_outside > 0);
    assert!(s.fragments_visited < s.bsp_fragments);
    assert_like_zbuffer(&f2b, &v, 1.0, "street view, front to back");
    let (b2f, s) = bsp::render(&v, &options(BspTraversal::BackToFront)).unwrap();
    assert_eq!(s.subtrees_hidden, 0);
    assert_eq!(s.fragments_visited, s.bsp_fragments);
    assert_eq!(f2b.ids, b2f.ids);
}

#[test]
fn tolerances_beyond_a_thousandth_of_the_scale_are_refused() {
    let scene = demo::default_scene();
    for (tolerance, ok) in [
        (0.0, true),
        (1e-3, true),
        (2e-3, false),
        (1e300, false),
        (-1e-9, false),
        (f64::NAN, false),
    ] {
        let options = BspOptions {
            tolerance,
            ..BspOptions::default()
        };
        assert_eq!(options.validate().is_ok(), ok, "{tolerance}");
        assert_eq!(BspTree::build(&scene, &options).is_ok(), ok, "{tolerance}");
    }
}

/// A build that passes its fragment budget stops with an error naming the budget,
/// instead of splitting on until memory runs out (30,000 large random triangles did).
#[test]
fn a_build_past_its_fragment_budget_is_an_error() {
    let scene = random_triangle_objects(300, 7, 2.0, 3.0);
    let full = BspTree::build(&scene, &BspOptions::default()).unwrap();
    // Every polygon is a fragment, and each split makes two more.
    let st = full.stats();
    let made = st.input_polygons - st.degenerate + 2 * st.splits;
    assert!(made > 400, "{made}");
    let budget = (made / 2) as usize;
    let e = BspTree::build(&scene, &BspOptions::default().with_max_fragments(budget))
        .unwrap_err()
        .to_string();
    assert!(e.contains(&format!("passed {budget} fragments")), "{e}");
    // Exactly enough is enough: every fragment made, split or not, counts.
    assert!(
        BspTree::build(
            &scene,
            &BspOptions::default().with_max_fragments(made as usize)
        )
        .is_ok()
    );
}

/// A node plane seen edge-on (an orthographic view along an axis plane, which the
/// lattice scene's axis splitters make): the pixels whose ray lies in the plane must
/// fall on the same side of it for every polygon the plane cuts. With a cut that was
/// an affine function per polygon, the pixel at (18, 9) went to the front pieces of
/// one face and the back piece of a nearer one, and BSP painted the farther face
/// (depth 7 instead of 5.6). Found by the differential fuzzer, seed 50000857.
#[test]
fn pieces_cut_by_a_plane_seen_edge_on_keep_the_order() {
    let mut scene = Scene::new();
    {
        let mut b = MeshBuilder::new();
        b.push_position(DVec3::new(5.0, 5.0, 4.0)); // 0
        b.push_position(DVec3::new(5.0, 6.0, 1.0)); // 1
        b.push_position(DVec3::new(4.0, 6.0, -2.0)); // 2
        b.push_face(&[0, 1, 2], None).unwrap();
        b.push_position(DVec3::new(5.0, 4.0, 2.5)); // 3
        b.push_position(DVec3::new(6.0, 4.0, -0.75)); // 4
        b.push_position(DVec3::new(6.0, 5.0, -2.0)); // 5
        b.push_face(&[3, 4, 5], None).unwrap();
        b.push_face(&[3, 5, 0], None).unwrap();
        b.push_face(&[0, 5, 1], None).unwrap();
        b.push_position(DVec3::new(7.75, 1.375, 0.25)); // 6
        b.push_position(DVec3::new(5.0, 6.625, 3.5)); // 7
        b.push_position(DVec3::new(0.0, 5.5, -0.25)); // 8
        b.push_face(&[6, 7, 8], None).unwrap();
        b.push_position(DVec3::new(-0.125, 0.25, 2.75)); // 9
        b.push_position(DVec3::new(0.0, 0.875, 2.0)); // 10
        b.push_position(DVec3::new(4.0, 0.0, 1.75)); // 11
        b.push_face(&[9, 10, 11], None).unwrap();
        b.push_position(DVec3::new(2.75, 2.0, 0.0)); // 12
        b.push_position(DVec3::new(6.5, 0.75, 2.75)); // 13
        b.push_position(DVec3::new(4.625, 4.625, 3.75)); // 14
        b.push_face(&[12, 13, 14], None).unwrap();
        let d = ObjectDesc::new("o0", b.finish().0).with_closed(false);
        let d = d.with_convex(false);
        scene.add(d).unwrap();
    }
    {
        let mut b = MeshBuilder::new();
        b.push_position(DVec3::new(2.25, 9.5, 0.25)); // 0
        b.push_position(DVec3::new(2.25, 9.5, 2.25)); // 1
        b.push_position(DVec3::new(3.0, 9.5, 2.25)); // 2
        b.push_position(DVec3::new(3.0, 9.5, 0.25)); // 3
        b.push_face(&[0, 1, 2, 3], None).unwrap();
        b.push_position(DVec3::new(2.25, 8.0, 0.25)); // 4
        b.push_position(DVec3::new(3.0, 8.0, 0.25)); // 5
        b.push_face(&[4, 0, 3, 5], None).unwrap();
        b.push_position(DVec3::new(2.25, 8.0, 2.25)); // 6
        b.push_position(DVec3::new(3.0, 8.0, 2.25)); // 7
        b.push_face(&[6, 7, 2, 1], None).unwrap();
        let d = ObjectDesc::new("o1", b.finish().0).with_closed(true);
        scene.add(d).unwrap();
    }
    {
        let mut b = MeshBuilder::new();
        b.push_position(DVec3::new(2.75, 5.625, 2.25)); // 0
        b.push_position(DVec3::new(2.75, 5.625, 4.25)); // 1
        b.push_position(DVec3::new(4.5, 5.625, 4.25)); // 2
        b.push_position(DVec3::new(4.5, 5.625, 2.25)); // 3
        b.push_face(&[0, 1, 2, 3], None).unwrap();
        b.push_position(DVec3::new(2.75, 4.625, 2.25)); // 4
        b.push_position(DVec3::new(4.5, 4.625, 2.25)); // 5
        b.push_face(&[4, 0, 3, 5], None).unwrap();
        b.push_position(DVec3::new(2.75, 4.625, 4.25)); // 6
        b.push_position(DVec3::new(4.5, 4.625, 4.25)); // 7
        b.push_face(&[6, 7, 2, 1], None).unwrap();
        let d = ObjectDesc::new("o2", b.finish().0).with_closed(true);
        scene.add(d).unwrap();
    }
    let camera = Camera::orthographic(
        DVec3::new(4.0, 4.0, 8.0),
        DVec3::new(4.0, 4.0, 0.0),
        DVec3::Y,
        8.0,
        1.0,
        16.0,
    );
    let bsp = BspOptions::default()
        .with_seed(16207998911744526178)
        .with_candidates(8)
        .with_weights(8.0, 1.0)
        .with_score_sample(2048)
        .with_axis_planes(true);
    let vp = crate::Viewport::new(32, 32).unwrap();
    let prep =
        crate::PrepareOptions::default().with_backface(crate::cull::backface::BackfaceMode::Closed);
    let view = crate::prepare(&scene, &camera, vp, &prep).unwrap();
    let (z, _) = crate::surface::render(
        crate::surface::Algorithm::ZBuffer,
        &view,
        &RenderOptions::default(),
    )
    .unwrap();
    for t in [BspTraversal::BackToFront, BspTraversal::FrontToBack] {
        let opts = RenderOptions::default().with_bsp(bsp.with_traversal(t));
        let (frame, stats) = bsp::render(&view, &opts).unwrap();
        assert!(stats.bsp_splits > 0);
        let wrong: Vec<(usize, usize, u32, u32)> = (0..z.ids.len())
            .filter(|&i| z.ids[i] != frame.ids[i])
            .map(|i| (i % 32, i / 32, frame.ids[i], z.ids[i]))
            .collect();
        assert!(
            wrong.is_empty(),
            "{}: (x, y, bsp id, z-buffer id) {wrong:?}",
            t.name()
        );
    }
}
