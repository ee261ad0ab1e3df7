//! Boolean operations on octrees by parallel traversal (seed 003, "Compunerea
//! obiectelor reprezentate prin metoda Octree": walk both trees in parallel from the
//! roots, comparing each pair of nodes).
//!
//! - Input: two trees over the same region with the same depth.
//! - Output: their union, intersection or difference, with homogeneous octants merged.
//! - Rules per pair of nodes: when one node is a leaf that decides the result alone
//!   (Full ∪ x = Full, Empty ∩ x = Empty, Empty \ x = Empty, x \ Full = Empty) the
//!   result is that leaf and the other subtree is not visited; two leaves combine by the
//!   table below; otherwise the walk descends into the 8 pairs of children (a Full or
//!   Empty leaf standing for 8 children like itself) and merges them back if they come
//!   out homogeneous.
//! - Partial voxels ("a surface may pass here") follow the conservative table:
//!
//!   | a \ b | Empty | Full | Partial |
//!   | --- | --- | --- | --- |
//!   | ∪: Empty | Empty | Full | Partial(b) |
//!   | ∪: Full | Full | Full | Full |
//!   | ∪: Partial | Partial(a) | Full | Partial(min) |
//!   | ∩: Empty | Empty | Empty | Empty |
//!   | ∩: Full | Empty | Full | Partial(b) |
//!   | ∩: Partial | Empty | Partial(a) | Partial(min) |
//!   | \\: Empty | Empty | Empty | Empty |
//!   | \\: Full | Full | Empty | Partial(b) |
//!   | \\: Partial | Partial(a) | Empty | Partial(min) |
//!
//!   Partial with Partial stays Partial and keeps the lower of the two source faces, so
//!   union and intersection are commutative. It may overstate the boundary: two
//!   boundaries crossing one voxel can make it wholly inside or outside the result, which
//!   voxels cannot tell.
//! - Complexity: O(n_a + n_b) nodes visited, less where a leaf decides.

use super::{Leaf, NONE, Node, NodeKind, Octree, compact};
use crate::{Error, Result};

/// A boolean operation on two solids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BooleanOp {
    /// Points in either.
    Union,
    /// Points in both.
    Intersection,
    /// Points in the first and not in the second.
    Difference,
}

impl BooleanOp {
    /// The result of two leaves (the table of the module documentation).
    #[must_use]
    pub fn leaf(self, a: Leaf, b: Leaf) -> Leaf {
        use Leaf::{Empty, Full, Partial};
        match (self, a, b) {
            (_, Partial { face: f }, Partial { face: g }) => Partial { face: f.min(g) },
            (BooleanOp::Union, Full, _) | (BooleanOp::Union, _, Full) => Full,
            (BooleanOp::Union, Empty, x) | (BooleanOp::Union, x, Empty) => x,
            (BooleanOp::Intersection, Empty, _) | (BooleanOp::Intersection, _, Empty) => Empty,
            (BooleanOp::Intersection, Full, x) | (BooleanOp::Intersection, x, Full) => x,
            (BooleanOp::Difference, Empty, _) | (BooleanOp::Difference, _, Full) => Empty,
            (BooleanOp::Difference, x, Empty) => x,
            (BooleanOp::Difference, Full, Partial { face }) => Partial { face },
        }
    }

    /// The result when node `a` (first operand) is this leaf, whatever `b` is.
    fn decided_by_first(self, a: Leaf) -> Option<Leaf> {
        match (self, a) {
            (BooleanOp::Union, Leaf::Full) => Some(Leaf::Full),
            (BooleanOp::Intersection | BooleanOp::Difference, Leaf::Empty) => Some(Leaf::Empty),
            _ => None,
        }
    }

    /// The result when node `b` (second operand) is this leaf, whatever `a` is.
    fn decided_by_second(self, b: Leaf) -> Option<Leaf> {
        match (self, b) {
            (BooleanOp::Union, Leaf::Full) => Some(Leaf::Full),
            (BooleanOp::Intersection, Leaf::Empty) | (BooleanOp::Difference, Leaf::Full) => {
                Some(Leaf::Empty)
            }
            _ => None,
        }
    }
}

impl Octree {
    /// Combines two trees over the same region and depth by parallel traversal.
    pub fn combine(&self, other: &Octree, op: BooleanOp) -> Result<Octree> {
        if self.region != other.region || self.frame != other.frame || self.depth != other.depth {
            return Err(Error::option(
                "octree boolean",
                format!(
                    "the trees must share region and depth (depth {} vs {}, region {:?} vs {:?})",
                    self.depth, other.depth, self.region, other.region
                ),
            ));
        }
        let mut raw = vec![Node::new(NONE, 0, 0)];
        // (output index, node of a, node of b); a leaf stands for its own children.
        let mut stack = vec![(0usize, 0u32, 0u32)];
        while let Some((o, ia, ib)) = stack.pop() {
            let (na, nb) = (self.nodes[ia as usize], other.nodes[ib as usize]);
            let decided = match (na.leaf(), nb.leaf()) {
                (Some(a), Some(b)) => Some(op.leaf(a, b)),
                (Some(a), None) => op.decided_by_first(a),
                (None, Some(b)) => op.decided_by_second(b),
                (None, None) => None,
            };
            if let Some(leaf) = decided {
                raw[o].set_leaf(leaf);
                continue;
            }
            let first = raw.len();
            raw[o].kind = NodeKind::Internal;
            raw[o].first_child = first as u32;
            let level = raw[o].level + 1;
            for k in 0..8u8 {
                raw.push(Node::new(o as u32, level, k));
                let ca = na.child(k).unwrap_or(ia);
                let cb = nb.child(k).unwrap_or(ib);
                stack.push((first + usize::from(k), ca, cb));
            }
        }
        Ok(Octree {
            region: self.region,
            frame: self.frame,
            depth: self.depth,
            nodes: compact(&raw),
            build_stats: super::BuildStats::default(),
        })
    }

    /// The union with another tree over the same region and depth.
    pub fn union(&self, other: &Octree) -> Result<Octree> {
        self.combine(other, BooleanOp::Union)
    }

    /// The intersection with another tree over the same region and depth.
    pub fn intersection(&self, other: &Octree) -> Result<Octree> {
        self.combine(other, BooleanOp::Intersection)
    }

    /// The difference (this minus the other) with a tree over the same region and depth.
    pub fn difference(&self, other: &Octree) -> Result<Octree> {
        self.combine(other, BooleanOp::Difference)
    }
}

#[cfg(test)]
mod tests {
    use super::super::Region;
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_leaf_table() {
        use Leaf::{Empty, Full, Partial};
        let p = |f| Partial { face: f };
        let u = BooleanOp::Union;
        let i = BooleanOp::Intersection;
        let d = BooleanOp::Difference;
        assert_eq!(u.leaf(Empty, p(3)), p(3));
        assert_eq!(u.leaf(p(3), Full), Full);
        assert_eq!(u.leaf(p(7), p(3)), p(3));
        assert_eq!(i.leaf(Full, p(3)), p(3));
        assert_eq!(i.leaf(p(3), Empty), Empty);
        assert_eq!(d.leaf(Full, p(3)), p(3));
        assert_eq!(d.leaf(p(3), Full), Empty);
        assert_eq!(d.leaf(p(3), Empty), p(3));
        assert_eq!(d.leaf(Empty, Full), Empty);
        // The shortcuts agree with the table for every second operand.
        for op in [u, i, d] {
            for a in [Empty, Full, p(1)] {
                for b in [Empty, Full, p(2)] {
                    if let Some(r) = op.decided_by_first(a) {
                        assert_eq!(op.leaf(a, b), r, "{op:?} {a:?} {b:?}");
                    }
                    if let Some(r) = op.decided_by_second(b) {
                        assert_eq!(op.leaf(a, b), r, "{op:?} {a:?} {b:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn mismatched_trees_are_refused() {
        let r = Region::new(DVec3::ZERO, 1.0).unwrap();
        let a = Octree::uniform(r, 3, Leaf::Full).unwrap();
        let b = Octree::uniform(r, 4, Leaf::Full).unwrap();
        assert!(a.union(&b).is_err());
        let c = Octree::uniform(Region::new(DVec3::ONE, 1.0).unwrap(), 3, Leaf::Full).unwrap();
        assert!(a.intersection(&c).is_err());
    }
}
