//! 2D clipping windows: the axis-aligned rectangle of Cohen-Sutherland and Liang-Barsky,
//! and any convex polygon for the region-code clipper and 2D Sutherland-Hodgman.
//!
//! Source: seed 001 §6.1.1. Each of the `n` lines through the edges of a convex
//! `n`-gon divides the plane in two; the half-plane that contains the polygon is
//! "half-plane-0" (closed: the line itself belongs to it), the other "half-plane-1"
//! (open). A window is the intersection of its half-planes-0.
//!
//! # Line equations
//! The seed writes edge lines as `a_i x + b_i y + 1 = 0` (6.2), with
//! `[a_i b_i]^T = -[[x_A y_A], [x_B y_B]]^{-1} [1 1]^T` (its footnote 1). That form cannot
//! represent a line through the origin (it would need `1 = 0` there), so a window
//! whose edge passes through `(0, 0)` (for instance any window with a vertex at the
//! origin) would break it. We keep the general form `a x + b y + c = 0`
//! ([`EdgeLine`]), oriented so that `a x + b y + c >= 0` is half-plane-0, and
//! [`EdgeLine::seed_form`] gives the seed's `(a_i, b_i)` when it exists. For the
//! clipping arithmetic the same line is evaluated relative to its first vertex,
//! `(B - A) x (P - A)`, which is the same value without the cancellation of a large
//! `c` when the window is far from the origin.
//!
//! # Limitations
//! A [`ConvexWindow`] must be strictly convex: at least three finite vertices, no
//! three consecutive collinear, every vertex strictly on the inner side of every edge
//! it is not on (checked exactly with `robust::orient2d`, `O(n^2)` once at
//! construction). Either winding is accepted. Anything else is refused with a
//! [`WindowError`]: the seed's half-plane-0 is defined by "the side the other vertices
//! are on", which does not exist for a non-convex or degenerate polygon.
//!
//! Paper: Cyrus and Beck, "Generalized two- and three-dimensional clipping", Computers
//! & Graphics 3(1), 1978 (a convex window as the intersection of its edges' half-
//! planes).

use super::InRange;
use glam::DVec2;

/// Why a clipping window was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WindowError {
    /// A coordinate is NaN, infinite or beyond [`super::MAX_CLIP_COORDINATE`].
    #[error("a window coordinate is not finite or beyond 1e300")]
    NonFinite,
    /// A rectangle with `min >= max` on some axis (no interior).
    #[error("the rectangle has no interior (min must be below max on both axes)")]
    EmptyRectangle,
    /// Fewer than three vertices.
    #[error("a convex window needs at least 3 vertices, got {0}")]
    TooFewVertices(usize),
    /// Repeated vertices or three consecutive collinear vertices (edge `.0` has no
    /// well-defined half-plane, or duplicates its neighbour's line).
    #[error("the window is degenerate at edge {0} (repeated or collinear vertices)")]
    Degenerate(usize),
    /// Some vertex lies on the outer side of the line of edge `.0`.
    #[error("the window is not convex (a vertex lies outside the line of edge {0})")]
    NotConvex(usize),
}

impl From<WindowError> for crate::Error {
    fn from(e: WindowError) -> Self {
        crate::Error::option("clip window", e.to_string())
    }
}

/// An axis-aligned clipping rectangle `[xmin, xmax] x [ymin, ymax]` with a non-empty
/// interior and finite bounds (checked by [`Rect::new`], so clippers need not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    min: DVec2,
    max: DVec2,
}

impl Rect {
    /// The rectangle `[xmin, xmax] x [ymin, ymax]`.
    ///
    /// # Errors
    /// [`WindowError::NonFinite`] for NaN, infinite or out-of-range bounds,
    /// [`WindowError::EmptyRectangle`] unless `xmin < xmax` and `ymin < ymax`.
    pub fn new(xmin: f64, ymin: f64, xmax: f64, ymax: f64) -> Result<Self, WindowError> {
        if ![xmin, ymin, xmax, ymax].iter().all(|v| v.in_range()) {
            return Err(WindowError::NonFinite);
        }
        if !(xmin < xmax && ymin < ymax) {
            return Err(WindowError::EmptyRectangle);
        }
        Ok(Rect {
            min: DVec2::new(xmin, ymin),
            max: DVec2::new(xmax, ymax),
        })
    }

    /// The normalized-device-coordinate window `[-1, 1]^2`, what is left of the view
    /// volume after the divide by `w` (seed 000, "Περικοπή στο Οπτικό Πεδίο (3)").
    pub const NDC: Rect = Rect {
        min: DVec2::NEG_ONE,
        max: DVec2::ONE,
    };

    /// `(xmin, ymin)`.
    #[must_use]
    pub fn min(&self) -> DVec2 {
        self.min
    }

    /// `(xmax, ymax)`.
    #[must_use]
    pub fn max(&self) -> DVec2 {
        self.max
    }

    /// Whether `p` is in the closed rectangle.
    #[must_use]
    pub fn contains(&self, p: DVec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The corners in the order of seed 001's figure 6.3, `A = LU, B = RU, C = RL,
    /// D = LL` (left-upper, right-upper, right-lower, left-lower, with `y` up), so
    /// that edge `i` lies on line `i` of equation (6.4): `y = ymax`, `x = xmax`,
    /// `y = ymin`, `x = xmin`.
    #[must_use]
    pub fn corners(&self) -> [DVec2; 4] {
        [
            DVec2::new(self.min.x, self.max.y),
            self.max,
            DVec2::new(self.max.x, self.min.y),
            self.min,
        ]
    }
}

/// The line of one window edge in general form `a x + b y + c = 0`, oriented so that
/// half-plane-0 (the window's side, line included) is `a x + b y + c >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeLine {
    /// Coefficient of `x`.
    pub a: f64,
    /// Coefficient of `y`.
    pub b: f64,
    /// Constant term.
    pub c: f64,
}

impl EdgeLine {
    /// `a x + b y + c` at `p`: `>= 0` in half-plane-0.
    #[must_use]
    pub fn evaluate(&self, p: DVec2) -> f64 {
        self.a * p.x + self.b * p.y + self.c
    }

    /// The seed's form (6.2) `a_i x + b_i y + 1 = 0` of this line, `(a_i, b_i)`;
    /// `None` when the line passes through the origin, which that form cannot
    /// express. (Dividing by `c` may flip the orientation: the seed's form carries
    /// none, half-plane-0 being "the side of the other vertices".)
    #[must_use]
    pub fn seed_form(&self) -> Option<(f64, f64)> {
        if self.c == 0.0 {
            return None;
        }
        Some((self.a / self.c, self.b / self.c))
    }
}

/// A strictly convex clipping window given by its vertices in either winding.
///
/// Edge `i` goes from vertex `i` to vertex `i + 1` (cyclically) and its line is line
/// `i` of the region code (bit `i`).
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexWindow {
    vertices: Vec<DVec2>,
    /// Per edge: its direction, negated for clockwise windows so that
    /// `dir.perp_dot(p - start vertex) >= 0` is always half-plane-0.
    dirs: Vec<DVec2>,
    counter_clockwise: bool,
}

impl ConvexWindow {
    /// Builds the window and the half-plane-0 of each edge line (seed 001 step 1: the
    /// side "satisfied by all the other vertices").
    ///
    /// # Errors
    /// See [`WindowError`]: non-finite coordinates, fewer than 3 vertices, repeated or
    /// collinear consecutive vertices, or a non-convex polygon.
    ///
    /// ```
    /// use obscura::clip::ConvexWindow;
    /// use glam::DVec2;
    /// let tri = ConvexWindow::new(&[DVec2::ZERO, DVec2::new(2., 0.), DVec2::new(0., 2.)]).unwrap();
    /// assert!(tri.contains(DVec2::new(0.5, 0.5)));
    /// let bowtie = [DVec2::ZERO, DVec2::new(1., 1.), DVec2::new(1., 0.), DVec2::new(0., 1.)];
    /// assert!(ConvexWindow::new(&bowtie).is_err());
    /// ```
    pub fn new(vertices: &[DVec2]) -> Result<Self, WindowError> {
        let n = vertices.len();
        if vertices.iter().any(|v| !v.in_range()) {
            return Err(WindowError::NonFinite);
        }
        if n < 3 {
            return Err(WindowError::TooFewVertices(n));
        }
        let coord = |v: DVec2| robust::Coord { x: v.x, y: v.y };
        let orient = |a: DVec2, b: DVec2, c: DVec2| robust::orient2d(coord(a), coord(b), coord(c));
        // Exact predicates: a window must not be accepted or refused because of
        // rounding, and every later decision relies on its convexity.
        let sign = orient(vertices[0], vertices[1], vertices[2]);
        if sign == 0.0 {
            return Err(WindowError::Degenerate(0));
        }
        for i in 0..n {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            if a == b {
                return Err(WindowError::Degenerate(i));
            }
            for k in 2..n {
                let o = orient(a, b, vertices[(i + k) % n]);
                if o == 0.0 {
                    // Consecutive collinear vertices make a degenerate window; a
                    // farther vertex on the line means the polygon folds onto it.
                    return Err(if k == 2 || k == n - 1 {
                        WindowError::Degenerate(i)
                    } else {
                        WindowError::NotConvex(i)
                    });
                }
                if (o > 0.0) != (sign > 0.0) {
                    return Err(WindowError::NotConvex(i));
                }
            }
        }
        Ok(Self::from_checked(vertices, sign > 0.0))
    }

    /// The window of vertices already known to be strictly convex.
    fn from_checked(vertices: &[DVec2], counter_clockwise: bool) -> Self {
        let n = vertices.len();
        let s = if counter_clockwise { 1.0 } else { -1.0 };
        let dirs = (0..n)
            .map(|i| (vertices[(i + 1) % n] - vertices[i]) * s)
            .collect();
        ConvexWindow {
            vertices: vertices.to_vec(),
            dirs,
            counter_clockwise,
        }
    }

    /// The rectangle as a convex window with the seed's vertex order `A, B, C, D`
    /// ([`Rect::corners`]), so its 4-bit region codes are exactly the Cohen-Sutherland
    /// codes of equation (6.5).
    #[must_use]
    pub fn rectangle(rect: &Rect) -> Self {
        // LU, RU, RL, LL of a rectangle with an interior: strictly convex, clockwise.
        Self::from_checked(&rect.corners(), false)
    }

    /// The vertices as given.
    #[must_use]
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    /// The number of edges (= vertices = bits of a region code).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.vertices.len()
    }

    /// Whether the vertices are in counter-clockwise order (`y` up).
    #[must_use]
    pub fn is_counter_clockwise(&self) -> bool {
        self.counter_clockwise
    }

    /// The line of edge `i` in general form, oriented (half-plane-0 is `>= 0`).
    ///
    /// # Panics
    /// If `i >= edge_count()`.
    #[must_use]
    pub fn edge_line(&self, i: usize) -> EdgeLine {
        let (o, d) = (self.vertices[i], self.dirs[i]);
        // d.perp_dot(p - o) = -d.y x + d.x y + (d.y o.x - d.x o.y)
        EdgeLine {
            a: -d.y,
            b: d.x,
            c: d.y * o.x - d.x * o.y,
        }
    }

    /// The signed value of edge line `i` at `p`, `>= 0` in half-plane-0. It is the
    /// edge line's `a x + b y + c` computed relative to the edge's first vertex.
    #[inline]
    #[must_use]
    pub(crate) fn edge_value(&self, i: usize, p: DVec2) -> f64 {
        self.dirs[i].perp_dot(p - self.vertices[i])
    }

    /// Whether `p` is in the closed window (every edge value `>= 0`).
    #[must_use]
    pub fn contains(&self, p: DVec2) -> bool {
        (0..self.edge_count()).all(|i| self.edge_value(i, p) >= 0.0)
    }

    /// The window's area (positive for either winding).
    #[must_use]
    pub fn area(&self) -> f64 {
        polygon_area_2d(&self.vertices).abs()
    }
}

/// The signed area of a 2D polygon (shoelace): positive counter-clockwise.
#[must_use]
pub fn polygon_area_2d(points: &[DVec2]) -> f64 {
    let n = points.len();
    if n < 3 {
        return 0.0;
    }
    let o = points[0];
    let mut twice = 0.0;
    for i in 1..n - 1 {
        twice += (points[i] - o).perp_dot(points[i + 1] - o);
    }
    twice * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_refuses_bad_bounds() {
        assert_eq!(Rect::new(0., 0., 0., 1.), Err(WindowError::EmptyRectangle));
        assert_eq!(Rect::new(1., 0., 0., 1.), Err(WindowError::EmptyRectangle));
        assert_eq!(Rect::new(f64::NAN, 0., 1., 1.), Err(WindowError::NonFinite));
        assert_eq!(
            Rect::new(0., 0., f64::INFINITY, 1.),
            Err(WindowError::NonFinite)
        );
    }

    #[test]
    fn convex_window_refuses_degenerate_and_concave_polygons() {
        let v = |x: f64, y: f64| DVec2::new(x, y);
        assert_eq!(
            ConvexWindow::new(&[v(0., 0.), v(1., 0.)]),
            Err(WindowError::TooFewVertices(2))
        );
        assert_eq!(
            ConvexWindow::new(&[v(0., 0.), v(1., 0.), v(2., 0.)]),
            Err(WindowError::Degenerate(0))
        );
        assert!(matches!(
            ConvexWindow::new(&[v(0., 0.), v(1., 0.), v(1., 0.), v(0., 1.)]),
            Err(WindowError::Degenerate(_))
        ));
        // An arrow head: the vertex (1, 1) is a reflex vertex.
        assert!(matches!(
            ConvexWindow::new(&[v(0., 0.), v(2., 0.), v(1., 1.), v(2., 2.), v(0., 2.)]),
            Err(WindowError::NotConvex(_))
        ));
        // A pentagram turns the same way at every vertex but winds twice.
        let star: Vec<DVec2> = (0..5)
            .map(|k| {
                let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                v(a.cos(), a.sin())
            })
            .collect();
        assert!(matches!(
            ConvexWindow::new(&star),
            Err(WindowError::NotConvex(_))
        ));
        assert_eq!(
            ConvexWindow::new(&[v(0., 0.), v(f64::NAN, 0.), v(0., 1.)]),
            Err(WindowError::NonFinite)
        );
    }

    #[test]
    fn edge_lines_put_the_window_on_their_non_negative_side_in_both_windings() {
        let ccw = [
            DVec2::new(0., 0.),
            DVec2::new(3., 0.),
            DVec2::new(3., 2.),
            DVec2::new(0., 2.),
        ];
        let mut cw = ccw;
        cw.reverse();
        for verts in [ccw, cw] {
            let w = ConvexWindow::new(&verts).unwrap();
            let centre = DVec2::new(1.5, 1.0);
            for i in 0..4 {
                let line = w.edge_line(i);
                assert!(line.evaluate(centre) > 0.0);
                assert_eq!(line.evaluate(centre), w.edge_value(i, centre));
                // Both edge vertices are on the line.
                assert_eq!(line.evaluate(verts[i]), 0.0);
                assert_eq!(line.evaluate(verts[(i + 1) % 4]), 0.0);
            }
            assert_eq!(w.area(), 6.0);
        }
    }

    #[test]
    fn seed_form_matches_footnote_and_fails_through_the_origin() {
        // Line through A = (1, 3) and B = (4, 1). Footnote 1:
        // [a b]^T = -M^{-1} [1 1]^T with M = [[1, 3], [4, 1]], det = 1 - 12 = -11,
        // M^{-1} = (1/-11) [[1, -3], [-4, 1]], M^{-1}[1 1]^T = (1/-11) [-2, -3] =
        // [2/11, 3/11], so a = -2/11, b = -3/11. Check: -2/11 - 9/11 + 1 = 0.
        let w = ConvexWindow::new(&[DVec2::new(1., 3.), DVec2::new(4., 1.), DVec2::new(5., 5.)])
            .unwrap();
        let (a, b) = w.edge_line(0).seed_form().unwrap();
        assert!((a + 2.0 / 11.0).abs() < 1e-15 && (b + 3.0 / 11.0).abs() < 1e-15);
        // An edge from the origin: the seed's form does not exist.
        let w = ConvexWindow::new(&[DVec2::ZERO, DVec2::new(1., 0.), DVec2::new(0., 1.)]).unwrap();
        assert_eq!(w.edge_line(0).seed_form(), None);
    }
}
