//! Cross-checks of every clipping algorithm of the seeds: hand-computed cases (the
//! arithmetic is in the comments), the seeds' worked scenarios, and properties on
//! random input where the algorithms must agree with each other and with brute force.

use glam::{DMat4, DVec2, DVec3, DVec4};
use obscura::clip::split::{Split, split_polygon};
use obscura::clip::sutherland_hodgman::{self as sh, ClipPlane};
use obscura::clip::{
    ConvexWindow, OUT_BOTTOM, OUT_FAR, OUT_LEFT, OUT_NEAR, OUT_RIGHT, OUT_TOP, Rect, WindowError,
    cohen_sutherland as cs, liang_barsky as lb, outcode_homogeneous, polygon_area_2d,
    projection_order, region_codes,
};
use obscura::geom::{Aabb, Plane, polygon_area};
use proptest::prelude::*;

const TOL: f64 = 1e-9;

type Seg2 = Option<(DVec2, DVec2)>;
type Seg3 = Option<(DVec3, DVec3)>;
type Seg4 = Option<(DVec4, DVec4)>;

fn v2(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn near2(a: DVec2, b: DVec2, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

fn assert_seg2(got: Seg2, want: Seg2, tol: f64, what: &str) {
    match (got, want) {
        (None, None) => {}
        (Some((a, b)), Some((c, d))) => assert!(
            near2(a, c, tol) && near2(b, d, tol),
            "{what}: got {a} {b}, want {c} {d}"
        ),
        _ => panic!("{what}: got {got:?}, want {want:?}"),
    }
}

fn same_seg3(x: Seg3, y: Seg3, tol: f64) -> bool {
    match (x, y) {
        (None, None) => true,
        (Some((a, b)), Some((c, d))) => {
            (a - c).abs().max_element() <= tol && (b - d).abs().max_element() <= tol
        }
        _ => false,
    }
}

fn same_seg4(x: Seg4, y: Seg4, tol: f64) -> bool {
    match (x, y) {
        (None, None) => true,
        (Some((a, b)), Some((c, d))) => {
            (a - c).abs().max_element() <= tol && (b - d).abs().max_element() <= tol
        }
        _ => false,
    }
}

/// `gluPerspective`: vertical field of view `fov_y` (radians), eye space to OpenGL
/// clip space (`w = -z_eye`, near plane at `z = -w`, far at `z = w`).
fn perspective(fov_y: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let f = 1.0 / (fov_y / 2.0).tan();
    DMat4::from_cols(
        DVec4::new(f / aspect, 0., 0., 0.),
        DVec4::new(0., f, 0., 0.),
        DVec4::new(0., 0., (far + near) / (near - far), -1.),
        DVec4::new(0., 0., 2. * far * near / (near - far), 0.),
    )
}

fn in_homogeneous_volume(v: DVec4, tol: f64) -> bool {
    ClipPlane::ALL.iter().all(|p| p.distance(v) >= -tol)
}

fn in_box(p: DVec3, b: &Aabb, tol: f64) -> bool {
    p.cmpge(b.min - tol).all() && p.cmple(b.max + tol).all()
}

fn in_window(w: &ConvexWindow, p: DVec2, tol: f64) -> bool {
    // Distances, not raw edge values (those are scaled by the edge length).
    (0..w.edge_count()).all(|i| {
        let line = w.edge_line(i);
        line.evaluate(p) / line.a.hypot(line.b) >= -tol
    })
}

// ---------------------------------------------------------------------------------
// Hand-computed cases
// ---------------------------------------------------------------------------------

/// Seed 001, figure 6.3: PQ against the rectangle ABCD is cut into P T2, T2 T0, T0 T1,
/// T1 Q and only T2 T0 is kept.
#[test]
fn figure_6_3_segment_split_into_four_pieces() {
    // Window [0,4] x [0,4]; A = LU (0,4), B = RU (4,4), C = RL (4,0), D = LL (0,0).
    // P = (1,-1), Q = (6,9), Q - P = (5,10).
    // Codes (6.5): P has y < ymin -> p2 -> p = 0100; Q has y > ymax and x > xmax -> 0011.
    // r = p XOR q = 0111: lines 0 (y = 4), 1 (x = 4), 2 (y = 0) cross PQ.
    // T2: y = 0 -> t = 1/10 -> (1.5, 0); T0: y = 4 -> t = 5/10 -> (3.5, 4);
    // T1: x = 4 -> t = 3/5 -> (4, 5). Sorted: P, T2, T0, T1, Q.
    // Midpoints: t = .05 (1.25,-.5) 0100; t = .3 (2.5,2) 0000 kept;
    //            t = .55 (3.75,4.5) 0001; t = .8 (5,7) 0011.
    let rect = Rect::new(0., 0., 4., 4.).unwrap();
    let from_corners =
        ConvexWindow::new(&[v2(0., 4.), v2(4., 4.), v2(4., 0.), v2(0., 0.)]).unwrap();
    assert_eq!(from_corners, ConvexWindow::rectangle(&rect));
    let (p, q) = (v2(1., -1.), v2(6., 9.));
    let trace = region_codes::clip_segment_traced(&from_corners, p, q);
    assert_eq!(trace.p_code.to_string(), "0100");
    assert_eq!(trace.q_code.to_string(), "0011");
    assert_eq!(trace.xor.to_string(), "0111");
    assert!(trace.and.is_zero());
    assert!(!trace.accepted_whole);
    let lines: Vec<usize> = trace.crossings.iter().map(|c| c.line).collect();
    assert_eq!(lines, vec![2, 0, 1]);
    let want_t = [0.1, 0.5, 0.6];
    let want_pts = [v2(1.5, 0.), v2(3.5, 4.), v2(4., 5.)];
    for (c, (&t, &pt)) in trace.crossings.iter().zip(want_t.iter().zip(&want_pts)) {
        assert!(
            (c.t - t).abs() < 1e-15 && near2(c.point, pt, 1e-14),
            "{c:?}"
        );
    }
    let codes: Vec<String> = trace.pieces.iter().map(|p| p.code.to_string()).collect();
    assert_eq!(codes, vec!["0100", "0000", "0001", "0011"]);
    let kept: Vec<bool> = trace.pieces.iter().map(|p| p.kept).collect();
    assert_eq!(kept, vec![false, true, false, false]);
    let want = Some((v2(1.5, 0.), v2(3.5, 4.)));
    assert_seg2(trace.result, want, 1e-14, "trace");
    assert_seg2(
        region_codes::clip_segment(&from_corners, p, q),
        want,
        1e-14,
        "region codes",
    );
    // The same segment by every other clipper.
    assert_seg2(
        cs::clip_segment_2d(p, q, &rect),
        want,
        1e-14,
        "Cohen-Sutherland",
    );
    assert_seg2(
        lb::clip_segment_2d(p, q, &rect),
        want,
        1e-14,
        "Liang-Barsky",
    );
    assert_seg2(
        sh::clip_segment_2d(p, q, &from_corners),
        want,
        1e-14,
        "Sutherland-Hodgman",
    );
}

#[test]
fn cohen_sutherland_2d_by_hand() {
    // Window [0,4] x [0,3]; (-1,1) -> (5,2), d = (6,1).
    // c1 = 1000 (x < xmin), c2 = 0010 (x > xmax): no trivial decision.
    // p1 -> x = 0: y = 1 + 1 * (0 - (-1)) / 6 = 7/6.
    // p2 -> x = 4 towards (0, 7/6): d = (-5, -5/6), y = 2 + (-5/6)(4 - 5)/(-5) = 11/6.
    let rect = Rect::new(0., 0., 4., 3.).unwrap();
    let (a, b) = cs::clip_segment_2d(v2(-1., 1.), v2(5., 2.), &rect).unwrap();
    assert!(near2(a, v2(0., 7. / 6.), 1e-15) && near2(b, v2(4., 11. / 6.), 1e-15));
    assert_eq!(cs::outcode_2d(v2(-1., 1.), &rect), cs::LEFT);
    assert_eq!(cs::outcode_2d(v2(5., 2.), &rect), cs::RIGHT);
    // Trivial reject: both above (0001 & 0001 != 0), though the x-ranges overlap.
    assert_eq!(cs::clip_segment_2d(v2(-1., 4.), v2(5., 5.), &rect), None);
    // Both corner regions 1001 and 0011 share bit 0: reject without computing anything.
    let (_, steps) = cs::clip_segment_2d_traced(v2(-1., 4.), v2(5., 5.), &rect);
    assert_eq!(steps.len(), 1);
    assert_eq!(steps[0].decision, cs::Decision2d::Reject);
    // A segment missing the window without a trivial reject: (-2, 2) -> (1, 5), on the
    // line y = x + 4, has codes 1000 and 0001, AND = 0. p1 -> x = 0: y = 4, code 0001
    // (y > 3), now sharing bit 0 with p2: rejected after one clip.
    let (res, steps) = cs::clip_segment_2d_traced(v2(-2., 2.), v2(1., 5.), &rect);
    assert_eq!(res, None);
    assert_eq!(steps.len(), 2);
}

#[test]
fn region_codes_on_a_triangle_with_a_vertex_at_the_origin() {
    // Triangle (0,0), (4,0), (0,4), counter-clockwise. Lines: 0: y = 0 (inside y >= 0),
    // 1: x + y = 4 (inside x + y <= 4), 2: x = 0 (inside x >= 0). Lines 0 and 2 pass
    // through the origin: the seed's a x + b y + 1 = 0 cannot describe them.
    // P = (-1, 1): bit 2 -> p = 100. Q = (5, 1): x + y = 6 > 4 -> q = 010. r = 110.
    // T2: x = 0 at t = 1/6 -> (0, 1); T1: -1 + 6t + 1 = 4 -> t = 2/3 -> (3, 1).
    // Pieces: P T2 (mid x = -.5) 100; T2 T1 (mid (1.5,1)) 000 kept; T1 Q (mid (4,1)) 010.
    let ccw = [v2(0., 0.), v2(4., 0.), v2(0., 4.)];
    let w = ConvexWindow::new(&ccw).unwrap();
    assert!(w.is_counter_clockwise());
    assert_eq!(w.edge_line(0).seed_form(), None);
    assert_eq!(w.edge_line(2).seed_form(), None);
    let (p, q) = (v2(-1., 1.), v2(5., 1.));
    let t = region_codes::clip_segment_traced(&w, p, q);
    assert_eq!(
        (
            t.p_code.to_string(),
            t.q_code.to_string(),
            t.xor.to_string()
        ),
        ("100".into(), "010".into(), "110".into())
    );
    let codes: Vec<String> = t.pieces.iter().map(|p| p.code.to_string()).collect();
    assert_eq!(codes, vec!["100", "000", "010"]);
    let want = Some((v2(0., 1.), v2(3., 1.)));
    assert_seg2(t.result, want, 1e-15, "traced");
    // Clockwise, the bits are numbered along the other edge order but the result is
    // the same.
    let cw = ConvexWindow::new(&[ccw[2], ccw[1], ccw[0]]).unwrap();
    assert!(!cw.is_counter_clockwise());
    assert_seg2(
        region_codes::clip_segment(&cw, p, q),
        want,
        1e-15,
        "clockwise",
    );
    // Reversed segment: endpoints come back in the input order.
    assert_seg2(
        region_codes::clip_segment(&w, q, p),
        Some((v2(3., 1.), v2(0., 1.))),
        1e-15,
        "reversed",
    );
}

#[test]
fn cohen_sutherland_3d_box_recursion_by_hand() {
    // Box [0,1]^3; p1 = (-1,-1,.5) has x < xmin and y < ymin: c1 = 000101;
    // p2 = (1,2,.5) has y > ymax: c2 = 001000. c1 | c2 != 0, c1 & c2 = 0.
    // First R: lowest differing bit = bit 0 (x = 0): t = (0 - -1)/(1 - -1) = 1/2,
    // i = (0, .5, .5); p1 is outside R -> CS_Clip_3D(i, p2).
    // Codes 0 and 001000: R = y = 1, t = (1 - .5)/(2 - .5) = 1/3 from i,
    // i' = (1/3, 1, .5); i is inside R -> CS_Clip_3D(i, i'): accept.
    // Check on the original line x = -1 + 2s, y = -1 + 3s: x >= 0 <=> s >= 1/2,
    // y <= 1 <=> s <= 2/3: from (0, .5) to (1/3, 1).
    let unit = Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let (p1, p2) = (DVec3::new(-1., -1., 0.5), DVec3::new(1., 2., 0.5));
    assert_eq!(cs::outcode_box(p1, &unit), OUT_LEFT | OUT_BOTTOM);
    assert_eq!(cs::outcode_box(p2, &unit), OUT_TOP);
    let want = Some((DVec3::new(0., 0.5, 0.5), DVec3::new(1. / 3., 1., 0.5)));
    assert!(same_seg3(cs::clip_segment_box(p1, p2, &unit), want, 1e-15));
    assert!(same_seg3(lb::clip_segment_box(p1, p2, &unit), want, 1e-15));
    assert!(same_seg3(sh::clip_segment_box(p1, p2, &unit), want, 1e-15));
}

#[test]
fn twenty_seven_regions_in_3d() {
    let unit = Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let mut box_codes = std::collections::BTreeSet::new();
    let mut homogeneous_codes = std::collections::BTreeSet::new();
    for x in [-1.0, 0.5, 2.0] {
        for y in [-1.0, 0.5, 2.0] {
            for z in [-1.0, 0.5, 2.0] {
                box_codes.insert(cs::outcode_box(DVec3::new(x, y, z), &unit));
                // The same 27 cells of the cube [-1,1]^3 at w = 1 (coordinates 2s - 1).
                let h = DVec4::new(2. * x - 1., 2. * y - 1., 2. * z - 1., 1.);
                homogeneous_codes.insert(outcode_homogeneous(h));
            }
        }
    }
    assert_eq!(box_codes.len(), 27);
    assert_eq!(box_codes, homogeneous_codes);
    assert!(box_codes.contains(&0) && box_codes.contains(&(OUT_RIGHT | OUT_TOP | OUT_FAR)));
}

#[test]
fn homogeneous_segment_crossing_w_zero_by_hand() {
    // p1 = (.5,0,0,1) inside; p2 = (1.5,0,0,-1) behind the eye (w < 0).
    // c2: x > w (1.5 > -1) right; y = 0 < -w = 1 bottom and > w = -1 top; likewise
    // near and far: c2 = right|bottom|top|near|far, c1 = 0.
    // Lowest differing bit: right. (3): t = (x1 - w1)/((x1 - x2) + (w2 - w1))
    //   = (.5 - 1)/((.5 - 1.5) + (-1 - 1)) = -.5 / -3 = 1/6,
    // i = p1 + (p2 - p1)/6 = (.5 + 1/6, 0, 0, 1 - 2/6) = (2/3, 0, 0, 2/3): code 0, accept.
    let (p1, p2) = (DVec4::new(0.5, 0., 0., 1.), DVec4::new(1.5, 0., 0., -1.));
    assert_eq!(
        outcode_homogeneous(p2),
        OUT_RIGHT | OUT_BOTTOM | OUT_TOP | OUT_NEAR | OUT_FAR
    );
    assert_eq!(ClipPlane::Right.intersection_t(p1, p2), 1. / 6.);
    let want = Some((p1, DVec4::new(2. / 3., 0., 0., 2. / 3.)));
    let got = cs::clip_segment_homogeneous(p1, p2);
    assert!(same_seg4(got, want, 1e-15), "{got:?}");
    // Cohen-Sutherland put the new endpoint exactly on x = w.
    let (_, e) = got.unwrap();
    assert_eq!(e.x, e.w);
    assert!(same_seg4(lb::clip_segment_homogeneous(p1, p2), want, 1e-15));
    assert!(same_seg4(sh::clip_segment_homogeneous(p1, p2), want, 1e-15));
    // Reversed: the same piece, endpoints in the input order.
    let want_rev = want.map(|(a, b)| (b, a));
    assert!(same_seg4(
        cs::clip_segment_homogeneous(p2, p1),
        want_rev,
        1e-15
    ));
    assert!(same_seg4(
        lb::clip_segment_homogeneous(p2, p1),
        want_rev,
        1e-15
    ));
    assert!(same_seg4(
        sh::clip_segment_homogeneous(p2, p1),
        want_rev,
        1e-15
    ));
}

#[test]
fn liang_barsky_table_by_hand() {
    // p1 = (-2,0,0,1), p2 = (2,.5,0,1): Dx = 4, Dy = .5, Dz = 0, Dw = 0.
    // p1 = -Dx - Dw = -4, q1 = x1 + w1 = -1   -> t >= 1/4 (entering)
    // p2 =  Dx - Dw =  4, q2 = w1 - x1 =  3   -> t <= 3/4 (leaving)
    // p3 = -Dy - Dw = -.5, q3 = y1 + w1 = 1   -> t >= -2
    // p4 =  Dy - Dw =  .5, q4 = w1 - y1 = 1   -> t <= 2
    // p5 = p6 = 0 with q5 = q6 = 1 >= 0: parallel and inside.
    // t in [1/4, 3/4]: (-1, .125, 0, 1) to (1, .375, 0, 1).
    let (a, b) = (DVec4::new(-2., 0., 0., 1.), DVec4::new(2., 0.5, 0., 1.));
    assert_eq!(
        lb::homogeneous_pq(a, b),
        [
            (-4., -1.),
            (4., 3.),
            (-0.5, 1.),
            (0.5, 1.),
            (-0., 1.),
            (0., 1.)
        ]
    );
    assert_eq!(lb::homogeneous_parameters(a, b), Some((0.25, 0.75)));
    assert_eq!(
        lb::clip_segment_homogeneous(a, b),
        Some((
            DVec4::new(-1., 0.125, 0., 1.),
            DVec4::new(1., 0.375, 0., 1.)
        ))
    );
    // Crossing w = 0: p1 = (.5,0,0,1), p2 = (1.5,0,0,-1): Dx = 1, Dw = -2.
    // (p, q): (-1+2, 1.5) = (1, 1.5); (1+2, .5) = (3, .5); (0+2, 1) = (2, 1) four times.
    // All p > 0 (leaving): t <= min(1.5, 1/6, 1/2) = 1/6.
    let pq = lb::homogeneous_pq(DVec4::new(0.5, 0., 0., 1.), DVec4::new(1.5, 0., 0., -1.));
    assert_eq!(
        pq,
        [(1., 1.5), (3., 0.5), (2., 1.), (2., 1.), (2., 1.), (2., 1.)]
    );
    // Orthographic cube [-1,1]^3, (0,0,-3) -> (0,0,3): rows 5, 6 = (-6, -2), (6, 4):
    // t >= 1/3, t <= 2/3.
    let cube = Aabb {
        min: DVec3::splat(-1.),
        max: DVec3::ONE,
    };
    let (c, d) = (DVec3::new(0., 0., -3.), DVec3::new(0., 0., 3.));
    assert_eq!(lb::box_pq(c, d, &cube)[4], (-6., -2.));
    assert_eq!(lb::box_pq(c, d, &cube)[5], (6., 4.));
    assert_eq!(lb::box_parameters(c, d, &cube), Some((1. / 3., 2. / 3.)));
    // 2D: the rectangle rows.
    let rect = Rect::new(0., 0., 4., 4.).unwrap();
    assert_eq!(
        lb::rect_pq(v2(1., -1.), v2(6., 9.), &rect),
        [(-5., 1.), (5., 3.), (-10., -1.), (10., 5.)]
    );
}

#[test]
fn sutherland_hodgman_2d_by_hand_in_both_windings() {
    // Triangle (1,1), (3,1), (1,3) against [0,2]^2.
    // Counter-clockwise window (0,0),(2,0),(2,2),(0,2): stages y >= 0, x <= 2, y <= 2,
    // x >= 0.
    //  y >= 0: unchanged.
    //  x <= 2 (d = 2 - x: 1, -1, 1): (1,1) in; (1,1)->(3,1) leaves at t = 1/2: (2,1);
    //    (3,1)->(1,3) enters at (2,2), then (1,3): [(1,1),(2,1),(2,2),(1,3)].
    //  y <= 2 (d = 2 - y: 1, 1, 0, -1): (1,3)->(1,1) enters at (1,2), then (1,1), (2,1),
    //    (2,2) (on the line: kept, no intersection), (2,2)->(1,3) leaves from a vertex on
    //    the line: nothing new. [(1,2),(1,1),(2,1),(2,2)].
    //  x >= 0: unchanged.
    // The clockwise window A,B,C,D of figure 6.3 gives the same list (worked in the
    // doc example of `clip_polygon_2d`).
    let tri = [v2(1., 1.), v2(3., 1.), v2(1., 3.)];
    let want = vec![v2(1., 2.), v2(1., 1.), v2(2., 1.), v2(2., 2.)];
    let ccw = ConvexWindow::new(&[v2(0., 0.), v2(2., 0.), v2(2., 2.), v2(0., 2.)]).unwrap();
    let cw = ConvexWindow::rectangle(&Rect::new(0., 0., 2., 2.).unwrap());
    assert_eq!(sh::clip_polygon_2d(&tri, &ccw), want);
    assert_eq!(sh::clip_polygon_2d(&tri, &cw), want);
    // Square [1,3]^2 against the triangle (0,0),(4,0),(0,4): the line x + y = 4 passes
    // through the vertices (3,1) and (1,3), which stay (no duplicates); (3,3) goes.
    let square = [v2(1., 1.), v2(3., 1.), v2(3., 3.), v2(1., 3.)];
    let tri_window = ConvexWindow::new(&[v2(0., 0.), v2(4., 0.), v2(0., 4.)]).unwrap();
    assert_eq!(
        sh::clip_polygon_2d(&square, &tri_window),
        vec![v2(1., 1.), v2(3., 1.), v2(1., 3.)]
    );
}

#[test]
fn sutherland_hodgman_box_by_hand() {
    // Unit box; A = (.5,.5,-1), B = (.5,.5,2), C = (.5,.8,.5), all at x = .5.
    // near z >= 0 (d = z: -1, 2, .5): C->A leaves at t = .5/1.5 = 1/3: (.5,.7,0);
    //   A->B enters, from B at t = 2/3: (.5,.5,0), then B; then C.
    // far z <= 1 (d = 1 - z: 1, 1, -1, .5): (.5,.5,0)->B leaves at t = 1/2: (.5,.5,1);
    //   B->C enters from C at t = .5/1.5: (.5,.7,1), then C.
    // x = .5 and y in [.5,.8]: the other stages keep everything.
    // Area in the (y, z) plane: rectangle .2 x 1 plus triangle (.7,0),(.7,1),(.8,.5)
    // of area .05: 0.25.
    let unit = Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    let tri = [
        DVec3::new(0.5, 0.5, -1.),
        DVec3::new(0.5, 0.5, 2.),
        DVec3::new(0.5, 0.8, 0.5),
    ];
    let out = sh::clip_polygon_box(&tri, &unit);
    let want = [
        DVec3::new(0.5, 0.7, 0.),
        DVec3::new(0.5, 0.5, 0.),
        DVec3::new(0.5, 0.5, 1.),
        DVec3::new(0.5, 0.7, 1.),
        DVec3::new(0.5, 0.8, 0.5),
    ];
    assert_eq!(out.len(), want.len(), "{out:?}");
    for (o, w) in out.iter().zip(&want) {
        assert!((*o - *w).length() < 1e-12, "{out:?}");
    }
    assert!((polygon_area(&out) - 0.25).abs() < 1e-12);
}

#[test]
fn homogeneous_triangle_crossing_w_zero_by_hand() {
    // A = (.5,0,0,1), B = (1.5,0,0,-1) (behind the eye), C = (.5,.5,0,1).
    // Stage order near, far, left, right, bottom, top.
    // near (w + z: 1, -1, 1): A; A->B leaves at t = 1/2: X1 = (1,0,0,0);
    //   B->C enters, from C at t = 1/2: X2 = (1,.25,0,0); C.
    // far (w - z: 1, 0, 0, 1) and left (w + x: 1.5, 1, 1, 1.5): unchanged.
    // right (w - x: .5, -1, -1, .5): A; A->X1 leaves at t = .5/1.5 = 1/3:
    //   (.5 + .5/3, 0, 0, 1 - 1/3) = (2/3, 0, 0, 2/3); X2->C enters from C at 1/3:
    //   (.5 + .5/3, .5 - .25/3, 0, 2/3) = (2/3, 5/12, 0, 2/3); C.
    // bottom, top: unchanged. After the divide: (.5,0), (1,0), (1,5/8), (.5,.5),
    // a trapezoid of area (1 - .5)(.5 + .625)/2 = 0.28125.
    let tri = [
        DVec4::new(0.5, 0., 0., 1.),
        DVec4::new(1.5, 0., 0., -1.),
        DVec4::new(0.5, 0.5, 0., 1.),
    ];
    let out = sh::clip_polygon_homogeneous(&tri);
    let want = [
        tri[0],
        DVec4::new(2. / 3., 0., 0., 2. / 3.),
        DVec4::new(2. / 3., 5. / 12., 0., 2. / 3.),
        tri[2],
    ];
    assert_eq!(out.len(), 4, "{out:?}");
    for (o, w) in out.iter().zip(&want) {
        assert!((*o - *w).length() < 1e-15, "{out:?}");
    }
    let before = projection_order::clip_polygon_before_projection(&tri);
    assert!((polygon_area_2d(&before).abs() - 0.28125).abs() < 1e-14);
    // After projection B lands at (-1.5, 0), on the wrong side: the "visible" part is
    // (.5,0), then B's edges cut at x = -1: from (-1.5,0)->(.5,0) at (-1,0) and
    // (-1.5,0)->(.5,.5) at t = .25: (-1, .125). A trapezoid over x in [-1,.5] with
    // heights .125 and .5: area 1.5 * .625 / 2 = 0.46875, and on the left of x = .5
    // where nothing is visible.
    let after = projection_order::clip_polygon_after_projection(&tri);
    assert!((polygon_area_2d(&after).abs() - 0.46875).abs() < 1e-14);
    assert!(before.iter().all(|p| p.x >= 0.5 - 1e-15));
    assert!(after.iter().all(|p| p.x <= 0.5 + 1e-15));
}

#[test]
fn clipping_after_projection_goes_wrong_across_the_eye_plane() {
    // Camera: 90 degree vertical field of view, aspect 1, near 1, far 10, so
    // x_ndc = x_e / -z_e in front of the eye.
    // Segment a = (.5,0,-2) (in front) to b = (.5,0,2) (behind the eye).
    // Before: the part with z_e <= -1, from a (x_ndc = .25) to (.5,0,-1) (x_ndc = .5).
    // After: b has w = -z_e = -2 and projects to .5 / -2 = -.25; the projected segment
    // (.25,0)-(-.25,0) lies in the window and is kept whole, through the middle of the
    // screen, where the real segment never appears.
    let m = perspective(std::f64::consts::FRAC_PI_2, 1.0, 1.0, 10.0);
    let clip = |p: DVec3| m * p.extend(1.0);
    let (a, b) = (
        clip(DVec3::new(0.5, 0., -2.)),
        clip(DVec3::new(0.5, 0., 2.)),
    );
    assert!(b.w < 0.0);
    assert_seg2(
        projection_order::clip_segment_before_projection(a, b),
        Some((v2(0.25, 0.), v2(0.5, 0.))),
        1e-12,
        "before",
    );
    assert_seg2(
        projection_order::clip_segment_after_projection(a, b),
        Some((v2(0.25, 0.), v2(-0.25, 0.))),
        1e-12,
        "after",
    );
    // Drawback (a) of clipping after projection: no depth rejection. A segment beyond
    // the far plane (z_e = -20 < -10) is dropped before, kept after:
    // (0,0,-20) -> (0,0); (.5,0,-20) -> (.025, 0).
    let (c, d) = (
        clip(DVec3::new(0., 0., -20.)),
        clip(DVec3::new(0.5, 0., -20.)),
    );
    assert_eq!(projection_order::clip_segment_before_projection(c, d), None);
    assert_seg2(
        projection_order::clip_segment_after_projection(c, d),
        Some((v2(0., 0.), v2(0.025, 0.))),
        1e-12,
        "after, beyond far",
    );
    // An endpoint exactly on the eye plane has no projection.
    assert_eq!(
        projection_order::clip_segment_after_projection(a, DVec4::new(1., 0., 0., 0.)),
        None
    );
}

#[test]
fn split_by_hand() {
    // Square [-1,1]^2 at z = 0 (area 4), plane x = 0.5 with normal +x.
    // Edges (1,-1)->(1,1) front; (-1,-1)->(1,-1) crosses at (.5,-1); (1,1)->(-1,1)
    // crosses at (.5,1). Front: x in [.5,1], area .5 * 2 = 1; back: x in [-1,.5], 3.
    let sq = [
        DVec3::new(-1., -1., 0.),
        DVec3::new(1., -1., 0.),
        DVec3::new(1., 1., 0.),
        DVec3::new(-1., 1., 0.),
    ];
    let plane = Plane::from_point_normal(DVec3::new(0.5, 0., 0.), DVec3::X);
    let Split::Spanning { front, back } = split_polygon(&sq, &plane, 1e-12) else {
        panic!("the plane crosses the square")
    };
    assert_eq!(
        front,
        vec![
            DVec3::new(0.5, -1., 0.),
            DVec3::new(1., -1., 0.),
            DVec3::new(1., 1., 0.),
            DVec3::new(0.5, 1., 0.)
        ]
    );
    assert_eq!(polygon_area(&back), 3.0);
    // A plane without a usable normal, or a polygon of fewer than three vertices,
    // splits nothing: documented as Front.
    for d in [1.0, 0.0, f64::NAN] {
        let degenerate = Plane {
            normal: DVec3::ZERO,
            d,
        };
        assert_eq!(split_polygon(&sq, &degenerate, 1e-9), Split::Front);
    }
    let nan_normal = Plane {
        normal: DVec3::new(f64::NAN, 0.0, 1.0),
        d: 0.0,
    };
    assert_eq!(split_polygon(&sq, &nan_normal, 1e-9), Split::Front);
    assert_eq!(split_polygon(&[], &plane, 1e-9), Split::Front);
    assert_eq!(split_polygon(&sq[..2], &plane, 1e-9), Split::Front);
}

#[test]
fn bad_input_never_panics() {
    let rect = Rect::new(0., 0., 1., 1.).unwrap();
    let w = ConvexWindow::rectangle(&rect);
    let nan2 = v2(f64::NAN, 0.5);
    let inside = v2(0.5, 0.5);
    assert_eq!(cs::clip_segment_2d(nan2, inside, &rect), None);
    assert_eq!(lb::clip_segment_2d(nan2, inside, &rect), None);
    assert_eq!(sh::clip_segment_2d(nan2, inside, &w), None);
    assert_eq!(region_codes::clip_segment(&w, nan2, inside), None);
    let t = region_codes::clip_segment_traced(&w, nan2, inside);
    assert_eq!((t.result, t.p_code.to_string()), (None, "1111".to_string()));
    assert!(sh::clip_polygon_2d(&[nan2, inside, v2(0.2, 0.2)], &w).is_empty());
    assert!(sh::clip_polygon_2d(&[], &w).is_empty());
    assert!(sh::clip_polygon_2d(&[inside, v2(0.6, 0.6)], &w).is_empty());
    let cube = Aabb {
        min: DVec3::ZERO,
        max: DVec3::ONE,
    };
    assert!(sh::clip_polygon_box(&[DVec3::NAN; 3], &cube).is_empty());
    assert!(sh::clip_polygon_box(&[DVec3::ZERO, DVec3::X, DVec3::Y], &Aabb::EMPTY).is_empty());
    assert_eq!(
        sh::clip_segment_box(DVec3::ZERO, DVec3::ONE, &Aabb::EMPTY),
        None
    );
    assert_eq!(
        lb::clip_segment_box(DVec3::ZERO, DVec3::ONE, &Aabb::EMPTY),
        None
    );
    assert_eq!(
        cs::clip_segment_box(DVec3::ZERO, DVec3::ONE, &Aabb::EMPTY),
        None
    );
    let nan4 = DVec4::new(0., f64::NAN, 0., 1.);
    assert_eq!(cs::clip_segment_homogeneous(nan4, DVec4::W), None);
    assert_eq!(lb::clip_segment_homogeneous(nan4, DVec4::W), None);
    assert_eq!(sh::clip_segment_homogeneous(nan4, DVec4::W), None);
    assert_eq!(
        projection_order::clip_segment_before_projection(nan4, DVec4::W),
        None
    );
    assert_eq!(
        projection_order::clip_segment_after_projection(nan4, DVec4::W),
        None
    );
    assert!(projection_order::clip_polygon_before_projection(&[nan4; 3]).is_empty());
    assert!(projection_order::clip_polygon_after_projection(&[nan4; 3]).is_empty());
    // Windows.
    assert_eq!(Rect::new(1., 0., 1., 1.), Err(WindowError::EmptyRectangle));
    assert!(matches!(
        ConvexWindow::new(&[v2(0., 0.), v2(2., 0.), v2(1., 0.5), v2(2., 2.), v2(0., 2.)]),
        Err(WindowError::NotConvex(_))
    ));
    let err: obscura::Error = WindowError::TooFewVertices(2).into();
    assert!(err.to_string().contains("at least 3 vertices"), "{err}");
    // The eye itself (the 4D origin) is in the closed volume but has no projection.
    assert_eq!(
        projection_order::clip_segment_before_projection(DVec4::ZERO, DVec4::ZERO),
        None
    );
}

// ---------------------------------------------------------------------------------
// Properties
// ---------------------------------------------------------------------------------

fn coord() -> impl Strategy<Value = f64> {
    -10.0..10.0f64
}

fn point2() -> impl Strategy<Value = DVec2> {
    (coord(), coord()).prop_map(|(x, y)| v2(x, y))
}

fn rect() -> impl Strategy<Value = Rect> {
    (-5.0..5.0f64, -5.0..5.0f64, 0.1..8.0f64, 0.1..8.0f64)
        .prop_map(|(x, y, w, h)| Rect::new(x, y, x + w, y + h).unwrap())
}

fn aabb() -> impl Strategy<Value = Aabb> {
    (
        (-5.0..5.0f64, -5.0..5.0f64, -5.0..5.0f64),
        (0.1..8.0f64, 0.1..8.0f64, 0.1..8.0f64),
    )
        .prop_map(|((x, y, z), (w, h, d))| Aabb {
            min: DVec3::new(x, y, z),
            max: DVec3::new(x + w, y + h, z + d),
        })
}

fn point3() -> impl Strategy<Value = DVec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// Clip-space points, a fair share of them behind the eye (`w < 0`).
fn point4() -> impl Strategy<Value = DVec4> {
    (-3.0..3.0f64, -3.0..3.0f64, -3.0..3.0f64, -2.0..2.0f64)
        .prop_map(|(x, y, z, w)| DVec4::new(x, y, z, w))
}

/// A strictly convex polygon: points on an ellipse at increasing angles (gaps bounded
/// away from 0 and below pi), in either winding, sometimes with vertex 0 moved to the
/// origin (so edge lines pass through it).
fn convex_polygon() -> impl Strategy<Value = Vec<DVec2>> {
    (
        prop::collection::vec(0.3..1.0f64, 3..9),
        (-4.0..4.0f64, -4.0..4.0f64),
        (0.5..5.0f64, 0.5..5.0f64, 0.0..std::f64::consts::PI),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(gaps, (cx, cy), (rx, ry, rot), clockwise, at_origin)| {
            let total: f64 = gaps.iter().sum();
            let mut angle = 0.0f64;
            let (s, c) = rot.sin_cos();
            let mut pts: Vec<DVec2> = gaps
                .iter()
                .map(|g| {
                    let p = v2(rx * angle.cos(), ry * angle.sin());
                    angle += g / total * std::f64::consts::TAU;
                    v2(cx + c * p.x - s * p.y, cy + s * p.x + c * p.y)
                })
                .collect();
            if at_origin {
                let o = pts[0];
                pts.iter_mut().for_each(|p| *p -= o);
            }
            if clockwise {
                pts.reverse();
            }
            pts
        })
}

/// Brute force for a convex window: intersect, over the edges, the parameter
/// intervals where `P + t (Q - P)` is on the window's side of the edge's line, each
/// line taken from the two vertices, its side from the vertex centroid.
fn brute_force_convex(poly: &[DVec2], p: DVec2, q: DVec2) -> Seg2 {
    let n = poly.len();
    let centroid = poly.iter().copied().sum::<DVec2>() / n as f64;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        let side = (b - a).perp_dot(centroid - a).signum();
        let f0 = side * (b - a).perp_dot(p - a);
        let f1 = side * (b - a).perp_dot(q - a);
        // f(t) = f0 + t (f1 - f0) >= 0.
        if f0 < 0.0 && f1 < 0.0 {
            return None;
        }
        if f0 < 0.0 {
            t0 = t0.max(f0 / (f0 - f1));
        } else if f1 < 0.0 {
            t1 = t1.min(f0 / (f0 - f1));
        }
    }
    if t0 > t1 {
        return None;
    }
    Some((p + (q - p) * t0, p + (q - p) * t1))
}

/// Whether a result could legitimately be `None` or a point: the exact answer is a
/// segment shorter than `tol` (a graze), where the algorithms may round either way.
fn is_graze(s: Seg2, tol: f64) -> bool {
    s.is_none_or(|(a, b)| (a - b).length() < tol)
}

fn agree2(got: Seg2, want: Seg2) -> bool {
    match (got, want) {
        (Some((a, b)), Some((c, d))) => near2(a, c, TOL) && near2(b, d, TOL),
        (None, None) => true,
        _ => is_graze(got, 1e-7) && is_graze(want, 1e-7),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Cohen-Sutherland, Liang-Barsky, Sutherland-Hodgman and region codes agree on
    /// rectangles, and their output lies in the rectangle.
    #[test]
    fn segment_clippers_agree_on_rectangles(r in rect(), p in point2(), q in point2()) {
        let w = ConvexWindow::rectangle(&r);
        let reference = lb::clip_segment_2d(p, q, &r);
        let others = [
            ("Cohen-Sutherland", cs::clip_segment_2d(p, q, &r)),
            ("Sutherland-Hodgman", sh::clip_segment_2d(p, q, &w)),
            ("region codes", region_codes::clip_segment(&w, p, q)),
            ("region codes traced", region_codes::clip_segment_traced(&w, p, q).result),
        ];
        for (name, got) in others {
            prop_assert!(agree2(got, reference), "{name}: {got:?} vs Liang-Barsky {reference:?}");
        }
        if let Some((a, b)) = reference {
            for v in [a, b] {
                prop_assert!(v.cmpge(r.min() - TOL).all() && v.cmple(r.max() + TOL).all());
            }
        }
    }

    /// On a rectangle the region codes are exactly the Cohen-Sutherland codes (6.5),
    /// boundary points included (the grid puts many points on the lines).
    #[test]
    fn region_codes_are_cohen_sutherland_codes_on_rectangles(
        x in -3i32..8, y in -3i32..8, fx in 0.0..1.0f64
    ) {
        let r = Rect::new(0., 0., 4., 3.).unwrap();
        let w = ConvexWindow::rectangle(&r);
        for p in [v2(f64::from(x), f64::from(y)), v2(f64::from(x) + fx, f64::from(y) - fx)] {
            prop_assert_eq!(
                region_codes::region_code(&w, p).low_bits(),
                u64::from(cs::outcode_2d(p, &r))
            );
        }
    }

    /// Segments inside come back bit for bit; segments beyond one boundary vanish.
    #[test]
    fn inside_unchanged_outside_gone_2d(
        r in rect(),
        (s1, s2, s3, s4) in (0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64),
        side in 0usize..4,
        far in (0.01..5.0f64, 0.01..5.0f64),
    ) {
        let w = ConvexWindow::rectangle(&r);
        let size = r.max() - r.min();
        let p = r.min() + size * v2(s1, s2);
        let q = r.min() + size * v2(s3, s4);
        let inside = Some((p, q));
        prop_assert_eq!(cs::clip_segment_2d(p, q, &r), inside);
        prop_assert_eq!(lb::clip_segment_2d(p, q, &r), inside);
        prop_assert_eq!(sh::clip_segment_2d(p, q, &w), inside);
        prop_assert_eq!(region_codes::clip_segment(&w, p, q), inside);
        // A triangle of three points inside is inside (the window is convex).
        let tri = [p, q, r.min() + size * v2(s4, s1)];
        if polygon_area_2d(&tri).abs() > 1e-9 {
            prop_assert_eq!(sh::clip_polygon_2d(&tri, &w), tri.to_vec());
        }
        // Move both beyond the same boundary.
        let shift = |v: DVec2, d: f64| match side {
            0 => v2(v.x, r.max().y + d),
            1 => v2(r.max().x + d, v.y),
            2 => v2(v.x, r.min().y - d),
            _ => v2(r.min().x - d, v.y),
        };
        let (a, b) = (shift(p, far.0), shift(q, far.1));
        prop_assert_eq!(cs::clip_segment_2d(a, b, &r), None);
        prop_assert_eq!(lb::clip_segment_2d(a, b, &r), None);
        prop_assert_eq!(sh::clip_segment_2d(a, b, &w), None);
        prop_assert_eq!(region_codes::clip_segment(&w, a, b), None);
        prop_assert!(sh::clip_polygon_2d(&[a, b, shift(p, far.0 + far.1)], &w).is_empty());
    }

    /// Region codes on random convex windows (either winding, lines through the
    /// origin included) agree with brute-force half-plane intersection and with
    /// Sutherland-Hodgman; the trace agrees with the fast path and is consistent.
    #[test]
    fn region_codes_agree_with_brute_force_on_convex_windows(
        poly in convex_polygon(), p in point2(), q in point2()
    ) {
        let w = ConvexWindow::new(&poly).unwrap();
        let want = brute_force_convex(&poly, p, q);
        let got = region_codes::clip_segment(&w, p, q);
        prop_assert!(agree2(got, want), "region codes {got:?} vs brute force {want:?}");
        let by_sh = sh::clip_segment_2d(p, q, &w);
        prop_assert!(agree2(by_sh, want), "Sutherland-Hodgman {by_sh:?} vs {want:?}");
        let trace = region_codes::clip_segment_traced(&w, p, q);
        prop_assert!(agree2(trace.result, got));
        // Observation 2: bit i of the XOR is set iff line i separates P and Q.
        for i in 0..w.edge_count() {
            let line = w.edge_line(i);
            let separated = (line.evaluate(p) < 0.0) != (line.evaluate(q) < 0.0);
            let (vp, vq) = (line.evaluate(p), line.evaluate(q));
            let clear = vp.abs() > 1e-9 && vq.abs() > 1e-9;
            if clear {
                prop_assert_eq!(trace.xor.bit(i), separated);
            }
        }
        // Steps 5-6: the pieces tile [0, 1] in order, and kept = code 0.
        if !trace.accepted_whole {
            prop_assert_eq!(trace.pieces.len(), trace.crossings.len() + 1);
            let mut t = 0.0;
            for piece in &trace.pieces {
                prop_assert_eq!(piece.t.0, t);
                prop_assert!(piece.t.1 >= piece.t.0);
                prop_assert_eq!(piece.kept, piece.code.is_zero());
                t = piece.t.1;
            }
            prop_assert_eq!(t, 1.0);
        }
        if let Some((a, b)) = got {
            prop_assert!(in_window(&w, a, TOL) && in_window(&w, b, TOL));
        }
    }

    /// 2D Sutherland-Hodgman on convex windows: output inside the window, area of the
    /// intersection symmetric (clipping W by P gives the same area as P by W), at most
    /// both areas, and a polygon inside the window unchanged.
    #[test]
    fn sutherland_hodgman_2d_polygons(a in convex_polygon(), b in convex_polygon()) {
        let (wa, wb) = (ConvexWindow::new(&a).unwrap(), ConvexWindow::new(&b).unwrap());
        let ab = sh::clip_polygon_2d(&a, &wb);
        let ba = sh::clip_polygon_2d(&b, &wa);
        // The buffer-reusing form gives the same, whatever the buffers held before.
        let (mut out, mut scratch) = (ba.clone(), a.clone());
        sh::clip_polygon_2d_into(&a, &wb, &mut out, &mut scratch);
        prop_assert_eq!(&out, &ab);
        let (area_ab, area_ba) = (polygon_area_2d(&ab).abs(), polygon_area_2d(&ba).abs());
        prop_assert!((area_ab - area_ba).abs() <= 1e-9 * (1.0 + area_ab), "{area_ab} {area_ba}");
        prop_assert!(area_ab <= wa.area().min(wb.area()) + 1e-9);
        for v in &ab {
            prop_assert!(in_window(&wb, *v, TOL));
        }
        // Winding is kept.
        if area_ab > 1e-9 {
            prop_assert_eq!(polygon_area_2d(&ab) > 0.0, polygon_area_2d(&a) > 0.0);
        }
        // Shrink a towards a point of b's interior until it is inside b: unchanged.
        let centre = b.iter().copied().sum::<DVec2>() / b.len() as f64;
        let small: Vec<DVec2> = a.iter().map(|&v| centre + (v - a[0]) * 1e-3).collect();
        if small.iter().all(|&v| in_window(&wb, v, -1e-12)) {
            prop_assert_eq!(sh::clip_polygon_2d(&small, &wb), small);
        }
    }

    /// Cohen-Sutherland, Liang-Barsky and Sutherland-Hodgman agree against boxes;
    /// output inside; inside segments unchanged.
    #[test]
    fn segment_clippers_agree_on_boxes(
        b in aabb(), p in point3(), q in point3(), s in (0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64)
    ) {
        let by_cs = cs::clip_segment_box(p, q, &b);
        let by_lb = lb::clip_segment_box(p, q, &b);
        let by_sh = sh::clip_segment_box(p, q, &b);
        prop_assert!(same_seg3(by_cs, by_lb, TOL), "{by_cs:?} vs {by_lb:?}");
        prop_assert!(same_seg3(by_sh, by_lb, TOL), "{by_sh:?} vs {by_lb:?}");
        if let Some((x, y)) = by_lb {
            prop_assert!(in_box(x, &b, TOL) && in_box(y, &b, TOL));
        }
        let inside_p = b.min + (b.max - b.min) * DVec3::new(s.0, s.1, s.2);
        let inside_q = b.min + (b.max - b.min) * DVec3::new(s.2, s.0, s.1);
        let whole = Some((inside_p, inside_q));
        prop_assert_eq!(cs::clip_segment_box(inside_p, inside_q, &b), whole);
        prop_assert_eq!(lb::clip_segment_box(inside_p, inside_q, &b), whole);
        prop_assert_eq!(sh::clip_segment_box(inside_p, inside_q, &b), whole);
        // Beyond the far face (z > zmax): gone.
        let up = DVec3::new(0.0, 0.0, b.max.z - b.min.z + 0.5);
        prop_assert_eq!(cs::clip_segment_box(inside_p + up, inside_q + up, &b), None);
        prop_assert_eq!(lb::clip_segment_box(inside_p + up, inside_q + up, &b), None);
        prop_assert_eq!(sh::clip_segment_box(inside_p + up, inside_q + up, &b), None);
    }

    /// The three homogeneous segment clippers agree, also for segments crossing
    /// `w = 0`, and their output is in the view volume.
    #[test]
    fn segment_clippers_agree_in_homogeneous_space(p in point4(), q in point4()) {
        let by_cs = cs::clip_segment_homogeneous(p, q);
        let by_lb = lb::clip_segment_homogeneous(p, q);
        let by_sh = sh::clip_segment_homogeneous(p, q);
        prop_assert!(same_seg4(by_cs, by_lb, TOL), "{by_cs:?} vs {by_lb:?}");
        prop_assert!(same_seg4(by_sh, by_lb, TOL), "{by_sh:?} vs {by_lb:?}");
        for r in [by_cs, by_lb, by_sh].into_iter().flatten() {
            prop_assert!(in_homogeneous_volume(r.0, TOL) && in_homogeneous_volume(r.1, TOL));
            prop_assert!(r.0.w >= -TOL && r.1.w >= -TOL);
        }
        // Inside (both endpoints in the volume, which is convex): unchanged.
        if outcode_homogeneous(p) == 0 && outcode_homogeneous(q) == 0 {
            prop_assert_eq!(by_cs, Some((p, q)));
            prop_assert_eq!(by_lb, Some((p, q)));
            prop_assert_eq!(by_sh, Some((p, q)));
        }
        // Both beyond the same plane: nothing.
        if outcode_homogeneous(p) & outcode_homogeneous(q) != 0 {
            prop_assert!(by_cs.is_none() && by_lb.is_none() && by_sh.is_none());
        }
    }

    /// The seed's p/q table is the six inequalities (2): `q_i - t p_i` is the
    /// homogeneous plane equation at `p(t)` (left: `x + w`, right: `w - x`, ...).
    #[test]
    fn liang_barsky_table_is_the_inequalities(p in point4(), q in point4(), t in 0.0..1.0f64) {
        let at = p + (q - p) * t;
        let order = [
            ClipPlane::Left, ClipPlane::Right, ClipPlane::Bottom,
            ClipPlane::Top, ClipPlane::Near, ClipPlane::Far,
        ];
        for ((pi, qi), plane) in lb::homogeneous_pq(p, q).into_iter().zip(order) {
            prop_assert!(((qi - t * pi) - plane.distance(at)).abs() < 1e-12);
        }
    }

    /// Against the cube `[-1, 1]^3`, box Sutherland-Hodgman and homogeneous
    /// Sutherland-Hodgman with `w = 1` compute the very same vertices.
    #[test]
    fn box_and_homogeneous_sutherland_hodgman_agree_at_w_one(
        tri in prop::array::uniform3((-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64))
    ) {
        let pts = tri.map(|(x, y, z)| DVec3::new(x, y, z));
        let cube = Aabb { min: DVec3::splat(-1.0), max: DVec3::ONE };
        let by_box = sh::clip_polygon_box(&pts, &cube);
        let (mut out, mut scratch) = (vec![DVec3::ONE; 5], vec![DVec3::ZERO; 2]);
        sh::clip_polygon_box_into(&pts, &cube, &mut out, &mut scratch);
        prop_assert_eq!(&out, &by_box);
        let by_h: Vec<DVec3> = sh::clip_polygon_homogeneous(&pts.map(|p| p.extend(1.0)))
            .iter()
            .map(|v| v.truncate())
            .collect();
        prop_assert_eq!(&by_box, &by_h);
        for v in &by_box {
            prop_assert!(in_box(*v, &cube, TOL));
        }
    }

    /// Homogeneous Sutherland-Hodgman on triangles with vertices behind the eye equals
    /// an independent route: cut the eye-space triangle by the near and far planes
    /// (`split_polygon`), project what is left (all of it in front of the eye), and
    /// clip it in 2D against the window. Both give the same visible area.
    #[test]
    fn homogeneous_clipping_equals_eye_space_near_clipping(
        tri in prop::array::uniform3((-6.0..6.0f64, -6.0..6.0f64, -12.0..4.0f64))
    ) {
        let (near, far) = (1.0, 10.0);
        let m = perspective(1.0, 1.3, near, far);
        let eye = tri.map(|(x, y, z)| DVec3::new(x, y, z));
        prop_assume!(polygon_area(&eye) > 1e-3);
        let clip: Vec<DVec4> = eye.iter().map(|&p| m * p.extend(1.0)).collect();
        let before = projection_order::clip_polygon_before_projection(&clip);

        let keep_front = |poly: Vec<DVec3>, plane: Plane| -> Vec<DVec3> {
            match split_polygon(&poly, &plane, 1e-12) {
                Split::Front => poly,
                Split::Spanning { front, .. } => front,
                _ => Vec::new(),
            }
        };
        // Near: visible where z <= -near; far: where z >= -far.
        let mut part = keep_front(
            eye.to_vec(),
            Plane::from_point_normal(DVec3::new(0., 0., -near), DVec3::NEG_Z),
        );
        if !part.is_empty() {
            part = keep_front(part, Plane::from_point_normal(DVec3::new(0., 0., -far), DVec3::Z));
        }
        let projected: Vec<DVec4> = part.iter().map(|&p| m * p.extend(1.0)).collect();
        prop_assert!(projected.iter().all(|v| v.w > 0.0));
        let route = projection_order::clip_polygon_after_projection(&projected);
        let (a1, a2) = (polygon_area_2d(&before).abs(), polygon_area_2d(&route).abs());
        prop_assert!((a1 - a2).abs() <= 1e-9 * (1.0 + a1), "{a1} vs {a2}");
        for v in &before {
            prop_assert!(v.abs().max_element() <= 1.0 + TOL);
        }
    }

    /// For segments in front of the eye, between the near and far planes, clipping
    /// before and after the projection agree.
    #[test]
    fn before_and_after_projection_agree_in_front_of_the_eye(
        a in (-30.0..30.0f64, -30.0..30.0f64, -9.9..-1.01f64),
        b in (-30.0..30.0f64, -30.0..30.0f64, -9.9..-1.01f64),
    ) {
        let m = perspective(1.2, 1.5, 1.0, 10.0);
        let clip = |(x, y, z): (f64, f64, f64)| m * DVec4::new(x, y, z, 1.0);
        let before = projection_order::clip_segment_before_projection(clip(a), clip(b));
        let after = projection_order::clip_segment_after_projection(clip(a), clip(b));
        prop_assert!(agree2(before, after), "{before:?} vs {after:?}");
    }

    /// Split pieces: together the original's area, each on its side of the plane.
    #[test]
    fn split_pieces_keep_the_area_and_their_sides(
        poly in convex_polygon(),
        lift in (-1.0..1.0f64, -1.0..1.0f64, -3.0..3.0f64),
        normal in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
        offset in -3.0..3.0f64,
    ) {
        // The 2D polygon placed on the plane z = lift.0 x + lift.1 y + lift.2.
        let pts: Vec<DVec3> = poly
            .iter()
            .map(|p| DVec3::new(p.x, p.y, lift.0 * p.x + lift.1 * p.y + lift.2))
            .collect();
        let n = DVec3::new(normal.0, normal.1, normal.2);
        prop_assume!(n.length() > 0.1);
        let plane = Plane::from_point_normal(n.normalize() * offset, n);
        let area = polygon_area(&pts);
        let eps = 1e-9;
        match split_polygon(&pts, &plane, eps) {
            Split::Spanning { front, back } => {
                let sum = polygon_area(&front) + polygon_area(&back);
                prop_assert!((sum - area).abs() <= 1e-9 * (1.0 + area), "{sum} vs {area}");
                prop_assert!(front.iter().all(|&p| plane.signed_distance(p) >= -eps));
                prop_assert!(back.iter().all(|&p| plane.signed_distance(p) <= eps));
                // Both pieces keep the polygon's orientation.
                let normal_of = obscura::geom::newell_normal;
                prop_assert!(normal_of(&front).dot(normal_of(&pts)) > 0.0);
                prop_assert!(normal_of(&back).dot(normal_of(&pts)) > 0.0);
            }
            Split::Front => {
                prop_assert!(pts.iter().all(|&p| plane.signed_distance(p) >= -eps));
            }
            Split::Back => {
                prop_assert!(pts.iter().all(|&p| plane.signed_distance(p) <= eps));
            }
            Split::Coplanar { .. } => {
                prop_assert!(pts.iter().all(|&p| plane.signed_distance(p).abs() <= eps));
            }
        }
    }
}

/// Finite coordinates whose differences overflow (1e308 apart) gave NaN endpoints in
/// Liang-Barsky, the homogeneous clippers and the split: every clipper now refuses
/// coordinates beyond `MAX_CLIP_COORDINATE` with `None` (or an empty polygon, or an
/// unsplit polygon), and agrees just inside that range.
#[test]
fn coordinates_beyond_the_clip_range_are_refused_not_turned_into_nan() {
    let rect = Rect::new(0.0, 0.0, 1.0, 1.0).unwrap();
    let window = ConvexWindow::rectangle(&rect);
    let (a, b) = (DVec2::new(-1e308, 0.5), DVec2::new(1e308, 0.5));
    assert_eq!(cs::clip_segment_2d(a, b, &rect), None);
    assert_eq!(lb::clip_segment_2d(a, b, &rect), None);
    assert_eq!(sh::clip_segment_2d(a, b, &window), None);
    assert_eq!(region_codes::clip_segment(&window, a, b), None);
    // Just inside the range: finite results (rounding at this scale is about 1e284,
    // so no agreement to the window's size is expected).
    let (a, b) = (DVec2::new(-1e300, 0.5), DVec2::new(1e300, 0.5));
    for r in [
        cs::clip_segment_2d(a, b, &rect),
        lb::clip_segment_2d(a, b, &rect),
        sh::clip_segment_2d(a, b, &window),
        region_codes::clip_segment(&window, a, b),
    ]
    .into_iter()
    .flatten()
    {
        assert!(r.0.is_finite() && r.1.is_finite(), "{r:?}");
    }
    // Homogeneous, w at the largest double.
    let (p, q) = (
        DVec4::new(0.0, 0.0, 0.0, f64::MAX),
        DVec4::new(0.5, 0.0, 0.0, -f64::MAX),
    );
    assert_eq!(cs::clip_segment_homogeneous(p, q), None);
    assert_eq!(lb::clip_segment_homogeneous(p, q), None);
    assert_eq!(sh::clip_segment_homogeneous(p, q), None);
    assert!(sh::clip_polygon_homogeneous(&[p, q, DVec4::new(0., 0.5, 0., 1.)]).is_empty());
    // A window or box beyond the range is refused.
    assert_eq!(
        Rect::new(-f64::MAX, -f64::MAX, f64::MAX, f64::MAX),
        Err(WindowError::NonFinite)
    );
    // The split: unsplit, no NaN piece.
    let tri = [
        DVec3::new(-1e308, 0.0, 0.0),
        DVec3::new(1e308, 0.0, 0.0),
        DVec3::new(0.0, 1e308, 0.0),
    ];
    let plane = Plane::from_point_normal(DVec3::ZERO, DVec3::X);
    assert!(matches!(split_polygon(&tri, &plane, 1e-9), Split::Front));
    // A negative tolerance counts as 0: a square crossing the plane splits in two.
    let square = [
        DVec3::new(-1., -1., 0.),
        DVec3::new(1., -1., 0.),
        DVec3::new(1., 1., 0.),
        DVec3::new(-1., 1., 0.),
    ];
    match split_polygon(&square, &plane, -1.0) {
        Split::Spanning { front, back } => assert_eq!((front.len(), back.len()), (4, 4)),
        other => panic!("{other:?}"),
    }
}
