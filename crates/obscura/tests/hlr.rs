//! Exact hidden-line removal (`lines::hlr`): analytic cases (the cube, two
//! interpenetrating triangles) and a sampling oracle independent of the cutting code.
//!
//! The oracle: along every piece, points away from its ends are checked by casting the
//! ray from the eye (or, orthographic, from the near plane along the view direction)
//! through them against every triangle of the scene with the shared watertight test,
//! brute force; the faces hit strictly before the point (the view's culled polygons and
//! the edge's own faces left out, a face counted once) must number exactly the piece's
//! quantitative invisibility.

use std::collections::HashSet;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

use glam::{DMat4, DVec3};
use obscura::accel::triangles::{PrimaryRays, WatertightRay};
use obscura::bench_support::SplitMix64;
use obscura::index::SceneIndex;
use obscura::lines::hlr::{self, HlrOptions};
use obscura::lines::{Drawing, EdgeKinds};
use obscura::scene::{Faces, ObjectDesc, Scene, demo};
use obscura::view::{PrepareOptions, View};
use obscura::{Camera, Error, Viewport};

fn options() -> HlrOptions {
    let mut o = HlrOptions::default();
    o.edges.kinds = EdgeKinds::ALL;
    o
}

fn draw<'s>(scene: &'s Scene, camera: &Camera, w: u64, h: u64) -> (Drawing, View<'s>) {
    let index = SceneIndex::new(scene);
    let view = View::new(
        scene,
        camera,
        Viewport::new(w, h).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap();
    let (d, stats) = hlr::draw(&index, &view, &options()).unwrap();
    assert_eq!(stats.pieces as usize, d.pieces.len());
    (d, view)
}

/// The drawing's own promises: pieces grouped by edge in increasing t, contiguous,
/// neighbours of different invisibility, inside [0, 1], ends where the camera's ray
/// through the pixel meets the 3D point.
fn check_structure(d: &Drawing, camera: &Camera, vp: Viewport) {
    for w in d.pieces.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        assert!(a.edge <= b.edge, "grouped by edge");
        if a.edge == b.edge {
            assert!(a.t[1] <= b.t[0], "increasing t");
            if a.t[1] == b.t[0] {
                assert_ne!(a.invisibility, b.invisibility, "equal neighbours merged");
            }
        }
    }
    for p in &d.pieces {
        assert!(
            0.0 <= p.t[0] && p.t[0] < p.t[1] && p.t[1] <= 1.0,
            "{:?}",
            p.t
        );
        let e = &d.edges[p.edge as usize];
        for k in 0..2 {
            let x = e.point(p.t[k]);
            let ray = camera.ray(vp, p.points[k].x, p.points[k].y);
            let to = x - ray.origin;
            let off = to.cross(ray.direction.normalize()).length();
            assert!(
                off <= 1e-7 * (1.0 + to.length()),
                "pixel of t off the ray by {off}"
            );
        }
    }
}

/// Quantitative invisibility at world point `x` by brute-force ray casting.
struct Oracle<'a> {
    tris: Vec<([DVec3; 3], u32, u32)>, // triangle, polygon, face
    camera: &'a Camera,
    rays: PrimaryRays,
    ignored: Vec<bool>,
}

impl<'a> Oracle<'a> {
    fn new(scene: &Scene, view: &View<'_>, camera: &'a Camera) -> Self {
        let index = SceneIndex::new(scene);
        let t = index.triangles();
        let tris = t
            .vertices()
            .iter()
            .zip(t.triangle_polygons())
            .map(|(v, &p)| (*v, p, t.polygon_faces()[p as usize]))
            .collect();
        Oracle {
            tris,
            camera,
            rays: PrimaryRays::new(camera, view.viewport()),
            ignored: view.culled_polygons(),
        }
    }

    fn count(&self, x: DVec3, own: [Option<u32>; 2]) -> u32 {
        let (_, _, forward) = self.camera.basis();
        let depth = (x - self.camera.eye).dot(forward);
        let orthographic = matches!(
            self.camera.projection,
            obscura::scene::Projection::Orthographic { .. }
        );
        let (origin, dir, t_min) = if orthographic {
            let back = forward * (depth - self.camera.near);
            (x - back, back, 0.0)
        } else {
            (
                self.camera.eye,
                x - self.camera.eye,
                self.camera.near / depth,
            )
        };
        let ray = WatertightRay::new(origin, dir).unwrap();
        let tie = self.rays.tie_rule();
        let mut faces = HashSet::new();
        for (tri, p, f) in &self.tris {
            if self.ignored[*p as usize] || own.contains(&Some(*p)) {
                continue;
            }
            if ray.intersect_any(tri, t_min, 1.0 - 1e-7, &tie).is_some() {
                faces.insert(*f);
            }
        }
        faces.len() as u32
    }

    /// The largest count among rays through points a hair beside `x` (1e-9 of its
    /// distance, in the four image directions).
    fn count_beside(&self, x: DVec3, own: [Option<u32>; 2]) -> u32 {
        let (right, up, _) = self.camera.basis();
        let h = 1e-9 * (x - self.camera.eye).length().max(1.0);
        [right, -right, up, -up]
            .iter()
            .map(|d| self.count(x + *d * h, own))
            .max()
            .unwrap_or(0)
    }
}

/// Samples five points inside every piece longer than a thousandth of a pixel and
/// returns the disagreements with the oracle (and the number of samples).
fn oracle_mismatches(scene: &Scene, camera: &Camera, w: u64, h: u64) -> (usize, usize, Drawing) {
    let (d, view) = draw(scene, camera, w, h);
    check_structure(&d, camera, view.viewport());
    let oracle = Oracle::new(scene, &view, camera);
    let (mut bad, mut samples) = (0, 0);
    for p in &d.pieces {
        if p.length() < 1e-3 {
            continue;
        }
        let e = &d.edges[p.edge as usize];
        for f in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let t = p.t[0] + (p.t[1] - p.t[0]) * f;
            let x = e.point(t);
            let got = oracle.count(x, e.faces);
            samples += 1;
            // A point whose image lies exactly on an occluder's boundary (an edge
            // exactly behind a drawn edge) is covered by that occluder (closed
            // coverage), where a single ray may pass beside it: there the count just
            // beside the point, on the occluder's side, is the expected one.
            if got != p.invisibility && oracle.count_beside(x, e.faces) != p.invisibility {
                bad += 1;
                if bad <= 5 {
                    eprintln!(
                        "edge {} {:?} t {t} piece {:?} invisibility {} oracle {got} camera {:?}",
                        p.edge, e.world, p.t, p.invisibility, camera
                    );
                }
            }
        }
    }
    (bad, samples, d)
}

fn assert_oracle(scene: &Scene, camera: &Camera, w: u64, h: u64) -> Drawing {
    let (bad, samples, d) = oracle_mismatches(scene, camera, w, h);
    assert!(samples > 0, "nothing sampled");
    assert_eq!(
        bad, 0,
        "{bad} of {samples} samples disagree with ray casting"
    );
    d
}

fn persp(eye: DVec3, target: DVec3) -> Camera {
    Camera::perspective(eye, target, DVec3::Y, 45.0, 0.1, 100.0)
}

fn ortho(eye: DVec3, target: DVec3, height: f64) -> Camera {
    Camera::orthographic(eye, target, DVec3::Y, height, 0.1, 100.0)
}

fn scene_of(objects: Vec<(obscura::scene::Mesh, DMat4, bool)>) -> Scene {
    let mut s = Scene::new();
    for (k, (m, t, closed)) in objects.into_iter().enumerate() {
        s.add(
            ObjectDesc::new(format!("o{k}"), m)
                .with_transform(t)
                .with_closed(closed),
        )
        .unwrap();
    }
    s
}

#[test]
fn isometric_cube_shows_nine_edges_and_hides_three() {
    let scene = demo::cube();
    for camera in [
        persp(DVec3::splat(3.0), DVec3::ZERO),
        ortho(DVec3::splat(3.0), DVec3::ZERO, 3.0),
    ] {
        let (d, view) = draw(&scene, &camera, 300, 300);
        check_structure(&d, &camera, view.viewport());
        assert_eq!(d.edges.len(), 12);
        assert_eq!(d.pieces.len(), 12, "one piece per edge: {:?}", d.pieces);
        for p in &d.pieces {
            assert_eq!(p.t, [0.0, 1.0]);
            let e = &d.edges[p.edge as usize];
            // The three edges at the far corner (-0.5, -0.5, -0.5) are hidden.
            let far = e.world.iter().any(|w| *w == DVec3::splat(-0.5));
            assert_eq!(p.invisibility, u32::from(far), "edge {:?}", e.world);
        }
        assert_eq!(d.visible().count(), 9);
        assert_eq!(d.hidden().count(), 3);
    }
}

/// T1 lies in the plane y = 0, T2 in the plane z = 0 and passes through it; seen from
/// (0, 3, 6). The cut points follow from the geometry by hand (see each comment).
#[test]
fn interpenetrating_triangles_are_cut_where_they_pierce_and_hide() {
    let p = [
        [-2.0, 0.0, -1.0],
        [2.0, 0.0, -1.0],
        [0.0, 0.0, 2.0],
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [0.0, 2.0, 0.0],
    ];
    let scene = Scene::from_arrays(&p, Faces::Triangles(&[[0, 1, 2], [3, 4, 5]])).unwrap();
    let camera = persp(DVec3::new(0.0, 3.0, 6.0), DVec3::ZERO);
    let (d, view) = draw(&scene, &camera, 400, 300);
    check_structure(&d, &camera, view.viewport());
    let pieces_of = |a: [f64; 3], b: [f64; 3]| -> Vec<([f64; 2], u32)> {
        let (a, b) = (DVec3::from(a), DVec3::from(b));
        let k = d
            .edges
            .iter()
            .position(|e| e.world == [a, b] || e.world == [b, a])
            .expect("edge drawn");
        let flip = d.edges[k].world[0] != a;
        let mut v: Vec<([f64; 2], u32)> = d
            .pieces
            .iter()
            .filter(|p| p.edge as usize == k)
            .map(|p| {
                if flip {
                    ([1.0 - p.t[1], 1.0 - p.t[0]], p.invisibility)
                } else {
                    (p.t, p.invisibility)
                }
            })
            .collect();
        v.sort_by(|x, y| x.0[0].total_cmp(&y.0[0]));
        v
    };
    let close = |got: &[([f64; 2], u32)], want: &[([f64; 2], u32)]| {
        assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
        for (g, w) in got.iter().zip(want) {
            assert_eq!(g.1, w.1, "{got:?} vs {want:?}");
            assert!(
                (g.0[0] - w.0[0]).abs() < 1e-9 && (g.0[1] - w.0[1]).abs() < 1e-9,
                "{got:?} vs {want:?}"
            );
        }
    };
    // T2's slanted edges pierce y = 0 at t = 1/3; below, the ray to the point crosses T1
    // until it leaves T1 through the line 3x - 2z = -4 (resp. 3x + 2z = 4): t = 5/33.
    let pierced = [
        ([0.0, 5.0 / 33.0], 0),
        ([5.0 / 33.0, 1.0 / 3.0], 1),
        ([1.0 / 3.0, 1.0], 0),
    ];
    close(&pieces_of(p[3], p[5]), &pierced);
    close(&pieces_of(p[4], p[5]), &pierced);
    // T2's bottom edge (y = -1): rays meet y = 0 at (0.75 x, 0, 1.5), inside T1 for
    // |x| < 4/9, that is t in (5/18, 13/18).
    close(
        &pieces_of(p[3], p[4]),
        &[
            ([0.0, 5.0 / 18.0], 0),
            ([5.0 / 18.0, 13.0 / 18.0], 1),
            ([13.0 / 18.0, 1.0], 0),
        ],
    );
    // T1's far edge (z = -1): rays meet z = 0 at (6x/7, 3/7, 0), inside T2 for
    // |x| < 11/18, that is t in (25/72, 47/72).
    close(
        &pieces_of(p[0], p[1]),
        &[
            ([0.0, 25.0 / 72.0], 0),
            ([25.0 / 72.0, 47.0 / 72.0], 1),
            ([47.0 / 72.0, 1.0], 0),
        ],
    );
    // T1's two other edges pass beside T2 (they cross z = 0 at |x| = 4/3 > 2/3).
    close(&pieces_of(p[0], p[2]), &[([0.0, 1.0], 0)]);
    close(&pieces_of(p[1], p[2]), &[([0.0, 1.0], 0)]);
    assert_oracle(&scene, &camera, 400, 300);
}

#[test]
fn an_edge_behind_a_drawn_edge_is_hidden() {
    // Two unit squares facing the camera (+z), the second 1 behind the first and offset
    // so that its top edge lies exactly behind the first one's top edge in an
    // orthographic view along -z.
    let p = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.25, 1.0, -1.0],
        [0.75, 1.0, -1.0],
        [0.75, 2.0, -1.0],
        [0.25, 2.0, -1.0],
    ];
    let offsets = [0, 4, 8];
    let indices = [0, 1, 2, 3, 4, 5, 6, 7];
    let scene = Scene::from_arrays(
        &p,
        Faces::Polygons {
            offsets: &offsets,
            indices: &indices,
        },
    )
    .unwrap();
    let camera = ortho(DVec3::new(0.5, 1.0, 5.0), DVec3::new(0.5, 1.0, 0.0), 3.0);
    let (d, _) = draw(&scene, &camera, 200, 200);
    let k = d
        .edges
        .iter()
        .position(|e| {
            e.world.contains(&DVec3::new(0.25, 1.0, -1.0))
                && e.world.contains(&DVec3::new(0.75, 1.0, -1.0))
        })
        .unwrap();
    let pieces: Vec<_> = d.pieces.iter().filter(|p| p.edge as usize == k).collect();
    assert_eq!(pieces.len(), 1);
    assert_eq!(
        pieces[0].invisibility, 1,
        "drawn once, by the front square's edge"
    );
}

#[test]
fn dense_sphere_and_torus_agree_with_ray_casting() {
    let mut rng = SplitMix64(23);
    let sphere = scene_of(vec![(
        demo::uv_sphere_mesh(1.0, 24, 12),
        DMat4::IDENTITY,
        true,
    )]);
    let torus = scene_of(vec![(
        demo::torus_mesh(1.0, 0.35, 24, 12),
        DMat4::from_rotation_x(0.7),
        true,
    )]);
    for scene in [&sphere, &torus] {
        for k in 0..3 {
            let dir = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize_or(DVec3::Z);
            let eye = dir * rng.range(2.5, 5.0);
            let camera = if k == 2 {
                ortho(eye, DVec3::ZERO, 3.0)
            } else {
                persp(eye, DVec3::ZERO)
            };
            assert_oracle(scene, &camera, 320, 240);
        }
    }
}

#[test]
fn open_meshes_and_interpenetrating_boxes_agree_with_ray_casting() {
    let open = scene_of(vec![
        (
            demo::grid_mesh(2.0, 2.0, 6, 5),
            DMat4::from_rotation_x(0.4),
            false,
        ),
        (
            demo::cone_mesh(0.5, 1.0, 10),
            DMat4::from_translation(DVec3::new(0.2, -0.3, 0.1)),
            false,
        ),
    ]);
    let boxes = scene_of(vec![
        (
            demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
            DMat4::IDENTITY,
            true,
        ),
        (
            demo::box_mesh(DVec3::new(-0.2, -0.8, -0.3), DVec3::new(0.9, 0.3, 0.4)),
            DMat4::from_rotation_y(0.5),
            true,
        ),
        (
            demo::box_mesh(DVec3::new(-1.0, -0.1, -0.1), DVec3::new(1.0, 0.1, 0.1)),
            DMat4::from_rotation_z(0.3),
            true,
        ),
    ]);
    let mut rng = SplitMix64(7);
    for scene in [&open, &boxes] {
        for camera in views_around_origin(&mut rng, -1.0, (2.5, 4.0), 3.5) {
            assert_oracle(scene, &camera, 300, 300);
        }
    }
}

/// Four cameras looking at the origin from random directions (`y` of the direction
/// from `y_lo` to 1) at a random distance in `distance`, alternately perspective and
/// orthographic (of window height `ortho_height`).
fn views_around_origin(
    rng: &mut SplitMix64,
    y_lo: f64,
    distance: (f64, f64),
    ortho_height: f64,
) -> Vec<Camera> {
    (0..4)
        .map(|k| {
            let dir = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(y_lo, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize_or(DVec3::Z);
            let eye = dir * rng.range(distance.0, distance.1);
            if k % 2 == 1 {
                ortho(eye, DVec3::ZERO, ortho_height)
            } else {
                persp(eye, DVec3::ZERO)
            }
        })
        .collect()
}

#[test]
fn coplanar_touching_faces_and_thin_triangles_agree_with_ray_casting() {
    // Two boxes sharing a face plane (touching along x = 0.5), a third stacked on top.
    let touching = scene_of(vec![
        (
            demo::box_mesh(DVec3::new(-0.5, -0.5, -0.5), DVec3::new(0.5, 0.5, 0.5)),
            DMat4::IDENTITY,
            true,
        ),
        (
            demo::box_mesh(DVec3::new(0.5, -0.5, -0.3), DVec3::new(1.2, 0.2, 0.5)),
            DMat4::IDENTITY,
            true,
        ),
        (
            demo::box_mesh(DVec3::new(-0.4, 0.5, -0.4), DVec3::new(0.3, 0.9, 0.3)),
            DMat4::IDENTITY,
            true,
        ),
    ]);
    // Long thin triangles crossing each other at different depths.
    let mut rng = SplitMix64(99);
    let mut p = Vec::new();
    let mut t = Vec::new();
    for k in 0..12u32 {
        let a = DVec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.0, 1.0),
        );
        let b = DVec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.0, 1.0),
        );
        let c = a + DVec3::new(rng.range(-0.03, 0.03), rng.range(-0.03, 0.03), 0.02);
        p.extend([a.to_array(), b.to_array(), c.to_array()]);
        t.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let thin = Scene::from_arrays(&p, Faces::Triangles(&t)).unwrap();
    let mut rng = SplitMix64(3);
    for scene in [&touching, &thin] {
        for camera in views_around_origin(&mut rng, -0.2, (3.0, 5.0), 4.0) {
            assert_oracle(scene, &camera, 300, 300);
        }
    }
}

#[test]
fn faces_edge_on_and_a_camera_at_the_near_plane_agree_with_ray_casting() {
    let scene = scene_of(vec![
        (
            demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
            DMat4::IDENTITY,
            true,
        ),
        (
            demo::grid_mesh(2.0, 2.0, 3, 3),
            DMat4::from_translation(DVec3::new(0.0, 0.2, 0.0)),
            false,
        ),
    ]);
    // Eye in the plane of the grid (y = 0.2) and of the box's top (y = 0.5): both seen
    // exactly edge-on.
    for camera in [
        persp(DVec3::new(0.3, 0.2, 4.0), DVec3::new(0.0, 0.2, 0.0)),
        persp(DVec3::new(2.0, 0.5, 3.0), DVec3::new(0.0, 0.5, 0.0)),
        ortho(DVec3::new(0.3, 0.2, 4.0), DVec3::new(0.3, 0.2, 0.0), 3.0),
    ] {
        assert_oracle(&scene, &camera, 300, 300);
    }
    // The near plane cutting through the box and the grid.
    let near = Camera::perspective(
        DVec3::new(0.2, 0.6, 0.7),
        DVec3::new(-0.3, -0.2, -1.0),
        DVec3::Y,
        70.0,
        0.25,
        20.0,
    );
    assert_oracle(&scene, &near, 300, 300);
}

#[test]
fn time_limit_stop_flag_and_progress() {
    let scene = demo::sphere(40, 20);
    let index = SceneIndex::new(&scene);
    let vp = Viewport::new(200, 150).unwrap();
    let view = View::new(
        &scene,
        &scene.default_camera(vp.aspect()),
        vp,
        &PrepareOptions::default(),
    )
    .unwrap();
    let mut o = options();
    o.time_limit = Some(Duration::ZERO);
    assert!(matches!(
        hlr::draw(&index, &view, &o),
        Err(Error::TimeLimit { .. })
    ));
    let mut o = options();
    o.stop = Some(Arc::new(AtomicBool::new(true)));
    assert!(matches!(
        hlr::draw(&index, &view, &o),
        Err(Error::Stopped { .. })
    ));
    let mut o = options();
    let last = Arc::new(AtomicU64::new(0));
    let seen = Arc::clone(&last);
    o.progress = Some(Arc::new(move |done, total| {
        assert!(done <= total);
        seen.fetch_max(done, Ordering::Relaxed);
    }));
    let (d, stats) = hlr::draw(&index, &view, &o).unwrap();
    assert_eq!(last.load(Ordering::Relaxed), stats.edges);
    assert_eq!(d.edges.len() as u64, stats.edges);
}

/// The default drawing (feature edges only: silhouettes, creases, boundaries, borders,
/// intersection lines) of interpenetrating boxes, a torus and the demo scene, checked
/// by the library's own sampling oracle (`lines::check`, the one `--check` runs), which
/// shares no code with the cutting.
#[test]
fn feature_edge_drawings_pass_the_library_check() {
    use obscura::lines::EdgeKind;
    use obscura::lines::check::{CheckOptions, check};
    let boxes = scene_of(vec![
        (
            demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)),
            DMat4::IDENTITY,
            true,
        ),
        (
            demo::box_mesh(DVec3::new(-0.2, -0.8, -0.3), DVec3::new(0.9, 0.3, 0.4)),
            DMat4::from_rotation_y(0.5),
            true,
        ),
    ]);
    let torus = scene_of(vec![(
        demo::torus_mesh(1.0, 0.35, 40, 20),
        DMat4::IDENTITY,
        true,
    )]);
    let default = demo::default_scene();
    let mut rng = SplitMix64(11);
    for (name, scene) in [("boxes", &boxes), ("torus", &torus), ("default", &default)] {
        let index = SceneIndex::new(scene);
        let radius = scene.bounds().extent().length();
        for k in 0..4 {
            let dir = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(0.1, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize_or(DVec3::Z);
            let centre = scene.bounds().center();
            let eye = centre + dir * radius * rng.range(1.2, 2.0);
            let camera = if k % 2 == 1 {
                Camera::orthographic(eye, centre, DVec3::Y, radius, 0.01, 100.0 * radius)
            } else {
                Camera::perspective(eye, centre, DVec3::Y, 50.0, 0.01, 100.0 * radius)
            };
            let view = View::new(
                scene,
                &camera,
                Viewport::new(400, 300).unwrap(),
                &PrepareOptions::default(),
            )
            .unwrap();
            let (d, _) = hlr::draw(&index, &view, &HlrOptions::default()).unwrap();
            assert!(d.visible().count() > 0, "{name}: nothing visible");
            if name == "boxes" {
                assert!(
                    d.edges.iter().any(|e| e.kind == EdgeKind::Intersection),
                    "boxes: no intersection line"
                );
            }
            assert!(d.edges.iter().all(|e| e.kind != EdgeKind::Other), "{name}");
            let report = check(&index, &view, &d, &CheckOptions::default());
            assert!(report.samples > 0, "{name}: nothing sampled");
            assert!(report.agrees(), "{name} view {k}: {report:?}");
        }
    }
}
