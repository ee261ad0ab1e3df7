//! Clipping: every algorithm of the seeds, each a documented public function.
//!
//! | algorithm | function | seed |
//! | --- | --- | --- |
//! | outcodes of the view volume (6 bits, seed's bit order) | [`outcode_homogeneous`] | 000 |
//! | Sutherland-Hodgman 3D, homogeneous, six chained stages | [`sutherland_hodgman::clip_polygon_homogeneous`] | 000 |
//! | split a convex polygon by a plane into front and back pieces | [`split::split_polygon`] | 000 (BSP) |
//!
//! Clip space is OpenGL's: the view volume is `-w <= x, y, z <= w`. Clipping happens
//! before the divide by `w`, which is what makes primitives crossing the eye plane
//! (`w <= 0`) come out right.

pub mod split;
pub mod sutherland_hodgman;

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
    let mut c = 0;
    if v.x < -v.w {
        c |= OUT_LEFT;
    }
    if v.x > v.w {
        c |= OUT_RIGHT;
    }
    if v.y < -v.w {
        c |= OUT_BOTTOM;
    }
    if v.y > v.w {
        c |= OUT_TOP;
    }
    if v.z < -v.w {
        c |= OUT_NEAR;
    }
    if v.z > v.w {
        c |= OUT_FAR;
    }
    // NaN coordinates fail every comparison: count them as outside everything.
    if v.is_nan() {
        c = 0x3f;
    }
    c
}
