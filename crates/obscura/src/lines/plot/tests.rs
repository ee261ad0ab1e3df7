use glam::{DVec2, DVec3};

use super::*;
use crate::lines::{DrawnEdge, EdgeKind, Piece};
use crate::rng::SplitMix64;

fn p(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

/// A drawing of one edge per piece, each `(a, b, invisibility)`.
fn drawing(pieces: &[(DVec2, DVec2, u32)]) -> Drawing {
    let mut d = Drawing::new(200, 100);
    for (k, &(a, b, q)) in pieces.iter().enumerate() {
        d.edges.push(DrawnEdge {
            vertices: None,
            object: None,
            kind: EdgeKind::Crease,
            faces: [None, None],
            world: [DVec3::ZERO, DVec3::X],
        });
        d.pieces.push(Piece {
            edge: k as u32,
            t: [0.0, 1.0],
            points: [a, b],
            invisibility: q,
        });
    }
    d
}

fn run(pieces: &[(DVec2, DVec2, u32)]) -> (Plot, PlotStats) {
    plot(&drawing(pieces), &PlotOptions::default()).unwrap()
}

/// Distance from `q` to the segment `a`-`b`.
fn to_segment(q: DVec2, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((q - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + d * t)
}

fn near_lines(q: DVec2, lines: &[Polyline], tol: f64) -> bool {
    lines.iter().any(|l| {
        l.points
            .windows(2)
            .any(|w| to_segment(q, w[0], w[1]) <= tol)
    })
}

#[test]
fn pieces_meeting_end_to_end_become_one_polyline() {
    // A path of three pieces given out of order and in both directions.
    let (plot, stats) = run(&[
        (p(10.0, 10.0), p(10.0, 0.0), 0),
        (p(0.0, 0.0), p(5.0, 0.0), 0),
        (p(10.0, 0.0), p(5.0, 0.0), 0),
    ]);
    assert_eq!(plot.visible.len(), 1, "{plot:?}");
    let l = &plot.visible[0];
    // The straight joint at (5, 0) is left out.
    let mut pts = l.points.clone();
    if pts[0] != p(0.0, 0.0) {
        pts.reverse();
    }
    assert_eq!(pts, vec![p(0.0, 0.0), p(10.0, 0.0), p(10.0, 10.0)]);
    assert_eq!(stats.visible.length, 20.0);
    assert_eq!(stats.visible.polylines, 1);
    // A closed square: one closed polyline.
    let (plot, _) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(10.0, 10.0), p(10.0, 0.0), 0),
        (p(10.0, 10.0), p(0.0, 10.0), 0),
        (p(0.0, 0.0), p(0.0, 10.0), 0),
    ]);
    assert_eq!(plot.visible.len(), 1);
    let l = &plot.visible[0];
    assert_eq!(l.points.len(), 5);
    assert_eq!(l.start(), l.end());
    assert_eq!(l.length(), 40.0);
    // Ends within the tolerance join; farther ones do not.
    let (plot, _) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(10.005, 0.0), p(10.0, 10.0), 0),
        (p(10.0, 10.5), p(20.0, 10.5), 0),
    ]);
    assert_eq!(plot.visible.len(), 2);
}

#[test]
fn classes_are_joined_separately() {
    let (plot, stats) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(10.0, 0.0), p(20.0, 5.0), 1),
        (p(20.0, 5.0), p(30.0, 5.0), 3),
    ]);
    assert_eq!((plot.visible.len(), plot.hidden.len()), (1, 1));
    assert_eq!(plot.hidden[0].points.len(), 3);
    assert_eq!((stats.visible.pieces, stats.hidden.pieces), (1, 2));
}

#[test]
fn duplicates_reversed_and_overlapping_are_merged() {
    let (plot, stats) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(10.0, 0.0), p(0.0, 0.0), 0),
        (p(5.0, 0.0), p(15.0, 0.0), 0),
        // Off the line by less than the tolerance.
        (p(2.0, 0.004), p(4.0, -0.004), 0),
    ]);
    assert_eq!(plot.visible.len(), 1);
    assert!((plot.visible[0].length() - 15.0).abs() < 1e-9);
    assert!((stats.visible.duplicate_length - (10.0 + 10.0 + 10.0 + 2.0 - 15.0)).abs() < 1e-3);
    // Parallel lines farther apart than the tolerance are both kept, and so are
    // collinear pieces that only touch (they are joined instead).
    let (plot, stats) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(0.0, 0.05), p(10.0, 0.05), 0),
        (p(10.0, 0.0), p(20.0, 0.0), 0),
    ]);
    assert_eq!(stats.visible.duplicate_length, 0.0);
    assert!((stats.visible.length - 30.0).abs() < 1e-9);
    assert_eq!(plot.visible.len(), 2);
}

#[test]
fn hidden_pieces_under_visible_ones_are_dropped_there() {
    let (plot, stats) = run(&[
        (p(0.0, 5.0), p(20.0, 5.0), 1),
        (p(10.0, 5.0), p(5.0, 5.0), 0),
    ]);
    assert!((stats.hidden.under_visible_length - 5.0).abs() < 1e-9);
    assert_eq!(plot.hidden.len(), 2);
    assert!((stats.hidden.length - 15.0).abs() < 1e-9);
    assert!((stats.visible.length - 5.0).abs() < 1e-9);
    // Kept when asked.
    let o = PlotOptions {
        drop_hidden_under_visible: false,
        ..PlotOptions::default()
    };
    let (_, stats) = plot_with(
        &[
            (p(0.0, 5.0), p(20.0, 5.0), 1),
            (p(10.0, 5.0), p(5.0, 5.0), 0),
        ],
        &o,
    );
    assert_eq!(stats.hidden.length, 20.0);
}

fn plot_with(pieces: &[(DVec2, DVec2, u32)], o: &PlotOptions) -> (Plot, PlotStats) {
    plot(&drawing(pieces), o).unwrap()
}

#[test]
fn short_pieces_are_dropped_and_their_ends_merged() {
    let (plot, stats) = run(&[
        (p(0.0, 0.0), p(10.0, 0.0), 0),
        (p(10.0, 0.0), p(10.05, 0.02), 0),
        (p(10.05, 0.02), p(10.05, 10.0), 0),
        // Alone and short: gone.
        (p(50.0, 50.0), p(50.05, 50.0), 0),
    ]);
    assert_eq!(stats.visible.short_pieces, 2);
    assert_eq!(plot.visible.len(), 1, "{plot:?}");
    assert_eq!(plot.visible[0].points.len(), 3);
}

#[test]
fn non_finite_pieces_are_left_out_and_bad_options_refused() {
    let (plot, stats) = run(&[
        (p(0.0, 0.0), p(f64::NAN, 0.0), 0),
        (p(0.0, 0.0), p(1.0, 0.0), 0),
    ]);
    assert_eq!(stats.invalid_pieces, 1);
    assert_eq!(plot.visible.len(), 1);
    let d = drawing(&[]);
    for o in [
        PlotOptions::default().with_tolerance(0.0),
        PlotOptions::default().with_tolerance(f64::NAN),
        PlotOptions::default().with_min_length(-1.0),
    ] {
        assert!(super::plot(&d, &o).is_err());
    }
}

#[test]
fn ordering_finds_the_sweep_of_strokes_along_a_line() {
    // Twenty unit strokes at x = 10k .. 10k + 1, shuffled and some reversed: the best
    // tour from (0, 0) goes left to right, 19 gaps of 9.
    let mut rng = SplitMix64(7);
    let mut pieces: Vec<(DVec2, DVec2, u32)> = (0..20)
        .map(|k| {
            let (a, b) = (p(10.0 * k as f64, 0.0), p(10.0 * k as f64 + 1.0, 0.0));
            if k % 3 == 0 { (b, a, 0) } else { (a, b, 0) }
        })
        .collect();
    for i in (1..pieces.len()).rev() {
        pieces.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
    }
    let (plot, stats) = run(&pieces);
    assert!(
        (stats.visible.travel_after - 171.0).abs() < 1e-9,
        "{stats:?}"
    );
    assert!(stats.visible.travel_before > 171.0);
    assert!((travel(&plot.visible) - 171.0).abs() < 1e-9);
}

#[test]
fn greedy_order_takes_the_nearest_end_each_time() {
    // The grid's answer against a brute-force nearest end at every step.
    let mut rng = SplitMix64(99);
    let ends: Vec<[DVec2; 2]> = (0..500)
        .map(|_| {
            let a = p(rng.range(0.0, 1000.0), rng.range(0.0, 700.0));
            [a, a + p(rng.range(-20.0, 20.0), rng.range(-20.0, 20.0))]
        })
        .collect();
    let tour = nearest_neighbour(&ends);
    let mut taken = vec![false; ends.len()];
    let mut pos = DVec2::ZERO;
    for v in &tour {
        let best = (0..ends.len())
            .filter(|&k| !taken[k])
            .flat_map(|k| [(k, 0), (k, 1)])
            .min_by(|x, y| {
                ends[x.0][x.1]
                    .distance(pos)
                    .total_cmp(&ends[y.0][y.1].distance(pos))
            })
            .unwrap();
        assert_eq!((v.line as usize, v.reversed as usize), best);
        taken[best.0] = true;
        pos = ends[best.0][1 - best.1];
    }
}

/// Random pieces on a coarse lattice, so that many meet, overlap or repeat.
fn lattice_drawing(seed: u64, n: usize) -> Vec<(DVec2, DVec2, u32)> {
    let mut rng = SplitMix64(seed);
    let mut pick = |m: f64| (rng.next_u64() % m as u64) as f64;
    (0..n)
        .map(|_| {
            let a = p(pick(12.0) * 10.0, pick(8.0) * 10.0);
            let dir = [p(10.0, 0.0), p(0.0, 10.0), p(10.0, 10.0), p(20.0, 0.0)][pick(4.0) as usize];
            let q = if pick(3.0) == 0.0 {
                1 + pick(2.0) as u32
            } else {
                0
            };
            (a, a + dir, q)
        })
        .collect()
}

#[test]
fn polylines_cover_exactly_the_pieces_and_conserve_length() {
    for seed in 1..=12 {
        let pieces = lattice_drawing(seed, 150);
        let (plot, stats) = run(&pieces);
        let tol = 1e-6;
        // Every piece lies on a polyline of its class (a hidden one may lie on a
        // visible one instead).
        for &(a, b, q) in &pieces {
            for k in 0..=8 {
                let x = a.lerp(b, f64::from(k) / 8.0);
                let ok = near_lines(x, &plot.visible, tol)
                    || (q > 0 && near_lines(x, &plot.hidden, tol));
                assert!(ok, "seed {seed}: piece {a}-{b} ({q}) not drawn at {x}");
            }
        }
        // Every polyline lies on pieces of its class.
        for (lines, hidden) in [(&plot.visible, false), (&plot.hidden, true)] {
            for l in lines {
                for w in l.points.windows(2) {
                    for k in 0..=8 {
                        let x = w[0].lerp(w[1], f64::from(k) / 8.0);
                        assert!(
                            pieces
                                .iter()
                                .any(|&(a, b, q)| (q > 0) == hidden && to_segment(x, a, b) <= tol),
                            "seed {seed}: {x} on no piece"
                        );
                    }
                }
            }
        }
        // Length: the pieces' less what was removed as duplicates.
        for hidden in [false, true] {
            let layer = if hidden { stats.hidden } else { stats.visible };
            let input: f64 = pieces
                .iter()
                .filter(|x| (x.2 > 0) == hidden)
                .map(|x| x.0.distance(x.1))
                .sum();
            let kept = input - layer.duplicate_length - layer.under_visible_length;
            assert!(
                (layer.length - kept).abs() < 1e-6,
                "seed {seed}: {layer:?}, input {input}"
            );
            assert!(
                layer.travel_after <= layer.travel_before + 1e-9,
                "{layer:?}"
            );
        }
    }
}

#[test]
fn without_dedupe_or_order_pieces_stay_as_given() {
    let pieces = lattice_drawing(5, 60);
    let o = PlotOptions::default().with_dedupe(false).with_order(false);
    let (_, stats) = plot_with(&pieces, &o);
    let input: f64 = pieces.iter().map(|x| x.0.distance(x.1)).sum();
    assert!((stats.visible.length + stats.hidden.length - input).abs() < 1e-6);
    assert_eq!(stats.visible.travel_before, stats.visible.travel_after);
}

#[test]
fn straightening_keeps_curves_within_the_tolerance() {
    // A fine polygon approximating a circle: no point may be dropped (the chord error
    // of each step is larger than the tolerance), while collinear points are.
    let circle: Vec<DVec2> = (0..=100)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k) / 100.0;
            p(50.0 + 40.0 * a.cos(), 50.0 + 40.0 * a.sin())
        })
        .collect();
    assert_eq!(straighten(&circle, 0.001).len(), circle.len());
    let line: Vec<DVec2> = (0..=10)
        .map(|k| p(f64::from(k), 2.0 * f64::from(k)))
        .collect();
    assert_eq!(straighten(&line, 0.001), vec![line[0], line[10]]);
    // A line that goes back on itself keeps its turning points; repeated points go.
    let (a, b, c) = (p(0.0, 0.0), p(5.0, 0.0), p(9.0, 0.0));
    assert_eq!(straighten(&[a, b, a], 0.001), vec![a, b, a]);
    assert_eq!(straighten(&[a, c, b], 0.001), vec![a, c, b]);
    assert_eq!(straighten(&[a, b, b, c], 0.001), vec![a, c]);
    // Just within and just beyond the tolerance.
    let bent = [a, p(5.0, 0.0009), c];
    assert_eq!(straighten(&bent, 0.001).len(), 2);
    let bent = [a, p(5.0, 0.0011), c];
    assert_eq!(straighten(&bent, 0.001).len(), 3);
}
