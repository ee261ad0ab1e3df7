//! Binary space partitioning tree of a scene's polygons, with polygon splitting.
//!
//! Source: seed 000, "Αλγόριθμος BSP (1)-(5)": every node holds a polygon whose plane
//! divides space; the polygons in front of it go to one subtree, those behind to the
//! other, and polygons crossing the plane are split in two ("extending a clipping
//! algorithm so that it returns both the inside and the outside part",
//! [`crate::clip::split::split_polygon`]). From any viewpoint, polygons on the far side
//! of a node's plane cannot hide polygons on the viewer's side, so painting the far
//! subtree, the node, then the near subtree is a correct back-to-front order. Fuchs,
//! Kedem and Naylor, "On visible surface generation by a priori tree structures",
//! SIGGRAPH 1980.
//!
//! - Input: a [`Scene`] (world-space polygons of every object). The tree is built once
//!   and serves every view of the scene ([`BspTree::traverse`]; rendering is in
//!   `surface::bsp`).
//! - Output: nodes (plane, coplanar fragments, front and back children) and
//!   fragments: pieces of the scene's polygons, each keeping its face id, object and
//!   mesh polygon, in world space.
//! - Splitter choice: at each node up to [`BspOptions::candidates`] polygons of the
//!   node's set are sampled (deterministically, from [`BspOptions::seed`]) and each
//!   candidate's plane is scored against the set (or an evenly spaced sample of
//!   [`BspOptions::score_sample`] of it):
//!   `score = split_weight * splits + balance_weight * |front - back|`, where `splits`
//!   counts the polygons the plane would cut and `front`, `back` those entirely on each
//!   side. The lowest score wins. A large split weight gives fewer fragments and a
//!   deeper tree; a large balance weight a shallower tree with more fragments (seed:
//!   "a plane that divides the scene into two parts of about the same cardinality").
//!   With [`BspOptions::axis_planes`], sets of 64 polygons or more also score an
//!   axis-aligned plane through the median of the polygons' first vertices along the
//!   longest side of their box: a convex object has no balancing plane of its own
//!   (each face's plane leaves all the others on one side), so without it the tree
//!   of a sphere is a chain, O(m^2) to build for m faces. The axis plane wins when it
//!   scores better, or when every polygon candidate is such a one-sided plane and the
//!   axis plane cuts less than a quarter of the set. Such a node may hold no polygon.
//! - Coplanar polygons (within the tolerance) stay in the node, both facings, sorted
//!   by descending face id: painting them in that order makes the lower id win
//!   exact ties, as the z-buffer does.
//! - Complexity: building is O(c P) per level for c candidates, O(c P log P) for a
//!   balanced tree, O(c P^2) at worst (seed: O(P^2)); a traversal is O(nodes +
//!   fragments) (seed: `DisplayBSP` is O(P)). Both use explicit stacks, so depth is
//!   not limited by the thread's stack.
//! - Frame: the tree works in world coordinates minus an origin, the centre of the
//!   scene's box ([`BspTree::origin`]): planes and distances are computed there, so
//!   that a small scene far from the world's origin (a part at x = 1e7) keeps the
//!   precision of its own size. Node and fragment planes are in that frame.
//! - Tolerance: a vertex of a polygon within `tolerance * s` of a plane counts as on
//!   it, plus the splitter's own deviation from its plane (non-planar quads); `s` is
//!   the larger extent of the two polygons in the tree's frame (a polygon's centre's
//!   largest coordinate plus its radius), at most the largest coordinate in that frame
//!   (about half the scene's size), and the tolerance at least the rounding of the
//!   world coordinates (`16 eps` of the origin's largest coordinate).
//! - Limitations: static scenes only (seed: "suitable for static scenes, not dynamic
//!   ones"); random or interpenetrating geometry can multiply the fragment count.
//!
//! Layout: this file holds the types and accessors; `build` (splitter choice,
//! partition, splits, memory budget), `classify` (which side of a plane a fragment
//! lies, with its tolerance) and `traverse` (the viewpoint-ordered walks) one
//! operation each, as in `accel::bvh` and `accel::octree`.
//!
//! Papers: Schumacher, Brand, Gilliland and Sharp, "Study for applying
//! computer-generated images to visual simulation", AFHRL-TR-69-14, 1969 (priority by
//! separating planes); Fuchs, Kedem and Naylor, "On visible surface generation by a
//! priori tree structures", SIGGRAPH 1980 (the BSP tree).

use std::ops::ControlFlow;

use glam::DVec3;

use crate::geom::{Aabb, Plane};
use crate::scene::{Camera, Projection, Scene};
use crate::{Error, Result};

mod build;
mod classify;
#[cfg(test)]
mod tests;
mod traverse;

/// The order in which [`BspTree::traverse`] visits fragments.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BspTraversal {
    /// Far to near: for the painter's algorithm (later fragments overwrite).
    BackToFront,
    /// Near to far: for write-once painting that can stop when the image is full.
    #[default]
    FrontToBack,
}

impl BspTraversal {
    /// The command-line name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BspTraversal::BackToFront => "back-to-front",
            BspTraversal::FrontToBack => "front-to-back",
        }
    }
}

impl std::str::FromStr for BspTraversal {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "back-to-front" => Ok(BspTraversal::BackToFront),
            "front-to-back" => Ok(BspTraversal::FrontToBack),
            _ => Err(Error::option(
                "BspOptions::traversal",
                format!("unknown traversal \"{s}\" (known: back-to-front, front-to-back)"),
            )),
        }
    }
}

/// How a BSP tree chooses its splitting planes, and how it is traversed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct BspOptions {
    /// Candidate planes sampled per node (at least 1).
    pub candidates: usize,
    /// Cost weight of a polygon split by the plane.
    pub split_weight: f64,
    /// Cost weight of the imbalance between the two sides.
    pub balance_weight: f64,
    /// Polygons each candidate is scored against (an evenly spaced sample of the
    /// node's set); 0 scores against the whole set.
    pub score_sample: usize,
    /// The traversal `surface::bsp` renders with.
    pub traversal: BspTraversal,
    /// Seed of the candidate sampling (the same seed gives the same tree).
    pub seed: u64,
    /// Distance below which a point counts as on a plane, relative to the scene's
    /// half size (the largest coordinate in the tree's frame, see [`BspTree::origin`]).
    pub tolerance: f64,
    /// Whether an axis-aligned plane through the median of the polygons' centres is a
    /// candidate too (for sets of at least 64 polygons). Without it, a tree of convex
    /// objects is a chain as deep as their face count: every face's plane has all
    /// the other faces of its object on one side.
    pub axis_planes: bool,
    /// The most fragments a build may make (every polygon, and two per split) before it
    /// gives up with an error: polygons
    /// that cut each other everywhere (random or interpenetrating geometry) multiply
    /// (the 10,000 large triangles of `demo:triangles` would make 14 million
    /// fragments; 5,000 random large triangles made 2 million in 6 s). A fragment of
    /// such a tree takes about 500 bytes, not the 230 of a fragment alone: each copies
    /// the list of cuts that made it, which grows with the depth. The default, 2
    /// million, is about 1 GB and a few seconds of building; the memory budget
    /// ([`BspOptions::memory_limit`]) bounds the bytes whatever the count.
    pub max_fragments: usize,
    /// The memory budget of the build in bytes (see [`crate::budget`]): the tree's
    /// vectors (fragments, their vertices and cuts, nodes) and the sets waiting to be
    /// split are summed by capacity after each node, and the build stops with an
    /// [`Error::Budget`] naming "BSP fragments" when they pass it. `None`: the default
    /// budget. (A count of fragments alone is no bound of the bytes: each fragment
    /// copies the list of cuts that made it, which grows with the depth of the tree.)
    pub memory_limit: Option<u64>,
}

impl BspOptions {
    /// 8 candidates plus an axis-aligned plane, split weight 8, balance weight 1,
    /// scored against up to 2048 polygons, front-to-back rendering.
    pub const DEFAULT: BspOptions = BspOptions {
        candidates: 8,
        split_weight: 8.0,
        balance_weight: 1.0,
        score_sample: 2048,
        traversal: BspTraversal::FrontToBack,
        seed: 0x0B5C_0BA5_EED5,
        tolerance: 1e-9,
        axis_planes: true,
        max_fragments: 2_000_000,
        memory_limit: None,
    };

    /// These options with a memory budget in bytes (see [`BspOptions::memory_limit`]).
    #[must_use]
    pub fn with_memory_limit(mut self, memory_limit: Option<u64>) -> Self {
        self.memory_limit = memory_limit;
        self
    }

    /// These options with another fragment budget (see [`BspOptions::max_fragments`]).
    #[must_use]
    pub fn with_max_fragments(mut self, max_fragments: usize) -> Self {
        self.max_fragments = max_fragments;
        self
    }

    /// These options with other weights.
    #[must_use]
    pub fn with_weights(mut self, split_weight: f64, balance_weight: f64) -> Self {
        self.split_weight = split_weight;
        self.balance_weight = balance_weight;
        self
    }

    /// These options with another number of candidates per node.
    #[must_use]
    pub fn with_candidates(mut self, candidates: usize) -> Self {
        self.candidates = candidates;
        self
    }

    /// These options with another scoring sample size (0: the whole set).
    #[must_use]
    pub fn with_score_sample(mut self, score_sample: usize) -> Self {
        self.score_sample = score_sample;
        self
    }

    /// These options with another traversal.
    #[must_use]
    pub fn with_traversal(mut self, traversal: BspTraversal) -> Self {
        self.traversal = traversal;
        self
    }

    /// These options with or without axis-aligned candidate planes.
    #[must_use]
    pub fn with_axis_planes(mut self, axis_planes: bool) -> Self {
        self.axis_planes = axis_planes;
        self
    }

    /// These options with another sampling seed.
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The largest accepted [`BspOptions::tolerance`]: beyond a thousandth of the
    /// scene's scale, whole polygons would count as lying on planes that cross them
    /// (a tolerance of 1e300 made 62 of 83 pixels wrong).
    pub const MAX_TOLERANCE: f64 = 1e-3;

    /// Checks the weights and tolerance.
    pub fn validate(&self) -> Result<()> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !ok(self.split_weight) || !ok(self.balance_weight) {
            return Err(Error::option(
                "BspOptions::split_weight, balance_weight",
                format!(
                    "the weights must be finite and non-negative (got split {}, balance {})",
                    self.split_weight, self.balance_weight
                ),
            ));
        }
        if !(ok(self.tolerance) && self.tolerance <= Self::MAX_TOLERANCE) {
            return Err(Error::option(
                "bsp tolerance",
                format!(
                    "must be finite, non-negative and at most {} (got {})",
                    Self::MAX_TOLERANCE,
                    self.tolerance
                ),
            ));
        }
        Ok(())
    }
}

impl Default for BspOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Where the viewer is, for ordering a traversal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Viewpoint {
    /// A perspective eye at this world point.
    Point(DVec3),
    /// A parallel projection: the viewer is at infinity in this world direction
    /// (from the scene towards the eye).
    Direction(DVec3),
}

impl Viewpoint {
    /// The same viewpoint in a frame whose origin is the world point `origin` (a
    /// [`BspTree`]'s, see [`BspTree::origin`]): a point moves, a direction does not.
    #[must_use]
    pub fn relative_to(self, origin: DVec3) -> Self {
        match self {
            Viewpoint::Point(p) => Viewpoint::Point(p - origin),
            Viewpoint::Direction(d) => Viewpoint::Direction(d),
        }
    }

    /// The viewpoint of a camera.
    #[must_use]
    pub fn of_camera(camera: &Camera) -> Self {
        match camera.projection {
            Projection::Perspective { .. } => Viewpoint::Point(camera.eye),
            Projection::Orthographic { .. } => Viewpoint::Direction(camera.eye - camera.target),
        }
    }

    /// Positive when the viewer is on the plane's front side, negative behind, 0 on it
    /// (the viewpoint and the plane in the same frame: see [`Viewpoint::relative_to`]).
    #[inline]
    #[must_use]
    pub fn side(&self, plane: &Plane) -> f64 {
        match *self {
            Viewpoint::Point(p) => plane.evaluate(p),
            Viewpoint::Direction(d) => plane.normal.dot(d),
        }
    }
}

/// What a traversal calls ([`BspTree::traverse_with`]).
pub trait BspVisitor {
    /// Called before node `node`'s subtree is visited; `false` skips the whole subtree
    /// (e.g. because it is hidden). Visits everything by default.
    fn enter(&mut self, node: u32) -> bool {
        let _ = node;
        true
    }

    /// Called for each fragment in order; `Break` ends the traversal.
    fn fragment(&mut self, fragment: u32) -> ControlFlow<()>;
}

/// `local` of vertices made by splitting.
const MADE_BY_SPLIT: u32 = u32::MAX;

/// A vertex of the tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BspVertex {
    /// World-space position.
    pub world: DVec3,
    /// The object it belongs to.
    pub object: u32,
    /// Its index in the object's mesh, or [`MADE_BY_SPLIT`].
    local: u32,
}

impl BspVertex {
    /// The mesh vertex index, `None` for a vertex made by a split.
    #[must_use]
    pub fn mesh_vertex(&self) -> Option<u32> {
        (self.local != MADE_BY_SPLIT).then_some(self.local)
    }
}

/// A piece of a scene polygon (the whole polygon if it was never split).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Scene-wide face id.
    pub face: u32,
    /// Object index.
    pub object: u32,
    /// Index of the mesh polygon (in the object's mesh) it comes from.
    pub polygon: u32,
    /// The plane of the original polygon (Newell, unit normal, front side
    /// counter-clockwise), shared by all its pieces, in the tree's frame (see
    /// [`BspTree::origin`]).
    pub plane: Plane,
    /// Largest distance of the original polygon's vertices from that plane.
    pub thickness: f64,
    start: u32,
    len: u32,
    /// The fragment of the whole polygon (itself if never split).
    root: u32,
    /// The splits that made it: entries `cuts[cut_start..cut_start + cut_len]` of the
    /// tree (see [`BspTree::fragment_cuts`]).
    cut_start: u32,
    cut_len: u32,
}

/// A node: a plane, the fragments lying in it (none for an axis-aligned plane that
/// meets no polygon), and two subtrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BspNode {
    /// The splitting plane (that of the fragment chosen as splitter, or axis-aligned),
    /// in the tree's frame (see [`BspTree::origin`]).
    pub plane: Plane,
    /// The subtree on the plane's positive side.
    pub front: Option<u32>,
    /// The subtree on the negative side.
    pub back: Option<u32>,
    /// A distance within which a point counted as on this plane (an upper bound: each
    /// polygon was classified with the tolerance of its pair with the splitter).
    pub eps: f64,
    first: u32,
    count: u32,
    depth: u32,
}

/// Counts and time of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BspBuildStats {
    /// Scene polygons given to the build.
    pub input_polygons: u64,
    /// Polygons left out because they have no plane (zero area).
    pub degenerate: u64,
    /// Fragments stored in the nodes.
    pub fragments: u64,
    /// Nodes.
    pub nodes: u64,
    /// Polygon splits (each adds one fragment).
    pub splits: u64,
    /// Depth of the deepest node (the root has depth 1; 0 for an empty tree).
    pub depth: u64,
    /// Build time in milliseconds.
    pub build_ms: f64,
}

/// A BSP tree of a scene. See the module doc.
///
/// ```
/// use obscura::accel::bsp::{BspOptions, BspTraversal, BspTree, Viewpoint};
/// use obscura::scene::demo;
/// use glam::DVec3;
/// let tree = BspTree::build(&demo::cube(), &BspOptions::default()).unwrap();
/// assert_eq!(tree.stats().fragments, 6); // a convex solid needs no split
/// let order = tree.paint_order(Viewpoint::Point(DVec3::new(0., 0., 5.)), BspTraversal::BackToFront);
/// // The face nearest the eye (+z, face 5) is painted last.
/// assert_eq!(tree.fragment(*order.last().unwrap()).face, 5);
/// ```
#[derive(Clone, Debug)]
pub struct BspTree {
    nodes: Vec<BspNode>,
    node_fragments: Vec<u32>,
    fragments: Vec<Fragment>,
    fragment_vertices: Vec<u32>,
    vertices: Vec<BspVertex>,
    /// The splits of the fragments: `node << 1 | front` (see [`BspTree::fragment_cuts`]).
    cuts: Vec<u32>,
    /// Per vertex, its position in the tree's frame (world minus `origin`).
    local: Vec<DVec3>,
    /// The world point at the origin of the tree's frame.
    origin: DVec3,
    vertex_base: Vec<u32>,
    object_vertex_counts: Vec<u32>,
    face_count: u32,
    eps: f64,
    /// [`BspOptions::tolerance`].
    relative_tolerance: f64,
    /// The rounding of the world coordinates (the smallest tolerance).
    rounding: f64,
    /// Bounding sphere (centre, radius) of each fragment, for quick classification.
    spheres: Vec<[f64; 4]>,
    /// A distance far above the rounding of plane evaluations in the scene.
    slack: f64,
    /// Per node, the box of its subtree's fragments and their number.
    subtree_bounds: Vec<Aabb>,
    subtree_counts: Vec<u32>,
    stats: BspBuildStats,
}

impl BspTree {
    fn fragment_indices(&self, f: &Fragment) -> &[u32] {
        &self.fragment_vertices[f.start as usize..(f.start + f.len) as usize]
    }

    /// Build counts and time.
    #[must_use]
    pub fn stats(&self) -> &BspBuildStats {
        &self.stats
    }

    /// The root node, `None` for an empty tree.
    #[must_use]
    pub fn root(&self) -> Option<u32> {
        (!self.nodes.is_empty()).then_some(0)
    }

    /// Number of nodes. Children always have larger indices than their parent.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Node `i`.
    #[must_use]
    pub fn node(&self, i: u32) -> &BspNode {
        &self.nodes[i as usize]
    }

    /// The fragments lying in node `i`'s plane, in back-to-front painting order
    /// (descending face id).
    #[must_use]
    pub fn node_fragments(&self, i: u32) -> &[u32] {
        let n = &self.nodes[i as usize];
        &self.node_fragments[n.first as usize..(n.first + n.count) as usize]
    }

    /// The depth of node `i` (the root has depth 1).
    #[must_use]
    pub fn node_depth(&self, i: u32) -> u32 {
        self.nodes[i as usize].depth
    }

    /// Fragment `i` (ids come from [`BspTree::node_fragments`] or a traversal).
    #[must_use]
    pub fn fragment(&self, i: u32) -> &Fragment {
        &self.fragments[i as usize]
    }

    /// The vertex indices (into [`BspTree::vertices`]) of fragment `i`.
    #[must_use]
    pub fn fragment_vertex_indices(&self, i: u32) -> &[u32] {
        self.fragment_indices(&self.fragments[i as usize])
    }

    /// The fragment of the whole polygon fragment `i` is a piece of (`i` itself if the
    /// polygon was never split).
    #[must_use]
    pub fn fragment_root(&self, i: u32) -> u32 {
        self.fragments[i as usize].root
    }

    /// The splits that cut fragment `i` out of its whole polygon
    /// ([`BspTree::fragment_root`]), first to last: per split, the node whose plane cut
    /// it and whether the fragment is the piece on the plane's front (positive) side.
    /// The fragment is the part of the whole polygon on those sides of those planes
    /// (up to the rounding of its vertices): the painter draws it so, as the whole
    /// polygon's pixels on those sides, and the pieces of one polygon then cover each
    /// of its pixels exactly once (see [`crate::surface::bsp`]).
    pub fn fragment_cuts(&self, i: u32) -> impl ExactSizeIterator<Item = (u32, bool)> + '_ {
        let f = &self.fragments[i as usize];
        self.cuts[f.cut_start as usize..(f.cut_start + f.cut_len) as usize]
            .iter()
            .map(|&c| (c >> 1, c & 1 == 1))
    }

    /// The world-space points of fragment `i`.
    #[must_use]
    pub fn fragment_points(&self, i: u32) -> Vec<DVec3> {
        self.fragment_vertex_indices(i)
            .iter()
            .map(|&v| self.vertices[v as usize].world)
            .collect()
    }

    /// All vertices: every mesh vertex of every object, then those made by splits.
    #[must_use]
    pub fn vertices(&self) -> &[BspVertex] {
        &self.vertices
    }

    /// Index in [`BspTree::vertices`] of object `k`'s mesh vertex 0.
    #[must_use]
    pub fn object_vertex_base(&self, k: usize) -> u32 {
        self.vertex_base[k]
    }

    /// The world point at the origin of the tree's frame (the centre of the scene's
    /// box), in which node and fragment planes are expressed: a world point `p` is on
    /// the front side of a node's plane when `plane.evaluate(p - origin) > 0`, and a
    /// viewpoint is compared with them after [`Viewpoint::relative_to`]. Traversals
    /// take world viewpoints and do that themselves.
    #[must_use]
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The largest absolute tolerance of plane classification (before adding a
    /// splitter's thickness): pairs of small polygons get less (see the module doc).
    #[must_use]
    pub fn tolerance(&self) -> f64 {
        self.eps
    }

    /// Whether the tree was built from a scene with this scene's objects, meshes and
    /// face ids (same counts everywhere).
    #[must_use]
    pub fn matches(&self, scene: &Scene) -> bool {
        scene.face_count() == self.face_count
            && scene.objects().len() == self.object_vertex_counts.len()
            && scene
                .objects()
                .iter()
                .zip(&self.object_vertex_counts)
                .all(|(o, &n)| o.mesh.positions().len() == n as usize)
    }

    /// The world-space box of every fragment in node `i`'s subtree.
    #[must_use]
    pub fn subtree_bounds(&self, i: u32) -> &Aabb {
        &self.subtree_bounds[i as usize]
    }

    /// The number of fragments in node `i`'s subtree.
    #[must_use]
    pub fn subtree_fragments(&self, i: u32) -> u32 {
        self.subtree_counts[i as usize]
    }
}
