//! Scenes and checks shared by the hidden-surface tests (scanline, Warnock, depth sort,
//! BSP): each algorithm must give the z-buffer's frame on them.
#![allow(dead_code)]

use crate::rng::SplitMix64;
use crate::scene::demo;
use crate::scene::{Camera, MeshBuilder, ObjectDesc, Scene, Viewport};
use crate::surface::{Algorithm, RenderOptions, render};
use crate::{Frame, PrepareOptions, PreparedView, Stats, prepare};
use glam::{DMat4, DVec3};

/// A scene with its camera and image size.
pub struct Case {
    pub name: String,
    pub scene: Scene,
    pub camera: Camera,
    pub viewport: Viewport,
    pub prepare: PrepareOptions,
}

impl Case {
    pub fn new(name: &str, scene: Scene, camera: Camera, w: u64, h: u64) -> Self {
        Case {
            name: name.to_string(),
            scene,
            camera,
            viewport: Viewport::new(w, h).unwrap(),
            prepare: PrepareOptions::default(),
        }
    }

    /// Renders with `algorithm` and with the z-buffer.
    pub fn render_pair(&self, algorithm: Algorithm) -> ((Frame, Stats), (Frame, Stats)) {
        let view = prepare(&self.scene, &self.camera, self.viewport, &self.prepare).unwrap();
        let opts = RenderOptions::default();
        let a = render(algorithm, &view, &opts).unwrap();
        let z = render(Algorithm::ZBuffer, &view, &opts).unwrap();
        (a, z)
    }

    /// Asserts the frame of `algorithm` equals the z-buffer's (ids exactly, depths
    /// to f32 rounding), printing the differing pixels otherwise. Returns its stats.
    pub fn assert_matches_zbuffer(&self, algorithm: Algorithm) -> Stats {
        let ((frame, stats), (reference, _)) = self.render_pair(algorithm);
        assert_same(&self.name, algorithm, &frame, &reference);
        stats
    }
}

pub fn assert_same(name: &str, algorithm: Algorithm, frame: &Frame, reference: &Frame) {
    let diff = frame.differences(reference);
    if !diff.is_empty() {
        let shown: Vec<String> = diff
            .iter()
            .take(20)
            .map(|&(x, y, a, z)| {
                let k = frame.index(x, y);
                format!(
                    "({x},{y}) {algorithm} {} depth {} / zbuffer {} depth {}",
                    id(a),
                    frame.depth[k],
                    id(z),
                    reference.depth[k]
                )
            })
            .collect();
        panic!(
            "{name}: {} of {} pixels differ from the z-buffer:\n{}",
            diff.len(),
            frame.ids.len(),
            shown.join("\n")
        );
    }
    for (k, (&d, &r)) in frame.depth.iter().zip(&reference.depth).enumerate() {
        let ok = (d.is_infinite() && r.is_infinite()) || (d - r).abs() <= 1e-5 * r.abs();
        assert!(ok, "{name}: depth at pixel {k}: {d} vs z-buffer {r}");
    }
}

fn id(i: u32) -> String {
    if i == crate::BACKGROUND {
        "background".into()
    } else {
        i.to_string()
    }
}

/// One object made of the given polygons (world coordinates), not closed.
pub fn polygons_object(name: &str, polys: &[Vec<DVec3>]) -> ObjectDesc {
    let mut b = MeshBuilder::new();
    for p in polys {
        let base = b.vertex_count() as u32;
        for &v in p {
            b.push_position(v);
        }
        let idx: Vec<u32> = (0..p.len() as u32).map(|k| base + k).collect();
        b.push_face(&idx, None).unwrap();
    }
    ObjectDesc::new(name, b.finish().0).with_closed(false)
}

/// One object made of one polygon (world coordinates).
pub fn polygon_object(name: &str, pts: &[DVec3]) -> ObjectDesc {
    polygons_object(name, &[pts.to_vec()])
}

/// `n` random triangles, one object each: centres uniform in `[-half, half]^3`,
/// vertices uniform within `spread` of the centre on each axis. Some interpenetrate.
pub fn random_triangle_objects(n: usize, seed: u64, half: f64, spread: f64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut s = Scene::new();
    for i in 0..n {
        let c = DVec3::new(
            rng.range(-half, half),
            rng.range(-half, half),
            rng.range(-half, half),
        );
        let pts: Vec<DVec3> = (0..3)
            .map(|_| {
                c + DVec3::new(
                    rng.range(-spread, spread),
                    rng.range(-spread, spread),
                    rng.range(-spread, spread),
                )
            })
            .collect();
        s.add(polygon_object(&format!("t{i}"), &pts)).unwrap();
    }
    s
}

/// The prepared view of a scene (default options).
pub fn view<'s>(scene: &'s Scene, cam: &Camera, w: u32, h: u32) -> PreparedView<'s> {
    let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
    prepare(scene, cam, vp, &PrepareOptions::default()).unwrap()
}

/// Asserts that at least `min_fraction` of the pixels have the z-buffer's id, printing
/// the differing pixels otherwise.
pub fn assert_like_zbuffer(frame: &Frame, view: &PreparedView<'_>, min_fraction: f64, label: &str) {
    let (z, _) = render(Algorithm::ZBuffer, view, &RenderOptions::default()).unwrap();
    let diffs = frame.differences(&z);
    let fraction = 1.0 - diffs.len() as f64 / z.ids.len() as f64;
    assert!(
        fraction >= min_fraction,
        "{label}: {} of {} pixels differ from the z-buffer (x, y, got, z-buffer): {:?}",
        diffs.len(),
        z.ids.len(),
        &diffs[..diffs.len().min(30)]
    );
}

pub fn scene_of(polys: &[Vec<DVec3>]) -> Scene {
    let mut s = Scene::new();
    s.add(polygons_object("polygons", polys)).unwrap();
    s
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn front_camera() -> Camera {
    Camera::perspective(v(0., 0., 4.), DVec3::ZERO, DVec3::Y, 50.0, 0.5, 20.0)
}

/// Triangles with random vertices in a cube: overlapping, interpenetrating, any size.
pub fn random_triangles(seed: u64, n: usize, w: u64, h: u64) -> Case {
    let mut r = SplitMix64(seed);
    let tris: Vec<Vec<DVec3>> = (0..n)
        .map(|_| {
            (0..3)
                .map(|_| v(r.range(-1.5, 1.5), r.range(-1.2, 1.2), r.range(-1.0, 1.0)))
                .collect()
        })
        .collect();
    Case::new(
        &format!("random triangles {seed}"),
        scene_of(&tris),
        front_camera(),
        w,
        h,
    )
}

/// Long thin triangles (slivers a fraction of a pixel to a few pixels wide) at all
/// angles, crossing each other.
pub fn thin_triangles(seed: u64) -> Case {
    let mut r = SplitMix64(seed);
    let tris: Vec<Vec<DVec3>> = (0..60)
        .map(|_| {
            let a = v(r.range(-1.5, 1.5), r.range(-1.2, 1.2), r.range(-1.0, 1.0));
            let b = v(r.range(-1.5, 1.5), r.range(-1.2, 1.2), r.range(-1.0, 1.0));
            let width = r.range(0.0005, 0.05);
            let dir = (b - a).normalize();
            let side = dir.cross(DVec3::Z).normalize_or(DVec3::X) * width;
            vec![a, b, a + side]
        })
        .collect();
    Case::new("thin triangles", scene_of(&tris), front_camera(), 120, 90)
}

/// Quads and triangles that pass through each other at various angles.
pub fn interpenetrating() -> Case {
    let quad = |c: DVec3, u: DVec3, w: DVec3| vec![c - u - w, c + u - w, c + u + w, c - u + w];
    let polys = vec![
        quad(v(0., 0., 0.), v(1.2, 0., 0.3), v(0., 0.9, 0.)),
        quad(v(0.1, 0.05, 0.), v(1.0, 0., -0.5), v(0., 0.8, 0.2)),
        quad(v(-0.2, 0., 0.1), v(0.3, 0., 0.), v(0., 1.1, -0.6)),
        vec![v(-1.3, -0.8, -0.7), v(1.2, -0.5, 0.8), v(0.2, 1.0, 0.0)],
        vec![v(1.3, -0.9, -0.6), v(-1.0, 0.9, 0.7), v(-0.6, -1.0, 0.5)],
    ];
    Case::new(
        "interpenetrating",
        scene_of(&polys),
        front_camera(),
        128,
        96,
    )
}

/// Three slats each lying over the next in a cycle: no depth order exists.
pub fn cyclic_overlap() -> Case {
    let mut polys = Vec::new();
    for k in 0..3 {
        let a = f64::from(k) * std::f64::consts::TAU / 3.0;
        let (c, s) = (a.cos(), a.sin());
        // A long thin triangle along direction a, raised at one end, lowered at the other.
        let along = v(-s, c, 0.0);
        let across = v(c, s, 0.0) * 0.25;
        let centre = v(c, s, 0.0) * 0.35;
        let p0 = centre - along * 1.4 + DVec3::Z * 0.3;
        let p1 = centre + along * 1.4 - DVec3::Z * 0.3;
        polys.push(vec![p0 - across, p0 + across, p1]);
    }
    Case::new("cyclic overlap", scene_of(&polys), front_camera(), 128, 128)
}

/// Coplanar faces sharing edges: a grid of quads, a triangle fan, seen at an angle.
pub fn coplanar_touching() -> Case {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("grid", demo::grid_mesh(3.0, 3.0, 7, 5)).with_closed(false))
        .unwrap();
    let mut fan = Vec::new();
    let centre = v(0.2, 0.4, 0.1);
    for k in 0..11 {
        let a0 = f64::from(k) * std::f64::consts::TAU / 11.0;
        let a1 = f64::from(k + 1) * std::f64::consts::TAU / 11.0;
        fan.push(vec![
            centre,
            centre + v(a0.cos(), 0.0, a0.sin()) * 0.9,
            centre + v(a1.cos(), 0.0, a1.sin()) * 0.9,
        ]);
    }
    // The fan lies flat above the grid (plane y = 0.4): coplanar only with itself.
    for t in &mut fan {
        for p in t.iter_mut() {
            p.y = 0.4;
        }
    }
    s.add(polygons_object("fan", &fan)).unwrap();
    let cam = Camera::perspective(v(1.0, 2.5, 3.0), v(0., 0., 0.), DVec3::Y, 55.0, 0.1, 20.0);
    Case::new("coplanar touching", s, cam, 120, 90)
}

/// A floor running behind the eye and boxes cut by the near plane.
pub fn crossing_near_plane() -> Case {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("floor", demo::grid_mesh(40.0, 40.0, 4, 4)).with_closed(false))
        .unwrap();
    for (k, x) in [-0.6, 0.0, 0.7].into_iter().enumerate() {
        s.add(
            ObjectDesc::new(
                format!("box {k}"),
                demo::box_mesh(v(x - 0.3, 0.0, -0.4), v(x + 0.3, 1.2, 0.4)),
            )
            .with_transform(DMat4::from_rotation_y(0.3 * k as f64)),
        )
        .unwrap();
    }
    // The eye sits inside the middle box's near corner region: near = 0.5 cuts boxes.
    let cam = Camera::perspective(
        v(0.1, 0.6, 0.7),
        v(0.0, 0.4, -3.0),
        DVec3::Y,
        70.0,
        0.5,
        50.0,
    );
    Case::new("crossing the near plane", s, cam, 128, 96)
}

/// Random triangles seen by an orthographic camera.
pub fn orthographic(seed: u64) -> Case {
    let mut c = random_triangles(seed, 40, 100, 80);
    c.name = format!("orthographic {seed}");
    c.camera = Camera::orthographic(v(0.5, 0.3, 5.0), v(0., 0., 0.), DVec3::Y, 3.0, 1.0, 10.0);
    c
}

/// The default demo at a small size.
pub fn demo_default(w: u64, h: u64) -> Case {
    let scene = Scene::demo("default").unwrap();
    let vp = Viewport::new(w, h).unwrap();
    let cam = scene.default_camera(vp.aspect());
    Case::new("demo:default", scene, cam, w, h)
}

/// A small random scene: triangles, boxes and quads, random camera (sometimes
/// orthographic), random image size.
pub fn random_scene(seed: u64) -> Case {
    let mut r = SplitMix64(seed ^ 0x5EED);
    let mut s = Scene::new();
    let tris: Vec<Vec<DVec3>> = (0..(3 + r.next_u64() % 25))
        .map(|_| {
            let c = v(r.range(-1.5, 1.5), r.range(-1.5, 1.5), r.range(-1.5, 1.5));
            let size = r.range(0.05, 1.5);
            (0..3)
                .map(|_| c + v(r.range(-1., 1.), r.range(-1., 1.), r.range(-1., 1.)) * size)
                .collect()
        })
        .collect();
    s.add(polygons_object("triangles", &tris)).unwrap();
    for k in 0..(r.next_u64() % 4) {
        let c = v(r.range(-1.5, 1.5), r.range(-1.5, 1.5), r.range(-1.5, 1.5));
        let e = v(r.range(0.1, 0.8), r.range(0.1, 0.8), r.range(0.1, 0.8));
        s.add(
            ObjectDesc::new(format!("box {k}"), demo::box_mesh(c - e, c + e))
                .with_transform(DMat4::from_rotation_y(r.range(0.0, 3.0))),
        )
        .unwrap();
    }
    let dir = v(r.range(-1., 1.), r.range(-1., 1.), r.range(-1., 1.)).normalize_or(DVec3::Z);
    let dist = r.range(1.5, 6.0);
    let eye = dir * dist;
    let target = v(r.range(-0.5, 0.5), r.range(-0.5, 0.5), r.range(-0.5, 0.5));
    let cam = if r.next_u64().is_multiple_of(4) {
        Camera::orthographic(eye, target, DVec3::Y, r.range(1.0, 5.0), 0.1, 20.0)
    } else {
        Camera::perspective(
            eye,
            target,
            DVec3::Y,
            r.range(30.0, 90.0),
            r.range(0.05, 1.0),
            20.0,
        )
    };
    let (w, h) = (16 + r.next_u64() % 60, 12 + r.next_u64() % 50);
    Case::new(&format!("random scene {seed}"), s, cam, w, h)
}

/// Every case that must match the z-buffer exactly.
pub fn cross_validation_cases() -> Vec<Case> {
    let mut v = vec![
        random_triangles(1, 50, 96, 72),
        random_triangles(2, 200, 160, 120),
        thin_triangles(3),
        interpenetrating(),
        cyclic_overlap(),
        coplanar_touching(),
        crossing_near_plane(),
        orthographic(4),
        demo_default(160, 120),
    ];
    // A fan of triangles around a pixel centre, vertices on pixel centres and edges:
    // the top-left rule's hardest case for span ends.
    v.push(pixel_aligned_fan());
    v
}

/// Triangles whose vertices fall exactly on pixel centres and pixel corners (an
/// orthographic camera maps world units to pixels), so samples lie on edges and
/// vertices.
pub fn pixel_aligned_fan() -> Case {
    let c = v(16.5, 12.5, 0.0);
    let mut polys = Vec::new();
    let ring = [
        (8.5, 12.5),
        (10.0, 6.0),
        (16.5, 4.5),
        (23.0, 6.0),
        (25.5, 12.5),
        (23.0, 19.0),
        (16.5, 21.5),
        (10.0, 19.0),
    ];
    for k in 0..ring.len() {
        let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
        polys.push(vec![c, v(a.0, a.1, 0.1 * k as f64), v(b.0, b.1, 0.2)]);
    }
    // A square with edges through pixel centres and one overlapping it in front.
    polys.push(vec![
        v(2.5, 2.5, 0.5),
        v(6.5, 2.5, 0.5),
        v(6.5, 6.5, 0.5),
        v(2.5, 6.5, 0.5),
    ]);
    polys.push(vec![v(4.5, 4.5, 1.0), v(8.0, 4.5, 1.0), v(8.0, 8.0, 1.0)]);
    // The orthographic camera looks down -z with y up; pixel (i, j) samples world
    // (i + 0.5, 24 - (j + 0.5)): flip y so world (x, y) is pixel position (x, 24 - y).
    for p in polys.iter_mut() {
        for q in p.iter_mut() {
            q.y = 24.0 - q.y;
        }
    }
    let cam = Camera::orthographic(
        v(16.0, 12.0, 10.0),
        v(16.0, 12.0, 0.0),
        DVec3::Y,
        24.0,
        1.0,
        20.0,
    );
    Case::new("pixel-aligned fan", scene_of(&polys), cam, 32, 24)
}

/// Scenes whose frame must be all background.
pub fn background_cases() -> Vec<Case> {
    let empty = Case::new("empty scene", Scene::new(), front_camera(), 40, 30);
    let mut behind = Scene::new();
    behind
        .add(ObjectDesc::new(
            "behind",
            demo::box_mesh(v(-1., -1., 8.), v(1., 1., 9.)),
        ))
        .unwrap();
    let behind = Case::new("all faces culled", behind, front_camera(), 40, 30);
    let mut inside = Scene::new();
    inside
        .add(ObjectDesc::new(
            "room",
            demo::box_mesh(v(-1., -1., -1.), v(1., 1., 1.)),
        ))
        .unwrap();
    let cam = Camera::perspective(DVec3::ZERO, v(0., 0., -1.), DVec3::Y, 60.0, 0.1, 10.0);
    let inside = Case::new("camera inside a closed box", inside, cam, 40, 30);
    vec![empty, behind, inside]
}
