//! Roberts' algorithm (lines::roberts): seed 004's worked examples with the corrected
//! values of ALGORITHMS.md, and drawings of boxes checked against an independent
//! sampling reference (points along every piece, the segment to the viewer cut
//! analytically against every box).

use glam::{DMat4, DQuat, DVec3, DVec4};
use obscura::bench_support::SplitMix64;
use obscura::lines::roberts::{RobertsOptions, body_matrix, draw, edge_against_body, self_hidden};
use obscura::lines::{Drawing, EdgeKind};
use obscura::scene::{Camera, ObjectDesc, Scene, Viewport, demo};
use obscura::view::{PrepareOptions, View};

/// The seed's corrected body matrix of the unit cube centred at the origin:
/// -2x+1, 2x+1, -2y+1, 2y+1, -2z+1, 2z+1 (all >= 0 inside).
fn seed_cube() -> [DVec4; 6] {
    [
        DVec4::new(-2.0, 0.0, 0.0, 1.0),
        DVec4::new(2.0, 0.0, 0.0, 1.0),
        DVec4::new(0.0, -2.0, 0.0, 1.0),
        DVec4::new(0.0, 2.0, 0.0, 1.0),
        DVec4::new(0.0, 0.0, -2.0, 1.0),
        DVec4::new(0.0, 0.0, 2.0, 1.0),
    ]
}

/// The viewer at +z infinity: the direction towards it.
const G: DVec4 = DVec4::new(0.0, 0.0, 1.0, 0.0);

#[test]
fn seed_body_matrix_and_self_hidden_face() {
    // The uncorrected matrix of the seed (2x - 1, ... as printed) and the interior
    // point (1, 1, 1, 4): the products (-2, 6, -2, 6, -2, 6).
    let printed = [
        DVec4::new(2.0, 0.0, 0.0, -1.0),
        DVec4::new(2.0, 0.0, 0.0, 1.0),
        DVec4::new(0.0, 2.0, 0.0, -1.0),
        DVec4::new(0.0, 2.0, 0.0, 1.0),
        DVec4::new(0.0, 0.0, 2.0, -1.0),
        DVec4::new(0.0, 0.0, 2.0, 1.0),
    ];
    let s = DVec4::new(1.0, 1.0, 1.0, 4.0);
    let products: Vec<f64> = printed.iter().map(|c| s.dot(*c)).collect();
    assert_eq!(products, [-2.0, 6.0, -2.0, 6.0, -2.0, 6.0]);

    // body_matrix on the cube's faces in the seed's order (x = 1/2, x = -1/2, y =
    // 1/2, ...) gives the corrected columns, halved (unit normals).
    let cube = demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5));
    // box_mesh's faces: -x, +x, -y, +y, -z, +z; the seed's: +x, -x, +y, -y, +z, -z.
    let polygons: Vec<Vec<DVec3>> = [1, 0, 3, 2, 5, 4]
        .iter()
        .map(|&i| cube.polygon_points(i))
        .collect();
    let (columns, of_polygon) = body_matrix(&polygons);
    assert_eq!(of_polygon, (0..6).map(Some).collect::<Vec<_>>());
    let doubled: Vec<DVec4> = columns.iter().map(|c| *c * 2.0).collect();
    assert_eq!(doubled, seed_cube());

    // Viewer at +z, looking down -z: E = (0, 0, -1, 0) gives (0, 0, 0, 0, 2, -2), so
    // face 6 (z = -1/2) is self-hidden.
    let e = DVec4::new(0.0, 0.0, -1.0, 0.0);
    let products: Vec<f64> = seed_cube().iter().map(|c| e.dot(*c)).collect();
    assert_eq!(products, [0.0, 0.0, 0.0, 0.0, 2.0, -2.0]);
    assert_eq!(
        self_hidden(&seed_cube(), e),
        [false, false, false, false, false, true]
    );
}

#[test]
fn seed_example_hidden_segment() {
    // ALGORITHMS.md example 2: the segment (-2, 0, -2)-(2, 0, -2) behind the cube.
    let s = DVec4::new(-2.0, 0.0, -2.0, 1.0);
    let d = DVec4::new(4.0, 0.0, 0.0, 0.0);
    for penetration in [false, true] {
        let r = edge_against_body(&seed_cube(), s, d, G, penetration);
        assert_eq!(r.p, [5.0, -3.0, 1.0, 1.0, 5.0, -3.0]);
        assert_eq!(r.q, [-8.0, 8.0, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(r.w, [0.0, 0.0, 0.0, 0.0, -2.0, 2.0]);
        assert!(!r.trivially_visible);
        assert_eq!(r.hidden, Some((3.0 / 8.0, 5.0 / 8.0)), "{penetration}");
    }
}

#[test]
fn seed_example_penetrating_segment_corrected() {
    // ALGORITHMS.md example 3 (the seed's slides print other vectors): the segment
    // (-1, 0, -2)-(1, 0, 2) through the cube.
    let s = DVec4::new(-1.0, 0.0, -2.0, 1.0);
    let d = DVec4::new(2.0, 0.0, 4.0, 0.0);
    let r = edge_against_body(&seed_cube(), s, d, G, true);
    assert_eq!(r.p, [3.0, -1.0, 1.0, 1.0, 5.0, -3.0]);
    assert_eq!(r.q, [-4.0, 4.0, 0.0, 0.0, -8.0, 8.0]);
    assert_eq!(r.w, [0.0, 0.0, 0.0, 0.0, -2.0, 2.0]);
    // Hidden for 1/4 < t < 5/8: behind the cube from 1/4, inside from 3/8 (entering
    // through the back face), out through the front face at 5/8.
    assert_eq!(r.hidden, Some((1.0 / 4.0, 5.0 / 8.0)));
    // Without the bound a = 0 the corners (3/8, 0) and (5/8, 0) are not found: the
    // remaining corners all have t = 1/4, and nothing is hidden. This is why the seed
    // adds a = 0 when the edge may pierce the body.
    let r = edge_against_body(&seed_cube(), s, d, G, false);
    assert_eq!(r.hidden, None);
}

#[test]
fn segment_beside_or_in_front_of_the_cube_is_visible() {
    // In front (z = 2): the plane -2z + 1 is negative all along and falls towards
    // the viewer, so the edge is wholly visible by it alone.
    let r = edge_against_body(
        &seed_cube(),
        DVec4::new(-2.0, 0.0, 2.0, 1.0),
        DVec4::new(4.0, 0.0, 0.0, 0.0),
        G,
        true,
    );
    assert!(r.trivially_visible);
    assert_eq!(r.hidden, None);
    // Behind but beside (y = 2): never inside.
    let r = edge_against_body(
        &seed_cube(),
        DVec4::new(-2.0, 2.0, -2.0, 1.0),
        DVec4::new(4.0, 0.0, 0.0, 0.0),
        G,
        true,
    );
    assert_eq!(r.hidden, None);
    // Lying on the back face (z = -1/2) across it: the face is behind the segment's
    // own points, nothing is in front of them.
    let r = edge_against_body(
        &seed_cube(),
        DVec4::new(-1.0, 0.0, 0.5, 1.0),
        DVec4::new(2.0, 0.0, 0.0, 0.0),
        G,
        true,
    );
    assert_eq!(r.hidden, None);
}

// ---------------------------------------------------------------------------------
// Drawings against a sampling reference.

/// A box: centre, half extents, rotation.
#[derive(Clone, Copy, Debug)]
struct Boxed {
    centre: DVec3,
    half: DVec3,
    rotation: DQuat,
}

impl Boxed {
    fn transform(&self) -> DMat4 {
        DMat4::from_rotation_translation(self.rotation, self.centre)
    }

    /// The open interval of `u` in `(0, u_max]` where `o + u dir` is strictly inside
    /// (slabs in the box's frame), as a length in `u`.
    fn inside_length(&self, o: DVec3, dir: DVec3, u_max: f64) -> f64 {
        self.inside(o, dir, u_max).map_or(0.0, |(lo, hi)| hi - lo)
    }

    /// The interval of `u` in `[0, u_max]` where `o + u dir` is inside, if any.
    fn inside(&self, o: DVec3, dir: DVec3, u_max: f64) -> Option<(f64, f64)> {
        let inv = self.rotation.inverse();
        let (o, dir) = (inv * (o - self.centre), inv * dir);
        let (mut lo, mut hi) = (0.0f64, u_max);
        for k in 0..3 {
            if dir[k] == 0.0 {
                if o[k].abs() >= self.half[k] {
                    return None;
                }
                continue;
            }
            let a = (-self.half[k] - o[k]) / dir[k];
            let b = (self.half[k] - o[k]) / dir[k];
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
        (hi > lo).then_some((lo, hi))
    }
}

fn scene_of(boxes: &[Boxed]) -> Scene {
    let mut scene = Scene::new();
    for (i, b) in boxes.iter().enumerate() {
        let desc = ObjectDesc::new(format!("box{i}"), demo::box_mesh(-b.half, b.half))
            .with_transform(b.transform());
        scene.add(desc).unwrap();
    }
    scene
}

fn random_boxes(rng: &mut SplitMix64, n: usize, spread: f64) -> Vec<Boxed> {
    (0..n)
        .map(|_| Boxed {
            centre: DVec3::new(
                rng.range(-spread, spread),
                rng.range(-spread, spread),
                rng.range(-spread, spread),
            ),
            half: DVec3::new(
                rng.range(0.3, 1.2),
                rng.range(0.3, 1.2),
                rng.range(0.3, 1.2),
            ),
            rotation: DQuat::from_euler(
                glam::EulerRot::XYZ,
                rng.range(0.0, 6.3),
                rng.range(0.0, 6.3),
                rng.range(0.0, 6.3),
            ),
        })
        .collect()
}

/// Whether the world point `p` is hidden, by the reference: the segment to the eye
/// (perspective) or the ray towards the viewer (parallel) passes strictly through some
/// box for a length above `margin`. `None` when it is too close to call.
fn reference_hidden(boxes: &[Boxed], camera: &Camera, p: DVec3) -> Option<bool> {
    // Only what lies beyond the near plane hides, as the view clips it.
    let forward = (camera.target - camera.eye).normalize();
    let depth = (p - camera.eye).dot(forward);
    let (dir, u_max) = if matches!(camera.projection, obscura::Projection::Orthographic { .. }) {
        (-forward, depth - camera.near)
    } else {
        (camera.eye - p, 1.0 - camera.near / depth)
    };
    let scale = dir.length() * u_max;
    let deepest = boxes
        .iter()
        .map(|b| b.inside_length(p, dir, u_max) * scale)
        .fold(0.0, f64::max);
    if deepest > 1e-3 {
        Some(true)
    } else if deepest < 1e-9 {
        Some(false)
    } else {
        None
    }
}

/// The number of faces in front of the world point `p`, by the reference: 2 for each
/// box the segment to the viewer passes through, 1 for a box it starts in or on.
/// `None` when it is too close to call.
fn reference_count(boxes: &[Boxed], camera: &Camera, p: DVec3) -> Option<u32> {
    let forward = (camera.target - camera.eye).normalize();
    let depth = (p - camera.eye).dot(forward);
    let (dir, u_max) = if matches!(camera.projection, obscura::Projection::Orthographic { .. }) {
        (-forward, depth - camera.near)
    } else {
        (camera.eye - p, 1.0 - camera.near / depth)
    };
    let scale = dir.length();
    let mut count = 0;
    for b in boxes {
        if let Some((lo, hi)) = b.inside(p, dir, u_max) {
            let (lo, hi) = (lo * scale, hi * scale);
            if hi - lo > 1e-3 {
                if lo < 1e-9 {
                    count += 1;
                } else if lo > 1e-3 {
                    count += 2;
                } else {
                    return None;
                }
            } else if hi - lo > 1e-9 {
                return None;
            }
        }
    }
    Some(count)
}

/// Checks every piece of a quantitative drawing at interior points against the
/// reference count; returns the number of points compared.
fn check_counts(drawing: &Drawing, boxes: &[Boxed], camera: &Camera, label: &str) -> usize {
    let mut compared = 0;
    for piece in &drawing.pieces {
        let edge = &drawing.edges[piece.edge as usize];
        let [a, b] = piece.t;
        if piece.length() < 2.0 {
            continue;
        }
        for f in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let t = a + (b - a) * f;
            let near: Vec<Option<u32>> = [-1e-4, 0.0, 1e-4]
                .iter()
                .map(|dt| reference_count(boxes, camera, edge.point(t + dt)))
                .collect();
            if near.iter().any(Option::is_none) || near[0] != near[1] || near[1] != near[2] {
                continue;
            }
            assert_eq!(
                near[1].unwrap(),
                piece.invisibility,
                "{label}: edge {} ({:?}) at t = {t} (piece {:?})",
                piece.edge,
                edge.kind,
                piece.t
            );
            compared += 1;
        }
    }
    compared
}

/// Checks every piece of a drawing at interior points against the reference; returns
/// the number of points compared.
fn check(drawing: &Drawing, boxes: &[Boxed], camera: &Camera, label: &str) -> usize {
    check_with(drawing, &|p| reference_hidden(boxes, camera, p), label)
}

/// [`check`] with any reference.
fn check_with(drawing: &Drawing, reference: &dyn Fn(DVec3) -> Option<bool>, label: &str) -> usize {
    let mut compared = 0;
    for piece in &drawing.pieces {
        let edge = &drawing.edges[piece.edge as usize];
        let [a, b] = piece.t;
        if piece.length() < 2.0 {
            continue;
        }
        for f in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let t = a + (b - a) * f;
            let p = edge.point(t);
            // Near a change of visibility the reference cannot call it either way.
            let near: Vec<Option<bool>> = [-1e-4, 0.0, 1e-4]
                .iter()
                .map(|dt| reference(edge.point(t + dt)))
                .collect();
            if near.iter().any(Option::is_none) || near[0] != near[1] || near[1] != near[2] {
                continue;
            }
            let hidden = near[1].unwrap();
            assert_eq!(
                hidden,
                !piece.is_visible(),
                "{label}: edge {} ({:?}) at t = {t} (piece {:?}, point {p})",
                piece.edge,
                edge.kind,
                piece.t
            );
            compared += 1;
        }
    }
    compared
}

/// Pieces of each edge are contiguous and increasing.
fn check_pieces_tile_edges(drawing: &Drawing) {
    let mut last: Option<(u32, f64)> = None;
    for p in &drawing.pieces {
        assert!(p.t[0] < p.t[1]);
        if let Some((_, t)) = last.filter(|&(e, _)| e == p.edge) {
            assert!((p.t[0] - t).abs() < 1e-12, "gap in edge {}", p.edge);
        }
        last = Some((p.edge, p.t[1]));
    }
}

fn view<'s>(scene: &'s Scene, camera: &Camera, w: u32, h: u32) -> View<'s> {
    View::new(
        scene,
        camera,
        Viewport::new(u64::from(w), u64::from(h)).unwrap(),
        &PrepareOptions::default(),
    )
    .unwrap()
}

#[test]
fn random_boxes_match_the_sampling_reference() {
    let mut rng = SplitMix64(23);
    let mut total = 0;
    for round in 0..8 {
        let boxes = random_boxes(&mut rng, 6, 2.0);
        let scene = scene_of(&boxes);
        let dir = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        let camera = if round % 2 == 0 {
            Camera::perspective(dir * 14.0, DVec3::ZERO, DVec3::Y, 45.0, 0.5, 100.0)
        } else {
            Camera::orthographic(dir * 14.0, DVec3::ZERO, DVec3::Y, 9.0, 0.5, 100.0)
        };
        let v = view(&scene, &camera, 320, 240);
        let (drawing, stats) = draw(&v, &RobertsOptions::default()).unwrap();
        check_pieces_tile_edges(&drawing);
        // Body edges in object order, then the intersection lines.
        let objects: Vec<u32> = drawing
            .edges
            .iter()
            .map(|e| {
                if e.kind == EdgeKind::Crease {
                    e.object.unwrap()
                } else {
                    u32::MAX
                }
            })
            .collect();
        assert!(objects.windows(2).all(|w| w[0] <= w[1]));
        let label = format!("round {round} ({stats:?})");
        let n = check(&drawing, &boxes, &camera, &label);
        assert!(n > 100, "{label}: only {n} points compared");
        assert!(
            drawing.visible().count() > 0 && drawing.hidden().count() > 0,
            "{label}"
        );
        total += n;
        // Quantitative: the same visible pieces, hidden ones with their face counts.
        let mut options = RobertsOptions::default();
        options.quantitative = true;
        let (counted, _) = draw(&v, &options).unwrap();
        check_pieces_tile_edges(&counted);
        let visible = |d: &Drawing| -> Vec<(u32, [i64; 2])> {
            d.visible()
                .filter(|p| p.t[1] - p.t[0] > 1e-9)
                .map(|p| (p.edge, p.t.map(|t| (t * 1e8).round() as i64)))
                .collect()
        };
        assert_eq!(visible(&counted), visible(&drawing), "{label}");
        let n = check_counts(&counted, &boxes, &camera, &label);
        assert!(n > 100, "{label}: only {n} counts compared");
        assert!(
            counted.pieces.iter().any(|p| p.invisibility >= 2),
            "{label}"
        );
    }
    assert!(total > 2000, "{total}");
}

#[test]
fn self_hidden_planes_are_the_views_back_faces() {
    let mut rng = SplitMix64(5);
    for round in 0..4 {
        let boxes = random_boxes(&mut rng, 3, 3.0);
        let scene = scene_of(&boxes);
        let camera = if round % 2 == 0 {
            Camera::perspective(
                DVec3::new(3.0, 5.0, 12.0),
                DVec3::ZERO,
                DVec3::Y,
                50.0,
                0.5,
                80.0,
            )
        } else {
            Camera::orthographic(
                DVec3::new(-7.0, 4.0, 9.0),
                DVec3::ZERO,
                DVec3::Y,
                12.0,
                0.5,
                80.0,
            )
        };
        let v = view(&scene, &camera, 160, 120);
        let (drawing, stats) = draw(&v, &RobertsOptions::default()).unwrap();
        // A box shows 1 to 3 faces: 3 to 5 back faces... each box has 6 planes.
        assert_eq!(stats.planes, 18);
        let back = v.back_facing().iter().filter(|&&b| b).count() as u64;
        assert_eq!(stats.self_hidden_planes, back, "round {round}");
        // An edge is self-hidden exactly when both its polygons are back faces.
        let hidden_by_faces = drawing
            .edges
            .iter()
            .filter(|e| e.faces.iter().all(|f| v.back_facing()[f.unwrap() as usize]))
            .count() as u64;
        assert_eq!(stats.self_hidden_edges, hidden_by_faces);
    }
}

#[test]
fn unit_cube_from_a_corner_shows_nine_edges() {
    let scene = demo::cube();
    for camera in [
        Camera::orthographic(DVec3::splat(5.0), DVec3::ZERO, DVec3::Y, 3.0, 0.5, 20.0),
        Camera::perspective(DVec3::splat(5.0), DVec3::ZERO, DVec3::Y, 40.0, 0.5, 20.0),
    ] {
        let v = view(&scene, &camera, 200, 200);
        let (d, _) = draw(&v, &RobertsOptions::default()).unwrap();
        assert_eq!(d.edges.len(), 12);
        assert!(d.edges.iter().all(|e| e.kind == EdgeKind::Crease));
        assert_eq!(d.visible().count(), 9);
        assert_eq!(d.hidden().count(), 3);
        // Whole edges, pixel coordinates inside the picture.
        for p in &d.pieces {
            assert_eq!(p.t, [0.0, 1.0]);
            for q in p.points {
                assert!((0.0..=200.0).contains(&q.x) && (0.0..=200.0).contains(&q.y));
            }
        }
    }
}

#[test]
fn triangulated_faces_draw_no_diagonals() {
    // The cube as 12 triangles: the diagonals lie between coplanar triangles.
    let cube = demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5));
    let mut b = obscura::scene::MeshBuilder::new();
    for p in cube.positions() {
        b.push_position(*p);
    }
    for i in 0..6 {
        let f = cube.polygon(i);
        b.push_face(&[f[0], f[1], f[2]], None).unwrap();
        b.push_face(&[f[0], f[2], f[3]], None).unwrap();
    }
    let (mesh, _) = b.finish();
    let mut scene = Scene::new();
    scene.add(ObjectDesc::new("triangles", mesh)).unwrap();
    let camera = Camera::perspective(
        DVec3::new(2.0, 3.0, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        0.5,
        20.0,
    );
    let v = view(&scene, &camera, 100, 100);
    let (d, stats) = draw(&v, &RobertsOptions::default()).unwrap();
    assert_eq!(d.edges.len(), 12);
    assert_eq!(stats.planes, 6);
    assert_eq!(d.visible().count(), 9);
}

#[test]
fn interpenetrating_boxes_give_their_penetration_lines() {
    // B pokes out of A's +x face (x = 1): the intersection line is the square
    // x = 1, y and z in [-0.25, 0.25].
    let boxes = [
        Boxed {
            centre: DVec3::ZERO,
            half: DVec3::splat(1.0),
            rotation: DQuat::IDENTITY,
        },
        Boxed {
            centre: DVec3::new(1.5, 0.0, 0.0),
            half: DVec3::new(1.0, 0.25, 0.25),
            rotation: DQuat::IDENTITY,
        },
    ];
    let scene = scene_of(&boxes);
    let camera = Camera::perspective(
        DVec3::new(6.0, 3.0, 5.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        0.5,
        30.0,
    );
    let v = view(&scene, &camera, 300, 300);
    let (d, stats) = draw(&v, &RobertsOptions::default()).unwrap();
    let lines: Vec<_> = d
        .edges
        .iter()
        .filter(|e| e.kind == EdgeKind::Intersection)
        .collect();
    assert_eq!(lines.len(), 4, "{stats:?}");
    // B's four long edges leave A through its +x face.
    assert_eq!(stats.penetration_points, 4);
    let mut corners: Vec<[i64; 2]> = Vec::new();
    for e in &lines {
        for p in e.world {
            assert!((p.x - 1.0).abs() < 1e-12, "{p}");
            assert!((p.y.abs() - 0.25).abs() < 1e-12 && (p.z.abs() - 0.25).abs() < 1e-12);
            corners.push([(p.y * 4.0).round() as i64, (p.z * 4.0).round() as i64]);
        }
        assert_eq!(e.object, Some(0));
        // The polygons: A's +x face (polygon 1) and one of B's four sides.
        assert_eq!(e.faces[0], Some(1));
        assert!(matches!(e.faces[1], Some(8..=11)), "{:?}", e.faces);
    }
    corners.sort();
    corners.dedup();
    assert_eq!(corners.len(), 4);
    // Seen from +x, +y, +z: the line's two sides facing the viewer (+y, +z) are
    // visible, the two others hidden by B itself.
    let visible_lines = lines
        .iter()
        .filter(|e| {
            let m = e.point(0.5);
            m.y > 0.2 || m.z > 0.2
        })
        .count();
    assert_eq!(visible_lines, 2);
    for piece in &d.pieces {
        let e = &d.edges[piece.edge as usize];
        if e.kind == EdgeKind::Intersection {
            let m = e.point(0.5);
            assert_eq!(piece.is_visible(), m.y > 0.2 || m.z > 0.2, "{m}");
        }
    }
    // B's edges inside A are hidden, and all of it checks against the reference.
    check_pieces_tile_edges(&d);
    assert!(check(&d, &boxes, &camera, "interpenetrating") > 50);
    // Without intersections: only the 24 box edges.
    let mut options = RobertsOptions::default();
    options.intersections = false;
    let (d, _) = draw(&v, &options).unwrap();
    assert_eq!(d.edges.len(), 24);
}

#[test]
fn non_convex_input_is_refused_by_name() {
    let mut scene = Scene::new();
    scene
        .add(ObjectDesc::new(
            "box",
            demo::box_mesh(DVec3::splat(-1.0), DVec3::splat(1.0)),
        ))
        .unwrap();
    scene
        .add(
            ObjectDesc::new("doughnut", demo::torus_mesh(1.0, 0.3, 16, 8))
                .with_transform(DMat4::from_translation(DVec3::new(0.0, 0.0, 3.0))),
        )
        .unwrap();
    let camera = Camera::perspective(
        DVec3::new(0.0, 2.0, 12.0),
        DVec3::new(0.0, 0.0, 1.5),
        DVec3::Y,
        50.0,
        0.5,
        50.0,
    );
    let v = view(&scene, &camera, 64, 64);
    let err = draw(&v, &RobertsOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("doughnut") && err.contains("convex"), "{err}");
    // A convex flag forced on a non-convex mesh is refused too.
    let mut scene = Scene::new();
    scene
        .add(
            ObjectDesc::new("liar", demo::torus_mesh(1.0, 0.3, 16, 8))
                .with_convex(true)
                .with_closed(true),
        )
        .unwrap();
    let v = view(&scene, &camera, 64, 64);
    let err = draw(&v, &RobertsOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("liar"), "{err}");
}

#[test]
fn a_box_across_the_near_plane_hides_only_beyond_it() {
    // B spans depths 2..4 with the near plane at 3.5: beyond it, it covers
    // |x / depth| <= 1.5 / 3.5 = 0.43; the whole of it would cover up to 0.75. A's
    // front edges at x = +-5.5, depth 9.5 (0.58) are visible.
    let boxes = [
        Boxed {
            centre: DVec3::ZERO,
            half: DVec3::new(5.5, 5.5, 0.5),
            rotation: DQuat::IDENTITY,
        },
        Boxed {
            centre: DVec3::new(0.0, 0.0, 7.0),
            half: DVec3::new(1.5, 1.5, 1.0),
            rotation: DQuat::IDENTITY,
        },
    ];
    let scene = scene_of(&boxes);
    let camera = Camera::perspective(
        DVec3::new(0.0, 0.0, 10.0),
        DVec3::ZERO,
        DVec3::Y,
        90.0,
        3.5,
        50.0,
    );
    let v = view(&scene, &camera, 200, 200);
    let (d, _) = draw(&v, &RobertsOptions::default()).unwrap();
    check_pieces_tile_edges(&d);
    assert!(check(&d, &boxes, &camera, "near plane") > 20);
    // A's four front edges (z = 0.5) are wholly visible.
    let front: Vec<_> = d
        .pieces
        .iter()
        .filter(|p| {
            let e = &d.edges[p.edge as usize];
            e.object == Some(0) && e.world.iter().all(|w| w.z == 0.5)
        })
        .collect();
    assert_eq!(front.len(), 4);
    assert!(front.iter().all(|p| p.is_visible() && p.t == [0.0, 1.0]));
    // B's edges are clipped at the near plane: nothing of them nearer than 3.5.
    for p in &d.pieces {
        let e = &d.edges[p.edge as usize];
        if e.object == Some(1) {
            for t in p.t {
                assert!(
                    10.0 - e.point(t).z >= 3.5 * (1.0 - 1e-6),
                    "{:?}",
                    e.point(t)
                );
            }
        }
    }
}

#[test]
fn boxes_touching_along_a_face_hide_nothing_there() {
    // A unit box with another stacked on it: seen from (3, 4, 5), the upper box shows
    // 9 edges, the lower 7 (its top face's far edges lie on the upper box's far
    // bottom edges and are hidden by it); the two seams are drawn by both boxes.
    let boxes = [
        Boxed {
            centre: DVec3::splat(0.5),
            half: DVec3::splat(0.5),
            rotation: DQuat::IDENTITY,
        },
        Boxed {
            centre: DVec3::new(0.5, 1.5, 0.5),
            half: DVec3::splat(0.5),
            rotation: DQuat::IDENTITY,
        },
    ];
    let scene = scene_of(&boxes);
    let camera = Camera::perspective(
        DVec3::new(3.0, 4.0, 5.0),
        DVec3::new(0.5, 1.0, 0.5),
        DVec3::Y,
        40.0,
        0.5,
        30.0,
    );
    let v = view(&scene, &camera, 300, 300);
    let (d, stats) = draw(&v, &RobertsOptions::default()).unwrap();
    check_pieces_tile_edges(&d);
    assert!(check(&d, &boxes, &camera, "stacked") > 50);
    assert_eq!(stats.intersection_lines, 0, "{stats:?}");
    let visible = |object| {
        d.visible()
            .filter(|p| d.edges[p.edge as usize].object == Some(object))
            .count()
    };
    assert_eq!((visible(0), visible(1)), (7, 9));
}

/// The interval of `u` in `[0, u_max]` where `o + u dir` is inside the convex body of
/// world planes `(n, d)` (inside `n . x + d < 0`, outward normals), if any.
fn convex_inside(planes: &[(DVec3, f64)], o: DVec3, dir: DVec3, u_max: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (0.0f64, u_max);
    for &(n, d) in planes {
        let (a, b) = (n.dot(o) + d, n.dot(dir));
        if b == 0.0 {
            if a >= 0.0 {
                return None;
            }
        } else if b > 0.0 {
            hi = hi.min(-a / b);
        } else {
            lo = lo.max(-a / b);
        }
    }
    (hi > lo).then_some((lo, hi))
}

#[test]
fn spheres_of_many_planes_match_the_reference() {
    // Two overlapping polyhedral spheres (264 faces each: the bodies of many planes
    // are cut by clipping) and a box; perspective.
    let mut scene = Scene::new();
    let placements = [
        DMat4::from_translation(DVec3::new(-0.6, 0.0, 0.0)),
        DMat4::from_translation(DVec3::new(0.6, 0.3, 0.2)) * DMat4::from_scale(DVec3::splat(0.8)),
    ];
    for (i, m) in placements.iter().enumerate() {
        scene
            .add(
                ObjectDesc::new(format!("sphere{i}"), demo::uv_sphere_mesh(1.0, 24, 12))
                    .with_transform(*m),
            )
            .unwrap();
    }
    scene
        .add(ObjectDesc::new(
            "box",
            demo::box_mesh(DVec3::new(-2.5, -0.4, -2.0), DVec3::new(-1.0, 0.4, -1.2)),
        ))
        .unwrap();
    // Outward world planes of every object, from its polygons.
    let bodies: Vec<Vec<(DVec3, f64)>> = scene
        .objects()
        .iter()
        .map(|o| {
            (0..o.mesh.polygon_count())
                .map(|i| {
                    let pts = o.world_polygon(i);
                    let n = obscura::geom::newell_normal(&pts).normalize();
                    (n, -n.dot(pts[0]))
                })
                .collect()
        })
        .collect();
    let camera = Camera::perspective(
        DVec3::new(2.0, 3.0, 6.0),
        DVec3::ZERO,
        DVec3::Y,
        50.0,
        0.5,
        30.0,
    );
    let reference = |p: DVec3| -> Option<bool> {
        let forward = (camera.target - camera.eye).normalize();
        let depth = (p - camera.eye).dot(forward);
        let dir = camera.eye - p;
        let u_max = 1.0 - camera.near / depth;
        let deepest = bodies
            .iter()
            .map(|b| convex_inside(b, p, dir, u_max).map_or(0.0, |(lo, hi)| hi - lo) * dir.length())
            .fold(0.0, f64::max);
        if deepest > 1e-3 {
            Some(true)
        } else if deepest < 1e-9 {
            Some(false)
        } else {
            None
        }
    };
    let v = view(&scene, &camera, 400, 300);
    let (d, stats) = draw(&v, &RobertsOptions::default()).unwrap();
    assert!(stats.planes > 500, "{stats:?}");
    assert!(stats.intersection_lines > 20, "{stats:?}");
    check_pieces_tile_edges(&d);
    let n = check_with(&d, &reference, "spheres");
    assert!(n > 300, "{n}");
}

/// `demo:blocks` (the city's buildings without its ground) is the demo Roberts takes:
/// every edge drawn, and the drawing agrees with the library's sampling check (ray
/// casting through the scene's BVH) and with the exact HLR's visible length.
#[test]
fn demo_blocks_agree_with_ray_casting_and_hlr() {
    use obscura::SceneIndex;
    use obscura::lines::check::{CheckOptions, check};
    use obscura::lines::hlr::{self, HlrOptions};
    let scene = Scene::demo("blocks").unwrap();
    let vp = Viewport::new(640, 360).unwrap();
    let camera = scene.default_camera(vp.aspect());
    let v = View::new(&scene, &camera, vp, &PrepareOptions::default()).unwrap();
    let index = SceneIndex::new(&scene);
    let (d, _) = draw(&v, &RobertsOptions::default()).unwrap();
    assert!(d.visible().count() > 100 && d.hidden().count() > 100);
    let report = check(&index, &v, &d, &CheckOptions::default());
    assert!(report.samples > 0 && report.agrees(), "{report:?}");
    let (h, _) = hlr::draw(&index, &v, &HlrOptions::default()).unwrap();
    let length = |d: &Drawing| d.visible().map(|p| p.length()).sum::<f64>();
    let (a, b) = (length(&d), length(&h));
    assert!(
        (a - b).abs() <= 1e-6 * b,
        "visible length: roberts {a}, hlr {b}"
    );
}
