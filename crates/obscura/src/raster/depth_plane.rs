//! The depth of a planar polygon as an affine function of screen position.
//!
//! Seeds 000, 003 and 004 step the depth along a scanline by a constant,
//! `z(x + 1) = z(x) - a/c`, from the plane `ax + by + cz + d = 0`. What is affine in
//! screen space after a perspective projection is not the eye depth but its
//! reciprocal, so the view pipeline gives each vertex a *depth key* `zq` (near/depth
//! for perspective, a linear map of depth for orthographic; larger is nearer) and this
//! plane interpolates that key.
//!
//! Source: Blinn, *Hyperbolic interpolation* (IEEE CG&A, July 1992): `1 / depth` is
//! affine in screen space.

/// `zq(px, py) = z0 + dzdx (px - x0) + dzdy (py - y0)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthPlane {
    /// Anchor x.
    pub x0: f64,
    /// Anchor y.
    pub y0: f64,
    /// Key at the anchor.
    pub z0: f64,
    /// Change per pixel to the right (the seed's `-a/c`).
    pub dzdx: f64,
    /// Change per pixel down.
    pub dzdy: f64,
}

impl DepthPlane {
    /// The plane through polygon vertices `(x, y, zq)`, using the fan triangle of
    /// largest area for accuracy. `None` if the polygon has zero screen area.
    #[inline]
    #[must_use]
    pub fn from_points(points: &[(f64, f64, f64)]) -> Option<Self> {
        let n = points.len();
        if n < 3 {
            return None;
        }
        let p0 = points[0];
        let mut best = (0.0f64, 1);
        for k in 1..n - 1 {
            let (a, b) = (points[k], points[k + 1]);
            let det = (a.0 - p0.0) * (b.1 - p0.1) - (a.1 - p0.1) * (b.0 - p0.0);
            if det.abs() > best.0.abs() {
                best = (det, k);
            }
        }
        let (det, k) = best;
        if !(det != 0.0 && det.is_finite()) {
            return None;
        }
        Some(DepthPlane::through(p0, points[k], points[k + 1], det))
    }

    /// The plane through the points `p0`, `a`, `b`, given `det`, the determinant
    /// `(a - p0) x (b - p0)` of their `(x, y)` (non-zero and finite): the one
    /// expression of [`DepthPlane::from_points`] and of the triangle setups.
    #[inline(always)]
    #[must_use]
    pub(crate) fn through(
        p0: (f64, f64, f64),
        a: (f64, f64, f64),
        b: (f64, f64, f64),
        det: f64,
    ) -> DepthPlane {
        let (ax, ay, az) = (a.0 - p0.0, a.1 - p0.1, a.2 - p0.2);
        let (bx, by, bz) = (b.0 - p0.0, b.1 - p0.1, b.2 - p0.2);
        DepthPlane {
            x0: p0.0,
            y0: p0.1,
            z0: p0.2,
            dzdx: (az * by - bz * ay) / det,
            dzdy: (ax * bz - bx * az) / det,
        }
    }

    /// The key at `(px, py)`.
    #[inline(always)]
    #[must_use]
    pub fn at(&self, px: f64, py: f64) -> f64 {
        self.z0 + self.dzdx * (px - self.x0) + self.dzdy * (py - self.y0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_vertices_and_seed_step() {
        // Seed 004's triangle seen orthographically along z: z = (120 - 3x - y) / 4,
        // so z(x + 1) = z(x) - 3/4.
        let p = [(15.0, 15.0, 15.0), (25.0, 25.0, 5.0), (30.0, 10.0, 5.0)];
        let d = DepthPlane::from_points(&p).unwrap();
        for v in p {
            assert!((d.at(v.0, v.1) - v.2).abs() < 1e-12);
        }
        assert!((d.dzdx + 0.75).abs() < 1e-15);
        assert!((d.dzdy + 0.25).abs() < 1e-15);
        assert!(DepthPlane::from_points(&[(0., 0., 1.), (1., 1., 2.), (2., 2., 3.)]).is_none());
    }
}
