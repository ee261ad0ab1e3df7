//! The view volume `-w <= x, y, z <= w` of clip space: its six planes ([`ClipPlane`])
//! and the 6-bit outcodes of points against them ([`outcode_homogeneous`], seed 000;
//! the region codes of Cohen and Sutherland, in Newman and Sproull, "Principles of
//! Interactive Computer Graphics", 2nd ed., 1979). Shared by the Cohen-Sutherland and
//! Sutherland-Hodgman clippers, which both import it (and not each other).

use glam::DVec4;

/// Outcode bit: `x < -w` (left). The seed (000) writes the 6-digit code as
/// `z>zmax, z<zmin, y>ymax, y<ymin, x>xmax, x<xmin` from the most significant digit down.
pub const OUT_LEFT: u8 = 1 << 0;
/// Outcode bit: `x > w` (right).
pub const OUT_RIGHT: u8 = 1 << 1;
/// Outcode bit: `y < -w` (bottom).
pub const OUT_BOTTOM: u8 = 1 << 2;
/// Outcode bit: `y > w` (top).
pub const OUT_TOP: u8 = 1 << 3;
/// Outcode bit: `z < -w` (near).
pub const OUT_NEAR: u8 = 1 << 4;
/// Outcode bit: `z > w` (far).
pub const OUT_FAR: u8 = 1 << 5;

/// The 6-bit region code of a clip-space point against `-w <= x, y, z <= w`; 0 inside.
/// Two points with `c1 & c2 != 0` bound a segment entirely outside one plane.
///
/// ```
/// use obscura::clip::{outcode_homogeneous, OUT_FAR, OUT_LEFT};
/// use glam::DVec4;
/// assert_eq!(outcode_homogeneous(DVec4::new(0., 0., 0., 1.)), 0);
/// assert_eq!(outcode_homogeneous(DVec4::new(-2., 0., 3., 1.)), OUT_LEFT | OUT_FAR);
/// ```
#[inline]
#[must_use]
pub fn outcode_homogeneous(v: DVec4) -> u8 {
    // Without branches (each bit is a compare and a select), so that a caller
    // transforming points lane by lane keeps them in vector lanes.
    let bit = |out: bool, code: u8| if out { code } else { 0 };
    let c = bit(v.x < -v.w, OUT_LEFT)
        | bit(v.x > v.w, OUT_RIGHT)
        | bit(v.y < -v.w, OUT_BOTTOM)
        | bit(v.y > v.w, OUT_TOP)
        | bit(v.z < -v.w, OUT_NEAR)
        | bit(v.z > v.w, OUT_FAR);
    // NaN coordinates fail every comparison: count them as outside everything.
    if v.is_nan() { 0x3f } else { c }
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
    pub fn from_outcode_bit(bit: u8) -> Option<ClipPlane> {
        Some(match bit {
            OUT_LEFT => ClipPlane::Left,
            OUT_RIGHT => ClipPlane::Right,
            OUT_BOTTOM => ClipPlane::Bottom,
            OUT_TOP => ClipPlane::Top,
            OUT_NEAR => ClipPlane::Near,
            OUT_FAR => ClipPlane::Far,
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
    pub fn snap_onto(self, mut v: DVec4) -> DVec4 {
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
    pub fn outcode_bit(self) -> u8 {
        match self {
            ClipPlane::Left => OUT_LEFT,
            ClipPlane::Right => OUT_RIGHT,
            ClipPlane::Bottom => OUT_BOTTOM,
            ClipPlane::Top => OUT_TOP,
            ClipPlane::Near => OUT_NEAR,
            ClipPlane::Far => OUT_FAR,
        }
    }
}
