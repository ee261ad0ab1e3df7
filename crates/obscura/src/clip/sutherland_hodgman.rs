//! Sutherland-Hodgman polygon clipping in homogeneous coordinates: six chained stages,
//! one per face of the view volume, before the divide by `w`.
//!
//! Source: seed 000, "Αποκοπή Πολυγώνου Sutherland – Hodgman 3Δ": the 2D algorithm
//! with the inside test replaced by the sign of the plane equation and the line
//! intersection by a plane-line intersection (the t-formulae (3) of "Περικοπή στο
//! Οπτικό Πεδίο").
//!
//! # Watertightness
//! An edge shared by two polygons is traversed in opposite directions by each. The
//! intersection is always computed from the inside endpoint towards the outside one, so
//! both polygons get bit-identical new vertices and no crack opens along the clip plane.
//!
//! # Limitations
//! The input should be convex (the output of a concave polygon may have overlapping
//! edges, as the algorithm is known to produce). Output vertex count is at most
//! `n + 6`.

use glam::{DVec3, DVec4};

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

    /// The outcode bit of this plane.
    #[must_use]
    pub fn outcode_bit(self) -> u8 {
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
/// empty when nothing is inside. `scratch` is reused between calls.
pub fn clip_polygon_homogeneous_masked<V: ClipVertex>(
    input: &[V],
    planes_mask: u8,
    out: &mut Vec<V>,
    scratch: &mut Vec<V>,
) {
    out.clear();
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
