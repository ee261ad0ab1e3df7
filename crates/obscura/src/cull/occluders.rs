//! Occluders, from a point (seed 000 "από-Σημείο (2)-(6)"): candidate planar occluders
//! ranked by the Coorg-Teller metric `-A (n · v) / |v|^2`, their shadow (occlusion)
//! volumes, and the scene's bounds hierarchy walked against them: a node inside a
//! shadow volume is culled, outside kept, straddling opened.
//!
//! Paper: S. Coorg and S. Teller, "Real-time occlusion culling for models with large
//! occluders", Symposium on Interactive 3D Graphics, 1997.
//!
//! STUB of the contract: culls nothing yet.

use super::occlusion::{CullOptions, Culling};
use crate::Result;
use crate::index::SceneIndex;
use crate::view::ViewTransform;

/// Culls, among what the frustum left, the objects and clusters inside the shadow
/// volume of one of the best-ranked occluders.
pub(crate) fn cull(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let _ = (index, t, options, c);
    Ok(())
}
