//! Binned SAH construction (Wald 2007).
//!
//! Each range of triangles is binned by centroid into `B` equal slices of its centroid
//! box along each axis; each bin keeps its triangle count, box and centroid box. A
//! sweep from both ends gives, for every one of the `B - 1` planes between bins, the
//! cost `A_L N_L + A_R N_R` (half areas, counts); the cheapest plane over the three
//! axes wins if it beats making a leaf (`N` tests) after paying
//! [`BvhOptions::traversal_cost`] for the node. Children's boxes are the unions of
//! their bins' boxes, so no extra pass over the triangles is needed.
//!
//! Fallbacks: all centroids equal (the SAH cannot separate them) or deeper than
//! [`MEDIAN_DEPTH`]: split at the median by index order along the longest axis, which
//! halves the range and bounds the depth.

use super::{Bvh, BvhNode, BvhOptions, NodePair, f32_down, f32_up};
use crate::accel::triangles::SceneTriangles;

/// Below this depth splits are SAH; at and beyond it, median splits.
pub(crate) const MEDIAN_DEPTH: usize = 56;

/// A single-precision box under construction.
#[derive(Clone, Copy, Debug)]
struct Box3 {
    min: [f32; 3],
    max: [f32; 3],
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: [f32::INFINITY; 3],
        max: [f32::NEG_INFINITY; 3],
    };

    #[inline(always)]
    fn grow(&mut self, o: &Box3) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(o.min[k]);
            self.max[k] = self.max[k].max(o.max[k]);
        }
    }

    #[inline(always)]
    fn grow_point(&mut self, p: &[f32; 3]) {
        for (k, &x) in p.iter().enumerate() {
            self.min[k] = self.min[k].min(x);
            self.max[k] = self.max[k].max(x);
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

#[derive(Clone, Copy, Debug)]
struct Bin {
    count: u32,
    bounds: Box3,
    centroids: Box3,
}

const EMPTY_BIN: Bin = Bin {
    count: 0,
    bounds: Box3::EMPTY,
    centroids: Box3::EMPTY,
};

/// A range waiting to be turned into a node.
struct Task {
    node: u32,
    start: usize,
    end: usize,
    depth: usize,
    bounds: Box3,
    centroids: Box3,
}

pub(super) fn build(triangles: &SceneTriangles, options: &BvhOptions) -> Bvh {
    let n = triangles.len();
    let mut bvh = Bvh::default();
    if n == 0 || n > u32::MAX as usize / 2 {
        return bvh;
    }
    let bins = options.bins.clamp(2, 256);
    let max_leaf = options.max_leaf_size.max(1);
    let verts = triangles.vertices();
    let mut boxes: Vec<Box3> = Vec::with_capacity(n);
    let mut centroids: Vec<[f32; 3]> = Vec::with_capacity(n);
    let (mut root_bounds, mut root_centroids) = (Box3::EMPTY, Box3::EMPTY);
    let mut scale = 0.0f64;
    for t in verts {
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        scale = scale
            .max(lo.abs().max_element())
            .max(hi.abs().max_element());
        let b = Box3 {
            min: [f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)],
            max: [f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)],
        };
        let c: [f32; 3] = std::array::from_fn(|k| (b.min[k] + b.max[k]) * 0.5);
        root_bounds.grow(&b);
        root_centroids.grow_point(&c);
        boxes.push(b);
        centroids.push(c);
    }
    let mut index: Vec<u32> = (0..n as u32).collect();
    let mut nodes: Vec<BvhNode> = vec![BvhNode::default(); 2];
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
        let split: Option<(usize, Option<Plan>)> = if count <= 1 {
            None
        } else if task.depth >= MEDIAN_DEPTH {
            let range = &mut index[task.start..task.end];
            Some((median_split(range, &centroids, &task.centroids), None))
        } else {
            match sah_split(
                &index[task.start..task.end],
                &boxes,
                &centroids,
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
                        let range = &mut index[task.start..task.end];
                        let mid = partition(range, &centroids, &task.centroids, &plan, bins);
                        Some((mid, Some(plan)))
                    }
                }
                None if count <= max_leaf => None,
                None => {
                    let range = &mut index[task.start..task.end];
                    Some((median_split(range, &centroids, &task.centroids), None))
                }
            }
        };
        let left = nodes.len() as u32;
        let node = &mut nodes[task.node as usize];
        node.min = task.bounds.min;
        node.max = task.bounds.max;
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
        nodes.push(BvhNode::default());
        nodes.push(BvhNode::default());
        let (mid, plan) = split_at;
        let mid = task.start + mid;
        let ((lb, lc), (rb, rc)) = match plan {
            Some(p) => (p.left, p.right),
            None => (
                range_bounds(&index[task.start..mid], &boxes, &centroids),
                range_bounds(&index[mid..task.end], &boxes, &centroids),
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
    bvh.pairs = nodes
        .chunks(2)
        .map(|c| NodePair([c[0], c.get(1).copied().unwrap_or_default()]))
        .collect();
    bvh.triangles = index.iter().map(|&i| verts[i as usize]).collect();
    let polys = triangles.triangle_polygons();
    bvh.polygons = index.iter().map(|&i| polys[i as usize]).collect();
    bvh.order = index;
    bvh.scale = scale;
    bvh.stats.nodes = nodes.len() - 1;
    bvh.stats.leaves = leaves;
    bvh.stats.depth = max_depth;
    bvh.stats.sah_cost = sah;
    bvh
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32, bins: usize) -> usize {
    (((c - lo) * scale) as usize).min(bins - 1)
}

/// The best SAH plane of a range.
#[derive(Clone, Copy, Debug)]
struct Plan {
    axis: usize,
    /// Bins left of the plane.
    plane: usize,
    /// `A_L N_L + A_R N_R`.
    cost: f64,
    left: (Box3, Box3),
    right: (Box3, Box3),
}

/// The best SAH plane, `None` when the centroids coincide on every axis.
fn sah_split(
    index: &[u32],
    boxes: &[Box3],
    centroids: &[[f32; 3]],
    cbox: &Box3,
    bins: &mut [[Bin; 3]],
) -> Option<Plan> {
    let nb = bins.len();
    let mut scale = [0.0f32; 3];
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
    for &i in index {
        let c = &centroids[i as usize];
        let b = &boxes[i as usize];
        for k in 0..3 {
            let bin = &mut bins[bin_of(c[k], cbox.min[k], scale[k], nb)][k];
            bin.count += 1;
            bin.bounds.grow(b);
            bin.centroids.grow_point(c);
        }
    }
    let mut best: Option<(usize, usize, f64)> = None;
    let mut right_cost = vec![0.0f64; nb];
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
            if cnt == 0 || cnt as usize == index.len() {
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
        let (mut b, mut c) = (Box3::EMPTY, Box3::EMPTY);
        for bin in &bins[range] {
            b.grow(&bin[axis].bounds);
            c.grow(&bin[axis].centroids);
        }
        (b, c)
    };
    Some(Plan {
        axis,
        plane,
        cost,
        left: side(0..plane),
        right: side(plane..nb),
    })
}

/// Moves the triangles whose centroid bin is below `plane` to the front; returns how
/// many there are.
fn partition(
    index: &mut [u32],
    centroids: &[[f32; 3]],
    cbox: &Box3,
    plan: &Plan,
    bins: usize,
) -> usize {
    let (axis, plane) = (plan.axis, plan.plane);
    let extent = cbox.max[axis] - cbox.min[axis];
    let scale = bins as f32 / extent;
    let (mut i, mut j) = (0, index.len());
    while i < j {
        let c = centroids[index[i] as usize][axis];
        if bin_of(c, cbox.min[axis], scale, bins) < plane {
            i += 1;
        } else {
            j -= 1;
            index.swap(i, j);
        }
    }
    i
}

/// Splits at the median centroid along the longest axis of the centroid box.
fn median_split(index: &mut [u32], centroids: &[[f32; 3]], cbox: &Box3) -> usize {
    let e: [f32; 3] = std::array::from_fn(|k| cbox.max[k] - cbox.min[k]);
    let axis = if e[0] >= e[1] && e[0] >= e[2] {
        0
    } else if e[1] >= e[2] {
        1
    } else {
        2
    };
    let mid = index.len() / 2;
    index.select_nth_unstable_by(mid, |&a, &b| {
        centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
    });
    mid
}

fn range_bounds(index: &[u32], boxes: &[Box3], centroids: &[[f32; 3]]) -> (Box3, Box3) {
    let (mut b, mut c) = (Box3::EMPTY, Box3::EMPTY);
    for &i in index {
        b.grow(&boxes[i as usize]);
        c.grow_point(&centroids[i as usize]);
    }
    (b, c)
}
