//! Rasterization machinery shared by every image-space algorithm: which pixels a
//! screen-space polygon covers ([`PolygonCoverage`]) and its depth at a pixel
//! ([`DepthPlane`]).
//!
//! All algorithms that turn polygons into pixels (z-buffer, scanline, depth sort, BSP,
//! Warnock) use these, so they agree on coverage to the last pixel: that is what lets
//! the test suite demand identical id images.

mod coverage;
mod depth_plane;
pub mod depth_span;
pub mod kernel;
mod setup;
#[cfg(target_arch = "x86_64")]
pub mod simd;

pub use coverage::{EdgeFunction, FillRule, PixelRect, PolygonCoverage, sample_rect};
pub use depth_plane::DepthPlane;
pub use setup::{NARROW_EDGES, NARROW_WIDTH, NarrowEdges, PolygonSetup, TriangleSetup, row_span};
