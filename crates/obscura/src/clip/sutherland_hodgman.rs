//! Sutherland-Hodgman polygon clipping: the polygon goes through one stage per
//! boundary of a convex clipping region; each stage walks the edges `S -> P` and keeps
//! the inside vertices and the intersections of the edges that cross the boundary.
//!
//! * **Homogeneous 3D** ([`clip_polygon_homogeneous`]): six chained stages, one per
//!   face of the view volume `-w <= x, y, z <= w`, before the divide by `w`. Source:
//!   seed 000, "Αποκοπή Πολυγώνου Sutherland – Hodgman 3Δ": the 2D algorithm with the
//!   inside test replaced by the sign of the plane equation and the line intersection
//!   by a plane-line intersection (the t-formulae (3) of "Περικοπή στο Οπτικό Πεδίο").
//!   This is the form the view pipeline uses.
//! * **2D against any convex window** ([`clip_polygon_2d`]), either winding, one stage
//!   per window edge, inside = half-plane-0 of seed 001 §6.1 (line included).
//! * **3D against an axis-aligned box** ([`clip_polygon_box`]): the orthographic or
//!   parallel view volume (seed 000 eq. (1)), six stages.
//! * **Segments** ([`clip_segment_2d`], [`clip_segment_box`],
//!   [`clip_segment_homogeneous`]): a segment treated as an open polyline of two
//!   vertices, so each stage keeps an inside endpoint and replaces an outside one by
//!   its intersection with the boundary. These are the entry points the tests use to
//!   compare Sutherland-Hodgman with Cohen-Sutherland and Liang-Barsky.
//!
//! # Input, output, complexity
//! A convex polygon of `n` vertices; the clipped polygon (at most `n + k` vertices for
//! `k` stages), empty when fewer than 3 vertices survive. `O(k n)` time. Non-finite
//! input vertices give an empty result in the 2D and box forms.
//!
//! # Watertightness
//! An edge shared by two polygons is traversed in opposite directions by each. The
//! intersection is always computed from the inside endpoint towards the outside one, so
//! both polygons get bit-identical new vertices and no crack opens along the clip plane.
//!
//! # Vertices on a boundary
//! The 2D, box and segment forms create an intersection only when one endpoint is
//! strictly inside and the other strictly outside, so a vertex lying exactly on a
//! boundary is not emitted twice. The homogeneous polygon form keeps the closed test
//! of the pipeline (a vertex on a plane next to an outside vertex may be repeated; the
//! rasterizer ignores zero-length edges).
//!
//! # Limitations
//! The input should be convex (the output of a concave polygon may have overlapping
//! edges, as the algorithm is known to produce). Output vertex count is at most
//! `n + 6` in 3D, `n + m` against an `m`-edge window.

use super::InRange;
use glam::{DVec2, DVec3, DVec4};

use super::ConvexWindow;
use super::cohen_sutherland::valid_box;
use crate::geom::Aabb;

/// A vertex that can be clipped: its clip-space position, and interpolation of
/// everything it carries.
pub trait ClipVertex: Copy {
    /// The clip-space position `(x, y, z, w)`.
    fn clip(&self) -> DVec4;
    /// The vertex at `self + t (other - self)`.
    #[must_use]
    fn lerp(&self, other: &Self, t: f64) -> Self;
}

impl ClipVertex for DVec4 {
    fn clip(&self) -> DVec4 {
        *self
    }
    fn lerp(&self, other: &Self, t: f64) -> Self {
        *self + (*other - *self) * t
    }
}

/// A clip-space position with the eye-space position it came from, so clipped
/// vertices keep their eye coordinates (clip space is linear in eye space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipEyeVertex {
    /// Clip-space position.
    pub clip: DVec4,
    /// Eye-space position.
    pub eye: DVec3,
}

impl ClipVertex for ClipEyeVertex {
    fn clip(&self) -> DVec4 {
        self.clip
    }
    fn lerp(&self, other: &Self, t: f64) -> Self {
        ClipEyeVertex {
            clip: self.clip + (other.clip - self.clip) * t,
            eye: self.eye + (other.eye - self.eye) * t,
        }
    }
}

/// The six planes of the view volume in clip space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipPlane {
    /// `x >= -w`
    Left,
    /// `x <= w`
    Right,
    /// `y >= -w`
    Bottom,
    /// `y <= w`
    Top,
    /// `z >= -w`
    Near,
    /// `z <= w`
    Far,
}

impl ClipPlane {
    /// All six, in the order the stages run.
    pub const ALL: [ClipPlane; 6] = [
        ClipPlane::Near,
        ClipPlane::Far,
        ClipPlane::Left,
        ClipPlane::Right,
        ClipPlane::Bottom,
        ClipPlane::Top,
    ];

    /// The plane equation at `v`: `>= 0` inside.
    #[inline]
    #[must_use]
    pub fn distance(self, v: DVec4) -> f64 {
        match self {
            ClipPlane::Left => v.w + v.x,
            ClipPlane::Right => v.w - v.x,
            ClipPlane::Bottom => v.w + v.y,
            ClipPlane::Top => v.w - v.y,
            ClipPlane::Near => v.w + v.z,
            ClipPlane::Far => v.w - v.z,
        }
    }

    /// The plane of an outcode bit (`OUT_LEFT` ... `OUT_FAR`); `None` for anything
    /// that is not exactly one of those six bits.
    #[must_use]
    pub(crate) fn from_outcode_bit(bit: u8) -> Option<ClipPlane> {
        Some(match bit {
            super::OUT_LEFT => ClipPlane::Left,
            super::OUT_RIGHT => ClipPlane::Right,
            super::OUT_BOTTOM => ClipPlane::Bottom,
            super::OUT_TOP => ClipPlane::Top,
            super::OUT_NEAR => ClipPlane::Near,
            super::OUT_FAR => ClipPlane::Far,
            _ => return None,
        })
    }

    /// Where the line `p1 + t (p2 - p1)` meets this plane: seed 000's t-formulae (3),
    /// written exactly as there, e.g. left `t = (x1 + w1) / ((x1 - x2) + (w1 - w2))`,
    /// right `t = (x1 - w1) / ((x1 - x2) + (w2 - w1))`. Not finite when the segment
    /// is parallel to the plane; callers split only segments whose endpoints are on
    /// either side.
    ///
    /// ```
    /// use obscura::clip::sutherland_hodgman::ClipPlane;
    /// use glam::DVec4;
    /// let (p1, p2) = (DVec4::new(0., 0., 0., 1.), DVec4::new(3., 0., 0., 1.));
    /// // right: (0 - 1) / ((0 - 3) + (1 - 1)) = 1/3
    /// assert_eq!(ClipPlane::Right.intersection_t(p1, p2), 1.0 / 3.0);
    /// ```
    #[inline]
    #[must_use]
    pub fn intersection_t(self, p1: DVec4, p2: DVec4) -> f64 {
        let (w1, w2) = (p1.w, p2.w);
        match self {
            ClipPlane::Left => (p1.x + w1) / ((p1.x - p2.x) + (w1 - w2)),
            ClipPlane::Right => (p1.x - w1) / ((p1.x - p2.x) + (w2 - w1)),
            ClipPlane::Bottom => (p1.y + w1) / ((p1.y - p2.y) + (w1 - w2)),
            ClipPlane::Top => (p1.y - w1) / ((p1.y - p2.y) + (w2 - w1)),
            ClipPlane::Near => (p1.z + w1) / ((p1.z - p2.z) + (w1 - w2)),
            ClipPlane::Far => (p1.z - w1) / ((p1.z - p2.z) + (w2 - w1)),
        }
    }

    /// `v` with the coordinate of this plane set so that it lies exactly on it
    /// (`x = -w` for left, `x = w` for right, ...): an intersection computed in
    /// floating point may land a few ulps off the plane.
    #[inline]
    #[must_use]
    pub(crate) fn snap_onto(self, mut v: DVec4) -> DVec4 {
        match self {
            ClipPlane::Left => v.x = -v.w,
            ClipPlane::Right => v.x = v.w,
            ClipPlane::Bottom => v.y = -v.w,
            ClipPlane::Top => v.y = v.w,
            ClipPlane::Near => v.z = -v.w,
            ClipPlane::Far => v.z = v.w,
        }
        v
    }

    /// The outcode bit of this plane.
    #[must_use]
    pub(crate) fn outcode_bit(self) -> u8 {
        match self {
            ClipPlane::Left => super::OUT_LEFT,
            ClipPlane::Right => super::OUT_RIGHT,
            ClipPlane::Bottom => super::OUT_BOTTOM,
            ClipPlane::Top => super::OUT_TOP,
            ClipPlane::Near => super::OUT_NEAR,
            ClipPlane::Far => super::OUT_FAR,
        }
    }
}

/// One stage: clips `input` against `plane` into `out` (cleared first).
pub fn clip_polygon_to_plane<V: ClipVertex>(input: &[V], plane: ClipPlane, out: &mut Vec<V>) {
    out.clear();
    let n = input.len();
    if n == 0 {
        return;
    }
    let mut s = input[n - 1];
    let mut ds = plane.distance(s.clip());
    for &p in input {
        let dp = plane.distance(p.clip());
        let (s_in, p_in) = (ds >= 0.0, dp >= 0.0);
        if p_in {
            if !s_in {
                out.push(p.lerp(&s, dp / (dp - ds)));
            }
            out.push(p);
        } else if s_in {
            out.push(s.lerp(&p, ds / (ds - dp)));
        }
        s = p;
        ds = dp;
    }
}

/// Clips a convex polygon against the whole view volume, only through the planes in
/// `planes_mask` (outcode bits; `0x3f` for all six). The result is in `out`; it is
/// empty when nothing is inside, and for a vertex out of range (see the module doc of
/// [`crate::clip`]). `scratch` is reused between calls.
pub fn clip_polygon_homogeneous_masked<V: ClipVertex>(
    input: &[V],
    planes_mask: u8,
    out: &mut Vec<V>,
    scratch: &mut Vec<V>,
) {
    out.clear();
    if input.iter().any(|v| !v.clip().in_range()) {
        return;
    }
    out.extend_from_slice(input);
    for plane in ClipPlane::ALL {
        if planes_mask & plane.outcode_bit() == 0 {
            continue;
        }
        clip_polygon_to_plane(out, plane, scratch);
        std::mem::swap(out, scratch);
        if out.len() < 3 {
            out.clear();
            return;
        }
    }
}

/// Clips a convex polygon against the view volume `-w <= x, y, z <= w`.
///
/// ```
/// use obscura::clip::sutherland_hodgman::clip_polygon_homogeneous;
/// use glam::DVec4;
/// // A triangle with one vertex behind the eye (w < 0) is cut by the near plane.
/// let tri = [DVec4::new(0., 0., 0., 1.), DVec4::new(0.5, 0., 0., 1.), DVec4::new(0., 0.5, -3., -1.)];
/// let out = clip_polygon_homogeneous(&tri);
/// assert!(out.len() >= 3);
/// assert!(out.iter().all(|v| v.w > 0.0 && v.z >= -v.w - 1e-12));
/// ```
#[must_use]
pub fn clip_polygon_homogeneous<V: ClipVertex>(input: &[V]) -> Vec<V> {
    let mut out = Vec::with_capacity(input.len() + 6);
    let mut scratch = Vec::with_capacity(input.len() + 6);
    clip_polygon_homogeneous_masked(input, 0x3f, &mut out, &mut scratch);
    out
}

/// One stage against a boundary given by its signed distance (`>= 0` inside), for
/// plain point types. Intersections only for strict crossings (see the module doc).
fn stage<V: Copy>(
    input: &[V],
    distance: impl Fn(V) -> f64,
    lerp: impl Fn(V, V, f64) -> V,
    out: &mut Vec<V>,
) {
    out.clear();
    let Some(&last) = input.last() else {
        return;
    };
    let mut s = last;
    let mut ds = distance(s);
    for &p in input {
        let dp = distance(p);
        if dp >= 0.0 {
            if ds < 0.0 && dp > 0.0 {
                out.push(lerp(p, s, dp / (dp - ds)));
            }
            out.push(p);
        } else if ds > 0.0 {
            out.push(lerp(s, p, ds / (ds - dp)));
        }
        s = p;
        ds = dp;
    }
}

/// One stage for a segment (an open polyline of two vertices): `None` when both
/// endpoints are outside, else the outside endpoint (if any) moved onto the boundary,
/// computed from the inside endpoint.
#[inline]
fn segment_stage<V: Copy>(
    a: V,
    b: V,
    da: f64,
    db: f64,
    lerp: impl Fn(V, V, f64) -> V,
) -> Option<(V, V)> {
    match (da >= 0.0, db >= 0.0) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        (false, true) => Some((lerp(b, a, db / (db - da)), b)),
        (true, false) => Some((a, lerp(a, b, da / (da - db)))),
    }
}

fn lerp2(a: DVec2, b: DVec2, t: f64) -> DVec2 {
    a + (b - a) * t
}

fn lerp3(a: DVec3, b: DVec3, t: f64) -> DVec3 {
    a + (b - a) * t
}

/// Sutherland-Hodgman 2D: a convex polygon clipped by a convex window (either
/// winding for both), one stage per window edge in edge order. The output keeps the
/// input's winding; it is empty when nothing (of positive extent) is inside, or when
/// the input has a non-finite vertex.
///
/// ```
/// use obscura::clip::{ConvexWindow, Rect, sutherland_hodgman::clip_polygon_2d};
/// use glam::DVec2;
/// let window = ConvexWindow::rectangle(&Rect::new(0., 0., 2., 2.).unwrap());
/// let tri = [DVec2::new(1., 1.), DVec2::new(3., 1.), DVec2::new(1., 3.)];
/// // The triangle's part inside is the square [1,2]^2.
/// let out = clip_polygon_2d(&tri, &window);
/// assert_eq!(out, vec![DVec2::new(1., 2.), DVec2::new(1., 1.), DVec2::new(2., 1.), DVec2::new(2., 2.)]);
/// ```
#[must_use]
pub fn clip_polygon_2d(polygon: &[DVec2], window: &ConvexWindow) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(polygon.len() + window.edge_count());
    let mut scratch = Vec::with_capacity(polygon.len() + window.edge_count());
    clip_polygon_2d_into(polygon, window, &mut out, &mut scratch);
    out
}

/// [`clip_polygon_2d`] into `out` (cleared first), with `scratch` reused between
/// calls: no allocation once the buffers have grown.
pub fn clip_polygon_2d_into(
    polygon: &[DVec2],
    window: &ConvexWindow,
    out: &mut Vec<DVec2>,
    scratch: &mut Vec<DVec2>,
) {
    out.clear();
    if polygon.iter().any(|p| !p.in_range()) {
        return;
    }
    out.extend_from_slice(polygon);
    for i in 0..window.edge_count() {
        stage(out, |p| window.edge_value(i, p), lerp2, scratch);
        std::mem::swap(out, scratch);
        if out.len() < 3 {
            out.clear();
            return;
        }
    }
}

/// Sutherland-Hodgman 2D on a segment (an open polyline of two vertices): the part of
/// `a b` inside the convex window, endpoints in the same order, or `None`.
#[must_use]
pub fn clip_segment_2d(a: DVec2, b: DVec2, window: &ConvexWindow) -> Option<(DVec2, DVec2)> {
    if !(a.in_range() && b.in_range()) {
        return None;
    }
    let (mut a, mut b) = (a, b);
    for i in 0..window.edge_count() {
        let (da, db) = (window.edge_value(i, a), window.edge_value(i, b));
        (a, b) = segment_stage(a, b, da, db, lerp2)?;
    }
    Some((a, b))
}

/// The six boundaries of an axis-aligned box as (axis, bound, sign): the signed
/// distance is `sign * (p[axis] - bound)`, in the stage order of [`ClipPlane::ALL`]
/// (near = `z >= zmin`, far, left, right, bottom, top).
fn box_boundaries(bounds: &Aabb) -> [(usize, f64, f64); 6] {
    [
        (2, bounds.min.z, 1.0),
        (2, bounds.max.z, -1.0),
        (0, bounds.min.x, 1.0),
        (0, bounds.max.x, -1.0),
        (1, bounds.min.y, 1.0),
        (1, bounds.max.y, -1.0),
    ]
}

/// Sutherland-Hodgman 3D against an axis-aligned box (the orthographic or parallel view
/// volume): six chained stages in the order of [`ClipPlane::ALL`]. For the cube
/// `[-1, 1]^3` it computes the same vertices as [`clip_polygon_homogeneous`] with
/// `w = 1`. Empty output for an empty or non-finite box or a non-finite vertex.
///
/// ```
/// use obscura::clip::sutherland_hodgman::clip_polygon_box;
/// use obscura::geom::Aabb;
/// use glam::DVec3;
/// let unit = Aabb { min: DVec3::ZERO, max: DVec3::ONE };
/// let tri = [DVec3::new(0.5, 0.5, -1.), DVec3::new(0.5, 0.5, 2.), DVec3::new(0.5, 0.8, 0.5)];
/// let out = clip_polygon_box(&tri, &unit);
/// assert!(out.iter().all(|p| p.z >= 0.0 && p.z <= 1.0));
/// ```
#[must_use]
pub fn clip_polygon_box(polygon: &[DVec3], bounds: &Aabb) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(polygon.len() + 6);
    let mut scratch = Vec::with_capacity(polygon.len() + 6);
    clip_polygon_box_into(polygon, bounds, &mut out, &mut scratch);
    out
}

/// [`clip_polygon_box`] into `out` (cleared first), with `scratch` reused between
/// calls: no allocation once the buffers have grown.
pub fn clip_polygon_box_into(
    polygon: &[DVec3],
    bounds: &Aabb,
    out: &mut Vec<DVec3>,
    scratch: &mut Vec<DVec3>,
) {
    out.clear();
    if !valid_box(bounds) || polygon.iter().any(|p| !p.in_range()) {
        return;
    }
    out.extend_from_slice(polygon);
    for (axis, bound, sign) in box_boundaries(bounds) {
        stage(out, |p| sign * (p[axis] - bound), lerp3, scratch);
        std::mem::swap(out, scratch);
        if out.len() < 3 {
            out.clear();
            return;
        }
    }
}

/// Sutherland-Hodgman on a segment against an axis-aligned box; `None` when nothing
/// is inside (or for an empty or non-finite box).
#[must_use]
pub fn clip_segment_box(a: DVec3, b: DVec3, bounds: &Aabb) -> Option<(DVec3, DVec3)> {
    if !(a.in_range() && b.in_range() && valid_box(bounds)) {
        return None;
    }
    let (mut a, mut b) = (a, b);
    for (axis, bound, sign) in box_boundaries(bounds) {
        let (da, db) = (sign * (a[axis] - bound), sign * (b[axis] - bound));
        (a, b) = segment_stage(a, b, da, db, lerp3)?;
    }
    Some((a, b))
}

/// Sutherland-Hodgman on a segment in homogeneous clip space, against
/// `-w <= x, y, z <= w`, six stages in the order of [`ClipPlane::ALL`].
#[must_use]
pub fn clip_segment_homogeneous(a: DVec4, b: DVec4) -> Option<(DVec4, DVec4)> {
    if !(a.in_range() && b.in_range()) {
        return None;
    }
    let (mut a, mut b) = (a, b);
    for plane in ClipPlane::ALL {
        let (da, db) = (plane.distance(a), plane.distance(b));
        (a, b) = segment_stage(a, b, da, db, |p, q, t| p + (q - p) * t)?;
    }
    Some((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_polygon_is_unchanged() {
        let tri = [
            DVec4::new(0., 0., 0., 1.),
            DVec4::new(0.5, 0., 0., 1.),
            DVec4::new(0., 0.5, 0.5, 1.),
        ];
        assert_eq!(clip_polygon_homogeneous(&tri), tri.to_vec());
    }

    #[test]
    fn outside_polygon_vanishes() {
        let tri = [
            DVec4::new(2., 0., 0., 1.),
            DVec4::new(3., 0., 0., 1.),
            DVec4::new(2., 0.5, 0.5, 1.),
        ];
        assert!(clip_polygon_homogeneous(&tri).is_empty());
    }

    #[test]
    fn shared_edges_get_identical_vertices() {
        let a = DVec4::new(-0.3, -0.2, 0.1, 1.0);
        let b = DVec4::new(1.7, 0.4, -0.2, 1.0);
        let c = DVec4::new(0.1, 0.9, 0.3, 1.0);
        let d = DVec4::new(0.2, -0.9, 0.0, 1.0);
        let t1 = clip_polygon_homogeneous(&[a, b, c]);
        let t2 = clip_polygon_homogeneous(&[b, a, d]);
        let on_plane = |v: &DVec4| (v.x - v.w).abs() < 1e-12;
        let p1: Vec<_> = t1.iter().filter(|v| on_plane(v) && v.y < 0.5).collect();
        let p2: Vec<_> = t2.iter().filter(|v| on_plane(v) && v.y > -0.5).collect();
        // The intersection of edge a-b with x = w must be bit-identical in both.
        assert!(
            p1.iter().any(|v| p2.iter().any(|u| u == v)),
            "{t1:?} {t2:?}"
        );
    }

    #[test]
    fn eye_coordinates_follow_clip_coordinates() {
        let v = |x: f64, z: f64| ClipEyeVertex {
            clip: DVec4::new(x, 0.0, z, 1.0),
            eye: DVec3::new(x * 10.0, 0.0, z),
        };
        let out = clip_polygon_homogeneous(&[v(0.0, 0.0), v(3.0, 0.0), v(0.0, 0.5)]);
        for o in &out {
            assert!((o.eye.x - o.clip.x * 10.0).abs() < 1e-12);
        }
    }
}
