//! Feature edges (issue 23, item 1) and the sampling oracle of `--check`. Every
//! expectation is computed here from the geometry written here: the cube's edges by
//! which corner is nearest, the sphere's contour analytically, intersection segments
//! by hand.

use std::collections::BTreeSet;

use glam::{DVec2, DVec3};
use obscura::lines::check::{CheckOptions, Visibility, check};
use obscura::lines::edges::{EdgeOptions, feature_edges};
use obscura::lines::{Drawing, DrawnEdge, EdgeKind, EdgeKinds, Piece};
use obscura::scene::demo;
use obscura::scene::{Material, MeshBuilder, ObjectDesc};
use obscura::{Camera, PrepareOptions, Scene, SceneIndex, View, Viewport};

fn view<'s>(scene: &'s Scene, camera: &Camera) -> View<'s> {
    View::new(
        scene,
        camera,
        Viewport::new(320, 240).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap()
}

fn persp(eye: DVec3) -> Camera {
    Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 50.0, 0.1, 100.0)
}

fn ortho(eye: DVec3) -> Camera {
    Camera::orthographic(eye, DVec3::ZERO, DVec3::Y, 4.0, 0.1, 100.0)
}

fn edges(scene: &Scene, camera: &Camera, options: &EdgeOptions) -> Vec<DrawnEdge> {
    let index = SceneIndex::new(scene);
    feature_edges(&index, &view(scene, camera), options).unwrap()
}

fn count(e: &[DrawnEdge], kind: EdgeKind) -> usize {
    e.iter().filter(|e| e.kind == kind).count()
}

fn scene_of(meshes: Vec<obscura::scene::Mesh>) -> Scene {
    let mut s = Scene::new();
    for (i, m) in meshes.into_iter().enumerate() {
        s.add(ObjectDesc::new(format!("m{i}"), m)).unwrap();
    }
    s
}

fn mesh(points: &[DVec3], faces: &[&[u32]]) -> obscura::scene::Mesh {
    let mut b = MeshBuilder::new();
    for &p in points {
        b.push_position(p);
    }
    for f in faces {
        b.push_face(f, None).unwrap();
    }
    b.finish().0
}

/// The unit cube's corner nearest the eye, and whether an edge touches the farthest.
fn far_corner(eye: DVec3) -> DVec3 {
    -eye.signum() * 0.5
}

#[test]
fn cube_has_twelve_creases_and_six_silhouettes_from_a_corner() {
    let scene = demo::cube();
    for camera in [
        persp(DVec3::new(2.0, 1.5, 3.0)),
        ortho(DVec3::new(2.0, 1.5, 3.0)),
    ] {
        let all = edges(&scene, &camera, &EdgeOptions::default());
        assert_eq!(all.len(), 12, "{camera:?}");
        assert_eq!(count(&all, EdgeKind::Silhouette), 6);
        assert_eq!(count(&all, EdgeKind::Crease), 6);
        // The silhouettes are the hexagon: the edges touching neither the nearest nor
        // the farthest corner.
        let far = far_corner(camera.eye);
        for e in &all {
            let touches = e.world.iter().any(|&p| p == far || p == -far);
            assert_eq!(e.kind == EdgeKind::Silhouette, !touches, "{e:?}");
            assert!(e.vertices.is_some() && e.faces.iter().all(Option::is_some));
        }
        // Every edge is a 90 degree crease: with silhouettes left out, 6 creases remain
        // (priority), and with a threshold of 95 degrees none.
        let creases = EdgeOptions::default().with_kinds(EdgeKinds::NONE.with(EdgeKind::Crease));
        assert_eq!(edges(&scene, &camera, &creases).len(), 6);
        let steep = creases.with_crease_degrees(95.0);
        assert!(edges(&scene, &camera, &steep).is_empty());
    }
    // A mirrored cube (winding flipped by the transform) has the same silhouettes.
    let mut mirrored = Scene::new();
    mirrored
        .add(
            ObjectDesc::new(
                "mirror",
                demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
            )
            .with_transform(glam::DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0))),
        )
        .unwrap();
    let camera = persp(DVec3::new(2.0, 1.5, 3.0));
    let far = far_corner(camera.eye);
    let e = edges(&mirrored, &camera, &EdgeOptions::default());
    assert_eq!(count(&e, EdgeKind::Silhouette), 6);
    for e in e.iter().filter(|e| e.kind == EdgeKind::Silhouette) {
        assert!(!e.world.iter().any(|&p| p == far || p == -far), "{e:?}");
    }
    // Head-on: the four edges of the front face are silhouettes (the side faces are
    // edge-on in orthographic, facing away in perspective), the other 8 creases.
    for camera in [persp(DVec3::Z * 4.0), ortho(DVec3::Z * 4.0)] {
        let all = edges(&scene, &camera, &EdgeOptions::default());
        assert_eq!(count(&all, EdgeKind::Silhouette), 4, "{camera:?}");
        assert_eq!(count(&all, EdgeKind::Crease), 8);
        for e in all.iter().filter(|e| e.kind == EdgeKind::Silhouette) {
            assert!(e.world.iter().all(|p| p.z == 0.5), "{e:?}");
        }
    }
}

#[test]
fn sphere_silhouette_lies_on_the_analytic_contour() {
    let (segments, rings) = (64u32, 32u32);
    let scene = scene_of(vec![demo::uv_sphere_mesh(1.0, segments, rings)]);
    // The angular size of a facet (its diagonal) bounds how far a silhouette vertex is from the
    // contour.
    let facet = (std::f64::consts::TAU / f64::from(segments))
        .hypot(std::f64::consts::PI / f64::from(rings));
    let dir = DVec3::new(3.0, 2.0, 1.5).normalize();
    let distance = 4.0;
    for (camera, contour) in [
        // Perspective: the tangent cone touches at angle acos(R / D) from the eye's
        // direction; orthographic: the great circle at 90 degrees.
        (persp(dir * distance), (1.0 / distance).acos()),
        (ortho(dir * distance), std::f64::consts::FRAC_PI_2),
    ] {
        let e = edges(
            &scene,
            &camera,
            &EdgeOptions::default().with_kinds(EdgeKinds::NONE.with(EdgeKind::Silhouette)),
        );
        assert!(e.len() >= segments as usize, "{} silhouette edges", e.len());
        let mut degree = std::collections::HashMap::new();
        for edge in &e {
            for (p, v) in edge.world.iter().zip(edge.vertices.unwrap()) {
                let angle = p.normalize().dot(dir).clamp(-1.0, 1.0).acos();
                assert!(
                    (angle - contour).abs() <= facet,
                    "vertex at {:.4} rad, contour {contour:.4}, facet {facet:.4}",
                    angle
                );
                *degree.entry(v).or_insert(0) += 1;
            }
        }
        // A closed contour: every vertex starts as many edges as it ends.
        assert!(degree.values().all(|d| d % 2 == 0), "{degree:?}");
    }
}

#[test]
fn planar_faces_draw_no_diagonal() {
    // A unit square as two triangle faces: four boundaries, no diagonal unless every
    // edge is asked for (it is then an `Other` edge of two faces).
    let sq = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];
    let scene = scene_of(vec![mesh(&sq, &[&[0, 1, 2], &[0, 2, 3]])]);
    let camera = persp(DVec3::new(0.3, 0.4, 3.0));
    let e = edges(&scene, &camera, &EdgeOptions::default());
    assert_eq!((e.len(), count(&e, EdgeKind::Boundary)), (4, 4));
    let all = edges(
        &scene,
        &camera,
        &EdgeOptions::default().with_kinds(EdgeKinds::ALL),
    );
    assert_eq!((all.len(), count(&all, EdgeKind::Other)), (5, 1));
    // An L-shaped (non-convex) planar face is split into convex polygons of one face:
    // their shared edges are never drawn, even when every edge is asked for.
    let l = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(1.0, 2.0, 0.0),
        DVec3::new(0.0, 2.0, 0.0),
    ];
    let scene = scene_of(vec![mesh(&l, &[&[0, 1, 2, 3, 4, 5]])]);
    assert!(scene.objects()[0].mesh.polygon_count() > 1);
    let all = edges(
        &scene,
        &camera,
        &EdgeOptions::default().with_kinds(EdgeKinds::ALL),
    );
    assert_eq!(
        (all.len(), count(&all, EdgeKind::Boundary)),
        (6, 6),
        "{all:?}"
    );
}

#[test]
fn non_manifold_edges_are_boundaries() {
    // Three triangles on one edge (a book of three pages): the spine is drawn once,
    // as a boundary, with the other six edges.
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(-0.5, 0.0, 0.8),
        DVec3::new(-0.5, 0.0, -0.8),
    ];
    let scene = scene_of(vec![mesh(&p, &[&[0, 2, 1], &[0, 1, 3], &[0, 1, 4]])]);
    let e = edges(
        &scene,
        &persp(DVec3::new(1.0, 2.0, 3.0)),
        &EdgeOptions::default(),
    );
    assert_eq!((e.len(), count(&e, EdgeKind::Boundary)), (7, 7), "{e:?}");
    let spine = e
        .iter()
        .filter(|e| e.world == [p[0], p[1]])
        .collect::<Vec<_>>();
    assert_eq!(spine.len(), 1);
}

#[test]
fn crease_threshold_is_respected() {
    // Two squares folded by 40 degrees along x = 1, both facing the eye above.
    let a = 40f64.to_radians();
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1.0 + a.cos(), 0.0, a.sin()),
        DVec3::new(1.0 + a.cos(), 1.0, a.sin()),
    ];
    let scene = scene_of(vec![mesh(&p, &[&[0, 1, 2, 3], &[1, 4, 5, 2]])]);
    let camera = Camera::perspective(
        DVec3::new(1.0, 0.5, 6.0),
        DVec3::new(1.0, 0.5, 0.0),
        DVec3::Y,
        50.0,
        0.1,
        100.0,
    );
    let fold = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0)];
    let at30 = edges(&scene, &camera, &EdgeOptions::default());
    let creases: Vec<_> = at30.iter().filter(|e| e.kind == EdgeKind::Crease).collect();
    assert_eq!(creases.len(), 1);
    assert_eq!(creases[0].world, fold);
    assert_eq!(count(&at30, EdgeKind::Boundary), 6);
    let at45 = edges(
        &scene,
        &camera,
        &EdgeOptions::default().with_crease_degrees(45.0),
    );
    assert_eq!((at45.len(), count(&at45, EdgeKind::Crease)), (6, 0));
    let all45 = EdgeOptions::default()
        .with_crease_degrees(45.0)
        .with_kinds(EdgeKinds::ALL);
    let all45 = edges(&scene, &camera, &all45);
    assert_eq!(count(&all45, EdgeKind::Other), 1);
    // Out of range thresholds are refused, naming the option.
    let index = SceneIndex::new(&scene);
    for bad in [-1.0, 181.0, f64::NAN] {
        let err = feature_edges(
            &index,
            &view(&scene, &camera),
            &EdgeOptions::default().with_crease_degrees(bad),
        )
        .unwrap_err();
        assert!(err.to_string().contains("crease"), "{err}");
    }
}

#[test]
fn borders_between_colours_and_between_objects() {
    let p = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 1.0, 0.0),
    ];
    let camera = persp(DVec3::new(1.0, 0.5, 4.0));
    // One object, two coplanar faces of different materials.
    let mut b = MeshBuilder::new();
    for &q in &p {
        b.push_position(q);
    }
    for (k, c) in [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]].into_iter().enumerate() {
        b.push_material(Material {
            name: format!("c{k}"),
            color: c,
        });
    }
    b.push_face(&[0, 1, 2, 3], Some(0)).unwrap();
    b.push_face(&[1, 4, 5, 2], Some(1)).unwrap();
    let scene = scene_of(vec![b.finish().0]);
    let e = edges(&scene, &camera, &EdgeOptions::default());
    assert_eq!((e.len(), count(&e, EdgeKind::Border)), (7, 1));
    // Two objects sharing the edge x = 1: one border edge, with a polygon of each.
    let left = mesh(&p[..4], &[&[0, 1, 2, 3]]);
    let right = mesh(&[p[1], p[4], p[5], p[2]], &[&[0, 1, 2, 3]]);
    let scene = scene_of(vec![left, right]);
    let e = edges(&scene, &camera, &EdgeOptions::default());
    assert_eq!((e.len(), count(&e, EdgeKind::Border)), (7, 1), "{e:?}");
    let border = e.iter().find(|e| e.kind == EdgeKind::Border).unwrap();
    assert_eq!(border.faces, [Some(0), Some(1)]);
    assert_eq!(border.vertices, Some([1, 2]));
}

#[test]
fn two_triangles_cross_along_their_analytic_segment() {
    let t1 = mesh(
        &[
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ],
        &[&[0, 1, 2]],
    );
    let t2 = mesh(
        &[
            DVec3::new(0.5, -1.0, -1.0),
            DVec3::new(0.5, 3.0, -1.0),
            DVec3::new(0.5, -1.0, 3.0),
        ],
        &[&[0, 1, 2]],
    );
    let scene = scene_of(vec![t1, t2]);
    let index = SceneIndex::new(&scene);
    let only = EdgeOptions::default().with_kinds(EdgeKinds::NONE.with(EdgeKind::Intersection));
    let camera = persp(DVec3::new(3.0, 2.0, 4.0));
    let e = feature_edges(&index, &view(&scene, &camera), &only).unwrap();
    assert_eq!(e.len(), 1, "{e:?}");
    let [p, q] = e[0].world;
    let (lo, hi) = if p.y < q.y { (p, q) } else { (q, p) };
    // x = 0.5 on the plane z = 0, from y = 0 to the hypotenuse x + y = 2.
    assert!(lo.distance(DVec3::new(0.5, 0.0, 0.0)) < 1e-14, "{lo}");
    assert!(hi.distance(DVec3::new(0.5, 1.5, 0.0)) < 1e-14, "{hi}");
    assert_eq!(e[0].faces, [Some(0), Some(1)]);
    assert_eq!((e[0].object, e[0].vertices), (Some(0), None));
    // The same two triangles in one object cross along the same segment.
    let one = scene_of(vec![mesh(
        &[
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.5, -1.0, -1.0),
            DVec3::new(0.5, 3.0, -1.0),
            DVec3::new(0.5, -1.0, 3.0),
        ],
        &[&[0, 1, 2], &[3, 4, 5]],
    )]);
    let self_crossing = edges(&one, &camera, &only);
    assert_eq!(self_crossing.len(), 1);
    assert_eq!(self_crossing[0].world, e[0].world);
    // Computed once per scene.
    assert!(std::ptr::eq(
        index.intersection_lines(),
        index.intersection_lines()
    ));
}

#[test]
fn interpenetrating_boxes_meet_in_a_closed_loop() {
    let scene = scene_of(vec![
        demo::box_mesh(DVec3::ZERO, DVec3::splat(2.0)),
        demo::box_mesh(DVec3::ONE, DVec3::splat(3.0)),
    ]);
    let index = SceneIndex::new(&scene);
    let segs = index.intersection_lines();
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let loop6 = [
        v(2.0, 1.0, 1.0),
        v(2.0, 1.0, 2.0),
        v(1.0, 1.0, 2.0),
        v(1.0, 2.0, 2.0),
        v(1.0, 2.0, 1.0),
        v(2.0, 2.0, 1.0),
    ];
    assert_eq!(segs.len(), 6, "{segs:?}");
    let close = |a: DVec3, b: DVec3| a.distance(b) < 1e-12;
    for i in 0..6 {
        let (a, b) = (loop6[i], loop6[(i + 1) % 6]);
        assert!(
            segs.iter()
                .any(|s| (close(s.world[0], a) && close(s.world[1], b))
                    || (close(s.world[0], b) && close(s.world[1], a))),
            "no segment {a} - {b} in {segs:?}"
        );
    }
    for s in segs {
        let [a, b] = s.polygons.map(|p| scene.locate_face(p).unwrap().0);
        assert_ne!(a, b, "each segment has a face of each box");
    }
}

#[cfg(all(feature = "stl", feature = "obj"))]
/// A torus of triangles with coordinates on a grid of 1/256 (exact in `f32`, as STL
/// stores them).
fn torus_triangles() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = demo::torus_mesh(1.0, 0.4, 20, 10);
    let pos: Vec<DVec3> = t
        .positions()
        .iter()
        .map(|p| (*p * 256.0).round() / 256.0)
        .collect();
    let mut tris = Vec::new();
    for i in 0..t.polygon_count() {
        let poly = t.polygon(i);
        for w in poly[1..].windows(2) {
            tris.push([poly[0], w[0], w[1]]);
        }
    }
    (pos, tris)
}

#[cfg(all(feature = "stl", feature = "obj"))]
/// The edges as comparable keys: kind and world ends, ends ordered.
fn edge_keys(e: &[DrawnEdge]) -> BTreeSet<(EdgeKind, [u64; 3], [u64; 3])> {
    e.iter()
        .map(|e| {
            let (a, b) = (
                e.world[0].to_array().map(f64::to_bits),
                e.world[1].to_array().map(f64::to_bits),
            );
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            (e.kind, a, b)
        })
        .collect()
}

// Reads STL and OBJ files: built with those formats (default features).
#[cfg(all(feature = "stl", feature = "obj"))]
#[test]
fn a_triangle_soup_draws_as_the_indexed_mesh() {
    let (pos, tris) = torus_triangles();
    let faces: Vec<&[u32]> = tris.iter().map(|t| &t[..]).collect();
    let indexed = scene_of(vec![mesh(&pos, &faces)]);
    // Every triangle with its own three vertices.
    let soup_points: Vec<DVec3> = tris
        .iter()
        .flat_map(|t| t.map(|i| pos[i as usize]))
        .collect();
    let soup_faces: Vec<[u32; 3]> = (0..tris.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let soup_refs: Vec<&[u32]> = soup_faces.iter().map(|t| &t[..]).collect();
    let soup = scene_of(vec![mesh(&soup_points, &soup_refs)]);
    // And the same two as files: an ASCII STL and an indexed OBJ.
    let dir = std::env::temp_dir().join(format!("obscura-lines-edges-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut stl = String::from("solid torus\n");
    for t in &tris {
        stl.push_str("facet normal 0 0 0\nouter loop\n");
        for &i in t {
            let p = pos[i as usize];
            stl.push_str(&format!("vertex {} {} {}\n", p.x, p.y, p.z));
        }
        stl.push_str("endloop\nendfacet\n");
    }
    stl.push_str("endsolid torus\n");
    let mut obj = String::new();
    for p in &pos {
        obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for t in &tris {
        obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    std::fs::write(dir.join("torus.stl"), stl).unwrap();
    std::fs::write(dir.join("torus.obj"), obj).unwrap();
    let from_stl = Scene::load(dir.join("torus.stl")).unwrap();
    let from_obj = Scene::load(dir.join("torus.obj")).unwrap();
    std::fs::remove_dir_all(&dir).ok();

    let all = EdgeOptions::default().with_kinds(EdgeKinds::ALL);
    for camera in [
        persp(DVec3::new(1.5, 2.5, 3.0)),
        ortho(DVec3::new(-1.0, 3.0, 2.0)),
    ] {
        for options in [EdgeOptions::default(), all] {
            let reference = edge_keys(&edges(&indexed, &camera, &options));
            assert!(reference.iter().any(|k| k.0 == EdgeKind::Silhouette));
            for other in [&soup, &from_stl, &from_obj] {
                assert_eq!(edge_keys(&edges(other, &camera, &options)), reference);
            }
        }
        // The torus is closed: no boundary; every edge has two polygons.
        let e = edges(&soup, &camera, &all);
        assert_eq!(count(&e, EdgeKind::Boundary), 0);
        assert_eq!(e.len(), 3 * tris.len() / 2);
    }
}

/// A drawing of the cube's 12 edges, one piece each (or two, split at t = 0.5), with
/// visibility computed by hand: from a corner, an edge is hidden exactly when it
/// touches the corner farthest from the eye.
fn cube_drawing(scene: &Scene, camera: &Camera, split: bool) -> Drawing {
    let index = SceneIndex::new(scene);
    let v = view(scene, camera);
    let mut d = Drawing::new(320, 240);
    d.edges = feature_edges(
        &index,
        &v,
        &EdgeOptions::default().with_kinds(EdgeKinds::ALL),
    )
    .unwrap();
    let far = far_corner(camera.eye);
    for (i, e) in d.edges.iter().enumerate() {
        let hidden = e.world.contains(&far);
        let cuts: &[[f64; 2]] = if split {
            &[[0.0, 0.5], [0.5, 1.0]]
        } else {
            &[[0.0, 1.0]]
        };
        for &t in cuts {
            d.pieces.push(Piece {
                edge: i as u32,
                t,
                points: [DVec2::ZERO; 2],
                invisibility: u32::from(hidden),
            });
        }
    }
    d
}

#[test]
fn the_oracle_agrees_with_a_hand_made_drawing_and_catches_wrong_ones() {
    let scene = demo::cube();
    let index = SceneIndex::new(&scene);
    for camera in [
        persp(DVec3::new(2.0, 1.5, 3.0)),
        ortho(DVec3::new(-2.0, 1.5, 3.0)),
        persp(DVec3::new(-1.5, -2.0, -2.5)),
    ] {
        let v = view(&scene, &camera);
        for split in [false, true] {
            let d = cube_drawing(&scene, &camera, split);
            assert_eq!(d.edges.len(), 12);
            assert_eq!(d.hidden().count(), if split { 6 } else { 3 });
            let r = check(&index, &v, &d, &CheckOptions::default());
            assert!(r.agrees(), "{camera:?}: {r:?}");
            assert_eq!(r.pieces_checked as usize, d.pieces.len());
            assert_eq!(r.samples as usize, 3 * d.pieces.len());
        }
        // One visible piece marked hidden and one hidden piece marked visible.
        let mut d = cube_drawing(&scene, &camera, false);
        let shown = d.pieces.iter().position(Piece::is_visible).unwrap();
        let hidden = d.pieces.iter().position(|p| !p.is_visible()).unwrap();
        d.pieces[shown].invisibility = 1;
        d.pieces[hidden].invisibility = 0;
        let r = check(&index, &v, &d, &CheckOptions::default().with_samples(5));
        assert!(!r.agrees());
        assert_eq!(r.pieces_disagreeing, 2, "{r:?}");
        assert_eq!(r.disagreement_count, 10);
        let pieces: BTreeSet<u32> = r.disagreements.iter().map(|x| x.piece).collect();
        assert_eq!(pieces, BTreeSet::from([shown as u32, hidden as u32]));
        for x in &r.disagreements {
            if x.piece == shown as u32 {
                assert_eq!(
                    (x.expected, x.found),
                    (Visibility::Hidden, Visibility::Visible)
                );
            } else {
                assert_eq!(
                    (x.expected, x.found),
                    (Visibility::Visible, Visibility::Hidden)
                );
                // Hidden by one of the three faces seen.
                assert!(x.occluder.is_some());
            }
        }
    }
}
