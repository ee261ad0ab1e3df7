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

use std::ops::ControlFlow;
use std::time::Instant;

use glam::DVec3;

use crate::clip::split::{Split, split_polygon};
use crate::geom::{Aabb, Plane};
use crate::scene::{Camera, Projection, Scene, demo::SplitMix64};
use crate::{Error, Result};

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
                "--bsp-traversal",
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
                "--bsp-weights",
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
    pub(crate) fn of_camera(camera: &Camera) -> Self {
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
    pub(crate) fn mesh_vertex(&self) -> Option<u32> {
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

/// The centroid of the points and the largest distance from it.
fn bounding_sphere(points: &[DVec3]) -> [f64; 4] {
    let c = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    let r = points.iter().fold(0.0f64, |m, &p| m.max(p.distance(c)));
    [c.x, c.y, c.z, r]
}

/// Sets smaller than this get no axis-aligned candidate plane.
const AXIS_PLANE_MIN_SET: usize = 64;

/// A node's splitting plane: a polygon's (index in the node's set) or an
/// axis-aligned one.
enum Splitter {
    Polygon(usize),
    Axis(Plane),
}

/// Where a fragment lies relative to a plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Front,
    Back,
    On,
    Spanning,
}

impl BspTree {
    /// Builds the tree of every polygon of every object of the scene. An empty scene
    /// gives an empty tree. Fails only on invalid options.
    pub fn build(scene: &Scene, options: &BspOptions) -> Result<BspTree> {
        options.validate()?;
        let start = Instant::now();
        let mut tree = BspTree {
            nodes: Vec::new(),
            node_fragments: Vec::new(),
            fragments: Vec::new(),
            fragment_vertices: Vec::new(),
            vertices: Vec::new(),
            cuts: Vec::new(),
            local: Vec::new(),
            origin: DVec3::ZERO,
            vertex_base: Vec::with_capacity(scene.objects().len()),
            object_vertex_counts: Vec::with_capacity(scene.objects().len()),
            face_count: scene.face_count(),
            eps: 0.0,
            relative_tolerance: options.tolerance,
            rounding: 0.0,
            spheres: Vec::new(),
            slack: 0.0,
            subtree_bounds: Vec::new(),
            subtree_counts: Vec::new(),
            stats: BspBuildStats::default(),
        };
        let bounds = scene.bounds();
        if !bounds.is_empty() {
            tree.origin = bounds.center();
        }
        let mut scale = 0.0f64;
        for (k, o) in scene.objects().iter().enumerate() {
            tree.vertex_base.push(tree.vertices.len() as u32);
            tree.object_vertex_counts
                .push(o.mesh.positions().len() as u32);
            for (i, &p) in o.mesh.positions().iter().enumerate() {
                let world = o.transform.transform_point3(p);
                let local = world - tree.origin;
                scale = scale.max(local.abs().max_element());
                tree.vertices.push(BspVertex {
                    world,
                    object: k as u32,
                    local: i as u32,
                });
                tree.local.push(local);
            }
        }
        // World coordinates carry rounding of their own magnitude: points meant to be
        // on one plane are that far off it, whatever the tree's frame.
        let rounding = 16.0 * f64::EPSILON * tree.origin.abs().max_element();
        tree.eps = (options.tolerance * scale)
            .max(rounding)
            .max(f64::MIN_POSITIVE);
        tree.rounding = rounding.max(f64::MIN_POSITIVE);
        tree.slack = 1e-12 * scale.max(f64::MIN_POSITIVE);
        let mut points = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            let base = tree.vertex_base[k];
            for p in 0..o.mesh.polygon_count() {
                tree.stats.input_polygons += 1;
                let idx = o.mesh.polygon(p);
                points.clear();
                points.extend(idx.iter().map(|&i| tree.local[(base + i) as usize]));
                let Some(plane) = Plane::newell(&points) else {
                    tree.stats.degenerate += 1;
                    continue;
                };
                let thickness = points
                    .iter()
                    .fold(0.0f64, |m, &q| m.max(plane.evaluate(q).abs()));
                let start = tree.fragment_vertices.len() as u32;
                tree.fragment_vertices.extend(idx.iter().map(|&i| base + i));
                tree.spheres.push(bounding_sphere(&points));
                tree.fragments.push(Fragment {
                    face: o.first_face + o.mesh.polygon_face(p),
                    object: k as u32,
                    polygon: p as u32,
                    plane,
                    thickness,
                    start,
                    len: idx.len() as u32,
                    root: tree.fragments.len() as u32,
                    cut_start: 0,
                    cut_len: 0,
                });
            }
        }
        let all: Vec<u32> = (0..tree.fragments.len() as u32).collect();
        tree.build_nodes(all, options)?;
        tree.compute_subtree_bounds();
        tree.stats.nodes = tree.nodes.len() as u64;
        tree.stats.fragments = tree.node_fragments.len() as u64;
        tree.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(tree)
    }

    fn build_nodes(&mut self, all: Vec<u32>, options: &BspOptions) -> Result<()> {
        if all.is_empty() {
            return Ok(());
        }
        let mut rng = SplitMix64(options.seed);
        let placeholder = BspNode {
            plane: Plane {
                normal: DVec3::Z,
                d: 0.0,
            },
            front: None,
            back: None,
            eps: 0.0,
            first: 0,
            count: 0,
            depth: 0,
        };
        self.nodes.push(placeholder);
        let budget = crate::budget::MemoryBudget::from_option(options.memory_limit);
        // Bytes of the sets waiting on the stack.
        let mut waiting = all.capacity() as u64 * 4;
        let mut stack: Vec<(u32, Vec<u32>, u32)> = vec![(0, all, 1)];
        let mut points = Vec::new();
        while let Some((n, set, depth)) = stack.pop() {
            waiting -= set.capacity() as u64 * 4;
            let (plane, eps, splitter) = match self.choose_splitter(&set, options, &mut rng) {
                Splitter::Polygon(i) => {
                    let f = &self.fragments[set[i] as usize];
                    (f.plane, self.own_eps(set[i]) + f.thickness, Some(set[i]))
                }
                Splitter::Axis(plane) => (plane, self.eps, None),
            };
            // A polygon splitter stays in its node whatever its own vertices say (a
            // slightly non-planar quad must not be cut by its own plane).
            let mut on: Vec<u32> = splitter.into_iter().collect();
            let (mut front, mut back) = (Vec::new(), Vec::new());
            for &f in &set {
                if Some(f) == splitter {
                    continue;
                }
                match self.classify(f, &plane, eps) {
                    Side::Front => front.push(f),
                    Side::Back => back.push(f),
                    Side::On => on.push(f),
                    Side::Spanning => {
                        let (a, b) = self.split(f, n, &plane, eps, &mut points);
                        front.extend(a);
                        back.extend(b);
                    }
                }
            }
            on.sort_by_key(|&f| (std::cmp::Reverse(self.fragments[f as usize].face), f));
            let first = self.node_fragments.len() as u32;
            self.node_fragments.extend_from_slice(&on);
            self.stats.depth = self.stats.depth.max(u64::from(depth));
            let mut node = BspNode {
                plane,
                front: None,
                back: None,
                // An upper bound of the pairs' tolerances.
                eps: eps.max(self.eps),
                first,
                count: on.len() as u32,
                depth,
            };
            for (child, is_front) in [(back, false), (front, true)] {
                if child.is_empty() {
                    continue;
                }
                let idx = self.nodes.len() as u32;
                self.nodes.push(placeholder);
                if is_front {
                    node.front = Some(idx);
                } else {
                    node.back = Some(idx);
                }
                waiting += child.capacity() as u64 * 4;
                stack.push((idx, child, depth + 1));
            }
            self.nodes[n as usize] = node;
            let bytes = self.bytes() + waiting + stack.capacity() as u64 * 32;
            if bytes > budget.limit() {
                return Err(budget.exceeded("BSP fragments", self.fragments.len() as u64, bytes));
            }
            if self.fragments.len() > options.max_fragments {
                return Err(Error::option(
                    "bsp fragments",
                    format!(
                        "the tree of {} polygons passed {} fragments ({} splits so far): \
                         its polygons cut each other too much for a BSP tree (random or \
                         interpenetrating geometry); render with another algorithm, or \
                         raise BspOptions::max_fragments",
                        self.stats.input_polygons, options.max_fragments, self.stats.splits
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The bytes the tree's vectors hold (by capacity).
    fn bytes(&self) -> u64 {
        fn b<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * size_of::<T>()) as u64
        }
        b(&self.nodes)
            + b(&self.node_fragments)
            + b(&self.fragments)
            + b(&self.fragment_vertices)
            + b(&self.vertices)
            + b(&self.cuts)
            + b(&self.local)
            + b(&self.spheres)
    }

    /// Children have larger indices than their parent: one pass from the end.
    fn compute_subtree_bounds(&mut self) {
        let n = self.nodes.len();
        self.subtree_bounds = vec![Aabb::EMPTY; n];
        self.subtree_counts = vec![0; n];
        for i in (0..n).rev() {
            let node = self.nodes[i];
            let mut b = Aabb::EMPTY;
            for &f in self.node_fragments(i as u32) {
                for &v in self.fragment_indices(&self.fragments[f as usize]) {
                    b = b.with_point(self.vertices[v as usize].world);
                }
            }
            let mut count = node.count;
            for c in [node.front, node.back].into_iter().flatten() {
                b = b.union(self.subtree_bounds[c as usize]);
                count += self.subtree_counts[c as usize];
            }
            self.subtree_bounds[i] = b;
            self.subtree_counts[i] = count;
        }
    }

    /// The chosen splitter (see the module doc for the score).
    fn choose_splitter(&self, set: &[u32], options: &BspOptions, rng: &mut SplitMix64) -> Splitter {
        let n = set.len();
        if n <= 2 {
            return Splitter::Polygon(0);
        }
        let k = options.candidates.max(1);
        let candidates: Vec<usize> = if n <= k {
            (0..n).collect()
        } else {
            (0..k)
                .map(|_| (rng.next_u64() % n as u64) as usize)
                .collect()
        };
        let axis = (options.axis_planes && n >= AXIS_PLANE_MIN_SET)
            .then(|| self.median_plane(set))
            .flatten();
        if candidates.len() == 1 && axis.is_none() {
            return Splitter::Polygon(candidates[0]);
        }
        let sample = if options.score_sample == 0 || n <= options.score_sample {
            n
        } else {
            options.score_sample
        };
        // (score, whether the plane leaves one side empty without splitting, splits)
        let score = |plane: &Plane, eps: f64, skip: usize| {
            let (mut front, mut back, mut spans) = (0u64, 0u64, 0u64);
            for s in 0..sample {
                // Evenly spaced over the set: s * n / sample, in integers.
                let i = (s as u64 * n as u64 / sample as u64) as usize;
                if i == skip {
                    continue;
                }
                match self.classify(set[i], plane, eps) {
                    Side::Front => front += 1,
                    Side::Back => back += 1,
                    Side::Spanning => spans += 1,
                    Side::On => {}
                }
            }
            let cost = options.split_weight * spans as f64
                + options.balance_weight * (front as f64 - back as f64).abs();
            (cost, spans == 0 && (front == 0 || back == 0), spans)
        };
        let mut best = (f64::INFINITY, 0usize, false);
        for &c in &candidates {
            let f = &self.fragments[set[c] as usize];
            let (cost, one_sided, _) = score(&f.plane, self.own_eps(set[c]) + f.thickness, c);
            if cost < best.0 {
                best = (cost, c, one_sided);
            }
        }
        if let Some(plane) = axis {
            let (cost, _, spans) = score(&plane, self.eps, usize::MAX);
            // A one-sided polygon plane only peels one polygon off: on a convex
            // surface every candidate is one, and a chain of m nodes costs O(m^2) to
            // build. The axis plane then wins if it cuts less than a quarter of the set.
            let better = cost < best.0 || (best.2 && 4 * spans < sample as u64);
            if better && self.divides(set, &plane) {
                return Splitter::Axis(plane);
            }
        }
        Splitter::Polygon(best.1)
    }

    /// The plane perpendicular to the longest side of the box of the polygons'
    /// first vertices, through their median along it.
    fn median_plane(&self, set: &[u32]) -> Option<Plane> {
        let first = |f: u32| {
            let v = self.fragment_vertices[self.fragments[f as usize].start as usize];
            self.local[v as usize]
        };
        let (lo, hi) = set
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(first(f)), hi.max(first(f)))
            });
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if !(extent[axis] > 0.0) {
            return None;
        }
        let mut coords: Vec<f64> = set.iter().map(|&f| first(f)[axis]).collect();
        let mid = coords.len() / 2;
        let (_, &mut median, _) = coords.select_nth_unstable_by(mid, f64::total_cmp);
        let mut normal = DVec3::ZERO;
        normal[axis] = 1.0;
        Some(Plane { normal, d: -median })
    }

    /// Whether a plane without a polygon of its own leaves fewer polygons on each side
    /// than the set has (else the recursion would not end).
    fn divides(&self, set: &[u32], plane: &Plane) -> bool {
        let (mut front, mut back) = (0usize, 0usize);
        for &f in set {
            match self.classify(f, plane, self.eps) {
                Side::Front => front += 1,
                Side::Back => back += 1,
                Side::Spanning => {
                    front += 1;
                    back += 1;
                }
                Side::On => {}
            }
        }
        front < set.len() && back < set.len()
    }

    /// The tolerance of fragment `f` by its own extent (see [`BspTree::pair_eps`]).
    fn own_eps(&self, f: u32) -> f64 {
        let [cx, cy, cz, r] = self.spheres[f as usize];
        (self.relative_tolerance * (DVec3::new(cx, cy, cz).abs().max_element() + r))
            .max(self.rounding)
            .min(self.eps)
    }

    /// The tolerance of classifying fragment `f` against a plane whose own tolerance is
    /// `eps` (the splitter's, or the tree's for an axis plane): the larger of the two,
    /// each taken from its polygon's extent in the tree's frame (its centre's largest
    /// coordinate plus its radius), at most the tree's. With the tree's tolerance for
    /// every pair, a ground 2e5 across set 1e-4 for triangles 1e-4 across, and two of
    /// them were painted in the wrong order.
    fn pair_eps(&self, f: u32, eps: f64) -> f64 {
        eps.max(self.own_eps(f))
    }

    fn classify(&self, f: u32, plane: &Plane, eps: f64) -> Side {
        let eps = self.pair_eps(f, eps);
        let len = plane.normal.length();
        // Most fragments are far from the plane: their bounding sphere decides without
        // reading the vertices (with a margin far above rounding).
        let [cx, cy, cz, r] = self.spheres[f as usize];
        let d = plane.evaluate(DVec3::new(cx, cy, cz)) / len;
        if d - r > eps + self.slack {
            return Side::Front;
        }
        if d + r < -eps - self.slack {
            return Side::Back;
        }
        let frag = &self.fragments[f as usize];
        let (mut front, mut back) = (false, false);
        for &v in self.fragment_indices(frag) {
            // The same expression as `split_polygon`, so both agree on every vertex.
            let d = plane.evaluate(self.local[v as usize]) / len;
            front |= d > eps;
            back |= d < -eps;
        }
        match (front, back) {
            (true, true) => Side::Spanning,
            (true, false) => Side::Front,
            (false, true) => Side::Back,
            (false, false) => Side::On,
        }
    }

    /// Splits fragment `f` by the plane of node `node`; returns the new front and back
    /// fragments.
    fn split(
        &mut self,
        f: u32,
        node: u32,
        plane: &Plane,
        eps: f64,
        points: &mut Vec<DVec3>,
    ) -> (Option<u32>, Option<u32>) {
        let frag = self.fragments[f as usize];
        let idx: Vec<u32> = self.fragment_indices(&frag).to_vec();
        points.clear();
        points.extend(idx.iter().map(|&v| self.local[v as usize]));
        match split_polygon(points, plane, self.pair_eps(f, eps)) {
            Split::Front | Split::Coplanar { .. } => (Some(f), None),
            Split::Back => (None, Some(f)),
            Split::Spanning { front, back } => {
                self.stats.splits += 1;
                let mut made = Vec::new();
                let a = self.push_piece(&frag, &idx, points, &front, &mut made, node << 1 | 1);
                let b = self.push_piece(&frag, &idx, points, &back, &mut made, node << 1);
                (Some(a), Some(b))
            }
        }
    }

    /// Adds a piece of `parent`: points equal to a parent vertex reuse its index (so
    /// pieces keep the exact projection of the original vertices), new points become
    /// new vertices, shared by both pieces through `made`. The piece's cuts are its
    /// parent's and `cut`.
    fn push_piece(
        &mut self,
        parent: &Fragment,
        idx: &[u32],
        parent_points: &[DVec3],
        piece: &[DVec3],
        made: &mut Vec<(DVec3, u32)>,
        cut: u32,
    ) -> u32 {
        let start = self.fragment_vertices.len() as u32;
        for &q in piece {
            let old = parent_points.iter().position(|&p| p == q).map(|j| idx[j]);
            let v = match old.or_else(|| made.iter().find(|m| m.0 == q).map(|m| m.1)) {
                Some(v) => v,
                None => {
                    self.vertices.push(BspVertex {
                        world: q + self.origin,
                        object: parent.object,
                        local: MADE_BY_SPLIT,
                    });
                    self.local.push(q);
                    let v = (self.vertices.len() - 1) as u32;
                    made.push((q, v));
                    v
                }
            };
            self.fragment_vertices.push(v);
        }
        self.spheres.push(bounding_sphere(piece));
        let cut_start = self.cuts.len() as u32;
        let inherited = parent.cut_start as usize..(parent.cut_start + parent.cut_len) as usize;
        self.cuts.extend_from_within(inherited);
        self.cuts.push(cut);
        self.fragments.push(Fragment {
            start,
            len: piece.len() as u32,
            cut_start,
            cut_len: parent.cut_len + 1,
            ..*parent
        });
        (self.fragments.len() - 1) as u32
    }

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
    pub(crate) fn fragment_vertex_indices(&self, i: u32) -> &[u32] {
        self.fragment_indices(&self.fragments[i as usize])
    }

    /// The fragment of the whole polygon fragment `i` is a piece of (`i` itself if the
    /// polygon was never split).
    #[must_use]
    pub(crate) fn fragment_root(&self, i: u32) -> u32 {
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
    pub(crate) fn object_vertex_base(&self, k: usize) -> u32 {
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

    /// Visits the fragments in back-to-front or front-to-back order from a viewpoint
    /// (seed 000's `DisplayBSP`, with an explicit stack). The visitor may stop the
    /// traversal by returning `ControlFlow::Break`; returns whether it ran to the end.
    ///
    /// A viewpoint exactly on a node's plane sees that node's fragments edge-on and
    /// the two subtrees on opposite sides of a line of the image, so either order is
    /// correct there; the front subtree is taken as the near one.
    pub fn traverse<F>(&self, viewpoint: Viewpoint, traversal: BspTraversal, visit: F) -> bool
    where
        F: FnMut(u32) -> ControlFlow<()>,
    {
        struct Fragments<F>(F);
        impl<F: FnMut(u32) -> ControlFlow<()>> BspVisitor for Fragments<F> {
            fn fragment(&mut self, fragment: u32) -> ControlFlow<()> {
                (self.0)(fragment)
            }
        }
        self.traverse_with(viewpoint, traversal, &mut Fragments(visit))
    }

    /// [`BspTree::traverse`] with a visitor that may also skip whole subtrees
    /// ([`BspVisitor::enter`]).
    pub fn traverse_with<V: BspVisitor>(
        &self,
        viewpoint: Viewpoint,
        traversal: BspTraversal,
        visitor: &mut V,
    ) -> bool {
        enum Item {
            Node(u32),
            Fragments(u32),
        }
        let Some(root) = self.root() else {
            return true;
        };
        let viewpoint = viewpoint.relative_to(self.origin);
        let mut stack = vec![Item::Node(root)];
        while let Some(item) = stack.pop() {
            match item {
                Item::Node(n) => {
                    if !visitor.enter(n) {
                        continue;
                    }
                    let node = &self.nodes[n as usize];
                    let (near, far) = if viewpoint.side(&node.plane) >= 0.0 {
                        (node.front, node.back)
                    } else {
                        (node.back, node.front)
                    };
                    let (first, last) = match traversal {
                        BspTraversal::BackToFront => (far, near),
                        BspTraversal::FrontToBack => (near, far),
                    };
                    // The stack pops in reverse: push what is visited last first.
                    if let Some(c) = last {
                        stack.push(Item::Node(c));
                    }
                    stack.push(Item::Fragments(n));
                    if let Some(c) = first {
                        stack.push(Item::Node(c));
                    }
                }
                Item::Fragments(n) => {
                    let frags = self.node_fragments(n);
                    let flow = match traversal {
                        BspTraversal::BackToFront => {
                            frags.iter().try_for_each(|&f| visitor.fragment(f))
                        }
                        BspTraversal::FrontToBack => {
                            frags.iter().rev().try_for_each(|&f| visitor.fragment(f))
                        }
                    };
                    if flow.is_break() {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The world-space box of every fragment in node `i`'s subtree.
    #[must_use]
    pub(crate) fn subtree_bounds(&self, i: u32) -> &Aabb {
        &self.subtree_bounds[i as usize]
    }

    /// The number of fragments in node `i`'s subtree.
    #[must_use]
    pub(crate) fn subtree_fragments(&self, i: u32) -> u32 {
        self.subtree_counts[i as usize]
    }

    /// The fragments in the order a traversal visits them.
    #[must_use]
    pub fn paint_order(&self, viewpoint: Viewpoint, traversal: BspTraversal) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.node_fragments.len());
        self.traverse(viewpoint, traversal, |f| {
            out.push(f);
            ControlFlow::Continue(())
        });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ObjectDesc, demo};

    #[test]
    fn empty_scene_gives_empty_tree() {
        let t = BspTree::build(&Scene::new(), &BspOptions::default()).unwrap();
        assert_eq!(t.root(), None);
        assert!(
            t.paint_order(Viewpoint::Point(DVec3::Z), BspTraversal::BackToFront)
                .is_empty()
        );
        assert_eq!(t.stats().depth, 0);
    }

    #[test]
    fn bad_options_are_refused() {
        let s = demo::cube();
        let nan = BspOptions::default().with_weights(f64::NAN, 1.0);
        assert!(BspTree::build(&s, &nan).is_err());
        let negative = BspOptions::default().with_weights(1.0, -1.0);
        assert!(BspTree::build(&s, &negative).is_err());
        // Zero candidates is read as one.
        assert!(BspTree::build(&s, &BspOptions::default().with_candidates(0)).is_ok());
    }

    #[test]
    fn crossing_quads_split_once_and_keep_their_area() {
        // Two 2x2 squares crossing at right angles through each other's middle.
        let mut s = Scene::new();
        let quad = |pts: [DVec3; 4]| {
            let mut b = crate::scene::MeshBuilder::new();
            for p in pts {
                b.push_position(p);
            }
            b.push_face(&[0, 1, 2, 3], None).unwrap();
            b.finish().0
        };
        s.add(ObjectDesc::new(
            "a",
            quad([
                DVec3::new(-1., -1., 0.),
                DVec3::new(1., -1., 0.),
                DVec3::new(1., 1., 0.),
                DVec3::new(-1., 1., 0.),
            ]),
        ))
        .unwrap();
        s.add(ObjectDesc::new(
            "b",
            quad([
                DVec3::new(0., -1., -1.),
                DVec3::new(0., -1., 1.),
                DVec3::new(0., 1., 1.),
                DVec3::new(0., 1., -1.),
            ]),
        ))
        .unwrap();
        let t = BspTree::build(&s, &BspOptions::default()).unwrap();
        // a is the root; b's halves go to either side.
        assert_eq!(t.stats().splits, 1);
        assert_eq!(t.stats().fragments, 3);
        assert_eq!(t.stats().nodes, 3);
        assert_eq!(t.stats().depth, 2);
        let total: f64 = (0..t.node_count() as u32)
            .flat_map(|n| t.node_fragments(n).to_vec())
            .map(|f| crate::geom::polygon_area(&t.fragment_points(f)))
            .sum();
        assert!((total - 8.0).abs() < 1e-12);
        // The two new vertices are shared by both pieces.
        let made = t
            .vertices()
            .iter()
            .filter(|v| v.mesh_vertex().is_none())
            .count();
        assert_eq!(made, 2);
    }
}
