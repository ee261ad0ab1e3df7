//! Clipping: every algorithm of the seeds, each a documented public function.
//!
//! | algorithm | region | function | seed |
//! | --- | --- | --- | --- |
//! | outcodes of the view volume (6 bits, seed's bit order) | `-w <= x, y, z <= w` | [`outcode_homogeneous`] | 000 |
//! | Cohen-Sutherland 2D: 4-bit codes (eq. 6.5), 9 regions, iterative | rectangle | [`cohen_sutherland::clip_segment_2d`] | 001 §6.1.1 |
//! | Cohen-Sutherland 3D: 6-bit codes, 27 regions, recursive `CS_Clip_3D` | box | [`cohen_sutherland::clip_segment_box`] | 000 |
//! | Cohen-Sutherland 3D with the t-formulae (3) | homogeneous | [`cohen_sutherland::clip_segment_homogeneous`] | 000 |
//! | segment vs any convex polygon, `n`-bit region codes, XOR, sorted `T_i` | convex window | [`region_codes::clip_segment`], [`region_codes::clip_segment_traced`] | 001 §6.1.1 |
//! | Liang-Barsky, `t p_i <= q_i` | rectangle | [`liang_barsky::clip_segment_2d`] | 000 (2D form) |
//! | Liang-Barsky 3D, the seed's p/q table | homogeneous | [`liang_barsky::clip_segment_homogeneous`] | 000 |
//! | Liang-Barsky 3D, orthographic cube form | box | [`liang_barsky::clip_segment_box`] | 000 |
//! | Sutherland-Hodgman 3D, six chained stages (the view pipeline's) | homogeneous | [`sutherland_hodgman::clip_polygon_homogeneous`] | 000 |
//! | Sutherland-Hodgman 2D, one stage per window edge | convex window | [`sutherland_hodgman::clip_polygon_2d`] | 000, 001 §6.1 |
//! | Sutherland-Hodgman 3D, parallel projection | box | [`sutherland_hodgman::clip_polygon_box`] | 000 |
//! | Sutherland-Hodgman on a segment (open 2-vertex polyline) | all three | [`sutherland_hodgman::clip_segment_2d`], [`sutherland_hodgman::clip_segment_box`], [`sutherland_hodgman::clip_segment_homogeneous`] | 000 |
//! | clipping before vs after the projection | both | [`projection_order`] | 001 introduction |
//! | split a convex polygon by a plane into front and back pieces | plane | [`split::split_polygon`] | 000 (BSP) |
//!
//! Clip space is OpenGL's: the view volume is `-w <= x, y, z <= w`. Clipping happens
//! before the divide by `w`, which is what makes primitives crossing the eye plane
//! (`w <= 0`) come out right ([`projection_order`] shows both orders).
//!
//! Windows: [`Rect`] (axis-aligned, for Cohen-Sutherland and Liang-Barsky) and
//! [`ConvexWindow`] (any strictly convex polygon, either winding; non-convex and
//! degenerate ones are refused with a [`WindowError`]). Boxes are [`crate::geom::Aabb`].
//! Every segment clipper returns the visible part with its endpoints in the input
//! order, returns an unclipped endpoint bit for bit, and gives `None` for input out of
//! range (a coordinate that is not finite or beyond [`MAX_CLIP_COORDINATE`], where
//! differences of two coordinates would overflow); the tests in `tests/clipping.rs`
//! check that all of them agree. Windows and boxes beyond that range are refused too.

pub mod cohen_sutherland;
pub mod liang_barsky;
pub mod projection_order;
pub mod region_codes;
pub mod split;
pub mod sutherland_hodgman;
pub mod window;

pub use window::{ConvexWindow, EdgeLine, Rect, WindowError, polygon_area_2d};

/// The largest magnitude of a coordinate the clippers accept: differences and sums of
/// two such coordinates stay finite.
pub const MAX_CLIP_COORDINATE: f64 = 1e300;

/// Whether every coordinate is finite and within [`MAX_CLIP_COORDINATE`].
pub(crate) trait InRange {
    fn in_range(&self) -> bool;
}

impl InRange for f64 {
    fn in_range(&self) -> bool {
        self.abs() <= MAX_CLIP_COORDINATE
    }
}

/// The vectors: every coordinate in range (`max_element` alone would skip a NaN).
macro_rules! in_range_for_vectors {
    ($($v:ty),*) => {$(
        impl InRange for $v {
            fn in_range(&self) -> bool {
                self.to_array().iter().all(InRange::in_range)
            }
        }
    )*};
}

in_range_for_vectors!(glam::DVec2, glam::DVec3, glam::DVec4);

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
