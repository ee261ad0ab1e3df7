//! Acceleration structures shared by several algorithms.
//!
//! | structure | module | used by |
//! | --- | --- | --- |
//! | BSP tree with polygon splitting | [`bsp`] | `surface::bsp`, occlusion culling |

pub mod bsp;
