//! Acceleration structures shared by several algorithms.
//!
//! | structure | module | used by |
//! | --- | --- | --- |
//! | BSP tree with polygon splitting | [`bsp`] | `surface::bsp`, occlusion culling |
//! | world-space triangles, watertight ray-triangle test | [`triangles`] | `surface::raycast` |
//! | bounding-volume hierarchy (binned SAH) | [`bvh`] | `surface::raycast` |
//! | uniform grid with 3D-DDA traversal | [`grid`] | `surface::raycast` |

pub mod bsp;
pub mod bvh;
pub mod grid;
pub mod triangles;
