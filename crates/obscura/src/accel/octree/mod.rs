//! Octrees of solids: voxelization of meshes, boolean union, intersection and difference
//! by parallel traversal, Samet's neighbour finding in the 26 directions, and
//! front-to-back ray traversal.
//!
//! # Source
//! Seed 003, "Metodele OCTREE": space is cut into 8 octants (named by U/D, L/R, F/B); a
//! node whose voxels are all of one type is a leaf, otherwise it has 8 sons, down to a
//! voxel. Two objects are combined (union, intersection, ...) by walking both trees in
//! parallel from the roots; the neighbour in one of the 26 directions (6 faces, 12
//! edges, 8 vertices) is found by Samet's two phases: ascend to the common ancestor,
//! descend to the neighbour. Seed 000, "Υποδιαίρεση Χώρου (1)-(2)": recursive division
//! of a cell into 8 until a cell of elementary size (voxel). Viewing: W. G. Aref,
//! H. Samet, "An algorithm for perspective viewing of objects represented by octrees",
//! Computer Graphics Forum 14(1), 1995; H. Samet, "Neighbor finding in images
//! represented by octrees", CVGIP 46, 1989; ray traversal in the spirit of J. Revelles,
//! C. Ureña, M. Lastra, "An efficient parametric algorithm for octree traversal", 2000.
//!
//! # Representation
//! A flat array of [`Node`]s (16 bytes each), the root at index 0. An internal node's 8
//! children are consecutive, in octant order; every node knows its parent and its
//! octant, which is all Samet's neighbour finding needs. The region is a cube
//! ([`Region`]); the tree has a fixed `depth`, so the finest cells (voxels) form a
//! `2^depth` grid on a side. A node's [`Cell`] (level and integer coordinates) is not
//! stored: it follows from the path, and traversals compute it on the way down.
//!
//! # Octants
//! `octant = x + 2 y + 4 z`, where a bit is 1 for the upper half along that axis. In the
//! seed's naming: L/R is x (left 0, right 1), D/U is y (down 0, up 1), B/F is z (back 0,
//! front 1: front is +z, towards a viewer looking down -z, the eye-space convention).
//!
//! | octant | 0 | 1 | 2 | 3 | 4 | 5 | 6 | 7 |
//! | --- | --- | --- | --- | --- | --- | --- | --- | --- |
//! | seed name | LDB | RDB | LUB | RUB | LDF | RDF | LUF | RUF |
//!
//! # Node kinds
//! - [`NodeKind::Empty`]: outside every solid, no surface passes through.
//! - [`NodeKind::Full`]: inside a closed solid, no surface passes through.
//! - [`NodeKind::Partial`]: a surface passes through (a boundary voxel). Partial leaves
//!   exist only at the finest level and are never merged: merging them would claim a
//!   homogeneity they do not have. Each records a source face ([`Node::face`]).
//! - [`NodeKind::Internal`]: 8 children. No internal node has 8 children that are all
//!   Full leaves or all Empty leaves (homogeneous regions are leaves, as the seed asks).
//!
//! # Memory and time
//! 16 bytes per node. A surface of area `A` (in voxel units) gives about `1.5 A`
//! Partial voxels and about 2.5 times as many nodes in all: cost follows the surface,
//! not the volume. The build walks each cell's triangle list once per level, so it costs
//! about (triangles + Partial voxels) x depth. Node counts (deterministic):
//!
//! | scene | depth 6 | depth 7 | depth 8 |
//! | --- | --- | --- | --- |
//! | `demo:default` (5,406 triangles) | 19,657 (0.3 MB) | 115,393 (1.8 MB) | 507,609 (8.1 MB) |
//! | `demo:sphere` (998,000 triangles) | 47,561 (0.8 MB) | 192,393 (3.1 MB) | 772,873 (12.4 MB) |
//!
//! Each level multiplies the nodes by about 4. The depth is limited to [`MAX_DEPTH`]
//! (1024 voxels on a side), where a surface filling the region can need a few hundred MB.
//! The build also holds the world-space triangles (84 bytes each) while it runs.
//!
//! # Frame
//! A scene far from the origin beside its size is voxelized relative to the centre of
//! its box ([`Octree::frame_origin`]): its triangles are translated by minus that
//! centre, the region and every cell box are computed in that frame, and rays are
//! translated likewise. In world coordinates, the cell boxes of a unit box at 1e12
//! would be rounded to 1.2e-4 (a tenth of a voxel at depth 10), and the region's
//! floor of a billionth of the coordinates made it 1000 wide (the octree agreed with
//! the z-buffer on 18 % of the pixels, 99.3 % at the origin); in its own frame the
//! image is the same at every offset. A scene whose centre is within its own extent of
//! the origin keeps the world frame (nothing to gain), so such trees are unchanged.
//!
//! # Modules
//! - [`build`](Octree::build): voxelization (triangle-box overlap, winding numbers),
//! - [`combine`](Octree::combine): booleans by parallel traversal,
//! - [`neighbour`](Octree::neighbour): Samet's neighbour finding,
//! - [`first_hit`](Octree::first_hit): front-to-back ray traversal.

mod boolean;
mod build;
mod neighbour;
mod traverse;

use glam::DVec3;

use crate::geom::Aabb;
use crate::{Error, Result};

pub use boolean::BooleanOp;
pub use build::{
    BuildStats, TriangleSoup, closest_point_on_triangle, triangle_box_overlap, winding_number,
};
pub use neighbour::{Direction, DirectionKind};
pub use traverse::{RayHit, front_to_back_order};

/// The deepest tree accepted: 1024 voxels on a side.
pub const MAX_DEPTH: u32 = 10;

/// The deepest grid [`Octree::from_fn`] accepts (16.7 million voxels, about 300 MB
/// while it is merged).
pub const FROM_FN_MAX_DEPTH: u32 = 8;

/// "No node": the parent of the root, the first child of a leaf.
pub(crate) const NONE: u32 = u32::MAX;

/// No face: the face of nodes that are not partial.
pub const NO_FACE: u32 = u32::MAX;

/// What a node is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum NodeKind {
    /// A leaf outside every solid, with no surface through it.
    Empty,
    /// A leaf inside a closed solid, with no surface through it.
    Full,
    /// A finest-level leaf a surface passes through (a boundary voxel).
    Partial,
    /// A node with 8 children.
    Internal,
}

/// The content of a leaf: what a voxel grid stores per cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Leaf {
    /// Outside.
    Empty,
    /// Inside.
    Full,
    /// On the boundary, with the scene-wide id of a face through it.
    Partial {
        /// The source face.
        face: u32,
    },
}

impl Leaf {
    /// The node kind of this leaf.
    #[must_use]
    pub fn kind(self) -> NodeKind {
        match self {
            Leaf::Empty => NodeKind::Empty,
            Leaf::Full => NodeKind::Full,
            Leaf::Partial { .. } => NodeKind::Partial,
        }
    }
}

/// A node of an [`Octree`]: 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Node {
    parent: u32,
    first_child: u32,
    face: u32,
    kind: NodeKind,
    level: u8,
    octant: u8,
}

impl Node {
    fn new(parent: u32, level: u8, octant: u8) -> Self {
        Node {
            parent,
            first_child: NONE,
            face: NO_FACE,
            kind: NodeKind::Empty,
            level,
            octant,
        }
    }

    fn set_leaf(&mut self, leaf: Leaf) {
        self.kind = leaf.kind();
        self.first_child = NONE;
        self.face = match leaf {
            Leaf::Partial { face } => face,
            _ => NO_FACE,
        };
    }

    /// What the node is.
    #[must_use]
    pub fn kind(&self) -> NodeKind {
        self.kind
    }

    /// Whether the node has no children.
    #[must_use]
    pub(crate) fn is_leaf(&self) -> bool {
        self.kind != NodeKind::Internal
    }

    /// The leaf content, `None` for an internal node.
    #[must_use]
    pub fn leaf(&self) -> Option<Leaf> {
        match self.kind {
            NodeKind::Empty => Some(Leaf::Empty),
            NodeKind::Full => Some(Leaf::Full),
            NodeKind::Partial => Some(Leaf::Partial { face: self.face }),
            NodeKind::Internal => None,
        }
    }

    /// The parent's index, `None` for the root.
    #[must_use]
    pub fn parent(&self) -> Option<u32> {
        (self.parent != NONE).then_some(self.parent)
    }

    /// The index of child `octant` (0..8), `None` for a leaf.
    #[must_use]
    pub fn child(&self, octant: u8) -> Option<u32> {
        (self.kind == NodeKind::Internal && octant < 8)
            .then(|| self.first_child + u32::from(octant))
    }

    /// The source face of a partial leaf ([`NO_FACE`] otherwise).
    #[must_use]
    pub fn face(&self) -> u32 {
        self.face
    }

    /// The level: 0 for the root, the tree's depth for a voxel.
    #[must_use]
    pub fn level(&self) -> u32 {
        u32::from(self.level)
    }

    /// Which octant of its parent this node is (0 for the root).
    #[must_use]
    pub fn octant(&self) -> u8 {
        self.octant
    }
}

/// A cell of the subdivision: its level and integer coordinates in units of its own
/// size (`0..2^level` on each axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Cell {
    /// 0 for the whole region.
    pub level: u32,
    /// Coordinates, `0..2^level`.
    pub x: u32,
    /// Coordinates, `0..2^level`.
    pub y: u32,
    /// Coordinates, `0..2^level`.
    pub z: u32,
}

impl Cell {
    /// The whole region.
    pub const ROOT: Cell = Cell {
        level: 0,
        x: 0,
        y: 0,
        z: 0,
    };

    /// The child cell in `octant`.
    #[must_use]
    pub fn child(self, octant: u8) -> Cell {
        let o = u32::from(octant);
        Cell {
            level: self.level + 1,
            x: 2 * self.x + (o & 1),
            y: 2 * self.y + ((o >> 1) & 1),
            z: 2 * self.z + ((o >> 2) & 1),
        }
    }

    /// Whether the cell touches the region's boundary.
    #[must_use]
    pub(crate) fn touches_boundary(self) -> bool {
        let last = (1u32 << self.level) - 1;
        [self.x, self.y, self.z]
            .iter()
            .any(|&c| c == 0 || c == last)
    }
}

/// The cubic region an octree covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    min: DVec3,
    side: f64,
}

impl Region {
    /// The cube `[min, min + side]^3`; `side` must be positive and everything finite.
    pub fn new(min: DVec3, side: f64) -> Result<Region> {
        if !(min.is_finite() && side > 0.0 && side.is_finite() && (min + side).is_finite()) {
            return Err(Error::option(
                "octree region",
                format!(
                    "need a finite corner and a positive finite side (corner {:?}, side {side})",
                    min.to_array()
                ),
            ));
        }
        Ok(Region { min, side })
    }

    /// The cube around a box, its side the box's largest extent padded by 1/64 of it on
    /// each end, so that the surfaces stay strictly inside (which lets the voxelization call every cell on the
    /// region's boundary outside). `None` for an empty or non-finite box.
    #[must_use]
    pub fn enclosing(bounds: &Aabb) -> Option<Region> {
        if bounds.is_empty() || !(bounds.min.is_finite() && bounds.max.is_finite()) {
            return None;
        }
        let extent = bounds.extent().max_element();
        let scale = bounds.min.abs().max(bounds.max.abs()).max_element();
        // No cell finer than a billionth of the coordinates (far above their rounding).
        // Relative to the coordinates only, never an absolute length: a floor of 1e-9
        // made a scene 1e-20 across one voxel, and a unit box at 1e12 a dot in a
        // region 1000 wide (the scene's own frame, `Octree::from_scene`, avoids that).
        let side = (extent * (1.0 + 2.0 / 64.0)).max(scale * 1e-9);
        // A single point (no surface at all) at the origin still needs a cube.
        let side = if side > 0.0 { side } else { 1.0 };
        Region::new(bounds.center() - DVec3::splat(side * 0.5), side).ok()
    }

    /// The lower corner.
    #[must_use]
    pub fn min(&self) -> DVec3 {
        self.min
    }

    /// The upper corner.
    #[must_use]
    pub fn max(&self) -> DVec3 {
        self.min + self.side
    }

    /// The side length.
    #[must_use]
    pub fn side(&self) -> f64 {
        self.side
    }

    /// The side of a cell at `level`.
    #[must_use]
    pub fn cell_side(&self, level: u32) -> f64 {
        // A power-of-two scaling is exact.
        self.side * 0.5f64.powi(level as i32)
    }

    /// The box of a cell. Every caller computes boxes through this function, so a cell
    /// has the same box, to the bit, whichever way it was reached.
    #[must_use]
    pub fn cell_box(&self, cell: Cell) -> Aabb {
        let s = self.cell_side(cell.level);
        let lo = |o: f64, c: u32| o + f64::from(c) * s;
        let hi = |o: f64, c: u32| o + f64::from(c + 1) * s;
        Aabb {
            min: DVec3::new(
                lo(self.min.x, cell.x),
                lo(self.min.y, cell.y),
                lo(self.min.z, cell.z),
            ),
            max: DVec3::new(
                hi(self.min.x, cell.x),
                hi(self.min.y, cell.y),
                hi(self.min.z, cell.z),
            ),
        }
    }
}

/// Leaf counts by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeafCounts {
    /// Empty leaves.
    pub empty: usize,
    /// Full leaves.
    pub full: usize,
    /// Partial leaves (boundary voxels).
    pub partial: usize,
}

/// A voxel octree of solids (see the module documentation). Two trees are equal when
/// their regions, depths and node arrays are (how they were built does not count).
#[derive(Clone, Debug)]
pub struct Octree {
    region: Region,
    frame: DVec3,
    depth: u32,
    nodes: Vec<Node>,
    build_stats: BuildStats,
}

impl PartialEq for Octree {
    fn eq(&self, other: &Self) -> bool {
        self.region == other.region
            && self.frame == other.frame
            && self.depth == other.depth
            && self.nodes == other.nodes
    }
}

pub(crate) fn check_depth(depth: u32) -> Result<()> {
    if depth > MAX_DEPTH {
        return Err(Error::option(
            "RenderOptions::octree_depth",
            format!(
                "depth {depth} is above the maximum {MAX_DEPTH} ({} voxels on a side)",
                1u32 << MAX_DEPTH
            ),
        ));
    }
    Ok(())
}

impl Octree {
    /// A tree of one leaf.
    pub fn uniform(region: Region, depth: u32, leaf: Leaf) -> Result<Octree> {
        check_depth(depth)?;
        let leaf = match leaf {
            // A partial leaf above the finest level would break the invariant.
            Leaf::Partial { .. } if depth > 0 => {
                return Octree::from_fn(region, depth, |_| leaf);
            }
            l => l,
        };
        let mut root = Node::new(NONE, 0, 0);
        root.set_leaf(leaf);
        Ok(Octree {
            region,
            frame: DVec3::ZERO,
            depth,
            nodes: vec![root],
            build_stats: BuildStats::default(),
        })
    }

    /// The tree of a voxel grid given cell by cell (`f` is called once per finest cell,
    /// `8^depth` times, and the full tree is held before merging: for small grids, tests
    /// and imported volumes; depths above [`FROM_FN_MAX_DEPTH`] are refused).
    pub fn from_fn(region: Region, depth: u32, f: impl Fn(Cell) -> Leaf) -> Result<Octree> {
        if depth > FROM_FN_MAX_DEPTH {
            return Err(Error::option(
                "octree depth",
                format!(
                    "a tree given voxel by voxel is limited to depth {FROM_FN_MAX_DEPTH} \
                     (8^{depth} voxels asked for)"
                ),
            ));
        }
        let mut raw = vec![Node::new(NONE, 0, 0)];
        let mut stack = vec![(0usize, Cell::ROOT)];
        while let Some((i, cell)) = stack.pop() {
            if cell.level == depth {
                raw[i].set_leaf(f(cell));
                continue;
            }
            let first = raw.len();
            raw[i].kind = NodeKind::Internal;
            raw[i].first_child = first as u32;
            for k in 0..8u8 {
                raw.push(Node::new(i as u32, (cell.level + 1) as u8, k));
                stack.push((first + usize::from(k), cell.child(k)));
            }
        }
        Ok(Octree {
            region,
            frame: DVec3::ZERO,
            depth,
            nodes: compact(&raw),
            build_stats: BuildStats::default(),
        })
    }

    /// The region, in the tree's own frame: world coordinates less
    /// [`Octree::frame_origin`] (the same as world coordinates for trees built by
    /// [`Octree::build`], [`Octree::uniform`] and [`Octree::from_fn`]).
    #[must_use]
    pub fn region(&self) -> &Region {
        &self.region
    }

    /// Where the tree's frame has its origin, in world coordinates: zero, except for
    /// [`Octree::from_scene`] of a scene far from the origin beside its size, which is
    /// voxelized relative to the centre of its box (see "Frame" in the module
    /// documentation). Ray queries ([`Octree::first_hit`]) take world coordinates.
    #[must_use]
    pub fn frame_origin(&self) -> DVec3 {
        self.frame
    }

    /// The depth: voxels are cells of this level.
    #[must_use]
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// All nodes, the root first.
    #[must_use]
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Node `i`.
    #[must_use]
    pub fn node(&self, i: u32) -> &Node {
        &self.nodes[i as usize]
    }

    /// Number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes used by the nodes.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }

    /// How the tree was built (zero for trees not made by voxelization).
    #[must_use]
    pub(crate) fn build_stats(&self) -> &BuildStats {
        &self.build_stats
    }

    /// Leaf counts by kind.
    #[must_use]
    pub fn leaf_counts(&self) -> LeafCounts {
        let mut c = LeafCounts::default();
        for n in &self.nodes {
            match n.kind {
                NodeKind::Empty => c.empty += 1,
                NodeKind::Full => c.full += 1,
                NodeKind::Partial => c.partial += 1,
                NodeKind::Internal => {}
            }
        }
        c
    }

    /// Indices of the leaves.
    pub fn leaves(&self) -> impl Iterator<Item = u32> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.is_leaf())
            .map(|(i, _)| i as u32)
    }

    /// The cell of node `i` (by walking up to the root: O(depth)).
    #[must_use]
    pub fn cell(&self, i: u32) -> Cell {
        let level = self.nodes[i as usize].level();
        let (mut x, mut y, mut z) = (0, 0, 0);
        let mut n = i;
        let mut bit = 0;
        while let Some(p) = self.nodes[n as usize].parent() {
            let o = u32::from(self.nodes[n as usize].octant);
            x |= (o & 1) << bit;
            y |= ((o >> 1) & 1) << bit;
            z |= ((o >> 2) & 1) << bit;
            bit += 1;
            n = p;
        }
        Cell { level, x, y, z }
    }

    /// The leaf containing the voxel `(x, y, z)` (finest-level coordinates), `None`
    /// outside the grid.
    #[must_use]
    pub(crate) fn leaf_at(&self, x: u32, y: u32, z: u32) -> Option<u32> {
        let n = 1u32 << self.depth;
        if x >= n || y >= n || z >= n {
            return None;
        }
        let mut i = 0u32;
        let mut level = 0;
        while self.nodes[i as usize].kind == NodeKind::Internal {
            let shift = self.depth - level - 1;
            let o = ((x >> shift) & 1) | (((y >> shift) & 1) << 1) | (((z >> shift) & 1) << 2);
            i = self.nodes[i as usize].first_child + o;
            level += 1;
        }
        Some(i)
    }

    /// The content of voxel `(x, y, z)`, `None` outside the grid.
    #[must_use]
    pub fn voxel(&self, x: u32, y: u32, z: u32) -> Option<Leaf> {
        self.leaf_at(x, y, z)
            .and_then(|i| self.nodes[i as usize].leaf())
    }
}

/// Copies a tree whose internal nodes have consecutive children into a fresh array
/// (root first, children blocks in depth-first order), merging internal nodes whose
/// subtree is all Full or all Empty into one leaf. O(n).
pub(crate) fn compact(raw: &[Node]) -> Vec<Node> {
    // Bottom-up: the uniform kind of each subtree, if any. Children always come after
    // their parent in `raw`, so a reverse sweep sees children first.
    let mut uniform: Vec<Option<NodeKind>> = vec![None; raw.len()];
    for i in (0..raw.len()).rev() {
        let n = &raw[i];
        uniform[i] = match n.kind {
            NodeKind::Empty | NodeKind::Full => Some(n.kind),
            NodeKind::Partial => None,
            NodeKind::Internal => {
                let first = n.first_child as usize;
                let k = uniform[first];
                (k.is_some() && uniform[first + 1..first + 8].iter().all(|&c| c == k))
                    .then_some(k)
                    .flatten()
            }
        };
    }
    let mut out = Vec::with_capacity(raw.len());
    out.push(Node::new(NONE, 0, 0));
    let mut stack = vec![(0usize, 0usize)]; // (raw index, out index)
    while let Some((r, o)) = stack.pop() {
        let n = &raw[r];
        match (uniform[r], n.kind) {
            (Some(k), _) => {
                out[o].kind = k;
            }
            (None, NodeKind::Internal) => {
                let first = out.len();
                out[o].kind = NodeKind::Internal;
                out[o].first_child = first as u32;
                for k in 0..8u8 {
                    out.push(Node::new(o as u32, out[o].level + 1, k));
                }
                for k in (0..8).rev() {
                    stack.push((n.first_child as usize + k, first + k));
                }
            }
            (None, _) => {
                out[o].kind = n.kind;
                out[o].face = n.face;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Region {
        Region::new(DVec3::ZERO, 1.0).unwrap()
    }

    #[test]
    fn node_is_sixteen_bytes() {
        assert_eq!(std::mem::size_of::<Node>(), 16);
    }

    #[test]
    fn octants_follow_the_documented_bits() {
        let c = Cell::ROOT.child(5); // RDF: x high, y low, z high
        assert_eq!((c.x, c.y, c.z), (1, 0, 1));
        let b = unit().cell_box(c);
        assert_eq!(b.min, DVec3::new(0.5, 0.0, 0.5));
        assert_eq!(b.max, DVec3::new(1.0, 0.5, 1.0));
    }

    #[test]
    fn from_fn_merges_homogeneous_octants() {
        // Full in the octant x < 1/2 of a depth-3 grid: the root has 8 children, 4 Full
        // leaves and 4 Empty leaves.
        let t = Octree::from_fn(
            unit(),
            3,
            |c| if c.x < 4 { Leaf::Full } else { Leaf::Empty },
        )
        .unwrap();
        assert_eq!(t.node_count(), 9);
        let counts = t.leaf_counts();
        assert_eq!((counts.full, counts.empty, counts.partial), (4, 4, 0));
        let t = Octree::from_fn(unit(), 4, |_| Leaf::Empty).unwrap();
        assert_eq!(t.node_count(), 1);
        // Partial voxels are never merged.
        let t = Octree::from_fn(unit(), 2, |_| Leaf::Partial { face: 3 }).unwrap();
        assert_eq!(t.node_count(), 1 + 8 + 64);
        for i in t.leaves() {
            assert_eq!(t.node(i).level(), 2);
        }
    }

    #[test]
    fn cells_and_point_location_agree() {
        let t = Octree::from_fn(unit(), 3, |c| {
            if (c.x + c.y + c.z) % 3 == 0 {
                Leaf::Partial { face: c.x }
            } else {
                Leaf::Empty
            }
        })
        .unwrap();
        for i in 0..t.node_count() as u32 {
            let c = t.cell(i);
            let s = 1 << (t.depth() - c.level);
            let found = t.leaf_at(c.x * s, c.y * s, c.z * s).unwrap();
            if t.node(i).is_leaf() {
                assert_eq!(found, i);
            }
        }
        assert_eq!(t.leaf_at(8, 0, 0), None);
        assert_eq!(t.voxel(3, 0, 0), Some(Leaf::Partial { face: 3 }));
    }

    #[test]
    fn regions_are_validated_and_padded() {
        assert!(Region::new(DVec3::ZERO, 0.0).is_err());
        assert!(Region::new(DVec3::NAN, 1.0).is_err());
        assert!(Region::new(DVec3::ZERO, f64::INFINITY).is_err());
        let b = Aabb {
            min: DVec3::new(-1., 0., 0.),
            max: DVec3::new(1., 0.5, 0.),
        };
        let r = Region::enclosing(&b).unwrap();
        assert!(r.min().cmplt(b.min).all() && r.max().cmpgt(b.max).all());
        assert!((r.side() - 2.0 * (1.0 + 1.0 / 32.0)).abs() < 1e-12);
        assert!(Region::enclosing(&Aabb::EMPTY).is_none());
        assert!(check_depth(MAX_DEPTH + 1).is_err());
        assert!(Octree::from_fn(unit(), FROM_FN_MAX_DEPTH + 1, |_| Leaf::Empty).is_err());
        assert!(Octree::uniform(unit(), MAX_DEPTH, Leaf::Partial { face: 0 }).is_err());
        assert_eq!(
            Octree::uniform(unit(), MAX_DEPTH, Leaf::Full)
                .unwrap()
                .node_count(),
            1
        );
    }
}
