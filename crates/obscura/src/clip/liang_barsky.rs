//! Liang-Barsky line clipping: the segment `p(t) = p1 + t (p2 - p1)`, `t` in `[0, 1]`,
//! is inside the clipping region where every inequality `t p_i <= q_i` holds. Each
//! inequality with `p_i < 0` bounds `t` from below (the segment enters there), with
//! `p_i > 0` from above (it leaves); `p_i = 0` means parallel to that boundary, and
//! `q_i < 0` then means entirely outside it. The visible part is
//! `[max(0, entering q_i/p_i), min(1, leaving q_i/p_i)]` when that interval is not
//! empty.
//!
//! Source: seed 000, "Αποκοπή Ευθύγραμμου Τμήματος Liang – Barsky 3Δ", slides (4) and
//! (5): in homogeneous coordinates, with `Dx = x2 - x1` (and `Dy, Dz, Dw` alike),
//!
//! | i | `p_i` | `q_i` | boundary |
//! | --- | --- | --- | --- |
//! | 1 | `-Dx - Dw` | `x1 + w1` | left, `x >= -w` |
//! | 2 | `Dx - Dw` | `w1 - x1` | right, `x <= w` |
//! | 3 | `-Dy - Dw` | `y1 + w1` | bottom, `y >= -w` |
//! | 4 | `Dy - Dw` | `w1 - y1` | top, `y <= w` |
//! | 5 | `-Dz - Dw` | `z1 + w1` | near, `z >= -w` |
//! | 6 | `Dz - Dw` | `w1 - z1` | far, `z <= w` |
//!
//! ([`homogeneous_pq`]); for the orthographic or parallel view volume the region is a
//! box and `zmin <= z1 + t Dz <= zmax` joins the 2D inequalities ([`box_pq`]); in 2D
//! the rectangle gives the first four rows with `w` replaced by the bounds
//! ([`rect_pq`]).
//!
//! # Input and output
//! A segment by its two endpoints; the visible part with endpoints in the same order
//! (an endpoint with `t = 0` or `t = 1` is returned bit for bit), or `None`. The
//! `*_parameters` functions return the interval `(t_enter, t_exit)` itself. Any
//! non-finite coordinate gives `None`. A segment that only touches the region gives a
//! zero-length result (`t_enter == t_exit`).
//!
//! # Complexity
//! `O(1)`: one division per boundary the segment is not parallel to, no iteration.
//!
//! Paper: Liang and Barsky, "A new concept and method for line clipping", ACM
//! Transactions on Graphics 3(1), 1984.

use super::InRange;
use glam::{DVec2, DVec3, DVec4};

use super::{Rect, valid_box};
use crate::geom::Aabb;

/// The `t` interval where every `t p_i <= q_i` holds, within `[0, 1]`.
#[inline]
fn interval(pq: &[(f64, f64)]) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let mut parallel_outside = false;
    // No early exit: the divisions are independent and the selections compile to
    // conditional moves, which beats branching on the random signs of `p_i`.
    for &(p, q) in pq {
        let r = q / p;
        t0 = if p < 0.0 { t0.max(r) } else { t0 };
        t1 = if p > 0.0 { t1.min(r) } else { t1 };
        parallel_outside |= p == 0.0 && q < 0.0;
    }
    if parallel_outside || t0 > t1 {
        return None;
    }
    Some((t0, t1))
}

/// The points of the interval: the endpoints themselves when not clipped, so a segment
/// inside comes back unchanged.
#[inline]
fn endpoints<V>(p1: V, p2: V, (t0, t1): (f64, f64), at: impl Fn(f64) -> V) -> (V, V) {
    (
        if t0 == 0.0 { p1 } else { at(t0) },
        if t1 == 1.0 { p2 } else { at(t1) },
    )
}

/// The 2D table: `(p_i, q_i)` for left, right, bottom, top of the rectangle:
/// `(-Dx, x1 - xmin), (Dx, xmax - x1), (-Dy, y1 - ymin), (Dy, ymax - y1)`.
#[must_use]
pub fn rect_pq(p1: DVec2, p2: DVec2, rect: &Rect) -> [(f64, f64); 4] {
    let d = p2 - p1;
    let (min, max) = (rect.min(), rect.max());
    [
        (-d.x, p1.x - min.x),
        (d.x, max.x - p1.x),
        (-d.y, p1.y - min.y),
        (d.y, max.y - p1.y),
    ]
}

/// The parameter interval of segment `p1 p2` inside the rectangle, or `None`.
#[must_use]
pub(crate) fn rect_parameters(p1: DVec2, p2: DVec2, rect: &Rect) -> Option<(f64, f64)> {
    if !(p1.in_range() && p2.in_range()) {
        return None;
    }
    interval(&rect_pq(p1, p2, rect))
}

/// Liang-Barsky 2D: the part of segment `p1 p2` inside the rectangle, or `None`.
///
/// ```
/// use obscura::clip::{Rect, liang_barsky::clip_segment_2d};
/// use glam::DVec2;
/// let r = Rect::new(0., 0., 4., 4.).unwrap();
/// // t in [max(-0.2, 0.1), min(0.6, 0.5)] = [0.1, 0.5] (seed 001, figure 6.3's case).
/// let (a, b) = clip_segment_2d(DVec2::new(1., -1.), DVec2::new(6., 9.), &r).unwrap();
/// assert!((a - DVec2::new(1.5, 0.)).length() < 1e-15 && (b - DVec2::new(3.5, 4.)).length() < 1e-15);
/// ```
#[must_use]
pub fn clip_segment_2d(p1: DVec2, p2: DVec2, rect: &Rect) -> Option<(DVec2, DVec2)> {
    let t = rect_parameters(p1, p2, rect)?;
    Some(endpoints(p1, p2, t, |t| p1 + (p2 - p1) * t))
}

/// The seed's table `(p_i, q_i)`, `i = 1..6`, for the homogeneous view volume
/// `-w <= x, y, z <= w` (see the module doc), in the order left, right, bottom, top,
/// near, far.
///
/// ```
/// use obscura::clip::liang_barsky::homogeneous_pq;
/// use glam::DVec4;
/// let pq = homogeneous_pq(DVec4::new(-2., 0., 0., 1.), DVec4::new(2., 0.5, 0., 1.));
/// assert_eq!(pq[0], (-4., -1.)); // p1 = -Dx - Dw = -4, q1 = x1 + w1 = -1
/// assert_eq!(pq[1], (4., 3.)); //   p2 = Dx - Dw = 4,   q2 = w1 - x1 = 3
/// ```
#[must_use]
pub fn homogeneous_pq(p1: DVec4, p2: DVec4) -> [(f64, f64); 6] {
    let d = p2 - p1;
    [
        (-d.x - d.w, p1.x + p1.w),
        (d.x - d.w, p1.w - p1.x),
        (-d.y - d.w, p1.y + p1.w),
        (d.y - d.w, p1.w - p1.y),
        (-d.z - d.w, p1.z + p1.w),
        (d.z - d.w, p1.w - p1.z),
    ]
}

/// The parameter interval of the homogeneous segment inside the view volume, or
/// `None`.
#[must_use]
pub fn homogeneous_parameters(p1: DVec4, p2: DVec4) -> Option<(f64, f64)> {
    if !(p1.in_range() && p2.in_range()) {
        return None;
    }
    interval(&homogeneous_pq(p1, p2))
}

/// Liang-Barsky 3D in homogeneous clip space, before the divide: the part of `p1 p2`
/// with `-w <= x, y, z <= w`, or `None`. A segment crossing `w = 0` keeps only its
/// part in front of the eye.
///
/// ```
/// use obscura::clip::liang_barsky::clip_segment_homogeneous;
/// use glam::DVec4;
/// // Dx = 1, Dw = -2: p2 = Dx - Dw = 3, q2 = w1 - x1 = 0.5, so t <= 1/6; the others
/// // (p = 1 or 2, q >= 1) allow t up to 1/2 at least.
/// let (a, b) = clip_segment_homogeneous(DVec4::new(0.5, 0., 0., 1.), DVec4::new(1.5, 0., 0., -1.)).unwrap();
/// assert_eq!(a, DVec4::new(0.5, 0., 0., 1.));
/// assert!((b - DVec4::new(2. / 3., 0., 0., 2. / 3.)).length() < 1e-15);
/// ```
#[must_use]
pub fn clip_segment_homogeneous(p1: DVec4, p2: DVec4) -> Option<(DVec4, DVec4)> {
    let t = homogeneous_parameters(p1, p2)?;
    Some(endpoints(p1, p2, t, |t| p1 + (p2 - p1) * t))
}

/// The table for an axis-aligned box (the orthographic cube form): the 2D rows plus
/// `(-Dz, z1 - zmin), (Dz, zmax - z1)`, in the order left, right, bottom, top, near,
/// far.
#[must_use]
pub fn box_pq(p1: DVec3, p2: DVec3, bounds: &Aabb) -> [(f64, f64); 6] {
    let d = p2 - p1;
    [
        (-d.x, p1.x - bounds.min.x),
        (d.x, bounds.max.x - p1.x),
        (-d.y, p1.y - bounds.min.y),
        (d.y, bounds.max.y - p1.y),
        (-d.z, p1.z - bounds.min.z),
        (d.z, bounds.max.z - p1.z),
    ]
}

/// The parameter interval of the segment inside the box, or `None` (also for an
/// empty or non-finite box).
#[must_use]
pub fn box_parameters(p1: DVec3, p2: DVec3, bounds: &Aabb) -> Option<(f64, f64)> {
    if !(p1.in_range() && p2.in_range() && valid_box(bounds)) {
        return None;
    }
    interval(&box_pq(p1, p2, bounds))
}

/// Liang-Barsky 3D against an axis-aligned box (orthographic or parallel view
/// volume): the part of `p1 p2` inside, or `None`.
#[must_use]
pub fn clip_segment_box(p1: DVec3, p2: DVec3, bounds: &Aabb) -> Option<(DVec3, DVec3)> {
    let t = box_parameters(p1, p2, bounds)?;
    Some(endpoints(p1, p2, t, |t| p1 + (p2 - p1) * t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_segments_are_decided_by_q_alone() {
        let r = Rect::new(0., 0., 1., 1.).unwrap();
        // Horizontal at y = 2: p3 = p4 = 0, q4 = 1 - 2 < 0.
        assert_eq!(
            rect_parameters(DVec2::new(-1., 2.), DVec2::new(2., 2.), &r),
            None
        );
        // Horizontal at y = 0.5 across: t in [1/3, 2/3].
        assert_eq!(
            rect_parameters(DVec2::new(-1., 0.5), DVec2::new(2., 0.5), &r),
            Some((1.0 / 3.0, 2.0 / 3.0))
        );
        // A point (zero-length segment) inside and outside.
        let p = DVec2::new(0.5, 0.5);
        assert_eq!(clip_segment_2d(p, p, &r), Some((p, p)));
        assert_eq!(
            clip_segment_2d(DVec2::splat(2.), DVec2::splat(2.), &r),
            None
        );
    }

    #[test]
    fn touching_a_corner_gives_a_point() {
        // The line x + y = 2 touches the unit square at (1, 1) only, at t = 1/2.
        let r = Rect::new(0., 0., 1., 1.).unwrap();
        let t = rect_parameters(DVec2::new(0., 2.), DVec2::new(2., 0.), &r);
        assert_eq!(t, Some((0.5, 0.5)));
    }

    #[test]
    fn non_finite_input_gives_nothing() {
        assert_eq!(homogeneous_parameters(DVec4::NAN, DVec4::W), None);
        let cube = Aabb {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        };
        assert_eq!(box_parameters(DVec3::ZERO, DVec3::INFINITY, &cube), None);
        let bad = Aabb {
            min: DVec3::ZERO,
            max: DVec3::new(1., f64::NAN, 1.),
        };
        assert_eq!(box_parameters(DVec3::ZERO, DVec3::ONE, &bad), None);
    }
}
