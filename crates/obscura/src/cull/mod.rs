//! Culling: removing what cannot be seen before any visibility algorithm runs.
//!
//! | stage | module | seed |
//! | --- | --- | --- |
//! | back faces of closed opaque 2-manifolds, `n · v` | [`backface`] | 000, 002 |
//! | objects outside the view volume by bounding sphere and box | [`frustum`] | 000 |
//! | occlusion culling: the stage, its reasons and its result | [`occlusion`] | 000 |
//! | clusters of about a hundred triangles, the unit inside big meshes | [`clusters`] | — |
//! | from a region: cells, portals, stab trees, PVS, portal rendering; from a point: screen-space portals | [`portals`] | 000 "από-Περιοχή (1)-(7)", "από-Σημείο (1)" |
//! | occluders ranked by the Coorg-Teller metric, shadow volumes, hierarchy walk | [`occluders`] | 000 "από-Σημείο (2)-(6)" |
//! | occluder fusion: a masked coverage buffer and a hierarchical z-buffer | [`buffer`] | 000 "από-Σημείο (6)" |
//!
//! Every occlusion method is conservative: nothing visible is ever culled, so the
//! picture with culling equals the picture without it, and every culled object or
//! cluster carries the reason ([`occlusion::CullReason`]).

pub mod backface;
pub mod buffer;
pub mod clusters;
pub mod frustum;
pub mod occluders;
pub mod occlusion;
pub mod portals;
