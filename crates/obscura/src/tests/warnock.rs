//! Warnock's area subdivision: the z-buffer's frame on every kind of scene, the window
//! relations against brute force, and the seed's five rules firing where they should.

use super::hsr_scenes;

use crate::raster::{FillRule, PixelRect, PolygonCoverage};
use crate::rng::SplitMix64;
use crate::scene::Camera;
use crate::surface::stats::WarnockStats;
use crate::surface::warnock::{Relation, classify};
use crate::surface::{Algorithm, RenderOptions};
use crate::{BACKGROUND, Stats, prepare};
use glam::DVec3;
use hsr_scenes::{Case, scene_of};

const ALGO: Algorithm = Algorithm::Warnock;

/// Every window ends in exactly one rule or a pixel decision, and every rule-5 window
/// has at least two non-empty quarters.
fn assert_rule_accounting(stats: &Stats) {
    let s = wk(stats);
    let ended = s.rule1 + s.rule2 + s.rule3 + s.rule4 + s.pixel_decisions;
    assert_eq!(s.windows, ended + s.rule5);
    assert!(s.windows > 2 * s.rule5);
}

/// Warnock's own figures in the stats of a render.
fn wk(stats: &Stats) -> &WarnockStats {
    stats.warnock().expect("Warnock's stats")
}

#[test]
fn random_triangles_match_zbuffer() {
    let s = hsr_scenes::random_triangles(1, 50, 96, 72).assert_matches_zbuffer(ALGO);
    assert_rule_accounting(&s);
    hsr_scenes::random_triangles(2, 200, 160, 120).assert_matches_zbuffer(ALGO);
}

#[test]
fn thin_triangles_match_zbuffer() {
    hsr_scenes::thin_triangles(3).assert_matches_zbuffer(ALGO);
}

#[test]
fn interpenetrating_faces_match_zbuffer() {
    hsr_scenes::interpenetrating().assert_matches_zbuffer(ALGO);
}

#[test]
fn cyclic_overlap_matches_zbuffer() {
    hsr_scenes::cyclic_overlap().assert_matches_zbuffer(ALGO);
}

#[test]
fn coplanar_touching_faces_match_zbuffer() {
    hsr_scenes::coplanar_touching().assert_matches_zbuffer(ALGO);
    hsr_scenes::pixel_aligned_fan().assert_matches_zbuffer(ALGO);
}

#[test]
fn clipped_polygons_match_zbuffer() {
    hsr_scenes::crossing_near_plane().assert_matches_zbuffer(ALGO);
}

#[test]
fn orthographic_view_matches_zbuffer() {
    hsr_scenes::orthographic(4).assert_matches_zbuffer(ALGO);
}

#[test]
fn demo_default_matches_zbuffer() {
    let s = hsr_scenes::demo_default(160, 120).assert_matches_zbuffer(ALGO);
    assert_rule_accounting(&s);
}

#[test]
fn random_sweep_matches_zbuffer() {
    for seed in 0..120 {
        let s = hsr_scenes::random_scene(seed).assert_matches_zbuffer(ALGO);
        assert_rule_accounting(&s);
    }
}

#[test]
fn empty_culled_and_inside_views_are_background() {
    for case in hsr_scenes::background_cases() {
        let ((frame, stats), (reference, _)) = case.render_pair(ALGO);
        assert_eq!(frame.covered_pixels(), 0, "{}", case.name);
        assert_eq!(frame, reference, "{}", case.name);
        // Nothing in view: the whole image is one window decided by rule 1.
        assert_eq!(wk(&stats).windows, 1, "{}", case.name);
        assert_eq!(wk(&stats).rule1, 1, "{}", case.name);
    }
}

#[test]
fn relations_agree_with_brute_force() {
    let mut r = SplitMix64(99);
    let (w, h) = (24u32, 20u32);
    let mut seen = [0usize; 4];
    for _ in 0..400 {
        let n = 3 + (r.next_u64() % 3) as usize;
        // A convex polygon: points on an ellipse at sorted angles.
        let (cx, cy) = (r.range(-2.0, 26.0), r.range(-2.0, 22.0));
        let (rx, ry) = (r.range(0.3, 14.0), r.range(0.3, 14.0));
        let mut angles: Vec<f64> = (0..n)
            .map(|_| r.range(0.0, std::f64::consts::TAU))
            .collect();
        angles.sort_by(f64::total_cmp);
        let pts: Vec<(f64, f64)> = angles
            .iter()
            .map(|a| (cx + rx * a.cos(), cy + ry * a.sin()))
            .collect();
        let Some(c) = PolygonCoverage::new(&pts, FillRule::TopLeft, w, h) else {
            continue;
        };
        for _ in 0..20 {
            let x0 = (r.next_u64() % u64::from(w)) as u32;
            let y0 = (r.next_u64() % u64::from(h)) as u32;
            let x1 = x0 + 1 + (r.next_u64() % u64::from(w - x0)) as u32;
            let y1 = y0 + 1 + (r.next_u64() % u64::from(h - y0)) as u32;
            let win = PixelRect { x0, y0, x1, y1 };
            let mut covered = 0;
            for y in y0..y1 {
                if let Some((a, b)) = c.row_span(y) {
                    covered += b.min(x1).saturating_sub(a.max(x0));
                }
            }
            let rel = classify(&c, win);
            let area = win.area() as u32;
            let b = c.rect();
            let box_inside = b.x0 >= x0 && b.x1 <= x1 && b.y0 >= y0 && b.y1 <= y1;
            let partial = if box_inside {
                Relation::Inside
            } else {
                Relation::Intersecting
            };
            // Surrounding is exact both ways; disjoint is never wrong, but a window
            // that only the convex hull of its samples shares with the polygon (a
            // sliver passing between samples, a corner near a vertex) may be called
            // partial: it is subdivided further, which costs time, not correctness.
            match rel {
                Relation::Surrounding => assert_eq!(covered, area, "{pts:?} {win:?}"),
                Relation::Disjoint => assert_eq!(covered, 0, "{pts:?} {win:?}"),
                _ => {
                    assert!(covered < area, "{pts:?} {win:?}");
                    assert_eq!(rel, partial, "{pts:?} {win:?}");
                }
            }
            if covered == area {
                assert_eq!(rel, Relation::Surrounding, "{pts:?} {win:?}");
            }
            seen[rel as usize] += 1;
        }
    }
    assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
}

fn pixel_camera(w: f64, h: f64) -> Camera {
    // Orthographic, one world unit per pixel, world y up: pixel (i, j) samples
    // world (i + 0.5, h - j - 0.5).
    Camera::orthographic(
        DVec3::new(w / 2.0, h / 2.0, 10.0),
        DVec3::new(w / 2.0, h / 2.0, 0.0),
        DVec3::Y,
        h,
        1.0,
        20.0,
    )
}

fn pixel_case(name: &str, polys: &[Vec<(f64, f64, f64)>], w: u64, h: u64) -> Case {
    let polys: Vec<Vec<DVec3>> = polys
        .iter()
        .map(|p| {
            p.iter()
                .map(|&(x, y, z)| DVec3::new(x, h as f64 - y, z))
                .collect()
        })
        .collect();
    Case::new(
        name,
        scene_of(&polys),
        pixel_camera(w as f64, h as f64),
        w,
        h,
    )
}

#[test]
fn rule1_fires_once_on_an_empty_scene() {
    let case = pixel_case("empty", &[], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(wk(&stats).windows, 1);
    assert_eq!(wk(&stats).rule1, 1);
    let s = wk(&stats);
    for (k, n) in [
        ("rule2", s.rule2),
        ("rule3", s.rule3),
        ("rule4", s.rule4),
        ("rule5", s.rule5),
        ("pixel_decisions", s.pixel_decisions),
    ] {
        assert_eq!(n, 0, "{k}");
    }
}

#[test]
fn rule2_draws_a_lone_small_triangle_in_the_first_window() {
    let tri = vec![(5.2, 4.1, 0.0), (12.7, 6.3, 0.0), (7.4, 11.9, 0.0)];
    let case = pixel_case("small triangle", &[tri], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    // Inside the whole image and alone: rule 2 at once.
    assert_eq!(wk(&stats).windows, 1);
    assert_eq!(wk(&stats).rule2, 1);
    let ((frame, _), _) = case.render_pair(ALGO);
    assert!(frame.covered_pixels() > 10);
    assert_eq!(frame.id(0, 0), BACKGROUND);
    assert_eq!(frame.id(7, 7), 0);
}

#[test]
fn rule3_fills_the_image_with_a_surrounding_quad() {
    let quad = vec![
        (-5.0, -5.0, 0.0),
        (40.0, -5.0, 0.0),
        (40.0, 30.0, 0.0),
        (-5.0, 30.0, 0.0),
    ];
    let case = pixel_case("covering quad", &[quad], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(wk(&stats).windows, 1);
    assert_eq!(wk(&stats).rule3, 1);
    let ((frame, _), _) = case.render_pair(ALGO);
    assert_eq!(frame.covered_pixels(), 32 * 24);
}

#[test]
fn rule4_lets_a_near_surrounding_quad_hide_a_far_triangle() {
    let quad = vec![
        (-5.0, -5.0, 2.0),
        (40.0, -5.0, 2.0),
        (40.0, 30.0, 2.0),
        (-5.0, 30.0, 2.0),
    ];
    let tri = vec![(5.2, 4.1, -1.0), (12.7, 6.3, -1.0), (7.4, 11.9, -1.0)];
    let case = pixel_case("quad over triangle", &[quad.clone(), tri.clone()], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(wk(&stats).windows, 1);
    assert_eq!(wk(&stats).rule4, 1);
    let ((frame, _), _) = case.render_pair(ALGO);
    assert!(frame.ids.iter().all(|&i| i == 0));

    // With the triangle in front instead, rule 4 cannot decide the whole image: the
    // windows holding the triangle's outline subdivide, and windows fully inside the
    // quad but away from the triangle are decided by rule 3.
    let tri_front: Vec<_> = tri.iter().map(|&(x, y, _)| (x, y, 3.0)).collect();
    let case = pixel_case("triangle over quad", &[quad, tri_front], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert!(wk(&stats).rule5 >= 1);
    assert!(wk(&stats).rule3 >= 1);
    assert_rule_accounting(&stats);
}

#[test]
fn rule5_subdivides_interpenetrating_faces_down_to_pixels() {
    // Two quads over the same pixels whose depths cross along x = 15.25, which no
    // window boundary follows: z_b = -1 + (x - 4) 4/45.
    let zb = 17.0 / 15.0;
    let a = vec![
        (4.0, 4.0, 0.0),
        (28.0, 4.0, 0.0),
        (28.0, 20.0, 0.0),
        (4.0, 20.0, 0.0),
    ];
    let b = vec![
        (4.0, 4.0, -1.0),
        (28.0, 4.0, zb),
        (28.0, 20.0, zb),
        (4.0, 20.0, -1.0),
    ];
    let case = pixel_case("crossing quads", &[a, b], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert!(wk(&stats).rule5 >= 1);
    assert!(wk(&stats).pixel_decisions >= 1);
    // Subdivision reached single pixels: 32x24, 16x12, 8x6, 4x3, 2x2 or 2x1, 1x1.
    assert_eq!(wk(&stats).max_depth, 5);
    assert_rule_accounting(&stats);
    let ((frame, _), _) = case.render_pair(ALGO);
    assert_eq!(frame.id(8, 10), 0);
    assert_eq!(frame.id(24, 10), 1);
}

#[test]
fn windows_see_only_faces_not_disjoint_from_them() {
    // Two triangles in opposite corners: the root subdivides once and each quarter
    // holds one triangle (rule 2) or none (rule 1).
    let t1 = vec![(1.0, 1.0, 0.0), (9.0, 1.0, 0.0), (1.0, 9.0, 0.0)];
    let t2 = vec![(30.0, 22.0, 0.0), (20.0, 22.0, 0.0), (30.0, 14.0, 0.0)];
    let case = pixel_case("opposite corners", &[t1, t2], 32, 24);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(wk(&stats).windows, 5);
    assert_eq!(wk(&stats).rule5, 1);
    assert_eq!(wk(&stats).rule2, 2);
    assert_eq!(wk(&stats).rule1, 2);
}

#[test]
fn same_frames_with_the_inclusive_fill_rule() {
    // The seed-task scene with the inclusive rule (shared edges covered twice).
    let scene = crate::Scene::demo("seed-task").unwrap();
    let vp = crate::Viewport::new(32, 32).unwrap();
    let view = prepare(
        &scene,
        scene.camera().unwrap(),
        vp,
        &crate::PrepareOptions::default(),
    )
    .unwrap();
    let opts = RenderOptions::default().with_fill_rule(FillRule::Inclusive);
    let (z, _) = crate::render(Algorithm::ZBuffer, &view, &opts).unwrap();
    for algo in [Algorithm::Warnock, Algorithm::Scanline] {
        let (f, _) = crate::render(algo, &view, &opts).unwrap();
        hsr_scenes::assert_same("seed task, inclusive", algo, &f, &z);
    }
}
