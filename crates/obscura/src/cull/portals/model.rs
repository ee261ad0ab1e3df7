//! The cell model: convex cells, the portals that join them, the objects each holds.

use std::sync::{Arc, OnceLock};

use glam::DVec3;

use super::locate::{CellIndex, in_cell};

use crate::geom::Plane;

/// A convex region of space: the intersection of the half-spaces behind its planes
/// (`normal · p + d <= 0`, normals pointing out of the cell).
#[derive(Clone, Debug, PartialEq)]
pub struct Cell {
    /// A name for messages and tables (`A`, `room 3`).
    pub name: String,
    /// The bounding planes, normals pointing out.
    pub planes: Vec<Plane>,
    /// The scene objects this cell holds (an object that spans cells is in each).
    pub objects: Vec<u32>,
}

/// A convex planar polygon on the common boundary of two cells, through which one can
/// see from one into the other.
#[derive(Clone, Debug, PartialEq)]
pub struct Portal {
    /// The two cells it joins.
    pub cells: [u32; 2],
    /// Its vertices, in order, convex and planar.
    pub polygon: Vec<DVec3>,
}

/// Cells and portals: the scene description that cells-and-portals culling reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellGraph {
    /// The cells.
    pub cells: Vec<Cell>,
    /// The portals.
    pub portals: Vec<Portal>,
    /// The BSP tree [`CellGraph::locate`] uses, built on its first call (construct with
    /// `CellIndexCache::default()`, or `..Default::default()`; after editing `cells`,
    /// call [`CellGraph::reindex`]).
    pub index: CellIndexCache,
    /// The cells cover their regions only in part (a PRT1 import: each leaf known by the
    /// hull of its portals, see [`super::prt`]): a view whose near rectangle may leave
    /// the viewer's cell is not portal-culled, with a note.
    pub partial_cells: bool,
}

/// A lazily built [`CellIndex`] (equal to any other: it is derived data).
#[derive(Clone, Debug, Default)]
pub struct CellIndexCache(OnceLock<Arc<CellIndex>>);

impl PartialEq for CellIndexCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl CellGraph {
    /// A graph of these cells and portals.
    #[must_use]
    pub fn new(cells: Vec<Cell>, portals: Vec<Portal>) -> CellGraph {
        CellGraph {
            cells,
            portals,
            index: CellIndexCache::default(),
            partial_cells: false,
        }
    }

    /// The cell that holds point `p` (inside or on the boundary of), or `None` for a
    /// point outside every cell (and in cells without planes, as a PRT1 import's). The
    /// first such cell in order when cells share the point on a common boundary.
    ///
    /// O(log n): descends the BSP tree over the cell boundaries ([`CellIndex`]), built
    /// on the first call and kept; the answers are those of [`CellGraph::locate_linear`].
    #[must_use]
    pub fn locate(&self, p: DVec3) -> Option<u32> {
        self.cell_index().locate(self, p)
    }

    /// [`CellGraph::locate`] by a linear scan of the cells (the reference).
    #[must_use]
    pub fn locate_linear(&self, p: DVec3) -> Option<u32> {
        (0..self.cells.len())
            .find(|&c| in_cell(self, c, p))
            .map(|c| c as u32)
    }

    /// The BSP tree over the cell boundaries, built on first use.
    pub fn cell_index(&self) -> &CellIndex {
        self.index.0.get_or_init(|| Arc::new(CellIndex::new(self)))
    }

    /// Forgets the BSP tree (after `cells` changed); the next locate rebuilds it.
    pub fn reindex(&mut self) {
        self.index = CellIndexCache::default();
    }
}
