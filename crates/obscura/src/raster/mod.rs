//! Rasterization machinery shared by every image-space algorithm: which pixels a
//! screen-space polygon covers ([`PolygonCoverage`]) and its depth at a pixel
//! ([`DepthPlane`]).
//!
//! All algorithms that turn polygons into pixels (z-buffer, scanline, depth sort, BSP,
//! Warnock) use these, so they agree on coverage to the last pixel: that is what lets
//! the test suite demand identical id images.

mod coverage;
mod depth_plane;

pub use coverage::{EdgeFunction, FillRule, PixelRect, PolygonCoverage, sample_rect};
pub use depth_plane::DepthPlane;
