//! Culling: removing what cannot be seen before any visibility algorithm runs.
//!
//! | stage | module | seed |
//! | --- | --- | --- |
//! | back faces of closed opaque 2-manifolds, `n · v` | [`backface`] | 000, 002 |
//! | objects outside the view volume by bounding sphere and box | [`frustum`] | 000 |

pub mod backface;
pub mod frustum;
