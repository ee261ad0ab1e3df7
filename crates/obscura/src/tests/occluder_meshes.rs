//! Per-object occluder meshes (issue 24, "Candidate occluders (large faces, or a
//! per-object occluder mesh)"): a sphere of small faces hides nothing by any one of
//! them, but the box inscribed in it, given as its occluder mesh, hides what is behind
//! it; every picture stays the same; occluder meshes that leave their object, objects
//! that are open or inside out, are refused with the file's line and the object's name.

use glam::{DMat4, DVec3};

use super::cull::same_picture;
use crate::cull::occluders::select::OccluderCandidates;
use crate::cull::occlusion::{CullMethod, CullOptions, CullReason};
use crate::rng::SplitMix64;
use crate::scene::demo::{box_mesh, uv_sphere_mesh};
use crate::scene::{Camera, ObjectDesc, Scene};
use crate::{Error, SceneIndex};

/// The sphere's radius, and the half side of a cube well inside it.
const R: f64 = 2.0;
const HALF: f64 = 1.0;

/// A sphere at the origin and, behind it along +z, a small box; the sphere with the
/// inscribed cube as its occluder mesh when `occluder`.
fn statue(occluder: bool) -> Scene {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("statue", uv_sphere_mesh(R, 24, 12)))
        .unwrap();
    s.add(ObjectDesc::new(
        "behind",
        box_mesh(DVec3::new(-0.2, -0.2, 5.0), DVec3::new(0.2, 0.2, 5.4)),
    ))
    .unwrap();
    if occluder {
        s.set_occluder(
            0,
            &box_mesh(DVec3::splat(-HALF), DVec3::splat(HALF)),
            DMat4::IDENTITY,
        )
        .unwrap();
    }
    s
}

#[test]
fn an_occluder_mesh_culls_what_its_object_hides_and_the_picture_stays() {
    let front = Camera::perspective(
        DVec3::new(0.0, 0.0, -6.0),
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::Y,
        50.0,
        0.1,
        100.0,
    );
    let options = CullOptions::with_method(CullMethod::Occluders);
    // Without: no single small face of the sphere hides the box.
    let plain = statue(false);
    let c = same_picture(&plain, &SceneIndex::new(&plain), &front, &options);
    assert_eq!(c.objects[1], None);
    // With: the cube's face towards the eye hides it, and is the first occluder.
    let scene = statue(true);
    let index = SceneIndex::new(&scene);
    let cands = OccluderCandidates::new(&scene);
    assert!(
        cands
            .candidates()
            .iter()
            .filter(|c| c.object == 0)
            .all(|c| c.polygon == u32::MAX && c.stands_for.is_some())
    );
    assert_eq!(
        cands.candidates().iter().filter(|c| c.object == 0).count(),
        6,
        "the cube's faces replace the sphere's"
    );
    let c = same_picture(&scene, &index, &front, &options);
    assert_eq!(c.objects[1], Some(CullReason::Occluder(0)), "{:?}", c.notes);
    assert_eq!(c.objects[0], None, "the statue itself is drawn");
    assert_eq!(c.occluders.first(), Some(&u32::MAX));
    // The eye inside the statue's box (here inside the sphere itself): the occluder
    // mesh is not used, nothing behind is culled by it.
    let inside = Camera::perspective(
        DVec3::new(0.0, 0.0, -1.5),
        DVec3::new(0.0, 0.0, 5.0),
        DVec3::Y,
        50.0,
        0.1,
        100.0,
    );
    let c = same_picture(&scene, &index, &inside, &options);
    assert_eq!(c.objects[1], None);
    // Random views around: always the same picture; sometimes culled.
    let mut rng = SplitMix64(3);
    let mut culled = 0;
    for _ in 0..40 {
        let a = rng.range(-0.6, 0.6);
        let d = rng.range(2.05, 12.0);
        let eye = DVec3::new(d * a.sin(), rng.range(-1.0, 1.0), -d * a.cos());
        let cam = Camera::perspective(
            eye,
            DVec3::new(rng.range(-1.0, 1.0), 0.0, 5.2),
            DVec3::Y,
            rng.range(30.0, 90.0),
            rng.range(0.01, 0.5),
            100.0,
        );
        let c = same_picture(&scene, &index, &cam, &options);
        culled += usize::from(c.objects[1].is_some());
    }
    assert!(culled > 5, "{culled}");
    // The buffer draws it in place of the sphere, the frustum ignores it: the picture
    // stays too.
    for m in [CullMethod::Buffer, CullMethod::Frustum] {
        same_picture(&scene, &index, &front, &CullOptions::with_method(m));
    }
    // The buffer draws the cube's faces as whole quads (no gap along a diagonal): the
    // box behind is hidden by the cube alone, as the sphere's own 162 triangles hid it.
    let c = same_picture(
        &scene,
        &index,
        &front,
        &CullOptions::with_method(CullMethod::Buffer),
    );
    assert_eq!(c.objects[1], Some(CullReason::Buffer), "{:?}", c.notes);
    assert!(
        c.notes
            .iter()
            .any(|n| n.contains("occluder polygons") && n.contains(" 0 of 0 triangles")),
        "the cube's faces drawn as polygons, none of the sphere's triangles: {:?}",
        c.notes
    );
}

#[test]
fn occluder_meshes_outside_their_object_are_refused() {
    let mut s = statue(false);
    let err =
        |s: &mut Scene, k: usize, m: &crate::scene::Mesh, t: DMat4| match s.set_occluder(k, m, t) {
            Err(Error::InvalidObject { object, message }) => format!("{object}: {message}"),
            other => panic!("{other:?}"),
        };
    // Outside the box; inside the box but outside the sphere (a corner); the cube too
    // big once scaled; an open object; an object index out of range.
    let e = err(
        &mut s,
        0,
        &box_mesh(DVec3::splat(-1.0), DVec3::new(1.0, 1.0, 2.5)),
        DMat4::IDENTITY,
    );
    assert!(
        e.starts_with("statue: occluder mesh: vertex") && e.contains("bounding box"),
        "{e}"
    );
    let e = err(
        &mut s,
        0,
        &box_mesh(DVec3::splat(-1.9), DVec3::splat(1.9)),
        DMat4::IDENTITY,
    );
    assert!(e.contains("outside the object's mesh"), "{e}");
    let e = err(
        &mut s,
        0,
        &box_mesh(DVec3::splat(-1.0), DVec3::splat(1.0)),
        DMat4::from_scale(DVec3::splat(1.5)),
    );
    assert!(e.contains("outside the object's mesh"), "{e}");
    let grid = s
        .add(ObjectDesc::new(
            "floor",
            crate::scene::demo::grid_mesh(4.0, 4.0, 2, 2),
        ))
        .unwrap();
    let e = err(
        &mut s,
        grid,
        &box_mesh(DVec3::splat(-0.1), DVec3::splat(0.0)),
        DMat4::IDENTITY,
    );
    assert!(e.contains("not closed"), "{e}");
    assert!(matches!(
        s.set_occluder(99, &box_mesh(DVec3::ZERO, DVec3::ONE), DMat4::IDENTITY),
        Err(Error::InvalidOption { .. })
    ));
    // A mirrored statue (scaled by -1 on x) takes the cube, and fronts stay fronts.
    let mut m = Scene::new();
    m.add(
        ObjectDesc::new("mirrored", uv_sphere_mesh(R, 24, 12))
            .with_transform(DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0))),
    )
    .unwrap();
    m.set_occluder(
        0,
        &box_mesh(DVec3::splat(-HALF), DVec3::splat(HALF)),
        DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
    )
    .unwrap();
    let occ = m.objects()[0].occluder.as_ref().unwrap();
    for p in 0..occ.polygon_count() {
        let n = occ.polygon_plane(p).unwrap().normal;
        let c = occ.polygon_points(p).iter().sum::<DVec3>() / 4.0;
        assert!(n.dot(c) > 0.0, "face {p} faces in");
    }
}

#[cfg(feature = "toml-scene")]
fn scene_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("obscura-occmesh-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An L-shaped prism (closed, counter-clockwise from outside unless `reversed`).
#[cfg(feature = "toml-scene")]
fn l_prism_obj(reversed: bool) -> String {
    let outline = [
        (0.0, 0.0),
        (2.0, 0.0),
        (2.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (0.0, 2.0),
    ];
    let mut s = String::new();
    for z in [0.0, 1.0] {
        for (x, y) in outline {
            s += &format!("v {x} {y} {z}\n");
        }
    }
    let mut faces: Vec<Vec<usize>> = vec![(1..=6).rev().collect(), (7..=12).collect()];
    for i in 0..6 {
        let j = (i + 1) % 6;
        faces.push(vec![i + 1, j + 1, j + 7, i + 7]);
    }
    for mut f in faces {
        if reversed {
            f.reverse();
        }
        s += "f";
        for v in f {
            s += &format!(" {v}");
        }
        s += "\n";
    }
    s
}

#[test]
#[cfg(feature = "toml-scene")]
fn scene_files_give_occluder_meshes_and_refuse_bad_ones_at_their_line() {
    let dir = scene_dir("toml");
    std::fs::write(dir.join("l.obj"), l_prism_obj(false)).unwrap();
    std::fs::write(dir.join("inside-out.obj"), l_prism_obj(true)).unwrap();
    // A thin triangle with its corners in the two arms of the L, its long edge across
    // the notch: vertices inside, an edge midpoint outside.
    std::fs::write(
        dir.join("across.obj"),
        "v 1.8 0.5 0.5\nv 0.5 1.8 0.5\nv 0.5 0.5 0.5\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("arm.obj"),
        "v 0.2 0.2 0.2\nv 1.8 0.2 0.2\nv 1.8 0.8 0.2\nv 0.2 0.8 0.2\nf 1 2 3 4\n",
    )
    .unwrap();
    let load = |text: &str| {
        let file = dir.join("scene.toml");
        std::fs::write(&file, text).unwrap();
        Scene::load(&file)
    };
    // Accepted: a box in a sphere (moved with it), a mesh file in the L.
    let ok = "[[object]]\nname = \"statue\"\nprimitive = \"sphere\"\nradius = 2.0\ntranslate = [0, 0, 3]\n\
              occluder_box = [[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]]\n\n\
              [[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder = \"arm.obj\"\n";
    let s = load(ok).unwrap();
    let occ = s.objects()[0].occluder.as_ref().unwrap();
    assert!((occ.bounds().min - DVec3::new(-1.0, -1.0, 2.0)).length() < 1e-12);
    assert!(s.objects()[1].occluder.is_some());
    let line_of =
        |text: &str, needle: &str| text[..text.find(needle).unwrap()].matches('\n').count() + 1;
    let cases = [
        (
            "[[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder = \"across.obj\"\n",
            "occluder =",
            "midpoint",
        ),
        (
            "[[object]]\nname = \"ell\"\nmesh = \"inside-out.obj\"\noccluder = \"arm.obj\"\n",
            "occluder =",
            "inside out",
        ),
        (
            "[[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder_box = [[0.2, 0.2, 0.2], [1.5, 1.5, 0.8]]\n",
            "occluder_box",
            "outside the object's mesh",
        ),
        (
            "[[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder_box = [[0, 0, 0], [3, 1, 1]]\n",
            "occluder_box",
            "bounding box",
        ),
        (
            "[[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder_box = [[1, 1, 1], [0, 0, 0]]\n",
            "occluder_box",
            "max above",
        ),
        (
            "[[object]]\nname = \"floor\"\nprimitive = \"grid\"\noccluder_box = [[0, 0, 0], [0.1, 0.1, 0.1]]\n",
            "occluder_box",
            "not closed",
        ),
        (
            "[[object]]\nname = \"ell\"\nmesh = \"l.obj\"\noccluder = \"arm.obj\"\noccluder_box = [[0, 0, 0], [1, 1, 1]]\n",
            "occluder_box",
            "not both",
        ),
    ];
    for (text, key, what) in cases {
        match load(text) {
            Err(Error::Parse { line, message, .. }) => {
                assert_eq!(line, line_of(text, key), "{text}: {message}");
                assert!(message.contains(what), "{text}: {message}");
                if what != "not both" && what != "max above" {
                    assert!(
                        message.contains("object \"ell\"") || message.contains("object \"floor\""),
                        "{message}"
                    );
                }
            }
            other => panic!("{text}: {other:?}"),
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
