//! Pixel coverage of convex polygons: edge functions evaluated at pixel centres with
//! the top-left fill rule, exact enough to be watertight.
//!
//! # The rule
//! Pixel `(i, j)` samples the point `(i + 0.5, j + 0.5)` (row 0 at the top, y down).
//! A polygon covers the pixel when the sample is strictly inside every edge, or on an
//! edge that is a *top* edge (exactly horizontal, interior below) or a *left* edge
//! (interior to its right). A sample on an edge shared by two polygons therefore
//! belongs to exactly one of them. [`FillRule::Inclusive`] counts every edge as
//! inside instead (the convention of seed 004's worked task).
//!
//! # Why it is watertight in floating point
//! The edge function of the edge `P-Q` is evaluated from a *canonical* endpoint: the
//! smaller of `P` and `Q` in `(y, x)` order, in the canonical direction. Two polygons
//! sharing the edge traverse it in opposite directions but compute the same value,
//! bit for bit, and merely negate it: so no sample can be inside both or neither.
//! Every arithmetic step is monotonic in `px`, so along a row the set of covered
//! pixels of one edge is an interval even with rounding: [`PolygonCoverage::row_span`]
//! finds it from a closed-form guess corrected by the per-pixel test, and the span
//! equals the pixels for which [`PolygonCoverage::covers`] is true.
//!
//! The evaluation is `dx * (py - oy) - dy * (px - ox)` in `f64`, in exactly that
//! order (no fused multiply-add): fast kernels must use the same expression.
//!
//! Source: Pineda, *A parallel algorithm for polygon rasterization* (SIGGRAPH 1988).

use std::cmp::Ordering;

use super::rounding::sample_range;

/// Which samples on an edge count as inside.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FillRule {
    /// Top-left rule: samples on top and left edges are inside, on others outside.
    #[default]
    TopLeft,
    /// Samples on any edge are inside (seed 004's task; shared edges are covered twice).
    Inclusive,
}

/// A rectangle of pixels `x0..x1` by `y0..y1` (half-open).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelRect {
    /// Whether it holds no pixel.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Number of pixels.
    #[must_use]
    pub fn area(&self) -> u64 {
        if self.is_empty() {
            0
        } else {
            u64::from(self.x1 - self.x0) * u64::from(self.y1 - self.y0)
        }
    }
}

/// The edge function of one polygon edge, evaluated canonically (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeFunction {
    /// Canonical origin x.
    pub ox: f64,
    /// Canonical origin y.
    pub oy: f64,
    /// Canonical direction x (other end minus origin).
    pub dx: f64,
    /// Canonical direction y.
    pub dy: f64,
    /// `+1` or `-1`: the polygon's interior is where `sign * raw > 0`.
    pub sign: f64,
    /// Whether samples exactly on the edge are inside (top-left edges, or every edge
    /// with the inclusive rule).
    pub include_zero: bool,
}

impl EdgeFunction {
    /// A placeholder for the unused slots of fixed-size edge arrays (polygon setups,
    /// the scanline's inline edges): no sample is inside it.
    pub const UNSET: EdgeFunction = EdgeFunction {
        ox: 0.0,
        oy: 0.0,
        dx: 0.0,
        dy: 0.0,
        sign: 0.0,
        include_zero: false,
    };

    /// The part of the raw value that depends on the row: `dx * (py - oy)`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn row_term(&self, py: f64) -> f64 {
        self.dx * (py - self.oy)
    }

    /// The raw (canonical, unsigned) value at `px` given the row term.
    #[inline(always)]
    #[must_use]
    pub fn raw(&self, px: f64, row_term: f64) -> f64 {
        row_term - self.dy * (px - self.ox)
    }

    /// Whether the sample `(px, py)` is inside this edge.
    #[inline(always)]
    #[must_use]
    pub fn inside(&self, px: f64, py: f64) -> bool {
        self.inside_row(px, self.row_term(py))
    }

    /// Whether `px` is inside, given the row term of the sample's row.
    #[inline(always)]
    #[must_use]
    pub fn inside_row(&self, px: f64, row_term: f64) -> bool {
        let e = self.sign * self.raw(px, row_term);
        e > 0.0 || (e == 0.0 && self.include_zero)
    }

    /// The edge `p -> q` of a polygon whose signed area has sign `area_sign`.
    /// `None` for a zero-length edge.
    #[inline]
    #[must_use]
    pub fn new(p: (f64, f64), q: (f64, f64), area_sign: f64, fill: FillRule) -> Option<Self> {
        let key = |a: (f64, f64)| (a.1, a.0);
        let (o, e, flip) = match key(p).partial_cmp(&key(q))? {
            Ordering::Less => (p, q, 1.0),
            Ordering::Greater => (q, p, -1.0),
            Ordering::Equal => return None,
        };
        let sign = flip * area_sign;
        // Direction of travel with the interior on the left (in the y-down frame,
        // "left" of travel is the side where the function is positive):
        let (ex, ey) = ((e.0 - o.0) * sign, (e.1 - o.1) * sign);
        let top_left = (ey == 0.0 && ex > 0.0) || ey < 0.0;
        Some(EdgeFunction {
            ox: o.0,
            oy: o.1,
            dx: e.0 - o.0,
            dy: e.1 - o.1,
            sign,
            include_zero: match fill {
                FillRule::TopLeft => top_left,
                FillRule::Inclusive => true,
            },
        })
    }
}

/// The pixels a convex screen-space polygon covers.
///
/// ```
/// use obscura::raster::{FillRule, PolygonCoverage};
/// // A 4x4 square from (1,1) to (5,5) covers exactly the 16 pixels 1..5 x 1..5.
/// let sq = [(1.0, 1.0), (5.0, 1.0), (5.0, 5.0), (1.0, 5.0)];
/// let c = PolygonCoverage::new(&sq, FillRule::TopLeft, 8, 8).unwrap();
/// let n: u32 = c.spans().map(|(_, x0, x1)| x1 - x0).sum();
/// assert_eq!(n, 16);
/// assert_eq!(c.row_span(1), Some((1, 5)));
/// ```
#[derive(Clone, Debug)]
pub struct PolygonCoverage {
    edges: Vec<EdgeFunction>,
    rect: PixelRect,
}

/// Twice the signed area of the polygon with `n >= 3` vertices `xy(0..n)`, summed over
/// the fan from vertex 0 (the one order every setup of the coverage rule uses); `None`
/// when it is zero or not finite.
#[inline(always)]
pub(crate) fn fan_area2(n: usize, xy: impl Fn(usize) -> (f64, f64)) -> Option<f64> {
    let (x0, y0) = xy(0);
    let mut area2 = 0.0;
    for k in 1..n - 1 {
        let ((px, py), (qx, qy)) = (xy(k), xy(k + 1));
        let (ax, ay) = (px - x0, py - y0);
        let (bx, by) = (qx - x0, qy - y0);
        area2 += ax * by - ay * bx;
    }
    (area2 != 0.0 && area2.is_finite()).then_some(area2)
}

impl PolygonCoverage {
    /// Sets up a convex polygon (either winding) clipped to a `width x height` image.
    /// `None` when it has zero or non-finite area, or its box holds no sample.
    #[must_use]
    pub fn new(points: &[(f64, f64)], fill: FillRule, width: u32, height: u32) -> Option<Self> {
        let n = points.len();
        if n < 3 {
            return None;
        }
        let area_sign = fan_area2(n, |k| points[k])?.signum();
        let mut edges = Vec::with_capacity(n);
        let (mut minx, mut miny, mut maxx, mut maxy) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for k in 0..n {
            let p = points[k];
            minx = minx.min(p.0);
            maxx = maxx.max(p.0);
            miny = miny.min(p.1);
            maxy = maxy.max(p.1);
            if let Some(e) = EdgeFunction::new(p, points[(k + 1) % n], area_sign, fill) {
                edges.push(e);
            }
        }
        let rect = sample_rect(minx, miny, maxx, maxy, width, height)?;
        Some(PolygonCoverage { edges, rect })
    }

    /// The edges.
    #[must_use]
    pub fn edges(&self) -> &[EdgeFunction] {
        &self.edges
    }

    /// The pixels whose samples lie in the polygon's bounding box (clipped to the image).
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        self.rect
    }

    /// Whether pixel `(i, j)` is covered.
    #[inline]
    #[must_use]
    pub fn covers(&self, i: u32, j: u32) -> bool {
        let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
        self.edges.iter().all(|e| e.inside(px, py))
    }

    /// The covered pixels of row `j` as `[x0, x1)`, or `None` if none.
    #[must_use]
    pub fn row_span(&self, j: u32) -> Option<(u32, u32)> {
        edges_row_span(&self.edges, self.rect, j, self.rect.x0, self.rect.x1)
    }

    /// Every non-empty row span as `(row, x0, x1)`, top to bottom.
    pub fn spans(&self) -> impl Iterator<Item = (u32, u32, u32)> + '_ {
        (self.rect.y0..self.rect.y1).filter_map(|j| self.row_span(j).map(|(a, b)| (j, a, b)))
    }
}

/// The pixels of row `j` within columns `[x0, x1)` covered by the convex polygon with
/// these edges and sample rectangle `r`, as a half-open span, or `None`: the one
/// implementation behind [`PolygonCoverage::row_span`] (a whole row),
/// [`PolygonSetup::row_span_within`](super::PolygonSetup::row_span_within) (a row cut to
/// columns) and the scanline's edges, which are not held in either. Each edge's
/// test is monotonic along the row (every step of the canonical expression is monotonic
/// in `px`), so its inside pixels form an interval: a closed-form guess of its end,
/// corrected by the exact test, finds it.
#[inline(always)]
#[must_use]
pub fn edges_row_span(
    edges: &[EdgeFunction],
    r: PixelRect,
    j: u32,
    x0: u32,
    x1: u32,
) -> Option<(u32, u32)> {
    if j < r.y0 || j >= r.y1 {
        return None;
    }
    let py = f64::from(j) + 0.5;
    let (mut lo, mut hi) = (i64::from(r.x0.max(x0)), i64::from(r.x1.min(x1)));
    if lo >= hi {
        return None;
    }
    for e in edges {
        let row = e.row_term(py);
        let slope = -e.sign * e.dy;
        let inside = |i: i64| e.inside_row(i as f64 + 0.5, row);
        if slope == 0.0 {
            if !inside(lo) {
                return None;
            }
            continue;
        }
        // Where the edge crosses the row; only a guess, the loops below make it exact.
        let cross = e.ox + row / e.dy;
        let guess = if cross.is_finite() {
            (cross - 0.5).ceil()
        } else {
            lo as f64
        };
        let g = guess.clamp(lo as f64 - 1.0, hi as f64 + 1.0) as i64;
        if slope > 0.0 {
            let mut i = g.clamp(lo, hi);
            if i < hi && inside(i) {
                while i > lo && inside(i - 1) {
                    i -= 1;
                }
            } else {
                while i < hi && !inside(i) {
                    i += 1;
                }
            }
            lo = i;
        } else {
            let mut i = g.clamp(lo - 1, hi - 1);
            if i >= lo && inside(i) {
                while i + 1 < hi && inside(i + 1) {
                    i += 1;
                }
            } else {
                while i >= lo && !inside(i) {
                    i -= 1;
                }
            }
            hi = i + 1;
        }
        if lo >= hi {
            return None;
        }
    }
    Some((lo as u32, hi as u32))
}

/// The pixels whose centres lie in `[minx, maxx] x [miny, maxy]`, clipped to the image
/// (`None` when none does, or a bound is not finite).
#[inline(always)]
#[must_use]
pub fn sample_rect(
    minx: f64,
    miny: f64,
    maxx: f64,
    maxy: f64,
    width: u32,
    height: u32,
) -> Option<PixelRect> {
    if !(minx.is_finite() && miny.is_finite() && maxx.is_finite() && maxy.is_finite()) {
        return None;
    }
    let (x0, x1) = sample_range(minx, maxx, width);
    let (y0, y1) = sample_range(miny, maxy, height);
    let r = PixelRect { x0, y0, x1, y1 };
    (!r.is_empty()).then_some(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(c: &PolygonCoverage) -> u64 {
        c.spans().map(|(_, a, b)| u64::from(b - a)).sum()
    }

    fn brute(c: &PolygonCoverage, w: u32, h: u32) -> u64 {
        let mut n = 0;
        for j in 0..h {
            for i in 0..w {
                n += u64::from(c.covers(i, j));
            }
        }
        n
    }

    #[test]
    fn top_left_rule_on_a_pixel_aligned_square() {
        // Edges through pixel centres: left and top included, right and bottom not.
        let sq = [(1.5, 1.5), (4.5, 1.5), (4.5, 4.5), (1.5, 4.5)];
        let c = PolygonCoverage::new(&sq, FillRule::TopLeft, 8, 8).unwrap();
        assert_eq!(count(&c), 9);
        assert!(c.covers(1, 1) && !c.covers(4, 1) && !c.covers(1, 4));
        let c = PolygonCoverage::new(&sq, FillRule::Inclusive, 8, 8).unwrap();
        assert_eq!(count(&c), 16);
        // Reversed winding gives the same pixels.
        let mut rev = sq;
        rev.reverse();
        let c = PolygonCoverage::new(&rev, FillRule::TopLeft, 8, 8).unwrap();
        assert_eq!(count(&c), 9);
    }

    #[test]
    fn shared_edges_cover_each_pixel_exactly_once() {
        // A fan of triangles around a centre on a pixel centre, ring vertices on the
        // 1/8-pixel lattice (on pixel centres and off them), so an exact integer test
        // (coordinates times 8) decides, independently of the code under test, which
        // samples lie strictly inside or strictly outside the ring.
        let c = (7.5, 7.5);
        let ring: Vec<(f64, f64)> = (0..13)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 13.0;
                let snap = |v: f64| (v * 8.0).round() / 8.0;
                (snap(7.5 + 6.3 * a.cos()), snap(7.5 + 6.3 * a.sin()))
            })
            .collect();
        let lattice: Vec<(i64, i64)> = ring
            .iter()
            .map(|&(x, y)| ((x * 8.0) as i64, (y * 8.0) as i64))
            .collect();
        // Twice the signed area of (p, q, s), exactly.
        let cross = |p: (i64, i64), q: (i64, i64), s: (i64, i64)| {
            (q.0 - p.0) * (s.1 - p.1) - (q.1 - p.1) * (s.0 - p.0)
        };
        let n = lattice.len();
        let edges = || (0..n).map(|k| (lattice[k], lattice[(k + 1) % n]));
        // The input is what the test needs: a strictly convex ring, one orientation.
        let turn = (0..n)
            .map(|k| cross(lattice[k], lattice[(k + 1) % n], lattice[(k + 2) % n]).signum())
            .collect::<Vec<_>>();
        assert!(turn.iter().all(|&t| t == turn[0] && t != 0), "{turn:?}");
        let mut hits = vec![0u8; 16 * 16];
        for k in 0..ring.len() {
            let tri = [c, ring[k], ring[(k + 1) % ring.len()]];
            if let Some(cov) = PolygonCoverage::new(&tri, FillRule::TopLeft, 16, 16) {
                for (j, a, b) in cov.spans() {
                    for i in a..b {
                        hits[(j * 16 + i) as usize] += 1;
                    }
                }
            }
        }
        let (mut inside, mut outside) = (0, 0);
        for j in 0..16i64 {
            for i in 0..16i64 {
                let s = (8 * i + 4, 8 * j + 4);
                let h = hits[(j * 16 + i) as usize];
                let sides: Vec<i64> = edges().map(|(p, q)| cross(p, q, s) * turn[0]).collect();
                if sides.iter().all(|&e| e > 0) {
                    // Strictly inside the ring: in exactly one triangle of the fan
                    // (on a spoke or the centre, the rule gives it to one).
                    assert_eq!(h, 1, "pixel {i},{j} inside the ring");
                    inside += 1;
                } else if sides.iter().any(|&e| e < 0) {
                    assert_eq!(h, 0, "pixel {i},{j} outside the ring");
                    outside += 1;
                } else {
                    // On the ring's boundary: the rule decides, but never twice.
                    assert!(h <= 1, "pixel {i},{j} on the ring");
                }
            }
        }
        // About the disc's area, pi * 6.3^2 = 125 pixels, and the rest outside.
        assert!(
            (110..140).contains(&inside) && outside > 100,
            "{inside} {outside}"
        );
    }

    #[test]
    fn spans_match_the_per_pixel_test() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let tri = [
                (rnd() * 40.0 - 4.0, rnd() * 30.0 - 4.0),
                (rnd() * 40.0 - 4.0, rnd() * 30.0 - 4.0),
                (rnd() * 40.0 - 4.0, rnd() * 30.0 - 4.0),
            ];
            if let Some(c) = PolygonCoverage::new(&tri, FillRule::TopLeft, 32, 24) {
                assert_eq!(count(&c), brute(&c, 32, 24), "{tri:?}");
            }
        }
    }

    #[test]
    fn degenerate_and_offscreen() {
        assert!(
            PolygonCoverage::new(&[(0., 0.), (1., 1.), (2., 2.)], FillRule::TopLeft, 8, 8)
                .is_none()
        );
        assert!(
            PolygonCoverage::new(
                &[(-5., -5.), (-1., -5.), (-1., -1.)],
                FillRule::TopLeft,
                8,
                8
            )
            .is_none()
        );
        assert!(
            PolygonCoverage::new(
                &[(0., 0.), (f64::NAN, 1.), (2., 0.)],
                FillRule::TopLeft,
                8,
                8
            )
            .is_none()
        );
    }
}
