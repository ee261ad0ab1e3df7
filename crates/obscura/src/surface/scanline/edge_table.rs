//! The edge table (edges bucketed by the first row they cross) and the entries of the
//! active edge list, each stepping its crossing `x` by `1/m` per row as seed 003 does
//! (`x_min := x_min + 1/m`) and then settling the exact first pixel of its crossing
//! with the shared edge function.
//!
//! An edge is active on the rows whose sample line `y = j + 0.5` meets it, both end
//! rows included, within its polygon's sample box: a row through a vertex then sees
//! both edges that meet there, which costs nothing in exactness (a span is the
//! intersection of what every active edge allows) and means every row of a polygon's
//! sample box has its edges. Horizontal edges never cross a sample line and stay out
//! of the table: whether a row lying on one is covered is settled by the span check.
//!
//! The table is filled as the scan goes down ([`EdgeTable`]): the polygons are
//! bucketed by the first row of their sample box, and a polygon's edges are placed
//! when it is set up, on that row. An edge waiting for a later row takes `(polygon,
//! edge, last row)` (12 bytes). An edge's function and slope are set up when it enters
//! the active list, from its polygon's data. Memory therefore follows the active
//! faces, not the scene. Building the whole table first (every edge with its rows, in
//! the polygons' order, then sorted by row) wrote 12 MB for Sponza's 443k edges and
//! cost more than placing the edges as their polygons are set up.

use crate::raster::{EdgeFunction, round_down, round_up, sample_rect};
use crate::view::{PreparedView, ViewPolygon};

/// One entry of the active edge list: the seed's `(x_min, 1/m, y_max)`, the bound
/// that lets `x` alone settle the crossing pixel, and which of its face's edges it is
/// (32 bytes; its face is the [`super::faces::ScanFace`] holding it). Its edge function
/// is its face's, read only when the crossing is too near a pixel centre.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanEdge {
    /// Where it crosses the current row's sample line (stepped by `1/m` per row).
    pub x: f64,
    /// `dx/dy`, the seed's `1/m`.
    pub inverse_slope: f64,
    /// The [`tolerance`] of the edge: how far `x` may be from the exact crossing, plus
    /// how near a pixel centre the shared edge test may round the wrong way, over
    /// every row of the edge. Infinite when no bound is known.
    pub tolerance: f64,
    /// The last row it is active on.
    pub last_row: u32,
    /// Its index among its face's edge functions; the top bit tells a left edge.
    pub index_left: u32,
}

const LEFT: u32 = 1 << 31;

impl ScanEdge {
    /// A placeholder.
    pub const NONE: ScanEdge = ScanEdge {
        x: 0.0,
        inverse_slope: 0.0,
        tolerance: f64::INFINITY,
        last_row: 0,
        index_left: 0,
    };

    /// Packs an edge's index and side.
    #[inline]
    pub fn index_left(index: u32, left: bool) -> u32 {
        debug_assert!(index < LEFT);
        index | if left { LEFT } else { 0 }
    }

    /// Whether the face lies to the right of it (its crossing opens the face's span).
    #[inline(always)]
    pub fn left(&self) -> bool {
        self.index_left & LEFT != 0
    }

    /// Its index among its face's edge functions.
    #[inline(always)]
    pub fn index(&self) -> u32 {
        self.index_left & !LEFT
    }

    /// The crossing pixel (not clamped) when `x` settles it: the first pixel whose
    /// centre lies right of `x`, `floor(x - 0.5) + 1`, if every centre is farther
    /// from `x` than `tolerance`. The shared edge test is then known to switch exactly
    /// there: it is monotonic along the row and agrees with the exact sign at the two
    /// centres around the crossing. `None` sends the edge to [`exact_pixel`].
    ///
    /// `v = x - 0.5` is rounded to the nearest integer `r` by adding and subtracting
    /// `1.5 * 2^52` (exact for `|v| < 2^30`), and the low bits of the sum are `r`
    /// itself; `v - r` is then exact, so the distance to the nearest centre is
    /// compared without rounding. NaN and infinities fail the test.
    ///
    /// Precondition, not checked here (it is per edge, not per row): a finite
    /// `tolerance` only for an `x` within `2^29` of the origin, which [`tolerance`]
    /// ensures (it is infinite for an edge reaching farther).
    #[inline(always)]
    pub fn settled_pixel(x: f64, tolerance: f64) -> Option<i64> {
        const ROUND: f64 = 6_755_399_441_055_744.0;
        let v = x - 0.5;
        let sum = v + ROUND;
        let d = v - (sum - ROUND);
        let r = i64::from(sum.to_bits() as u32 as i32);
        (d.abs() > tolerance).then_some(r + i64::from(d > 0.0))
    }
}

/// The crossing pixel of a left (`left`) or right edge with shared edge function `e`
/// on the row with sample line `py`, within columns `lo..=hi`, found from the
/// incremental guess `x` by the edge test itself. Returns it and how many pixels the
/// guess was off.
#[inline(never)]
pub(crate) fn exact_pixel(
    e: &EdgeFunction,
    left: bool,
    x: f64,
    py: f64,
    lo: u32,
    hi: u32,
) -> (u32, u64) {
    let row = e.row_term(py);
    let (lo, hi) = (i64::from(lo), i64::from(hi));
    // The first pixel whose centre is at or right of x.
    let guess = ceil_within(x - 0.5, lo, hi);
    let inside = |i: i64| e.inside_row(i as f64 + 0.5, row);
    let found = if left {
        first_true(lo, hi, guess, inside)
    } else {
        first_true(lo, hi, guess, |i| !inside(i))
    };
    (found as u32, found.abs_diff(guess))
}

/// A bound, in pixels, on the error of an incrementally stepped crossing `x` of edge
/// `e` with inverse slope `s` over `rows` rows, plus the distance from the exact
/// crossing within which the shared edge test may round to the wrong side. With `u`
/// the unit roundoff: the first `x = ox + (py - oy) s` is within `u (|ox| + 4 |py - oy|
/// |s|)`; each of the `rows` steps adds at most `u (|x| + |s|)` (the rounding of the
/// sum and of `s`); the edge test `dx (py - oy) - dy (px - ox)` is off by at most
/// `2u (|dx| |py - oy| + |dy| |px - ox|)`, which is `2u (|s| |py - oy| + |px - ox|)`
/// in pixels. The sum is taken with `|py - oy| <= |dy| + 2`, `|x|, |px - ox| <= the
/// edge's extent + 2`, doubled twice for safety; infinite if not finite or not small,
/// and for an edge reaching `2^29` pixels from the origin or farther (so that a
/// stepped `x`, within the bound of the edge, stays where
/// [`ScanEdge::settled_pixel`] can round it).
pub(crate) fn tolerance(e: &EdgeFunction, s: f64, rows: u32) -> f64 {
    let u = f64::EPSILON; // twice the unit roundoff
    let x_extent = e.ox.abs().max((e.ox + e.dx).abs()) + e.dx.abs() + 2.0;
    let y_extent = e.dy.abs() + 2.0;
    let s = s.abs();
    let bound =
        4.0 * u * (x_extent + 8.0 * y_extent * s + (f64::from(rows) + 4.0) * (s + x_extent) + 4.0);
    if bound < 0.25 && x_extent < REACH {
        bound
    } else {
        f64::INFINITY
    }
}

/// `2^29`: edges reaching this far from the origin have no [`tolerance`].
const REACH: f64 = 536_870_912.0;

/// `ceil(v)` clamped to `lo..=hi` (`lo >= 0`; `lo` for NaN), without a call to the
/// C library's `ceil` on targets without a rounding instruction.
#[inline(always)]
fn ceil_within(v: f64, lo: i64, hi: i64) -> i64 {
    if !(v > lo as f64) {
        return lo;
    }
    if !(v < hi as f64) {
        return hi;
    }
    // v > lo >= 0: truncation is the floor.
    let t = v as i64;
    if (t as f64) < v { t + 1 } else { t }
}

/// The first `i` in `lo..hi` where the monotone predicate (false then true) holds,
/// or `hi`, searched from `guess`.
#[inline]
fn first_true(lo: i64, hi: i64, guess: i64, pred: impl Fn(i64) -> bool) -> i64 {
    let mut i = guess.clamp(lo, hi);
    if i < hi && !pred(i) {
        while i < hi && !pred(i) {
            i += 1;
        }
    } else {
        while i > lo && pred(i - 1) {
            i -= 1;
        }
    }
    i
}

/// An edge of the table: edge `pair` (from vertex `pair` to the next) of a polygon,
/// and the last row it is active on.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TableEdge {
    /// The polygon's index in the view.
    pub polygon: u32,
    /// The edge's index in the polygon.
    pub pair: u32,
    /// The last row it is active on (its first is its bucket's).
    pub last_row: u32,
}

/// The edge table, bucketed by row and filled as the scan goes down: the polygons
/// bucketed by the first row of their sample box (flat arrays, one entry a polygon),
/// and per row the edges that start on it below their polygon's first row. A polygon's
/// edges are placed when it is set up, on that first row: those starting there enter
/// the active edge list at once ([`EdgeTable::place`]), the others wait in their row's
/// bucket. The buckets hold exactly the edges of the seed's table, but it is never
/// built whole: a polygon's vertices are read once for its box and once more when it
/// is set up, and the table's memory follows the faces under the scanline.
#[derive(Debug, Default)]
pub(crate) struct EdgeTable {
    /// Per row (and one past the last): where its polygons start in `polygons`.
    starts: Vec<u32>,
    /// The polygons with a sample box, by first row (in view order within a row).
    polygons: Vec<u32>,
    /// Per row: the edges waiting for it.
    later: Vec<Vec<TableEdge>>,
    /// Emptied buckets, kept for their memory.
    spare: Vec<Vec<TableEdge>>,
    /// Edges placed so far.
    placed: usize,
}

/// The rows `first..=last` on which an edge from `ya` to `yb` (`ya < yb`) of a polygon
/// whose sample box has rows `y0..y1` is active, if any.
#[inline]
pub(crate) fn edge_rows(ya: f64, yb: f64, y0: u32, y1: u32) -> Option<(u32, u32)> {
    let first = round_up(ya - 0.5).max(f64::from(y0));
    let last = round_down(yb - 0.5).min(f64::from(y1) - 1.0);
    (first <= last).then_some((first as u32, last as u32))
}

/// The rows of a polygon's sample box (as [`sample_rect`] has them; `None` when the
/// box holds no sample).
#[inline]
fn box_rows(poly: &ViewPolygon<'_>, width: u32, height: u32) -> Option<(u32, u32)> {
    sample_rows(poly.vertices().map(|v| (v.x, v.y)), width, height)
}

/// The rows of the sample box of the points `(x, y)`, see [`box_rows`]. It must be the
/// box of the face's setup: a face is set up on the first row of this box, and its
/// edges are placed within the setup's rows (a test checks the two agree).
#[inline]
fn sample_rows(
    points: impl Iterator<Item = (f64, f64)>,
    width: u32,
    height: u32,
) -> Option<(u32, u32)> {
    let (mut minx, mut miny) = (f64::INFINITY, f64::INFINITY);
    let (mut maxx, mut maxy) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for (x, y) in points {
        minx = minx.min(x);
        maxx = maxx.max(x);
        miny = miny.min(y);
        maxy = maxy.max(y);
    }
    sample_rect(minx, miny, maxx, maxy, width, height).map(|r| (r.y0, r.y1))
}

impl EdgeTable {
    /// The table of a `width x height` image: the view's polygons whose sample box
    /// holds a sample, bucketed by its first row with a counting sort (one pass over
    /// the polygons, their vertices read in memory order).
    pub fn build(view: &PreparedView<'_>, width: u32, height: u32) -> Self {
        let mut first_rows: Vec<u32> = Vec::with_capacity(view.polygon_count());
        let mut starts = vec![0u32; height as usize + 1];
        for poly in view.polygons() {
            let row = box_rows(&poly, width, height).map_or(u32::MAX, |(y0, _)| y0);
            if row != u32::MAX {
                starts[row as usize + 1] += 1;
            }
            first_rows.push(row);
        }
        for r in 0..height as usize {
            starts[r + 1] += starts[r];
        }
        let mut next = starts.clone();
        let mut polygons = vec![0u32; starts[height as usize] as usize];
        for (k, &row) in first_rows.iter().enumerate() {
            if row != u32::MAX {
                let at = &mut next[row as usize];
                polygons[*at as usize] = k as u32;
                *at += 1;
            }
        }
        EdgeTable {
            starts,
            polygons,
            later: vec![Vec::new(); height as usize],
            spare: Vec::new(),
            placed: 0,
        }
    }

    /// Number of edges placed so far (after the scan: every edge of every face set up
    /// that meets a sample line in its box).
    pub fn len(&self) -> usize {
        self.placed
    }

    /// The polygons whose sample box starts on `row`.
    pub fn polygons(&self, row: u32) -> &[u32] {
        let r = row as usize;
        &self.polygons[self.starts[r] as usize..self.starts[r + 1] as usize]
    }

    /// Places the edges of polygon `polygon` (of the view), set up on the first row
    /// of its sample box, whose rows are `rows`: calls `now(pair, last_row)` for each
    /// edge active from that row on and puts the others in the buckets of their first
    /// rows. `ys`: the `y` of its vertices when it is a triangle (read again from the
    /// view otherwise).
    pub fn place(
        &mut self,
        view: &PreparedView<'_>,
        polygon: u32,
        ys: Option<[f64; 3]>,
        rows: (u32, u32),
        mut now: impl FnMut(u32, u32),
    ) {
        if let Some([a, b, c]) = ys {
            for (pair, (p, q)) in [(a, b), (b, c), (c, a)].into_iter().enumerate() {
                self.place_edge(polygon, pair as u32, p, q, rows, &mut now);
            }
            return;
        }
        let (starts, indices, _) = view.polygon_arrays();
        let vertices = view.vertices();
        let (a, b) = (
            starts[polygon as usize] as usize,
            starts[polygon as usize + 1] as usize,
        );
        let ring = &indices[a..b];
        let n = ring.len();
        for (pair, &i) in ring.iter().enumerate() {
            let j = ring[if pair + 1 == n { 0 } else { pair + 1 }];
            let (p, q) = (vertices[i as usize].y, vertices[j as usize].y);
            self.place_edge(polygon, pair as u32, p, q, rows, &mut now);
        }
    }

    /// Places edge `pair` of `polygon`, from a vertex at `py` to one at `qy` (see
    /// [`Self::place`]).
    #[inline(always)]
    fn place_edge(
        &mut self,
        polygon: u32,
        pair: u32,
        py: f64,
        qy: f64,
        rows: (u32, u32),
        now: &mut impl FnMut(u32, u32),
    ) {
        if py == qy {
            return;
        }
        let Some((first, last_row)) = edge_rows(py.min(qy), py.max(qy), rows.0, rows.1) else {
            return;
        };
        self.placed += 1;
        if first == rows.0 {
            now(pair, last_row);
        } else {
            let bucket = &mut self.later[first as usize];
            if bucket.capacity() == 0
                && let Some(v) = self.spare.pop()
            {
                *bucket = v;
            }
            bucket.push(TableEdge {
                polygon,
                pair,
                last_row,
            });
        }
    }

    /// Takes the edges waiting for `row` (give the bucket back with [`Self::give_back`]).
    pub fn take_later(&mut self, row: u32) -> Vec<TableEdge> {
        std::mem::take(&mut self.later[row as usize])
    }

    /// Returns a bucket taken with [`Self::take_later`], its memory kept for later rows'
    /// buckets.
    pub fn give_back(&mut self, mut bucket: Vec<TableEdge>) {
        if bucket.capacity() > 0 {
            bucket.clear();
            self.spare.push(bucket);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_within_matches_ceil() {
        for v in [
            0.0,
            0.25,
            1.0,
            1.5,
            2.999,
            3.0,
            7.0001,
            -0.5,
            12.0,
            40.0,
            f64::NAN,
        ] {
            let expected = if v.is_nan() {
                2
            } else {
                (v.ceil() as i64).clamp(2, 12)
            };
            assert_eq!(ceil_within(v, 2, 12), expected, "{v}");
        }
    }

    #[test]
    fn settled_pixel_is_the_first_centre_right_of_x_when_far_from_centres() {
        let t = 1e-6;
        // Within the reach of a finite tolerance (see `tolerance`), and the values
        // that must settle nothing.
        let mut xs = vec![
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            5e8 + 0.25,
            -5e8 - 0.75,
        ];
        for k in -40..400 {
            let c = f64::from(k) * 0.25;
            xs.extend([c, c + 1e-7, c - 1e-7, c + 2e-6, c - 2e-6, c + 0.1, c + 0.37]);
        }
        for x in xs {
            let v = x - 0.5;
            // Independent expectation: the library floor and the distance to the
            // nearest centre.
            let far = (v - v.round()).abs() > t;
            let expected = far.then(|| (v.floor() + 1.0) as i64);
            assert_eq!(ScanEdge::settled_pixel(x, t), expected, "{x}");
        }
        // An unknown bound settles nothing.
        assert_eq!(ScanEdge::settled_pixel(3.2, f64::INFINITY), None);
    }

    #[test]
    fn tolerance_is_infinite_for_edges_out_of_reach() {
        let edge = |ox: f64, dx: f64| EdgeFunction {
            ox,
            oy: 0.0,
            dx,
            dy: 10.0,
            sign: 1.0,
            include_zero: false,
        };
        // A small edge near the origin: a tiny, finite bound.
        let near = tolerance(&edge(100.0, 5.0), 0.5, 10);
        assert!(near > 0.0 && near < 1e-9, "{near}");
        // Edges starting, ending or lying beyond 2^29: no bound.
        for (ox, dx) in [(6e8, 1.0), (100.0, 6e8), (-6e8, 5.0), (1e20, 0.0)] {
            assert_eq!(tolerance(&edge(ox, dx), dx / 10.0, 10), f64::INFINITY);
        }
    }

    #[test]
    fn table_rows_are_the_rows_of_the_faces_setup() {
        use crate::raster::{FillRule, PolygonSetup, TriangleSetup};
        // Polygons of 3 to 8 vertices on ellipses of many sizes and places: sub-pixel,
        // on sample lines, crossing the image's borders, off the image.
        let mut rng = crate::rng::SplitMix64(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.next_f64();
        let (w, h) = (64, 48);
        let mut set_up = 0;
        for case in 0..4000 {
            let n = 3 + case % 6;
            let (cx, cy) = (next() * 90.0 - 13.0, next() * 70.0 - 11.0);
            let (rx, ry) = (next().powi(3) * 40.0, next().powi(3) * 30.0);
            let snap = case % 4 == 0;
            let turn = next() * 6.0;
            let points: Vec<(f64, f64, f64)> = (0..n)
                .map(|k| {
                    let a = turn + k as f64 * std::f64::consts::TAU / n as f64;
                    let (x, y) = (cx + rx * a.cos(), cy + ry * a.sin());
                    let (x, y) = if snap {
                        ((x * 2.0).round() / 2.0, (y * 2.0).round() / 2.0)
                    } else {
                        (x, y)
                    };
                    (x, y, 1.0)
                })
                .collect();
            let rows = sample_rows(points.iter().map(|p| (p.0, p.1)), w, h);
            let rect = if n == 3 {
                TriangleSetup::new([points[0], points[1], points[2]], FillRule::TopLeft, w, h)
                    .map(|t| t.rect)
            } else {
                let mut s = PolygonSetup::<16>::new();
                s.set(&points, FillRule::TopLeft, w, h).then(|| s.rect())
            };
            if let Some(r) = rect {
                set_up += 1;
                assert_eq!(rows, Some((r.y0, r.y1)), "case {case}: {points:?}");
            }
        }
        assert!(set_up > 1000, "{set_up}");
    }

    #[test]
    fn first_true_finds_the_switch_from_any_guess() {
        for switch in 0..=10 {
            for guess in -3..14 {
                assert_eq!(first_true(0, 10, guess, |i| i >= switch), switch.min(10));
            }
        }
    }
}
