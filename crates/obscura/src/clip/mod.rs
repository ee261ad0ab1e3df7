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
//!
//! Papers: each clipper's module cites its own; clipping before the divide is Blinn and
//! Newell, "Clipping using homogeneous coordinates", SIGGRAPH 1978.

pub mod cohen_sutherland;
pub mod liang_barsky;
pub mod projection_order;
pub mod region_codes;
pub mod split;
pub mod sutherland_hodgman;
mod view_volume;
pub mod window;

pub use view_volume::{
    OUT_BOTTOM, OUT_FAR, OUT_LEFT, OUT_NEAR, OUT_RIGHT, OUT_TOP, outcode_homogeneous,
};
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

/// Whether a box can clip: finite, and `min <= max` on every axis (a flat box is
/// allowed, it clips to a plane).
pub(crate) fn valid_box(bounds: &crate::geom::Aabb) -> bool {
    bounds.min.in_range() && bounds.max.in_range() && !bounds.is_empty()
}
