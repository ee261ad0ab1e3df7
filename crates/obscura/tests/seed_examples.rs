//! The worked examples of the seed lecture notes, reproduced exactly
//! (answers checked in ../shared/ALGORITHMS.md, "Worked examples, checked").

use glam::DVec3;
use obscura::geom::Plane;
use obscura::raster::FillRule;
use obscura::scene::{Camera, MeshBuilder, ObjectDesc, demo};
use obscura::surface::{Algorithm, RenderOptions, render};
use obscura::{BACKGROUND, Frame, PrepareOptions, Scene, Viewport, prepare};

/// Renders with lattice sampling (the seeds' convention: edges inclusive).
fn render_lattice(scene: &Scene, camera: &Camera, size: u32) -> Frame {
    let vp = Viewport::new(u64::from(size), u64::from(size)).unwrap();
    let view = prepare(scene, camera, vp, &PrepareOptions::default()).unwrap();
    let opts = RenderOptions::default().with_fill_rule(FillRule::Inclusive);
    render(Algorithm::ZBuffer, &view, &opts).unwrap().0
}

/// Seed 004's z-buffer task: the frame buffer of ALGORITHMS.md, example 1, character by
/// character (rows y = 31 at the top down to y = 0; '.' background, '1' quad, '2' triangle).
#[test]
fn seed_004_zbuffer_task_reproduces_the_picture() {
    let rows_25_to_10 = [
        "..........1111111111111111......",
        "..........1111111111111111......",
        "..........1111111111111111......",
        "..........11111111111111112.....",
        "..........11111111111111112.....",
        "..........11111111111111112.....",
        "..........111111111221111122....",
        "..........111111112221111122....",
        "..........111111122221111122....",
        "..........1111112222221111222...",
        "..........1111122222221111222...",
        "..........1111111122221111222...",
        "..........11111111111221112222..",
        "..........11111111111111112222..",
        "..........1111111111111111.222..",
        "..........1111111111111111....2.",
    ];
    let mut expected = vec![".".repeat(32); 32];
    for (k, row) in rows_25_to_10.iter().enumerate() {
        expected[31 - (25 - k)] = (*row).to_string();
    }
    for y in 5..=9 {
        expected[31 - y] = "..........1111111111111111......".to_string();
    }
    let scene = demo::seed_task();
    let frame = render_lattice(&scene, scene.camera().unwrap(), 32);
    let got: Vec<String> = (0..32)
        .map(|j| {
            (0..32)
                .map(|i| match frame.id(i, j) {
                    BACKGROUND => '.',
                    0 => '1',
                    1 => '2',
                    other => panic!("unexpected id {other}"),
                })
                .collect()
        })
        .collect();
    assert_eq!(got, expected, "\n{}", got.join("\n"));
    let count = |c: char| {
        got.iter()
            .map(|r| r.chars().filter(|&x| x == c).count())
            .sum::<usize>()
    };
    assert_eq!((count('1'), count('2')), (308, 58));
    // The triangle is in front exactly where 3x + y < 80 (z_triangle > 10).
    for j in 0..32u32 {
        for i in 0..32u32 {
            let (x, y) = (f64::from(i), f64::from(31 - j));
            if frame.id(i, j) == 1 && (10.0..=25.0).contains(&x) && (5.0..=25.0).contains(&y) {
                assert!(3.0 * x + y < 80.0, "triangle wins at ({x}, {y})");
            }
        }
    }
}

/// Seed 004: the triangle's plane by Cramer's rule and by Newell's method, and the step
/// of the incremental depth along a scanline, z(x+1) = z(x) - 3/4.
#[test]
fn seed_004_plane_of_the_triangle() {
    let t = [
        DVec3::new(15., 15., 15.),
        DVec3::new(25., 25., 5.),
        DVec3::new(30., 10., 5.),
    ];
    let p = Plane::from_three_points_cramer(t[0], t[1], t[2]).unwrap();
    assert!((p.normal * -120.0 - DVec3::new(3., 1., 4.)).length() < 1e-12);
    let n = Plane::newell(&t).unwrap();
    let along = n.normal.dot(DVec3::new(3., 1., 4.).normalize()).abs();
    assert!((along - 1.0).abs() < 1e-12);
    let step = -p.normal.x / p.normal.z;
    assert!((step + 0.75).abs() < 1e-15);
}

/// Seed 002's 8x8 example: the buffer starts at 0 (far), a first polygon at depth 5
/// fills the upper-left triangle, a second polygon with depths 3..8 overwrites only where
/// its depth is greater. The seed's final depth buffer, row 0 at the top.
#[test]
fn seed_002_eight_by_eight_example() {
    let expected: [[u32; 8]; 8] = [
        [5, 5, 5, 5, 5, 5, 5, 0],
        [5, 5, 5, 5, 5, 5, 0, 0],
        [5, 5, 5, 5, 5, 0, 0, 0],
        [5, 5, 5, 5, 0, 0, 0, 0],
        [6, 5, 5, 3, 0, 0, 0, 0],
        [7, 6, 5, 4, 3, 0, 0, 0],
        [8, 7, 6, 5, 4, 3, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
    ];
    // Pixel (c, r) samples the lattice point x = c, y = 7 - r; the seed's depth z grows
    // towards the viewer, so the camera sits on +z.
    let poly = |pts: &[(f64, f64, f64)]| {
        let mut b = MeshBuilder::new();
        for &(x, y, z) in pts {
            b.push_position(DVec3::new(x, y, z));
        }
        let idx: Vec<u32> = (0..pts.len() as u32).collect();
        b.push_face(&idx, None).unwrap();
        b.finish().0
    };
    let mut scene = Scene::new();
    // First polygon: c + r <= 6 at z = 5.
    scene
        .add(ObjectDesc::new(
            "first",
            poly(&[(0., 7., 5.), (0., 1., 5.), (6., 7., 5.)]),
        ))
        .unwrap();
    // Second polygon: rows 4..=6, c <= r - 1, with z = r - c + 2 = 9 - x - y.
    let z = |x: f64, y: f64| 9.0 - x - y;
    scene
        .add(ObjectDesc::new(
            "second",
            poly(&[
                (0., 3., z(0., 3.)),
                (0., 1., z(0., 1.)),
                (5., 1., z(5., 1.)),
                (3., 3., z(3., 3.)),
            ]),
        ))
        .unwrap();
    let eye_z = 100.0;
    let cam = Camera::orthographic(
        DVec3::new(3.5, 3.5, eye_z),
        DVec3::new(3.5, 3.5, 0.0),
        DVec3::Y,
        8.0,
        1.0,
        200.0,
    );
    let frame = render_lattice(&scene, &cam, 8);
    for r in 0..8u32 {
        for c in 0..8u32 {
            let d = frame.depth[frame.index(c, r)];
            let seed_z = if d.is_infinite() {
                0.0
            } else {
                eye_z - f64::from(d)
            };
            assert!(
                (seed_z - f64::from(expected[r as usize][c as usize])).abs() < 1e-4,
                "pixel ({c}, {r}): z {seed_z}, expected {}",
                expected[r as usize][c as usize]
            );
        }
    }
    // Where both have depth 5 (row 4, column 1) the first polygon keeps the pixel.
    assert_eq!(frame.id(1, 4), 0);
    assert_eq!(frame.id(0, 4), 1);
    assert_eq!(frame.id(3, 4), 1);
}

/// The seed's depth merge of two partial frames gives the frame of the whole scene.
#[test]
fn depth_merge_of_two_halves_equals_the_whole() {
    let scene = demo::default_scene();
    let vp = Viewport::new(160, 90).unwrap();
    let cam = *scene.camera().unwrap();
    let whole = {
        let v = prepare(&scene, &cam, vp, &PrepareOptions::default()).unwrap();
        render(Algorithm::ZBuffer, &v, &RenderOptions::default())
            .unwrap()
            .0
    };
    // Split the objects into two scenes, keeping face ids by giving each the other's
    // objects with their faces dropped: simplest is to render each half and remap.
    let half = |keep: &dyn Fn(usize) -> bool| {
        let mut s = Scene::new();
        let mut first_ids = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            if keep(k) {
                first_ids.push(o.first_face);
                s.add(ObjectDesc {
                    name: o.name.clone(),
                    mesh: o.mesh.clone(),
                    transform: o.transform,
                    color: o.color,
                    closed: Some(o.closed),
                    convex: Some(o.convex),
                })
                .unwrap();
            }
        }
        let v = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
        let mut f = render(Algorithm::ZBuffer, &v, &RenderOptions::default())
            .unwrap()
            .0;
        for id in &mut f.ids {
            if *id != BACKGROUND {
                let (k, local) = s.locate_face(*id).unwrap();
                *id = first_ids[k] + local;
            }
        }
        f
    };
    let a = half(&|k| k % 2 == 0);
    let b = half(&|k| k % 2 == 1);
    let merged = a.merge_depth(&b).unwrap();
    let diff = merged.differences(&whole);
    assert!(
        diff.is_empty(),
        "{} pixels differ: {:?}",
        diff.len(),
        &diff[..diff.len().min(10)]
    );
}
