//! View-frustum culling of bounding volumes in clip space, before the divide.
//!
//! Source: seed 000 ("Περικοπή στο Οπτικό Πεδίο"). A bounding sphere is tested against
//! the six planes of the view volume, extracted from the view-projection matrix (its
//! rows combined as `row3 ± row_k`, which is the clip-space condition
//! `-w <= x, y, z <= w` pulled back to world space). A box is tested by the outcodes of
//! its eight corners in clip space: all sharing an outside bit means outside; all zero
//! means inside, so its faces need no clipping.

use glam::{DMat4, DVec4};

use crate::clip::outcode_homogeneous;
use crate::geom::{Aabb, Sphere};

/// Where a bounding volume lies relative to the view volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    /// Entirely outside: everything in it can be culled.
    Outside,
    /// Entirely inside: nothing in it needs clipping.
    Inside,
    /// Possibly crossing the boundary.
    Intersecting,
}

/// The six planes `(a, b, c, d)` (inside where `a x + b y + c z + d >= 0`, normal of unit
/// length) of the view volume of `view_projection`, in world space:
/// left, right, bottom, top, near, far.
///
/// Given a projection matrix alone, the planes are those of eye space. Far from the
/// origin, test eye-space volumes against those (as
/// [`crate::view::ViewTransform::object_containment`] does): planes taken from a
/// view-projection matrix there carry the rounding of large translations, which their
/// normalization magnifies when `far / near` is large.
#[must_use]
pub fn frustum_planes(view_projection: &DMat4) -> [DVec4; 6] {
    let r = |i: usize| view_projection.row(i);
    let planes = [
        r(3) + r(0),
        r(3) - r(0),
        r(3) + r(1),
        r(3) - r(1),
        r(3) + r(2),
        r(3) - r(2),
    ];
    planes.map(|p| p / p.truncate().length())
}

/// Classifies a sphere against frustum planes from [`frustum_planes`].
#[must_use]
pub fn classify_sphere(planes: &[DVec4; 6], sphere: &Sphere) -> Containment {
    let mut inside = true;
    for p in planes {
        let d = p.truncate().dot(sphere.center) + p.w;
        if d < -sphere.radius {
            return Containment::Outside;
        }
        if d < sphere.radius {
            inside = false;
        }
    }
    if inside {
        Containment::Inside
    } else {
        Containment::Intersecting
    }
}

/// Classifies a world-space box by the clip-space outcodes of its corners under
/// `view_projection`.
#[must_use]
pub fn classify_aabb(view_projection: &DMat4, aabb: &Aabb) -> Containment {
    if aabb.is_empty() {
        return Containment::Outside;
    }
    classify_clip_points(aabb.corners().map(|c| *view_projection * c.extend(1.0)))
}

/// Classifies the convex hull of clip-space points (a box's corners, say) by their
/// outcodes: all sharing an outside bit means outside, all zero inside.
#[must_use]
pub fn classify_clip_points(points: impl IntoIterator<Item = DVec4>) -> Containment {
    let (mut and, mut or) = (0x3f, 0);
    for c in points {
        let code = outcode_homogeneous(c);
        and &= code;
        or |= code;
    }
    if and != 0 {
        Containment::Outside
    } else if or == 0 {
        Containment::Inside
    } else {
        Containment::Intersecting
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::DVec3;

    #[test]
    fn spheres_and_boxes() {
        let cam = Camera::perspective(
            DVec3::new(0., 0., 10.),
            DVec3::ZERO,
            DVec3::Y,
            60.0,
            1.0,
            100.0,
        );
        let vp = cam.projection_matrix(1.0) * cam.view_matrix();
        let planes = frustum_planes(&vp);
        let s = |x: f64, y: f64, z: f64, r: f64| Sphere {
            center: DVec3::new(x, y, z),
            radius: r,
        };
        assert_eq!(
            classify_sphere(&planes, &s(0., 0., 0., 1.)),
            Containment::Inside
        );
        assert_eq!(
            classify_sphere(&planes, &s(0., 0., 20., 1.)),
            Containment::Outside
        ); // behind the eye
        assert_eq!(
            classify_sphere(&planes, &s(0., 0., 9.5, 1.)),
            Containment::Intersecting
        ); // near plane
        assert_eq!(
            classify_sphere(&planes, &s(100., 0., 0., 1.)),
            Containment::Outside
        );
        let b = |lo: f64, hi: f64| Aabb {
            min: DVec3::splat(lo),
            max: DVec3::splat(hi),
        };
        assert_eq!(classify_aabb(&vp, &b(-1., 1.)), Containment::Inside);
        assert_eq!(classify_aabb(&vp, &b(50., 60.)), Containment::Outside);
        assert_eq!(classify_aabb(&vp, &b(-1., 9.5)), Containment::Intersecting);
    }
}
