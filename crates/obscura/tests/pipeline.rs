//! The view pipeline against answers computed independently of it: analytic
//! projections of a cube, back-face counts from world-space normals, the horizon of an
//! infinite floor that crosses the eye plane.

use glam::{DMat4, DVec3};
use obscura::cull::backface::BackfaceMode;
use obscura::scene::{Camera, ObjectDesc, demo};
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::{BACKGROUND, Frame, PrepareOptions, Scene, Viewport, prepare};

fn zbuffer(scene: &Scene, cam: &Camera, w: u32, h: u32, opts: &PrepareOptions) -> Frame {
    let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
    let view = prepare(scene, cam, vp, opts).unwrap();
    render(Algorithm::ZBuffer, &view, &RenderOptions::default())
        .unwrap()
        .0
}

/// Projects a world point with the textbook formulas, independently of obscura's
/// matrices: returns pixel coordinates (x right, y down).
fn project(cam: &Camera, w: f64, h: f64, p: DVec3) -> (f64, f64) {
    let f = (cam.target - cam.eye).normalize();
    let r = f.cross(cam.up).normalize();
    let u = r.cross(f);
    let d = p - cam.eye;
    let (x, y, z) = (d.dot(r), d.dot(u), d.dot(f));
    let (nx, ny) = match cam.projection {
        obscura::Projection::Perspective { fov_y_degrees } => {
            let t = (fov_y_degrees.to_radians() / 2.0).tan();
            (x / z / (t * w / h), y / z / t)
        }
        obscura::Projection::Orthographic { height } => {
            (x / (height / 2.0 * w / h), y / (height / 2.0))
        }
    };
    ((nx + 1.0) / 2.0 * w, (1.0 - ny) / 2.0 * h)
}

/// Whether a point is inside a convex polygon (either winding), strictly, by cross
/// products; `None` when it is within `eps` of an edge (ambiguous by construction).
fn inside_convex(poly: &[(f64, f64)], p: (f64, f64), eps: f64) -> Option<bool> {
    let n = poly.len();
    let mut sign = 0.0;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        let (ex, ey) = (b.0 - a.0, b.1 - a.1);
        let c = ex * (p.1 - a.1) - ey * (p.0 - a.0);
        let dist = c / (ex * ex + ey * ey).sqrt();
        if dist.abs() < eps {
            return None;
        }
        if sign == 0.0 {
            sign = dist.signum();
        } else if dist.signum() != sign {
            return Some(false);
        }
    }
    Some(true)
}

#[test]
fn cube_head_on_covers_the_expected_square() {
    // Unit cube, eye 2.5 in front of its centre, 90 degree fov: the front face (depth 2)
    // spans [-0.25, 0.25] of the half-width, pixels [37.5, 62.5) on a 100 px image; by the
    // top-left rule the left and top edges (through pixel centres) are in, right and
    // bottom out: columns and rows 37..=61, 25 x 25 pixels, all of face 5 (+z).
    let scene = demo::cube();
    let cam = Camera::perspective(
        DVec3::new(0., 0., 2.5),
        DVec3::ZERO,
        DVec3::Y,
        90.0,
        0.1,
        10.0,
    );
    let f = zbuffer(&scene, &cam, 100, 100, &PrepareOptions::default());
    for j in 0..100 {
        for i in 0..100 {
            let inside = (37..=61).contains(&i) && (37..=61).contains(&j);
            assert_eq!(
                f.id(i, j),
                if inside { 5 } else { BACKGROUND },
                "pixel {i},{j}"
            );
            if inside {
                assert!((f.depth[f.index(i, j)] - 2.0).abs() < 1e-5);
            }
        }
    }
}

/// A face id, its projected polygon and whether it faces the camera.
type ProjectedFace = (u32, Vec<(f64, f64)>, bool);

#[test]
fn cube_from_known_cameras_covers_the_projected_faces() {
    // For several cameras, project each face of the cube with the textbook formulas and
    // check, pixel by pixel, that the frame shows a face whose projection contains the
    // pixel centre and is front-facing, and background outside the silhouette.
    let scene = demo::cube();
    let cube = &scene.objects()[0];
    let cams = [
        Camera::perspective(
            DVec3::new(1.7, 1.3, 2.2),
            DVec3::ZERO,
            DVec3::Y,
            50.0,
            0.1,
            10.0,
        ),
        Camera::perspective(
            DVec3::new(-2.0, -1.1, 1.5),
            DVec3::new(0.1, 0.0, -0.1),
            DVec3::Y,
            70.0,
            0.5,
            8.0,
        ),
        Camera::orthographic(
            DVec3::new(2.0, 2.5, -3.0),
            DVec3::ZERO,
            DVec3::Y,
            2.5,
            0.1,
            10.0,
        ),
        Camera::perspective(
            DVec3::new(0.3, 3.0, 0.2),
            DVec3::ZERO,
            DVec3::Z,
            60.0,
            0.1,
            10.0,
        ),
    ];
    let (w, h) = (96u32, 72u32);
    for cam in cams {
        let f = zbuffer(&scene, &cam, w, h, &PrepareOptions::default());
        let (right, up, fwd) = cam.basis();
        let _ = (right, up);
        let faces: Vec<ProjectedFace> = (0..6)
            .map(|p| {
                let pts = cube.world_polygon(p);
                let n = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
                let to_eye = match cam.projection {
                    obscura::Projection::Perspective { .. } => cam.eye - pts[0],
                    obscura::Projection::Orthographic { .. } => -fwd,
                };
                let front = n.dot(to_eye) > 0.0;
                (
                    p as u32,
                    pts.iter()
                        .map(|&q| project(&cam, f64::from(w), f64::from(h), q))
                        .collect(),
                    front,
                )
            })
            .collect();
        let mut checked = 0;
        for j in 0..h {
            for i in 0..w {
                let c = (f64::from(i) + 0.5, f64::from(j) + 0.5);
                let mut containing = Vec::new();
                let mut ambiguous = false;
                for (id, poly, front) in &faces {
                    if !front {
                        continue;
                    }
                    match inside_convex(poly, c, 1e-6) {
                        Some(true) => containing.push(*id),
                        Some(false) => {}
                        None => ambiguous = true,
                    }
                }
                if ambiguous {
                    continue;
                }
                checked += 1;
                let got = f.id(i, j);
                match containing.as_slice() {
                    [] => assert_eq!(got, BACKGROUND, "pixel {i},{j} should be background"),
                    [only] => assert_eq!(got, *only, "pixel {i},{j}"),
                    more => panic!("front faces of a convex solid overlap at {i},{j}: {more:?}"),
                }
            }
        }
        assert!(checked > (w * h) as usize * 9 / 10);
    }
}

#[test]
fn backface_culling_removes_exactly_the_faces_facing_away() {
    // Count, in world space, the faces whose outward normal has the eye strictly on its
    // positive side; the pipeline's back-face stage must keep exactly those.
    let meshes = [
        ("sphere", demo::uv_sphere_mesh(1.0, 24, 12), DMat4::IDENTITY),
        (
            "torus",
            demo::torus_mesh(1.0, 0.35, 20, 10),
            DMat4::from_rotation_x(0.7),
        ),
        (
            "cone",
            demo::cone_mesh(0.8, 1.5, 17),
            DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)),
        ),
    ];
    let eyes = [
        DVec3::new(0.3, 0.4, 3.0),
        DVec3::new(-2.5, 1.2, -0.7),
        DVec3::new(0.05, -3.1, 0.2),
    ];
    for (name, mesh, transform) in meshes {
        let mut scene = Scene::new();
        scene
            .add(ObjectDesc::new(name, mesh).with_transform(transform))
            .unwrap();
        let o = &scene.objects()[0];
        assert!(o.closed, "{name} must be detected closed");
        for eye in eyes {
            let cam = Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 60.0, 0.01, 100.0);
            let vp = Viewport::new(32, 32).unwrap();
            let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
            let stage = view.stats().stage("faces: back-face culling").unwrap();
            assert_eq!(stage.unit, "faces");
            let expected = (0..o.mesh.polygon_count())
                .filter(|&p| {
                    let pts = o.world_polygon(p);
                    // A mirroring transform reverses the winding: the outward normal flips.
                    let n =
                        obscura::geom::newell_normal(&pts) * if o.mirrored { -1.0 } else { 1.0 };
                    n.dot(eye - pts[0]) > 1e-12
                })
                .count();
            assert_eq!(stage.input as usize, o.mesh.polygon_count());
            assert_eq!(stage.output as usize, expected, "{name} from {eye}");
            // Off: nothing is culled.
            let off = prepare(
                &scene,
                &cam,
                vp,
                &PrepareOptions::default().with_backface(BackfaceMode::Off),
            )
            .unwrap();
            assert_eq!(
                off.stats()
                    .stage("faces: back-face culling")
                    .unwrap()
                    .output as usize,
                o.mesh.polygon_count()
            );
        }
    }
}

#[test]
fn open_meshes_keep_their_back_faces_unless_told() {
    let mut scene = Scene::new();
    scene
        .add(ObjectDesc::new("sheet", demo::grid_mesh(2.0, 2.0, 4, 4)))
        .unwrap();
    assert!(!scene.objects()[0].closed);
    // Seen from below: every face faces away.
    let cam = Camera::perspective(
        DVec3::new(0.0, -3.0, 0.1),
        DVec3::ZERO,
        DVec3::Y,
        60.0,
        0.1,
        10.0,
    );
    let vp = Viewport::new(40, 40).unwrap();
    let shown = zbuffer(&scene, &cam, 40, 40, &PrepareOptions::default());
    assert!(shown.covered_pixels() > 100);
    let all = prepare(
        &scene,
        &cam,
        vp,
        &PrepareOptions::default().with_backface(BackfaceMode::All),
    )
    .unwrap();
    assert_eq!(all.polygon_count(), 0);
}

#[test]
fn camera_inside_a_closed_object() {
    // From inside a closed cube every face is a back face: culled by default (nothing is
    // seen, no panic), visible with back-face culling off.
    let scene = demo::cube();
    let cam = Camera::perspective(
        DVec3::new(0.1, 0.05, 0.2),
        DVec3::new(0.1, 0.05, -1.0),
        DVec3::Y,
        90.0,
        0.01,
        10.0,
    );
    let culled = zbuffer(&scene, &cam, 32, 32, &PrepareOptions::default());
    assert_eq!(culled.covered_pixels(), 0);
    let seen = zbuffer(
        &scene,
        &cam,
        32,
        32,
        &PrepareOptions::default().with_backface(BackfaceMode::Off),
    );
    assert_eq!(seen.covered_pixels(), 32 * 32);
    // Looking down -z from inside, the centre pixel shows the -z face (id 4) at depth 0.7.
    assert_eq!(seen.id(16, 16), 4);
    assert!((seen.depth[seen.index(16, 16)] - 0.7).abs() < 1e-5);
}

#[test]
fn floor_crossing_the_eye_plane_shows_the_exact_horizon() {
    // An open floor y = 0 of 2000 x 2000 around an eye at height 1 looking along -z: the
    // floor extends behind the eye (w <= 0), so it must be clipped before the divide.
    // Pixel row j is floor iff its centre ray goes down and meets the floor before `far`.
    let mut scene = Scene::new();
    scene
        .add(ObjectDesc::new(
            "floor",
            demo::grid_mesh(2000.0, 2000.0, 1, 1),
        ))
        .unwrap();
    let (w, h) = (64u32, 48u32);
    let far = 50.0;
    let cam = Camera::perspective(
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 1.0, -1.0),
        DVec3::Y,
        60.0,
        0.1,
        far,
    );
    let f = zbuffer(&scene, &cam, w, h, &PrepareOptions::default());
    let t = (30f64).to_radians().tan();
    for j in 0..h {
        let ny = 1.0 - 2.0 * (f64::from(j) + 0.5) / f64::from(h); // ray slope at depth 1
        for i in 0..w {
            let nx = 2.0 * (f64::from(i) + 0.5) / f64::from(w) - 1.0;
            let dir_y = ny * t;
            // depth of the hit along -z: 1 / -dir_y
            let expected = dir_y < 0.0 && 1.0 / -dir_y <= far;
            let margin = ((1.0 / -dir_y) - far).abs() > 1e-3 * far;
            if !margin {
                continue;
            }
            let _ = nx;
            assert_eq!(f.id(i, j) != BACKGROUND, expected, "pixel {i},{j}");
            if expected {
                let d = f64::from(f.depth[f.index(i, j)]);
                assert!((d - 1.0 / -dir_y).abs() < 1e-4 * d, "depth at {i},{j}: {d}");
            }
        }
    }
}

#[test]
fn frustum_culling_of_objects_changes_nothing_but_the_work() {
    let scene = demo::city(12, 12, 3);
    let cam = Camera::perspective(
        DVec3::new(3.0, 2.0, 3.0),
        DVec3::new(-2.0, 0.5, -1.0),
        DVec3::Y,
        40.0,
        0.1,
        40.0,
    );
    let vp = Viewport::new(120, 90).unwrap();
    let on = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let mut no_cull = PrepareOptions::default();
    no_cull.frustum_cull_objects = false;
    let off = prepare(&scene, &cam, vp, &no_cull).unwrap();
    let objects = on.stats().stage("objects: frustum").unwrap();
    assert!(
        objects.output < objects.input,
        "some buildings are outside the view"
    );
    let a = render(Algorithm::ZBuffer, &on, &RenderOptions::default())
        .unwrap()
        .0;
    let b = render(Algorithm::ZBuffer, &off, &RenderOptions::default())
        .unwrap()
        .0;
    assert_eq!(a.ids, b.ids);
}

/// A unit cube at the origin, the scene of the bad-input tests below.
fn unit_cube_scene() -> Scene {
    let mut s = Scene::new();
    s.add(ObjectDesc::new(
        "cube",
        demo::box_mesh(DVec3::splat(-1.0), DVec3::ONE),
    ))
    .unwrap();
    s
}

#[test]
fn viewports_built_by_hand_are_checked_by_prepare() {
    let s = unit_cube_scene();
    let cam = s.default_camera(1.0);
    for (w, h) in [(0, 5), (5, 0), (16385, 1), (u32::MAX, u32::MAX)] {
        let vp = Viewport {
            width: w,
            height: h,
        };
        let e = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap_err();
        assert!(
            matches!(e, obscura::Error::InvalidViewport { .. }),
            "{w}x{h}: {e}"
        );
        assert!(Frame::new(vp).is_err(), "{w}x{h}");
    }
}

#[test]
fn cameras_beyond_the_single_precision_range_are_refused() {
    let ok = Camera::perspective(
        DVec3::new(2., 1.5, 4.),
        DVec3::ZERO,
        DVec3::Y,
        60.0,
        0.1,
        10.0,
    );
    assert!(ok.validate().is_ok());
    let refused = |c: Camera, needle: &str| {
        let e = c.validate().unwrap_err().to_string();
        assert!(e.contains(needle), "{e} should mention {needle}");
    };
    // Depth keys near / depth in f32: near 1e-300 gave NaN depths, 1e-44 wrong ones.
    for near in [1e-300, 1e-44, 1e-31] {
        refused(Camera { near, ..ok }, "too small");
    }
    // The smallest accepted near for far 10: far / near = 1e30.
    assert!(Camera { near: 1e-29, ..ok }.validate().is_ok());
    refused(
        Camera {
            eye: DVec3::new(2e31, 0.0, 0.0),
            ..ok
        },
        "beyond the largest coordinate",
    );
    refused(
        Camera {
            near: 1.0,
            far: 1e31,
            ..ok
        },
        "beyond the largest distance",
    );
    let ortho = |height: f64, near: f64, far: f64| {
        Camera::orthographic(
            DVec3::new(0., 0., 5.),
            DVec3::ZERO,
            DVec3::Y,
            height,
            near,
            far,
        )
    };
    refused(ortho(4.0, -1e300, 1e300), "beyond the largest distance");
    // Directions from the eye are not resolved below about 1e-16 radians: a pixel
    // must span 64 times that (1e-13 degrees over 64 rows, 1e-9 over 10,000 rows).
    for (fov, rows) in [(1e-13, 64), (1e-9, 10_000), (1e-12, 2)] {
        let narrow = Camera::perspective(ok.eye, ok.target, ok.up, fov, 0.1, 10.0);
        assert!(narrow.validate().is_ok());
        let vp = Viewport::new(rows, rows).unwrap();
        let e = narrow.validate_for(vp).unwrap_err().to_string();
        assert!(e.contains("smallest accepted"), "{e}");
        let scene = unit_cube_scene();
        let view = prepare(&scene, &narrow, vp, &PrepareOptions::default());
        assert!(view.is_err(), "fov {fov} over {rows} rows");
    }
    let fine = Camera::perspective(ok.eye, ok.target, ok.up, 1e-10, 0.1, 10.0);
    assert!(fine.validate_for(Viewport::new(64, 64).unwrap()).is_ok());
    refused(ortho(1e39, 0.1, 100.0), "height");
}

#[test]
fn very_narrow_views_give_every_image_space_algorithm_the_z_buffer_image() {
    // An orthographic window 1e-12 high: the polygons' eye-space extents are about
    // 1e-12 at coordinates about 4, so their areas are below 1e-24 of their
    // coordinates squared. Depth sort used to find no plane for them and drew nothing.
    // Also the narrowest perspective view accepted (16 rows).
    let narrowest = (Camera::MIN_PIXEL_ANGLE * 16.0 * 1.01).to_degrees();
    let s = unit_cube_scene();
    let (eye, target) = (DVec3::new(2., 1.5, 4.), DVec3::new(0.1, 0.2, 0.3));
    for cam in [
        Camera::orthographic(eye, target, DVec3::Y, 1e-12, 0.1, 100.0),
        Camera::orthographic(eye, target, DVec3::Y, 1e-13, 0.1, 100.0),
        Camera::perspective(eye, target, DVec3::Y, narrowest, 0.1, 100.0),
    ] {
        let vp = Viewport::new(24, 16).unwrap();
        let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
        let ro = RenderOptions::default();
        let z = render(Algorithm::ZBuffer, &view, &ro).unwrap().0;
        assert_eq!(z.covered_pixels(), 24 * 16, "{cam:?}");
        for a in [
            Algorithm::Scanline,
            Algorithm::DepthSort,
            Algorithm::DepthSortMatrix,
            Algorithm::Bsp,
            Algorithm::Warnock,
        ] {
            let f = render(a, &view, &ro).unwrap().0;
            assert_eq!(f.ids, z.ids, "{} with {cam:?}", a.name());
        }
    }
}

#[test]
fn objects_beyond_the_coordinate_range_or_not_affine_are_refused() {
    let cube = demo::box_mesh(DVec3::splat(-1.0), DVec3::ONE);
    let mut s = Scene::new();
    let huge = s
        .add(
            ObjectDesc::new("huge", cube.clone())
                .with_transform(DMat4::from_scale(DVec3::splat(1e31))),
        )
        .unwrap_err()
        .to_string();
    assert!(
        huge.contains("\"huge\"") && huge.contains("largest coordinate"),
        "{huge}"
    );
    let projective = DMat4::from_cols(
        glam::DVec4::X,
        glam::DVec4::Y,
        glam::DVec4::Z,
        glam::DVec4::new(0., 0., 0., -1.),
    );
    let e = s
        .add(ObjectDesc::new("projective", cube.clone()).with_transform(projective))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("\"projective\"") && e.contains("not affine"),
        "{e}"
    );
    // Just inside the limits: accepted.
    s.add(ObjectDesc::new("big", cube).with_transform(DMat4::from_scale(DVec3::splat(1e29))))
        .unwrap();
}

#[test]
fn an_object_inside_the_frustum_by_its_box_keeps_no_vertex_outside() {
    // A box whose front face lies on the near plane: its box corners pass the frustum
    // test, but its vertices, transformed in two steps, can round outside it. Every
    // polygon of the view must then have finite screen vertices.
    for z_front in [4.9, 4.9 - 1e-15, 4.9 + 1e-15] {
        let mut s = Scene::new();
        s.add(ObjectDesc::new(
            "box",
            demo::box_mesh(
                DVec3::new(-0.02, -0.02, -1.0),
                DVec3::new(0.02, 0.02, z_front),
            ),
        ))
        .unwrap();
        let cam = Camera::perspective(
            DVec3::new(0., 0., 5.),
            DVec3::ZERO,
            DVec3::Y,
            60.0,
            0.1,
            100.0,
        );
        let view = prepare(
            &s,
            &cam,
            Viewport::new(16, 16).unwrap(),
            &PrepareOptions::default(),
        )
        .unwrap();
        for poly in view.polygons() {
            for v in poly.vertices() {
                assert!(
                    v.x.is_finite() && v.y.is_finite() && v.zq.is_finite(),
                    "z {z_front}: face {} has vertex {v:?}",
                    poly.face
                );
            }
        }
        let (frame, _) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
        assert!(frame.depth.iter().all(|d| !d.is_nan()));
    }
}

#[test]
fn a_small_object_far_from_the_origin_is_framed_and_drawn() {
    // A unit triangle at y = 1e13: the default camera is a few units from it, which the
    // eye-on-target test once took for no direction (its threshold grew with |eye|).
    let mut s = Scene::new();
    s.add(triangle_at(DVec3::new(0.0, 1e13, 0.0))).unwrap();
    let vp = Viewport::new(64, 64).unwrap();
    let cam = s.default_camera(vp.aspect());
    assert!(cam.validate().is_ok(), "{cam:?}");
    let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
    let (frame, _) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
    assert!(frame.covered_pixels() > 100, "{}", frame.covered_pixels());
}

fn triangle_at(at: DVec3) -> ObjectDesc {
    let mut b = obscura::scene::MeshBuilder::new();
    for p in [at, at + DVec3::X, at + DVec3::Z] {
        b.push_position(p);
    }
    b.push_face(&[0, 1, 2], None).unwrap();
    ObjectDesc::new("far", b.finish().0)
}

/// Orthographic planes far wider than the scene: the depth keys span the objects'
/// depths, not `near..far`, so the image and the depths are those of planes fitted to
/// the scene. (Keys linear over `0.001..1e9` in `f32` have a step of 60 units: 1256 of
/// 3355 pixels of the demo scene took the wrong face, and every depth was 0.001; with
/// `-1e10..1e10` every depth was 0.)
#[test]
fn orthographic_depth_keys_span_the_scene_not_the_planes() {
    let scene = demo::default_scene();
    let (w, h) = (100, 80);
    let base = scene.default_camera(f64::from(w) / f64::from(h));
    let mut fitted = Camera::orthographic(base.eye, base.target, base.up, 8.0, 1.0, 2.0);
    fitted.fit_depth_range(&scene.bounds());
    let reference = zbuffer(&scene, &fitted, w, h, &PrepareOptions::default());
    let covered = reference.ids.iter().filter(|&&i| i != BACKGROUND).count();
    assert!(covered > 2000, "{covered}");
    for (near, far) in [(0.001, 1e9), (-1e10, 1e10), (fitted.near, 1e20)] {
        let wide = Camera {
            near,
            far,
            ..fitted
        };
        let frame = zbuffer(&scene, &wide, w, h, &PrepareOptions::default());
        let wrong = frame
            .ids
            .iter()
            .zip(&reference.ids)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            wrong <= 3,
            "near {near}, far {far}: {wrong} of {covered} pixels differ"
        );
        for (k, (&d, &r)) in frame.depth.iter().zip(&reference.depth).enumerate() {
            if frame.ids[k] != BACKGROUND && frame.ids[k] == reference.ids[k] {
                assert!(
                    d > 0.0 && (d - r).abs() <= 1e-5 * r,
                    "pixel {k}: {d} vs {r}"
                );
            }
        }
    }
}

/// A triangle with a vertex on a plane (or a corner) of the view volume: clipping there
/// made two points that differ by rounding, `(-5.6e-16, 0)` and `(-5.6e-16, -5.6e-16)`,
/// and the edge between them, of arbitrary direction, cut the pixels on one side of its
/// line out of the polygon: a pixel 0.14 pixel inside the triangle was lost by every
/// image-space algorithm, and only the ray casters drew it. (Found by differential
/// fuzzing on scenes whose coordinates are small dyadic numbers.)
#[test]
fn a_vertex_on_the_view_volume_boundary_loses_no_pixel() {
    let cases = [
        // A vertex on the corner of the top and left planes; pixel (2, 1).
        (
            [(2.25, 2.75, 2.5), (4.25, 2.75, -1.5), (4.25, 4.75, -2.5)],
            (
                DVec3::new(3.25, 1.75, 3.5),
                DVec3::new(3.25, 1.75, 0.0),
                0.4375,
                15.0,
            ),
            5,
            (2, 1),
        ),
        // A vertex on the top plane only; pixel (6, 2).
        (
            [(1.5, 3.0, -1.5), (2.0, 3.0, 3.0), (1.5, 3.5, 1.75)],
            (
                DVec3::new(2.0, 2.0, 4.0),
                DVec3::new(2.0, 2.0, 0.0),
                0.5,
                16.0,
            ),
            16,
            (6, 2),
        ),
    ];
    for (points, (eye, target, near, far), size, (i, j)) in cases {
        let mut scene = Scene::new();
        let mut b = obscura::scene::MeshBuilder::new();
        for (x, y, z) in points {
            b.push_position(DVec3::new(x, y, z));
        }
        b.push_face(&[0, 1, 2], None).unwrap();
        scene
            .add(ObjectDesc::new("t", b.finish().0).with_closed(false))
            .unwrap();
        let cam = Camera::perspective(eye, target, DVec3::Y, 90.0, near, far);
        let opts = PrepareOptions::default().with_backface(BackfaceMode::Off);
        let z = zbuffer(&scene, &cam, size, size, &opts);
        assert_eq!(z.ids[(j * size + i) as usize], 0, "pixel ({i}, {j})");
        let view = prepare(
            &scene,
            &cam,
            Viewport::new(u64::from(size), u64::from(size)).unwrap(),
            &opts,
        )
        .unwrap();
        let (ray, _) = render(Algorithm::Raycast, &view, &RenderOptions::default()).unwrap();
        assert_eq!(ray.ids, z.ids, "the ray caster's image");
    }
}

/// Orthographic windows whose pixels are finer than the rounding of the coordinates are
/// refused, naming the height: a window 1e-20 high over a unit cube drew a quarter of the
/// face that fills it, 1e-300 drew nothing, and one 1e-14 high seen from 10 units over
/// 4 rows made depth sort draw nothing. Windows just above the floor are drawn (see
/// `very_narrow_views_give_every_image_space_algorithm_the_z_buffer_image`).
#[test]
fn orthographic_windows_finer_than_the_coordinates_are_refused() {
    let s = unit_cube_scene();
    let refused = |eye: DVec3, height: f64, rows: u64| {
        let cam = Camera::orthographic(eye, DVec3::ZERO, DVec3::Y, height, 0.1, 100.0);
        let vp = Viewport::new(rows, rows).unwrap();
        prepare(&s, &cam, vp, &PrepareOptions::default())
            .err()
            .map(|e| e.to_string())
    };
    for (eye, height, rows) in [
        (DVec3::new(0.0, 0.0, 5.0), 1e-20, 64),
        (DVec3::new(0.0, 0.0, 5.0), 1e-300, 64),
        (DVec3::new(0.0, 0.0, 10.0), 1e-14, 4),
    ] {
        let e = refused(eye, height, rows).expect("refused");
        assert!(e.contains("orthographic height"), "{e}");
    }
    // The floor is 4 eps of the largest coordinate per pixel: 8.9e-15 from 10 units.
    let floor = 4.0 * f64::EPSILON * 10.0;
    let eye = DVec3::new(0.0, 0.0, 10.0);
    assert!(refused(eye, floor * 4.0 * 0.99, 4).is_some());
    assert_eq!(refused(eye, floor * 4.0 * 1.01, 4), None);
}

/// An up vector is a direction: its length does not matter. A zero one and one along
/// the view direction are refused with messages that say which; distances in messages
/// are written in scientific notation (a far plane of 1e300 was printed with 301 digits).
#[test]
fn camera_messages_say_what_is_wrong() {
    let s = unit_cube_scene();
    let vp = Viewport::new(32, 24).unwrap();
    let cam = |up: DVec3| {
        Camera::perspective(
            DVec3::new(0.5, 0.5, 5.0),
            DVec3::splat(0.5),
            up,
            40.0,
            1.0,
            10.0,
        )
    };
    let reference = zbuffer(
        &s,
        &cam(DVec3::new(1.0, 1.0, 0.0)),
        32,
        24,
        &PrepareOptions::default(),
    );
    assert!(reference.covered_pixels() > 100);
    for up in [DVec3::new(1e-10, 1e-10, 0.0), DVec3::new(1e300, 1e300, 0.0)] {
        let f = zbuffer(&s, &cam(up), 32, 24, &PrepareOptions::default());
        assert_eq!(f.ids, reference.ids, "up {up:?}");
    }
    let message = |c: Camera| {
        prepare(&s, &c, vp, &PrepareOptions::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    assert!(message(cam(DVec3::ZERO)).contains("up vector is zero"));
    let along = message(cam(DVec3::new(0.0, 0.0, -3.0)));
    assert!(along.contains("parallel to the view direction"), "{along}");
    let far = message(Camera {
        far: 1e300,
        ..cam(DVec3::Y)
    });
    assert!(far.contains("1e300") && far.len() < 200, "{far}");
}

/// A scene of one open polygon with the given vertices.
fn one_polygon(points: &[DVec3]) -> Scene {
    let mut b = obscura::scene::MeshBuilder::new();
    for &p in points {
        b.push_position(p);
    }
    let indices: Vec<u32> = (0..points.len() as u32).collect();
    b.push_face(&indices, None).unwrap();
    let mut s = Scene::new();
    s.add(ObjectDesc::new("polygon", b.finish().0).with_closed(false))
        .unwrap();
    s
}

/// Far from the origin, points reach eye space relative to the camera, so a scene and
/// camera moved together by an offset that keeps every coordinate exact (a power of two
/// here) give the same image and depths as at the origin. Through the single view
/// matrix (`R p - R eye`, two products of 1e13 cancelling) a unit triangle seen from 5
/// units moved by up to 1/7 pixel at 2^43: 7 of 256x256 pixels changed, and the ray
/// casters, which work relative to the eye, disagreed with the z-buffer there.
#[test]
fn a_scene_moved_far_from_the_origin_gives_the_same_image() {
    let points = [
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::new(1.0, -0.75, 0.25),
        DVec3::new(0.125, 1.0, -0.5),
    ];
    let vp = Viewport::new(256, 256).unwrap();
    let image = |e: i32| {
        let off = DVec3::new(2f64.powi(e), 0.0, 2f64.powi(e));
        let scene = one_polygon(&points.map(|p| p + off));
        let cam = Camera::perspective(
            DVec3::new(0.5, 0.25, 5.0) + off,
            off,
            DVec3::Y,
            40.0,
            1.0,
            10.0,
        );
        let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        let ro = RenderOptions::default();
        let zb = render(Algorithm::ZBuffer, &view, &ro).unwrap().0;
        let rc = render(Algorithm::Raycast, &view, &ro).unwrap().0;
        assert_eq!(rc.differences(&zb), vec![], "offset 2^{e}: ray casting");
        zb
    };
    let home = image(0);
    assert!(home.covered_pixels() > 8000, "{}", home.covered_pixels());
    for e in [30, 40, 43, 46] {
        let far = image(e);
        assert_eq!(far.differences(&home), vec![], "offset 2^{e}");
        let worst = far
            .depth
            .iter()
            .zip(&home.depth)
            .filter(|(a, _)| a.is_finite())
            .map(|(a, b)| (a - b).abs() / b)
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "offset 2^{e}: depths differ by {worst:e}");
    }
}

/// Object frustum culling far from the origin (differential-fuzz finding 11): a
/// triangle 1e11 across at 4e22, the camera 1e11 from it, far / near 1.3e8. The far
/// plane taken from the view-projection matrix's rows was off by 1e14 there, and the
/// object, which covers a pixel, was culled by its bounding sphere. Culling now tests
/// the volumes in eye space, relative to the camera.
#[test]
fn object_culling_far_from_the_origin_keeps_what_is_seen() {
    let scene = one_polygon(&[
        DVec3::new(
            -7.039483384069957e21,
            -5.175982482524232e21,
            -4.087648410817198e22,
        ),
        DVec3::new(
            -7.039483384004883e21,
            -5.175982482527743e21,
            -4.087648410829896e22,
        ),
        DVec3::new(
            -7.039483384015108e21,
            -5.175982482447298e21,
            -4.087648410818173e22,
        ),
    ]);
    let cam = Camera::perspective(
        DVec3::new(
            -7.039483383957134e21,
            -5.175982482597245e21,
            -4.087648410816534e22,
        ),
        DVec3::new(
            -7.039483383955459e21,
            -5.175982482593433e21,
            -4.087648410816394e22,
        ),
        DVec3::Y,
        144.64786508535303,
        31963.81071426129,
        4301384660725.959,
    );
    let vp = Viewport::new(3, 3).unwrap();
    let on = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    let mut no_cull = PrepareOptions::default();
    no_cull.frustum_cull_objects = false;
    let off = prepare(&scene, &cam, vp, &no_cull).unwrap();
    let ro = RenderOptions::default();
    let seen = render(Algorithm::ZBuffer, &off, &ro).unwrap().0;
    assert_eq!(seen.covered_pixels(), 1, "the triangle covers one pixel");
    assert_eq!(on.polygon_count(), 1);
    assert_eq!(
        render(Algorithm::ZBuffer, &on, &ro).unwrap().0.ids,
        seen.ids
    );
    for algo in [Algorithm::Bsp, Algorithm::Raycast] {
        let f = render(algo, &on, &ro).unwrap().0;
        assert_eq!(f.differences(&seen), vec![], "{algo}");
    }
}

/// A quad lying exactly on the near plane, seen head-on from the origin, for several
/// `near` and both projections: every exact algorithm draws all of it, as it draws the
/// same quad a little beyond the plane. The pipeline decided such a quad by the
/// rounding of its clip coordinates (dropped whole for `near` 0.5 and 1/3 in
/// perspective, 0.1 in parallel projection) and the ray casters by the rounding of
/// each pixel's `t` (they kept 1,070 to 1,676 of its pixels).
#[test]
fn a_polygon_on_the_near_plane_is_drawn_by_every_algorithm() {
    let corners = [(-0.37, -0.29), (0.41, -0.33), (0.39, 0.31), (-0.35, 0.27)];
    let vp = Viewport::new(64, 64).unwrap();
    for ortho in [false, true] {
        for near in [0.5, 0.1, 0.3, 1.0 / 3.0, 0.7, 1e-3, 10.0, 2.2] {
            let frame = |depth: f64| {
                // In perspective the quad grows with its depth, so that it covers the
                // same pixels at `near` and a little beyond.
                let s = if ortho { near } else { depth };
                let scene = one_polygon(&corners.map(|(x, y)| DVec3::new(x * s, y * s, -depth)));
                let cam = if ortho {
                    Camera::orthographic(DVec3::ZERO, -DVec3::Z, DVec3::Y, near, near, 100.0 * near)
                } else {
                    Camera::perspective(DVec3::ZERO, -DVec3::Z, DVec3::Y, 60.0, near, 100.0 * near)
                };
                let view = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
                let ro = RenderOptions::default();
                let zb = render(Algorithm::ZBuffer, &view, &ro).unwrap().0;
                for algo in Algorithm::ALL {
                    if algo.is_exact() {
                        let f = render(algo, &view, &ro).unwrap().0;
                        let d = f.differences(&zb);
                        assert!(
                            d.is_empty(),
                            "{algo}, near {near}, ortho {ortho}: {} pixels differ, first {:?}",
                            d.len(),
                            d.first()
                        );
                    }
                }
                zb.covered_pixels()
            };
            let (on, beyond) = (frame(near), frame(near * 1.001));
            assert!(beyond > 1000, "{beyond}");
            assert!(
                on.abs_diff(beyond) <= 8,
                "near {near}, ortho {ortho}: {on} vs {beyond}"
            );
        }
    }
}
