//! Small pure functions on polygons given as vertex lists: Newell's normal (Newell's
//! method as described in Sutherland, Sproull and Schumacher, "A characterization of
//! ten hidden-surface algorithms", Computing Surveys 1974), area, centroid, planarity
//! and convexity. Triangulation is its own module, `geom::triangulate`.

use glam::{DVec2, DVec3};

/// Newell's normal of a polygon: twice its vector area. Zero for degenerate polygons;
/// exact (up to rounding) for planar ones, the best-fit direction for non-planar ones.
#[must_use]
pub fn newell_normal(points: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    let count = points.len();
    if count < 3 {
        return n;
    }
    // Relative to the first vertex: the same sum, with far less cancellation when the
    // polygon is small and far from the origin.
    let o = points[0];
    for i in 0..count {
        let a = points[i] - o;
        let b = points[(i + 1) % count] - o;
        n.x += (a.y - b.y) * (a.z + b.z);
        n.y += (a.z - b.z) * (a.x + b.x);
        n.z += (a.x - b.x) * (a.y + b.y);
    }
    n
}

/// The area of a planar polygon (for a non-planar one, the area of its projection on
/// the best-fit plane).
#[must_use]
pub fn polygon_area(points: &[DVec3]) -> f64 {
    newell_normal(points).length() * 0.5
}

/// The average of the vertices.
#[must_use]
pub fn polygon_centroid(points: &[DVec3]) -> DVec3 {
    points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64
}

/// The largest distance of a vertex from the polygon's Newell plane; `f64::INFINITY`
/// for degenerate polygons.
#[must_use]
pub fn max_plane_deviation(points: &[DVec3]) -> f64 {
    match super::Plane::newell(points) {
        Some(p) => points
            .iter()
            .fold(0.0f64, |m, &v| m.max(p.evaluate(v).abs())),
        None => f64::INFINITY,
    }
}

/// Projects the polygon on the coordinate plane most parallel to it, preserving its
/// orientation (counter-clockwise seen from the side `normal` points to).
pub(super) fn project(points: &[DVec3], normal: DVec3) -> Vec<DVec2> {
    let a = normal.abs();
    let (i, j, s) = if a.z >= a.x && a.z >= a.y {
        (0, 1, normal.z.signum())
    } else if a.x >= a.y {
        (1, 2, normal.x.signum())
    } else {
        (2, 0, normal.y.signum())
    };
    points.iter().map(|p| DVec2::new(p[i], p[j] * s)).collect()
}

/// Whether a (nearly) planar polygon is strictly convex in its plane: every turn has
/// the same orientation, and the turns add up to one revolution (no self-overlap).
/// Collinear vertices are allowed.
#[must_use]
pub fn is_convex(points: &[DVec3]) -> bool {
    let n = newell_normal(points);
    if points.len() < 3 || n == DVec3::ZERO {
        return false;
    }
    if points.len() == 3 {
        return true;
    }
    let p = project(points, n);
    let count = p.len();
    let mut winding = 0.0;
    for i in 0..count {
        let a = p[i];
        let b = p[(i + 1) % count];
        let c = p[(i + 2) % count];
        let cross = (b - a).perp_dot(c - b);
        if cross < 0.0 {
            return false;
        }
        let (d1, d2) = (b - a, c - b);
        if d1 != DVec2::ZERO && d2 != DVec2::ZERO {
            winding += d1.perp_dot(d2).atan2(d1.dot(d2));
        }
    }
    (winding - std::f64::consts::TAU).abs() < 1e-6
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(v: &[(f64, f64)]) -> Vec<DVec3> {
        v.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect()
    }

    #[test]
    fn area_of_unit_square_and_triangle() {
        assert_eq!(
            polygon_area(&pts(&[(0., 0.), (1., 0.), (1., 1.), (0., 1.)])),
            1.0
        );
        assert_eq!(polygon_area(&pts(&[(0., 0.), (4., 0.), (0., 3.)])), 6.0);
    }

    #[test]
    fn convexity() {
        assert!(is_convex(&pts(&[(0., 0.), (1., 0.), (1., 1.), (0., 1.)])));
        assert!(!is_convex(&pts(&[
            (0., 0.),
            (2., 0.),
            (1., 0.5),
            (2., 2.),
            (0., 2.)
        ])));
        // clockwise is convex too (seen from the other side)
        assert!(is_convex(&pts(&[(0., 1.), (1., 1.), (1., 0.), (0., 0.)])));
        // a bow tie is not
        assert!(!is_convex(&pts(&[(0., 0.), (1., 1.), (1., 0.), (0., 1.)])));
        // a pentagram traced as a 5-gon (winds twice) is not
        let star: Vec<_> = (0..5)
            .map(|i| {
                let a = i as f64 * 2.0 * std::f64::consts::TAU / 5.0;
                DVec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        assert!(!is_convex(&star));
    }

    #[test]
    fn deviation() {
        let q = [
            DVec3::new(0., 0., 0.),
            DVec3::new(1., 0., 0.),
            DVec3::new(1., 1., 0.2),
            DVec3::new(0., 1., 0.),
        ];
        let d = max_plane_deviation(&q);
        assert!(d > 0.04 && d < 0.06, "{d}");
        assert_eq!(
            max_plane_deviation(&pts(&[(0., 0.), (1., 0.), (0., 1.)])),
            0.0
        );
    }
}
