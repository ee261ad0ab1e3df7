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
//! The table holds only `(polygon, edge)` pairs (8 bytes an edge); an edge's function
//! and slope are set up when it enters the active list, from its polygon's data made
//! when the polygon's first edge enters. Memory therefore follows the active faces,
//! not the scene.

use crate::raster::{EdgeFunction, sample_rect};
use crate::view::PreparedView;

/// One entry of the active edge list.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanEdge {
    /// The canonical edge function (the shared coverage rule).
    pub edge: EdgeFunction,
    /// Where it crosses the current row's sample line.
    pub x: f64,
    /// `dx/dy`, the seed's `1/m`.
    pub inverse_slope: f64,
    /// Bottom end (the top end is the edge function's origin).
    pub y_max: f64,
    /// The slot of its face among the active faces.
    pub slot: u32,
    /// Its index among its face's edge functions.
    pub index: u32,
    /// The last row it is active on.
    pub last_row: u32,
    /// The face's sample box columns: crossings are clamped to `x_lo..=x_hi`.
    pub x_lo: u32,
    /// One past the last column of the face's sample box.
    pub x_hi: u32,
    /// The crossing pixel of the current row: for a left edge the first pixel inside
    /// it, for a right edge the first pixel past it (`x_hi` when none).
    pub pixel: u32,
    /// Whether the face lies to the right of it (its crossing opens the face's span);
    /// otherwise the crossing closes it.
    pub left: bool,
}

impl ScanEdge {
    /// Settles the crossing pixel of row `py` (sample line), starting from the
    /// incremental `x` and correcting it with the edge function. Returns how many
    /// pixels the incremental guess was off.
    #[inline]
    pub fn cross(&mut self, py: f64) -> u64 {
        let e = &self.edge;
        let row = e.row_term(py);
        let (lo, hi) = (i64::from(self.x_lo), i64::from(self.x_hi));
        // The first pixel whose centre is at or right of x.
        let guess = ceil_within(self.x - 0.5, lo, hi);
        let inside = |i: i64| e.inside_row(i as f64 + 0.5, row);
        let found = if self.left {
            first_true(lo, hi, guess, inside)
        } else {
            first_true(lo, hi, guess, |i| !inside(i))
        };
        self.pixel = found as u32;
        found.abs_diff(guess)
    }
}

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

/// Above this every `f64` is an integer.
const ALL_INTEGERS: f64 = 4_503_599_627_370_496.0;

/// `v.ceil()` by truncation (no C library call on targets without a rounding
/// instruction); NaN stays NaN.
#[inline(always)]
fn round_up(v: f64) -> f64 {
    if !(v.abs() < ALL_INTEGERS) {
        return v;
    }
    let t = v as i64 as f64;
    if t < v { t + 1.0 } else { t }
}

/// `v.floor()` by truncation; NaN stays NaN.
#[inline(always)]
fn round_down(v: f64) -> f64 {
    if !(v.abs() < ALL_INTEGERS) {
        return v;
    }
    let t = v as i64 as f64;
    if t > v { t - 1.0 } else { t }
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

/// An edge of the table: edge `pair` (from vertex `pair` to the next) of a polygon.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TableEdge {
    /// The polygon's index in the view.
    pub polygon: u32,
    /// The edge's index in the polygon.
    pub pair: u32,
}

/// Edges bucketed by their first active row (flat arrays).
#[derive(Debug, Default)]
pub(crate) struct EdgeTable {
    starts: Vec<u32>,
    edges: Vec<TableEdge>,
}

/// The rows `first..=last` on which an edge from `ya` to `yb` (`ya < yb`) of a polygon
/// whose sample box has rows `y0..y1` is active, if any.
#[inline]
pub(crate) fn edge_rows(ya: f64, yb: f64, y0: u32, y1: u32) -> Option<(u32, u32)> {
    let first = round_up(ya - 0.5).max(f64::from(y0));
    let last = round_down(yb - 0.5).min(f64::from(y1) - 1.0);
    (first <= last).then_some((first as u32, last as u32))
}

impl EdgeTable {
    /// The table of every non-horizontal edge of the view's polygons that meets a
    /// sample line of a `width x height` image within its polygon's sample box.
    pub fn build(view: &PreparedView<'_>, width: u32, height: u32) -> Self {
        let mut rows: Vec<u32> = Vec::with_capacity(view.polygon_count() * 3);
        let mut edges: Vec<TableEdge> = Vec::with_capacity(view.polygon_count() * 3);
        for (k, poly) in view.polygons().enumerate() {
            let (mut minx, mut miny) = (f64::INFINITY, f64::INFINITY);
            let (mut maxx, mut maxy) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            for v in poly.vertices() {
                minx = minx.min(v.x);
                maxx = maxx.max(v.x);
                miny = miny.min(v.y);
                maxy = maxy.max(v.y);
            }
            // The box the coverage rule will use; no box, no coverage.
            let Some(rect) = sample_rect(minx, miny, maxx, maxy, width, height) else {
                continue;
            };
            let n = poly.len();
            for pair in 0..n {
                let (p, q) = (poly.vertex(pair), poly.vertex((pair + 1) % n));
                if p.y == q.y {
                    continue;
                }
                if let Some((first, _)) = edge_rows(p.y.min(q.y), p.y.max(q.y), rect.y0, rect.y1) {
                    rows.push(first);
                    edges.push(TableEdge {
                        polygon: k as u32,
                        pair: pair as u32,
                    });
                }
            }
        }
        // Bucket by first row with a counting sort (stable: polygon order in a bucket).
        let mut starts = vec![0u32; height as usize + 1];
        for &row in &rows {
            starts[row as usize + 1] += 1;
        }
        for r in 0..height as usize {
            starts[r + 1] += starts[r];
        }
        let mut next = starts.clone();
        let mut sorted = vec![
            TableEdge {
                polygon: 0,
                pair: 0
            };
            edges.len()
        ];
        for (&row, &e) in rows.iter().zip(&edges) {
            sorted[next[row as usize] as usize] = e;
            next[row as usize] += 1;
        }
        EdgeTable {
            starts,
            edges: sorted,
        }
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// The edges that become active on `row`.
    pub fn bucket(&self, row: u32) -> &[TableEdge] {
        let r = row as usize;
        &self.edges[self.starts[r] as usize..self.starts[r + 1] as usize]
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
    fn rounding_by_truncation_matches_the_library() {
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.5,
            -2.5,
            1e-300,
            -1e-300,
            7.999_999_999,
            -7.999_999_999,
            1e15 + 0.5,
            -1e15 - 0.5,
            1e20,
            -1e20,
        ] {
            assert_eq!(round_up(v), v.ceil(), "{v}");
            assert_eq!(round_down(v), v.floor(), "{v}");
        }
        assert!(round_up(f64::NAN).is_nan() && round_down(f64::INFINITY).is_infinite());
    }

    #[test]
    fn first_true_finds_the_switch_from_any_guess() {
        for switch in 0..=10 {
            for guess in -3..14 {
                assert_eq!(first_true(0, 10, guess, |i| i >= switch), switch.min(10));
            }
        }
    }

    #[test]
    fn crossing_is_corrected_from_a_bad_guess() {
        use crate::raster::FillRule;
        // A left edge from (2.2, 0) to (6.2, 8): at row 3 (y = 3.5) it is at x = 3.95,
        // so the first pixel inside is 4 (centre 4.5 > 3.95 > 3.5).
        let e = EdgeFunction::new((2.2, 0.0), (6.2, 8.0), -1.0, FillRule::TopLeft).unwrap();
        let mut s = ScanEdge {
            edge: e,
            slot: 0,
            index: 0,
            left: e.sign < 0.0,
            y_max: 8.0,
            x: 0.0, // deliberately wrong
            inverse_slope: 0.5,
            last_row: 7,
            x_lo: 0,
            x_hi: 16,
            pixel: 0,
        };
        assert!(s.left);
        let off = s.cross(3.5);
        assert_eq!(s.pixel, 4);
        assert_eq!(off, 4);
        s.x = 3.95;
        assert_eq!(s.cross(3.5), 0);
    }
}
