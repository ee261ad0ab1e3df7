//! The public API a user meets first (issue 22, section 3): scenes from arrays in
//! memory, cameras from matrices and from pinhole intrinsics, and file formats behind
//! cargo features. Every expectation is computed here, on inputs written here.

mod common;

use common::TempDir;
use glam::{DMat4, DVec3};
use obscura::scene::{Faces, Intrinsics};
use obscura::{Algorithm, Camera, Error, Frame, PrepareOptions, Scene, Viewport, prepare, render};

/// A cube (six quads), a triangle in front of it and a pentagon behind, overlapping in
/// the picture, with one degenerate face (id 7) that must keep its id.
fn arrays() -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>) {
    let mut p: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                f64::from(i & 1),
                f64::from((i >> 1) & 1),
                f64::from((i >> 2) & 1),
            ]
        })
        .collect();
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut offsets = vec![0];
    let mut indices = Vec::new();
    for q in quads {
        indices.extend(q);
        offsets.push(indices.len() as u32);
    }
    // A triangle in front (face 6), a degenerate one (face 7), a pentagon behind (8).
    p.extend([[-0.3, -0.2, 1.6], [1.4, 0.1, 1.5], [0.4, 1.3, 1.7]]);
    indices.extend([8, 9, 10]);
    offsets.push(indices.len() as u32);
    indices.extend([8, 8, 9]);
    offsets.push(indices.len() as u32);
    let base = p.len() as u32;
    for k in 0..5 {
        let a = f64::from(k) * std::f64::consts::TAU / 5.0;
        p.push([0.5 + 1.2 * a.cos(), 0.5 + 1.2 * a.sin(), -0.8]);
    }
    indices.extend(base..base + 5);
    offsets.push(indices.len() as u32);
    (p, offsets, indices)
}

fn picture(scene: &Scene, camera: &Camera, viewport: Viewport) -> Frame {
    let view = prepare(scene, camera, viewport, &PrepareOptions::default()).unwrap();
    render(Algorithm::ZBuffer, &view, &Default::default())
        .unwrap()
        .0
}

fn camera() -> Camera {
    Camera::perspective(
        DVec3::new(1.9, 1.4, 4.2),
        DVec3::new(0.5, 0.5, 0.3),
        DVec3::Y,
        50.0,
        0.5,
        20.0,
    )
}

#[test]
#[cfg(feature = "obj")]
fn a_scene_from_arrays_renders_as_the_same_mesh_loaded_from_obj() {
    let (p, offsets, indices) = arrays();
    let scene = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )
    .unwrap();
    let mut obj = String::new();
    for v in &p {
        obj.push_str(&format!("v {:?} {:?} {:?}\n", v[0], v[1], v[2]));
    }
    for w in offsets.windows(2) {
        let face: Vec<String> = indices[w[0] as usize..w[1] as usize]
            .iter()
            .map(|i| (i + 1).to_string())
            .collect();
        obj.push_str(&format!("f {}\n", face.join(" ")));
    }
    let dir = TempDir::new("obj");
    let path = dir.join("same.obj");
    std::fs::write(&path, obj).unwrap();
    let loaded = Scene::load(&path).unwrap();

    assert_eq!(scene.face_count(), 9);
    assert_eq!(loaded.face_count(), 9);
    assert_eq!(scene.report().degenerate_faces, 1);
    assert_eq!(loaded.report().degenerate_faces, 1);
    let vp = Viewport::new(96, 72).unwrap();
    let a = picture(&scene, &camera(), vp);
    let b = picture(&loaded, &camera(), vp);
    assert_eq!(a.ids, b.ids);
    assert_eq!(a.depth, b.depth);
    // Every face the camera sees is there: the cube's three front faces, the triangle
    // (id 6) and the pentagon (id 8) around the cube; never the degenerate id 7.
    let seen = |id: u32| a.ids.contains(&id);
    assert!(seen(6) && seen(8) && !seen(7), "{:?}", a.ids);
    assert!(a.ids.iter().filter(|&&id| id < 6).count() > 100);
}

#[test]
fn triangles_and_polygons_give_the_same_scene() {
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let tris = Scene::from_arrays(&p, Faces::Triangles(&[[0, 1, 2], [0, 2, 3]])).unwrap();
    let polys = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &[0, 3, 6],
            indices: &[0, 1, 2, 0, 2, 3],
        },
    )
    .unwrap();
    let cam = Camera::perspective(
        DVec3::new(0.4, 0.6, 2.0),
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::Y,
        60.0,
        0.1,
        10.0,
    );
    let vp = Viewport::new(40, 30).unwrap();
    let (a, b) = (picture(&tris, &cam, vp), picture(&polys, &cam, vp));
    assert_eq!(a.ids, b.ids);
    assert!(a.ids.contains(&0) && a.ids.contains(&1));
}

#[test]
fn bad_arrays_are_refused_naming_the_face_or_vertex() {
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let e =
        Scene::from_arrays(&p, Faces::Triangles(&[[0, 1, 2], [0, 1, 2], [0, 9, 2]])).unwrap_err();
    assert!(matches!(e, Error::InvalidObject { .. }), "{e:?}");
    let m = e.to_string();
    assert!(m.contains("face 2: vertex index 9 is out of range"), "{m}");
    let e = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &[0, 3, 7],
            indices: &[0, 1, 2, 0, 1, 2, 3],
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("face 1: vertex index 3 is out of range"), "{e}");
    let mut bad = p;
    bad[1][2] = f64::NAN;
    let e = Scene::from_arrays(&bad, Faces::Triangles(&[[0, 1, 2]]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 1 is not finite"), "{e}");
    bad[1][2] = 1e31;
    let e = Scene::from_arrays(&bad, Faces::Triangles(&[[0, 1, 2]]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 1: coordinate 1e31"), "{e}");
    // Only degenerate faces: empty, with the reason.
    let e = Scene::from_arrays(&p, Faces::Triangles(&[[0, 0, 1]])).unwrap_err();
    assert!(matches!(e, Error::EmptyScene(_)), "{e:?}");
    assert!(e.to_string().contains("degenerate"), "{e}");
}

#[test]
fn a_camera_from_look_at_matrices_gives_the_same_picture() {
    let (p, offsets, indices) = arrays();
    let scene = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )
    .unwrap();
    let vp = Viewport::new(96, 72).unwrap();
    let ortho = Camera::orthographic(
        DVec3::new(-2.0, 1.5, 3.0),
        DVec3::new(0.5, 0.5, 0.5),
        DVec3::new(0.1, 1.0, 0.0),
        2.5,
        0.25,
        12.0,
    );
    for cam in [camera(), ortho] {
        let again =
            Camera::from_matrices(cam.view_matrix(), cam.projection_matrix(vp.aspect()), vp)
                .unwrap();
        assert_eq!(
            std::mem::discriminant(&again.projection),
            std::mem::discriminant(&cam.projection)
        );
        assert!((again.eye - cam.eye).length() < 1e-12, "{again:?}");
        assert!((again.near - cam.near).abs() < 1e-12 * cam.far);
        assert!((again.far - cam.far).abs() < 1e-9 * cam.far);
        let (a, b) = (picture(&scene, &cam, vp), picture(&scene, &again, vp));
        assert!(a.covered_pixels() > 1000);
        assert_eq!(a.ids, b.ids, "{cam:?} -> {again:?}");
    }
}

#[test]
fn matrices_that_are_no_camera_are_refused_saying_why() {
    let vp = Viewport::new(64, 48).unwrap();
    let cam = camera();
    let (view, proj) = (cam.view_matrix(), cam.projection_matrix(vp.aspect()));
    let err = |v: DMat4, p: DMat4, vp: Viewport| match Camera::from_matrices(v, p, vp) {
        Err(Error::InvalidCamera(m)) => m,
        other => panic!("expected InvalidCamera, got {other:?}"),
    };
    let mut nan = view;
    nan.y_axis.z = f64::NAN;
    assert!(err(nan, proj, vp).contains("view matrix has non-finite"));
    let mut nan = proj;
    nan.x_axis.x = f64::NAN;
    assert!(err(view, nan, vp).contains("projection matrix has non-finite"));
    assert!(err(DMat4::ZERO, proj, vp).contains("not affine"));
    let flat = DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0));
    assert!(err(flat, proj, vp).contains("singular"));
    let scaled = DMat4::from_scale(DVec3::splat(2.0)) * view;
    assert!(err(scaled, proj, vp).contains("not a rotation and a translation"));
    let mirrored = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)) * view;
    assert!(err(mirrored, proj, vp).contains("not a rotation and a translation"));
    let mut singular = proj;
    singular.y_axis.y = 0.0;
    assert!(err(view, singular, vp).contains("singular"));
    let mut skewed = proj;
    skewed.y_axis.x = 0.1;
    assert!(err(view, skewed, vp).contains("skewed"));
    let mut odd = proj;
    odd.z_axis.w = -0.5;
    assert!(err(view, odd, vp).contains("neither perspective"));
    // An off-centre window and pixels that are not square (a 64:48 window over a
    // square viewport) are cameras now: their lens holds them.
    let mut shifted = proj;
    shifted.z_axis.x = 0.1;
    let c = Camera::from_matrices(view, shifted, vp).unwrap();
    assert!((c.lens.shift.x - 0.05).abs() < 1e-15 && c.lens.shift.y == 0.0);
    let square = Viewport::new(48, 48).unwrap();
    let c = Camera::from_matrices(view, proj, square).unwrap();
    assert!((c.lens.pixel_aspect - 64.0 / 48.0).abs() < 1e-12);
}

#[test]
fn centred_intrinsics_equal_the_matching_field_of_view() {
    let (p, offsets, indices) = arrays();
    let scene = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )
    .unwrap();
    let (w, h) = (120u32, 90u32);
    // A 50 degree vertical field of view over 90 rows: fy = 45 / tan(25 degrees).
    let f = 45.0 / 25f64.to_radians().tan();
    let k = Intrinsics {
        fx: f,
        fy: f,
        cx: 60.0,
        cy: 45.0,
        width: w,
        height: h,
    };
    let cam = camera();
    let from_k = Camera::from_intrinsics(cam.view_matrix(), &k, cam.near, cam.far).unwrap();
    assert!((k.fov_y_degrees() - 50.0).abs() < 1e-12);
    let vp = k.viewport().unwrap();
    assert_eq!((vp.width, vp.height), (w, h));
    let (a, b) = (picture(&scene, &cam, vp), picture(&scene, &from_k, vp));
    assert!(a.covered_pixels() > 1000);
    assert_eq!(a.ids, b.ids);
}

#[test]
fn intrinsics_that_are_no_camera_are_refused_saying_why() {
    let k = Intrinsics {
        fx: 100.0,
        fy: 100.0,
        cx: 32.0,
        cy: 24.0,
        width: 64,
        height: 48,
    };
    let view = camera().view_matrix();
    let err = |k: Intrinsics| match Camera::from_intrinsics(view, &k, 0.1, 10.0) {
        Err(Error::InvalidCamera(m)) => m,
        other => panic!("expected InvalidCamera, got {other:?}"),
    };
    assert!(Camera::from_intrinsics(view, &k, 0.1, 10.0).is_ok());
    // OpenCV's centre of a 64x48 image, (31.5, 23.5), is half a pixel up and left of
    // ours: a window moved half a pixel right and down. Unequal focal lengths are
    // pixels of aspect fy / fx. (Both were refused before cameras had a lens.)
    let c = Camera::from_intrinsics(
        view,
        &Intrinsics {
            cx: 31.5,
            cy: 23.5,
            ..k
        },
        0.1,
        10.0,
    )
    .unwrap();
    assert_eq!(c.lens.shift.to_array(), [0.5 / 64.0, -0.5 / 48.0]);
    let c = Camera::from_intrinsics(view, &Intrinsics { fy: 120.0, ..k }, 0.1, 10.0).unwrap();
    assert_eq!(c.lens.pixel_aspect, 1.2);
    assert!(
        err(Intrinsics {
            fx: -1.0,
            fy: -1.0,
            ..k
        })
        .contains("positive")
    );
    assert!(err(Intrinsics { fx: f64::NAN, ..k }).contains("finite"));
    assert!(matches!(
        Camera::from_intrinsics(view, &Intrinsics { width: 0, ..k }, 0.1, 10.0),
        Err(Error::InvalidViewport { .. })
    ));
    assert!(Camera::from_intrinsics(view, &k, 0.0, 10.0).is_err());
}

/// A file of each format this build leaves out is refused naming the feature (run by
/// CI's `cargo test -p obscura --no-default-features`).
#[test]
fn formats_left_out_of_the_build_name_their_feature() {
    let dir = TempDir::new("features");
    let cases = [
        ("a.obj", "obj", cfg!(feature = "obj")),
        ("a.gltf", "gltf", cfg!(feature = "gltf")),
        ("a.glb", "gltf", cfg!(feature = "gltf")),
        ("a.stl", "stl", cfg!(feature = "stl")),
        ("a.ply", "ply", cfg!(feature = "ply")),
        ("a.toml", "toml-scene", cfg!(feature = "toml-scene")),
    ];
    for (name, feature, enabled) in cases {
        let path = dir.join(name);
        std::fs::write(&path, "not a valid file of any format\n").unwrap();
        let e = Scene::load(&path).unwrap_err();
        let disabled = matches!(e, Error::FormatDisabled { feature: f, .. } if f == feature);
        assert_eq!(disabled, !enabled, "{name}: {e}");
        if !enabled {
            let m = e.to_string();
            assert!(m.contains(&format!("cargo feature \"{feature}\"")), "{m}");
            assert!(m.contains(name), "{m}");
        }
    }
}
