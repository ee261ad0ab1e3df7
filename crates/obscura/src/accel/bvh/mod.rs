//! A bounding-volume hierarchy over the triangles of a scene, for ray casting.
//!
//! Source: seed 000, "Περιβάλλοντες Όγκοι (5)-(7)" (hierarchies of bounding volumes and
//! the hierarchical `IntersectionTest`), seed 002 "Gerarchie di Bounding Volume" (a
//! child need not be tested if the ray misses its parent). Build: Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies" (2007), binned SAH; the
//! binary tree is then collapsed into an 8-wide one (Dammertz et al., "Shallow Bounding
//! Volume Hierarchies for Fast SIMD Ray Tracing of Incoherent Rays", 2008; Embree's
//! BVH8). Traversal: ordered, with a conservative single-precision box test (see
//! `traverse.rs`).
//!
//! - Input: [`SceneTriangles`]. Output: a [`Bvh`], built once and reusable for any
//!   number of views (it holds its own copy of the triangles in leaf order).
//! - Build (module `build`): binned surface area heuristic with [`BvhOptions::bins`] bins
//!   (16 by default) per axis, O(T log T) for T triangles; deep or unsplittable
//!   ranges fall back to median splits, so the depth stays below [`MAX_DEPTH`].
//! - Collapse: each wide node takes the binary node's two children and repeatedly
//!   opens the interior child of largest surface area until it has [`WIDTH`] = 8 (the
//!   SAH's most likely visited), which divides the depth by about three.
//! - Layout: [`BvhNode`] holds its eight children's boxes as structure-of-arrays
//!   (`min[axis][child]`), 256 bytes (four cache lines); leaves are stored in the
//!   slots of their parent (triangle range), so a ray tests eight boxes per step with
//!   one 8-lane computation and never visits a leaf node. Wider nodes mean fewer
//!   dependent steps per ray: on Sponza's atrium view a ray visits about 17 nodes
//!   against 27 with 4-wide nodes (and about 45 binary ones).
//! - Traversal (`traverse.rs`): the children a ray enters are visited nearest first, the
//!   others pushed with their entry distance and skipped when popped if a nearer hit
//!   was found since; triangles by the watertight `f64` test of
//!   [`crate::accel::triangles`], so the BVH finds exactly the hits brute force finds.
//!   [`Bvh::closest_hit_recursive`] is the seeds' `IntersectionTest` verbatim
//!   (unordered recursion), kept for comparison.
//! - Packets (`packet.rs`): coherent rays (4x4 pixels) traced together, with per-ray
//!   masks, so that each gets exactly its single-ray hit; the renderer uses them.
//! - Limitations: boxes are single precision (rounded outwards), so
//!   scenes with coordinates beyond about 10^30 are not supported; at most 2^29
//!   triangles.

mod build;
pub(crate) mod packet;
mod packet_lanes;
mod ray_packet;
pub(crate) mod traverse;

use std::time::Instant;

use glam::DVec3;

use crate::accel::triangles::SceneTriangles;
use crate::geom::Aabb;
use build::BinaryNode;

/// The deepest the binary tree may get (the build switches to median splits well
/// before); the wide tree is never deeper.
pub const MAX_DEPTH: usize = 96;

/// Children per node.
pub const WIDTH: usize = 8;

/// The largest leaf (triangles in one slot).
pub const MAX_LEAF_SIZE: usize = 16;

/// Build parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct BvhOptions {
    /// Bins per axis for the SAH sweep (2..=64).
    pub bins: usize,
    /// Ranges up to this size (at most [`MAX_LEAF_SIZE`]) may become leaves when the
    /// SAH prefers it; larger ones are always split.
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

/// What a slot of a [`BvhNode`] holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Nothing (a node with fewer than eight children).
    Empty,
    /// An interior node.
    Node(u32),
    /// A leaf: `count` triangles from `first` (in leaf order).
    Leaf {
        /// The first triangle.
        first: u32,
        /// How many.
        count: u32,
    },
}

/// An 8-wide node: the boxes of up to eight children, as structure of arrays, and what
/// each child is. Empty slots have the box `[+inf, +inf]`, which no ray enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct BvhNode {
    /// Lower corners: `min[axis][child]`.
    pub min: [[f32; WIDTH]; 3],
    /// Upper corners: `max[axis][child]`.
    pub max: [[f32; WIDTH]; 3],
    /// Per child: the node index (interior) or the first triangle (leaf).
    pub child: [u32; WIDTH],
    /// Per child: 0 for an interior node or an empty slot, else the leaf's triangle
    /// count.
    pub count: [u32; WIDTH],
}

const EMPTY_CHILD: u32 = u32::MAX;

impl Default for BvhNode {
    fn default() -> Self {
        BvhNode {
            min: [[f32::INFINITY; WIDTH]; 3],
            max: [[f32::INFINITY; WIDTH]; 3],
            child: [EMPTY_CHILD; WIDTH],
            count: [0; WIDTH],
        }
    }
}

impl BvhNode {
    /// The slots that hold a node or a leaf, one bit each. Traversals enter only
    /// these: an empty slot's box (`+inf` corners) is rejected by the slab test only
    /// while the ray's numbers are finite in `f32`.
    #[inline(always)]
    #[must_use]
    pub(crate) fn occupied(&self) -> u32 {
        (0..WIDTH).fold(0, |c, k| {
            c | u32::from(self.child[k] != EMPTY_CHILD || self.count[k] != 0) << k
        })
    }

    /// What slot `k` holds.
    #[must_use]
    pub fn slot(&self, k: usize) -> Slot {
        match (self.child[k], self.count[k]) {
            (EMPTY_CHILD, 0) => Slot::Empty,
            (c, 0) => Slot::Node(c),
            (first, count) => Slot::Leaf { first, count },
        }
    }

    /// The box of slot `k` in double precision (meaningless for empty slots).
    #[must_use]
    pub fn slot_box(&self, k: usize) -> Aabb {
        Aabb {
            min: DVec3::new(
                f64::from(self.min[0][k]),
                f64::from(self.min[1][k]),
                f64::from(self.min[2][k]),
            ),
            max: DVec3::new(
                f64::from(self.max[0][k]),
                f64::from(self.max[1][k]),
                f64::from(self.max[2][k]),
            ),
        }
    }

    fn set(&mut self, k: usize, b: &BinaryNode, slot: Slot) {
        for axis in 0..3 {
            self.min[axis][k] = b.min[axis];
            self.max[axis][k] = b.max[axis];
        }
        (self.child[k], self.count[k]) = match slot {
            Slot::Empty => (EMPTY_CHILD, 0),
            Slot::Node(i) => (i, 0),
            Slot::Leaf { first, count } => (first, count),
        };
    }
}

/// Figures of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhBuildStats {
    /// Milliseconds spent building (binary SAH build, collapse, triangle copy).
    pub build_ms: f64,
    /// Nodes of the binary SAH tree.
    pub binary_nodes: usize,
    /// Depth of the binary tree (the root alone has depth 1).
    pub binary_depth: usize,
    /// Wide nodes.
    pub nodes: usize,
    /// Leaves (triangle ranges).
    pub leaves: usize,
    /// Depth of the wide tree in nodes (leaves sit in their parent's slots).
    pub depth: usize,
    /// The SAH cost of the binary tree (expected node visits + triangle tests of a
    /// random ray meeting the root box, with the build's costs).
    pub sah_cost: f64,
}

/// An 8-wide bounding-volume hierarchy over triangles (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
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
        let tree = build::build(triangles, options);
        let mut bvh = Bvh {
            nodes: collapse(&tree.nodes),
            scale: tree.scale,
            ..Bvh::default()
        };
        let verts = triangles.vertices();
        let polys = triangles.triangle_polygons();
        bvh.triangles = tree.order.iter().map(|&i| verts[i as usize]).collect();
        bvh.polygons = tree.order.iter().map(|&i| polys[i as usize]).collect();
        bvh.order = tree.order;
        let depth = bvh
            .nodes_with_depth()
            .iter()
            .map(|n| n.1)
            .max()
            .unwrap_or(0);
        bvh.stats = BvhBuildStats {
            build_ms: start.elapsed().as_secs_f64() * 1e3,
            binary_nodes: tree.nodes.len(),
            binary_depth: tree.depth,
            nodes: bvh.nodes.len(),
            leaves: tree.leaves,
            depth,
            sah_cost: tree.sah_cost,
        };
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

    /// Node `i` (the root is 0).
    #[inline(always)]
    #[must_use]
    pub fn node(&self, i: u32) -> &BvhNode {
        &self.nodes[i as usize]
    }

    /// The number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
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
        if self.nodes.is_empty() {
            return out;
        }
        let mut stack = vec![(0u32, 1usize)];
        while let Some((i, d)) = stack.pop() {
            out.push((i, d));
            let n = self.node(i);
            for k in (0..WIDTH).rev() {
                if let Slot::Node(c) = n.slot(k) {
                    stack.push((c, d + 1));
                }
            }
        }
        out
    }

    /// Checks the structural invariants: every triangle in exactly one leaf, every
    /// child's boxes inside the box its parent keeps for it, every leaf box containing
    /// its triangles, the depth within [`MAX_DEPTH`]. Returns what is wrong.
    pub fn check_invariants(&self) -> Result<(), String> {
        if self.nodes.is_empty() {
            return if self.triangles.is_empty() {
                Ok(())
            } else {
                Err("triangles but no nodes".into())
            };
        }
        let mut seen = vec![0u32; self.triangles.len()];
        for (i, depth) in self.nodes_with_depth() {
            if depth > MAX_DEPTH {
                return Err(format!("node {i} at depth {depth} > {MAX_DEPTH}"));
            }
            let n = self.node(i);
            for k in 0..WIDTH {
                let b = n.slot_box(k);
                match n.slot(k) {
                    Slot::Empty => {}
                    Slot::Leaf { first, count } => {
                        let range = first as usize..(first + count) as usize;
                        if range.end > self.triangles.len() {
                            return Err(format!("leaf {i}/{k} points past the triangles"));
                        }
                        for t in range {
                            seen[t] += 1;
                            if let Some(v) = self.triangles[t].iter().find(|&&v| !b.contains(v)) {
                                return Err(format!("leaf {i}/{k}: vertex {v:?} outside {b:?}"));
                            }
                        }
                    }
                    Slot::Node(c) => {
                        if c as usize >= self.nodes.len() || c <= i {
                            return Err(format!("node {i}/{k} points to node {c}"));
                        }
                        let child = self.node(c);
                        for kk in 0..WIDTH {
                            if child.slot(kk) == Slot::Empty {
                                continue;
                            }
                            let cb = child.slot_box(kk);
                            if !(b.contains(cb.min) && b.contains(cb.max)) {
                                return Err(format!(
                                    "node {c} slot {kk} {cb:?} not inside its box in {i}: {b:?}"
                                ));
                            }
                        }
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

/// Collapses a binary tree into a [`WIDTH`]-wide one (see the module doc).
fn collapse(binary: &[BinaryNode]) -> Vec<BvhNode> {
    let Some(root) = binary.first() else {
        return Vec::new();
    };
    let mut wide = vec![BvhNode::default()];
    if root.is_leaf() {
        wide[0].set(
            0,
            root,
            Slot::Leaf {
                first: root.first,
                count: root.count,
            },
        );
        return wide;
    }
    // (binary interior node, wide node that represents it)
    let mut stack = vec![(0u32, 0u32)];
    // Each wide node stands for at least one binary interior node.
    wide.reserve(binary.len() / 2);
    // The children of the wide node being formed: binary index, half area (interior
    // nodes; -1 for leaves, never opened).
    let mut kids: Vec<(u32, f64)> = Vec::with_capacity(WIDTH);
    let kid = |c: u32| {
        let n = &binary[c as usize];
        (c, if n.is_leaf() { -1.0 } else { n.half_area() })
    };
    while let Some((b, w)) = stack.pop() {
        let node = &binary[b as usize];
        kids.clear();
        kids.extend([kid(node.first), kid(node.first + 1)]);
        while kids.len() < WIDTH {
            // The last of equal largest areas, as before the areas were cached.
            let Some((k, &(c, area))) = kids
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.1.total_cmp(&b.1.1))
            else {
                break;
            };
            if area < 0.0 {
                break;
            }
            kids.swap_remove(k);
            let first = binary[c as usize].first;
            kids.extend([kid(first), kid(first + 1)]);
        }
        for (k, &(c, _)) in kids.iter().enumerate() {
            let child = &binary[c as usize];
            let slot = if child.is_leaf() {
                Slot::Leaf {
                    first: child.first,
                    count: child.count,
                }
            } else {
                let index = wide.len() as u32;
                wide.push(BvhNode::default());
                stack.push((c, index));
                Slot::Node(index)
            };
            wide[w as usize].set(k, child, slot);
        }
    }
    wide
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
    fn node_is_whole_cache_lines() {
        assert_eq!(std::mem::size_of::<BvhNode>(), 32 * WIDTH);
        assert_eq!(std::mem::align_of::<BvhNode>(), 64);
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
            assert_eq!(s.binary_nodes, 2 * s.leaves - 1);
            assert!(s.depth >= 1 && s.depth <= s.binary_depth);
            // Collapsing keeps every binary leaf and removes interior nodes (each wide
            // node absorbs up to seven binary ones).
            let leaves: usize = (0..bvh.node_count() as u32)
                .map(|i| {
                    (0..WIDTH)
                        .filter(|&k| matches!(bvh.node(i).slot(k), Slot::Leaf { .. }))
                        .count()
                })
                .sum();
            assert_eq!(leaves, s.leaves);
            let interior = s.binary_nodes - s.leaves;
            assert!(
                s.nodes * (WIDTH - 1) >= interior && s.nodes < interior.max(2),
                "{s:?}"
            );
        }
        let empty = Bvh::build(&SceneTriangles::default(), &BvhOptions::default());
        assert_eq!(empty.node_count(), 0);
        empty.check_invariants().unwrap();
    }

    #[test]
    fn a_single_triangle_is_a_root_with_one_leaf() {
        let mut b = crate::scene::MeshBuilder::new();
        for p in [DVec3::ZERO, DVec3::X, DVec3::Y] {
            b.push_position(p);
        }
        b.push_face(&[0, 1, 2], None).unwrap();
        let mut s = crate::Scene::new();
        s.add(crate::scene::ObjectDesc::new("t", b.finish().0))
            .unwrap();
        let bvh = Bvh::build(&SceneTriangles::new(&s), &BvhOptions::default());
        assert_eq!(bvh.node_count(), 1);
        assert_eq!(bvh.node(0).slot(0), Slot::Leaf { first: 0, count: 1 });
        assert_eq!(bvh.node(0).slot(1), Slot::Empty);
        bvh.check_invariants().unwrap();
    }
}
