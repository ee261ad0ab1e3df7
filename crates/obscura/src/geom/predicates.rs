//! Exact geometric predicates: signs that never lie, through the `robust` crate
//! (adaptive-precision arithmetic).
//!
//! Paper: J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast
//! robust geometric predicates", Discrete & Computational Geometry 18(3), 1997.

use glam::DVec3;

/// Shewchuk's `orient3d`: positive when `d` lies below the plane of `a, b, c` (the side
/// from which `a, b, c` appear clockwise), negative above, zero on it; the sign is
/// exact. Equals `det[a - d; b - d; c - d] = -((b - a) x (c - a)) · (d - a)` up to
/// rounding of the magnitude.
///
/// ```
/// use glam::DVec3;
/// use obscura::geom::orient3d;
/// let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
/// assert!(orient3d(a, b, c, DVec3::Z) < 0.0);
/// assert_eq!(orient3d(a, b, c, DVec3::new(3.0, 7.0, 0.0)), 0.0);
/// ```
#[inline]
#[must_use]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let p = |v: DVec3| robust::Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    robust::orient3d(p(a), p(b), p(c), p(d))
}
