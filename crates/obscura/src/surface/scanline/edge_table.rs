//! The edge table (edges bucketed by the first row they cross) and the entries of the
//! active edge list, each stepping its crossing `x` by `1/m` per row as seed 003 does
//! (`x_min := x_min + 1/m`) and then settling the exact first pixel of its crossing
//! with the shared edge function.
//!
//! An edge is active on the rows whose sample line `y = j + 0.5` meets it, both end
//! rows included: a row through a vertex then sees both edges that meet there, which
//! costs nothing in exactness (a span is the intersection of what every active edge
//! allows) and means every row of a polygon's sample box has its edges.

use crate::raster::EdgeFunction;
use crate::view::PreparedView;

use super::screen_faces::ScreenFaces;

/// One edge of the edge table and of the active edge list.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScanEdge {
    /// The canonical edge function (the shared coverage rule).
    pub edge: EdgeFunction,
    /// Index of its face in the screen faces.
    pub face: u32,
    /// Whether the face lies to the right of it (its crossing opens the face's span);
    /// otherwise the crossing closes it.
    pub left: bool,
    /// Bottom end (the top end is the edge function's origin).
    pub y_max: f64,
    /// Where it crosses the current row's sample line.
    pub x: f64,
    /// `dx/dy`, the seed's `1/m`.
    pub inverse_slope: f64,
    /// The last row it is active on.
    pub last_row: u32,
    /// The face's sample box columns: crossings are clamped to `x_lo..=x_hi`.
    pub x_lo: u32,
    /// One past the last column of the face's sample box.
    pub x_hi: u32,
    /// The crossing pixel of the current row: for a left edge the first pixel inside
    /// it, for a right edge the first pixel past it (`x_hi` when none).
    pub pixel: u32,
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

/// Edges bucketed by their first active row (flat arrays).
#[derive(Debug, Default)]
pub(crate) struct EdgeTable {
    starts: Vec<u32>,
    edges: Vec<ScanEdge>,
}

impl EdgeTable {
    /// The table of every non-horizontal edge of `faces`, for an image `height` rows
    /// high. Horizontal edges never cross a sample line: whether a row on one is
    /// covered is settled by the per-face span check.
    pub fn build(view: &PreparedView<'_>, faces: &ScreenFaces, height: u32) -> Self {
        let mut edges: Vec<ScanEdge> = Vec::with_capacity(faces.len() * 3);
        let mut first_rows: Vec<u32> = Vec::with_capacity(faces.len() * 3);
        let mut points: Vec<(f64, f64)> = Vec::new();
        for (f, face) in faces.faces.iter().enumerate() {
            points.clear();
            points.extend(
                view.polygon(face.polygon as usize)
                    .vertices()
                    .map(|v| (v.x, v.y)),
            );
            let rect = face.rect;
            let fns = faces.edges_of(f);
            let n = points.len();
            // The coverage made one edge function per pair of distinct consecutive
            // points, in order: pair them up to get the exact end ordinates.
            let mut k_fn = 0;
            for k in 0..n {
                let (p, q) = (points[k], points[(k + 1) % n]);
                if p == q {
                    continue;
                }
                let Some(&e) = fns.get(k_fn) else { break };
                k_fn += 1;
                if e.dy == 0.0 {
                    continue;
                }
                let (y_min, y_max) = (p.1.min(q.1), p.1.max(q.1));
                debug_assert_eq!(y_min, e.oy);
                let first = ((y_min - 0.5).ceil()).max(f64::from(rect.y0));
                let last = ((y_max - 0.5).floor()).min(f64::from(rect.y1) - 1.0);
                if !(first <= last) {
                    continue;
                }
                let inverse_slope = e.dx / e.dy;
                first_rows.push(first as u32);
                edges.push(ScanEdge {
                    edge: e,
                    face: f as u32,
                    left: e.sign < 0.0,
                    y_max,
                    x: e.ox + (first + 0.5 - e.oy) * inverse_slope,
                    inverse_slope,
                    last_row: last as u32,
                    x_lo: rect.x0,
                    x_hi: rect.x1,
                    pixel: rect.x0,
                });
            }
        }
        // Bucket by first row with a counting sort (stable: face order in a bucket).
        let mut starts = vec![0u32; height as usize + 1];
        for &row in &first_rows {
            starts[row as usize + 1] += 1;
        }
        for r in 0..height as usize {
            starts[r + 1] += starts[r];
        }
        let mut next = starts.clone();
        let mut order = vec![0u32; edges.len()];
        for (k, &row) in first_rows.iter().enumerate() {
            order[next[row as usize] as usize] = k as u32;
            next[row as usize] += 1;
        }
        EdgeTable {
            starts,
            edges: order.iter().map(|&k| edges[k as usize]).collect(),
        }
    }

    /// Number of edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }

    /// The edges that become active on `row`.
    pub fn bucket(&self, row: u32) -> &[ScanEdge] {
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
            face: 0,
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
