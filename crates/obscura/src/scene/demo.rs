//! Built-in demo scenes ([`Scene::demo`], the CLI's `demo:NAME`) and the mesh generators
//! they are made of.
//!
//! | name | what | size |
//! | --- | --- | --- |
//! | `default` | interpenetrating and overlapping solids on a floor | ~10k faces |
//! | `seed-task` | seed 004's z-buffer task: a quad and a triangle, 32x32 orthographic | 2 faces |
//! | `cube` | a unit cube | 6 faces |
//! | `sphere` | a UV sphere of about a million triangles (benchmarks) | 998,000 |
//! | `city` | 10,000 boxes on a ground plane | 120,001 |
//! | `triangles` | 10,000 large overlapping triangles (z-buffer fill-rate benchmark) | 10,000 |
//! | `level` | a level of 35 cells (rooms, corridors, doors, furniture) with its cells and portals | ~1k |
//! | `level-grid` | a generated level of 100 cells (PVS speed) | ~4k |
//! | `cells5` | the seed's five cells A..E of the PVS example ([`crate::cull::portals::seed_example`]) | ~60 |
//!
//! Generators produce counter-clockwise faces seen from outside, so closed ones can be
//! back-face culled.

use std::f64::consts::{PI, TAU};

use glam::{DMat4, DVec3};

use super::{Camera, Mesh, MeshBuilder, ObjectDesc, Scene};
use crate::{Error, Result};

use crate::rng::SplitMix64;

/// The names [`Scene::demo`] (and the CLI's `demo:NAME`) accepts.
pub const NAMES: [&str; 10] = [
    "default",
    "seed-task",
    "cube",
    "sphere",
    "city",
    "blocks",
    "triangles",
    "level",
    "level-grid",
    "cells5",
];

/// A built-in scene by name.
pub fn scene(name: &str) -> Result<Scene> {
    match name {
        "" | "default" => Ok(default_scene()),
        "seed-task" | "zbuffer-task" => Ok(seed_task()),
        "cube" => Ok(cube()),
        "sphere" => Ok(sphere(1000, 500)),
        "city" => Ok(city(100, 100, 7)),
        "blocks" => Ok(blocks(10, 10, 7)),
        "triangles" => Ok(overlapping_triangles(10_000, 11)),
        "level" => Ok(level()),
        "level-grid" => Ok(level_grid(10)),
        "cells5" => Ok(crate::cull::portals::seed_example().1),
        _ => Err(Error::UnknownDemo {
            name: name.to_string(),
            known: NAMES.join(", "),
        }),
    }
}

fn build(f: impl FnOnce(&mut MeshBuilder)) -> Mesh {
    let mut b = MeshBuilder::new();
    f(&mut b);
    b.finish().0
}

/// An axis-aligned box as six quads.
#[must_use]
pub fn box_mesh(min: DVec3, max: DVec3) -> Mesh {
    build(|b| {
        for i in 0..8u32 {
            let p = DVec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            );
            b.push_position(p);
        }
        // -x, +x, -y, +y, -z, +z; counter-clockwise from outside
        for f in [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ] {
            b.push_face(&f, None).expect("indices in range");
        }
    })
}

/// A flat grid of `nx * nz` quads in the plane y = 0, centred on the origin, facing +y.
#[must_use]
pub fn grid_mesh(width: f64, depth: f64, nx: u32, nz: u32) -> Mesh {
    build(|b| {
        for j in 0..=nz {
            for i in 0..=nx {
                let x = (f64::from(i) / f64::from(nx) - 0.5) * width;
                let z = (f64::from(j) / f64::from(nz) - 0.5) * depth;
                b.push_position(DVec3::new(x, 0.0, z));
            }
        }
        let v = |i: u32, j: u32| j * (nx + 1) + i;
        for j in 0..nz {
            for i in 0..nx {
                b.push_face(&[v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i + 1, j)], None)
                    .expect("in range");
            }
        }
    })
}

/// A UV sphere of triangles: `segments` around, `rings` from pole to pole, giving
/// `2 * segments * (rings - 1)` triangles.
#[must_use]
pub fn uv_sphere_mesh(radius: f64, segments: u32, rings: u32) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut b = MeshBuilder::with_capacity(
        (segments * (rings - 1) + 2) as usize,
        (2 * segments * (rings - 1)) as usize,
    );
    let north = b.push_position(DVec3::new(0.0, radius, 0.0));
    for j in 1..rings {
        let theta = PI * f64::from(j) / f64::from(rings);
        for i in 0..segments {
            let phi = TAU * f64::from(i) / f64::from(segments);
            b.push_position(
                DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ) * radius,
            );
        }
    }
    let south = b.push_position(DVec3::new(0.0, -radius, 0.0));
    let v = |j: u32, i: u32| 1 + (j - 1) * segments + i % segments;
    for i in 0..segments {
        b.push_face(&[north, v(1, i + 1), v(1, i)], None)
            .expect("in range");
    }
    for j in 1..rings - 1 {
        for i in 0..segments {
            b.push_face(&[v(j, i), v(j, i + 1), v(j + 1, i)], None)
                .expect("in range");
            b.push_face(&[v(j, i + 1), v(j + 1, i + 1), v(j + 1, i)], None)
                .expect("in range");
        }
    }
    for i in 0..segments {
        b.push_face(&[south, v(rings - 1, i), v(rings - 1, i + 1)], None)
            .expect("in range");
    }
    b.finish().0
}

/// A torus around the y axis (major radius `major`, tube radius `minor`) of planar quads.
#[must_use]
pub fn torus_mesh(major: f64, minor: f64, segments: u32, sides: u32) -> Mesh {
    build(|b| {
        for i in 0..segments {
            let u = TAU * f64::from(i) / f64::from(segments);
            for j in 0..sides {
                let v = TAU * f64::from(j) / f64::from(sides);
                let r = major + minor * v.cos();
                b.push_position(DVec3::new(r * u.cos(), minor * v.sin(), r * u.sin()));
            }
        }
        let idx = |i: u32, j: u32| (i % segments) * sides + j % sides;
        for i in 0..segments {
            for j in 0..sides {
                b.push_face(
                    &[idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j)],
                    None,
                )
                .expect("in range");
            }
        }
    })
}

/// A right circular cone (apex up at `height`, base disc at y = 0) with `segments` sides.
#[must_use]
pub fn cone_mesh(radius: f64, height: f64, segments: u32) -> Mesh {
    build(|b| {
        let apex = b.push_position(DVec3::new(0.0, height, 0.0));
        for i in 0..segments {
            let a = TAU * f64::from(i) / f64::from(segments);
            b.push_position(DVec3::new(radius * a.cos(), 0.0, radius * a.sin()));
        }
        let v = |i: u32| 1 + i % segments;
        for i in 0..segments {
            b.push_face(&[apex, v(i + 1), v(i)], None)
                .expect("in range");
        }
        let base: Vec<u32> = (0..segments).map(v).collect();
        b.push_face(&base, None).expect("in range");
    })
}

/// Seed 004's task: quadrilateral P1(10,5,10) P2(10,25,10) P3(25,25,10) P4(25,5,10)
/// (face 0) and triangle T1(15,15,15) T2(25,25,5) T3(30,10,5) (face 1), seen by an
/// orthographic camera from +z on a 32x32 image whose pixel centres fall on the
/// integer lattice: pixel `(i, j)` samples `(x, y) = (i, 31 - j)`.
#[must_use]
pub fn seed_task() -> Scene {
    let mut s = Scene::new();
    let quad = build(|b| {
        for p in [
            (10., 5., 10.),
            (10., 25., 10.),
            (25., 25., 10.),
            (25., 5., 10.),
        ] {
            b.push_position(DVec3::new(p.0, p.1, p.2));
        }
        b.push_face(&[0, 1, 2, 3], None).expect("in range");
    });
    let tri = build(|b| {
        for p in [(15., 15., 15.), (25., 25., 5.), (30., 10., 5.)] {
            b.push_position(DVec3::new(p.0, p.1, p.2));
        }
        b.push_face(&[0, 1, 2], None).expect("in range");
    });
    s.add(ObjectDesc::new("quad", quad).with_color([0.9, 0.3, 0.2]))
        .expect("valid");
    s.add(ObjectDesc::new("triangle", tri).with_color([0.2, 0.5, 0.9]))
        .expect("valid");
    s.set_camera(Some(seed_task_camera()));
    s
}

/// The camera of [`seed_task`] (use with a 32x32 viewport).
#[must_use]
pub fn seed_task_camera() -> Camera {
    Camera::orthographic(
        DVec3::new(15.5, 15.5, 100.0),
        DVec3::new(15.5, 15.5, 0.0),
        DVec3::Y,
        32.0,
        50.0,
        150.0,
    )
}

/// A unit cube centred on the origin.
#[must_use]
pub fn cube() -> Scene {
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("cube", box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)))
            .with_color([0.9, 0.55, 0.25]),
    )
    .expect("valid");
    s
}

/// A UV sphere of radius 1 with a camera that fills most of a 16:9 image with it.
#[must_use]
pub fn sphere(segments: u32, rings: u32) -> Scene {
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("sphere", uv_sphere_mesh(1.0, segments, rings))
            .with_color([0.3, 0.6, 0.9])
            .with_closed(true)
            .with_convex(true),
    )
    .expect("valid");
    s.set_camera(Some(Camera::perspective(
        DVec3::new(0.0, 0.6, 3.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        0.5,
        10.0,
    )));
    s
}

/// A city of `nx * nz` boxes of random heights on a ground plane, one object for the
/// ground and one per box.
#[must_use]
pub fn city(nx: u32, nz: u32, seed: u64) -> Scene {
    city_blocks(nx, nz, seed, true)
}

/// The buildings of [`city`] without the ground: convex closed boxes only, the input
/// Roberts' hidden-line algorithm takes (`demo:blocks`, 10 x 10).
#[must_use]
pub fn blocks(nx: u32, nz: u32, seed: u64) -> Scene {
    city_blocks(nx, nz, seed, false)
}

fn city_blocks(nx: u32, nz: u32, seed: u64, ground: bool) -> Scene {
    let mut s = Scene::new();
    let mut rng = SplitMix64(seed);
    let block = 1.0;
    let (w, d) = (f64::from(nx) * block, f64::from(nz) * block);
    if ground {
        s.add(
            ObjectDesc::new("ground", grid_mesh(w * 1.2, d * 1.2, 1, 1))
                .with_color([0.55, 0.55, 0.5]),
        )
        .expect("valid");
    }
    let unit = std::sync::Arc::new(box_mesh(
        DVec3::new(-0.5, 0.0, -0.5),
        DVec3::new(0.5, 1.0, 0.5),
    ));
    for j in 0..nz {
        for i in 0..nx {
            let cx = (f64::from(i) + 0.5) * block - w * 0.5;
            let cz = (f64::from(j) + 0.5) * block - d * 0.5;
            let r = rng.next_f64();
            let height = 0.3 + 6.0 * r * r * r + rng.range(0.0, 0.5);
            let size = rng.range(0.45, 0.8) * block;
            let t = DMat4::from_translation(DVec3::new(cx, 0.0, cz))
                * DMat4::from_scale(DVec3::new(size, height, size * rng.range(0.7, 1.0)));
            let grey = rng.range(0.55, 0.9) as f32;
            let desc = ObjectDesc {
                name: format!("building {i},{j}"),
                mesh: unit.clone(),
                transform: t,
                color: [grey, grey * 0.95, grey * 0.9],
                closed: Some(true),
                convex: Some(true),
            };
            s.add(desc).expect("valid");
        }
    }
    let r = w.max(d);
    s.set_camera(Some(Camera::perspective(
        DVec3::new(r * 0.55, r * 0.35, r * 0.75),
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::Y,
        50.0,
        0.1,
        r * 3.0,
    )));
    s
}

/// `n` large triangles overlapping in front of the camera, at random depths and tilts
/// so that many interpenetrate: a fill-rate benchmark for image-space algorithms. At
/// 1920x1080 each covers about 2.5% of the image on average (some 52,000 pixels), so
/// 10,000 of them make some 520 million depth tests. One open object: no back face is
/// culled.
#[must_use]
pub fn overlapping_triangles(n: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut b = MeshBuilder::with_capacity(n * 3, n);
    for _ in 0..n {
        let c = DVec3::new(
            rng.range(-7.0, 7.0),
            rng.range(-4.0, 4.0),
            rng.range(-3.0, 3.0),
        );
        let r = rng.range(1.0, 3.0);
        let a0 = rng.range(0.0, TAU);
        let base = b.vertex_count() as u32;
        for k in 0..3 {
            // Three corners roughly a third of a turn apart, each with its own depth.
            let a = a0 + f64::from(k) * TAU / 3.0 + rng.range(-0.4, 0.4);
            b.push_position(c + DVec3::new(r * a.cos(), r * a.sin(), rng.range(-1.0, 1.0)));
        }
        b.push_face(&[base, base + 1, base + 2], None)
            .expect("indices in range");
    }
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new("triangles", b.finish().0)
            .with_color([0.85, 0.6, 0.3])
            .with_closed(false)
            .with_convex(false),
    )
    .expect("valid");
    s.set_camera(Some(Camera::perspective(
        DVec3::new(0.0, 0.0, 12.0),
        DVec3::ZERO,
        DVec3::Y,
        50.0,
        1.0,
        30.0,
    )));
    s
}

/// The seed of [`level`]'s generator.
const LEVEL_SEED: u64 = 24;

/// The cells of [`level`] across and deep: 7 x 5 (three rows of rooms, two of
/// corridors).
const LEVEL_SIZE: (usize, usize) = (7, 5);

/// The demo level (`demo:level`): 35 cells in a 7 x 5 grid, whose rows alternate rooms
/// (4 to 7 units a side, with furniture) and corridors (2 deep), joined by doors (a
/// random spanning tree of the grid plus about a quarter of the other walls), walls 3
/// high with door holes, floors and ceilings; its cells and portals set on the scene
/// ([`Scene::cells`]), and a camera inside the first room looking at its door.
/// [`level_walk`] walks it.
#[must_use]
pub fn level() -> Scene {
    level_scene(LEVEL_SIZE.0, LEVEL_SIZE.1, LEVEL_SEED)
}

/// A generated level of `n * n` cells (`demo:level-grid` is `level_grid(10)`, 100
/// cells: the PVS speed target), built like [`level`].
#[must_use]
pub fn level_grid(n: usize) -> Scene {
    level_scene(n, n, LEVEL_SEED + 1)
}

fn level_scene(nx: usize, nz: usize, seed: u64) -> Scene {
    let plan = crate::cull::portals::floorplan::level_plan(nx, nz, seed);
    let (graph, mut scene) = plan.build().expect("the generated plan is valid");
    scene.set_cells(Some(std::sync::Arc::new(graph)));
    // In the first room's corner farthest from its first door, looking at the door.
    let room = &plan.rooms[0].polygon;
    let centre = room.iter().copied().sum::<glam::DVec2>() / room.len() as f64;
    let look = plan
        .doors
        .iter()
        .find(|d| d.rooms.contains(&0))
        .map_or(room[2], |d| (d.a + d.b) * 0.5);
    let corner = room
        .iter()
        .copied()
        .max_by(|a, b| a.distance(look).total_cmp(&b.distance(look)))
        .unwrap_or(room[0]);
    let eye = corner + (centre - corner).normalize_or_zero() * 0.8;
    scene.set_camera(Some(Camera::perspective(
        DVec3::new(eye.x, 1.6, eye.y),
        DVec3::new(look.x, 1.2, look.y),
        DVec3::Y,
        75.0,
        0.05,
        200.0,
    )));
    scene
}

/// A camera walk through [`level`]: a depth-first tour through its doors, 16 legs of 6
/// cameras (96 views), eyes 1.6 above the floor, always inside a cell.
#[must_use]
pub fn level_walk() -> Vec<Camera> {
    let plan = crate::cull::portals::floorplan::level_plan(LEVEL_SIZE.0, LEVEL_SIZE.1, LEVEL_SEED);
    crate::cull::portals::floorplan::plan_walk(&plan, 16, 6)
}

/// The default demo: interpenetrating and overlapping solids on a floor.
#[must_use]
pub fn default_scene() -> Scene {
    let mut s = Scene::new();
    let add = |s: &mut Scene, name: &str, mesh: Mesh, t: DMat4, color: [f32; 3]| {
        s.add(
            ObjectDesc::new(name, mesh)
                .with_transform(t)
                .with_color(color),
        )
        .expect("valid demo object");
    };
    add(
        &mut s,
        "floor",
        box_mesh(DVec3::new(-5.0, -0.25, -5.0), DVec3::new(5.0, 0.0, 5.0)),
        DMat4::IDENTITY,
        [0.78, 0.76, 0.72],
    );
    add(
        &mut s,
        "cube",
        box_mesh(DVec3::splat(-1.1), DVec3::splat(1.1)),
        DMat4::from_translation(DVec3::new(0.0, 1.1, 0.0)) * DMat4::from_rotation_y(0.5),
        [0.92, 0.55, 0.25],
    );
    add(
        &mut s,
        "torus",
        torus_mesh(1.55, 0.32, 64, 24),
        DMat4::from_translation(DVec3::new(0.9, 1.75, 0.9))
            * DMat4::from_rotation_y(-0.6)
            * DMat4::from_rotation_x(1.35),
        [0.3, 0.55, 0.92],
    );
    add(
        &mut s,
        "sphere",
        uv_sphere_mesh(1.0, 48, 24),
        DMat4::from_translation(DVec3::new(-1.3, 1.0, 1.25)),
        [0.45, 0.78, 0.4],
    );
    add(
        &mut s,
        "cone",
        cone_mesh(0.8, 2.6, 40),
        DMat4::from_translation(DVec3::new(1.9, 0.0, -1.6)) * DMat4::from_rotation_z(0.25),
        [0.95, 0.8, 0.3],
    );
    // Two thin panels crossing each other in front (interpenetrating, overlapping).
    let panel = || box_mesh(DVec3::new(-1.2, 0.0, -0.04), DVec3::new(1.2, 1.6, 0.04));
    add(
        &mut s,
        "panel A",
        panel(),
        DMat4::from_translation(DVec3::new(-0.6, 0.0, 2.9)) * DMat4::from_rotation_y(0.55),
        [0.75, 0.45, 0.85],
    );
    add(
        &mut s,
        "panel B",
        panel(),
        DMat4::from_translation(DVec3::new(0.4, 0.0, 2.8)) * DMat4::from_rotation_y(-0.6),
        [0.35, 0.8, 0.78],
    );
    s.set_camera(Some(Camera::perspective(
        DVec3::new(4.3, 3.6, 7.4),
        DVec3::new(0.1, 1.0, 0.6),
        DVec3::Y,
        40.0,
        0.5,
        40.0,
    )));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::EdgeAdjacency;

    /// Signed volume by the divergence theorem: positive for outward-facing closed meshes.
    fn signed_volume(m: &Mesh) -> f64 {
        (0..m.polygon_count())
            .map(|i| {
                let p = m.polygon_points(i);
                (1..p.len() - 1)
                    .map(|k| p[0].dot(p[k].cross(p[k + 1])))
                    .sum::<f64>()
                    / 6.0
            })
            .sum()
    }

    #[test]
    fn generators_are_closed_and_face_outward() {
        let cases = [
            (box_mesh(DVec3::ZERO, DVec3::new(1., 2., 3.)), 6.0, 1e-12),
            (uv_sphere_mesh(1.0, 64, 32), 4.0 / 3.0 * PI, 0.02),
            (
                torus_mesh(2.0, 0.5, 64, 32),
                2.0 * PI * PI * 2.0 * 0.25,
                0.02,
            ),
            (cone_mesh(1.0, 3.0, 64), PI, 0.01),
        ];
        for (mesh, volume, tol) in cases {
            assert!(EdgeAdjacency::new(&mesh).is_closed());
            let v = signed_volume(&mesh);
            assert!((v - volume).abs() / volume < tol, "volume {v} vs {volume}");
        }
    }

    #[test]
    fn demo_scenes_load() {
        for name in ["default", "seed-task", "cube", "city"] {
            let s = scene(name).unwrap();
            assert!(s.polygon_count() > 0, "{name}");
        }
        assert!(matches!(scene("nope"), Err(Error::UnknownDemo { .. })));
        let s = sphere(1000, 500);
        assert_eq!(s.triangle_count(), 998_000);
        let tris = scene("triangles").unwrap();
        assert_eq!(tris.triangle_count(), 10_000);
        assert!(!tris.objects()[0].closed);
        let city = scene("city").unwrap();
        assert_eq!(city.triangle_count(), 10_000 * 12 + 2);
    }
}
