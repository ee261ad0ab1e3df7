//! The shadow (occlusion) volume of one convex planar occluder seen from a point, and
//! the test of a box against it.
//!
//! From a perspective eye `e`, the volume is bounded by the plane through `e` and each
//! edge of the occluder, and by the occluder's own plane (its far side): a point inside
//! every edge plane and behind the occluder lies on a line of sight that crosses the
//! occluder first. For a parallel projection along `d` the edge planes contain `d`
//! instead of passing through the eye.
//!
//! # Rounding towards keeping
//! A box is inside only if all eight corners are inside every plane by a margin:
//! - edge planes: [`ShadowVolume::side_margin`], a small angle (perspective, times the
//!   distance from the eye) or length (parallel), a fraction of a pixel chosen by the
//!   caller, so that every pixel sample the box can cover lies strictly inside the
//!   occluder's own outline on the screen;
//! - the occluder's plane: `1e-5` of the distance from the eye (perspective; of the depth
//!   range for a parallel view) plus twice the occluder's flatness, far more than the
//!   depth keys' `f32` resolution, so the occluder wins every depth test against it. A
//!   box touching the occluder's plane, or containing the occluder, is never inside.
//!
//! The eight corners are not visited one by one: for a plane with normal `n`, the
//! smallest `n · x` over a box is `n · centre - |n| · half_extent` (componentwise
//! absolute values), which is exactly the smallest over its corners; the margins use
//! the farthest corner's distance from the eye, which only makes them larger.

use glam::DVec3;

use super::select::Candidate;
use crate::geom::Aabb;

/// Relative depth margin behind the occluder's plane (see the
/// [module documentation](self)).
pub const DEPTH_MARGIN: f64 = 1e-5;

/// Where a box lies relative to a shadow volume.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxClass {
    /// Wholly inside, by the margins: hidden by the occluder.
    Inside,
    /// Wholly outside one bounding plane: the occluder hides nothing of it.
    Outside,
    /// Neither: some of it may be hidden.
    Straddling,
}

/// A plane `n · (x - origin) = 0` with `n` a unit vector towards the inside.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Side {
    normal: DVec3,
    origin: DVec3,
}

/// The shadow volume of one occluder (see the [module documentation](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowVolume {
    sides: Vec<Side>,
    /// The occluder's unit normal, towards the viewer.
    normal: DVec3,
    /// A point of the occluder's plane (its centre).
    centre: DVec3,
    /// The perspective eye; `None` for a parallel projection.
    eye: Option<DVec3>,
    /// Margin of the edge planes: an angle in radians (perspective) or a length
    /// (parallel).
    pub side_margin: f64,
    /// Absolute part of the margin behind the occluder's plane.
    depth_margin: f64,
}

/// Smallest and largest of `n · (x - origin)` over the box.
#[inline]
fn range(n: DVec3, origin: DVec3, b: &Aabb) -> (f64, f64) {
    let c = (b.min + b.max) * 0.5 - origin;
    let h = (b.max - b.min) * 0.5;
    let mid = n.dot(c);
    let r = n.abs().dot(h);
    (mid - r, mid + r)
}

impl ShadowVolume {
    /// The volume of `occluder` seen from the perspective eye `eye`, with edge planes
    /// pulled in by the angle `side_margin` (radians). `None` when the occluder does not
    /// face the eye clearly (the cosine between its normal and the direction to the eye
    /// at most `1e-3`: edge-on, the eye on its plane, seen from behind) or an edge plane
    /// is not defined.
    #[must_use]
    pub fn perspective(occluder: &Candidate, eye: DVec3, side_margin: f64) -> Option<Self> {
        let to_eye = eye - occluder.centre;
        let dist = to_eye.length();
        if !(occluder.normal.dot(to_eye) > 1e-3 * dist) || !eye.is_finite() {
            return None;
        }
        let v = &occluder.vertices;
        let mut sides = Vec::with_capacity(v.len());
        for i in 0..v.len() {
            let (a, b) = (v[i] - eye, v[(i + 1) % v.len()] - eye);
            let n = a.cross(b);
            let len = n.length();
            if !(len > 1e-9 * a.length() * b.length()) {
                return None;
            }
            let mut n = n / len;
            if n.dot(occluder.centre - eye) < 0.0 {
                n = -n;
            }
            sides.push(Side {
                normal: n,
                origin: eye,
            });
        }
        Some(ShadowVolume {
            sides,
            normal: occluder.normal,
            centre: occluder.centre,
            eye: Some(eye),
            side_margin,
            depth_margin: 2.0 * occluder.flatness,
        })
    }

    /// The volume of `occluder` for a parallel projection along `direction`, with edge
    /// planes pulled in by the length `side_margin`, and `depth_range` the view's far
    /// minus near distance (the depth margin is `1e-5` of it). `None` when the occluder
    /// does not face the viewer clearly (cosine at most `1e-3`) or an edge is parallel
    /// to the view direction.
    #[must_use]
    pub fn parallel(
        occluder: &Candidate,
        direction: DVec3,
        side_margin: f64,
        depth_range: f64,
    ) -> Option<Self> {
        let d = direction.normalize_or_zero();
        if !(occluder.normal.dot(-d) > 1e-3) {
            return None;
        }
        let v = &occluder.vertices;
        let mut sides = Vec::with_capacity(v.len());
        for i in 0..v.len() {
            let e = v[(i + 1) % v.len()] - v[i];
            let n = d.cross(e);
            let len = n.length();
            if !(len > 1e-9 * e.length()) {
                return None;
            }
            let mut n = n / len;
            if n.dot(occluder.centre - v[i]) < 0.0 {
                n = -n;
            }
            sides.push(Side {
                normal: n,
                origin: v[i],
            });
        }
        Some(ShadowVolume {
            sides,
            normal: occluder.normal,
            centre: occluder.centre,
            eye: None,
            side_margin,
            depth_margin: 2.0 * occluder.flatness + DEPTH_MARGIN * depth_range.abs(),
        })
    }

    /// Where the box `b` lies (see [`BoxClass`]). Inside only by the margins; an empty
    /// or non-finite box is never inside.
    #[must_use]
    pub fn classify(&self, b: &Aabb) -> BoxClass {
        if !(b.min.is_finite() && b.max.is_finite()) || b.is_empty() {
            return BoxClass::Straddling;
        }
        // The farthest corner's distance from the eye, for the relative margins.
        let (side_tol, depth_tol) = match self.eye {
            Some(e) => {
                let far = (b.min - e).abs().max((b.max - e).abs()).length();
                (
                    self.side_margin * far,
                    self.depth_margin + DEPTH_MARGIN * far,
                )
            }
            None => (self.side_margin, self.depth_margin),
        };
        let mut inside = true;
        // Behind the occluder: n · (x - centre) <= -depth_tol at every corner.
        let (lo, hi) = range(self.normal, self.centre, b);
        if lo > 0.0 {
            return BoxClass::Outside;
        }
        if !(hi <= -depth_tol) {
            inside = false;
        }
        for s in &self.sides {
            let (lo, hi) = range(s.normal, s.origin, b);
            if hi < 0.0 {
                return BoxClass::Outside;
            }
            if !(lo >= side_tol) {
                inside = false;
            }
        }
        if inside {
            BoxClass::Inside
        } else {
            BoxClass::Straddling
        }
    }

    /// Whether the point `p` is inside by the margins (a box of one point).
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        self.classify(&Aabb { min: p, max: p }) == BoxClass::Inside
    }

    /// The number of edge planes.
    #[must_use]
    pub fn edge_planes(&self) -> usize {
        self.sides.len()
    }
}
