use glam::DVec3;

use super::*;
use crate::cull::backface::BackfaceMode;
use crate::scene::demo;
use crate::scene::{Camera, Scene, Viewport};

#[test]
fn cube_from_the_front_shows_one_face_filling_the_expected_square() {
    let scene = demo::cube();
    let vp = Viewport::new(100, 100).unwrap();
    // Unit cube, eye at z = 2.5: the front face (z = 0.5) is at depth 2, and with a
    // 90 degree fov it spans +-0.5/2 of the half-width 1: pixels 37.5 .. 62.5.
    let cam = Camera::perspective(
        DVec3::new(0., 0., 2.5),
        DVec3::ZERO,
        DVec3::Y,
        90.0,
        0.1,
        10.0,
    );
    let v = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
    assert_eq!(v.polygon_count(), 1);
    let p = v.polygon(0);
    assert_eq!(p.face, 5);
    for vert in p.vertices() {
        assert!((vert.x - 37.5).abs() < 1e-9 || (vert.x - 62.5).abs() < 1e-9);
        assert!((vert.depth() - 2.0).abs() < 1e-12);
        assert!((vert.zq - 0.1 / 2.0).abs() < 1e-15);
    }
    let culling = v.stats().stage("faces: back-face culling").unwrap();
    assert_eq!(culling.input, 6);
    assert_eq!(culling.output, 1);
    // Several stages start with "faces:": a name must pick one.
    assert!(v.stats().stage("faces:").is_none());
    assert!(v.stats().stage("no such stage").is_none());
}

#[test]
fn faces_crossing_the_eye_plane_are_clipped_at_near() {
    // A big floor under the eye extends behind it: clipping must keep only w > 0.
    let mut s = Scene::new();
    s.add(crate::scene::ObjectDesc::new(
        "floor",
        demo::grid_mesh(100.0, 100.0, 1, 1),
    ))
    .unwrap();
    let cam = Camera::perspective(
        DVec3::new(0., 1., 0.),
        DVec3::new(0., 1., -1.),
        DVec3::Y,
        60.0,
        0.1,
        1000.0,
    );
    let v = prepare(
        &s,
        &cam,
        Viewport::new(64, 64).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap();
    assert_eq!(v.polygon_count(), 1);
    for vert in v.polygon(0).vertices() {
        assert!(vert.depth() >= 0.1 - 1e-9);
        assert!(vert.x.is_finite() && vert.y.is_finite());
        assert!(
            vert.x >= -1e-9
                && vert.x <= 64.0 + 1e-9
                && vert.y >= 32.0 - 1e-9
                && vert.y <= 64.0 + 1e-9
        );
    }
}

fn same_view(a: &PreparedView<'_>, b: &PreparedView<'_>, what: &str) {
    let bits = |v: &ViewVertex| [v.x, v.y, v.zq, v.eye.x, v.eye.y, v.eye.z].map(f64::to_bits);
    assert_eq!(a.vertices().len(), b.vertices().len(), "{what}");
    assert!(
        a.vertices()
            .iter()
            .zip(b.vertices())
            .all(|(p, q)| bits(p) == bits(q)),
        "{what}: vertices differ"
    );
    assert_eq!(a.polygon_arrays(), b.polygon_arrays(), "{what}");
    let objects = |v: &PreparedView<'_>| v.polygons().map(|p| p.object).collect::<Vec<_>>();
    assert_eq!(objects(a), objects(b), "{what}");
    // The per-view decisions every algorithm reads: the same objects kept and the same
    // back faces as the stage-per-pass pipeline's inline tests.
    assert_eq!(a.kept_objects(), b.kept_objects(), "{what}: kept objects");
    assert_eq!(a.polygon_base(), b.polygon_base(), "{what}");
    assert_eq!(a.back_facing(), b.back_facing(), "{what}: back faces");
    let counts = |v: &PreparedView<'_>| {
        v.stats()
            .stages
            .iter()
            .map(|s| (s.unit, s.input, s.output))
            .collect::<Vec<_>>()
    };
    assert_eq!(counts(a), counts(b), "{what}");
}

#[test]
fn fused_passes_equal_the_stage_per_pass_pipeline() {
    use crate::scene::random::{mirrored, orbit_cameras, random_triangles};
    // Big enough (more than PARALLEL_MIN faces and vertices) for the parallel passes.
    let scenes = [
        ("triangles", random_triangles(25_000, 3, 1.0, 0.05)),
        ("city", demo::city(60, 60, 4)),
        ("mirrored city", mirrored(&demo::city(12, 12, 5))),
        ("sphere", demo::sphere(160, 80)),
        ("default", demo::default_scene()),
    ];
    let mut clipped = 0;
    for (name, scene) in &scenes {
        for (ci, cam) in orbit_cameras(scene, 2, 17).iter().enumerate() {
            let vp = Viewport::new(200, 150).unwrap();
            for backface in [BackfaceMode::Closed, BackfaceMode::All, BackfaceMode::Off] {
                let opts = PrepareOptions::default().with_backface(backface);
                let expect = reference::prepare_reference(scene, cam, vp, &opts).unwrap();
                clipped += expect.stats.stage("faces: clip").unwrap().output;
                for threads in [1, 2, 3] {
                    #[cfg(feature = "parallel")]
                    let got = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads)
                        .build()
                        .unwrap()
                        .install(|| prepare(scene, cam, vp, &opts).unwrap());
                    #[cfg(not(feature = "parallel"))]
                    let got = prepare(scene, cam, vp, &opts).unwrap();
                    same_view(
                        &got,
                        &expect,
                        &format!("{name} camera {ci} {backface:?} {threads}"),
                    );
                }
            }
        }
    }
    assert!(clipped > 100, "the close cameras must clip: {clipped}");
}

#[test]
fn empty_scene_gives_empty_view() {
    let s = Scene::new();
    let cam = Camera::perspective(DVec3::Z, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 10.0);
    let v = prepare(
        &s,
        &cam,
        Viewport::new(8, 8).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap();
    assert_eq!(v.polygon_count(), 0);
}
