//! Off-centre windows and non-square pixels (a camera's `Lens`): the picture of a
//! shifted camera is a part of a larger centred picture, intrinsics with `fx != fy`
//! put points where the pinhole formula says, asymmetric `glFrustum` and `glOrtho`
//! matrices come back from a camera unchanged, and every algorithm that must equal the
//! z-buffer still does through a shifted lens. Every expectation is computed here, on
//! inputs written here.

use glam::{DMat4, DVec2, DVec3, DVec4};
use obscura::bench_support::SplitMix64;
use obscura::scene::{Faces, Intrinsics};
use obscura::{
    Algorithm, Camera, Error, Frame, Lens, PrepareOptions, PreparedView, Projection, RenderOptions,
    Scene, Viewport, prepare, render,
};

/// Triangles in layers parallel to the image plane (each slightly tilted, none
/// touching another: layers 0.15 apart, tilts below 0.06), so that no two are ever
/// near a depth tie; random in `x` and `y`, overlapping in the picture.
fn layered_triangles(seed: u64, n: usize) -> Scene {
    let mut r = SplitMix64(seed);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..n {
        let z = -0.15 * k as f64;
        let (tx, ty) = (r.range(-0.02, 0.02), r.range(-0.02, 0.02));
        let (cx, cy) = (r.range(-1.4, 1.4), r.range(-1.0, 1.0));
        let base = positions.len() as u32;
        for _ in 0..3 {
            let (x, y) = (cx + r.range(-1.2, 1.2), cy + r.range(-1.2, 1.2));
            positions.push([x, y, z + tx * x + ty * y]);
        }
        triangles.push([base, base + 1, base + 2]);
    }
    Scene::from_arrays(&positions, Faces::Triangles(&triangles)).unwrap()
}

fn frame(scene: &Scene, camera: &Camera, viewport: Viewport, algorithm: Algorithm) -> Frame {
    let view = prepare(scene, camera, viewport, &PrepareOptions::default()).unwrap();
    render(algorithm, &view, &RenderOptions::default())
        .unwrap()
        .0
}

/// The smallest distance, in pixels, from a pixel centre of the rectangle `rect`
/// (`x0, y0, width, height`) to an edge of a polygon of the view: edges nearer than
/// rounding could flip a pixel between two pictures computed differently.
fn edge_clearance(view: &PreparedView<'_>, rect: (u32, u32, u32, u32)) -> f64 {
    let mut clearance = f64::INFINITY;
    for poly in view.polygons() {
        let pts = poly.screen_points();
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len = dx.hypot(dy);
            if len == 0.0 {
                continue;
            }
            for j in rect.1..rect.1 + rect.3 {
                for i in rect.0..rect.0 + rect.2 {
                    let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
                    let t = (((px - a.0) * dx + (py - a.1) * dy) / (len * len)).clamp(0.0, 1.0);
                    let d = (a.0 + t * dx - px).hypot(a.1 + t * dy - py);
                    clearance = clearance.min(d);
                }
            }
        }
    }
    clearance
}

/// Asserts that `small` is the part of `big` at `(x0, y0)`: ids equal pixel for pixel,
/// depths to single-precision rounding. Returns how many pixels are covered.
fn assert_part_of(small: &Frame, big: &Frame, x0: u32, y0: u32, label: &str) -> usize {
    let mut differing = Vec::new();
    for j in 0..small.height {
        for i in 0..small.width {
            let (a, b) = (small.id(i, j), big.id(i + x0, j + y0));
            let (da, db) = (
                small.depth[small.index(i, j)],
                big.depth[big.index(i + x0, j + y0)],
            );
            let depth_off = a != u32::MAX && (da - db).abs() > 1e-5 * db.abs();
            if a != b || depth_off {
                differing.push((i, j, a, b, da, db));
            }
        }
    }
    assert!(
        differing.is_empty(),
        "{label}: {} pixels differ (x, y, shifted id, centred id, depths): {:?}",
        differing.len(),
        &differing[..differing.len().min(10)]
    );
    small.covered_pixels()
}

#[test]
fn a_shifted_principal_point_shows_part_of_a_larger_centred_picture() {
    let scene = layered_triangles(11, 24);
    let eye = Camera::perspective(
        DVec3::new(0.3, -0.2, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        40.0,
        0.5,
        20.0,
    );
    let view = eye.view_matrix();
    let (w, h) = (56u32, 40u32);
    let f = 60.0;
    for (dx, dy) in [(7.0f64, -5.0f64), (-13.0, 9.0), (0.0, 6.0)] {
        // The centred camera with the same focal length on a viewport 2|d| larger each
        // way; the shifted camera's pixel (i, j) sees what its pixel (i + |dx| - dx,
        // j + |dy| - dy) sees.
        let (big_w, big_h) = (w + 2 * dx.abs() as u32, h + 2 * dy.abs() as u32);
        let centred = Intrinsics {
            fx: f,
            fy: f,
            cx: f64::from(big_w) / 2.0,
            cy: f64::from(big_h) / 2.0,
            width: big_w,
            height: big_h,
        };
        let shifted = Intrinsics {
            cx: f64::from(w) / 2.0 + dx,
            cy: f64::from(h) / 2.0 + dy,
            width: w,
            height: h,
            ..centred
        };
        let big_cam = Camera::from_intrinsics(view, &centred, 0.5, 20.0).unwrap();
        let cam = Camera::from_intrinsics(view, &shifted, 0.5, 20.0).unwrap();
        assert_eq!(big_cam.lens, Lens::CENTRED);
        assert_eq!(
            cam.lens.shift,
            DVec2::new(-dx / f64::from(w), dy / f64::from(h))
        );
        let (big_vp, vp) = (centred.viewport().unwrap(), shifted.viewport().unwrap());
        let (x0, y0) = ((dx.abs() - dx) as u32, (dy.abs() - dy) as u32);
        // No edge passes within rounding of a compared pixel centre (else the test
        // would compare rounding, not geometry).
        let big_view = prepare(&scene, &big_cam, big_vp, &PrepareOptions::default()).unwrap();
        let clearance = edge_clearance(&big_view, (x0, y0, w, h));
        assert!(
            clearance > 1e-4,
            "({dx}, {dy}): an edge {clearance:e} px from a pixel centre"
        );
        // The octree casts the same rays through its voxels: its pictures too.
        for algorithm in [
            Algorithm::ZBuffer,
            Algorithm::Raycast,
            Algorithm::RaycastBvh,
            Algorithm::Octree,
        ] {
            let big = frame(&scene, &big_cam, big_vp, algorithm);
            let small = frame(&scene, &cam, vp, algorithm);
            let label = format!("{algorithm}, principal point moved by ({dx}, {dy})");
            let covered = assert_part_of(&small, &big, x0, y0, &label);
            assert!(covered > 300, "{label}: only {covered} pixels covered");
            // The part differs from the centred picture of the same size: the shift
            // is not a no-op.
            let same_size = frame(
                &scene,
                &Camera {
                    lens: Lens::CENTRED,
                    ..cam
                },
                vp,
                algorithm,
            );
            assert!(
                same_size.differences(&small).len() > 20,
                "{label}: nothing moved"
            );
        }
    }
}

#[test]
fn a_shifted_orthographic_window_shows_part_of_a_larger_one() {
    let scene = layered_triangles(12, 24);
    let (w, h) = (50u32, 36u32);
    // The window moved 9 pixels right and 4 up: shifts of 9 / 50 of its width and
    // 4 / 36 of its height.
    let (mx, my) = (9u32, 4u32);
    let (big_w, big_h) = (w + 2 * mx, h + 2 * my);
    // One world unit is 12 pixels in both pictures.
    let pixel = 1.0 / 12.0;
    let big_cam = Camera::orthographic(
        DVec3::new(0.2, 0.1, 5.0),
        DVec3::new(0.2, 0.1, 0.0),
        DVec3::Y,
        f64::from(big_h) * pixel,
        1.0,
        10.0,
    );
    let cam = Camera {
        projection: Projection::Orthographic {
            height: f64::from(h) * pixel,
        },
        lens: Lens {
            shift: DVec2::new(f64::from(mx) / f64::from(w), f64::from(my) / f64::from(h)),
            ..Lens::CENTRED
        },
        ..big_cam
    };
    let (big_vp, vp) = (
        Viewport::new(u64::from(big_w), u64::from(big_h)).unwrap(),
        Viewport::new(u64::from(w), u64::from(h)).unwrap(),
    );
    // Centred, the small window's top-left corner is the big one's pixel (9, 4).
    let (x0, y0) = (2 * mx, 0);
    let big_view = prepare(&scene, &big_cam, big_vp, &PrepareOptions::default()).unwrap();
    let clearance = edge_clearance(&big_view, (x0, y0, w, h));
    assert!(
        clearance > 1e-4,
        "an edge {clearance:e} px from a pixel centre"
    );
    for algorithm in [
        Algorithm::ZBuffer,
        Algorithm::Raycast,
        Algorithm::RaycastGrid,
    ] {
        let big = frame(&scene, &big_cam, big_vp, algorithm);
        let small = frame(&scene, &cam, vp, algorithm);
        let covered = assert_part_of(&small, &big, x0, y0, &format!("orthographic {algorithm}"));
        assert!(covered > 300, "{algorithm}: only {covered} pixels covered");
    }
}

/// The eye-space position a pinhole camera `k` sees at pixel `(u, v)` and depth
/// `depth`: `X = (u - cx) depth / fx`, `Y = (cy - v) depth / fy` (y up in eye space,
/// down in the image), `Z = -depth`.
fn unproject(k: &Intrinsics, u: f64, v: f64, depth: f64) -> DVec3 {
    DVec3::new((u - k.cx) * depth / k.fx, (k.cy - v) * depth / k.fy, -depth)
}

#[test]
fn intrinsics_with_unequal_focal_lengths_put_points_where_the_pinhole_formula_says() {
    let k = Intrinsics {
        fx: 90.0,
        fy: 130.0,
        cx: 71.3,
        cy: 40.6,
        width: 128,
        height: 96,
    };
    // A pose: eye at (1, 2, 6) looking at (0.5, 0, 0), so eye space is not world space.
    let pose = Camera::perspective(
        DVec3::new(1.0, 2.0, 6.0),
        DVec3::new(0.5, 0.0, 0.0),
        DVec3::Y,
        45.0,
        0.1,
        50.0,
    );
    let view = pose.view_matrix();
    let camera = Camera::from_intrinsics(view, &k, 0.1, 50.0).unwrap();
    assert_eq!(camera.lens.pixel_aspect, 130.0 / 90.0);
    let vp = k.viewport().unwrap();
    let eye_to_world = view.inverse();
    // Points given by where they should appear: pixel position and depth.
    let targets = [
        (20.25, 15.75, 3.0),
        (100.6, 80.2, 7.5),
        (64.0, 48.0, 5.0),
        (8.4, 88.3, 2.2),
        (119.7, 6.1, 11.0),
        (71.3, 40.6, 4.0),
    ];
    let t = obscura::view::ViewTransform::new(&camera, vp);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for &(u, v, depth) in &targets {
        // The pinhole formula by hand, from the world point back to the pixel.
        let world = eye_to_world.transform_point3(unproject(&k, u, v, depth));
        let e = view.transform_point3(world);
        let (pu, pv) = (k.fx * e.x / -e.z + k.cx, k.cy - k.fy * e.y / -e.z);
        assert!((pu - u).abs() < 1e-9 && (pv - v).abs() < 1e-9);
        // The view transform's projection of the same point.
        let s = t.to_screen(t.world_to_clip(world), t.world_to_eye(world));
        assert!(
            (s.x - u).abs() < 1e-9 && (s.y - v).abs() < 1e-9,
            "({u}, {v}): projected to ({}, {})",
            s.x,
            s.y
        );
        assert!((s.depth() - depth).abs() < 1e-9 * depth);
        // A small triangle around the point, its incircle 1.5 pixels in radius in
        // the image: corners 3 pixels from the point, built with fx and fy by hand.
        let base = positions.len() as u32;
        for (a, b) in [(0.0, -3.0), (2.598, 1.5), (-2.598, 1.5)] {
            let p = eye_to_world.transform_point3(unproject(&k, u + a, v + b, depth));
            positions.push(p.to_array());
        }
        triangles.push([base, base + 1, base + 2]);
    }
    let scene = Scene::from_arrays(&positions, Faces::Triangles(&triangles)).unwrap();
    for algorithm in [
        Algorithm::ZBuffer,
        Algorithm::Raycast,
        Algorithm::RaycastBvh,
    ] {
        let f = frame(&scene, &camera, vp, algorithm);
        for (id, &(u, v, _)) in targets.iter().enumerate() {
            let id = id as u32;
            // The pixel holding the point has the triangle's id; pixels 4 away don't.
            assert_eq!(f.id(u as u32, v as u32), id, "{algorithm}: ({u}, {v})");
            for (a, b) in [(4.0, 0.0), (-4.0, 0.0), (0.0, 4.0), (0.0, -4.0)] {
                let (x, y) = (u + a, v + b);
                if x >= 0.0 && y >= 0.0 && x < 128.0 && y < 96.0 {
                    assert_ne!(f.id(x as u32, y as u32), id, "{algorithm}: ({x}, {y})");
                }
            }
            // The covered pixels' centres average to the triangle's centroid, the
            // point itself (its corners are symmetric about it), to within a pixel's
            // sampling: a wrong focal length would scale the triangle about the
            // principal point and move it.
            let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
            for j in 0..96 {
                for i in 0..128 {
                    if f.id(i, j) == id {
                        n += 1.0;
                        sx += f64::from(i) + 0.5;
                        sy += f64::from(j) + 0.5;
                    }
                }
            }
            assert!(n >= 7.0, "{algorithm}: triangle {id} covers {n} pixels");
            assert!(
                (sx / n - u).abs() < 0.6 && (sy / n - v).abs() < 0.6,
                "{algorithm}: triangle {id} centred at ({}, {}), not ({u}, {v})",
                sx / n,
                sy / n
            );
        }
    }
}

/// `glFrustum(l, r, b, t, n, f)` written out from its reference page.
fn gl_frustum(l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
        DVec4::new(
            (r + l) / (r - l),
            (t + b) / (t - b),
            -(f + n) / (f - n),
            -1.0,
        ),
        DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
    )
}

/// `glOrtho(l, r, b, t, n, f)` written out from its reference page.
fn gl_ortho(l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(2.0 / (r - l), 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 / (t - b), 0.0, 0.0),
        DVec4::new(0.0, 0.0, -2.0 / (f - n), 0.0),
        DVec4::new(
            -(r + l) / (r - l),
            -(t + b) / (t - b),
            -(f + n) / (f - n),
            1.0,
        ),
    )
}

fn assert_close(a: DMat4, b: DMat4, label: &str) {
    let scale = b.to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (x, y) in a.to_cols_array().iter().zip(b.to_cols_array()) {
        assert!((x - y).abs() <= 1e-12 * scale, "{label}: {a:?} != {b:?}");
    }
}

#[test]
fn asymmetric_gl_frustum_and_gl_ortho_matrices_come_back_unchanged() {
    let vp = Viewport::new(160, 90).unwrap();
    let pose = Camera::perspective(
        DVec3::new(-2.0, 1.0, 3.0),
        DVec3::new(0.3, 0.2, -0.4),
        DVec3::Y,
        45.0,
        0.1,
        50.0,
    );
    let view = pose.view_matrix();
    // Off-centre both ways, wider than the viewport's aspect (non-square pixels),
    // and one window that does not contain the view axis at all.
    let frusta = [
        (-0.3, 0.9, -0.2, 0.4, 0.5, 40.0),
        (0.2, 0.6, -0.5, -0.1, 0.25, 9.0),
        (-1.1, -0.2, -0.3, 0.35, 1.0, 30.0),
    ];
    for (l, r, b, t, n, f) in frusta {
        let label = format!("glFrustum({l}, {r}, {b}, {t}, {n}, {f})");
        let m = gl_frustum(l, r, b, t, n, f);
        let cam = Camera::from_matrices(view, m, vp).unwrap();
        assert!(
            matches!(cam.projection, Projection::Perspective { .. }),
            "{label}"
        );
        assert!((cam.near - n).abs() < 1e-12 * f && (cam.far - f).abs() < 1e-9 * f);
        assert_close(cam.projection_matrix(vp.aspect()), m, &label);
        // The window at unit depth is glFrustum's divided by near.
        let (wl, wr, wb, wt) = cam.window(vp.aspect());
        for (got, want) in [(wl, l), (wr, r), (wb, b), (wt, t)] {
            assert!(
                (got * n - want).abs() < 1e-12,
                "{label}: window {:?}",
                cam.window(vp.aspect())
            );
        }
        // The ray through the image's top-left corner goes through (l, t, -n) in eye space.
        let ray = cam.ray(vp, 0.0, 0.0);
        let corner = view.inverse().transform_point3(DVec3::new(l, t, -n));
        let expected = (corner - cam.eye).normalize();
        assert!(
            (ray.direction.normalize() - expected).length() < 1e-12,
            "{label}"
        );
        assert_eq!(ray.origin, cam.eye);
        // And again through the camera's own matrices: the same camera.
        let again =
            Camera::from_matrices(cam.view_matrix(), cam.projection_matrix(vp.aspect()), vp)
                .unwrap();
        assert!((again.lens.shift - cam.lens.shift).length() < 1e-12);
        assert!((again.lens.pixel_aspect - cam.lens.pixel_aspect).abs() < 1e-12);
    }
    let boxes = [
        (-1.0, 3.0, -0.5, 1.5, 0.5, 20.0),
        (2.0, 4.5, 1.0, 2.0, -3.0, 8.0),
    ];
    for (l, r, b, t, n, f) in boxes {
        let label = format!("glOrtho({l}, {r}, {b}, {t}, {n}, {f})");
        let m = gl_ortho(l, r, b, t, n, f);
        let cam = Camera::from_matrices(view, m, vp).unwrap();
        assert_eq!(
            cam.projection,
            Projection::Orthographic { height: t - b },
            "{label}"
        );
        assert!((cam.near - n).abs() < 1e-12 * f && (cam.far - f).abs() < 1e-9 * f);
        assert_close(cam.projection_matrix(vp.aspect()), m, &label);
        let (wl, wr, wb, wt) = cam.window(vp.aspect());
        for (got, want) in [(wl, l), (wr, r), (wb, b), (wt, t)] {
            assert!(
                (got - want).abs() < 1e-12,
                "{label}: window {:?}",
                cam.window(vp.aspect())
            );
        }
        // The ray through the bottom-right corner starts at (r, b, 0) in eye space.
        let ray = cam.ray(vp, 160.0, 90.0);
        let corner = view.inverse().transform_point3(DVec3::new(r, b, 0.0));
        assert!((ray.origin - corner).length() < 1e-12, "{label}: {ray:?}");
    }
}

#[test]
fn skewed_and_oblique_projections_are_refused_saying_why() {
    let vp = Viewport::new(64, 48).unwrap();
    let view =
        Camera::perspective(DVec3::Z * 4.0, DVec3::ZERO, DVec3::Y, 50.0, 0.5, 20.0).view_matrix();
    let err = |p: DMat4| match Camera::from_matrices(view, p, vp) {
        Err(Error::InvalidCamera(m)) => m,
        other => panic!("expected InvalidCamera, got {other:?}"),
    };
    let frustum = gl_frustum(-0.3, 0.5, -0.2, 0.4, 0.5, 20.0);
    let ortho = gl_ortho(-1.0, 2.0, -0.5, 1.5, 0.5, 20.0);
    assert!(Camera::from_matrices(view, frustum, vp).is_ok());
    assert!(Camera::from_matrices(view, ortho, vp).is_ok());
    for p in [frustum, ortho] {
        let mut skewed = p;
        skewed.y_axis.x = 0.2;
        assert!(err(skewed).contains("skewed"), "{}", err(skewed));
        let mut skewed = p;
        skewed.x_axis.y = -0.1;
        assert!(err(skewed).contains("skewed"));
        let mut oblique_depth = p;
        oblique_depth.x_axis.z = 0.3;
        assert!(err(oblique_depth).contains("depth depends on x or y"));
    }
    let mut moving = frustum;
    moving.w_axis.x = 0.1;
    assert!(
        err(moving).contains("the window moves with depth"),
        "{}",
        err(moving)
    );
    let mut oblique = ortho;
    oblique.z_axis.y = 0.1;
    assert!(
        err(oblique).contains("an oblique projection"),
        "{}",
        err(oblique)
    );
}

#[test]
fn lenses_that_are_no_camera_are_refused_saying_why() {
    let vp = Viewport::new(64, 48).unwrap();
    let base = Camera::perspective(DVec3::Z * 4.0, DVec3::ZERO, DVec3::Y, 50.0, 0.5, 20.0);
    let with = |shift: DVec2, pixel_aspect: f64| Camera {
        lens: Lens {
            shift,
            pixel_aspect,
        },
        ..base
    };
    let err = |c: Camera| match c.validate_for(vp) {
        Err(Error::InvalidCamera(m)) => m,
        other => panic!("expected InvalidCamera for {c:?}, got {other:?}"),
    };
    assert!(with(DVec2::new(3.0, -2.0), 0.5).validate_for(vp).is_ok());
    assert!(err(with(DVec2::new(f64::NAN, 0.0), 1.0)).contains("finite"));
    assert!(err(with(DVec2::ZERO, 0.0)).contains("pixel aspect 0e0 positive"));
    assert!(err(with(DVec2::ZERO, f64::INFINITY)).contains("positive and finite"));
    // A window 1e9 widths off the axis: its pixels span 1e-20 radians there.
    let far_off = err(with(DVec2::new(1e9, 0.0), 1.0));
    assert!(
        far_off.contains("a pixel at the window's edge spans"),
        "{far_off}"
    );
    // An orthographic window beyond the largest coordinate.
    let ortho = Camera {
        projection: Projection::Orthographic { height: 2.0 },
        lens: Lens {
            shift: DVec2::new(0.0, 1e31),
            ..Lens::CENTRED
        },
        ..base
    };
    assert!(
        err(ortho).contains("beyond the largest accepted"),
        "{}",
        err(ortho)
    );
    // The pipeline refuses them the same way.
    let scene = Scene::demo("default").unwrap();
    assert!(matches!(
        prepare(
            &scene,
            &with(DVec2::new(1e9, 0.0), 1.0),
            vp,
            &PrepareOptions::default()
        ),
        Err(Error::InvalidCamera(_))
    ));
}

#[test]
fn a_tile_camera_renders_its_tile_of_the_whole_picture() {
    // Four tiles of a 2 x 2 split of one view, each rendered by the same camera with
    // half the field of view and a quarter-picture shift, make up the whole picture.
    let scene = layered_triangles(13, 24);
    let whole = Camera::perspective(
        DVec3::new(0.1, 0.2, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        50.0,
        0.5,
        20.0,
    );
    let (w, h) = (40u32, 30u32);
    let vp = Viewport::new(u64::from(2 * w), u64::from(2 * h)).unwrap();
    let tile_vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
    let half_fov = 2.0 * ((50f64.to_radians() / 2.0).tan() * 0.5).atan();
    let view = prepare(&scene, &whole, vp, &PrepareOptions::default()).unwrap();
    assert!(edge_clearance(&view, (0, 0, 2 * w, 2 * h)) > 1e-4);
    let reference = frame(&scene, &whole, vp, Algorithm::ZBuffer);
    for (tx, ty) in [(0u32, 0u32), (1, 0), (0, 1), (1, 1)] {
        let tile = Camera {
            projection: Projection::Perspective {
                fov_y_degrees: half_fov.to_degrees(),
            },
            lens: Lens {
                // Left tiles' windows move left, top tiles' up, by half a tile.
                shift: DVec2::new(f64::from(tx) - 0.5, 0.5 - f64::from(ty)),
                ..Lens::CENTRED
            },
            ..whole
        };
        let f = frame(&scene, &tile, tile_vp, Algorithm::ZBuffer);
        assert_part_of(
            &f,
            &reference,
            tx * w,
            ty * h,
            &format!("tile ({tx}, {ty})"),
        );
    }
    assert!(
        reference.covered_pixels() > 1000,
        "{}",
        reference.covered_pixels()
    );
}
