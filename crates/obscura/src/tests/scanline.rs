//! The scanline algorithm: the z-buffer's frame on every kind of scene, and its own
//! machinery (active edge list, spans per row, coherence) on scenes worked by hand.

use super::hsr_scenes;

use crate::scene::Camera;
use crate::surface::scanline::{self, SpanDecision};
use crate::surface::stats::ScanlineStats;
use crate::surface::{Algorithm, RenderOptions};
use crate::{BACKGROUND, Stats, prepare};
use glam::DVec3;
use hsr_scenes::{Case, scene_of};

/// The scanline's own figures in the stats of a render.
fn sl(stats: &Stats) -> &ScanlineStats {
    stats.scanline().expect("the scanline's stats")
}

const ALGO: Algorithm = Algorithm::Scanline;

#[test]
fn random_triangles_match_zbuffer() {
    hsr_scenes::random_triangles(1, 50, 96, 72).assert_matches_zbuffer(ALGO);
    hsr_scenes::random_triangles(2, 200, 160, 120).assert_matches_zbuffer(ALGO);
}

#[test]
fn thin_triangles_match_zbuffer() {
    hsr_scenes::thin_triangles(3).assert_matches_zbuffer(ALGO);
}

#[test]
fn interpenetrating_faces_match_zbuffer() {
    let stats = hsr_scenes::interpenetrating().assert_matches_zbuffer(ALGO);
    // Faces cross inside spans: some spans must be decided pixel by pixel.
    assert!(sl(&stats).spans_per_pixel > 0);
}

#[test]
fn cyclic_overlap_matches_zbuffer() {
    hsr_scenes::cyclic_overlap().assert_matches_zbuffer(ALGO);
}

#[test]
fn coplanar_touching_faces_match_zbuffer() {
    hsr_scenes::coplanar_touching().assert_matches_zbuffer(ALGO);
    let stats = hsr_scenes::pixel_aligned_fan().assert_matches_zbuffer(ALGO);
    // The square's bottom edge lies on a row of samples: there its side edges allow
    // a span that the bottom edge (not a top-left edge) refuses, and the span check
    // must fall back to the coverage rule.
    assert!(sl(&stats).span_fallbacks >= 1);
}

#[test]
fn clipped_polygons_match_zbuffer() {
    let case = hsr_scenes::crossing_near_plane();
    let view = prepare(&case.scene, &case.camera, case.viewport, &case.prepare).unwrap();
    let clipped = view.stats().stage("faces: clip").unwrap();
    assert!(
        clipped.output > 0,
        "the scene must make the pipeline clip faces"
    );
    case.assert_matches_zbuffer(ALGO);
}

#[test]
fn orthographic_view_matches_zbuffer() {
    hsr_scenes::orthographic(4).assert_matches_zbuffer(ALGO);
}

#[test]
fn demo_default_matches_zbuffer() {
    hsr_scenes::demo_default(160, 120).assert_matches_zbuffer(ALGO);
}

#[test]
fn random_sweep_matches_zbuffer() {
    for seed in 0..120 {
        hsr_scenes::random_scene(seed).assert_matches_zbuffer(ALGO);
    }
}

#[test]
fn empty_culled_and_inside_views_are_background() {
    for case in hsr_scenes::background_cases() {
        let ((frame, stats), (reference, _)) = case.render_pair(ALGO);
        assert_eq!(frame.covered_pixels(), 0, "{}", case.name);
        assert!(frame.depth.iter().all(|d| d.is_infinite()), "{}", case.name);
        assert_eq!(frame, reference, "{}", case.name);
        assert_eq!(sl(&stats).spans, 0, "{}", case.name);
    }
}

/// Polygons given in pixels (`x` right, `y` down, `z` toward the camera) seen by an
/// orthographic camera that maps world units to the pixels of a `width x height` image:
/// pixel (i, j) samples world (i + 0.5, height - j - 0.5).
fn pixel_case(name: &str, polys: &[Vec<(f64, f64, f64)>], width: u64, height: u64) -> Case {
    let (w, h) = (width as f64, height as f64);
    let polys: Vec<Vec<DVec3>> = polys
        .iter()
        .map(|p| p.iter().map(|&(x, y, z)| DVec3::new(x, h - y, z)).collect())
        .collect();
    let cam = Camera::orthographic(
        DVec3::new(w / 2.0, h / 2.0, 10.0),
        DVec3::new(w / 2.0, h / 2.0, 0.0),
        DVec3::Y,
        h,
        1.0,
        20.0,
    );
    Case::new(name, scene_of(&polys), cam, width, height)
}

/// Face 0: the square (2,2)-(10,10) in pixels at z = 0. Face 1: the triangle
/// (6,4) (14,4) (6,8) at z = 1, nearer. Both are seen by an orthographic camera that
/// maps world units to pixels (pixel (i, j) samples world (i + 0.5, 12 - j - 0.5)).
fn square_and_triangle() -> Case {
    let polys = [
        vec![(2., 2., 0.), (10., 2., 0.), (10., 10., 0.), (2., 10., 0.)],
        vec![(6., 4., 1.), (14., 4., 1.), (6., 8., 1.)],
    ];
    pixel_case("square and triangle", &polys, 20, 12)
}

#[test]
fn active_edge_list_and_spans_of_a_hand_worked_scene() {
    let case = square_and_triangle();
    let view = prepare(&case.scene, &case.camera, case.viewport, &case.prepare).unwrap();
    let (frame, stats, rows) = scanline::trace(&view, &RenderOptions::default(), 0..12).unwrap();

    // Horizontal edges never enter the table: two sides of the square, two of the
    // triangle.
    assert_eq!(stats.edges, 4);
    assert_eq!(stats.max_active_edges, 4);

    // Row 1 (y = 1.5) is above everything; rows 2..=9 cross the square, rows 4..=7 the
    // triangle (its sample lines y = 4.5 .. 7.5).
    assert!(rows[1].active_edges.is_empty());
    assert_eq!(rows[1].spans.len(), 1);
    for r in [2, 3, 8, 9] {
        assert_eq!(rows[r].active_edges.len(), 2, "row {r}");
        assert_eq!(rows[r].spans.len(), 3, "row {r}");
    }

    // Row 5: the triangle's slanted edge runs from (14,4) to (6,8): 1/m = -2, and at
    // y = 5.5 it is at x = 11, so pixels 6..=10 are in the triangle.
    let r5 = &rows[5];
    let edges: Vec<(u32, bool, u32)> = r5
        .active_edges
        .iter()
        .map(|e| (e.face, e.left, e.crossing))
        .collect();
    assert_eq!(
        edges,
        vec![(0, true, 2), (1, true, 6), (0, false, 10), (1, false, 11)]
    );
    let slanted = &r5.active_edges[3];
    assert_eq!(
        (
            slanted.y_min,
            slanted.x,
            slanted.y_max,
            slanted.inverse_slope
        ),
        (4.0, 11.0, 8.0, -2.0)
    );
    let spans: Vec<(u32, u32, Vec<u32>)> = r5
        .spans
        .iter()
        .map(|s| (s.x0, s.x1, s.faces.clone()))
        .collect();
    assert_eq!(
        spans,
        vec![
            (0, 2, vec![]),
            (2, 6, vec![0]),
            (6, 10, vec![0, 1]),
            (10, 11, vec![1]),
            (11, 20, vec![]),
        ]
    );
    // Rows 6 and 7: the triangle ends at x = 9 and 7, inside the square.
    for (r, end) in [(6, 9), (7, 7)] {
        let s: Vec<(u32, u32, usize)> = rows[r]
            .spans
            .iter()
            .map(|s| (s.x0, s.x1, s.faces.len()))
            .collect();
        assert_eq!(
            s,
            vec![(0, 2, 0), (2, 6, 1), (6, end, 2), (end, 10, 1), (10, 20, 0)],
            "row {r}"
        );
    }

    // The overlap is decided at its ends on rows 4 and 5 (where the order is also
    // proven fixed), then reused by coherence on rows 6 and 7.
    let overlap: Vec<SpanDecision> = (4..8)
        .map(|r| {
            rows[r]
                .spans
                .iter()
                .find(|s| s.faces.len() == 2)
                .unwrap()
                .decision
        })
        .collect();
    assert_eq!(
        overlap,
        vec![
            SpanDecision::NearestAtEnds,
            SpanDecision::NearestAtEnds,
            SpanDecision::Coherence,
            SpanDecision::Coherence
        ]
    );
    assert_eq!(stats.spans_by_coherence, 2);
    // Each reuse skips finding the nearest of 2 faces (1) and checking it at both ends (2).
    assert_eq!(stats.comparisons_skipped_by_coherence, 6);
    // Single-face spans: 8 rows of the square alone or with the triangle's side spans.
    let single: usize = rows
        .iter()
        .flat_map(|r| &r.spans)
        .filter(|s| s.decision == SpanDecision::SingleFace)
        .count();
    assert_eq!(stats.spans_without_comparison, single as u64);
    assert_eq!(single, 4 + 2 * 4); // rows 2,3,8,9: one; rows 4..=7: two

    // The picture: the triangle over the square.
    assert_eq!(frame.id(7, 5), 1);
    assert_eq!(frame.id(10, 5), 1);
    assert_eq!(frame.id(11, 5), BACKGROUND);
    assert_eq!(frame.id(9, 6), 0);
    assert_eq!(frame.id(3, 3), 0);
    hsr_scenes::assert_same(
        &case.name,
        ALGO,
        &frame,
        &crate::render(Algorithm::ZBuffer, &view, &RenderOptions::default())
            .unwrap()
            .0,
    );
}

#[test]
fn coherence_skips_comparisons_on_repeated_rows() {
    // Three stacked rectangles over 40 identical rows, each nearer than the one left
    // of it. On each row the spans where a nearer face enters ({0,1} and {0,1,2}) are
    // decided at their ends twice (first row, then the row that proves the order) and
    // reused on the 38 rows after; where face 0 leaves ({1,2}), face 2 stays the
    // nearest, kept from the span before without any comparison, on every row.
    let rect =
        |x0: f64, x1: f64, z: f64| vec![(x0, 4., z), (x1, 4., z), (x1, 44., z), (x0, 44., z)];
    let polys = [rect(2., 30., 0.), rect(10., 40., 1.), rect(20., 50., 2.)];
    let case = pixel_case("stacked rectangles", &polys, 64, 48);
    let stats = case.assert_matches_zbuffer(ALGO);
    // Per row: [10,20) {0,1}, [20,30) {0,1,2}, [30,40) {1,2}: three multi-face spans.
    assert_eq!(sl(&stats).spans_decided_at_ends, 2 * 2);
    assert_eq!(sl(&stats).spans_by_coherence, 2 * 38);
    assert_eq!(sl(&stats).spans_by_kept_nearest, 40);
    // Skipped per reuse: 3 (k - 1) for k faces: 3 + 6.
    assert_eq!(sl(&stats).comparisons_skipped_by_coherence, 9 * 38);
    assert_eq!(sl(&stats).spans_without_comparison, 2 * 40);
    assert_eq!(sl(&stats).spans, 5 * 40);
}

#[test]
fn coherence_is_not_used_when_faces_interpenetrate() {
    // Two rectangles over the same rows whose depths cross at x = 20: the order
    // changes inside the span, so it can never be reused.
    let polys = [
        vec![(4., 4., 0.), (36., 4., 0.), (36., 28., 0.), (4., 28., 0.)],
        vec![(4., 4., -1.), (36., 4., 1.), (36., 28., 1.), (4., 28., -1.)],
    ];
    let case = pixel_case("crossing rectangles", &polys, 40, 32);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(sl(&stats).spans_by_coherence, 0);
    assert_eq!(sl(&stats).orders_proven, 0);
    assert_eq!(sl(&stats).spans_per_pixel, 24);
    let ((frame, _), _) = case.render_pair(ALGO);
    // Left of x = 20 the flat one (face 0) is nearer, right of it the tilted one.
    assert_eq!(frame.id(10, 10), 0);
    assert_eq!(frame.id(30, 10), 1);
}

#[test]
fn a_face_hidden_over_its_whole_span_is_left_out_on_entering() {
    // Face 0: the square (2,2)-(16,10) at z = 1, nearer; face 1: the triangle (6,4)
    // (14,4) (6,8) at z = 0, behind it. On rows 4..=7 the triangle enters inside the
    // square's span and ends before it: the square, kept as the nearest face, is
    // nearer at the triangle's first and last samples, so the triangle is left out
    // (two comparisons each time) and every span holds the square alone.
    let polys = [
        vec![(2., 2., 1.), (16., 2., 1.), (16., 10., 1.), (2., 10., 1.)],
        vec![(6., 4., 0.), (14., 4., 0.), (6., 8., 0.)],
    ];
    let case = pixel_case("triangle behind a square", &polys, 20, 12);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(sl(&stats).faces_hidden_on_entering, 4);
    assert_eq!(sl(&stats).depth_comparisons, 8);
    // Rows 2, 3, 8, 9: one span; rows 4..=7: split at the triangle's crossings.
    assert_eq!(sl(&stats).spans, 4 + 4 * 3);
    assert_eq!(sl(&stats).spans_without_comparison, 16);
    let ((frame, _), _) = case.render_pair(ALGO);
    assert_eq!(frame.id(8, 5), 0);
}

#[test]
fn degenerate_polygons_are_skipped_without_panic() {
    // A zero-area triangle (collinear) and a triangle smaller than a pixel between
    // samples: neither covers anything.
    let polys = vec![
        vec![
            DVec3::new(-1., 0., 0.),
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
        ],
        vec![
            DVec3::new(0.001, 0.001, 0.),
            DVec3::new(0.002, 0.001, 0.),
            DVec3::new(0.001, 0.002, 0.),
        ],
    ];
    let cam = Camera::perspective(
        DVec3::new(0., 0., 4.),
        DVec3::ZERO,
        DVec3::Y,
        50.0,
        0.5,
        20.0,
    );
    let case = Case::new("degenerate", scene_of(&polys), cam, 8, 6);
    let stats = case.assert_matches_zbuffer(ALGO);
    assert_eq!(sl(&stats).spans, 0);
}

#[test]
fn a_single_face_is_drawn_without_any_depth_comparison() {
    // A triangle (2,1) (13,4) (5,10) in pixels: every span holds that one face.
    let polys = [vec![(2.0, 1.0, 0.0), (13.0, 4.0, 0.0), (5.0, 10.0, 0.0)]];
    let case = pixel_case("single triangle", &polys, 16, 12);
    let stats = case.assert_matches_zbuffer(ALGO);
    // Rows 1..=9 (sample lines 1.5 .. 9.5) each hold one span of the triangle.
    assert_eq!(sl(&stats).spans, 9);
    assert_eq!(sl(&stats).spans_without_comparison, 9);
    assert_eq!(sl(&stats).depth_comparisons, 0);
    assert_eq!(sl(&stats).edges, 3);
}
