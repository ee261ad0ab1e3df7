//! Polygon setup for fast rasterizers: the edges, pixel rectangle and depth plane of a
//! convex screen-space polygon, computed without allocating, and the covered pixels of
//! a row found from them.
//!
//! - Input: the polygon's vertices `(x, y, zq)` in pixels (either winding), a fill rule
//!   and the image size.
//! - Output: exactly the [`EdgeFunction`]s and [`PixelRect`] of
//!   [`PolygonCoverage::new`](super::PolygonCoverage::new) and the plane of
//!   [`DepthPlane::from_points`]; per row, the covered pixels as a span
//!   ([`PolygonSetup::row_span_within`]) or a bit mask ([`PolygonSetup::row_mask`]). Both equal
//!   the pixels for which [`PolygonCoverage::covers`](super::PolygonCoverage::covers) is
//!   true: they evaluate the same canonical edge expression, per pixel.
//! - Complexity: O(n) setup for n vertices; O(n) per row span (a closed-form guess and
//!   one or two exact tests per edge), O(n w) per row mask of width w.
//! - Limitations: [`PolygonSetup::row_mask`] handles rows of at most 64 pixels.
//!
//! Sources: the shared coverage rule of `raster::coverage` (see `docs/ARCHITECTURE.md`);
//! "triangle setup" as in Pineda, *A parallel algorithm for polygon rasterization*
//! (SIGGRAPH 1988): edge functions set up once per polygon, then evaluated per pixel.

use super::coverage::{edges_row_span, fan_area2, sample_rect};
use super::{DepthPlane, EdgeFunction, FillRule, PixelRect};

/// A convex polygon of at most `N` vertices set up for rasterization, in fixed-size
/// arrays: `PolygonSetup<3>` for triangles (the compiler then unrolls every loop),
/// `PolygonSetup<16>` for the rest (a clipped triangle has at most 9 vertices, a
/// clipped quad 10). Polygons with more vertices are refused by
/// [`PolygonSetup::set`]; [`PolygonCoverage`](super::PolygonCoverage) takes them.
///
/// ```
/// use obscura::raster::{FillRule, PolygonCoverage, PolygonSetup};
/// let tri = [(1.0, 1.0, 0.5), (9.0, 2.0, 0.5), (3.0, 7.0, 0.5)];
/// let mut setup = PolygonSetup::<3>::new();
/// assert!(setup.set(&tri, FillRule::TopLeft, 16, 16));
/// let cov = PolygonCoverage::new(&[(1.0, 1.0), (9.0, 2.0), (3.0, 7.0)], FillRule::TopLeft, 16, 16).unwrap();
/// assert_eq!(setup.rect(), cov.rect());
/// for j in 0..16 {
///     assert_eq!(setup.row_span_within(j, 0, 16), cov.row_span(j));
/// }
/// ```
#[derive(Clone, Copy, Debug)]
pub struct PolygonSetup<const N: usize> {
    points: [(f64, f64, f64); N],
    edges: [EdgeFunction; N],
    point_count: usize,
    edge_count: usize,
    rect: Option<PixelRect>,
}

impl<const N: usize> Default for PolygonSetup<N> {
    fn default() -> Self {
        PolygonSetup {
            points: [(0.0, 0.0, 0.0); N],
            edges: [EdgeFunction::UNSET; N],
            point_count: 0,
            edge_count: 0,
            rect: None,
        }
    }
}

impl<const N: usize> PolygonSetup<N> {
    /// An empty setup (covers nothing until [`PolygonSetup::set`] succeeds).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether polygons of `n` vertices fit.
    #[must_use]
    pub const fn fits(n: usize) -> bool {
        n <= N
    }

    /// Sets up the polygon with vertices `(x, y, zq)` for a `width x height` image.
    /// Returns `false`, and covers nothing, exactly when
    /// [`PolygonCoverage::new`](super::PolygonCoverage::new) would return `None` (fewer
    /// than three vertices, zero or non-finite area, or no sample in its box), and
    /// also when the polygon has more than `N` vertices (see [`PolygonSetup::fits`]).
    #[inline(always)]
    pub fn set(
        &mut self,
        points: &[(f64, f64, f64)],
        fill: FillRule,
        width: u32,
        height: u32,
    ) -> bool {
        self.rect = None;
        self.point_count = 0;
        self.edge_count = 0;
        let n = points.len();
        if n < 3 || n > N {
            return false;
        }
        // The box first: it rejects the many polygons that cover no sample (sub-pixel
        // or off-screen) before any edge is set up. The order of the checks does not
        // change which polygons are rejected.
        let (mut minx, mut miny, mut maxx, mut maxy) = (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        );
        for p in points {
            minx = minx.min(p.0);
            maxx = maxx.max(p.0);
            miny = miny.min(p.1);
            maxy = maxy.max(p.1);
        }
        let Some(rect) = sample_rect(minx, miny, maxx, maxy, width, height) else {
            return false;
        };
        let Some(area2) = fan_area2(n, |k| (points[k].0, points[k].1)) else {
            return false;
        };
        let area_sign = area2.signum();
        let mut count = 0;
        for k in 0..n {
            let (p, q) = (points[k], points[if k + 1 == n { 0 } else { k + 1 }]);
            if let Some(e) = EdgeFunction::new((p.0, p.1), (q.0, q.1), area_sign, fill) {
                self.edges[count] = e;
                count += 1;
            }
        }
        self.points[..n].copy_from_slice(points);
        self.point_count = n;
        self.edge_count = count;
        self.rect = Some(rect);
        true
    }

    /// The edges (those of [`PolygonCoverage::edges`](super::PolygonCoverage::edges)).
    #[must_use]
    pub fn edges(&self) -> &[EdgeFunction] {
        &self.edges[..self.edge_count]
    }

    /// The pixels whose samples lie in the polygon's box, clipped to the image; empty
    /// when the last [`PolygonSetup::set`] failed.
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        self.rect.unwrap_or(PixelRect {
            x0: 0,
            y0: 0,
            x1: 0,
            y1: 0,
        })
    }

    /// The depth-key plane, as [`DepthPlane::from_points`] gives it. After a successful
    /// [`PolygonSetup::set`] it always exists: every fan determinant it considers is one
    /// of the terms of the area sum, so a finite non-zero area means finite
    /// determinants, one of them non-zero.
    #[inline(always)]
    #[must_use]
    pub fn depth_plane(&self) -> Option<DepthPlane> {
        self.rect?;
        DepthPlane::from_points(&self.points[..self.point_count])
    }

    /// Whether pixel `(i, j)` is covered (the per-pixel rule, for tests and slow paths).
    #[must_use]
    pub fn covers(&self, i: u32, j: u32) -> bool {
        let r = self.rect();
        if i < r.x0 || i >= r.x1 || j < r.y0 || j >= r.y1 {
            return false;
        }
        let (px, py) = (f64::from(i) + 0.5, f64::from(j) + 0.5);
        self.edges().iter().all(|e| e.inside(px, py))
    }

    /// The covered pixels of row `j` within columns `[x0, x1)`, as a half-open span,
    /// or `None` (see [`edges_row_span`], which it calls).
    #[inline(always)]
    #[must_use]
    pub fn row_span_within(&self, j: u32, x0: u32, x1: u32) -> Option<(u32, u32)> {
        edges_row_span(self.edges(), self.rect?, j, x0, x1)
    }

    /// The covered pixels of row `j` among the `count <= 64` columns from `x0`, as bit
    /// `i` for column `x0 + i`: every pixel tested, no guess. Columns outside the
    /// polygon's rectangle are never set.
    #[inline]
    #[must_use]
    pub fn row_mask(&self, j: u32, x0: u32, count: u32) -> u64 {
        debug_assert!(count <= 64);
        let Some(r) = self.rect else {
            return 0;
        };
        if j < r.y0 || j >= r.y1 {
            return 0;
        }
        let lo = r.x0.max(x0);
        let hi = r.x1.min(x0.saturating_add(count.min(64)));
        if lo >= hi {
            return 0;
        }
        let py = f64::from(j) + 0.5;
        let mut mask = (u64::MAX >> (64 - (hi - lo))) << (lo - x0);
        for e in self.edges() {
            let row = e.row_term(py);
            let mut m = 0u64;
            for i in lo..hi {
                m |= u64::from(e.inside_row(f64::from(i) + 0.5, row)) << (i - x0);
            }
            mask &= m;
            if mask == 0 {
                break;
            }
        }
        mask
    }
}

/// A set-up triangle: what [`PolygonSetup<3>`] holds, computed without loops over
/// vertices or branches on the edge orientation (triangles are most polygons of most
/// scenes, and their setup is most of the work of drawing small ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleSetup {
    /// The three edges, as [`PolygonCoverage::edges`](super::PolygonCoverage::edges).
    pub edges: [EdgeFunction; 3],
    /// The pixels whose samples lie in its box, clipped to the image.
    pub rect: PixelRect,
    /// The depth-key plane, as [`DepthPlane::from_points`].
    pub plane: DepthPlane,
}

/// The edge `p -> q` as [`EdgeFunction::new`] makes it, for distinct finite points.
#[inline(always)]
fn triangle_edge(p: (f64, f64), q: (f64, f64), area_sign: f64, inclusive: bool) -> EdgeFunction {
    let less = p.1 < q.1 || (p.1 == q.1 && p.0 < q.0);
    let (o, e) = if less { (p, q) } else { (q, p) };
    let sign = if less { area_sign } else { -area_sign };
    let (dx, dy) = (e.0 - o.0, e.1 - o.1);
    let (ex, ey) = (dx * sign, dy * sign);
    let top_left = (ey == 0.0 && ex > 0.0) || ey < 0.0;
    EdgeFunction {
        ox: o.0,
        oy: o.1,
        dx,
        dy,
        sign,
        include_zero: inclusive || top_left,
    }
}

/// The sample rectangle of the triangle `p` in a `width x height` image and twice its
/// signed area (the area of [`PolygonCoverage::new`](super::PolygonCoverage::new) and
/// the determinant [`DepthPlane::from_points`] picks for a triangle, both by
/// `coverage::fan_area2`); `None` when no sample is in its box or the area is zero or not finite.
/// The triangle setups of the rasterizers share it.
#[inline(always)]
pub(crate) fn triangle_rect_and_area(
    p: [(f64, f64, f64); 3],
    width: u32,
    height: u32,
) -> Option<(PixelRect, f64)> {
    let [a, b, c] = p;
    let minx = a.0.min(b.0).min(c.0);
    let maxx = a.0.max(b.0).max(c.0);
    let miny = a.1.min(b.1).min(c.1);
    let maxy = a.1.max(b.1).max(c.1);
    let rect = sample_rect(minx, miny, maxx, maxy, width, height)?;
    let area2 = fan_area2(3, |k| (p[k].0, p[k].1))?;
    Some((rect, area2))
}

impl TriangleSetup {
    /// Sets up the triangle `(x, y, zq)` for a `width x height` image; `None` exactly
    /// when [`PolygonCoverage::new`](super::PolygonCoverage::new) gives `None`.
    ///
    /// The edges need no zero-length check: with a non-zero finite area the three
    /// points are distinct (equal points make both products of the area equal).
    #[inline(always)]
    #[must_use]
    pub fn new(p: [(f64, f64, f64); 3], fill: FillRule, width: u32, height: u32) -> Option<Self> {
        let (rect, area2) = triangle_rect_and_area(p, width, height)?;
        let [a, b, c] = p;
        let area_sign = area2.signum();
        let inclusive = fill == FillRule::Inclusive;
        let edges = [
            triangle_edge((a.0, a.1), (b.0, b.1), area_sign, inclusive),
            triangle_edge((b.0, b.1), (c.0, c.1), area_sign, inclusive),
            triangle_edge((c.0, c.1), (a.0, a.1), area_sign, inclusive),
        ];
        let plane = DepthPlane::through(a, b, c, area2);
        Some(TriangleSetup { edges, rect, plane })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::raster::PolygonCoverage;
    use crate::rng::SplitMix64;

    fn random_polygon(rng: &mut SplitMix64, scale: f64, n: usize) -> Vec<(f64, f64, f64)> {
        // A convex polygon: points on an ellipse at sorted random angles.
        let (cx, cy) = (rng.range(-10.0, 50.0), rng.range(-10.0, 40.0));
        let (rx, ry) = (rng.range(0.01, 1.0) * scale, rng.range(0.01, 1.0) * scale);
        let mut angles: Vec<f64> = (0..n)
            .map(|_| rng.range(0.0, std::f64::consts::TAU))
            .collect();
        angles.sort_by(f64::total_cmp);
        if rng.next_f64() < 0.5 {
            angles.reverse();
        }
        angles
            .iter()
            .map(|a| {
                // Some vertices on the pixel-centre grid, to exercise ties.
                let (x, y) = (cx + rx * a.cos(), cy + ry * a.sin());
                let snap = rng.next_f64() < 0.3;
                let f = |v: f64| if snap { v.floor() + 0.5 } else { v };
                (f(x), f(y), rng.range(0.1, 1.0))
            })
            .collect()
    }

    #[test]
    fn setup_equals_polygon_coverage_rows_and_masks_equal_covers() {
        let mut rng = SplitMix64(7);
        let mut setup = PolygonSetup::<16>::new();
        let mut tri = PolygonSetup::<3>::new();
        let (w, h) = (40u32, 30u32);
        let mut checked = 0;
        for round in 0..3000 {
            let scale = [0.3, 2.0, 8.0, 40.0, 1e4][round % 5];
            let n = 3 + (round / 5) % 6;
            let pts = random_polygon(&mut rng, scale, n);
            let fill = if round % 3 == 0 {
                FillRule::Inclusive
            } else {
                FillRule::TopLeft
            };
            let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.1)).collect();
            let cov = PolygonCoverage::new(&xy, fill, w, h);
            let ok = setup.set(&pts, fill, w, h);
            assert_eq!(ok, cov.is_some(), "{pts:?}");
            assert_eq!(tri.set(&pts, fill, w, h), ok && n == 3);
            if n == 3 {
                let fast = TriangleSetup::new([pts[0], pts[1], pts[2]], fill, w, h);
                assert_eq!(fast.is_some(), ok, "{pts:?}");
                if let Some(fast) = fast {
                    assert_eq!((tri.edges(), tri.rect()), (setup.edges(), setup.rect()));
                    assert_eq!(tri.depth_plane(), setup.depth_plane());
                    assert_eq!(&fast.edges[..], setup.edges());
                    assert_eq!(fast.rect, setup.rect());
                    assert_eq!(Some(fast.plane), setup.depth_plane());
                }
            }
            let Some(cov) = cov else {
                assert!(setup.rect().is_empty() && setup.row_span_within(0, 0, w).is_none());
                continue;
            };
            checked += 1;
            assert_eq!(setup.rect(), cov.rect());
            assert_eq!(setup.edges(), cov.edges());
            assert_eq!(setup.depth_plane(), DepthPlane::from_points(&pts));
            assert!(setup.depth_plane().is_some());
            for j in 0..h {
                assert_eq!(
                    setup.row_span_within(j, 0, w),
                    cov.row_span(j),
                    "{pts:?} row {j}"
                );
                // A window that cuts the row, as a tile would.
                let (a, b) = (7, 23);
                let expect = cov
                    .row_span(j)
                    .map(|(x0, x1)| (x0.max(a), x1.min(b)))
                    .filter(|(x0, x1)| x0 < x1);
                assert_eq!(setup.row_span_within(j, a, b), expect);
                let mut mask = 0u64;
                for i in 0..w {
                    mask |= u64::from(cov.covers(i, j)) << i;
                    assert_eq!(setup.covers(i, j), cov.covers(i, j));
                }
                assert_eq!(setup.row_mask(j, 0, w), mask, "{pts:?} row {j}");
                assert_eq!(setup.row_mask(j, 5, 16), (mask >> 5) & 0xffff);
            }
        }
        assert!(checked > 1500, "{checked}");
    }

    #[test]
    fn degenerate_polygons_cover_nothing() {
        let mut s = PolygonSetup::<4>::new();
        let line = [(0.0, 0.0, 1.0), (4.0, 4.0, 1.0), (8.0, 8.0, 1.0)];
        assert!(!s.set(&line, FillRule::TopLeft, 16, 16));
        assert!(s.depth_plane().is_none() && s.row_mask(2, 0, 16) == 0);
        let nan = [(0.0, 0.0, 1.0), (f64::NAN, 4.0, 1.0), (8.0, 0.0, 1.0)];
        assert!(!s.set(&nan, FillRule::TopLeft, 16, 16));
        let two = [(0.0, 0.0, 1.0), (4.0, 4.0, 1.0)];
        assert!(!s.set(&two, FillRule::TopLeft, 16, 16));
        for t in [
            line,
            nan,
            [(0.0, 0.0, 1.0), (0.0, 0.0, 1.0), (5.0, 1.0, 1.0)],
        ] {
            assert!(TriangleSetup::new(t, FillRule::TopLeft, 16, 16).is_none());
        }
        let huge = [(0.0, 0.0, 1.0), (1e300, 0.0, 1.0), (0.0, 1e300, 1.0)];
        assert!(TriangleSetup::new(huge, FillRule::TopLeft, 16, 16).is_none());
        assert!(!s.set(&huge, FillRule::TopLeft, 16, 16)); // area overflows
        let square = [
            (1.0, 1.0, 1.0),
            (5.0, 1.0, 1.0),
            (5.0, 5.0, 1.0),
            (1.0, 5.0, 1.0),
        ];
        assert!(s.set(&square, FillRule::TopLeft, 16, 16));
        let pentagon = [
            (1.0, 1.0, 1.0),
            (5.0, 1.0, 1.0),
            (6.0, 3.0, 1.0),
            (5.0, 5.0, 1.0),
            (1.0, 5.0, 1.0),
        ];
        assert!(!PolygonSetup::<4>::fits(5));
        assert!(!s.set(&pentagon, FillRule::TopLeft, 16, 16)); // too many vertices for N = 4
        assert!(s.rect().is_empty());
    }
}
