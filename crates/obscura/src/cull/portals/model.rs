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
