//! Clipping before or after the projection: the two places seed 001's introduction
//! (Chapter 6) puts clipping, both implemented so they can be compared.
//!
//! 1. **Before the projection** ([`clip_segment_before_projection`],
//!    [`clip_polygon_before_projection`]): clip in 3D against the view volume, here in
//!    homogeneous clip space `-w <= x, y, z <= w` before the divide by `w`
//!    (Sutherland-Hodgman), then divide. Costs 3D work, but the near and far planes
//!    reject what is too close or too far, and a primitive crossing the eye plane
//!    `w = 0` keeps exactly its part in front of the eye.
//! 2. **After the projection** ([`clip_segment_after_projection`],
//!    [`clip_polygon_after_projection`]): divide every vertex by `w` first, then clip
//!    the 2D projection against the window `[-1, 1]^2` (Cohen-Sutherland for segments,
//!    as seed 001 suggests for the rectangle; 2D Sutherland-Hodgman for polygons).
//!    Cheaper in 2D, but (a) nothing is rejected by depth: a primitive beyond the far
//!    plane or before the near plane is kept, and (b) every vertex is projected, even
//!    those later thrown away. Worse, a vertex behind the eye (`w < 0`) projects to
//!    the mirror image of where it should go, so a primitive crossing `w = 0` comes
//!    out wrong: this is why the view pipeline ([`crate::view`]) clips before the
//!    divide.
//!
//! For primitives entirely in front of the eye and between the near and far planes
//! the two modes agree (projection maps segments to segments and the view volume's
//! side planes to the window's edges); the tests check that, and the failure.
//!
//! # Input and output
//! Clip-space vertices (`DVec4`, e.g. eye space times a perspective matrix); the
//! visible part in normalized device coordinates `(x/w, y/w)`. After projection, a
//! vertex with `w = 0` has no image and gives `None` (or an empty polygon); non-finite
//! input too.
//!
//! # Complexity
//! `O(1)` per segment, `O(n)` per `n`-gon (six or four stages).
//!
//! Paper: Blinn and Newell, "Clipping using homogeneous coordinates", SIGGRAPH 1978.

use super::InRange;
use glam::{DVec2, DVec4};

use super::{ConvexWindow, Rect, cohen_sutherland, sutherland_hodgman};

fn divide(v: DVec4) -> DVec2 {
    DVec2::new(v.x / v.w, v.y / v.w)
}

/// Mode 1 for a segment: clip in homogeneous space, then divide. `None` when nothing
/// of the segment is in the view volume (with `w > 0`).
///
/// ```
/// use obscura::clip::projection_order::clip_segment_before_projection;
/// use glam::{DVec2, DVec4};
/// // From inside to behind the eye (w < 0): only the part with w > 0 remains, from
/// // (0.5, 0) to where it leaves through x = w at t = 1/6, (2/3)/(2/3) = (1, 0).
/// let (a, b) = clip_segment_before_projection(DVec4::new(0.5, 0., 0., 1.), DVec4::new(1.5, 0., 0., -1.)).unwrap();
/// assert_eq!(a, DVec2::new(0.5, 0.));
/// assert!((b - DVec2::new(1., 0.)).length() < 1e-12);
/// ```
#[must_use]
pub fn clip_segment_before_projection(a: DVec4, b: DVec4) -> Option<(DVec2, DVec2)> {
    let (a, b) = sutherland_hodgman::clip_segment_homogeneous(a, b)?;
    // The only point of the volume with w = 0 is the eye itself (x = y = z = w = 0),
    // which has no projection.
    if !(a.w > 0.0 && b.w > 0.0) {
        return None;
    }
    Some((divide(a), divide(b)))
}

/// Mode 2 for a segment: divide both endpoints by `w`, then clip the projected segment
/// against the window `[-1, 1]^2` with Cohen-Sutherland. Wrong for a segment crossing
/// `w = 0`, and does not clip depth (see the module doc).
///
/// ```
/// use obscura::clip::projection_order::clip_segment_after_projection;
/// use glam::{DVec2, DVec4};
/// // The same segment as in `clip_segment_before_projection`: its far end projects to
/// // (1.5 / -1, 0) = (-1.5, 0), on the wrong side, and the "visible" part found goes
/// // left from (0.5, 0) to (-1, 0) instead of right to (1, 0).
/// let (a, b) = clip_segment_after_projection(DVec4::new(0.5, 0., 0., 1.), DVec4::new(1.5, 0., 0., -1.)).unwrap();
/// assert_eq!((a, b), (DVec2::new(0.5, 0.), DVec2::new(-1., 0.)));
/// ```
#[must_use]
pub fn clip_segment_after_projection(a: DVec4, b: DVec4) -> Option<(DVec2, DVec2)> {
    if a.w == 0.0 || b.w == 0.0 {
        return None;
    }
    cohen_sutherland::clip_segment_2d(divide(a), divide(b), &Rect::NDC)
}

/// Mode 1 for a convex polygon: Sutherland-Hodgman in homogeneous space (six
/// stages), then divide. Empty when nothing is visible.
#[must_use]
pub fn clip_polygon_before_projection(polygon: &[DVec4]) -> Vec<DVec2> {
    if polygon.iter().any(|v| !v.in_range()) {
        return Vec::new();
    }
    let clipped = sutherland_hodgman::clip_polygon_homogeneous(polygon);
    if clipped.iter().any(|v| !(v.w > 0.0)) {
        return Vec::new();
    }
    clipped.into_iter().map(divide).collect()
}

/// Mode 2 for a convex polygon: divide every vertex, then 2D Sutherland-Hodgman
/// against `[-1, 1]^2`. Wrong for a polygon crossing `w = 0`.
#[must_use]
pub fn clip_polygon_after_projection(polygon: &[DVec4]) -> Vec<DVec2> {
    if polygon.iter().any(|v| v.w == 0.0) {
        return Vec::new();
    }
    let projected: Vec<DVec2> = polygon.iter().copied().map(divide).collect();
    sutherland_hodgman::clip_polygon_2d(&projected, &ConvexWindow::rectangle(&Rect::NDC))
}
