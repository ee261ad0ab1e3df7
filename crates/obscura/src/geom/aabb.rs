//! Axis-aligned bounding boxes.
//!
//! Paper: Rubin and Whitted, "A 3-dimensional representation for fast rendering of
//! complex scenes", SIGGRAPH 1980 (hierarchies of bounding boxes).

use glam::{DMat4, DVec3};

use super::slab::{RaySlabs, slab};

/// An axis-aligned box `[min, max]`. The empty box has `min > max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lower corner.
    pub min: DVec3,
    /// The upper corner.
    pub max: DVec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: contains nothing, and growing it by a point gives that point.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The box of a set of points (empty for none).
    #[must_use]
    pub fn from_points<I: IntoIterator<Item = DVec3>>(points: I) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.with_point(p))
    }

    /// This box grown to contain `p`.
    #[inline]
    #[must_use]
    pub fn with_point(self, p: DVec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// The union of two boxes.
    #[inline]
    #[must_use]
    pub fn union(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Whether the box contains nothing.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// The largest absolute coordinate of the box (the scale of the rounding of points
    /// in it); 0 for an empty box.
    #[must_use]
    pub fn magnitude(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            self.min.abs().max(self.max.abs()).max_element()
        }
    }

    /// The centre.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// The size along each axis.
    #[must_use]
    pub fn extent(&self) -> DVec3 {
        self.max - self.min
    }

    /// Half the surface area (the SAH cost measure); 0 for an empty box.
    #[must_use]
    pub fn half_area(&self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The eight corners.
    #[must_use]
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }

    /// The box of this box's corners after an affine transform.
    #[must_use]
    pub fn transformed(&self, m: &DMat4) -> Self {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(self.corners().map(|c| m.transform_point3(c)))
    }

    /// Whether `p` is inside or on the boundary.
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Whether the two boxes share at least a boundary point.
    #[must_use]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// The parameter interval `[t0, t1]` in which the ray `origin + direction t` is
    /// inside the box (one slab per axis, see `geom::slab`), `None` if it misses. Not
    /// clipped to `t >= 0`. The box must not be empty (each slab is read as the
    /// interval between its two bounds).
    #[must_use]
    pub fn ray_interval(&self, origin: DVec3, direction: DVec3) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 0..3 {
            if !slab(
                origin[k],
                direction[k],
                self.min[k],
                self.max[k],
                &mut t0,
                &mut t1,
            ) {
                return None;
            }
        }
        Some((t0, t1))
    }

    /// [`Aabb::ray_interval`] with the ray's projections computed beforehand (the
    /// first three directions of a [`RaySlabs`] are the axes); the same interval, bit
    /// for bit.
    #[must_use]
    pub fn ray_interval_projected(&self, ray: &RaySlabs) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 0..3 {
            if !ray.clip(k, self.min[k], self.max[k], &mut t0, &mut t1) {
                return None;
            }
        }
        Some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basics() {
        let b = Aabb::from_points([DVec3::new(1., 2., 3.), DVec3::new(-1., 0., 5.)]);
        assert_eq!(b.min, DVec3::new(-1., 0., 3.));
        assert_eq!(b.max, DVec3::new(1., 2., 5.));
        assert_eq!(b.half_area(), 2.0 * 2.0 + 2.0 * 2.0 + 2.0 * 2.0);
        assert!(Aabb::EMPTY.is_empty());
        assert!(!b.is_empty());
        assert!(b.contains(DVec3::new(0., 1., 4.)));
        assert!(!b.contains(DVec3::new(0., 1., 6.)));
        let t = b.transformed(&DMat4::from_translation(DVec3::X));
        assert_eq!(t.min.x, 0.0);
    }

    #[test]
    fn ray_intervals_through_the_box() {
        let b = Aabb {
            min: DVec3::new(1.0, -1.0, -1.0),
            max: DVec3::new(3.0, 1.0, 1.0),
        };
        // Along +x through the middle: enters at x = 1, leaves at x = 3.
        let o = DVec3::ZERO;
        assert_eq!(b.ray_interval(o, DVec3::X), Some((1.0, 3.0)));
        assert_eq!(b.ray_interval(o, DVec3::X * 2.0), Some((0.5, 1.5)));
        // Behind the origin: a negative interval (not clipped to t >= 0).
        assert_eq!(b.ray_interval(o, -DVec3::X), Some((-3.0, -1.0)));
        // Parallel to the y and z slabs but outside one of them: a miss.
        assert_eq!(b.ray_interval(DVec3::new(0.0, 2.0, 0.0), DVec3::X), None);
        // A diagonal: the latest entry and the earliest exit over the three slabs.
        let d = DVec3::new(1.0, 0.5, 0.25);
        assert_eq!(b.ray_interval(o, d), Some((1.0, 2.0)));
        let ray = RaySlabs::new(o, d);
        assert_eq!(b.ray_interval_projected(&ray), b.ray_interval(o, d));
    }
}
