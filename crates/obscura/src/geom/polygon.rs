//! Small pure functions on polygons given as vertex lists.

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
fn project(points: &[DVec3], normal: DVec3) -> Vec<DVec2> {
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

/// Triangulates a simple polygon (planar or nearly so) by ear clipping in its Newell
/// plane. Returns triangles as index triples into `points`, counter-clockwise in the
/// same sense as the polygon. Falls back to a fan for polygons that are not simple.
///
/// ```
/// use obscura::geom::triangulate;
/// use glam::DVec3;
/// // An L-shaped (concave) hexagon.
/// let l = [(0.,0.),(2.,0.),(2.,1.),(1.,1.),(1.,2.),(0.,2.)].map(|(x,y)| DVec3::new(x,y,0.));
/// let tris = triangulate(&l);
/// assert_eq!(tris.len(), 4);
/// ```
#[must_use]
pub fn triangulate(points: &[DVec3]) -> Vec<[u32; 3]> {
    let count = points.len();
    if count < 3 {
        return Vec::new();
    }
    if count == 3 {
        return vec![[0, 1, 2]];
    }
    let n = newell_normal(points);
    let fan = || {
        (1..count as u32 - 1)
            .map(|i| [0, i, i + 1])
            .collect::<Vec<_>>()
    };
    if n == DVec3::ZERO || !n.is_finite() {
        return fan();
    }
    let p = project(points, n);
    let mut remaining: Vec<usize> = (0..count).collect();
    let mut out = Vec::with_capacity(count - 2);
    let area2 = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let mut guard = 0;
    while remaining.len() > 3 {
        let m = remaining.len();
        let mut clipped = false;
        for k in 0..m {
            let (ia, ib, ic) = (
                remaining[(k + m - 1) % m],
                remaining[k],
                remaining[(k + 1) % m],
            );
            let (a, b, c) = (p[ia], p[ib], p[ic]);
            if area2(a, b, c) <= 0.0 {
                continue; // reflex or flat corner: not an ear
            }
            let contains = remaining.iter().any(|&j| {
                if j == ia || j == ib || j == ic {
                    return false;
                }
                let q = p[j];
                area2(a, b, q) >= 0.0 && area2(b, c, q) >= 0.0 && area2(c, a, q) >= 0.0
            });
            if contains {
                continue;
            }
            out.push([ia as u32, ib as u32, ic as u32]);
            remaining.remove(k);
            clipped = true;
            break;
        }
        guard += 1;
        if !clipped || guard > count * count {
            return fan();
        }
    }
    out.push([
        remaining[0] as u32,
        remaining[1] as u32,
        remaining[2] as u32,
    ]);
    out
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
    fn ear_clipping_preserves_area() {
        let l = pts(&[(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]);
        let tris = triangulate(&l);
        let total: f64 = tris
            .iter()
            .map(|t| polygon_area(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]]))
            .sum();
        assert!((total - 3.0).abs() < 1e-12);
        // every triangle keeps the polygon's orientation
        for t in &tris {
            let n = newell_normal(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]]);
            assert!(n.z > 0.0);
        }
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
