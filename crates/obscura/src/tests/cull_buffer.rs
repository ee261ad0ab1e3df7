//! The occlusion buffer (issue 24, item 4) against ground truth: the z-buffer of the
//! whole scene says which faces are visible; every one must survive the culling, and
//! the picture with culling must equal the picture without it (ids and depths). The
//! buffers themselves against brute force: per pixel, the nearest key of the
//! triangles covering its sample, which the buffer's bound must never pass.

use glam::{DMat4, DVec3};

use crate::SceneIndex;
use crate::cpu::{Avx2, Avx512, Kernel};
use crate::cull::buffer::masked::{self, MaskedBuffer};
use crate::cull::buffer::raster::{Poly, Tri};
use crate::cull::buffer::{BufferKind, BufferOptions, OcclusionBuffer};
use crate::cull::occlusion::{CullMethod, CullOptions, CullReason};
use crate::frame::BACKGROUND;
use crate::rng::SplitMix64;
use crate::scene::{Camera, ObjectDesc, Scene, Viewport, demo};
use crate::surface::{Algorithm, RenderOptions};
use crate::view::{PrepareOptions, View};

/// What one view's check found.
#[derive(Default, Debug)]
struct Tally {
    /// Objects without a visible pixel that the frustum kept.
    hidden: usize,
    /// Of those, culled by the buffer.
    hidden_culled: usize,
    /// Clusters culled by the buffer.
    clusters_culled: usize,
}

impl std::ops::AddAssign for Tally {
    fn add_assign(&mut self, o: Tally) {
        self.hidden += o.hidden;
        self.hidden_culled += o.hidden_culled;
        self.clusters_culled += o.clusters_culled;
    }
}

fn options(kind: BufferKind, divisor: u32, clusters: bool) -> CullOptions {
    let mut o = CullOptions::with_method(CullMethod::Buffer);
    o.clusters = clusters;
    o.buffer = BufferOptions {
        kind,
        divisor,
        keep_image: true,
        ..BufferOptions::default()
    };
    o
}

/// The main check: conservative (every face visible in the full z-buffer survives)
/// and the same picture with and without culling.
fn check(
    scene: &Scene,
    index: &SceneIndex<'_>,
    camera: &Camera,
    vp: Viewport,
    o: &CullOptions,
) -> Tally {
    let po = PrepareOptions::default();
    let ro = RenderOptions::default();
    let plain = View::new(scene, camera, vp, &po).unwrap();
    let (f0, _) = index.render_view(&plain, Algorithm::ZBuffer, &ro).unwrap();
    let culling = index.cull(camera, vp, o).unwrap();
    // Scene polygon bases and face ranges of the objects.
    let objects = scene.objects();
    let mut base = Vec::new();
    let mut b = 0usize;
    for ob in objects {
        base.push(b);
        b += ob.mesh.polygon_count();
    }
    let mut seen = vec![false; objects.len()];
    for &id in &f0.ids {
        if id == BACKGROUND {
            continue;
        }
        let k = objects
            .iter()
            .rposition(|ob| ob.first_face <= id)
            .expect("an object of the face");
        let ob = &objects[k];
        let local = id - ob.first_face;
        seen[k] = true;
        for p in ob.mesh.polygons_of_face(local) {
            assert!(
                !culling.faces[base[k] + p],
                "visible face {id} (object {k} {}, polygon {p}) culled: object {:?}, camera {camera:?}",
                ob.name,
                culling.objects[k]
            );
        }
    }
    let mut t = Tally::default();
    for (k, ob) in objects.iter().enumerate() {
        if !seen[k]
            && ob.mesh.polygon_count() > 0
            && culling.objects[k] != Some(CullReason::Frustum)
        {
            t.hidden += 1;
            if culling.objects[k] == Some(CullReason::Buffer) {
                t.hidden_culled += 1;
            }
        }
    }
    t.clusters_culled = culling.stats.clusters_by_reason.buffer as usize;
    let image = culling.buffer_image.as_ref().expect("keep_image fills it");
    assert_eq!(image.depth.len(), (image.width * image.height) as usize);
    let culled = View::new_culled(scene, camera, vp, &po, culling).unwrap();
    let (f1, _) = index.render_view(&culled, Algorithm::ZBuffer, &ro).unwrap();
    assert_eq!(f0.ids, f1.ids, "ids differ with culling, camera {camera:?}");
    assert_eq!(
        f0.depth, f1.depth,
        "depths differ with culling, camera {camera:?}"
    );
    t
}

/// Street-level cameras in `city(10, 10, _)`: on the street lines between the blocks
/// (x or z at an integer), eye height about 1.7, random headings.
fn street_cameras(count: usize, seed: u64, orthographic: bool) -> Vec<Camera> {
    let mut rng = SplitMix64(seed);
    (0..count)
        .map(|_| {
            let line = (rng.range(-4.0, 4.0)).round();
            let along = rng.range(-4.8, 4.8);
            let eye = if rng.next_f64() < 0.5 {
                DVec3::new(line, rng.range(1.5, 1.9), along)
            } else {
                DVec3::new(along, rng.range(1.5, 1.9), line)
            };
            let a = rng.range(0.0, std::f64::consts::TAU);
            let target = eye + DVec3::new(a.cos(), rng.range(-0.15, 0.05), a.sin());
            if orthographic {
                Camera::orthographic(eye, target, DVec3::Y, rng.range(1.0, 4.0), 0.05, 60.0)
            } else {
                Camera::perspective(eye, target, DVec3::Y, rng.range(40.0, 80.0), 0.05, 60.0)
            }
        })
        .collect()
}

#[test]
fn city_from_street_level_is_conservative_and_culls_most_hidden_boxes() {
    let scene = demo::city(10, 10, 3);
    let index = SceneIndex::new(&scene);
    let vp = Viewport::new(160, 90).unwrap();
    let mut total = Tally::default();
    for (i, cam) in street_cameras(16, 11, false).iter().enumerate() {
        let kind = if i % 2 == 0 {
            BufferKind::Masked
        } else {
            BufferKind::HierarchicalZ
        };
        total += check(&scene, &index, cam, vp, &options(kind, 1, i % 4 < 2));
    }
    let fraction = total.hidden_culled as f64 / total.hidden.max(1) as f64;
    println!(
        "city street level: the buffer culled {} of {} hidden boxes the frustum kept ({:.1}%)",
        total.hidden_culled,
        total.hidden,
        100.0 * fraction
    );
    assert!(total.hidden > 50, "{total:?}: the views must hide boxes");
    assert!(
        fraction > 0.5,
        "{total:?}: culls {fraction:.3} of the hidden boxes"
    );
}

#[test]
fn city_orthographic_and_coarse_buffers_are_conservative() {
    let scene = demo::city(10, 10, 4);
    let index = SceneIndex::new(&scene);
    let vp = Viewport::new(160, 90).unwrap();
    let mut total = Tally::default();
    for (i, cam) in street_cameras(8, 5, true).iter().enumerate() {
        let kind = if i % 2 == 0 {
            BufferKind::Masked
        } else {
            BufferKind::HierarchicalZ
        };
        total += check(
            &scene,
            &index,
            cam,
            vp,
            &options(kind, 1 + (i as u32 % 3), true),
        );
    }
    for (i, cam) in street_cameras(6, 9, false).iter().enumerate() {
        let kind = if i % 2 == 0 {
            BufferKind::Masked
        } else {
            BufferKind::HierarchicalZ
        };
        total += check(
            &scene,
            &index,
            cam,
            vp,
            &options(kind, 2 + (i as u32 % 3), true),
        );
    }
    println!("city orthographic and coarse: {total:?}");
    assert!(total.hidden_culled > 0, "{total:?}: nothing culled at all");
}

/// Random axis-aligned and rotated boxes in a cube, one object each.
fn random_boxes(n: usize, seed: u64) -> Scene {
    let mut rng = SplitMix64(seed);
    let mut s = Scene::new();
    let unit = std::sync::Arc::new(demo::box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5)));
    for i in 0..n {
        let c = DVec3::new(
            rng.range(-8.0, 8.0),
            rng.range(-8.0, 8.0),
            rng.range(-8.0, 8.0),
        );
        let size = DVec3::new(
            rng.range(0.3, 4.0),
            rng.range(0.3, 4.0),
            rng.range(0.3, 4.0),
        );
        let t = DMat4::from_translation(c)
            * DMat4::from_rotation_y(rng.range(0.0, 3.0))
            * DMat4::from_rotation_x(rng.range(0.0, 3.0))
            * DMat4::from_scale(size);
        s.add(ObjectDesc {
            name: format!("box {i}"),
            mesh: unit.clone(),
            transform: t,
            color: [0.7, 0.7, 0.7],
            closed: Some(true),
            convex: Some(true),
        })
        .unwrap();
    }
    s
}

#[test]
fn random_boxes_from_inside_and_outside_both_projections_are_conservative() {
    let vp = Viewport::new(120, 90).unwrap();
    let mut total = Tally::default();
    for seed in 0..3u64 {
        let scene = random_boxes(60, seed);
        let index = SceneIndex::new(&scene);
        let mut rng = SplitMix64(seed + 100);
        for i in 0..8 {
            let eye = DVec3::new(
                rng.range(-12.0, 12.0),
                rng.range(-12.0, 12.0),
                rng.range(-12.0, 12.0),
            );
            let target = DVec3::new(
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
            );
            let cam = if i % 3 == 2 {
                Camera::orthographic(eye, target, DVec3::Y, rng.range(4.0, 20.0), 0.1, 60.0)
            } else {
                Camera::perspective(eye, target, DVec3::Y, rng.range(30.0, 90.0), 0.1, 60.0)
            };
            let kind = if i % 2 == 0 {
                BufferKind::Masked
            } else {
                BufferKind::HierarchicalZ
            };
            total += check(
                &scene,
                &index,
                &cam,
                vp,
                &options(kind, 1 + (i % 2), i % 4 < 2),
            );
        }
    }
    println!("random boxes: {total:?}");
    assert!(total.hidden_culled > 0, "{total:?}");
}

#[test]
fn mirrored_city_and_sponza_like_single_object_are_conservative() {
    // Mirroring flips the winding: the occluders' front faces must follow.
    let scene = crate::scene::random::mirrored(&demo::city(8, 8, 2));
    let index = SceneIndex::new(&scene);
    let vp = Viewport::new(128, 72).unwrap();
    let mut total = Tally::default();
    for cam in street_cameras(6, 21, false) {
        let cam = Camera {
            eye: cam.eye * DVec3::new(0.8, 1.0, 0.8),
            target: cam.target * DVec3::new(0.8, 1.0, 0.8),
            ..cam
        };
        total += check(
            &scene,
            &index,
            &cam,
            vp,
            &options(BufferKind::Masked, 1, true),
        );
    }
    // One big object: only its clusters can go.
    let mut one = Scene::new();
    let blocks = demo::blocks(6, 6, 8);
    let mut b = crate::scene::MeshBuilder::new();
    for o in blocks.objects() {
        let base = b.vertex_count() as u32;
        for &p in o.mesh.positions() {
            b.push_position(o.transform.transform_point3(p));
        }
        for i in 0..o.mesh.polygon_count() {
            let poly: Vec<u32> = o.mesh.polygon(i).iter().map(|&v| v + base).collect();
            b.push_face(&poly, None).unwrap();
        }
    }
    let _ = &mut one;
    let (mesh, _) = b.finish();
    one.add(ObjectDesc::new("all blocks", mesh)).unwrap();
    let index = SceneIndex::new(&one);
    let mut clusters = 0;
    for cam in street_cameras(6, 23, false) {
        let cam = Camera {
            eye: cam.eye * DVec3::new(0.6, 0.5, 0.6),
            target: cam.target * DVec3::new(0.6, 0.5, 0.6),
            ..cam
        };
        clusters += check(
            &one,
            &index,
            &cam,
            vp,
            &options(BufferKind::Masked, 1, true),
        )
        .clusters_culled;
    }
    println!("mirrored city {total:?}; one-object blocks: {clusters} clusters culled");
    assert!(
        clusters > 0,
        "the clusters of one big object are culled too"
    );
}

#[test]
fn degenerate_occluders_break_nothing() {
    // Zero-area triangles, slivers, edge-on quads and a wall, with boxes behind.
    let mut s = Scene::new();
    let mut b = crate::scene::MeshBuilder::new();
    let tri = |b: &mut crate::scene::MeshBuilder, p: [DVec3; 3]| {
        let i = p.map(|q| b.push_position(q));
        let _ = b.push_face(&i, None);
    };
    tri(
        &mut b,
        [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(2.0, 2.0, 0.0),
        ],
    );
    tri(
        &mut b,
        [
            DVec3::new(-3.0, 0.0, 0.0),
            DVec3::new(3.0, 1e-9, 0.0),
            DVec3::new(3.0, 2e-9, 0.0),
        ],
    );
    tri(
        &mut b,
        [
            DVec3::new(-3.0, -1.0, 1.0),
            DVec3::new(3.0, -1.0, 1.0),
            DVec3::new(0.0, -1.0, -1.0),
        ],
    );
    tri(
        &mut b,
        [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
        ],
    );
    let (mesh, _) = b.finish();
    s.add(ObjectDesc::new("degenerate", mesh)).unwrap();
    s.add(ObjectDesc::new(
        "wall",
        demo::box_mesh(DVec3::new(-2.0, -2.0, -0.1), DVec3::new(2.0, 2.0, 0.1)),
    ))
    .unwrap();
    for k in 0..5 {
        let x = f64::from(k) - 2.0;
        s.add(ObjectDesc::new(
            format!("behind {k}"),
            demo::box_mesh(
                DVec3::new(x - 0.2, -0.2, -3.0),
                DVec3::new(x + 0.2, 0.2, -2.6),
            ),
        ))
        .unwrap();
    }
    let index = SceneIndex::new(&s);
    let vp = Viewport::new(96, 64).unwrap();
    let mut total = Tally::default();
    for (i, eye) in [
        DVec3::new(0.0, 0.0, 6.0),
        DVec3::new(0.3, 0.0, 3.0),
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::new(5.0, 0.0, 0.0),
    ]
    .into_iter()
    .enumerate()
    {
        let cam = Camera::perspective(eye, DVec3::new(0.0, 0.0, -2.0), DVec3::Y, 60.0, 0.05, 50.0);
        for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
            total += check(&s, &index, &cam, vp, &options(kind, 1 + i as u32 % 2, true));
        }
    }
    assert!(
        total.hidden_culled >= 5,
        "the wall hides the boxes behind it: {total:?}"
    );
    // A zero divisor is refused, naming the option.
    let mut o = options(BufferKind::Masked, 1, true);
    o.buffer.divisor = 0;
    let cam = Camera::perspective(
        DVec3::new(0.0, 0.0, 6.0),
        DVec3::ZERO,
        DVec3::Y,
        60.0,
        0.05,
        50.0,
    );
    let e = index.cull(&cam, vp, &o).unwrap_err();
    assert!(e.to_string().contains("divisor"), "{e}");
}

// ---------------------------------------------------------------------------------
// The buffers against brute force

/// Random triangles in a `w x h` buffer (keys in 0.05..1), some large, some thin.
fn random_tris(n: usize, seed: u64, w: f64, h: f64) -> Vec<Tri> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|i| {
            let (cx, cy) = (rng.range(-5.0, w + 5.0), rng.range(-5.0, h + 5.0));
            let size = if i % 5 == 0 { 40.0 } else { 8.0 };
            let mut t = [0; 3].map(|_| {
                [
                    cx + rng.range(-size, size),
                    cy + rng.range(-size, size),
                    rng.range(0.05, 1.0),
                ]
            });
            // Degenerate ones: a point, a segment (collinear), an edge-on sliver.
            match i % 13 {
                3 => t = [t[0]; 3],
                7 => {
                    t[2] = [
                        (t[0][0] + t[1][0]) * 0.5,
                        (t[0][1] + t[1][1]) * 0.5,
                        t[2][2],
                    ]
                }
                11 => t[2] = [t[0][0] + 1e-9, t[0][1], t[2][2]],
                _ => {}
            }
            t
        })
        .collect()
}

/// Per sample point, the nearest key of the triangles whose closed interior holds it
/// (barycentric, exact enough in f64); `-inf` where none.
fn brute_key(tris: &[Tri], x: f64, y: f64) -> f64 {
    let mut best = f64::NEG_INFINITY;
    for t in tris {
        let [a, b, c] = *t;
        let d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if d == 0.0 {
            continue;
        }
        let l1 = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / d;
        let l2 = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / d;
        let l0 = 1.0 - l1 - l2;
        if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
            best = best.max(l0 * a[2] + l1 * b[2] + l2 * c[2]);
        }
    }
    best
}

#[test]
fn both_buffers_never_claim_nearer_than_the_brute_force_per_sample_key() {
    let (w, h) = (61u32, 37u32);
    for divisor in [1u32, 2, 3] {
        let tris = random_tris(60, u64::from(divisor), f64::from(w), f64::from(h));
        for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
            let mut buf = OcclusionBuffer::new();
            buf.reset(kind, divisor, w * divisor, h * divisor);
            // Buffer coordinates = viewport pixels (x - 0.5) / d: give viewport pixels.
            let d = f64::from(divisor);
            let screen: Vec<Tri> = tris
                .iter()
                .map(|t| t.map(|[x, y, z]| [x * d + 0.5, y * d + 0.5, z]))
                .collect();
            buf.draw_screen_triangles(&screen, Kernel::Portable);
            let (mut covered, mut known) = (0, 0);
            for y in 0..h {
                for x in 0..w {
                    // The buffer pixel's samples: X = x + s / d.
                    let mut truth = f64::INFINITY;
                    for sy in 0..divisor {
                        for sx in 0..divisor {
                            let k = brute_key(
                                &tris,
                                f64::from(x) + f64::from(sx) / d,
                                f64::from(y) + f64::from(sy) / d,
                            );
                            truth = truth.min(k);
                        }
                    }
                    let bound = f64::from(buf.bound(x, y));
                    assert!(
                        bound <= truth,
                        "{kind:?} /{divisor}: pixel ({x}, {y}) bound {bound} nearer than the occluders' {truth}"
                    );
                    if truth > f64::NEG_INFINITY {
                        covered += 1;
                        if bound > f64::NEG_INFINITY {
                            known += 1;
                        }
                    }
                }
            }
            // The buffer knows most covered pixels (the masked one merges layers).
            assert!(
                known * 10 >= covered * 7,
                "{kind:?} /{divisor}: {known} of {covered}"
            );
        }
    }
}

#[test]
fn box_tests_agree_with_the_per_pixel_bounds() {
    // A box rectangle is hidden exactly when its key is behind every pixel's bound
    // (the masked test works per tile; the pyramid per texel: neither may say more).
    let (w, h) = (83u32, 45u32);
    let tris = random_tris(80, 7, f64::from(w), f64::from(h));
    let mut rng = SplitMix64(8);
    for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
        let mut buf = OcclusionBuffer::new();
        buf.reset(kind, 1, w, h);
        let screen: Vec<Tri> = tris
            .iter()
            .map(|t| t.map(|[x, y, z]| [x + 0.5, y + 0.5, z]))
            .collect();
        buf.draw_screen_triangles(&screen, Kernel::Auto);
        let mut hidden = 0;
        for _ in 0..400 {
            let x0 = (rng.next_f64() * f64::from(w)) as u32;
            let y0 = (rng.next_f64() * f64::from(h)) as u32;
            let x1 = (x0 + (rng.next_f64() * 20.0) as u32).min(w - 1);
            let y1 = (y0 + (rng.next_f64() * 12.0) as u32).min(h - 1);
            let key = rng.range(0.0, 0.6) as f32;
            let truth = (y0..=y1).all(|y| (x0..=x1).all(|x| key < buf.bound(x, y)));
            let r = crate::cull::buffer::BoxRect {
                x0,
                y0,
                x1,
                y1,
                key,
                area: 0.0,
            };
            assert_eq!(buf.hidden(&r), truth, "{kind:?} {r:?}");
            hidden += usize::from(truth);
        }
        assert!(
            hidden > 20,
            "{kind:?}: {hidden} hidden rectangles, the test must see some"
        );
    }
}

#[test]
fn masked_merge_keeps_both_layers_as_bounds() {
    // Two half-tile triangles at different depths, then a full cover: by hand.
    let mut b = MaskedBuffer::default();
    b.reset(8, 4, 0.0);
    // Left half (x <= 3.5) at key 0.5, right half at 0.3: rectangles as two triangles
    // whose diagonals pass no pixel sample (a sample on an edge shared by two triangles
    // is covered by neither: inner coverage with a margin).
    let quad = |x0: f64, x1: f64, z: f64| -> [Tri; 2] {
        [
            [[x0, -1.0, z], [x1, -1.0, z], [x1, 5.0, z]],
            [[x0, -1.0, z], [x1, 5.0, z], [x0, 5.0, z]],
        ]
    };
    b.draw(&quad(-1.3, 3.5, 0.5), Kernel::Portable);
    for y in 0..4 {
        for x in 0..8 {
            let want = if x <= 3 { 0.5 } else { f32::NEG_INFINITY };
            let got = b.bound(x, y);
            assert!(
                got <= want && (want == f32::NEG_INFINITY) == (got == f32::NEG_INFINITY),
                "({x},{y}) {got}"
            );
            assert!(
                want == f32::NEG_INFINITY || want - got < 1e-4,
                "({x},{y}) {got}"
            );
        }
    }
    b.draw(&quad(3.5, 9.0, 0.3), Kernel::Portable);
    // The tile is full: every pixel is bounded by the farther of the two.
    for y in 0..4 {
        for x in 0..8 {
            let got = b.bound(x, y);
            assert!(got <= 0.3 && got > 0.2999, "({x},{y}) {got}");
        }
    }
    assert!(b.hidden(0, 0, 7, 3, 0.29));
    assert!(!b.hidden(0, 0, 7, 3, 0.31));
}

/// The vector kernels this processor has for the rasterizer tests of `what`: AVX2,
/// and AVX-512 where present; `None` without AVX2. Each missing one is reported by
/// `simd_test_skipped` (a failure under `OBSCURA_REQUIRE_SIMD`).
fn vector_kernels(what: &str) -> Option<Vec<Kernel>> {
    if !Avx2::is_available() {
        crate::cpu::simd_test_skipped("AVX2", what);
        return None;
    }
    let mut kernels = vec![Kernel::Avx2];
    if Avx512::is_available() {
        kernels.push(Kernel::Avx512);
    } else {
        crate::cpu::simd_test_skipped("AVX-512", what);
    }
    Some(kernels)
}

/// Draws the same occluders into a `w x h` buffer of sample side `r` with the portable
/// masked kernel and each vector kernel of `kernels`, and into two hierarchical-z
/// buffers (portable and AVX2): asserts that something was drawn and that every
/// kernel left the same bits.
fn same_bits_in_every_kernel(
    (w, h, r): (u32, u32, f64),
    kernels: &[Kernel],
    portable: impl Fn(&mut MaskedBuffer),
    vector: impl Fn(&mut MaskedBuffer, Kernel),
    hiz: impl Fn(&mut crate::cull::buffer::hiz::HizBuffer, Kernel),
) {
    let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits());
    let mut p = MaskedBuffer::default();
    p.reset(w, h, r);
    portable(&mut p);
    let (pm, p0, p1) = p.state();
    assert!(pm.iter().any(|&m| m != 0) && p0.iter().any(|z| z.is_finite()));
    for &kernel in kernels {
        let mut v = MaskedBuffer::default();
        v.reset(w, h, r);
        vector(&mut v, kernel);
        let (vm, v0, v1) = v.state();
        assert_eq!(pm, vm, "{kernel:?}");
        assert!(same(&p0, &v0), "{kernel:?}");
        assert!(same(&p1, &v1), "{kernel:?}");
    }
    let mut hp = crate::cull::buffer::hiz::HizBuffer::default();
    let mut hv = crate::cull::buffer::hiz::HizBuffer::default();
    hp.reset(w, h, r);
    hv.reset(w, h, r);
    hiz(&mut hp, Kernel::Portable);
    hiz(&mut hv, Kernel::Avx2);
    assert!(hp.pixels().iter().any(|z| z.is_finite()));
    assert!(same(hp.pixels(), hv.pixels()));
}

#[test]
fn vector_and_portable_rasterizers_leave_the_same_bits() {
    let Some(kernels) = vector_kernels("occlusion buffer rasterizers") else {
        return;
    };
    let (w, h) = (203u32, 117u32);
    for seed in 0..4 {
        let tris = random_tris(300, seed, f64::from(w), f64::from(h));
        let r = [0.0, 0.5][seed as usize % 2];
        same_bits_in_every_kernel(
            (w, h, r),
            &kernels,
            |b| masked::draw_portable(b, &tris),
            |b, k| b.draw(&tris, k),
            |b, k| b.draw(&tris, k),
        );
    }
}

/// `bound <= num / den` exactly (`den > 0`), for a finite or `-inf` bound.
fn exactly_at_most(bound: f32, num: i128, den: i128) -> bool {
    if bound == f32::NEG_INFINITY || bound <= 0.0 && num >= 0 {
        return true;
    }
    assert!(bound.is_finite() && bound > 2f32.powi(-40), "bound {bound}");
    // bound = mant * 2^exp exactly.
    let bits = bound.to_bits();
    let (e, f) = ((bits >> 23) as i32, i128::from(bits & 0x7f_ffff));
    let (mant, exp) = (f | 1 << 23, e - 127 - 23);
    if exp >= 0 {
        (mant * den) << exp <= num
    } else {
        mant * den <= num << -exp
    }
}

#[test]
fn masked_raster_marks_only_pixels_inside_with_keys_never_nearer_exact_arithmetic() {
    // One triangle at a time into an empty buffer: a pixel with a bound is one the
    // raster marked covered. Vertices on a grid of 1/256 pixel and keys on one of
    // 2^-20, so orientations, barycentric weights and keys are exact integers.
    let (w, h) = (45u32, 29u32);
    let mut rng = SplitMix64(2024);
    let (mut covered, mut inside) = (0usize, 0usize);
    for case in 0..2500 {
        let r = [0.0, 0.5][case % 2];
        let steps = (r * 2.0) as i128 + 1; // samples per axis: 1 (r = 0) or 2 (r = 1/2)
        let size = [0.7, 3.0, 10.0, 10.0, 40.0, 300.0][case % 6];
        let (cx, cy) = (
            rng.range(-5.0, f64::from(w) + 5.0),
            rng.range(-5.0, f64::from(h) + 5.0),
        );
        let mut v = [0; 3].map(|_| {
            [
                ((cx + rng.range(-size, size)) * 256.0).round(),
                ((cy + rng.range(-size, size)) * 256.0).round(),
                (rng.range(0.05, 1.0) * f64::from(1 << 20)).round(),
            ]
        });
        if case % 7 == 3 {
            // A sliver: the third vertex a hair off the first edge.
            v[2][0] = ((v[0][0] + v[1][0]) * 0.5).round() + 1.0;
            v[2][1] = ((v[0][1] + v[1][1]) * 0.5).round();
        }
        let tri: Tri = v.map(|[x, y, k]| [x / 256.0, y / 256.0, k / f64::from(1 << 20)]);
        let vi = v.map(|c| c.map(|x| x as i128));
        let orient = |a: [i128; 3], b: [i128; 3], p: [i128; 2]| {
            (b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])
        };
        let d = orient(vi[0], vi[1], [vi[2][0], vi[2][1]]);
        if d == 0 {
            continue;
        }
        let sgn = d.signum();
        let mut b = MaskedBuffer::default();
        b.reset(w, h, r);
        b.draw(&[tri], Kernel::Auto);
        for y in 0..h {
            for x in 0..w {
                let bound = b.bound(x, y);
                // Every sample (X, Y) = (x + s / 2, y + t / 2), in 1/256 pixel.
                let mut all_inside = true;
                for t in 0..steps {
                    for s in 0..steps {
                        let p = [i128::from(x) * 256 + s * 128, i128::from(y) * 256 + t * 128];
                        let wts = [
                            orient(vi[1], vi[2], p) * sgn,
                            orient(vi[2], vi[0], p) * sgn,
                            orient(vi[0], vi[1], p) * sgn,
                        ];
                        let strictly = wts.iter().all(|&q| q > 0);
                        all_inside &= strictly;
                        if bound == f32::NEG_INFINITY {
                            continue;
                        }
                        assert!(
                            strictly,
                            "case {case}: pixel ({x}, {y}) marked, its sample {p:?}/256 is not inside {tri:?}"
                        );
                        // The key there: sum of weights * keys / (|d| 2^20).
                        let num: i128 = (0..3).map(|i| wts[i] * vi[i][2]).sum();
                        assert!(
                            exactly_at_most(bound, num, d.abs() << 20),
                            "case {case}: pixel ({x}, {y}) bound {bound} nearer than the key {} at {p:?}/256 of {tri:?}",
                            num as f64 / (d.abs() << 20) as f64
                        );
                    }
                }
                inside += usize::from(all_inside);
                covered += usize::from(bound != f32::NEG_INFINITY);
            }
        }
    }
    // The margins lose only slivers along the edges.
    assert!(
        covered * 100 >= inside * 97 && inside > 100_000,
        "{covered} pixels marked of {inside} inside"
    );
}

// ---------------------------------------------------------------------------------
// Convex polygons as one primitive

/// A random convex polygon of `n` vertices around `(cx, cy)` (radii up to `size`, the
/// angles sorted), its keys on the plane `k0 + kx X + ky Y`, either orientation.
fn random_poly(
    rng: &mut SplitMix64,
    n: usize,
    c: [f64; 2],
    size: f64,
    k: [f64; 3],
) -> Vec<[f64; 3]> {
    let mut ang: Vec<f64> = (0..n)
        .map(|_| rng.range(0.0, std::f64::consts::TAU))
        .collect();
    ang.sort_by(f64::total_cmp);
    let (rx, ry) = (rng.range(0.2, 1.0) * size, rng.range(0.2, 1.0) * size);
    let mut v: Vec<[f64; 3]> = ang
        .iter()
        .map(|a| {
            let (x, y) = (c[0] + rx * a.cos(), c[1] + ry * a.sin());
            [x, y, k[0] + k[1] * x + k[2] * y]
        })
        .collect();
    if rng.next_f64() < 0.5 {
        v.reverse();
    }
    v
}

/// Random polygons (all accepted by [`Poly::new`]) in a `w x h` buffer.
fn random_polys(count: usize, seed: u64, w: f64, h: f64) -> Vec<Poly> {
    let mut rng = SplitMix64(seed);
    let mut out = Vec::new();
    while out.len() < count {
        let n = 3 + (rng.next_f64() * 6.0) as usize;
        let c = [rng.range(-5.0, w + 5.0), rng.range(-5.0, h + 5.0)];
        let size = if out.len() % 5 == 0 { 40.0 } else { 8.0 };
        let k = [
            rng.range(0.3, 0.7),
            rng.range(-2e-3, 2e-3),
            rng.range(-2e-3, 2e-3),
        ];
        if let Some(p) = Poly::new(&random_poly(&mut rng, n, c, size, k)) {
            out.push(p);
        }
    }
    out
}

#[test]
fn polygon_rasterizers_leave_the_same_bits_in_every_kernel() {
    let Some(kernels) = vector_kernels("occlusion buffer polygon rasterizers") else {
        return;
    };
    let (w, h) = (203u32, 117u32);
    for seed in 0..4 {
        let polys = random_polys(300, seed + 100, f64::from(w), f64::from(h));
        assert!(polys.iter().any(|p| p.vertices().len() <= 4));
        assert!(polys.iter().any(|p| p.vertices().len() > 4));
        let r = [0.0, 0.5][seed as usize % 2];
        same_bits_in_every_kernel(
            (w, h, r),
            &kernels,
            |b| masked::draw_polys_portable(b, &polys),
            |b, k| b.draw_polygons(&polys, k),
            |b, k| b.draw_polygons(&polys, k),
        );
    }
}

#[test]
fn polygon_raster_marks_only_pixels_inside_with_keys_never_nearer_exact_arithmetic() {
    // One convex polygon at a time into an empty buffer (both kinds): a pixel with a
    // bound is one the raster marked covered. Vertices on a grid of 1/256 pixel, keys
    // on the plane (k0 + kx X + ky Y) / 2^20 with X, Y in 1/256 and integer k: every
    // orientation and key below is an exact integer.
    let (w, h) = (45u32, 29u32);
    let mut rng = SplitMix64(2025);
    let (mut covered, mut inside, mut drawn) = (0usize, 0usize, 0usize);
    for case in 0..1200 {
        let r = [0.0, 0.5][case % 2];
        let steps = (r * 2.0) as i128 + 1;
        let size = [0.9, 3.0, 10.0, 10.0, 40.0, 300.0][case % 6];
        let n = 3 + case % 6;
        let c = [
            rng.range(-5.0, f64::from(w) + 5.0),
            rng.range(-5.0, f64::from(h) + 5.0),
        ];
        let k = [
            (rng.range(0.3, 0.7) * f64::from(1 << 20)).round() as i128,
            (rng.range(-2.0, 2.0)).round() as i128,
            (rng.range(-2.0, 2.0)).round() as i128,
        ];
        let vi: Vec<[i128; 3]> = random_poly(&mut rng, n, c, size, [0.0; 3])
            .iter()
            .map(|p| {
                let (x, y) = (
                    (p[0] * 256.0).round() as i128,
                    (p[1] * 256.0).round() as i128,
                );
                [x, y, k[0] + k[1] * x + k[2] * y]
            })
            .collect();
        let verts: Vec<[f64; 3]> = vi
            .iter()
            .map(|p| {
                [
                    p[0] as f64 / 256.0,
                    p[1] as f64 / 256.0,
                    p[2] as f64 / f64::from(1 << 20),
                ]
            })
            .collect();
        let Some(poly) = Poly::new(&verts) else {
            continue;
        };
        drawn += 1;
        let m = vi.len();
        let orient = |a: [i128; 3], b: [i128; 3], p: [i128; 2]| {
            (b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])
        };
        let area: i128 = (1..m - 1)
            .map(|i| orient(vi[0], vi[i], [vi[i + 1][0], vi[i + 1][1]]))
            .sum();
        let sgn = area.signum();
        for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
            let bound_of: Box<dyn Fn(u32, u32) -> f32> = match kind {
                BufferKind::Masked => {
                    let mut b = MaskedBuffer::default();
                    b.reset(w, h, r);
                    b.draw_polygons(&[poly], Kernel::Auto);
                    Box::new(move |x, y| b.bound(x, y))
                }
                _ => {
                    let mut b = crate::cull::buffer::hiz::HizBuffer::default();
                    b.reset(w, h, r);
                    b.draw_polygons(&[poly], Kernel::Auto);
                    Box::new(move |x, y| b.bound(x, y))
                }
            };
            for y in 0..h {
                for x in 0..w {
                    let bound = bound_of(x, y);
                    let mut all_inside = true;
                    for t in 0..steps {
                        for s in 0..steps {
                            let p = [i128::from(x) * 256 + s * 128, i128::from(y) * 256 + t * 128];
                            let strictly =
                                (0..m).all(|i| orient(vi[i], vi[(i + 1) % m], p) * sgn > 0);
                            all_inside &= strictly;
                            if bound == f32::NEG_INFINITY {
                                continue;
                            }
                            assert!(
                                strictly,
                                "case {case} {kind:?}: pixel ({x}, {y}) marked, its sample {p:?}/256 is not inside {verts:?}"
                            );
                            let num = k[0] + k[1] * p[0] + k[2] * p[1];
                            assert!(
                                exactly_at_most(bound, num, 1 << 20),
                                "case {case} {kind:?}: pixel ({x}, {y}) bound {bound} nearer than the key {} at {p:?}/256 of {verts:?}",
                                num as f64 / f64::from(1 << 20)
                            );
                        }
                    }
                    if kind == BufferKind::Masked {
                        inside += usize::from(all_inside);
                        covered += usize::from(bound != f32::NEG_INFINITY);
                    }
                }
            }
        }
    }
    assert!(drawn > 900, "{drawn} polygons accepted");
    assert!(
        covered * 100 >= inside * 97 && inside > 50_000,
        "{covered} pixels marked of {inside} inside"
    );
}

#[test]
fn a_square_as_one_polygon_leaves_no_gap_along_its_diagonal() {
    // The square [-0.5, 15.5]^2 (buffer coordinates, r = 0: the sample of pixel (i, j)
    // is (i, j)): every pixel 0..=15 has its sample inside. Its two triangles share
    // the diagonal y = x, which passes through the samples (i, i): inner coverage gives
    // them to neither.
    let z = 0.5;
    let sq = [
        [-0.5, -0.5, z],
        [15.5, -0.5, z],
        [15.5, 15.5, z],
        [-0.5, 15.5, z],
    ];
    let poly = Poly::new(&sq).expect("a square is convex and planar");
    let tris: [Tri; 2] = [[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]];
    let (w, h) = (24u32, 20u32);
    for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
        for kernel in [Kernel::Portable, Kernel::Auto] {
            let (poly_bound, tri_bound, poly_hidden, tri_hidden): (Vec<f32>, Vec<f32>, bool, bool) =
                if kind == BufferKind::Masked {
                    let (mut a, mut b) = (MaskedBuffer::default(), MaskedBuffer::default());
                    a.reset(w, h, 0.0);
                    b.reset(w, h, 0.0);
                    a.draw_polygons(&[poly], kernel);
                    b.draw(&tris, kernel);
                    (
                        (0..w * h).map(|i| a.bound(i % w, i / w)).collect(),
                        (0..w * h).map(|i| b.bound(i % w, i / w)).collect(),
                        a.hidden(2, 2, 13, 13, 0.49),
                        b.hidden(2, 2, 13, 13, 0.49),
                    )
                } else {
                    let mut a = crate::cull::buffer::hiz::HizBuffer::default();
                    let mut b = crate::cull::buffer::hiz::HizBuffer::default();
                    a.reset(w, h, 0.0);
                    b.reset(w, h, 0.0);
                    a.draw_polygons(&[poly], kernel);
                    b.draw(&tris, kernel);
                    (
                        (0..w * h).map(|i| a.bound(i % w, i / w)).collect(),
                        (0..w * h).map(|i| b.bound(i % w, i / w)).collect(),
                        a.hidden(2, 2, 13, 13, 0.49),
                        b.hidden(2, 2, 13, 13, 0.49),
                    )
                };
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    let (pb, tb) = (poly_bound[i], tri_bound[i]);
                    if x <= 15 && y <= 15 {
                        assert!(
                            pb <= 0.5 && pb > 0.4999,
                            "{kind:?} {kernel:?}: ({x}, {y}) polygon bound {pb}"
                        );
                        if x == y {
                            assert_eq!(
                                tb,
                                f32::NEG_INFINITY,
                                "{kind:?} {kernel:?}: ({x}, {x}) on the diagonal"
                            );
                        } else {
                            assert!(tb <= 0.5, "{kind:?} {kernel:?}: ({x}, {y}) {tb}");
                        }
                    } else {
                        assert_eq!(pb, f32::NEG_INFINITY, "{kind:?} {kernel:?}: ({x}, {y})");
                        assert_eq!(tb, f32::NEG_INFINITY, "{kind:?} {kernel:?}: ({x}, {y})");
                    }
                }
            }
            // A box behind the square, across its diagonal: hidden only by the polygon.
            assert!(poly_hidden, "{kind:?} {kernel:?}");
            assert!(!tri_hidden, "{kind:?} {kernel:?}");
        }
    }
}

#[test]
fn non_convex_non_planar_and_degenerate_polygons_are_refused() {
    let z = 0.5;
    let ok = [
        [0.0, 0.0, z],
        [10.0, 0.0, z],
        [10.0, 10.0, z],
        [0.0, 10.0, z],
    ];
    assert!(Poly::new(&ok).is_some());
    // Clockwise, and with repeated vertices: still the square.
    let mut cw = ok;
    cw.reverse();
    assert!(Poly::new(&cw).is_some());
    let rep = [ok[0], ok[0], ok[1], ok[2], ok[2], ok[3], ok[0]];
    assert_eq!(Poly::new(&rep).map(|p| p.vertices().len()), Some(4));
    let refused: [(&str, Vec<[f64; 3]>); 9] = [
        // A dart (one reflex vertex).
        (
            "dart",
            vec![[0.0, 0.0, z], [10.0, 5.0, z], [0.0, 10.0, z], [3.0, 5.0, z]],
        ),
        // A bow tie (self-intersecting).
        (
            "bow tie",
            vec![
                [0.0, 0.0, z],
                [10.0, 10.0, z],
                [10.0, 0.0, z],
                [0.0, 10.0, z],
            ],
        ),
        // A pentagram (every turn the same way, wound twice).
        (
            "pentagram",
            (0..5)
                .map(|i| {
                    let a = f64::from(i * 2) * std::f64::consts::TAU / 5.0;
                    [10.0 * a.cos(), 10.0 * a.sin(), z]
                })
                .collect(),
        ),
        // A vertex on an edge (three collinear).
        (
            "collinear",
            vec![
                [0.0, 0.0, z],
                [5.0, 0.0, z],
                [10.0, 0.0, z],
                [10.0, 10.0, z],
            ],
        ),
        // Not planar: one key off the others' plane by far more than rounding.
        (
            "warped",
            vec![
                [0.0, 0.0, z],
                [10.0, 0.0, z],
                [10.0, 10.0, 0.6],
                [0.0, 10.0, z],
            ],
        ),
        (
            "too few",
            vec![[0.0, 0.0, z], [10.0, 0.0, z], [0.0, 0.0, z]],
        ),
        (
            "too many",
            (0..9)
                .map(|i| {
                    let a = f64::from(i) * std::f64::consts::TAU / 9.0;
                    [10.0 * a.cos(), 10.0 * a.sin(), z]
                })
                .collect(),
        ),
        (
            "not finite",
            vec![[0.0, 0.0, z], [10.0, 0.0, f64::NAN], [0.0, 10.0, z]],
        ),
        // A sliver whose plane would be ill-conditioned.
        (
            "sliver",
            vec![[0.0, 0.0, z], [1e4, 0.0, z], [1e4, 1e-6, z], [0.0, 1e-6, z]],
        ),
    ];
    for (name, v) in &refused {
        assert!(Poly::new(v).is_none(), "{name} accepted");
    }
    // Eight vertices on a circle: accepted, and planar keys on a tilted plane too.
    let oct: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            let a = f64::from(i) * std::f64::consts::TAU / 8.0;
            let (x, y) = (20.0 + 10.0 * a.cos(), 20.0 + 10.0 * a.sin());
            [x, y, 0.3 + 0.01 * x - 0.004 * y]
        })
        .collect();
    assert!(Poly::new(&oct).is_some());
}

#[test]
fn occlusion_buffer_draws_screen_polygons_and_refuses_bad_ones() {
    // A square of viewport pixels [0, 32]^2 (samples 0.5 .. 31.5 inside) with divisor
    // 2: buffer pixels 0..=15 have all their samples inside; a box rectangle across
    // the diagonal, behind, is hidden (it is not with the square's two triangles).
    let z = 0.5;
    let sq = [
        [0.0, 0.0, z],
        [32.0, 0.0, z],
        [32.0, 32.0, z],
        [0.0, 32.0, z],
    ];
    let rect = crate::cull::buffer::BoxRect {
        x0: 1,
        y0: 1,
        x1: 14,
        y1: 14,
        key: 0.49,
        area: 0.0,
    };
    for kind in [BufferKind::Masked, BufferKind::HierarchicalZ] {
        let mut buf = OcclusionBuffer::new();
        buf.reset(kind, 2, 48, 40);
        buf.draw_screen_polygons(&[&sq], Kernel::Auto).unwrap();
        assert!(buf.hidden(&rect), "{kind:?}");
        for y in 0..20 {
            for x in 0..24 {
                let b = buf.bound(x, y);
                if x <= 15 && y <= 15 {
                    assert!(b <= 0.5 && b > 0.4999, "{kind:?} ({x}, {y}) {b}");
                } else {
                    assert_eq!(b, f32::NEG_INFINITY, "{kind:?} ({x}, {y})");
                }
            }
        }
        let mut tri = OcclusionBuffer::new();
        tri.reset(kind, 2, 48, 40);
        tri.draw_screen_triangles(
            &[[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]],
            Kernel::Auto,
        );
        assert!(!tri.hidden(&rect), "{kind:?}");
        // A dart among good polygons: an error naming it, nothing drawn.
        let dart = [
            [0.0, 0.0, z],
            [20.0, 10.0, z],
            [0.0, 20.0, z],
            [6.0, 10.0, z],
        ];
        let mut bad = OcclusionBuffer::new();
        bad.reset(kind, 1, 48, 40);
        let err = bad
            .draw_screen_polygons(&[&sq, &dart], Kernel::Auto)
            .unwrap_err();
        assert!(err.to_string().contains("polygon 1"), "{err}");
        assert!((0..40).all(|y| (0..48).all(|x| bad.bound(x, y) == f32::NEG_INFINITY)));
    }
}

/// Hundreds of street views, both kinds (run by hand: `cargo test --release -p obscura
/// --lib cull_buffer -- --ignored --nocapture`).
#[test]
#[ignore = "hundreds of views: minutes"]
fn hundreds_of_street_views() {
    let vp = Viewport::new(320, 180).unwrap();
    for seed in 0..3 {
        let scene = demo::city(10, 10, seed);
        let index = SceneIndex::new(&scene);
        let mut total = Tally::default();
        for (i, cam) in street_cameras(120, seed + 40, i_ortho(seed))
            .iter()
            .enumerate()
        {
            let kind = if i % 2 == 0 {
                BufferKind::Masked
            } else {
                BufferKind::HierarchicalZ
            };
            total += check(
                &scene,
                &index,
                cam,
                vp,
                &options(kind, 1 + (i as u32 % 2), i % 3 != 0),
            );
        }
        println!(
            "city seed {seed}: {total:?} ({:.1}% of hidden boxes culled)",
            100.0 * total.hidden_culled as f64 / total.hidden.max(1) as f64
        );
    }
}

fn i_ortho(seed: u64) -> bool {
    seed == 2
}
