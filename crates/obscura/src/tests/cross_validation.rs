//! Cross-validation: every hidden-surface algorithm except the octree must produce the
//! z-buffer's id image on generated scenes seen from several cameras.
//!
//! Two requirements per view: at least 99.9% of pixels agree, and every pixel that
//! differs is a *near tie*, found by brute force over all polygons: its sample lies
//! within `EDGE_TIE` pixels of a polygon edge (coverage is decided by rounding) or the
//! two nearest polygons there have depths within `DEPTH_TIE` (relative). A scene without
//! near ties therefore has to match on 100% of its pixels.

use crate::cull::backface::BackfaceMode;
use crate::raster::FillRule;
use crate::scene::random::{
    coplanar_grid, cyclic_triple, interpenetrating_quads, long_thin_triangles, mirrored,
    orbit_cameras, random_triangles,
};
use crate::scene::{Camera, ObjectDesc, demo};
use crate::surface::{Algorithm, AlgorithmStats, RenderOptions, render};
use crate::{Frame, Lens, PrepareOptions, PreparedView, Scene, Viewport, prepare};
use glam::{DMat4, DVec2, DVec3};

const EDGE_TIE: f64 = 1e-4;
const DEPTH_TIE: f64 = 1e-5;
const WIDTH: u32 = 80;
const HEIGHT: u32 = 60;

struct Case {
    name: String,
    scene: Scene,
    cameras: Vec<Camera>,
    backface: BackfaceMode,
}

fn case(name: &str, scene: Scene, seed: u64) -> Case {
    let cameras = orbit_cameras(&scene, 2, seed);
    Case {
        name: name.to_string(),
        scene,
        cameras,
        backface: BackfaceMode::Closed,
    }
}

fn combine(parts: &[(Scene, DMat4)]) -> Scene {
    let mut s = Scene::new();
    for (scene, t) in parts {
        for o in scene.objects() {
            s.add(ObjectDesc {
                name: o.name.clone(),
                mesh: o.mesh.clone(),
                transform: *t * o.transform,
                color: o.color,
                closed: Some(o.closed),
                convex: Some(o.convex),
            })
            .unwrap();
        }
    }
    s
}

fn solid(mesh: crate::scene::Mesh, t: DMat4) -> Scene {
    let mut s = Scene::new();
    s.add(ObjectDesc::new("solid", mesh).with_transform(t))
        .unwrap();
    s
}

/// The generated scenes: at least 30, each seen by three cameras (two perspective, the
/// second close enough to cut the scene with the near plane, and one orthographic).
fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for seed in 0..6 {
        v.push(case(
            &format!("random triangles {seed}"),
            random_triangles(40 + 30 * seed as usize, seed, 1.0, 0.45),
            seed,
        ));
    }
    for seed in 0..3 {
        v.push(case(
            &format!("long thin triangles {seed}"),
            long_thin_triangles(80, 100 + seed, 1.0),
            seed,
        ));
    }
    for seed in 0..4 {
        v.push(case(
            &format!("interpenetrating quads {seed}"),
            interpenetrating_quads(6 + 4 * seed as usize, 200 + seed, 1.0),
            seed,
        ));
    }
    for (k, t) in [
        DMat4::IDENTITY,
        DMat4::from_rotation_x(0.4),
        DMat4::from_rotation_y(2.0) * DMat4::from_rotation_x(-0.3),
    ]
    .into_iter()
    .enumerate()
    {
        let s = combine(&[(cyclic_triple(), t)]);
        v.push(case(&format!("cyclic triple {k}"), s, 300 + k as u64));
    }
    for seed in 0..3 {
        v.push(case(
            &format!("coplanar grid {seed}"),
            coplanar_grid(5 + seed as u32, 4, 400 + seed),
            seed,
        ));
    }
    // Dense meshes, closed: back faces culled.
    v.push(case(
        "dense sphere",
        solid(demo::uv_sphere_mesh(1.0, 64, 32), DMat4::IDENTITY),
        7,
    ));
    v.push(case(
        "dense torus",
        solid(
            demo::torus_mesh(1.0, 0.4, 48, 24),
            DMat4::from_rotation_x(0.9),
        ),
        8,
    ));
    v.push(case(
        "tiny triangles (sub-pixel)",
        solid(demo::uv_sphere_mesh(1.0, 160, 80), DMat4::IDENTITY),
        9,
    ));
    // Solids that interpenetrate, with n-gons (cone base, box quads).
    let inter = interpenetrating_solids();
    v.push(case("interpenetrating solids", inter, 10));
    let mut open = case(
        "interpenetrating solids, back faces kept",
        combine(&[(demo::default_scene(), DMat4::IDENTITY)]),
        11,
    );
    open.backface = BackfaceMode::Off;
    v.push(open);
    v.push(case("default demo", demo::default_scene(), 12));
    let sheets: Vec<(Scene, DMat4)> = (0..5)
        .map(|k| {
            let t = DMat4::from_translation(DVec3::new(
                0.15 * f64::from(k),
                0.1 * f64::from(k),
                -0.3 * f64::from(k),
            )) * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2 + 0.05 * f64::from(k));
            (solid(demo::grid_mesh(1.5, 1.0, 3, 2), DMat4::IDENTITY), t)
        })
        .collect();
    v.push(case("stacked parallel sheets", combine(&sheets), 17));
    v.push(case(
        "slivers among large triangles",
        combine(&[
            (long_thin_triangles(25, 501, 1.0), DMat4::IDENTITY),
            (random_triangles(12, 502, 0.6, 0.9), DMat4::IDENTITY),
        ]),
        18,
    ));
    v.push(case("small city", demo::city(6, 6, 5), 13));
    v.push(case(
        "mirrored default demo",
        mirrored(&demo::default_scene()),
        14,
    ));
    v.push(case(
        "mirrored random triangles",
        mirrored(&random_triangles(60, 77, 1.0, 0.5)),
        15,
    ));
    // A floor through the eye and objects crossing the near plane.
    let floor = combine(&[
        (
            solid(demo::grid_mesh(40.0, 40.0, 8, 8), DMat4::IDENTITY),
            DMat4::IDENTITY,
        ),
        (
            solid(
                demo::box_mesh(DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 1.5, 0.5)),
                DMat4::IDENTITY,
            ),
            DMat4::from_translation(DVec3::new(0.3, 0.0, -2.0)),
        ),
    ]);
    let mut c = case("floor crossing the eye plane", floor, 16);
    c.cameras = vec![
        Camera::perspective(
            DVec3::new(0.0, 0.8, 1.0),
            DVec3::new(0.2, 0.5, -3.0),
            DVec3::Y,
            70.0,
            0.05,
            30.0,
        ),
        Camera::perspective(
            DVec3::new(-0.2, 0.3, -1.0),
            DVec3::new(0.3, 0.6, -2.0),
            DVec3::Y,
            90.0,
            0.4,
            30.0,
        ),
    ];
    v.push(c);
    // Off-centre windows and non-square pixels (a camera's lens): shifted right and
    // down with wide pixels, shifted so far that the view axis is outside the picture
    // with narrow ones, and an orthographic window shifted left.
    let mut c = case(
        "interpenetrating solids through shifted lenses",
        interpenetrating_solids(),
        19,
    );
    let lens = |x: f64, y: f64, pixel_aspect: f64| Lens {
        shift: DVec2::new(x, y),
        pixel_aspect,
    };
    let eye = DVec3::new(1.2, 1.0, 3.2);
    c.cameras = vec![
        Camera {
            lens: lens(0.2, -0.15, 1.3),
            ..Camera::perspective(eye, DVec3::ZERO, DVec3::Y, 40.0, 0.5, 20.0)
        },
        Camera {
            lens: lens(-0.7, 0.55, 0.8),
            ..Camera::perspective(eye, DVec3::new(1.0, -0.8, 0.0), DVec3::Y, 35.0, 0.5, 20.0)
        },
        Camera {
            lens: lens(-0.3, 0.1, 1.0),
            ..Camera::orthographic(eye, DVec3::ZERO, DVec3::Y, 2.2, 0.1, 20.0)
        },
    ];
    v.push(c);
    v
}

/// Interpenetrating solids (a box, a sphere and a cone) with n-gons.
fn interpenetrating_solids() -> Scene {
    combine(&[
        (
            solid(
                demo::box_mesh(DVec3::splat(-0.6), DVec3::splat(0.6)),
                DMat4::from_rotation_y(0.3),
            ),
            DMat4::IDENTITY,
        ),
        (
            solid(demo::uv_sphere_mesh(0.7, 24, 12), DMat4::IDENTITY),
            DMat4::from_translation(DVec3::new(0.5, 0.3, 0.2)),
        ),
        (
            solid(demo::cone_mesh(0.5, 1.6, 11), DMat4::IDENTITY),
            DMat4::from_translation(DVec3::new(-0.4, -0.5, 0.3)),
        ),
    ])
}

/// Brute force: whether pixel `(i, j)` is a near tie for the polygons of the view.
fn near_tie(view: &PreparedView<'_>, i: u32, j: u32) -> bool {
    let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
    let vp = view.viewport();
    let mut depths: Vec<f64> = Vec::new();
    for poly in view.polygons() {
        let pts = poly.screen_points();
        let n = pts.len();
        for k in 0..n {
            let (a, b) = (pts[k], pts[(k + 1) % n]);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len2 = dx * dx + dy * dy;
            if len2 == 0.0 {
                continue;
            }
            let t = (((px - a.0) * dx + (py - a.1) * dy) / len2).clamp(0.0, 1.0);
            let (cx, cy) = (a.0 + t * dx - px, a.1 + t * dy - py);
            if (cx * cx + cy * cy).sqrt() < EDGE_TIE {
                return true;
            }
        }
        if let Some(cov) = poly.coverage(FillRule::TopLeft, vp.width, vp.height)
            && cov.covers(i, j)
            && let Some(plane) = poly.depth_plane()
        {
            depths.push(view.transform().depth_of_zq(plane.at(px, py)));
        }
    }
    depths.sort_by(f64::total_cmp);
    depths
        .windows(2)
        .next()
        .is_some_and(|w| (w[1] - w[0]).abs() <= DEPTH_TIE * w[0].abs().max(1e-12))
}

/// Whether the algorithm draws the z-buffer's stored depth keys (so its depths must be
/// the z-buffer's exactly, see [`crate::view::ViewTransform::depth_of_key`]).
fn stores_keys(algorithm: Algorithm) -> bool {
    !matches!(
        algorithm,
        Algorithm::Raycast
            | Algorithm::RaycastBounds
            | Algorithm::RaycastBvh
            | Algorithm::RaycastGrid
            | Algorithm::Octree
    )
}

/// Checks one algorithm on every view; returns how many views were compared.
fn check_algorithm(algorithm: Algorithm, cases: &[Case]) -> usize {
    let vp = Viewport::new(u64::from(WIDTH), u64::from(HEIGHT)).unwrap();
    let mut views = 0;
    let mut failures = Vec::new();
    for c in cases {
        for (k, cam) in c.cameras.iter().enumerate() {
            let view = prepare(
                &c.scene,
                cam,
                vp,
                &PrepareOptions::default().with_backface(c.backface),
            )
            .unwrap();
            let reference: Frame = render(Algorithm::ZBuffer, &view, &RenderOptions::default())
                .unwrap()
                .0;
            let frame = match render(algorithm, &view, &RenderOptions::default()) {
                Ok((f, _)) => f,
                Err(e) => panic!("{algorithm} failed on {} camera {k}: {e}", c.name),
            };
            views += 1;
            let diff = frame.differences(&reference);
            let real: Vec<_> = diff
                .iter()
                .filter(|&&(x, y, _, _)| !near_tie(&view, x, y))
                .collect();
            // The algorithms that store `f32` depth keys share the z-buffer's rule from
            // key to depth, so where they show the same face their depths must be its
            // depths bit for bit. (Their keys come from the same plane evaluated in
            // `f64` in another order; on these scenes that never reaches the `f32`
            // rounding. Ray casting measures depth along its rays instead.)
            if stores_keys(algorithm) {
                let off = (0..frame.ids.len())
                    .filter(|&k| {
                        frame.ids[k] == reference.ids[k]
                            && frame.depth[k].to_bits() != reference.depth[k].to_bits()
                    })
                    .count();
                if off > 0 {
                    failures.push(format!(
                        "{algorithm} on \"{}\" camera {k}: {off} pixels show the z-buffer's face with another depth",
                        c.name
                    ));
                }
            }
            let agree = 1.0 - diff.len() as f64 / vp.pixel_count() as f64;
            if agree < 0.999 || !real.is_empty() {
                failures.push(format!(
                    "{algorithm} on \"{}\" camera {k}: {:.4}% agree, {} differing pixels of which {} are not near ties; first (x, y, {algorithm} id, z-buffer id): {:?}",
                    c.name,
                    agree * 100.0,
                    diff.len(),
                    real.len(),
                    &real[..real.len().min(8)]
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    views
}

#[test]
fn there_are_at_least_thirty_scenes_with_several_cameras() {
    let cases = cases();
    assert!(cases.len() >= 30, "{} scenes", cases.len());
    assert!(cases.iter().all(|c| c.cameras.len() >= 2));
    // Every view shows something (a test that renders nothing proves nothing).
    let vp = Viewport::new(u64::from(WIDTH), u64::from(HEIGHT)).unwrap();
    for c in &cases {
        for (k, cam) in c.cameras.iter().enumerate() {
            let view = prepare(
                &c.scene,
                cam,
                vp,
                &PrepareOptions::default().with_backface(c.backface),
            )
            .unwrap();
            let f = render(Algorithm::ZBuffer, &view, &RenderOptions::default())
                .unwrap()
                .0;
            assert!(
                f.covered_pixels() > 30,
                "\"{}\" camera {k} shows only {} pixels",
                c.name,
                f.covered_pixels()
            );
        }
    }
}

#[test]
fn the_near_tie_oracle_is_strict() {
    // On a scene of separated triangles in general position almost no pixel is a near tie:
    // the oracle must not excuse everything.
    let s = random_triangles(30, 5, 1.0, 0.3);
    let cam = orbit_cameras(&s, 1, 3)[0];
    let vp = Viewport::new(u64::from(WIDTH), u64::from(HEIGHT)).unwrap();
    let view = prepare(&s, &cam, vp, &PrepareOptions::default()).unwrap();
    let ties = (0..HEIGHT)
        .flat_map(|j| (0..WIDTH).map(move |i| (i, j)))
        .filter(|&(i, j)| near_tie(&view, i, j))
        .count();
    assert!(ties < 5, "{ties} near-tie pixels");
}

macro_rules! cross_check {
    ($name:ident, $algo:expr) => {
        #[test]
        fn $name() {
            let cases = cases();
            let views: usize = cases.iter().map(|c| c.cameras.len()).sum();
            assert_eq!(check_algorithm($algo, &cases), views);
        }
    };
}

cross_check!(scanline_matches_zbuffer, Algorithm::Scanline);
cross_check!(depth_sort_matches_zbuffer, Algorithm::DepthSort);
cross_check!(
    depth_sort_matrix_matches_zbuffer,
    Algorithm::DepthSortMatrix
);
cross_check!(bsp_matches_zbuffer, Algorithm::Bsp);
cross_check!(warnock_matches_zbuffer, Algorithm::Warnock);
cross_check!(raycast_matches_zbuffer, Algorithm::Raycast);
cross_check!(raycast_bounds_matches_zbuffer, Algorithm::RaycastBounds);
cross_check!(raycast_bvh_matches_zbuffer, Algorithm::RaycastBvh);
cross_check!(raycast_grid_matches_zbuffer, Algorithm::RaycastGrid);

/// The harness itself must be able to fail: the octree only approximates the scene by
/// voxels, so it is rejected.
#[test]
#[should_panic(expected = "are not near ties")]
fn the_harness_rejects_an_approximate_algorithm() {
    check_algorithm(Algorithm::Octree, &cases()[..2]);
}

/// A scene on a lattice of dyadic coordinates, seen orthographically so that pixel
/// centres fall exactly on edges and vertices: a height field of triangles sharing
/// their edges, lattice triangles crossing it, and boxes, all inside a `w x h` window.
fn lattice_scene(rng: &mut crate::rng::SplitMix64, w: u32, h: u32) -> (Scene, Camera) {
    let mut pick = |n: u64| (rng.next_u64() % n) as f64;
    let mut polys: Vec<Vec<DVec3>> = Vec::new();
    let (nx, ny) = (1 + pick(6) as usize, 1 + pick(6) as usize);
    let cell = 1.0 + pick(8);
    let (ox, oy) = (pick(u64::from(w)) * 0.5, pick(u64::from(h)) * 0.5);
    let heights: Vec<f64> = (0..(nx + 1) * (ny + 1))
        .map(|_| (pick(33) - 16.0) * 0.25)
        .collect();
    let at = |i: usize, j: usize| {
        DVec3::new(
            ox + i as f64 * cell,
            oy + j as f64 * cell,
            heights[j * (nx + 1) + i],
        )
    };
    for i in 0..nx {
        for j in 0..ny {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if pick(2) == 0.0 {
                polys.extend([vec![a, b, c], vec![a, c, d]]);
            } else {
                polys.extend([vec![a, b, d], vec![b, c, d]]);
            }
        }
    }
    for _ in 0..pick(12) as usize {
        let mut point = || {
            DVec3::new(
                (pick(2 * u64::from(w) + 3) - 1.0) * 0.5,
                (pick(2 * u64::from(h) + 3) - 1.0) * 0.5,
                (pick(33) - 16.0) * 0.25,
            )
        };
        polys.push(vec![point(), point(), point()]);
    }
    let mut scene = Scene::new();
    let mut b = crate::scene::MeshBuilder::new();
    for p in &polys {
        let first = b.vertex_count() as u32;
        for &q in p {
            b.push_position(q);
        }
        // Degenerate lattice triangles are dropped by the builder.
        let _ = b.push_face(&[first, first + 1, first + 2], None);
    }
    let (mesh, _) = b.finish();
    if mesh.polygon_count() > 0 {
        scene.add(ObjectDesc::new("lattice", mesh)).unwrap();
    }
    for k in 0..pick(3) as usize {
        let lo = DVec3::new(
            pick(u64::from(w)),
            pick(u64::from(h)),
            (pick(17) - 8.0) * 0.25,
        );
        let size = DVec3::new(1.0 + pick(8), 1.0 + pick(8), (1.0 + pick(8)) * 0.25);
        scene
            .add(
                ObjectDesc::new(format!("box{k}"), demo::box_mesh(lo, lo + size)).with_closed(true),
            )
            .unwrap();
    }
    let c = DVec3::new(f64::from(w) * 0.5, f64::from(h) * 0.5, 0.0);
    let cam = Camera::orthographic(c + DVec3::Z * 8.0, c, DVec3::Y, f64::from(h), 1.0, 16.0);
    (scene, cam)
}

/// The list-priority algorithms split polygons; the pieces of a polygon must cover
/// each of its pixels once. Painting each piece by its own vertices left cracks where
/// a piece was cut again (a T-junction: the new vertex on the edge it shares with its
/// sibling is rounded off that edge, and a pixel centre on the edge fell between the
/// two): background, or a farther face, showing through a surface. On lattice scenes
/// whose pixel centres lie exactly on edges, BSP, depth sort and its matrix variant
/// must show background exactly where the z-buffer does.
#[test]
fn split_pieces_leave_no_cracks_on_lattice_scenes() {
    let mut rng = crate::rng::SplitMix64(2026);
    let sizes = [(13, 7), (16, 8), (32, 32), (31, 17), (64, 16)];
    let algorithms = [
        Algorithm::Bsp,
        Algorithm::DepthSort,
        Algorithm::DepthSortMatrix,
    ];
    let mut split_views = 0;
    for case in 0..600 {
        let (w, h) = sizes[case % sizes.len()];
        let (scene, cam) = lattice_scene(&mut rng, w, h);
        let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
        let prep = PrepareOptions::default().with_backface(BackfaceMode::Off);
        let view = prepare(&scene, &cam, vp, &prep).unwrap();
        let fill = if case % 4 == 0 {
            FillRule::Inclusive
        } else {
            FillRule::TopLeft
        };
        let opts = RenderOptions::default().with_fill_rule(fill);
        let (z, _) = render(Algorithm::ZBuffer, &view, &opts).unwrap();
        for algo in algorithms {
            let (frame, stats) = render(algo, &view, &opts).unwrap();
            let splits = match &stats.algorithm {
                AlgorithmStats::Bsp(s) => s.bsp_splits,
                AlgorithmStats::DepthSort(s) => s.splits,
                AlgorithmStats::DepthSortMatrix(s) => s.splits,
                other => panic!("{algo:?} reports no splits: {other:?}"),
            };
            split_views += usize::from(splits > 0);
            let holes: Vec<(usize, u32, u32)> = (0..z.ids.len())
                .filter(|&i| (z.ids[i] == crate::BACKGROUND) != (frame.ids[i] == crate::BACKGROUND))
                .map(|i| (i % w as usize, frame.ids[i], z.ids[i]))
                .collect();
            assert!(
                holes.is_empty(),
                "case {case} {algo:?} ({w}x{h}, {fill:?}): coverage differs from the z-buffer \
                 at (column, id, z-buffer id) {holes:?}"
            );
        }
    }
    // The scenes do make the algorithms split.
    assert!(split_views > 300, "{split_views}");
}
