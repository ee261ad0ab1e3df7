//! Screen-space portals, from a point (seed 000 "από-Σημείο (1)"; Luebke and Georges):
//! no precomputation; from the viewer's cell, recursively through each portal whose
//! screen rectangle meets the current one, the rectangle shrunk to the intersection.
//! An object of a cell is kept if its screen rectangle meets the rectangle of a visit
//! to that cell.
//!
//! Conservative: rectangles are rounded outward by a pixel; a portal with a vertex at
//! or behind the eye plane (crossing the near plane) gets the whole current rectangle
//! (its projection is unbounded); an object box with a corner there is kept by any
//! visit. The walk starts, turns back and stops as the portal walk does
//! ([`super::render`]): from every cell the near rectangle may lie in, only through
//! portals facing away from the eye, the whole rectangle through a portal the eye is
//! on.
//!
//! Paper: D. Luebke and C. Georges, "Portals and mirrors: simple, fast evaluation of
//! potentially visible sets", Symposium on Interactive 3D Graphics, 1995.

use glam::DVec3;

use super::model::CellGraph;
use super::render::{Side, portal_side};
use super::stab::{Adjacency, tolerance};
use crate::geom::Aabb;
use crate::view::ViewTransform;

/// A pixel rectangle `[min x, min y, max x, max y]` (y down).
pub type Rect = [f64; 4];

/// One step of a screen-portal walk.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenVisit {
    /// The cell.
    pub cell: u32,
    /// The portal crossed into it (`None` for a start cell).
    pub portal: Option<u32>,
    /// The visit it came from.
    pub parent: Option<usize>,
    /// The screen rectangle through which the cell is seen.
    pub rect: Rect,
}

/// The screen rectangle of a set of world points, rounded out by a pixel; `None` when a
/// point is at or behind the eye plane (no rectangle bounds its projection).
#[must_use]
pub fn screen_rect(t: &ViewTransform, points: impl IntoIterator<Item = DVec3>) -> Option<Rect> {
    let mut r = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in points {
        let e = t.world_to_eye(p);
        let depth = -e.z;
        if !(depth > 1e-9 * (1.0 + e.abs().max_element())) {
            return None;
        }
        let c = t.eye_to_clip(e);
        if !(c.w > 0.0) {
            return None;
        }
        let x = (c.x / c.w + 1.0) * 0.5 * t.width;
        let y = (1.0 - c.y / c.w) * 0.5 * t.height;
        r = [r[0].min(x), r[1].min(y), r[2].max(x), r[3].max(y)];
    }
    if !r.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some([r[0] - 1.0, r[1] - 1.0, r[2] + 1.0, r[3] + 1.0])
}

/// The intersection of two rectangles; `None` when empty.
#[must_use]
pub fn intersect(a: Rect, b: Rect) -> Option<Rect> {
    let r = [
        a[0].max(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].min(b[3]),
    ];
    (r[0] <= r[2] && r[1] <= r[3]).then_some(r)
}

/// Whether an object box may show inside a visit's rectangle.
#[must_use]
pub fn box_meets(t: &ViewTransform, rect: Rect, b: &Aabb) -> bool {
    if b.is_empty() {
        return false;
    }
    match screen_rect(t, b.corners()) {
        None => true,
        Some(r) => intersect(r, rect).is_some(),
    }
}

/// The screen-portal walk of a perspective view from the cells `starts` (see
/// [`super::render`] for how they are chosen), with the whole viewport as first
/// rectangle; `None` when it passes `max_visits` visits.
#[must_use]
pub fn screen_walk(
    graph: &CellGraph,
    t: &ViewTransform,
    starts: &[u32],
    max_visits: usize,
) -> Option<Vec<ScreenVisit>> {
    let adjacency = Adjacency::new(graph);
    let mut w = ScreenWalker {
        graph,
        adjacency: &adjacency,
        t,
        eps: tolerance(graph),
        on_path: vec![false; graph.cells.len()],
        visits: Vec::new(),
        max_visits,
        aborted: false,
    };
    let whole = [-1.0, -1.0, t.width + 1.0, t.height + 1.0];
    for &s in starts {
        w.visit(s, whole, None, None);
    }
    (!w.aborted).then_some(w.visits)
}

struct ScreenWalker<'a> {
    graph: &'a CellGraph,
    adjacency: &'a Adjacency,
    t: &'a ViewTransform,
    eps: f64,
    on_path: Vec<bool>,
    visits: Vec<ScreenVisit>,
    max_visits: usize,
    aborted: bool,
}

impl ScreenWalker<'_> {
    fn visit(&mut self, cell: u32, rect: Rect, portal: Option<u32>, parent: Option<usize>) {
        if self.aborted {
            return;
        }
        if self.visits.len() >= self.max_visits {
            self.aborted = true;
            return;
        }
        let idx = self.visits.len();
        self.visits.push(ScreenVisit {
            cell,
            portal,
            parent,
            rect,
        });
        self.on_path[cell as usize] = true;
        for &(p, next) in &self.adjacency.neighbours[cell as usize] {
            if self.aborted {
                break;
            }
            if self.on_path[next as usize] {
                continue;
            }
            let r = match portal_side(self.graph, cell, p, self.t.eye, self.eps) {
                Side::Behind => continue,
                Side::Whole => Some(rect),
                Side::Through => {
                    let poly = &self.graph.portals[p as usize].polygon;
                    match screen_rect(self.t, poly.iter().copied()) {
                        None => Some(rect),
                        Some(pr) => intersect(pr, rect),
                    }
                }
            };
            if let Some(r) = r {
                self.visit(next, r, Some(p), Some(idx));
            }
        }
        self.on_path[cell as usize] = false;
    }
}
