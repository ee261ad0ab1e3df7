//! The scene index and the view's decisions: every algorithm gives, through a
//! `SceneIndex` (structures built once) and a `View` (decisions made once), the very
//! picture of the per-call path; the view's back faces are the world-space rule; its
//! object culling changes no picture.

use glam::DVec3;
use obscura::scene::demo;
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::view::View;
use obscura::{Camera, PrepareOptions, Scene, SceneIndex, Viewport, prepare};

/// Cameras that see the scene partly: from inside its box looking along an axis (some
/// objects behind the eye, culled) and from outside it.
fn cameras(scene: &Scene) -> Vec<Camera> {
    let b = scene.bounds();
    let (c, e) = ((b.min + b.max) * 0.5, (b.max - b.min) * 0.5);
    let low = c - DVec3::new(0.0, 0.6 * e.y, 0.0);
    vec![
        Camera::perspective(
            low,
            low + DVec3::new(1.0, 0.1, 0.3),
            DVec3::Y,
            60.0,
            0.05,
            50.0 * e.length(),
        ),
        Camera::perspective(c + e * 2.5, c, DVec3::Y, 45.0, 0.05, 50.0 * e.length()),
    ]
}

fn scenes() -> Vec<(&'static str, Scene)> {
    vec![
        ("city", demo::city(5, 5, 3)),
        ("default", demo::default_scene()),
    ]
}

fn depth_bits(d: &[f32]) -> Vec<u32> {
    d.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn every_algorithm_gives_the_per_call_picture_through_the_index() {
    let vp = Viewport::new(64, 48).unwrap();
    let (po, ro) = (PrepareOptions::default(), RenderOptions::default());
    for (name, scene) in scenes() {
        let index = SceneIndex::new(&scene);
        for (c, cam) in cameras(&scene).iter().enumerate() {
            let prepared = prepare(&scene, cam, vp, &po).unwrap();
            let view = View::new(&scene, cam, vp, &po).unwrap();
            for a in Algorithm::ALL {
                let (old, _) = render(a, &prepared, &ro).unwrap();
                let (via_prepared, _) = index.render(&prepared, a, &ro).unwrap();
                let (via_view, _) = index.render_view(&view, a, &ro).unwrap();
                for (what, f) in [("prepared", &via_prepared), ("view", &via_view)] {
                    assert_eq!(old.ids, f.ids, "{name} camera {c} {a} via {what}: ids");
                    assert_eq!(
                        depth_bits(&old.depth),
                        depth_bits(&f.depth),
                        "{name} camera {c} {a} via {what}: depths"
                    );
                }
            }
        }
        let b = index.builds();
        assert_eq!(
            (b.triangles, b.bvh, b.bsp, b.octree),
            (1, 1, 1, 1),
            "{name}: one of each for every view and algorithm"
        );
    }
}

#[test]
fn the_views_back_faces_are_the_world_space_rule() {
    let vp = Viewport::new(64, 48).unwrap();
    let mut checked = (0, 0);
    for (name, scene) in scenes() {
        for cam in cameras(&scene) {
            let view = View::new(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
            let base = view.polygon_base();
            for (k, o) in scene.objects().iter().enumerate() {
                for p in 0..o.mesh.polygon_count() {
                    let got = view.back_facing()[base[k] as usize + p];
                    if !view.kept_objects()[k] || !o.closed {
                        assert!(!got, "{name}: object {k} is not culled by back faces");
                        continue;
                    }
                    // Newell's normal of the world-space polygon, against the eye.
                    let w: Vec<DVec3> = o
                        .mesh
                        .polygon(p)
                        .iter()
                        .map(|&i| o.transform.transform_point3(o.mesh.positions()[i as usize]))
                        .collect();
                    let mut n = DVec3::ZERO;
                    for (a, b) in w.iter().zip(w.iter().cycle().skip(1)) {
                        n += DVec3::new(
                            (a.y - b.y) * (a.z + b.z),
                            (a.z - b.z) * (a.x + b.x),
                            (a.x - b.x) * (a.y + b.y),
                        );
                    }
                    if o.mirrored {
                        n = -n;
                    }
                    let to_eye = cam.eye - w[0];
                    let dot = n.dot(to_eye);
                    if dot.abs() <= 1e-9 * n.length() * to_eye.length() {
                        continue; // edge-on within rounding: either answer is right
                    }
                    assert_eq!(got, dot < 0.0, "{name}: object {k} polygon {p}");
                    checked.0 += 1;
                    checked.1 += usize::from(got);
                }
            }
        }
    }
    assert!(checked.1 > 0 && checked.1 < checked.0, "{checked:?}");
}

#[test]
fn object_culling_changes_no_ray_cast_or_bsp_picture() {
    let vp = Viewport::new(64, 48).unwrap();
    let ro = RenderOptions::default();
    let mut culled = 0;
    for (name, scene) in scenes() {
        let index = SceneIndex::new(&scene);
        for cam in cameras(&scene) {
            let on = View::new(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
            let mut off_options = PrepareOptions::default();
            off_options.frustum_cull_objects = false;
            let off = View::new(&scene, &cam, vp, &off_options).unwrap();
            culled += on.kept_objects().iter().filter(|&&k| !k).count();
            assert!(
                off.kept_objects()
                    .iter()
                    .zip(scene.objects())
                    .all(|(&k, o)| k || o.mesh.polygon_count() == 0)
            );
            for a in [
                Algorithm::Raycast,
                Algorithm::RaycastBounds,
                Algorithm::RaycastBvh,
                Algorithm::RaycastGrid,
                Algorithm::Bsp,
            ] {
                let (x, _) = index.render_view(&on, a, &ro).unwrap();
                let (y, _) = index.render_view(&off, a, &ro).unwrap();
                assert_eq!(x.ids, y.ids, "{name} {a}");
            }
        }
    }
    assert!(culled > 0, "the cameras cull some objects");
}
