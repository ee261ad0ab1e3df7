//! A bounding-volume hierarchy over the triangles of a scene, for ray casting.
//!
//! Source: seed 000, "Περιβάλλοντες Όγκοι (5)-(7)" (hierarchies of bounding volumes and
//! the hierarchical `IntersectionTest`), seed 002 "Gerarchie di Bounding Volume" (a
//! child need not be tested if the ray misses its parent). Build: Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies" (2007), binned SAH.
//! Traversal: ordered, with the robust box test of Ize, "Robust BVH Ray Traversal"
//! (JCGT 2013) adapted to single precision by a margin (see [`traverse`]).
//!
//! - Input: [`SceneTriangles`]. Output: a [`Bvh`], built once and reusable for any
//!   number of views (it holds its own copy of the triangles in leaf order).
//! - Build ([`build`]): binned surface area heuristic with [`BvhOptions::bins`] bins
//!   (16 by default) per axis, O(T log T) for T triangles; deep or unsplittable
//!   ranges fall back to median splits, so depth stays below [`MAX_DEPTH`].
//! - Layout: nodes of 32 bytes (single-precision box, two `u32`), siblings stored side
//!   by side in 64-byte pairs so one cache line holds both boxes a step tests.
//! - Traversal ([`traverse`]): nearest child first, the other pushed with its entry
//!   distance and skipped when popped if a nearer hit was found since; triangles by
//!   the watertight `f64` test of [`crate::accel::triangles`], so the BVH finds
//!   exactly the hits brute force finds. [`Bvh::closest_hit_recursive`] is the seeds'
//!   `IntersectionTest` verbatim (unordered recursion), kept for comparison.
//! - Limitations: binary tree, scalar box tests (no 4/8-wide nodes or packets); the
//!   boxes are single precision (rounded outwards), so scenes spanning more than
//!   about 10^30 units are not supported.

mod build;
pub mod traverse;

use std::time::Instant;

use glam::DVec3;

use crate::accel::triangles::SceneTriangles;
use crate::geom::Aabb;

/// The deepest a tree may get (build switches to median splits well before).
pub const MAX_DEPTH: usize = 96;

/// Build parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct BvhOptions {
    /// Bins per axis for the SAH sweep.
    pub bins: usize,
    /// Ranges up to this size may become leaves when the SAH prefers it; larger ones
    /// are always split.
    pub max_leaf_size: usize,
    /// Cost of visiting a node relative to one triangle test (SAH).
    pub traversal_cost: f64,
}

impl Default for BvhOptions {
    fn default() -> Self {
        BvhOptions {
            bins: 16,
            max_leaf_size: 8,
            traversal_cost: 1.0,
        }
    }
}

/// A node: its box in single precision (rounded outwards) and either two children
/// (`count == 0`, children at `first` and `first + 1`) or `count` triangles from
/// `first`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct BvhNode {
    /// Lower corner.
    pub min: [f32; 3],
    /// Left child (interior) or first triangle (leaf).
    pub first: u32,
    /// Upper corner.
    pub max: [f32; 3],
    /// Number of triangles (0 for interior nodes).
    pub count: u32,
}

impl BvhNode {
    /// Whether it is a leaf.
    #[inline(always)]
    #[must_use]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The box in double precision.
    #[must_use]
    pub fn aabb(&self) -> Aabb {
        Aabb {
            min: DVec3::new(
                f64::from(self.min[0]),
                f64::from(self.min[1]),
                f64::from(self.min[2]),
            ),
            max: DVec3::new(
                f64::from(self.max[0]),
                f64::from(self.max[1]),
                f64::from(self.max[2]),
            ),
        }
    }
}

/// Two sibling nodes in one cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct NodePair(pub(crate) [BvhNode; 2]);

/// Figures of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhBuildStats {
    /// Milliseconds spent building (including the triangle copy).
    pub build_ms: f64,
    /// Number of nodes.
    pub nodes: usize,
    /// Number of leaves.
    pub leaves: usize,
    /// Depth (the root alone has depth 1).
    pub depth: usize,
    /// The SAH cost of the tree (expected node visits + triangle tests of a random
    /// ray hitting the root box, with the build's costs).
    pub sah_cost: f64,
}

/// A bounding-volume hierarchy over triangles (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pairs: Vec<NodePair>,
    triangles: Vec<[DVec3; 3]>,
    polygons: Vec<u32>,
    order: Vec<u32>,
    stats: BvhBuildStats,
    scale: f64,
}

impl Bvh {
    /// Builds the hierarchy over the triangles.
    #[must_use]
    pub fn build(triangles: &SceneTriangles, options: &BvhOptions) -> Self {
        let start = Instant::now();
        let mut bvh = build::build(triangles, options);
        bvh.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        bvh
    }

    /// The build figures.
    #[must_use]
    pub fn stats(&self) -> &BvhBuildStats {
        &self.stats
    }

    /// Whether it holds no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Node `i` (the root is 0; node 1 does not exist, it pads the root's pair).
    #[inline(always)]
    #[must_use]
    pub fn node(&self, i: u32) -> &BvhNode {
        &self.pairs[(i >> 1) as usize].0[(i & 1) as usize]
    }

    /// The root, if the tree is not empty.
    #[must_use]
    pub fn root(&self) -> Option<&BvhNode> {
        (!self.is_empty()).then(|| self.node(0))
    }

    /// The triangles in leaf order.
    #[must_use]
    pub fn triangles(&self) -> &[[DVec3; 3]] {
        &self.triangles
    }

    /// The polygon of each triangle in leaf order.
    #[must_use]
    pub fn triangle_polygons(&self) -> &[u32] {
        &self.polygons
    }

    /// For each triangle in leaf order, its index in the [`SceneTriangles`] it was
    /// built from.
    #[must_use]
    pub fn triangle_order(&self) -> &[u32] {
        &self.order
    }

    /// The largest absolute coordinate of any triangle (sets the box-test margin).
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Every node index reachable from the root with its depth (root depth 1), in
    /// depth-first order.
    #[must_use]
    pub fn nodes_with_depth(&self) -> Vec<(u32, usize)> {
        let mut out = Vec::new();
        if self.is_empty() {
            return out;
        }
        let mut stack = vec![(0u32, 1usize)];
        while let Some((i, d)) = stack.pop() {
            out.push((i, d));
            let n = self.node(i);
            if !n.is_leaf() {
                stack.push((n.first + 1, d + 1));
                stack.push((n.first, d + 1));
            }
        }
        out
    }

    /// Checks the structural invariants: every triangle in exactly one leaf, every
    /// child box inside its parent's, every leaf box containing its triangles, depth
    /// within [`MAX_DEPTH`]. Returns what is wrong.
    pub fn check_invariants(&self) -> Result<(), String> {
        if self.is_empty() {
            return Ok(());
        }
        let mut seen = vec![0u32; self.triangles.len()];
        for (i, depth) in self.nodes_with_depth() {
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = self.node(i);
            let b = n.aabb();
            if n.is_leaf() {
                let range = n.first as usize..(n.first + n.count) as usize;
                if range.end > self.triangles.len() {
                    return Err(format!("leaf {i} points past the triangles"));
                }
                for k in range {
                    seen[k] += 1;
                    if let Some(v) = self.triangles[k].iter().find(|&&v| !b.contains(v)) {
                        return Err(format!("leaf {i}: vertex {v:?} outside {b:?}"));
                    }
                }
            } else {
                for c in [n.first, n.first + 1] {
                    let cb = self.node(c).aabb();
                    if !(b.contains(cb.min) && b.contains(cb.max)) {
                        return Err(format!("child {c} {cb:?} not inside parent {i} {b:?}"));
                    }
                }
            }
        }
        if let Some(k) = seen.iter().position(|&s| s != 1) {
            return Err(format!("triangle {k} is in {} leaves", seen[k]));
        }
        let mut order = self.order.clone();
        order.sort_unstable();
        if order.iter().enumerate().any(|(k, &o)| o as usize != k) {
            return Err("the triangle order is not a permutation".into());
        }
        Ok(())
    }
}

/// Rounds down to `f32` (the largest `f32` not above `x`).
#[inline]
pub(crate) fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x { f.next_down() } else { f }
}

/// Rounds up to `f32` (the smallest `f32` not below `x`).
#[inline]
pub(crate) fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x { f.next_up() } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo;

    #[test]
    fn node_is_32_bytes_and_pairs_fill_a_cache_line() {
        assert_eq!(std::mem::size_of::<BvhNode>(), 32);
        assert_eq!(std::mem::size_of::<NodePair>(), 64);
        assert_eq!(std::mem::align_of::<NodePair>(), 64);
    }

    #[test]
    fn outward_rounding() {
        for x in [0.1, -0.1, 1e-40, -1e-40, 3.0, 1e30, -7.123456789] {
            assert!(
                f64::from(f32_down(x)) <= x && f64::from(f32_up(x)) >= x,
                "{x}"
            );
            assert!(f32_up(x) == f32_down(x) || f32_down(x).next_up() == f32_up(x));
        }
    }

    #[test]
    fn invariants_hold_on_demo_scenes() {
        for scene in [demo::default_scene(), demo::city(8, 8, 1), demo::cube()] {
            let tris = SceneTriangles::new(&scene);
            let bvh = Bvh::build(&tris, &BvhOptions::default());
            bvh.check_invariants().unwrap();
            let s = bvh.stats();
            assert_eq!(s.nodes, 2 * s.leaves - 1);
            assert!(s.depth >= 1 && s.depth <= MAX_DEPTH);
        }
        let empty = Bvh::build(&SceneTriangles::default(), &BvhOptions::default());
        assert!(empty.root().is_none());
        empty.check_invariants().unwrap();
    }
}
