//! Samet's neighbour finding in the 26 directions.
//!
//! - Input: a node and a [`Direction`] (6 faces, 12 edges, 8 vertices).
//! - Output: the neighbour of equal or greater size across that face, edge or vertex:
//!   the node of the same level whose cell is the node's cell shifted by the direction,
//!   or, where that cell is inside a larger leaf, that leaf. `None` at the region's
//!   boundary. The neighbour may be internal (the same size, subdivided);
//!   [`Octree::adjacent_leaves`] then collects the leaves of it that touch the node.
//! - Method (seed 003, after H. Samet, "Neighbor finding in images represented by
//!   octrees", CVGIP 46(3), 1989): (a) ascend from the node while the move leaves the
//!   parent's cell, keeping along each axis only the components of the move that still
//!   leave it; the first ancestor within whose cell the move stays is the nearest common
//!   ancestor. (b) Descend from it along the mirrored path: at each level take the octant
//!   of the path with the bits of the move's remaining axes flipped; stop early at a
//!   leaf (a greater neighbour).
//! - Complexity: O(depth) worst case, O(1) on average over the nodes of a tree (most
//!   neighbours are siblings or cousins).

use super::{Node, NodeKind, Octree};

/// A direction to a neighbour: each component -1, 0 or 1, not all 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Direction([i8; 3]);

/// What a direction crosses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DirectionKind {
    /// A face (one non-zero component): 6 directions.
    Face,
    /// An edge (two non-zero components): 12 directions.
    Edge,
    /// A vertex (three non-zero components): 8 directions.
    Vertex,
}

const fn all_directions() -> [Direction; 26] {
    let mut out = [Direction([0, 0, 0]); 26];
    let mut n = 0;
    let mut i = 0;
    while i < 27 {
        let d = [
            (i % 3) as i8 - 1,
            ((i / 3) % 3) as i8 - 1,
            (i / 9) as i8 - 1,
        ];
        if !(d[0] == 0 && d[1] == 0 && d[2] == 0) {
            out[n] = Direction(d);
            n += 1;
        }
        i += 1;
    }
    out
}

impl Direction {
    /// The 26 directions.
    pub const ALL: [Direction; 26] = all_directions();

    /// The 6 face directions: -x, +x, -y, +y, -z, +z.
    pub const FACES: [Direction; 6] = [
        Direction([-1, 0, 0]),
        Direction([1, 0, 0]),
        Direction([0, -1, 0]),
        Direction([0, 1, 0]),
        Direction([0, 0, -1]),
        Direction([0, 0, 1]),
    ];

    /// A direction from its components (each in -1..=1, not all 0).
    #[must_use]
    pub fn new(dx: i8, dy: i8, dz: i8) -> Option<Direction> {
        let d = [dx, dy, dz];
        (d.iter().all(|c| (-1..=1).contains(c)) && d != [0, 0, 0]).then_some(Direction(d))
    }

    /// The components.
    #[must_use]
    pub fn components(self) -> [i8; 3] {
        self.0
    }

    /// Face, edge or vertex.
    #[must_use]
    pub fn kind(self) -> DirectionKind {
        match self.0.iter().filter(|&&c| c != 0).count() {
            1 => DirectionKind::Face,
            2 => DirectionKind::Edge,
            _ => DirectionKind::Vertex,
        }
    }

    /// The reverse direction.
    #[must_use]
    pub fn opposite(self) -> Direction {
        Direction(self.0.map(|c| -c))
    }

    /// The octant bits of the axes this direction moves along.
    fn mask(d: [i8; 3]) -> u8 {
        (0..3).filter(|&a| d[a] != 0).map(|a| 1u8 << a).sum()
    }
}

/// Samet's neighbour of `node` in direction `dir`, on any node array that keeps the
/// [`super::Octree`] layout (so it also serves trees still being built).
pub(crate) fn neighbour(nodes: &[Node], node: u32, dir: Direction) -> Option<u32> {
    // (a) Ascend. The path holds, per level from the node up, the octant and the axes
    // the move crosses at that level.
    let mut path = [(0u8, 0u8); 32];
    let mut len = 0;
    let mut cur = node as usize;
    let mut d = dir.0;
    let ancestor = loop {
        let n = &nodes[cur];
        let parent = n.parent()?;
        let o = n.octant;
        path[len] = (o, Direction::mask(d));
        len += 1;
        // The move leaves the parent's cell along the axes where the node is on the
        // side it moves towards.
        let mut leaving = [0i8; 3];
        for a in 0..3 {
            let upper = (o >> a) & 1 == 1;
            if d[a] != 0 && upper == (d[a] > 0) {
                leaving[a] = d[a];
            }
        }
        if leaving == [0, 0, 0] {
            break parent;
        }
        d = leaving;
        cur = parent as usize;
    };
    // (b) Descend along the mirrored path.
    let mut q = ancestor;
    while len > 0 {
        len -= 1;
        let n = &nodes[q as usize];
        if n.kind != NodeKind::Internal {
            return Some(q);
        }
        let (o, m) = path[len];
        q = n.first_child + u32::from(o ^ m);
    }
    Some(q)
}

/// The leaves touching `node` across the face, edge or vertex `dir`: the neighbour
/// itself when it is a leaf, else its descendants on the side facing `node`.
pub(crate) fn adjacent_leaves(nodes: &[Node], node: u32, dir: Direction, out: &mut Vec<u32>) {
    let Some(q) = neighbour(nodes, node, dir) else {
        return;
    };
    // A child faces back towards `node` when, along each axis of the move, it is on the
    // side the move comes from.
    let (mut want, mut care) = (0u8, 0u8);
    for a in 0..3 {
        if dir.0[a] != 0 {
            care |= 1 << a;
            if dir.0[a] < 0 {
                want |= 1 << a;
            }
        }
    }
    let mut stack = vec![q];
    while let Some(i) = stack.pop() {
        let n = &nodes[i as usize];
        if n.kind != NodeKind::Internal {
            out.push(i);
            continue;
        }
        for k in 0..8u8 {
            if k & care == want {
                stack.push(n.first_child + u32::from(k));
            }
        }
    }
}

impl Octree {
    /// The neighbour of equal or greater size of node `node` across the face, edge or
    /// vertex `dir` (Samet), `None` at the region's boundary.
    #[must_use]
    pub fn neighbour(&self, node: u32, dir: Direction) -> Option<u32> {
        neighbour(&self.nodes, node, dir)
    }

    /// The leaves touching node `node` across the face, edge or vertex `dir`.
    #[must_use]
    pub fn adjacent_leaves(&self, node: u32, dir: Direction) -> Vec<u32> {
        let mut out = Vec::new();
        adjacent_leaves(&self.nodes, node, dir, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Leaf, Region};
    use super::*;
    use glam::DVec3;

    #[test]
    fn twenty_six_distinct_directions() {
        let mut all = Direction::ALL.to_vec();
        all.sort_by_key(|d| d.0);
        all.dedup();
        assert_eq!(all.len(), 26);
        let count = |k| Direction::ALL.iter().filter(|d| d.kind() == k).count();
        assert_eq!(
            (
                count(DirectionKind::Face),
                count(DirectionKind::Edge),
                count(DirectionKind::Vertex)
            ),
            (6, 12, 8)
        );
        assert!(Direction::new(0, 0, 0).is_none());
        assert!(Direction::new(2, 0, 0).is_none());
    }

    #[test]
    fn siblings_cousins_and_larger_neighbours() {
        // Depth 2, only octant 0 of the root subdivided.
        let t = Octree::from_fn(Region::new(DVec3::ZERO, 1.0).unwrap(), 2, |c| {
            if c.x < 2 && c.y < 2 && c.z < 2 {
                Leaf::Partial {
                    face: c.x + 2 * c.y + 4 * c.z,
                }
            } else {
                Leaf::Empty
            }
        })
        .unwrap();
        assert_eq!(t.node_count(), 1 + 8 + 8);
        let root = t.node(0);
        let first = root.child(0).unwrap();
        let small = t.node(first).child(1).unwrap(); // voxel (1, 0, 0)
        let east = Direction::new(1, 0, 0).unwrap();
        // Across the root's mid-plane: the larger leaf, octant 1 of the root.
        assert_eq!(t.neighbour(small, east), root.child(1));
        // Back west: a sibling.
        assert_eq!(t.neighbour(small, east.opposite()), t.node(first).child(0));
        // West of voxel 0 is outside the region.
        assert_eq!(
            t.neighbour(t.node(first).child(0).unwrap(), east.opposite()),
            None
        );
        // From the large leaf 1 going west: the same-size internal node 0, whose leaves
        // facing east are its octants 1, 3, 5, 7.
        let big = root.child(1).unwrap();
        assert_eq!(t.neighbour(big, east.opposite()), Some(first));
        let mut leaves = t.adjacent_leaves(big, east.opposite());
        leaves.sort_unstable();
        let expected: Vec<u32> = [1u8, 3, 5, 7]
            .iter()
            .map(|&k| t.node(first).child(k).unwrap())
            .collect();
        assert_eq!(leaves, expected);
        // A vertex neighbour across the root's centre.
        let up_corner = Direction::new(1, 1, 1).unwrap();
        assert_eq!(
            t.neighbour(t.node(first).child(7).unwrap(), up_corner),
            root.child(7)
        );
    }
}
