//! Binned SAH construction (Wald 2007).
//!
//! Each range of triangles is binned by centroid into `B` equal slices of its centroid
//! box along each axis; each bin keeps its triangle count, box and centroid box. A
//! sweep from both ends gives, for every one of the `B - 1` planes between bins, the
//! cost `A_L N_L + A_R N_R` (half areas, counts); the cheapest plane over the three
//! axes wins if it beats making a leaf (`N` tests) after paying
//! [`BvhOptions::traversal_cost`] for the node. Children's boxes are the unions of
//! their bins' boxes and their centroid boxes are gathered while partitioning, so no
//! extra pass over the triangles is needed. Ranges smaller than the bin count use
//! `max(N, 4)` bins.
//!
//! Fallbacks: all centroids equal (the SAH cannot separate them) or deeper than
//! [`MEDIAN_DEPTH`]: split at the median by index order along the longest axis, which
//! halves the range and bounds the depth.

use super::{BvhOptions, f32_down, f32_up};
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

/// A triangle during the build: its box, centroid and index. The primitives are moved
/// while partitioning (not an index array into them), so every pass reads memory
/// sequentially; with a million triangles, random access would cost a cache miss per
/// triangle per level.
#[derive(Clone, Copy, Debug)]
struct Prim {
    bounds: Box3,
    /// Centre of the box; the fourth lane is 0.
    centroid: [f32; 4],
    index: u32,
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
    let mut scale = 0.0f64;
    for t in verts {
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        scale = scale
            .max(lo.abs().max_element())
            .max(hi.abs().max_element());
        let b = Box3::new(
            [f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)],
            [f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)],
        );
        let c: [f32; 4] = std::array::from_fn(|k| (b.min[k] + b.max[k]) * 0.5);
        root_bounds.grow(&b);
        root_centroids.grow_point(&c);
        prims.push(Prim {
            bounds: b,
            centroid: c,
            index: prims.len() as u32,
        });
    }
    let mut nodes: Vec<BinaryNode> = vec![BinaryNode::default()];
    let mut stack = vec![Task {
        node: 0,
        start: 0,
        end: n,
        depth: 1,
        bounds: root_bounds,
        centroids: root_centroids,
    }];
    let mut bin_store = vec![[EMPTY_BIN; 3]; bins];
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
        } else {
            match sah_split(
                &prims[task.start..task.end],
                &task.centroids,
                &mut bin_store,
            ) {
                Some(plan) => {
                    let leaf_cost = count as f64;
                    let split_cost =
                        options.traversal_cost + plan.cost / area.max(f64::MIN_POSITIVE);
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
    tree.order = prims.iter().map(|p| p.index).collect();
    tree.nodes = nodes;
    tree.scale = scale;
    tree.leaves = leaves;
    tree.depth = max_depth;
    tree.sah_cost = sah;
    tree
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
    let mut out = [0u32; 4];
    for k in 0..4 {
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
    /// `A_L N_L + A_R N_R`.
    cost: f64,
    left: Box3,
    right: Box3,
}

/// The best SAH plane, `None` when the centroids coincide on every axis.
fn sah_split(prims: &[Prim], cbox: &Box3, bins: &mut [[Bin; 3]]) -> Option<Plan> {
    // Small ranges need few bins: the sweep and the reset cost O(bins) per node.
    let nb = bins.len().min(prims.len().max(4));
    let bins = &mut bins[..nb];
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
    let mut best: Option<(usize, usize, f64)> = None;
    let mut right_cost = [0.0f64; MAX_BINS];
    for k in 0..3 {
        if !usable[k] {
            continue;
        }
        // right_cost[s] = A(bins s..) * N(bins s..)
        let (mut acc, mut cnt) = (Box3::EMPTY, 0u32);
        for s in (1..nb).rev() {
            acc.grow(&bins[s][k].bounds);
            cnt += bins[s][k].count;
            right_cost[s] = acc.half_area() * f64::from(cnt);
        }
        let (mut acc, mut cnt) = (Box3::EMPTY, 0u32);
        for s in 1..nb {
            acc.grow(&bins[s - 1][k].bounds);
            cnt += bins[s - 1][k].count;
            if cnt == 0 || cnt as usize == prims.len() {
                continue;
            }
            let cost = acc.half_area() * f64::from(cnt) + right_cost[s];
            if best.is_none_or(|b| cost < b.2) {
                best = Some((k, s, cost));
            }
        }
    }
    let (axis, plane, cost) = best?;
    let side = |range: std::ops::Range<usize>| {
        let mut b = Box3::EMPTY;
        for bin in &bins[range] {
            b.grow(&bin[axis].bounds);
        }
        b
    };
    Some(Plan {
        axis,
        plane,
        cost,
        left: side(0..plane),
        right: side(plane..nb),
    })
}

/// Moves the triangles whose centroid bin is below the plan's plane to the front;
/// returns how many there are and the centroid boxes of both sides.
fn partition(prims: &mut [Prim], cbox: &Box3, plan: &Plan, bins: usize) -> (usize, Box3, Box3) {
    let (axis, plane) = (plan.axis, plan.plane);
    // The same bin count and scale as the sweep (see `sah_split`).
    let nb = bins.min(prims.len().max(4));
    let extent = cbox.max[axis] - cbox.min[axis];
    let scale = nb as f32 / extent;
    let (mut left, mut right) = (Box3::EMPTY, Box3::EMPTY);
    let (mut i, mut j) = (0, prims.len());
    while i < j {
        let c = prims[i].centroid;
        if bin_of(c[axis], cbox.min[axis], scale, nb) < plane {
            left.grow_point(&c);
            i += 1;
        } else {
            right.grow_point(&c);
            j -= 1;
            prims.swap(i, j);
        }
    }
    (i, left, right)
}

/// Splits at the median centroid along the longest axis of the centroid box.
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

fn range_bounds(prims: &[Prim]) -> (Box3, Box3) {
    let (mut b, mut c) = (Box3::EMPTY, Box3::EMPTY);
    for p in prims {
        b.grow(&p.bounds);
        c.grow_point(&p.centroid);
    }
    (b, c)
}
