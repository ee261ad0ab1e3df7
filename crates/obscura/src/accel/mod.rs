//! Acceleration structures shared by several algorithms.
//!
//! | structure | module | used by |
//! | --- | --- | --- |
//! | BSP tree with polygon splitting | [`bsp`] | `surface::bsp`, occlusion culling |
//! | octree of solids (voxels, booleans, neighbours, ray order) | [`octree`] | `surface::octree` |
//! | world-space triangles, watertight ray-triangle test | [`triangles`] | `surface::raycast` |
//! | bounding-volume hierarchy (binned SAH, 8-wide) | [`bvh`] | `surface::raycast` |
//! | uniform grid with 3D-DDA traversal | [`grid`] | `surface::raycast` |

pub mod bsp;
pub mod bvh;
pub mod grid;
pub mod octree;
pub mod triangles;
