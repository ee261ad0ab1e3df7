//! Generated test scenes: random and adversarial configurations for cross-validating the
//! algorithms and for benchmark sweeps. All deterministic for a given seed.
//!
//! | generator | what it stresses |
//! | --- | --- |
//! | [`random_triangles`] | general position, overlap, interpenetration |
//! | [`long_thin_triangles`] | slivers: edge coverage, sorting by extents |
//! | [`interpenetrating_quads`] | faces crossing each other (depth order changes inside a face) |
//! | [`cyclic_triple`] | three triangles each over the next: no valid depth order |
//! | [`coplanar_grid`] | coplanar faces sharing edges (the fill rule) |
//! | [`scaled_triangles`] | a fixed screen footprint split into `n` triangles (complexity sweeps) |

#[cfg(test)]
use std::f64::consts::TAU;

#[cfg(test)]
use glam::DMat4;
use glam::DVec3;

use super::{Camera, Mesh, MeshBuilder, ObjectDesc, Scene};
use crate::rng::SplitMix64;

fn soup(tris: &[[DVec3; 3]]) -> Mesh {
    let mut b = MeshBuilder::with_capacity(tris.len() * 3, tris.len());
    for t in tris {
        let base = b.vertex_count() as u32;
        for &p in t {
            b.push_position(p);
        }
        b.push_face(&[base, base + 1, base + 2], None)
            .expect("indices in range");
    }
    b.finish().0
}

#[cfg(test)]
fn unit_vector(rng: &mut SplitMix64) -> DVec3 {
    let z = rng.range(-1.0, 1.0);
    let a = rng.range(0.0, TAU);
    let r = (1.0 - z * z).sqrt();
    DVec3::new(r * a.cos(), r * a.sin(), z)
}

fn scene_of(name: &str, mesh: Mesh, color: [f32; 3]) -> Scene {
    let mut s = Scene::new();
    s.add(
        ObjectDesc::new(name, mesh)
            .with_color(color)
            .with_closed(false)
            .with_convex(false),
    )
    .expect("generated geometry is finite");
    s
}

#[cfg(test)]
/// `n` triangles with centres uniform in the cube `[-extent, extent]^3` and vertices
/// within `size` of their centre: one open object (a triangle soup).
#[must_use]
pub fn random_triangles(n: usize, seed: u64, extent: f64, size: f64) -> Scene {
    let mut rng = SplitMix64(seed);
    let tris: Vec<[DVec3; 3]> = (0..n)
        .map(|_| {
            let c = DVec3::new(
                rng.range(-extent, extent),
                rng.range(-extent, extent),
                rng.range(-extent, extent),
            );
            [0; 3].map(|_| c + unit_vector(&mut rng) * size * rng.range(0.3, 1.0))
        })
        .collect();
    scene_of("random triangles", soup(&tris), [0.8, 0.6, 0.4])
}

#[cfg(test)]
/// `n` slivers: length about `2 * extent`, width 1% to 3% of it, random orientations.
#[must_use]
pub fn long_thin_triangles(n: usize, seed: u64, extent: f64) -> Scene {
    let mut rng = SplitMix64(seed);
    let tris: Vec<[DVec3; 3]> = (0..n)
        .map(|_| {
            let c = DVec3::new(
                rng.range(-extent, extent),
                rng.range(-extent, extent),
                rng.range(-extent, extent),
            ) * 0.3;
            let dir = unit_vector(&mut rng) * extent;
            let side = dir.cross(unit_vector(&mut rng)).normalize_or(DVec3::X)
                * extent
                * rng.range(0.01, 0.03);
            [c - dir, c + dir, c + side]
        })
        .collect();
    scene_of("long thin triangles", soup(&tris), [0.5, 0.7, 0.9])
}

#[cfg(test)]
/// `n` square quads of side `2 * size` through a small region, randomly tilted, so
/// that most pairs interpenetrate.
#[must_use]
pub fn interpenetrating_quads(n: usize, seed: u64, size: f64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut b = MeshBuilder::new();
    for _ in 0..n {
        let c = DVec3::new(
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
        ) * size;
        let u = unit_vector(&mut rng);
        let v = u.cross(unit_vector(&mut rng)).normalize_or(DVec3::Y);
        let w = u.cross(v);
        let base = b.vertex_count() as u32;
        for (a, bb) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            b.push_position(c + (v * a + w * bb) * size);
        }
        b.push_face(&[base, base + 1, base + 2, base + 3], None)
            .expect("in range");
    }
    scene_of("interpenetrating quads", b.finish().0, [0.6, 0.85, 0.5])
}

#[cfg(test)]
/// Three tilted blades arranged as a pinwheel: each blade's centre line is tangent to
/// a circle around the origin, rotated by 120 degrees from the last, and rises along its
/// length, so where blade `k` crosses blade `k + 1` it is the higher one. Each lies over
/// the next: a cyclic overlap that no ordering of whole faces can paint.
#[must_use]
pub fn cyclic_triple() -> Scene {
    let mut tris = Vec::new();
    for k in 0..3 {
        let a = f64::from(k) * TAU / 3.0;
        let (dir, side) = (
            DVec3::new(a.cos(), a.sin(), 0.0),
            DVec3::new(-a.sin(), a.cos(), 0.0),
        );
        let p = side * 0.4;
        let at = |s: f64, w: f64| p + dir * s + side * w + DVec3::Z * (0.3 + s * 0.6 / 3.2);
        tris.push([at(-1.6, 0.45), at(-1.6, -0.45), at(1.6, 0.0)]);
    }
    scene_of("cyclic triple", soup(&tris), [0.9, 0.5, 0.5])
}

#[cfg(test)]
/// A flat grid of `nx * ny` quads in the plane z = 0, each split into two triangles
/// along alternating diagonals, vertices jittered in the plane: coplanar faces that
/// share edges everywhere.
#[must_use]
pub fn coplanar_grid(nx: u32, ny: u32, seed: u64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut b = MeshBuilder::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let jitter = if i == 0 || j == 0 || i == nx || j == ny {
                0.0
            } else {
                0.3
            };
            let x = f64::from(i) + rng.range(-jitter, jitter);
            let y = f64::from(j) + rng.range(-jitter, jitter);
            b.push_position(DVec3::new(
                x - f64::from(nx) / 2.0,
                y - f64::from(ny) / 2.0,
                0.0,
            ));
        }
    }
    let v = |i: u32, j: u32| j * (nx + 1) + i;
    for j in 0..ny {
        for i in 0..nx {
            let (a, bb, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            if (i + j) % 2 == 0 {
                b.push_face(&[a, bb, c], None).expect("in range");
                b.push_face(&[a, c, d], None).expect("in range");
            } else {
                b.push_face(&[a, bb, d], None).expect("in range");
                b.push_face(&[bb, c, d], None).expect("in range");
            }
        }
    }
    scene_of("coplanar grid", b.finish().0, [0.85, 0.8, 0.4])
}

/// About `n` triangles whose projections tile a fixed screen area several layers deep,
/// for complexity sweeps: as `n` grows each triangle shrinks, so the covered pixel
/// count stays about the same (the assumption behind the z-buffer's O(p)).
#[must_use]
pub fn scaled_triangles(n: usize, seed: u64) -> Scene {
    let layers = 4usize;
    let per_layer = n.div_ceil(layers).max(2);
    let cells = ((per_layer / 2) as f64).sqrt().ceil().max(1.0) as usize;
    let mut rng = SplitMix64(seed);
    let mut tris = Vec::with_capacity(n);
    'outer: for layer in 0..layers {
        let z = -(layer as f64) * 0.5;
        let step = 4.0 / cells as f64;
        for j in 0..cells {
            for i in 0..cells {
                let (x, y) = (-2.0 + i as f64 * step, -2.0 + j as f64 * step);
                let jit = |r: &mut SplitMix64| r.range(-0.05, 0.05) * step;
                let p = |r: &mut SplitMix64, dx: f64, dy: f64| {
                    DVec3::new(
                        x + dx * step + jit(r),
                        y + dy * step + jit(r),
                        z + r.range(-0.2, 0.2),
                    )
                };
                let (a, b, c, d) = (
                    p(&mut rng, 0.0, 0.0),
                    p(&mut rng, 1.0, 0.0),
                    p(&mut rng, 1.0, 1.0),
                    p(&mut rng, 0.0, 1.0),
                );
                tris.push([a, b, c]);
                if tris.len() == n {
                    break 'outer;
                }
                tris.push([a, c, d]);
                if tris.len() == n {
                    break 'outer;
                }
            }
        }
    }
    let mut s = scene_of("scaled triangles", soup(&tris), [0.7, 0.7, 0.9]);
    s.set_camera(Some(Camera::perspective(
        DVec3::new(0.0, 0.0, 6.0),
        DVec3::ZERO,
        DVec3::Y,
        45.0,
        1.0,
        20.0,
    )));
    s
}

#[cfg(test)]
/// Cameras around a scene: `count` perspective views from random directions at 1.5 to
/// 3 bounding radii, the last one at 1.1 radii with its near plane through the middle of
/// the bounds (so it cuts the scene); and one orthographic view.
#[must_use]
pub fn orbit_cameras(scene: &Scene, count: usize, seed: u64) -> Vec<Camera> {
    let mut rng = SplitMix64(seed);
    let b = scene.bounds();
    let (c, r) = (b.center(), (b.extent().length() * 0.5).max(1e-6));
    let mut cams = Vec::with_capacity(count + 1);
    for k in 0..count {
        let dir = unit_vector(&mut rng);
        let close = k + 1 == count;
        let dist = if close {
            r * 1.1
        } else {
            r * rng.range(1.5, 3.0)
        };
        let eye = c + dir * dist;
        let up = if dir.cross(DVec3::Y).length() > 0.1 {
            DVec3::Y
        } else {
            DVec3::X
        };
        // The close camera's near plane passes through the middle of the bounds.
        let near = if close {
            dist - r * 0.5
        } else {
            (dist - r).max(r * 0.01)
        };
        cams.push(Camera::perspective(
            eye,
            c,
            up,
            rng.range(40.0, 75.0),
            near,
            dist + r * 1.5,
        ));
    }
    let dir = unit_vector(&mut rng);
    let up = if dir.cross(DVec3::Y).length() > 0.1 {
        DVec3::Y
    } else {
        DVec3::X
    };
    cams.push(Camera::orthographic(
        c + dir * r * 3.0,
        c,
        up,
        r * 2.2,
        r * 0.5,
        r * 6.0,
    ));
    cams
}

#[cfg(test)]
/// A scene with the given objects' transforms mirrored (negative determinant), to check
/// that winding is handled.
#[must_use]
pub fn mirrored(scene: &Scene) -> Scene {
    let mut s = Scene::new();
    let m = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
    for o in scene.objects() {
        s.add(ObjectDesc {
            name: format!("{} (mirrored)", o.name),
            mesh: o.mesh.clone(),
            transform: m * o.transform,
            color: o.color,
            closed: Some(o.closed),
            convex: Some(o.convex),
        })
        .expect("mirroring keeps geometry finite");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generators_make_what_they_say() {
        assert_eq!(random_triangles(50, 1, 1.0, 0.3).polygon_count(), 50);
        assert_eq!(long_thin_triangles(20, 2, 1.0).polygon_count(), 20);
        assert_eq!(interpenetrating_quads(10, 3, 1.0).polygon_count(), 10);
        assert_eq!(cyclic_triple().polygon_count(), 3);
        assert_eq!(coplanar_grid(4, 3, 4).polygon_count(), 24);
        for n in [100, 1000, 12345] {
            assert_eq!(scaled_triangles(n, 5).polygon_count(), n);
        }
        let s = random_triangles(5, 9, 1.0, 0.3);
        assert_eq!(orbit_cameras(&s, 3, 1).len(), 4);
        for c in orbit_cameras(&s, 3, 1) {
            c.validate().unwrap();
        }
        assert!(mirrored(&s).objects()[0].mirrored);
    }

    #[test]
    fn cyclic_triple_really_overlaps_cyclically() {
        // Sample the plane; where two blades' projections both contain a point, the one
        // with the larger z there is "over". Every blade must be over the next one.
        let s = cyclic_triple();
        let o = &s.objects()[0];
        let tris: Vec<Vec<DVec3>> = (0..3).map(|k| o.world_polygon(k)).collect();
        let height = |t: &[DVec3], x: f64, y: f64| -> Option<f64> {
            let d = (t[1].x - t[0].x) * (t[2].y - t[0].y) - (t[2].x - t[0].x) * (t[1].y - t[0].y);
            let u = ((x - t[0].x) * (t[2].y - t[0].y) - (t[2].x - t[0].x) * (y - t[0].y)) / d;
            let v = ((t[1].x - t[0].x) * (y - t[0].y) - (x - t[0].x) * (t[1].y - t[0].y)) / d;
            (u > 0.0 && v > 0.0 && u + v < 1.0)
                .then(|| t[0].z + u * (t[1].z - t[0].z) + v * (t[2].z - t[0].z))
        };
        let mut over = [[false; 3]; 3];
        for i in -100..=100 {
            for j in -100..=100 {
                let (x, y) = (f64::from(i) * 0.02, f64::from(j) * 0.02);
                let h: Vec<Option<f64>> = tris.iter().map(|t| height(t, x, y)).collect();
                for a in 0..3 {
                    for b in 0..3 {
                        if let (Some(ha), Some(hb)) = (h[a], h[b])
                            && ha > hb
                        {
                            over[a][b] = true;
                        }
                    }
                }
            }
        }
        let forward = (0..3).all(|k| over[k][(k + 1) % 3]);
        let backward = (0..3).all(|k| over[(k + 1) % 3][k]);
        assert!(forward != backward, "not a strict cycle: {over:?}");
        for k in 0..3 {
            assert!(
                !(over[k][(k + 1) % 3] && over[(k + 1) % 3][k]),
                "blades {k} and {} interpenetrate",
                (k + 1) % 3
            );
        }
    }
}
