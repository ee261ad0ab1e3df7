//! Cells and portals (seed 000 "από-Περιοχή (1)-(7)" and "από-Σημείο (1)").
//!
//! From a region: a scene of convex cells joined by portals; stab trees from each cell
//! through the portal sequences a line of sight can pass; the symmetric PVS table; a
//! BSP tree over cell boundaries that finds the viewer's cell in O(log n); portal
//! rendering that clips the view frustum to each portal. From a point: Luebke and
//! Georges' screen-space portals, rectangles intersected recursively.
//!
//! Papers: S. Teller and C. Séquin, "Visibility preprocessing for interactive
//! walkthroughs", SIGGRAPH 1991; D. Luebke and C. Georges, "Portals and mirrors:
//! simple, fast evaluation of potentially visible sets", Symposium on Interactive 3D
//! Graphics, 1995.
//!
//! STUB of the contract: the model types; the methods cull nothing yet.

pub mod floorplan;
mod locate;
mod model;
pub mod prt;
mod validate;

pub use floorplan::{Door, FloorPlan, Furniture, Room, seed_example};
pub use locate::CellIndex;
pub use model::{Cell, CellGraph, CellIndexCache, Portal};
#[cfg(test)]
pub(crate) use validate::segment_hits_scene;
pub use validate::{CellIssue, CellIssueKind, CellReport, CellShape};

use super::occlusion::{CullOptions, Culling};
use crate::Result;
use crate::index::SceneIndex;
use crate::view::ViewTransform;

/// Portal culling from a region: the viewer's cell, its PVS row, portal rendering.
pub(crate) fn cull_portals(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let _ = (index, t, options, c);
    Ok(())
}

/// Screen-space portal culling from a point.
pub(crate) fn cull_screen_portals(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let _ = (index, t, options, c);
    Ok(())
}
