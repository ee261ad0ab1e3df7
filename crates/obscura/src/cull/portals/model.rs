//! The cell model: convex cells, the portals that join them, the objects each holds.

use glam::DVec3;

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
}

impl CellGraph {
    /// The cell that holds point `p` (inside or on the boundary of), or `None` for a
    /// point outside every cell. The first such cell in order when cells share the
    /// point on a common boundary.
    ///
    /// CONTRACT: a linear scan; the builder replaces it by the BSP tree over cell
    /// boundaries (O(log n)) with the same answers.
    #[must_use]
    pub fn locate(&self, p: DVec3) -> Option<u32> {
        self.cells
            .iter()
            .position(|c| c.planes.iter().all(|pl| pl.signed_distance(p) <= 1e-9))
            .map(|i| i as u32)
    }
}
