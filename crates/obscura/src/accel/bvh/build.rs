//! Binned SAH construction (Wald 2007).
//!
//! Input: the scene's triangles; output: a binary tree whose leaves hold ranges of a
//! permutation of them. O(T log T) for T triangles, single threaded, no allocation per
//! node (the triangles are partitioned in place, the nodes and bins preallocated).
//!
//! Each range of triangles is binned by centroid into `B` equal slices of its centroid
//! box along each axis; each bin keeps its triangle count and box. A sweep from both
//! ends gives, for every one of the `B - 1` planes between bins, the cost
//! `A_L N_L + A_R N_R` (half areas, counts); the cheapest plane over the three axes
//! wins if it beats making a leaf (`N` tests) after paying
//! [`BvhOptions::traversal_cost`] for the node. Children's boxes are the unions of
//! their bins' boxes and their centroid boxes are gathered while partitioning, so no
//! extra pass over the triangles is needed. Ranges of fewer than `2B` triangles use
//! `max(N / 2, 4)` bins: the reset and sweep of the bins cost as much as binning the
//! triangles there, and on Sponza the SAH cost of the tree grows by 0.004% only.
//!
//! Small ranges (at most [`SMALL`] triangles, most nodes of a tree with leaves of one
//! to four triangles) are not binned: every split of the triangles sorted by centroid
//! along each axis is evaluated (the exact SAH sweep, Wald 2007 §3, cheaper there than
//! resetting and sweeping the bins), and a pair of triangles has one split only.
//!
//! Fallbacks: all centroids equal (the SAH cannot separate them) or deeper than
//! [`MEDIAN_DEPTH`]: split at the median by index order along the longest axis, which
//! halves the range and bounds the depth.
//!
//! Limitations: boxes and centroids are single precision (rounded outwards from the
//! `f64` vertices); the SAH costs within a node are compared in `f32`, so near-equal
//! planes may be chosen differently than in exact arithmetic (the tree stays valid).

use super::BvhOptions;
use crate::accel::triangles::SceneTriangles;

/// A node of the binary tree: its box and either two children (`count == 0`, at
/// `first` and `first + 1`) or `count` triangles from `first` (in build order).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct BinaryNode {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BinaryNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub fn half_area(&self) -> f64 {
        Box3::new(self.min, self.max).half_area()
    }
}

/// The binary SAH tree: nodes (root at 0) and the triangles' order in its leaves.
#[derive(Clone, Debug, Default)]
pub(super) struct BinaryTree {
    pub nodes: Vec<BinaryNode>,
    pub order: Vec<u32>,
    pub leaves: usize,
    pub depth: usize,
    pub sah_cost: f64,
    pub scale: f64,
}

/// The most bins per axis.
pub(crate) const MAX_BINS: usize = 64;

/// Below this depth splits are SAH; at and beyond it, median splits.
pub(crate) const MEDIAN_DEPTH: usize = 56;

/// A single-precision box under construction. Four lanes, the last always 0, so that
/// growing one box by another is one vector min and one max.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Box3 {
    min: [f32; 4],
    max: [f32; 4],
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0],
        max: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0],
    };

    fn new(min: [f32; 3], max: [f32; 3]) -> Self {
        Box3 {
            min: [min[0], min[1], min[2], 0.0],
            max: [max[0], max[1], max[2], 0.0],
        }
    }

    fn min3(&self) -> [f32; 3] {
        [self.min[0], self.min[1], self.min[2]]
    }

    fn max3(&self) -> [f32; 3] {
        [self.max[0], self.max[1], self.max[2]]
    }

    // Plain comparisons instead of `f32::min`: the inputs are never NaN, and this
    // compiles to single min/max instructions in the binning loop.
    #[inline(always)]
    fn grow(&mut self, o: &Box3) {
        for k in 0..4 {
            self.min[k] = if o.min[k] < self.min[k] {
                o.min[k]
            } else {
                self.min[k]
            };
            self.max[k] = if o.max[k] > self.max[k] {
                o.max[k]
            } else {
                self.max[k]
            };
        }
    }

    /// Grows by a point given in four lanes (the last 0).
    #[inline(always)]
    fn grow_point(&mut self, p: &[f32; 4]) {
        for (k, &x) in p.iter().enumerate() {
            self.min[k] = if x < self.min[k] { x } else { self.min[k] };
            self.max[k] = if x > self.max[k] { x } else { self.max[k] };
        }
    }

    /// Half the surface area of the box with its sides multiplied by `scale`, in
    /// `f32` (the SAH sweep compares such areas within one node; the scale keeps
    /// them far from overflow whatever the coordinates); 0 for an empty box.
    #[inline(always)]
    fn scaled_half_area(&self, scale: f32) -> f32 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        let e: [f32; 3] = std::array::from_fn(|k| (self.max[k] - self.min[k]) * scale);
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }

    /// Half the surface area, in `f64` to keep sums of many areas exact enough.
    #[inline(always)]
    fn half_area(&self) -> f64 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        let e: [f64; 3] = std::array::from_fn(|k| f64::from(self.max[k]) - f64::from(self.min[k]));
        e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
    }
}

/// A triangle during the build: its box and centroid, with its index in the fourth
/// lane of the centroid (as bits; the lane is carried along by the vector operations
/// and never read as a number). The primitives are moved while partitioning (not an
/// index array into them), so every pass reads memory sequentially; with a million
/// triangles, random access would cost a cache miss per triangle per level. 48 bytes,
/// aligned to 16, so no primitive needs more than two cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct Prim {
    bounds: Box3,
    centroid: [f32; 4],
}

impl Prim {
    fn index(&self) -> u32 {
        self.centroid[3].to_bits()
    }
}

#[derive(Clone, Copy, Debug)]
struct Bin {
    count: u32,
    bounds: Box3,
}

const EMPTY_BIN: Bin = Bin {
    count: 0,
    bounds: Box3::EMPTY,
};

/// The boxes and centroid boxes of two children: `(left, left centroids, right,
/// right centroids)`.
type ChildBoxes = (Box3, Box3, Box3, Box3);

/// A range waiting to be turned into a node.
struct Task {
    node: u32,
    start: usize,
    end: usize,
    depth: usize,
    bounds: Box3,
    centroids: Box3,
}

pub(super) fn build(triangles: &SceneTriangles, options: &BvhOptions) -> BinaryTree {
    let n = triangles.len();
    let mut tree = BinaryTree::default();
    if n == 0 || n > (u32::MAX >> 3) as usize {
        return tree;
    }
    let bins = options.bins.clamp(2, MAX_BINS);
    let max_leaf = options.max_leaf_size.clamp(1, super::MAX_LEAF_SIZE);
    let verts = triangles.vertices();
    let mut prims: Vec<Prim> = Vec::with_capacity(n);
    let (mut root_bounds, mut root_centroids) = (Box3::EMPTY, Box3::EMPTY);
    // Four lanes (the last unused) so that the loop vectorizes; plain comparisons
    // since the coordinates are finite.
    let mut scale4 = [0.0f64; 4];
    for (i, t) in verts.iter().enumerate() {
        let v: [[f64; 4]; 3] = t.map(|p| [p.x, p.y, p.z, 0.0]);
        let lo: [f64; 4] = std::array::from_fn(|k| {
            let l = if v[0][k] < v[1][k] { v[0][k] } else { v[1][k] };
            if l < v[2][k] { l } else { v[2][k] }
        });
        let hi: [f64; 4] = std::array::from_fn(|k| {
            let h = if v[0][k] > v[1][k] { v[0][k] } else { v[1][k] };
            if h > v[2][k] { h } else { v[2][k] }
        });
        for k in 0..4 {
            // max(|lo|, |hi|) = max(-lo, hi) as lo <= hi.
            let m = if -lo[k] > hi[k] { -lo[k] } else { hi[k] };
            scale4[k] = if m > scale4[k] { m } else { scale4[k] };
        }
        let b = Box3 {
            min: below4(lo),
            max: above4(hi),
        };
        let c: [f32; 4] = std::array::from_fn(|k| (b.min[k] + b.max[k]) * 0.5);
        root_bounds.grow(&b);
        root_centroids.grow_point(&c);
        prims.push(Prim {
            bounds: b,
            centroid: [c[0], c[1], c[2], f32::from_bits(i as u32)],
        });
    }
    let scale = scale4[0].max(scale4[1]).max(scale4[2]);
    // At most 2n - 1 nodes: reserved, so the array is never copied while it grows.
    let mut nodes: Vec<BinaryNode> = Vec::with_capacity(2 * n - 1);
    nodes.push(BinaryNode::default());
    let mut stack = vec![Task {
        node: 0,
        start: 0,
        end: n,
        depth: 1,
        bounds: root_bounds,
        centroids: root_centroids,
    }];
    let mut bin_store = Binner {
        bins: vec![[EMPTY_BIN; 3]; bins],
        right: vec![[0.0; 3]; bins],
    };
    let (mut leaves, mut max_depth, mut sah) = (0usize, 0usize, 0.0f64);
    let root_area = root_bounds.half_area().max(f64::MIN_POSITIVE);
    while let Some(task) = stack.pop() {
        let count = task.end - task.start;
        max_depth = max_depth.max(task.depth);
        let area = task.bounds.half_area();
        let split: Option<(usize, Option<ChildBoxes>)> = if count <= 1 {
            None
        } else if task.depth >= MEDIAN_DEPTH {
            let range = &mut prims[task.start..task.end];
            Some((median_split(range, &task.centroids), None))
        } else if count == 2 {
            // One way to split two triangles: each alone.
            let (a, b) = (&prims[task.start], &prims[task.start + 1]);
            let apart = (0..3).any(|k| a.centroid[k] != b.centroid[k]);
            let split_cost = options.traversal_cost
                + (a.bounds.half_area() + b.bounds.half_area()) / area.max(f64::MIN_POSITIVE);
            if count <= max_leaf && (!apart || split_cost >= 2.0 || area == 0.0) {
                None
            } else {
                Some((1, None))
            }
        } else if count <= SMALL {
            let range = &mut prims[task.start..task.end];
            match small_split(range, &task.bounds) {
                Some(plan) => {
                    let split_cost =
                        options.traversal_cost + f64::from(plan.cost) / area.max(f64::MIN_POSITIVE);
                    if count <= max_leaf && (split_cost >= count as f64 || area == 0.0) {
                        None
                    } else {
                        plan.apply(range);
                        Some((plan.at, None))
                    }
                }
                None if count <= max_leaf => None,
                None => Some((median_split(range, &task.centroids), None)),
            }
        } else {
            match sah_split(
                &prims[task.start..task.end],
                &task.bounds,
                &task.centroids,
                &mut bin_store,
            ) {
                Some(plan) => {
                    let leaf_cost = count as f64;
                    let split_cost =
                        options.traversal_cost + f64::from(plan.cost) / area.max(f64::MIN_POSITIVE);
                    if count <= max_leaf && (split_cost >= leaf_cost || area == 0.0) {
                        None
                    } else {
                        let range = &mut prims[task.start..task.end];
                        let (mid, lc, rc) = partition(range, &task.centroids, &plan, bins);
                        Some((mid, Some((plan.left, lc, plan.right, rc))))
                    }
                }
                None if count <= max_leaf => None,
                None => {
                    let range = &mut prims[task.start..task.end];
                    Some((median_split(range, &task.centroids), None))
                }
            }
        };
        let left = nodes.len() as u32;
        let node = &mut nodes[task.node as usize];
        node.min = task.bounds.min3();
        node.max = task.bounds.max3();
        let Some(split_at) = split else {
            node.first = task.start as u32;
            node.count = count as u32;
            leaves += 1;
            sah += area / root_area * count as f64;
            continue;
        };
        node.first = left;
        node.count = 0;
        sah += area / root_area * options.traversal_cost;
        nodes.push(BinaryNode::default());
        nodes.push(BinaryNode::default());
        let (mid, plan) = split_at;
        let mid = task.start + mid;
        let ((lb, lc), (rb, rc)) = match plan {
            Some((lb, lc, rb, rc)) => ((lb, lc), (rb, rc)),
            None => (
                range_bounds(&prims[task.start..mid]),
                range_bounds(&prims[mid..task.end]),
            ),
        };
        // Push the right first so the left subtree is laid out next (depth first).
        stack.push(Task {
            node: left + 1,
            start: mid,
            end: task.end,
            depth: task.depth + 1,
            bounds: rb,
            centroids: rc,
        });
        stack.push(Task {
            node: left,
            start: task.start,
            end: mid,
            depth: task.depth + 1,
            bounds: lb,
            centroids: lc,
        });
    }
    tree.order = prims.iter().map(Prim::index).collect();
    tree.nodes = nodes;
    tree.scale = scale;
    tree.leaves = leaves;
    tree.depth = max_depth;
    tree.sah_cost = sah;
    tree
}

/// [`f32_down`](super::f32_down) lane by lane, without branches (so that it
/// vectorizes, and because whether the nearest float is above `x` is a coin toss).
/// The nearest float `f`, then one step down if it is above `x`: one unit less in the
/// bits if `f` is positive, one more if negative (when `f` rounds to zero from below
/// it is -0, whose next step down is the negative denormal closest to zero; +0 is
/// never above `x`, as `x` would then be negative and round to -0).
#[inline(always)]
fn below4(x: [f64; 4]) -> [f32; 4] {
    std::array::from_fn(|k| {
        let f = x[k] as f32;
        let bits = f.to_bits();
        let up = u32::from(f64::from(f) > x[k]);
        let negative = bits >> 31;
        f32::from_bits(bits.wrapping_sub(up).wrapping_add((negative & up) << 1))
    })
}

/// [`f32_up`](super::f32_up) lane by lane: `-below(-x)`.
#[inline(always)]
fn above4(x: [f64; 4]) -> [f32; 4] {
    below4(x.map(|v| -v)).map(|v| -v)
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32, bins: usize) -> usize {
    // `x = (c - lo) * scale` is in [0, bins]. Adding 2^23 to `x - 1/2` (clamped at 0)
    // leaves round(x - 1/2) in the low mantissa bits (the sum stays in [2^23, 2^24),
    // where floats are the integers): floor(x) but for ties, by a branch-free
    // conversion, which Rust's `as` is not (it handles NaN and overflow), and which
    // vectorizes over the three axes. The mapping is monotone and the same in the
    // sweep and the partition, which is all binning needs.
    const MAGIC: f32 = 8_388_608.0;
    let x = (c - lo) * scale - 0.5;
    let x = if x > 0.0 { x } else { 0.0 } + MAGIC;
    ((x.to_bits() & 0x007f_ffff) as usize).min(bins - 1)
}

/// [`bin_of`] on the three axes at once (same operations lane by lane, so the same
/// results).
#[inline(always)]
fn bins_of(c: &[f32; 4], lo: &[f32; 4], scale: &[f32; 4], bins: usize) -> [usize; 3] {
    const MAGIC: f32 = 8_388_608.0;
    let mut out = [0u32; 3];
    // Three lanes: the fourth of a centroid holds a triangle's index.
    for k in 0..3 {
        let x = (c[k] - lo[k]) * scale[k] - 0.5;
        let x = if x > 0.0 { x } else { 0.0 } + MAGIC;
        out[k] = (x.to_bits() & 0x007f_ffff).min(bins as u32 - 1);
    }
    [out[0] as usize, out[1] as usize, out[2] as usize]
}

/// The best SAH plane of a range.
#[derive(Clone, Copy, Debug)]
struct Plan {
    axis: usize,
    /// Bins left of the plane.
    plane: usize,
    /// `A_L N_L + A_R N_R`, with the areas in the node's own scale (see `sah_split`).
    cost: f32,
    left: Box3,
    right: Box3,
}

/// Bins per axis, and the sweep's right-hand costs, reused from node to node.
struct Binner {
    bins: Vec<[Bin; 3]>,
    right: Vec<[f32; 3]>,
}

/// The best SAH plane, `None` when the centroids coincide on every axis. Areas are
/// measured with the node's largest side as unit (`Plan::cost` is relative to that).
#[inline(always)]
fn sah_split(prims: &[Prim], bounds: &Box3, cbox: &Box3, binner: &mut Binner) -> Option<Plan> {
    // Small ranges need few bins: the sweep and the reset cost O(bins) per node (see
    // the module doc; `partition` must use the same count).
    let nb = binner.bins.len().min((prims.len() / 2).max(4));
    let bins = &mut binner.bins[..nb];
    let right = &mut binner.right[..nb];
    let mut scale = [0.0f32; 4];
    let mut usable = [false; 3];
    for k in 0..3 {
        let extent = cbox.max[k] - cbox.min[k];
        usable[k] = extent > 0.0 && extent.is_finite();
        scale[k] = if usable[k] { nb as f32 / extent } else { 0.0 };
    }
    if !usable.iter().any(|&u| u) {
        return None;
    }
    bins.fill([EMPTY_BIN; 3]);
    for p in prims {
        let index = bins_of(&p.centroid, &cbox.min, &scale, nb);
        for k in 0..3 {
            let bin = &mut bins[index[k]][k];
            bin.count += 1;
            bin.bounds.grow(&p.bounds);
        }
    }
    let side = (0..3).fold(0.0f32, |m, k| m.max(bounds.max[k] - bounds.min[k]));
    let unit = if side > 0.0 && side.is_finite() {
        1.0 / side
    } else {
        1.0
    };
    // The three axes swept together (independent chains): right[s][k] = A N of the
    // bins from s on, then the left side's A N plus that for each plane.
    let (mut acc, mut cnt) = ([Box3::EMPTY; 3], [0u32; 3]);
    for s in (1..nb).rev() {
        for k in 0..3 {
            acc[k].grow(&bins[s][k].bounds);
            cnt[k] += bins[s][k].count;
            right[s][k] = acc[k].scaled_half_area(unit) * cnt[k] as f32;
        }
    }
    let n = prims.len() as u32;
    let (mut acc, mut cnt) = ([Box3::EMPTY; 3], [0u32; 3]);
    let mut best: Option<(usize, usize, f32, Box3)> = None;
    for s in 1..nb {
        for k in 0..3 {
            acc[k].grow(&bins[s - 1][k].bounds);
            cnt[k] += bins[s - 1][k].count;
            if !usable[k] || cnt[k] == 0 || cnt[k] == n {
                continue;
            }
            let cost = acc[k].scaled_half_area(unit) * cnt[k] as f32 + right[s][k];
            if best.is_none_or(|b| cost < b.2) {
                best = Some((k, s, cost, acc[k]));
            }
        }
    }
    let (axis, plane, cost, left) = best?;
    let mut right = Box3::EMPTY;
    for bin in &bins[plane..nb] {
        right.grow(&bin[axis].bounds);
    }
    Some(Plan {
        axis,
        plane,
        cost: cost * side * side,
        left,
        right,
    })
}

/// Ranges up to this size are split by [`small_split`].
const SMALL: usize = 8;

/// The best split of a small range (see [`small_split`]).
struct SmallPlan {
    /// The triangles in the order of the best axis; the left child takes `at`.
    order: [u8; SMALL],
    at: usize,
    /// `A_L N_L + A_R N_R`.
    cost: f32,
}

impl SmallPlan {
    fn apply(&self, prims: &mut [Prim]) {
        let mut copy = [prims[0]; SMALL];
        let n = prims.len();
        copy[..n].copy_from_slice(prims);
        for (p, &k) in prims.iter_mut().zip(&self.order[..n]) {
            *p = copy[k as usize];
        }
    }
}

/// The exact SAH split of a range of at most [`SMALL`] triangles: along each axis whose
/// centroids differ, the triangles sorted by centroid, and every split of that order
/// evaluated (a full sweep, Wald 2007 §3; the bins of [`sah_split`] would cost more
/// here and find no better). `None` when the centroids coincide on every axis.
#[inline(always)]
fn small_split(prims: &[Prim], bounds: &Box3) -> Option<SmallPlan> {
    let n = prims.len();
    debug_assert!((2..=SMALL).contains(&n));
    let side = (0..3).fold(0.0f32, |m, k| m.max(bounds.max[k] - bounds.min[k]));
    let unit = if side > 0.0 && side.is_finite() {
        1.0 / side
    } else {
        1.0
    };
    let mut best: Option<SmallPlan> = None;
    for axis in 0..3 {
        // Keys padded with +inf, which no real key reaches, so that the loops below
        // have a fixed length (and vectorize).
        let key: [f32; SMALL] =
            std::array::from_fn(|i| prims.get(i).map_or(f32::INFINITY, |p| p.centroid[axis]));
        // The stable order by key, each triangle placed at its rank (how many come
        // before it): without the data-dependent branches of a sort, which on such
        // short random inputs cost more than the comparisons.
        let mut order = [0u8; SMALL];
        for i in 0..n {
            let rank: usize = (0..SMALL)
                .map(|j| usize::from((key[j] < key[i]) | ((key[j] == key[i]) & (j < i))))
                .sum();
            order[rank] = i as u8;
        }
        if key[order[0] as usize] == key[order[n - 1] as usize] {
            continue;
        }
        let mut right = [0.0f32; SMALL];
        let mut acc = Box3::EMPTY;
        for i in (1..n).rev() {
            acc.grow(&prims[order[i] as usize].bounds);
            right[i] = acc.scaled_half_area(unit) * (n - i) as f32;
        }
        let mut acc = Box3::EMPTY;
        for i in 1..n {
            acc.grow(&prims[order[i - 1] as usize].bounds);
            let cost = acc.scaled_half_area(unit) * i as f32 + right[i];
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(SmallPlan { order, at: i, cost });
            }
        }
    }
    best.map(|b| SmallPlan {
        cost: b.cost * side * side,
        ..b
    })
}

/// Moves the triangles whose centroid bin is below the plan's plane to the front;
/// returns how many there are and the centroid boxes of both sides.
#[inline(always)]
fn partition(prims: &mut [Prim], cbox: &Box3, plan: &Plan, bins: usize) -> (usize, Box3, Box3) {
    let (axis, plane) = (plan.axis, plan.plane);
    // The same bin count and scale as the sweep (see `sah_split`).
    let nb = bins.min((prims.len() / 2).max(4));
    let extent = cbox.max[axis] - cbox.min[axis];
    let scale = nb as f32 / extent;
    let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
    let is_left = |c: &[f32; 4]| bin_of(c[axis], cbox.min[axis], scale, nb) < plane;
    // Hoare's scheme: only the triangles on the wrong side move, one swap per pair.
    let (mut i, mut j) = (0, prims.len());
    loop {
        while i < j {
            let c = prims[i].centroid;
            if !is_left(&c) {
                break;
            }
            left.grow_point(&c);
            i += 1;
        }
        while i < j {
            let c = prims[j - 1].centroid;
            if is_left(&c) {
                break;
            }
            right.grow_point(&c);
            j -= 1;
        }
        if i >= j {
            break;
        }
        // prims[i] belongs right and prims[j - 1] left.
        prims.swap(i, j - 1);
        left.grow_point(&prims[i].centroid);
        right.grow_point(&prims[j - 1].centroid);
        i += 1;
        j -= 1;
    }
    (i, left, right)
}

/// Splits at the median centroid along the longest axis of the centroid box.
#[inline(always)]
fn median_split(prims: &mut [Prim], cbox: &Box3) -> usize {
    let e: [f32; 3] = std::array::from_fn(|k| cbox.max[k] - cbox.min[k]);
    let axis = if e[0] >= e[1] && e[0] >= e[2] {
        0
    } else if e[1] >= e[2] {
        1
    } else {
        2
    };
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    mid
}

#[inline(always)]
fn range_bounds(prims: &[Prim]) -> (Box3, Box3) {
    let (mut b, mut c) = (Box3::EMPTY, Box3::EMPTY);
    for p in prims {
        b.grow(&p.bounds);
        c.grow_point(&p.centroid);
    }
    (b, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::{f32_down, f32_up};
    use crate::rng::SplitMix64;

    #[test]
    fn branch_free_rounding_equals_the_reference() {
        let mut rng = SplitMix64(3);
        let mut values = vec![
            0.0, -0.0, 1.0, -1.0, 0.1, -0.1, 1e-45, -1e-45, 1e-300, -1e-300,
        ];
        values.extend([
            3.5e38,
            -3.5e38,
            1e300,
            -1e300,
            f64::from(f32::MAX),
            16_777_217.0,
        ]);
        values.extend(
            (0..2000).map(|_| rng.range(-1.0, 1.0) * 10f64.powi((rng.next_u64() % 60) as i32 - 30)),
        );
        values.extend([
            f64::from(f32::MIN_POSITIVE),
            f64::from(f32::MIN_POSITIVE) * 0.75,
        ]);
        values.extend([1e-46, -1e-46, 3.5e38, f64::from(f32::MAX) * 1.5, 1e39]);
        values.extend([f64::from(f32::from_bits(1)), -f64::from(f32::from_bits(1))]);
        let values: Vec<f64> = values.iter().flat_map(|&v| [v, -v]).collect();
        for x in values.chunks(4) {
            let lanes: [f64; 4] = std::array::from_fn(|k| x.get(k).copied().unwrap_or(0.0));
            let (lo, hi) = (below4(lanes), above4(lanes));
            for k in 0..4 {
                let v = lanes[k];
                assert_eq!(lo[k].to_bits(), f32_down(v).to_bits(), "{v}");
                assert_eq!(hi[k].to_bits(), f32_up(v).to_bits(), "{v}");
            }
        }
    }

    /// A triangle's box `[lo, lo + size]` as the build stores it, with index `i`.
    fn prim(lo: [f32; 3], size: [f32; 3], i: u32) -> Prim {
        let b = Box3::new(lo, std::array::from_fn(|k| lo[k] + size[k]));
        let c: [f32; 4] = std::array::from_fn(|k| (b.min[k] + b.max[k]) * 0.5);
        Prim {
            bounds: b,
            centroid: [c[0], c[1], c[2], f32::from_bits(i)],
        }
    }

    /// Random boxes on a coarse grid (so that centroids often tie on some axis).
    fn random_prims(rng: &mut SplitMix64, n: usize) -> Vec<Prim> {
        (0..n as u32)
            .map(|i| {
                let lo = std::array::from_fn(|_| (rng.next_u64() % 8) as f32);
                let size = std::array::from_fn(|_| (rng.next_u64() % 5) as f32 * 0.5);
                prim(lo, size, i)
            })
            .collect()
    }

    /// `A_L N_L + A_R N_R` of a split into two sets, in `f64`.
    fn split_cost(left: &[Prim], right: &[Prim]) -> f64 {
        [left, right]
            .iter()
            .map(|side| range_bounds(side).0.half_area() * side.len() as f64)
            .sum()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn small_split_is_the_cheapest_split_of_a_sorted_order() {
        let mut rng = SplitMix64(11);
        for _ in 0..400 {
            let n = 3 + (rng.next_u64() % (SMALL as u64 - 2)) as usize;
            let prims = random_prims(&mut rng, n);
            let bounds = range_bounds(&prims).0;
            // Brute force: every cut of every axis's order (sorted by centroid, ties by
            // position, as any cut between equal centroids is a valid split too).
            let mut best: Option<f64> = None;
            for axis in 0..3 {
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&a, &b| prims[a].centroid[axis].total_cmp(&prims[b].centroid[axis]));
                if prims[order[0]].centroid[axis] == prims[order[n - 1]].centroid[axis] {
                    continue;
                }
                let sorted: Vec<Prim> = order.iter().map(|&k| prims[k]).collect();
                for at in 1..n {
                    let cost = split_cost(&sorted[..at], &sorted[at..]);
                    best = Some(best.map_or(cost, |b: f64| b.min(cost)));
                }
            }
            let plan = small_split(&prims, &bounds);
            let (Some(best), Some(plan)) = (best, plan) else {
                panic!("a split exists only if centroids differ on some axis");
            };
            assert!(close(f64::from(plan.cost), best), "{} vs {best}", plan.cost);
            // Applying the plan yields that split, and a permutation.
            let mut applied = prims.clone();
            plan.apply(&mut applied);
            let cost = split_cost(&applied[..plan.at], &applied[plan.at..]);
            assert!(close(cost, best), "{cost} vs {best}");
            let mut ids: Vec<u32> = applied.iter().map(Prim::index).collect();
            ids.sort_unstable();
            assert!(ids.iter().copied().eq(0..n as u32));
        }
        // Equal centroids on every axis: nothing to split.
        let same = [
            prim([0.0; 3], [1.0; 3], 0),
            prim([0.25; 3], [0.5; 3], 1),
            prim([0.0; 3], [1.0; 3], 2),
        ];
        assert!(small_split(&same, &range_bounds(&same).0).is_none());
    }

    #[test]
    fn binned_split_is_the_cheapest_bin_plane_and_partition_follows_it() {
        let mut rng = SplitMix64(5);
        for n in [9, 17, 40, 300, 1000] {
            let mut prims = random_prims(&mut rng, n);
            let (bounds, cbox) = range_bounds(&prims);
            let bins = 16;
            let mut binner = Binner {
                bins: vec![[EMPTY_BIN; 3]; bins],
                right: vec![[0.0; 3]; bins],
            };
            let plan = sah_split(&prims, &bounds, &cbox, &mut binner).expect("centroids differ");
            // Brute force over every plane between bins, from each triangle's bin.
            let nb = bins.min((n / 2).max(4));
            let mut best = f64::INFINITY;
            for axis in 0..3 {
                let extent = cbox.max[axis] - cbox.min[axis];
                if extent <= 0.0 {
                    continue;
                }
                let scale = nb as f32 / extent;
                let bin = |p: &Prim| bin_of(p.centroid[axis], cbox.min[axis], scale, nb);
                for plane in 1..nb {
                    let (l, r): (Vec<Prim>, Vec<Prim>) = prims.iter().partition(|p| bin(p) < plane);
                    if !l.is_empty() && !r.is_empty() {
                        best = best.min(split_cost(&l, &r));
                    }
                }
            }
            assert!(
                close(f64::from(plan.cost), best),
                "n {n}: {} vs {best}",
                plan.cost
            );
            let (mid, lc, rc) = partition(&mut prims, &cbox, &plan, bins);
            let (left, right) = prims.split_at(mid);
            assert!(close(split_cost(left, right), best), "n {n}");
            let scale = nb as f32 / (cbox.max[plan.axis] - cbox.min[plan.axis]);
            let bin = |p: &Prim| bin_of(p.centroid[plan.axis], cbox.min[plan.axis], scale, nb);
            assert!(left.iter().all(|p| bin(p) < plan.plane));
            assert!(right.iter().all(|p| bin(p) >= plan.plane));
            // The children's boxes: from the bins (plan) and gathered while partitioning.
            for (side, b, c) in [(left, plan.left, lc), (right, plan.right, rc)] {
                let (bb, cc) = range_bounds(side);
                assert_eq!((b.min3(), b.max3()), (bb.min3(), bb.max3()), "n {n}");
                assert_eq!((c.min3(), c.max3()), (cc.min3(), cc.max3()), "n {n}");
            }
            let mut ids: Vec<u32> = prims.iter().map(Prim::index).collect();
            ids.sort_unstable();
            assert!(ids.iter().copied().eq(0..n as u32));
        }
    }

    #[test]
    fn two_triangles_split_when_apart_and_stay_together_when_overlapping() {
        use crate::scene::{MeshBuilder, ObjectDesc, Scene};
        use glam::DVec3;
        let tree_of = |offset: DVec3| {
            let mut b = MeshBuilder::new();
            for p in [DVec3::ZERO, DVec3::X, DVec3::Y] {
                b.push_position(p);
            }
            for p in [DVec3::ZERO, DVec3::X, DVec3::Y] {
                b.push_position(p + offset);
            }
            b.push_face(&[0, 1, 2], None).unwrap();
            b.push_face(&[3, 4, 5], None).unwrap();
            let mut s = Scene::new();
            s.add(ObjectDesc::new("t", b.finish().0)).unwrap();
            build(&SceneTriangles::new(&s), &BvhOptions::default())
        };
        // Far apart (flat boxes, half areas 1 and 11 for the union): splitting costs
        // 1 + (1 + 1) / 11 < 2 tests.
        let apart = tree_of(DVec3::new(10.0, 0.0, 0.0));
        assert_eq!(apart.nodes.len(), 3);
        assert_eq!(apart.leaves, 2);
        // Shifted by a hair: 1 + 2 / 1.001 >= 2, a leaf of two.
        let together = tree_of(DVec3::new(1e-3, 0.0, 0.0));
        assert_eq!(together.nodes.len(), 1);
        assert_eq!(together.nodes[0].count, 2);
    }
}
