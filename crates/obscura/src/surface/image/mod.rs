//! Image-space machinery shared by several hidden-surface algorithms, in one place:
//!
//! - [`paint`]: painting screen polygons in an order (overwrite, write once with
//!   coverage counts, depth-tested), and pieces of polygons cut by planes, for the
//!   list-priority algorithms (depth sort, BSP);
//! - [`screen_faces`]: the prepared polygons with their coverage and key plane, the
//!   nearest-face rule on stored `f32` keys and runs of pixels written to the frame, for
//!   the scanline and Warnock;
//! - [`resolve`]: a frame of stored keys and encoded ids turned into depths and ids,
//!   as the z-buffer resolves its tiles (used by the scanline).
//!
//! The pixel rule itself (coverage, depth planes, block rasterization) lives below, in
//! [`crate::raster`]; what is here is what the algorithms do with a [`crate::Frame`].

pub(crate) mod paint;
pub(crate) mod resolve;
pub(crate) mod screen_faces;
