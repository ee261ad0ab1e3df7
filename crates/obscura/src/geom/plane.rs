//! Planes `n·p + d = 0`, from Newell's method or from three points by Cramer's rule.
//!
//! Source: seed 004 ("Визначення рівняння площини ... методом Н'юела"), which writes
//! the plane of the z-buffer task's triangle as `3x + y + 4z - 120 = 0` by solving
//! `(a/d, b/d, c/d) · M = (-1, -1, -1)` with Cramer's rule.
//!
//! Paper: Newell's method as given in Sutherland, Sproull and Schumacher, "A
//! characterization of ten hidden-surface algorithms", ACM Computing Surveys 6(1),
//! 1974.

use glam::DVec3;

/// A plane `normal · p + d = 0`. The normal is not necessarily of unit length; the
/// positive side (`normal · p + d > 0`) is the side the normal points to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// The normal `(a, b, c)`.
    pub normal: DVec3,
    /// The constant `d`.
    pub d: f64,
}

/// Where a point or polygon lies relative to a plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneSide {
    /// Strictly on the side the normal points to.
    Front,
    /// Strictly on the other side.
    Back,
    /// On the plane (within the tolerance used).
    On,
    /// Polygons only: vertices on both sides.
    Spanning,
}

impl PlaneSide {
    /// The side of a point at signed distance `d` ([`Plane::signed_distance`]), with
    /// `|d| <= eps` counted as on the plane (a NaN distance too). This and
    /// [`Plane::classify_points`] are the one rule of which side a point and a polygon
    /// lie on: clipping by a plane, the BSP tree and depth sort all decide with them.
    #[inline]
    #[must_use]
    pub fn of_distance(d: f64, eps: f64) -> PlaneSide {
        if d > eps {
            PlaneSide::Front
        } else if d < -eps {
            PlaneSide::Back
        } else {
            PlaneSide::On
        }
    }

    /// The side of a set of points from their signed distances: `Spanning` if some are
    /// strictly in front and some strictly behind (beyond `eps`), `On` if none is
    /// beyond `eps`.
    #[must_use]
    pub fn of_distances(distances: impl IntoIterator<Item = f64>, eps: f64) -> PlaneSide {
        let (mut front, mut back) = (false, false);
        for d in distances {
            // `of_distance` without branches: front beyond `eps`, else back beyond `-eps`.
            let f = d > eps;
            front |= f;
            back |= !f && d < -eps;
        }
        match (front, back) {
            (true, true) => PlaneSide::Spanning,
            (true, false) => PlaneSide::Front,
            (false, true) => PlaneSide::Back,
            (false, false) => PlaneSide::On,
        }
    }
}

impl Plane {
    /// The plane with this normal through this point.
    #[must_use]
    pub fn from_point_normal(point: DVec3, normal: DVec3) -> Self {
        Plane {
            normal,
            d: -normal.dot(point),
        }
    }

    /// The plane of a polygon by Newell's method: the normal is the sum over edges of
    /// `(y_i - y_j)(z_i + z_j), (z_i - z_j)(x_i + x_j), (x_i - x_j)(y_i + y_j)`
    /// (twice the projected areas), and `d` uses the centroid, so the result is the
    /// best fit for non-planar or nearly degenerate n-gons. The normal is unit length
    /// and points to the side from which the vertices are seen counter-clockwise.
    ///
    /// Returns `None` for fewer than three points or a polygon of (numerically) zero
    /// area: twice its area (`|n|`) at most `1e-24 s^2`, `s` the largest absolute
    /// coordinate. A polygon so small that this floor is below the rounding of its own
    /// vertices (smaller than about `1e-10 s`, as every eye-space face of an
    /// orthographic window `1e-12` high is) is judged against that rounding instead: it
    /// keeps its plane while `|n|` exceeds `8 n_v eps s e` (`n_v` vertices, `e` their
    /// largest coordinate difference from the first): to first order, the most that
    /// rounding coordinates of magnitude `s` (by up to `eps s / 2` each) changes the
    /// sum, whose `n_v` terms each move by at most `4 eps s e` per component.
    ///
    /// ```
    /// use obscura::geom::Plane;
    /// use glam::DVec3;
    /// let quad = [DVec3::new(0., 0., 1.), DVec3::new(1., 0., 1.), DVec3::new(1., 1., 1.), DVec3::new(0., 1., 1.)];
    /// let p = Plane::newell(&quad).unwrap();
    /// assert_eq!(p.normal, DVec3::Z);
    /// assert_eq!(p.d, -1.0);
    /// ```
    #[must_use]
    pub fn newell(points: &[DVec3]) -> Option<Self> {
        if points.len() < 3 {
            return None;
        }
        let n = super::newell_normal(points);
        // Scaled before squaring: |n| of a polygon 1e-100 across (1e-200) squares to
        // zero, and of one 1e100 across to infinity.
        // Rescaled only then, so ordinary polygons keep their planes to the bit.
        let len = n.length();
        let big = n.abs().max_element();
        let len = if (1e-150..=1e150).contains(&len) || !(big > 0.0 && big.is_finite()) {
            len
        } else {
            big * (n / big).length()
        };
        let scale = points
            .iter()
            .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        // Twice the area is |n|: refuse areas below 1e-24 of the coordinate scale
        // squared, unless the polygon is so small beside its coordinates that what
        // rounding can make of it is below that (computed only then: rare).
        let above_rounding = || {
            let extent = points
                .iter()
                .fold(0.0f64, |m, &p| m.max((p - points[0]).abs().max_element()));
            len > 8.0 * points.len() as f64 * f64::EPSILON * scale * extent
        };
        if !len.is_finite() || !(len > 1e-24 * scale * scale || above_rounding()) {
            return None;
        }
        let normal = n / len;
        let centroid = points.iter().copied().sum::<DVec3>() / points.len() as f64;
        Some(Plane::from_point_normal(centroid, normal))
    }

    /// The plane through three points written as `a_n x + b_n y + c_n z = -1` and solved
    /// by Cramer's rule, as seed 004 does; the result is scaled back to `n·p + d = 0`
    /// with `d = 1` divided out, i.e. `normal = (a_n, b_n, c_n)`, `d = 1`.
    ///
    /// This form cannot represent a plane through the origin (the system is singular);
    /// it then returns `None`. Use [`Plane::from_three_points`] in general.
    ///
    /// ```
    /// use obscura::geom::Plane;
    /// use glam::DVec3;
    /// // seed 004: T1(15,15,15) T2(25,25,5) T3(30,10,5) lie on 3x + y + 4z - 120 = 0
    /// let p = Plane::from_three_points_cramer(
    ///     DVec3::new(15., 15., 15.), DVec3::new(25., 25., 5.), DVec3::new(30., 10., 5.)).unwrap();
    /// let k = -120.0; // scale so that d = -120
    /// assert!((p.normal * k - DVec3::new(-3., -1., -4.) * -1.0).length() < 1e-9);
    /// ```
    #[must_use]
    pub fn from_three_points_cramer(p1: DVec3, p2: DVec3, p3: DVec3) -> Option<Self> {
        // Rows of M are the points; solve M · (a_n, b_n, c_n)^T = (-1, -1, -1)^T.
        let det = |a: DVec3, b: DVec3, c: DVec3| a.dot(b.cross(c));
        let m = det(p1, p2, p3);
        let scale = p1
            .abs()
            .max_element()
            .max(p2.abs().max_element())
            .max(p3.abs().max_element());
        if !(m.abs() > 1e-12 * scale * scale * scale) {
            return None;
        }
        // Column j of M replaced by the right-hand side (-1, -1, -1).
        let col = |v: DVec3, j: usize, r: f64| {
            let mut a = v.to_array();
            a[j] = r;
            DVec3::from_array(a)
        };
        let mj = |j: usize| det(col(p1, j, -1.0), col(p2, j, -1.0), col(p3, j, -1.0));
        let normal = DVec3::new(mj(0), mj(1), mj(2)) / m;
        Some(Plane { normal, d: 1.0 })
    }

    /// The plane through three points, by the cross product; counter-clockwise seen
    /// from the positive side. `None` when the points are collinear.
    #[must_use]
    pub fn from_three_points(p1: DVec3, p2: DVec3, p3: DVec3) -> Option<Self> {
        Plane::newell(&[p1, p2, p3])
    }

    /// `normal · p + d`: positive in front, scaled by `|normal|`.
    #[inline]
    #[must_use]
    pub fn evaluate(&self, p: DVec3) -> f64 {
        self.normal.dot(p) + self.d
    }

    /// The signed Euclidean distance of `p` (the normal need not be unit length):
    /// `evaluate(p) / |normal|`. Every "which side of this plane" decision of the crate
    /// goes through it ([`PlaneSide::of_distance`]), so that a classification and the
    /// split that follows it agree on every vertex.
    #[inline]
    #[must_use]
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        self.evaluate(p) / self.normal.length()
    }

    /// [`Plane::signed_distance`] as a function, the normal's length computed once (the
    /// same bits for every point): for the loops over a polygon's vertices, where a
    /// square root per vertex cost the BSP build 9 %.
    #[inline]
    pub fn signed_distance_fn(&self) -> impl Fn(DVec3) -> f64 + Copy + '_ {
        let len = self.normal.length();
        move |p| self.evaluate(p) / len
    }

    /// [`Plane::signed_distance`] of many points, by [`Plane::signed_distance_fn`].
    #[inline]
    pub fn signed_distances<I>(&self, points: I) -> impl Iterator<Item = f64>
    where
        I: IntoIterator<Item = DVec3>,
    {
        points.into_iter().map(self.signed_distance_fn())
    }

    /// The same plane with a unit normal.
    #[must_use]
    pub fn normalized(&self) -> Self {
        let l = self.normal.length();
        Plane {
            normal: self.normal / l,
            d: self.d / l,
        }
    }

    /// The same plane facing the other way.
    #[must_use]
    pub fn flipped(&self) -> Self {
        Plane {
            normal: -self.normal,
            d: -self.d,
        }
    }

    /// Which side `p` is on, with `|signed distance| <= eps` counted as on the plane.
    #[must_use]
    pub fn side_of(&self, p: DVec3, eps: f64) -> PlaneSide {
        PlaneSide::of_distance(self.signed_distance(p), eps)
    }

    /// Which side a polygon is on: `Spanning` if it has vertices strictly on both
    /// sides, `On` if every vertex is within `eps`.
    #[must_use]
    pub fn classify_polygon(&self, points: &[DVec3], eps: f64) -> PlaneSide {
        self.classify_points(points.iter().copied(), eps)
    }

    /// [`Plane::classify_polygon`] for points given one by one (vertices read through
    /// an index list, say).
    #[must_use]
    pub fn classify_points(&self, points: impl IntoIterator<Item = DVec3>, eps: f64) -> PlaneSide {
        PlaneSide::of_distances(self.signed_distances(points), eps)
    }

    /// Where the segment `a`-`b` meets the plane, as the parameter `t` of `a + t(b-a)`;
    /// `None` if the segment is parallel to the plane.
    #[must_use]
    pub fn intersect_segment(&self, a: DVec3, b: DVec3) -> Option<f64> {
        let da = self.evaluate(a);
        let db = self.evaluate(b);
        let denom = da - db;
        if denom == 0.0 { None } else { Some(da / denom) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newell_keeps_the_plane_of_a_tiny_polygon_far_from_the_origin() {
        // A square of side 1e-13, tilted 45 degrees about x, around z = -1.7 (an
        // eye-space face of a cube seen through an orthographic window 1e-12 high): its
        // area is far below 1e-24 of its coordinates squared, but far above what
        // rounding them can make.
        let (c, s) = (0.5f64.sqrt(), 1e-13);
        let quad: Vec<DVec3> = [(0., 0.), (s, 0.), (s, s), (0., s)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y * c, -1.7 + y * c))
            .collect();
        let p = Plane::newell(&quad).expect("a plane");
        let want = DVec3::new(0.0, -c, c);
        assert!((p.normal - want).length() < 1e-2, "{:?}", p.normal);
        // Collinear points at that scale still have no plane.
        let line: Vec<DVec3> = (0..4)
            .map(|k| DVec3::new(f64::from(k) * s, 0.0, -1.7))
            .collect();
        assert!(Plane::newell(&line).is_none());
    }

    #[test]
    fn cramer_reproduces_seed_004_task() {
        // a_n = -3/120, b_n = -1/120, c_n = -4/120
        let p = Plane::from_three_points_cramer(
            DVec3::new(15., 15., 15.),
            DVec3::new(25., 25., 5.),
            DVec3::new(30., 10., 5.),
        )
        .unwrap();
        assert!((p.normal.x - (-3.0 / 120.0)).abs() < 1e-15);
        assert!((p.normal.y - (-1.0 / 120.0)).abs() < 1e-15);
        assert!((p.normal.z - (-4.0 / 120.0)).abs() < 1e-15);
        // Scaling by -120 gives 3x + y + 4z - 120 = 0.
        let s = -120.0;
        assert!((p.normal * s - DVec3::new(3., 1., 4.)).length() < 1e-12);
        assert!((p.d * s + 120.0).abs() < 1e-12);
    }

    #[test]
    fn cramer_refuses_plane_through_origin() {
        assert!(Plane::from_three_points_cramer(DVec3::ZERO, DVec3::X, DVec3::Y).is_none());
    }

    #[test]
    fn newell_agrees_with_cramer_on_the_seed_triangle() {
        let pts = [
            DVec3::new(15., 15., 15.),
            DVec3::new(25., 25., 5.),
            DVec3::new(30., 10., 5.),
        ];
        let n = Plane::newell(&pts).unwrap();
        let c = Plane::from_three_points_cramer(pts[0], pts[1], pts[2])
            .unwrap()
            .normalized();
        // Same plane up to orientation.
        let sign = n.normal.dot(c.normal).signum();
        assert!((n.normal - c.normal * sign).length() < 1e-12);
        assert!((n.d - c.d * sign).abs() < 1e-9);
        // 3x + y + 4z - 120 = 0 up to scale
        let expected = DVec3::new(3., 1., 4.).normalize();
        assert!((n.normal.dot(expected).abs() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn newell_is_robust_for_nonplanar_quads() {
        // A slightly twisted quad: Newell gives the average plane, all vertices close to it.
        let q = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.01),
            DVec3::new(1., 1., 0.),
            DVec3::new(0., 1., 0.01),
        ];
        let p = Plane::newell(&q).unwrap();
        assert!(p.normal.z > 0.9999);
        for v in q {
            assert!(p.signed_distance(v).abs() <= 0.0050001);
        }
    }

    #[test]
    fn newell_refuses_degenerate() {
        assert!(Plane::newell(&[DVec3::ZERO, DVec3::X, DVec3::X * 2.0]).is_none());
        assert!(Plane::newell(&[DVec3::ZERO, DVec3::X]).is_none());
        assert!(Plane::newell(&[DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 0., 0.)]).is_none());
    }

    #[test]
    fn classify_and_intersect() {
        let p = Plane::from_point_normal(DVec3::ZERO, DVec3::Z);
        let tri = [
            DVec3::new(0., 0., -1.),
            DVec3::new(1., 0., 1.),
            DVec3::new(0., 1., 1.),
        ];
        assert_eq!(p.classify_polygon(&tri, 1e-9), PlaneSide::Spanning);
        assert_eq!(p.intersect_segment(tri[0], tri[1]), Some(0.5));
        assert_eq!(p.side_of(DVec3::new(0., 0., 1e-12), 1e-9), PlaneSide::On);
    }

    #[test]
    fn one_side_rule_for_points_and_polygons() {
        // Beyond eps on either side; within it (both ends included) and NaN: on.
        assert_eq!(PlaneSide::of_distance(0.25, 0.125), PlaneSide::Front);
        assert_eq!(PlaneSide::of_distance(-0.25, 0.125), PlaneSide::Back);
        assert_eq!(PlaneSide::of_distance(0.125, 0.125), PlaneSide::On);
        assert_eq!(PlaneSide::of_distance(-0.125, 0.125), PlaneSide::On);
        assert_eq!(PlaneSide::of_distance(f64::NAN, 0.125), PlaneSide::On);
        assert_eq!(PlaneSide::of_distances([], 0.0), PlaneSide::On);
        assert_eq!(
            PlaneSide::of_distances([0.0, 1.0, 0.0], 0.5),
            PlaneSide::Front
        );
        assert_eq!(PlaneSide::of_distances([-1.0, 0.25], 0.5), PlaneSide::Back);
        assert_eq!(
            PlaneSide::of_distances([-1.0, 1.0], 0.5),
            PlaneSide::Spanning
        );
        // A plane with a normal of length 2: distances are Euclidean (z = 3 is 1 above
        // z = 2), so eps is a distance whatever the normal's length.
        let p = Plane {
            normal: DVec3::new(0.0, 0.0, 2.0),
            d: -4.0,
        };
        assert_eq!(p.signed_distance(DVec3::new(5.0, -1.0, 3.0)), 1.0);
        assert_eq!(p.side_of(DVec3::new(0.0, 0.0, 2.75), 0.5), PlaneSide::Front);
        assert_eq!(p.side_of(DVec3::new(0.0, 0.0, 2.75), 0.75), PlaneSide::On);
        assert_eq!(p.side_of(DVec3::new(0.0, 0.0, 1.0), 0.5), PlaneSide::Back);
        let tri = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
        ];
        assert_eq!(p.classify_polygon(&tri, 0.5), PlaneSide::Back);
        assert_eq!(p.classify_points(tri.iter().copied(), 1.0), PlaneSide::On);
        assert_eq!(
            p.classify_points(tri.iter().map(|&q| q + DVec3::Z * 0.5), 0.25),
            PlaneSide::Spanning
        );
    }
}
