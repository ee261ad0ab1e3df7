//! Acceleration structures shared by several algorithms.
//!
//! | structure | module | used by |
//! | --- | --- | --- |
//! | BSP tree with polygon splitting | [`bsp`] | `surface::bsp`, occlusion culling |
//! | octree of solids (voxels, booleans, neighbours, ray order) | [`octree`] | `surface::octree` |

pub mod bsp;
pub mod octree;
