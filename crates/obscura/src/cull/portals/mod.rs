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
//! Files: `model` (cells, portals, the graph), `validate` (leaks and bad cells with
//! their places), `locate` (the BSP tree that finds the viewer's cell), [`floorplan`]
//! (2D plans extruded to walls with door holes; the seed's five cells), [`prt`] (the
//! Quake tools' PRT1 files), [`stab`] (adjacency graph, stab trees), [`pvs`] (the PVS
//! table), [`render`] (portal rendering with the PVS), [`screen`] (screen-space
//! portals).

pub mod floorplan;
mod locate;
mod model;
pub mod prt;
pub mod pvs;
pub mod render;
pub mod screen;
pub mod stab;
mod validate;

pub use floorplan::{Door, FloorPlan, Furniture, Room, seed_example};
pub use locate::CellIndex;
pub use model::{Cell, CellGraph, CellIndexCache, Portal};
pub use pvs::{Pvs, PvsOptions};
pub use render::{Visit, portal_walk};
pub use screen::ScreenVisit;
#[cfg(test)]
pub(crate) use validate::segment_hits_scene;
pub use validate::{CellIssue, CellIssueKind, CellReport, CellShape};

use std::time::Instant;

use super::occlusion::{CullOptions, CullReason, Culling};
use crate::Result;
use crate::geom::Aabb;
use crate::index::SceneIndex;
use crate::view::ViewTransform;

/// The most visits a walk makes before it gives up portal culling for the view.
pub const MAX_VISITS: usize = 100_000;

/// What a walk needs before it starts: the cell graph, and the cells it starts from;
/// `None` (after a note) when the view is not portal-culled.
fn prepare<'g>(
    index: &'g SceneIndex<'_>,
    t: &ViewTransform,
    c: &mut Culling,
) -> Option<(&'g CellGraph, Vec<u32>)> {
    let Some(graph) = index.scene().cells() else {
        c.notes
            .push("the scene has no cells: no portal culling".to_owned());
        return None;
    };
    if t.orthographic {
        c.notes.push(
            "orthographic view: lines of sight do not meet at the eye, no portal culling"
                .to_owned(),
        );
        return None;
    }
    let Some(eye_cell) = graph.locate(t.eye) else {
        c.notes.push(format!(
            "the viewer ({:.3}, {:.3}, {:.3}) is outside every cell: no portal culling",
            t.eye.x, t.eye.y, t.eye.z
        ));
        return None;
    };
    let radius = render::near_radius(t);
    if graph.partial_cells
        && graph.cells[eye_cell as usize]
            .planes
            .iter()
            .any(|pl| pl.signed_distance(t.eye) > -radius * pl.normal.length())
    {
        c.notes.push(format!(
            "the viewer ({:.3}, {:.3}, {:.3}) is within the near distance of the boundary of {}, \
             known only by its portals' hull (a PRT1 import): no portal culling",
            t.eye.x, t.eye.y, t.eye.z, graph.cells[eye_cell as usize].name
        ));
        return None;
    }
    let starts = render::start_cells(graph, t.eye, eye_cell, radius);
    Some((graph, starts))
}

/// Culls, with [`CullReason::Portal`], the objects held by cells (and their clusters)
/// that no visit may see: `sees(visit, box)` says whether visit `v` may see a box;
/// `visited_cells` gives the cell of each visit, in order. Objects in no cell are kept.
fn decide(
    index: &SceneIndex<'_>,
    graph: &CellGraph,
    options: &CullOptions,
    c: &mut Culling,
    visited_cells: impl Iterator<Item = u32>,
    sees: impl Fn(usize, &Aabb) -> bool,
) {
    let mut visits_of = vec![Vec::new(); graph.cells.len()];
    for (i, cell) in visited_cells.enumerate() {
        visits_of[cell as usize].push(i);
    }
    let scene = index.scene();
    let clusters = index.clusters();
    let n = scene.objects().len();
    let mut cells_of: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (i, cell) in graph.cells.iter().enumerate() {
        for &k in &cell.objects {
            if (k as usize) < n {
                cells_of[k as usize].push(i as u32);
            }
        }
    }
    for (k, cells) in cells_of.iter().enumerate() {
        if cells.is_empty() || c.objects[k].is_some() {
            continue;
        }
        let seen = |b: &Aabb| {
            cells
                .iter()
                .any(|&cl| visits_of[cl as usize].iter().any(|&v| sees(v, b)))
        };
        if !seen(&scene.objects()[k].bounds) {
            c.cull_object(k, CullReason::Portal);
            continue;
        }
        if options.clusters {
            for cl in clusters.of_object(k) {
                if c.clusters[cl].is_none() && !seen(clusters.bounds(cl)) {
                    c.cull_cluster(cl, CullReason::Portal);
                }
            }
        }
    }
}

/// Portal culling from a region: the viewer's cell, its PVS row, portal rendering.
pub(crate) fn cull_portals(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let start = Instant::now();
    let Some((graph, starts)) = prepare(index, t, c) else {
        return Ok(());
    };
    let Some(pvs) = index.pvs() else {
        return Ok(());
    };
    let adjacency = stab::Adjacency::new(graph);
    let bbox = options.portal_bounding_box.then_some(t.rotation);
    let mut w = render::Walker::new(graph, &adjacency, t.eye, Some(pvs), bbox, MAX_VISITS);
    let planes = render::view_planes(t);
    for &s in &starts {
        w.walk(s, planes.clone());
    }
    if w.aborted {
        c.notes.push(format!(
            "the portal walk passed {MAX_VISITS} visits: no portal culling"
        ));
        return Ok(());
    }
    let eye = t.eye;
    let cells = w.visits.iter().map(|v| v.cell);
    decide(index, graph, options, c, cells, |v, b| {
        w.visits[v].may_see(eye, b)
    });
    c.stage("portals", start);
    Ok(())
}

/// Screen-space portal culling from a point.
pub(crate) fn cull_screen_portals(
    index: &SceneIndex<'_>,
    t: &ViewTransform,
    options: &CullOptions,
    c: &mut Culling,
) -> Result<()> {
    let start = Instant::now();
    let Some((graph, starts)) = prepare(index, t, c) else {
        return Ok(());
    };
    let Some(visits) = screen::screen_walk(graph, t, &starts, MAX_VISITS) else {
        c.notes.push(format!(
            "the screen-portal walk passed {MAX_VISITS} visits: no portal culling"
        ));
        return Ok(());
    };
    let cells = visits.iter().map(|v| v.cell);
    decide(index, graph, options, c, cells, |v, b| {
        screen::box_meets(t, visits[v].rect, b)
    });
    c.stage("screen portals", start);
    Ok(())
}
