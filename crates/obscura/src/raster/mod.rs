//! Rasterization machinery shared by every image-space algorithm: which pixels a
//! screen-space polygon covers ([`PolygonCoverage`]) and its depth at a pixel
//! ([`DepthPlane`]).
//!
//! All algorithms that turn polygons into pixels (z-buffer, scanline, depth sort, BSP,
//! Warnock) use these, so they agree on coverage to the last pixel: that is what lets
//! the test suite demand identical id images.
//!
//! Sources: Pineda, *A parallel algorithm for polygon rasterization* (SIGGRAPH 1988).
//! Catmull, *A subdivision algorithm for computer display of curved surfaces* (PhD
//! thesis, University of Utah, 1974): the depth buffer the block rasterizer fills.

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512;
pub(crate) mod block;
mod coverage;
mod depth_plane;
pub(crate) mod lanes;
mod rounding;
mod setup;

pub use coverage::{
    EdgeFunction, FillRule, PixelRect, PolygonCoverage, edges_row_span, sample_rect,
};
pub use depth_plane::DepthPlane;
pub use lanes::DepthOfKey;
pub(crate) use rounding::{round_down, round_up, sample_range};
pub use setup::{PolygonSetup, TriangleSetup};
