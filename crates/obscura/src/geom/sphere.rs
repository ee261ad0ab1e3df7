//! Bounding spheres.
//!
//! Paper: Ritter, "An efficient bounding sphere", in Graphics Gems (Glassner, ed.),
//! Academic Press, 1990.

use glam::DVec3;

/// A sphere given by centre and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// The centre.
    pub center: DVec3,
    /// The radius (non-negative).
    pub radius: f64,
}

impl Sphere {
    /// A bounding sphere of the points by Ritter's method (two passes to find a
    /// diameter estimate, then growing to include outliers): within about 5% of the
    /// smallest enclosing sphere, in linear time. `None` for no points.
    #[must_use]
    pub fn bounding(points: &[DVec3]) -> Option<Self> {
        let first = *points.first()?;
        let far = |from: DVec3| {
            points.iter().copied().fold(from, |best, p| {
                if p.distance_squared(from) > best.distance_squared(from) {
                    p
                } else {
                    best
                }
            })
        };
        let a = far(first);
        let b = far(a);
        let mut center = (a + b) * 0.5;
        let mut radius = a.distance(b) * 0.5;
        for &p in points {
            let d = p.distance(center);
            if d > radius {
                let new_radius = (radius + d) * 0.5;
                center += (p - center) * ((new_radius - radius) / d);
                radius = new_radius;
            }
        }
        // Rounding can leave a point a hair outside: grow by a relative epsilon.
        let radius = radius * (1.0 + 1e-12) + 1e-300;
        Some(Sphere { center, radius })
    }

    /// Whether `p` lies inside or on the sphere.
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        p.distance_squared(self.center) <= self.radius * self.radius
    }

    /// The parameter interval `[t0, t1]` in which the ray `origin + t direction` is
    /// inside the sphere, `None` if it misses (or `direction` is zero): the distance
    /// from the centre to the ray compared with the radius (seed 002, "distanza di un
    /// punto da una retta"). Not clipped to `t >= 0`.
    #[must_use]
    pub fn ray_interval(&self, origin: DVec3, direction: DVec3) -> Option<(f64, f64)> {
        let dd = direction.length_squared();
        let oc = origin - self.center;
        let t_mid = -oc.dot(direction) / dd;
        let closest = oc + direction * t_mid;
        let gap = self.radius * self.radius - closest.length_squared();
        if !(gap >= 0.0) {
            return None;
        }
        let half = (gap / dd).sqrt();
        Some((t_mid - half, t_mid + half))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ritter_contains_all_points() {
        let pts: Vec<DVec3> = (0..100)
            .map(|i| {
                let t = i as f64 * 0.731;
                DVec3::new(t.sin() * 3.0, (t * 1.7).cos() * 2.0, (t * 0.3).sin())
            })
            .collect();
        let s = Sphere::bounding(&pts).unwrap();
        assert!(pts.iter().all(|&p| s.contains(p)));
        assert!(s.radius < 4.0);
        assert!(Sphere::bounding(&[]).is_none());
    }

    #[test]
    fn ray_interval_is_analytic() {
        let s = Sphere {
            center: DVec3::new(0.0, 0.0, -5.0),
            radius: 2.0,
        };
        let (t0, t1) = s.ray_interval(DVec3::ZERO, -DVec3::Z * 2.0).unwrap();
        assert!((t0 - 1.5).abs() < 1e-15 && (t1 - 3.5).abs() < 1e-15);
        // Passing at distance 1 from the centre: chord half-length sqrt(3).
        let (t0, t1) = s
            .ray_interval(DVec3::new(1.0, 0.0, 0.0), -DVec3::Z)
            .unwrap();
        assert!(
            (t0 - (5.0 - 3f64.sqrt())).abs() < 1e-12 && (t1 - (5.0 + 3f64.sqrt())).abs() < 1e-12
        );
        assert!(
            s.ray_interval(DVec3::new(2.5, 0.0, 0.0), -DVec3::Z)
                .is_none()
        );
        // Tangent: one point; a zero direction: nothing.
        assert_eq!(
            s.ray_interval(DVec3::new(2.0, 0.0, 0.0), -DVec3::Z),
            Some((5.0, 5.0))
        );
        assert!(s.ray_interval(DVec3::ZERO, DVec3::ZERO).is_none());
    }
}
