//! Cutting one edge: its part inside the view volume, and the parameter interval each
//! occluder hides.
//!
//! Clip coordinates are affine in the point, so clipping the segment `A + t (B - A)`
//! against the six planes `-w <= x, y, z <= w` (Liang and Barsky's parametric
//! clipping) gives an interval of the edge's own parameter `t`. The part an occluder
//! hides is the segment clipped by the occluder's side planes (closed: a point on the
//! image of the occluder's boundary is covered) and by its plane (strictly behind);
//! each is the sign of a function affine in `t`, so each bound is `t = f(A) / (f(A) -
//! f(B))`, with the signs at `A` and `B` exact (see [`super::occluders`]).

use glam::{DVec2, DVec3, DVec4};

use super::occluders::{Occluder, Occluders, PredicateCounters};
use crate::view::ViewTransform;

/// An edge ready to be cut: its ends in world and clip space, its part inside the view
/// volume and that part's image.
#[derive(Clone, Copy, Debug)]
pub(super) struct EdgeSetup {
    pub world: [DVec3; 2],
    pub clip: [DVec4; 2],
    /// The parameter interval inside the view volume.
    pub t: [f64; 2],
    /// The image of that interval's ends, in pixels.
    pub screen: [[f64; 2]; 2],
    /// The largest eye-space depth of the part inside the view volume.
    pub far_depth: f64,
}

impl EdgeSetup {
    /// `None` when no part of the edge of world ends `world` is inside the view volume
    /// (or the edge has no length).
    pub fn new(t: &ViewTransform, world: [DVec3; 2]) -> Option<EdgeSetup> {
        if world[0] == world[1] || !(world[0].is_finite() && world[1].is_finite()) {
            return None;
        }
        let eye = world.map(|w| t.world_to_eye(w));
        let clip = [t.eye_to_clip(eye[0]), t.eye_to_clip(eye[1])];
        let range = clip_parameter(clip)?;
        let screen = range.map(|u| {
            let p = pixel(t, clip, u);
            [p.x, p.y]
        });
        let depth = |u: f64| -(eye[0].z + (eye[1].z - eye[0].z) * u);
        Some(EdgeSetup {
            world,
            clip,
            t: range,
            screen,
            far_depth: depth(range[0]).max(depth(range[1])),
        })
    }
}

/// The image in pixels of the point at parameter `u` of the segment with clip-space
/// ends `clip` (x right, y down, as a `Frame`).
pub(super) fn pixel(t: &ViewTransform, clip: [DVec4; 2], u: f64) -> DVec2 {
    t.clip_to_pixel(clip[0] + (clip[1] - clip[0]) * u)
}

/// The parameter interval of the segment `clip[0] -> clip[1]` inside the view volume
/// `-w <= x, y, z <= w` (Liang-Barsky), `None` when empty or a single point.
pub(super) fn clip_parameter(clip: [DVec4; 2]) -> Option<[f64; 2]> {
    crate::clip::liang_barsky::homogeneous_parameters(clip[0], clip[1])
        .filter(|(lo, hi)| lo < hi)
        .map(|(lo, hi)| [lo, hi])
}

/// The part of an edge one occluder hides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cover {
    /// Parameter interval (within the edge's visible range).
    pub t: [f64; 2],
    /// The occluder's face id.
    pub face: u32,
    /// Whether the edge's image lies on the line of one of the occluder's sides: it is
    /// covered only by the occluder's boundary.
    pub boundary: bool,
}

/// Narrows `[lo, hi]` to where the affine function of values `fa` (at t = 0) and `fb`
/// (at t = 1) is positive, or non-negative when `closed`; false when nothing is left.
#[inline]
fn keep(fa: f64, fb: f64, closed: bool, lo: &mut f64, hi: &mut f64) -> bool {
    let (ina, inb) = if closed {
        (fa >= 0.0, fb >= 0.0)
    } else {
        (fa > 0.0, fb > 0.0)
    };
    match (ina, inb) {
        (true, true) => true,
        (false, false) => false,
        (false, true) => {
            *lo = lo.max(fa / (fa - fb));
            *lo < *hi
        }
        (true, false) => {
            *hi = hi.min(fa / (fa - fb));
            *lo < *hi
        }
    }
}

/// The interval of the edge that `o` covers in the image and lies strictly behind
/// (closed on the occluder's boundary); `None` when it hides no open interval.
pub(super) fn cover(
    occluders: &Occluders,
    o: &Occluder,
    edge: &EdgeSetup,
    counters: &mut PredicateCounters,
) -> Option<Cover> {
    let [a, b] = edge.world;
    let (mut lo, mut hi) = (edge.t[0], edge.t[1]);
    // The plane first: it rejects the occluders behind the edge with two values.
    let (ga, gb) = (o.plane.value(a, counters), o.plane.value(b, counters));
    if !keep(ga, gb, false, &mut lo, &mut hi) {
        return None;
    }
    let mut boundary = false;
    for s in occluders.sides_of(o) {
        let (fa, fb) = (s.value(a, counters), s.value(b, counters));
        if fa == 0.0 && fb == 0.0 {
            boundary = true;
            continue;
        }
        if !keep(fa, fb, true, &mut lo, &mut hi) {
            return None;
        }
    }
    Some(Cover {
        t: [lo, hi],
        face: o.face,
        boundary,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_parameter_keeps_the_inside() {
        let c = |x: f64| DVec4::new(x, 0.0, 0.0, 1.0);
        assert_eq!(clip_parameter([c(-3.0), c(1.0)]), Some([0.5, 1.0]));
        assert_eq!(clip_parameter([c(-0.5), c(0.5)]), Some([0.0, 1.0]));
        assert_eq!(clip_parameter([c(2.0), c(3.0)]), None);
        // Through the eye plane: w from -1 to 3, z = 0; inside from w >= |x| ...
        let a = DVec4::new(0.0, 0.0, 0.0, -1.0);
        let b = DVec4::new(0.0, 0.0, 0.0, 3.0);
        assert_eq!(clip_parameter([a, b]), Some([0.25, 1.0]));
    }

    #[test]
    fn keep_narrows_by_sign_changes() {
        let (mut lo, mut hi) = (0.0, 1.0);
        assert!(keep(-1.0, 3.0, true, &mut lo, &mut hi));
        assert_eq!((lo, hi), (0.25, 1.0));
        assert!(keep(1.0, -1.0, false, &mut lo, &mut hi));
        assert_eq!((lo, hi), (0.25, 0.5));
        assert!(!keep(0.0, 0.0, false, &mut lo, &mut hi));
        assert!(keep(0.0, 0.0, true, &mut lo, &mut hi));
        assert!(!keep(-1.0, -0.5, true, &mut lo, &mut hi));
    }
}
