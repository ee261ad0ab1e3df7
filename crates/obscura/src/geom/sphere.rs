//! Bounding spheres.

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
}
