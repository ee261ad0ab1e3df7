//! Voxelization of meshes into an octree.
//!
//! - Input: a [`TriangleSoup`] (world-space triangles with their scene-wide face ids,
//!   grouped by object, each object flagged closed or open), a cubic [`Region`] and a
//!   depth.
//! - Output: an [`Octree`] whose finest cells (voxels) are Partial when a triangle
//!   meets the closed cell (exact separating-axis test, [`triangle_box_overlap`]), else
//!   Full when the cell is inside a closed object, else Empty.
//! - Method: recursive subdivision that carries down the list of triangles meeting each
//!   cell and stops where the list is empty (seed 000, "Υποδιαίρεση Χώρου": divide a
//!   cell into 8 until an elementary cell, or until the cell is simple enough). Cells
//!   with no triangle are then classified per connected component: components are found
//!   by flood fill through face neighbours (Samet's neighbour finding, [`super::neighbour`]);
//!   two cells that touch and that no surface meets lie in one component of the
//!   complement of the surface, so they are both inside or both outside. A component
//!   touching the region's boundary is outside when every closed object lies strictly
//!   inside the region (always so for [`Region::enclosing`]); any other component is
//!   classified by one point-in-solid query at the centre of its largest cell. Finally
//!   homogeneous octants are merged.
//! - Point in solid: the generalized winding number ([`winding_number`], the sum of the
//!   solid angles of the triangles over 4π, Van Oosterom and Strackee's formula). For a
//!   closed mesh it is an integer (0 outside) at any point off the surface, and the
//!   query points are cell centres at least half a cell away from every triangle, so
//!   rounding cannot flip it; there are no special cases for rays through edges or
//!   vertices because there are no rays. A point is Full when some closed object has
//!   `|w| > 1/2` (orientation-independent, so mirrored objects need no care).
//! - Open meshes (not flagged closed) contribute Partial voxels only: a surface shell
//!   with no inside.
//! - Source face: a Partial voxel records the face of the triangle nearest to the
//!   voxel's centre among those meeting it (lower face id on a tie): a deterministic,
//!   view-independent choice.
//! - Complexity: O(Σ over levels of the triangle-cell incidences) for the subdivision
//!   (a triangle much smaller than the cells meets one cell per level), O(n depth) for
//!   the flood fill over n cells, O(T) per winding-number query (one per solid, plus
//!   one per pocket of inside cells cut off by a part thinner than two voxels).
//! - Limitations: the overlap test is exact in real arithmetic and evaluated in `f64`,
//!   so a triangle touching a cell within rounding may go either way (the same way for
//!   every caller, since cell boxes come from [`Region::cell_box`]). A face lying exactly
//!   on a cell plane marks the cells on both sides. A closed object thinner than a voxel
//!   has no Full cells. A mesh flagged closed that has small holes still gets a sensible
//!   inside (the generalized winding number degrades gracefully), decided once per
//!   component.

use std::time::Instant;

use glam::DVec3;

use super::neighbour::{Direction, adjacent_leaves};
use super::{Cell, Leaf, NONE, Node, NodeKind, Octree, Region, check_depth, compact};
use crate::Result;
use crate::geom::Aabb;
use crate::scene::Scene;

/// World-space triangles with their face ids, grouped by object.
#[derive(Clone, Debug, Default)]
pub struct TriangleSoup {
    triangles: Vec<[DVec3; 3]>,
    faces: Vec<u32>,
    objects: Vec<SoupObject>,
}

#[derive(Clone, Debug)]
struct SoupObject {
    start: usize,
    end: usize,
    closed: bool,
    bounds: Aabb,
}

impl TriangleSoup {
    /// An empty soup.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The triangles of a scene in world space: each convex polygon fanned from its
    /// first vertex, each triangle keeping the polygon's scene-wide face id; objects
    /// keep their `closed` flag.
    #[must_use]
    pub fn from_scene(scene: &Scene) -> Self {
        let mut soup = TriangleSoup::new();
        soup.triangles.reserve(scene.triangle_count());
        soup.faces.reserve(scene.triangle_count());
        let (mut world, mut order) = (Vec::new(), Vec::new());
        for o in scene.objects() {
            let start = soup.triangles.len();
            // Each vertex once, as `Object::world_polygon` computes it.
            o.world_positions_into(&mut world);
            // Polygons along a Morton curve (see `morton_key`), so no triangle is
            // moved afterwards.
            order.clear();
            order.extend((0..o.mesh.polygon_count()).map(|p| {
                let poly = o.mesh.polygon(p);
                let centre =
                    poly.iter().map(|&v| world[v as usize]).sum::<DVec3>() / poly.len() as f64;
                (u64::from(morton_key(centre, &o.bounds)) << 32) | p as u64
            }));
            order.sort_unstable();
            for &key in &order {
                let p = (key & 0xffff_ffff) as usize;
                let poly = o.mesh.polygon(p);
                let face = o.first_face + o.mesh.polygon_face(p);
                let v0 = world[poly[0] as usize];
                for k in 1..poly.len().saturating_sub(1) {
                    soup.triangles
                        .push([v0, world[poly[k] as usize], world[poly[k + 1] as usize]]);
                    soup.faces.push(face);
                }
            }
            soup.finish_object(start, o.closed, false);
        }
        soup
    }

    /// Adds an object made of `(triangle, face id)` pairs. Triangles with a non-finite
    /// coordinate are skipped (and so is the whole object's inside, which a hole would
    /// make meaningless: it is then treated as open). Returns how many were skipped.
    pub fn push_object(
        &mut self,
        triangles: impl IntoIterator<Item = ([DVec3; 3], u32)>,
        closed: bool,
    ) -> usize {
        let start = self.triangles.len();
        let mut skipped = 0;
        for (t, face) in triangles {
            if t.iter().all(|v| v.is_finite()) {
                self.triangles.push(t);
                self.faces.push(face);
            } else {
                skipped += 1;
            }
        }
        self.finish_object(start, closed && skipped == 0, true);
        skipped
    }

    fn finish_object(&mut self, start: usize, closed: bool, sort: bool) {
        let end = self.triangles.len();
        let bounds = Aabb::from_points(self.triangles[start..end].iter().flatten().copied());
        if sort {
            self.sort_along_morton_curve(start, end, &bounds);
        }
        self.objects.push(SoupObject {
            start,
            end,
            closed,
            bounds,
        });
    }

    /// Orders an object's triangles along a Morton curve (see [`morton_key`]).
    fn sort_along_morton_curve(&mut self, start: usize, end: usize, bounds: &Aabb) {
        let mut keyed: Vec<u64> = (start..end)
            .map(|i| {
                let t = &self.triangles[i];
                (u64::from(morton_key((t[0] + t[1] + t[2]) / 3.0, bounds)) << 32) | i as u64
            })
            .collect();
        keyed.sort_unstable();
        let index = |k: &u64| (k & 0xffff_ffff) as usize;
        let triangles: Vec<[DVec3; 3]> = keyed.iter().map(|k| self.triangles[index(k)]).collect();
        let faces: Vec<u32> = keyed.iter().map(|k| self.faces[index(k)]).collect();
        self.triangles[start..end].copy_from_slice(&triangles);
        self.faces[start..end].copy_from_slice(&faces);
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Triangle `i`.
    #[must_use]
    pub fn triangle(&self, i: usize) -> &[DVec3; 3] {
        &self.triangles[i]
    }

    /// The face id of triangle `i`.
    #[must_use]
    pub fn face(&self, i: usize) -> u32 {
        self.faces[i]
    }

    /// The box of every triangle.
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.objects
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(o.bounds))
    }

    /// Whether `p` is inside a closed object (winding number above 1/2 in magnitude).
    /// Meaningful off the surfaces; O(triangles of the closed objects whose box
    /// contains `p`).
    #[must_use]
    pub(crate) fn is_inside(&self, p: DVec3) -> bool {
        self.objects.iter().any(|o| {
            o.closed
                && o.bounds.contains(p)
                && object_winding_number(p, &self.triangles[o.start..o.end]).abs() > 0.5
        })
    }

    /// Whether every closed object lies strictly inside the region, so that the
    /// region's boundary is outside every solid.
    fn closed_strictly_inside(&self, region: &Region) -> bool {
        self.objects.iter().filter(|o| o.closed).all(|o| {
            o.bounds.is_empty()
                || (o.bounds.min.cmpgt(region.min()).all()
                    && o.bounds.max.cmplt(region.max()).all())
        })
    }
}

/// The position of a point along a Morton (Z-order) curve through a box, 10 bits per
/// axis. Triangles are kept in this order so that those meeting one cell are close in
/// memory: the subdivision walks each cell's list once per level, and in this order the
/// walk is nearly sequential. The order changes no result (ties between triangles are
/// broken by face id).
fn morton_key(p: DVec3, bounds: &Aabb) -> u32 {
    let scale = DVec3::splat(1023.0) / bounds.extent().max(DVec3::splat(f64::MIN_POSITIVE));
    let q = ((p - bounds.min) * scale).clamp(DVec3::ZERO, DVec3::splat(1023.0));
    let spread = |v: u32| {
        // 10 bits to every third bit of 30.
        let mut x = v & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    spread(q.x as u32) | (spread(q.y as u32) << 1) | (spread(q.z as u32) << 2)
}

/// The generalized winding number of a point with respect to triangles: the sum of
/// their signed solid angles over 4π (Van Oosterom and Strackee). For a closed,
/// outward-oriented mesh it is 1 inside and 0 outside.
#[must_use]
pub fn winding_number(p: DVec3, triangles: &[[DVec3; 3]]) -> f64 {
    let mut sum = 0.0;
    for t in triangles {
        let (a, b, c) = (t[0] - p, t[1] - p, t[2] - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        sum += 2.0 * det.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// [`winding_number`], summed in chunks on several threads for large objects (the sum
/// is an integer plus rounding, so the order of addition does not matter).
fn object_winding_number(p: DVec3, triangles: &[[DVec3; 3]]) -> f64 {
    #[cfg(feature = "parallel")]
    if triangles.len() >= 1 << 16 {
        use rayon::prelude::*;
        return triangles
            .par_chunks(1 << 14)
            .map(|c| winding_number(p, c))
            .sum();
    }
    winding_number(p, triangles)
}

/// The point of triangle `t` nearest to `p` (by the Voronoi regions of its vertices,
/// edges and face). Degenerate triangles fall back to their nearest vertex.
#[must_use]
pub fn closest_point_on_triangle(p: DVec3, t: &[DVec3; 3]) -> DVec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    let q = if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        a + ab * (d1 / (d1 - d3))
    } else {
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            a + ac * (d2 / (d2 - d6))
        } else {
            let va = d3 * d6 - d5 * d4;
            if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
                b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))
            } else {
                let den = 1.0 / (va + vb + vc);
                a + ab * (vb * den) + ac * (vc * den)
            }
        }
    };
    if q.is_finite() {
        q
    } else {
        *t.iter()
            .min_by(|u, v| u.distance_squared(p).total_cmp(&v.distance_squared(p)))
            .expect("three vertices")
    }
}

/// Whether a triangle meets the closed box `[min, max]`, by the separating axis
/// theorem (Akenine-Möller's 13 axes: the 3 box normals, the triangle's normal, and
/// the 9 cross products of box axes and triangle edges). Touching counts as meeting.
/// The box normals and a vertex inside the box are decided by exact comparisons; only
/// the other cases go through the rounded projections.
#[must_use]
pub fn triangle_box_overlap(t: &[DVec3; 3], min: DVec3, max: DVec3) -> bool {
    let tmin = t[0].min(t[1]).min(t[2]);
    let tmax = t[0].max(t[1]).max(t[2]);
    overlap_with_bounds(t, tmin, tmax, min, max, &mut 0)
}

/// [`triangle_box_overlap`] with the triangle's box already known; counts the cases
/// that needed the projections in `sat_tests`.
#[inline]
fn overlap_with_bounds(
    t: &[DVec3; 3],
    tmin: DVec3,
    tmax: DVec3,
    min: DVec3,
    max: DVec3,
    sat_tests: &mut u64,
) -> bool {
    if tmin.cmpgt(max).any() || tmax.cmplt(min).any() {
        return false;
    }
    // A vertex in the box settles it (the common case for triangles smaller than the
    // cells: after a split, most children a triangle reaches hold one of its vertices).
    if t.iter().any(|v| v.cmpge(min).all() && v.cmple(max).all()) {
        return true;
    }
    *sat_tests += 1;
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    let v = [t[0] - c, t[1] - c, t[2] - c];
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // The triangle's plane first: it rejects most misses with one projection.
    let n = edges[0].cross(edges[1]);
    if n.dot(v[0]).abs() > h.dot(n.abs()) {
        return false;
    }
    for e in edges {
        // unit_x × e, unit_y × e, unit_z × e
        for axis in [
            DVec3::new(0.0, -e.z, e.y),
            DVec3::new(e.z, 0.0, -e.x),
            DVec3::new(-e.y, e.x, 0.0),
        ] {
            let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
            let r = h.dot(axis.abs());
            let lo = p[0].min(p[1]).min(p[2]);
            let hi = p[0].max(p[1]).max(p[2]);
            if lo > r || hi < -r {
                return false;
            }
        }
    }
    true
}

/// How a voxelization went.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Triangles in the input.
    pub triangles: usize,
    /// Nodes before homogeneous octants were merged.
    pub raw_nodes: usize,
    /// Triangle-cell tests that needed the separating axes (boxes alone did not decide).
    pub sat_tests: u64,
    /// Connected components of cells with no surface.
    pub components: usize,
    /// Point-in-solid (winding number) queries made.
    pub inside_queries: usize,
    /// Milliseconds spent gathering the world-space triangles (by [`Octree::from_scene`]).
    pub triangles_ms: f64,
    /// Milliseconds spent subdividing.
    pub subdivide_ms: f64,
    /// Milliseconds spent classifying cells with no surface.
    pub classify_ms: f64,
    /// Milliseconds spent merging homogeneous octants.
    pub compact_ms: f64,
}

/// The children a box reaches, by which halves it reaches per axis: indexed by
/// `low | high << 3`, where bit `a` of `low` (`high`) says the box reaches the lower
/// (upper) half along axis `a`; child `k` is reached when, on every axis, the half its
/// bit names is.
const REACHED_CHILDREN: [u8; 64] = {
    let mut table = [0u8; 64];
    let mut i = 0;
    while i < 64 {
        let (low, high) = (i & 7, i >> 3);
        let mut k = 0;
        while k < 8 {
            if (!k & 7) & !low == 0 && k & !high == 0 {
                table[i] |= 1 << k;
            }
            k += 1;
        }
        i += 1;
    }
    table
};

/// Below this many triangles the build stays on one thread.
#[cfg(feature = "parallel")]
const PARALLEL_MIN_TRIANGLES: usize = 4096;

struct Builder<'a> {
    soup: &'a TriangleSoup,
    tmin: &'a [DVec3],
    tmax: &'a [DVec3],
    region: Region,
    depth: u32,
    nodes: Vec<Node>,
    /// Leaves no triangle meets, with their cells, to be classified.
    unknown: Vec<(u32, Cell)>,
    sat_tests: u64,
    /// The build's deadline (see [`crate::work`]), and whether it passed: the
    /// subdivision then stops and the build ends with its error.
    deadline: &'a crate::work::Deadline,
    stopped: bool,
}

impl Builder<'_> {
    fn overlaps(&mut self, t: u32, b: &Aabb) -> bool {
        let i = t as usize;
        overlap_with_bounds(
            &self.soup.triangles[i],
            self.tmin[i],
            self.tmax[i],
            b.min,
            b.max,
            &mut self.sat_tests,
        )
    }

    fn subdivide(&mut self, i: usize, cell: Cell, list: &[u32]) {
        if self.stopped {
            return;
        }
        if self.nodes.len() % 512 < 8 && self.deadline.is_over() {
            self.stopped = true;
            return;
        }
        if list.is_empty() {
            self.unknown.push((i as u32, cell));
            return;
        }
        if cell.level == self.depth {
            let face = self.nearest_face(cell, list);
            self.nodes[i].set_leaf(Leaf::Partial { face });
            return;
        }
        let first = self.nodes.len();
        self.nodes[i].kind = NodeKind::Internal;
        self.nodes[i].first_child = first as u32;
        for k in 0..8u8 {
            self.nodes
                .push(Node::new(i as u32, (cell.level + 1) as u8, k));
        }
        let lists = self.split(cell, list);
        for (k, sub) in lists.into_iter().enumerate() {
            self.subdivide(first + k, cell.child(k as u8), &sub);
        }
    }

    /// The lists of triangles meeting each child of `cell`: each triangle goes to the
    /// children its box reaches (one comparison with the mid-plane per axis), then the
    /// exact test decides.
    fn split(&mut self, cell: Cell, list: &[u32]) -> [Vec<u32>; 8] {
        let boxes: [Aabb; 8] = std::array::from_fn(|k| self.region.cell_box(cell.child(k as u8)));
        let mid = boxes[0].max;
        let mut lists: [Vec<u32>; 8] = Default::default();
        for &t in list {
            let (lo, hi) = (self.tmin[t as usize], self.tmax[t as usize]);
            let low = lo.cmple(mid).bitmask();
            let high = hi.cmpge(mid).bitmask();
            let mut reached = REACHED_CHILDREN[(low | (high << 3)) as usize];
            while reached != 0 {
                let k = reached.trailing_zeros() as usize;
                reached &= reached - 1;
                if self.overlaps(t, &boxes[k]) {
                    lists[k].push(t);
                }
            }
        }
        lists
    }

    /// Subdivides from the root; with the `parallel` feature the root's 8 octants are
    /// built on separate threads and spliced in order, which gives the very array the
    /// one-thread recursion gives.
    fn subdivide_root(&mut self, list: &[u32]) {
        #[cfg(feature = "parallel")]
        if self.depth > 1
            && list.len() >= PARALLEL_MIN_TRIANGLES
            && rayon::current_num_threads() > 1
        {
            use rayon::prelude::*;
            self.nodes[0].kind = NodeKind::Internal;
            self.nodes[0].first_child = 1;
            for k in 0..8u8 {
                self.nodes.push(Node::new(0, 1, k));
            }
            let lists = self.split(Cell::ROOT, list);
            let (soup, tmin, tmax, region, depth, deadline) = (
                self.soup,
                self.tmin,
                self.tmax,
                self.region,
                self.depth,
                self.deadline,
            );
            let parts: Vec<Builder<'_>> = lists
                .par_iter()
                .enumerate()
                .map(|(k, sub)| {
                    let mut part = Builder {
                        soup,
                        tmin,
                        tmax,
                        region,
                        depth,
                        nodes: vec![Node::new(0, 1, k as u8)],
                        unknown: Vec::new(),
                        sat_tests: 0,
                        deadline,
                        stopped: false,
                    };
                    part.subdivide(0, Cell::ROOT.child(k as u8), sub);
                    part
                })
                .collect();
            for (k, part) in parts.into_iter().enumerate() {
                self.splice(1 + k, &part);
            }
            return;
        }
        self.subdivide(0, Cell::ROOT, list);
    }

    /// Appends a subtree built on its own (its node 0 standing for node `at`).
    #[cfg(feature = "parallel")]
    fn splice(&mut self, at: usize, part: &Builder<'_>) {
        let base = self.nodes.len() as u32;
        let map = |i: u32| if i == 0 { at as u32 } else { base + i - 1 };
        let root = part.nodes[0];
        let n = &mut self.nodes[at];
        n.kind = root.kind;
        n.face = root.face;
        n.first_child = if root.first_child == NONE {
            NONE
        } else {
            map(root.first_child)
        };
        for &node in &part.nodes[1..] {
            let mut node = node;
            node.parent = map(node.parent);
            if node.first_child != NONE {
                node.first_child = map(node.first_child);
            }
            self.nodes.push(node);
        }
        self.unknown
            .extend(part.unknown.iter().map(|&(i, c)| (map(i), c)));
        self.sat_tests += part.sat_tests;
        self.stopped |= part.stopped;
    }

    /// The face of the triangle nearest to the cell's centre (lower face id, then lower
    /// triangle index, on a tie).
    fn nearest_face(&self, cell: Cell, list: &[u32]) -> u32 {
        let p = self.region.cell_box(cell).center();
        let mut best = (f64::INFINITY, u32::MAX);
        for &t in list {
            let t = t as usize;
            let q = closest_point_on_triangle(p, &self.soup.triangles[t]);
            let key = (q.distance_squared(p), self.soup.faces[t]);
            if key.0 < best.0 || (key.0 == best.0 && key.1 < best.1) {
                best = key;
            }
        }
        best.1
    }

    /// Gives every unknown leaf its kind, one decision per connected component.
    fn classify(&mut self) -> (usize, usize) {
        let mut slot = vec![NONE; self.nodes.len()];
        for (k, &(i, _)) in self.unknown.iter().enumerate() {
            slot[i as usize] = k as u32;
        }
        let boundary_is_outside = self.soup.closed_strictly_inside(&self.region);
        let mut component = vec![NONE; self.unknown.len()];
        let (mut components, mut queries) = (0, 0);
        let (mut queue, mut members, mut adjacent) = (Vec::new(), Vec::new(), Vec::new());
        for start in 0..self.unknown.len() {
            if component[start] != NONE {
                continue;
            }
            let c = components as u32;
            components += 1;
            component[start] = c;
            queue.push(start);
            members.clear();
            let mut touches_boundary = false;
            let mut largest = start;
            while let Some(k) = queue.pop() {
                members.push(k);
                let (node, cell) = self.unknown[k];
                touches_boundary |= cell.touches_boundary();
                if cell.level < self.unknown[largest].1.level {
                    largest = k;
                }
                for dir in Direction::FACES {
                    adjacent.clear();
                    adjacent_leaves(&self.nodes, node, dir, &mut adjacent);
                    for &m in &adjacent {
                        let s = slot[m as usize];
                        if s != NONE && component[s as usize] == NONE {
                            component[s as usize] = c;
                            queue.push(s as usize);
                        }
                    }
                }
            }
            let full = if touches_boundary && boundary_is_outside {
                false
            } else {
                queries += 1;
                let centre = self.region.cell_box(self.unknown[largest].1).center();
                self.soup.is_inside(centre)
            };
            let leaf = if full { Leaf::Full } else { Leaf::Empty };
            for &k in &members {
                self.nodes[self.unknown[k].0 as usize].set_leaf(leaf);
            }
        }
        (components, queries)
    }
}

impl Octree {
    /// Voxelizes triangles into a tree over `region` with voxels at level `depth`
    /// (at most [`super::MAX_DEPTH`]). Triangles outside the region are ignored.
    pub fn build(soup: &TriangleSoup, region: Region, depth: u32) -> Result<Octree> {
        Self::build_until(soup, region, depth, &crate::work::Deadline::default())
    }

    /// [`Octree::build`] that stops with the deadline's error (see [`crate::work`])
    /// when it passes during the subdivision.
    pub fn build_until(
        soup: &TriangleSoup,
        region: Region,
        depth: u32,
        deadline: &crate::work::Deadline,
    ) -> Result<Octree> {
        check_depth(depth)?;
        let start = Instant::now();
        let tmin: Vec<DVec3> = soup
            .triangles
            .iter()
            .map(|t| t[0].min(t[1]).min(t[2]))
            .collect();
        let tmax: Vec<DVec3> = soup
            .triangles
            .iter()
            .map(|t| t[0].max(t[1]).max(t[2]))
            .collect();
        let mut b = Builder {
            soup,
            tmin: &tmin,
            tmax: &tmax,
            region,
            depth,
            nodes: vec![Node::new(NONE, 0, 0)],
            unknown: Vec::new(),
            sat_tests: 0,
            deadline,
            stopped: false,
        };
        let root_box = region.cell_box(Cell::ROOT);
        let list: Vec<u32> = (0..soup.len() as u32)
            .filter(|&t| b.overlaps(t, &root_box))
            .collect();
        b.subdivide_root(&list);
        drop(list);
        if b.stopped {
            return Err(deadline.error("octree construction"));
        }
        let subdivide_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let (components, inside_queries) = b.classify();
        let classify_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let nodes = compact(&b.nodes);
        let compact_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(Octree {
            region,
            frame: DVec3::ZERO,
            depth,
            nodes,
            build_stats: BuildStats {
                triangles: soup.len(),
                triangles_ms: 0.0,
                raw_nodes: b.nodes.len(),
                sat_tests: b.sat_tests,
                components,
                inside_queries,
                subdivide_ms,
                classify_ms,
                compact_ms,
            },
        })
    }

    /// Voxelizes a scene over [`Region::enclosing`] its bounds, in the scene's own
    /// frame when it lies far from the origin beside its size (see "Frame" in the
    /// module documentation, [`Octree::frame_origin`]). A scene with no triangle gives
    /// a single Empty leaf over the unit cube.
    pub fn from_scene(scene: &Scene, depth: u32) -> Result<Octree> {
        Self::from_scene_until(scene, depth, &crate::work::Deadline::default())
    }

    /// [`Octree::from_scene`] that stops with the deadline's error (see
    /// [`crate::work`]) when it passes during the build.
    pub fn from_scene_until(
        scene: &Scene,
        depth: u32,
        deadline: &crate::work::Deadline,
    ) -> Result<Octree> {
        check_depth(depth)?;
        let start = Instant::now();
        let mut soup = TriangleSoup::from_scene(scene);
        let bounds = soup.bounds();
        let frame = scene_frame(&bounds);
        if frame != DVec3::ZERO {
            soup.translate(-frame);
        }
        let triangles_ms = start.elapsed().as_secs_f64() * 1e3;
        let mut tree = match Region::enclosing(&soup.bounds()) {
            Some(region) => Octree::build_until(&soup, region, depth, deadline)?,
            None => Octree::uniform(Region::new(DVec3::ZERO, 1.0)?, depth, Leaf::Empty)?,
        };
        tree.frame = frame;
        tree.build_stats.triangles_ms = triangles_ms;
        Ok(tree)
    }
}

/// The origin of the frame a scene with these bounds is voxelized in: the centre of
/// the box when it lies farther from the origin than the box's largest extent (the
/// world frame would round cell boxes to the coordinates' magnitude), else zero.
pub(crate) fn scene_frame(bounds: &Aabb) -> DVec3 {
    if bounds.is_empty() || !(bounds.min.is_finite() && bounds.max.is_finite()) {
        return DVec3::ZERO;
    }
    let centre = bounds.center();
    if centre.abs().max_element() > bounds.extent().max_element() {
        centre
    } else {
        DVec3::ZERO
    }
}

impl TriangleSoup {
    /// Moves every triangle (and the objects' boxes) by `by`.
    fn translate(&mut self, by: DVec3) {
        for t in &mut self.triangles {
            *t = t.map(|v| v + by);
        }
        for o in &mut self.objects {
            o.bounds = Aabb::from_points(self.triangles[o.start..o.end].iter().flatten().copied());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo;

    /// Clips a triangle by the six planes of a box (Sutherland-Hodgman): something is
    /// left exactly when they overlap, an independent check of the separating axes.
    fn clipped_area_nonzero(t: &[DVec3; 3], min: DVec3, max: DVec3) -> Option<bool> {
        let mut poly: Vec<DVec3> = t.to_vec();
        for axis in 0..3 {
            for (bound, keep_below) in [(max[axis], true), (min[axis], false)] {
                let inside = |p: DVec3| {
                    if keep_below {
                        p[axis] <= bound
                    } else {
                        p[axis] >= bound
                    }
                };
                let mut out = Vec::new();
                for k in 0..poly.len() {
                    let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                    if inside(a) {
                        out.push(a);
                    }
                    if inside(a) != inside(b) {
                        let s = (bound - a[axis]) / (b[axis] - a[axis]);
                        out.push(a + (b - a) * s);
                    }
                }
                poly = out;
                if poly.is_empty() {
                    return Some(false);
                }
            }
        }
        Some(true)
    }

    #[test]
    fn separating_axes_agree_with_clipping_on_random_triangles() {
        let mut rng = crate::rng::SplitMix64(11);
        let (min, max) = (DVec3::splat(-0.5), DVec3::splat(0.5));
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..20_000 {
            let mut p = || {
                DVec3::new(
                    rng.range(-1.5, 1.5),
                    rng.range(-1.5, 1.5),
                    rng.range(-1.5, 1.5),
                )
            };
            let t = [p(), p(), p()];
            let expected = clipped_area_nonzero(&t, min, max).unwrap();
            // Near-tangent cases may differ by rounding: skip triangles within 1e-9 of
            // the box boundary by testing a slightly smaller and larger box.
            let shrunk = triangle_box_overlap(&t, min + 1e-9, max - 1e-9);
            let grown = triangle_box_overlap(&t, min - 1e-9, max + 1e-9);
            if shrunk != grown {
                continue;
            }
            assert_eq!(triangle_box_overlap(&t, min, max), expected, "{t:?}");
            if expected {
                hits += 1;
            } else {
                misses += 1;
            }
        }
        assert!(hits > 1000 && misses > 1000, "{hits} {misses}");
    }

    #[test]
    fn separating_axes_known_cases() {
        let (min, max) = (DVec3::ZERO, DVec3::ONE);
        // A triangle through the middle of the box, its vertices all outside.
        let big = [
            DVec3::new(-5.0, -5.0, 0.5),
            DVec3::new(10.0, -5.0, 0.5),
            DVec3::new(-5.0, 10.0, 0.5),
        ];
        assert!(triangle_box_overlap(&big, min, max));
        // The box lies beyond this triangle's hypotenuse: only an edge axis separates.
        let corner = [
            DVec3::new(-1.0, -1.0, 0.5),
            DVec3::new(0.9, -1.0, 0.5),
            DVec3::new(-1.0, 0.9, 0.5),
        ];
        assert!(!triangle_box_overlap(&corner, min, max));
        // Touching a face counts.
        let touching = [
            DVec3::new(1.0, 0.2, 0.2),
            DVec3::new(2.0, 0.2, 0.2),
            DVec3::new(1.0, 0.8, 0.2),
        ];
        assert!(triangle_box_overlap(&touching, min, max));
        // The plane misses the box: the normal axis separates.
        let tilted = [
            DVec3::new(-1.0, -1.0, 1.2),
            DVec3::new(3.0, -1.0, 3.0),
            DVec3::new(-1.0, 3.0, 3.0),
        ];
        assert!(!triangle_box_overlap(&tilted, min, max));
    }

    #[test]
    fn winding_numbers_of_a_cube() {
        let s = demo::cube();
        let soup = TriangleSoup::from_scene(&s);
        assert_eq!(soup.len(), 12);
        let w = winding_number(DVec3::new(0.1, 0.2, -0.3), &soup.triangles);
        assert!((w - 1.0).abs() < 1e-12, "{w}");
        let w = winding_number(DVec3::new(0.1, 2.0, -0.3), &soup.triangles);
        assert!(w.abs() < 1e-12, "{w}");
        assert!(soup.is_inside(DVec3::splat(0.4)));
        assert!(!soup.is_inside(DVec3::splat(0.6)));
    }

    #[test]
    fn closest_points() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let near = |p: DVec3, q: DVec3| (closest_point_on_triangle(p, &t) - q).length() < 1e-12;
        assert!(near(DVec3::new(0.2, 0.2, 5.0), DVec3::new(0.2, 0.2, 0.0)));
        assert!(near(DVec3::new(-1.0, -1.0, 0.0), DVec3::ZERO));
        assert!(near(DVec3::new(2.0, -1.0, 0.0), DVec3::X));
        assert!(near(DVec3::new(0.5, -1.0, 1.0), DVec3::new(0.5, 0.0, 0.0)));
        assert!(near(DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.5, 0.5, 0.0)));
        assert!(near(
            DVec3::new(-3.0, 0.25, 0.0),
            DVec3::new(0.0, 0.25, 0.0)
        ));
        let flat = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(closest_point_on_triangle(DVec3::Y, &flat).is_finite());
    }

    #[test]
    fn a_cube_voxelizes_into_a_shell_around_a_full_core() {
        // Depth 4: the padding (1/64 of the side) is thinner than a voxel, so the
        // region's corner voxel holds the cube's corner.
        let t = Octree::from_scene(&demo::cube(), 4).unwrap();
        let c = t.leaf_counts();
        assert!(c.full > 0 && c.partial > 0);
        assert!(matches!(t.voxel(0, 0, 0), Some(Leaf::Partial { face }) if face < 6));
        let mid = 1 << (t.depth() - 1);
        assert_eq!(t.voxel(mid, mid, mid), Some(Leaf::Full));
        // Depth 7: voxels are thinner than the padding, so there is an outside; it
        // touches the region's boundary and needs no query, the inside needs one.
        let t = Octree::from_scene(&demo::cube(), 7).unwrap();
        assert_eq!(t.voxel(0, 0, 0), Some(Leaf::Empty));
        assert_eq!(t.build_stats().components, 2);
        assert_eq!(t.build_stats().inside_queries, 1);
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn parallel_build_equals_one_thread() {
        let scene = demo::sphere(96, 48); // above the parallel threshold
        let soup = TriangleSoup::from_scene(&scene);
        let region = Region::enclosing(&soup.bounds()).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let a = one.install(|| Octree::build(&soup, region, 6).unwrap());
        let b = two.install(|| Octree::build(&soup, region, 6).unwrap());
        assert_eq!(a.nodes(), b.nodes());
        assert_eq!(a.build_stats().sat_tests, b.build_stats().sat_tests);
        assert_eq!(a.build_stats().components, b.build_stats().components);
    }

    #[test]
    fn empty_and_tiny_inputs() {
        let t = Octree::from_scene(&Scene::new(), 5).unwrap();
        assert_eq!(t.node_count(), 1);
        assert_eq!(t.node(0).kind(), NodeKind::Empty);
        let t = Octree::from_scene(&demo::cube(), 0).unwrap();
        assert_eq!(t.node(0).kind(), NodeKind::Partial);
        assert!(Octree::from_scene(&demo::cube(), 11).is_err());
        let mut soup = TriangleSoup::new();
        let skipped = soup.push_object([([DVec3::NAN, DVec3::X, DVec3::Y], 0)], true);
        assert_eq!(skipped, 1);
        assert!(soup.is_empty());
    }
}
