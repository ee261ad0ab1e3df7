//! Clusters: big meshes cut into groups of about [`CLUSTER_TRIANGLES`] triangles, each
//! with its own world-space box, so that a scene made of one big object (Sponza) can
//! be culled piece by piece.
//!
//! Each object's polygons are split top down, as a bounding-volume hierarchy is built,
//! by the binned surface-area heuristic over their centroids (Wald 2007), until a part
//! holds at most [`CLUSTER_TRIANGLES`] triangles: neighbours in space end up in the
//! same cluster and boxes stay small, and big polygons (walls, floors) are kept apart
//! from small detail whose box they would swell. (Runs of a Morton curve, the first
//! version, left Sponza's clusters so large that no occlusion method culled one.) An
//! object of at most that many triangles is one cluster. In each cluster the polygons
//! are listed largest first: the occlusion buffer draws a cluster's big polygons as
//! occluders. Built once per scene ([`SceneIndex::clusters`]).

use glam::DVec3;

use super::frustum::Containment;
use super::occlusion::{CullReason, Culling};
use crate::geom::Aabb;
use crate::index::SceneIndex;
use crate::scene::Scene;
use crate::view::ViewTransform;

/// The triangles a cluster aims at.
pub const CLUSTER_TRIANGLES: usize = 100;

/// The clusters of a scene, object by object (see the [module documentation](self)).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clusters {
    /// Per cluster, its object.
    object: Vec<u32>,
    /// Per cluster, its first entry in `polygons`; then the total.
    starts: Vec<u32>,
    /// Polygon numbers local to the object (its mesh's polygons), cluster by cluster;
    /// in each cluster, largest world-space area first.
    polygons: Vec<u32>,
    /// The world-space area of each entry of `polygons`.
    areas: Vec<f32>,
    /// Per cluster, its world-space box.
    bounds: Vec<Aabb>,
    /// Per cluster, its triangle count.
    triangles: Vec<u32>,
    /// Per object, its first cluster; then the total.
    object_first: Vec<u32>,
}

impl Clusters {
    /// The clusters of a scene.
    #[must_use]
    pub fn new(scene: &Scene) -> Clusters {
        let mut c = Clusters::default();
        let mut items: Vec<Item> = Vec::new();
        let mut stack: Vec<(usize, usize)> = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            c.object_first.push(c.object.len() as u32);
            let mesh = &o.mesh;
            let n = mesh.polygon_count();
            if n == 0 {
                continue;
            }
            let (starts, indices, _) = mesh.polygon_arrays();
            let world: Vec<DVec3> = mesh
                .positions()
                .iter()
                .map(|&p| o.transform.transform_point3(p))
                .collect();
            items.clear();
            items.extend((0..n).map(|p| {
                let poly = &indices[starts[p] as usize..starts[p + 1] as usize];
                let bounds = Aabb::from_points(poly.iter().map(|&i| world[i as usize]));
                let a = world[poly[0] as usize];
                // The polygon's area (its fan's), for ranking occluders.
                let area = poly
                    .windows(2)
                    .skip(1)
                    .map(|w| {
                        (world[w[0] as usize] - a)
                            .cross(world[w[1] as usize] - a)
                            .length()
                    })
                    .sum::<f64>()
                    * 0.5;
                Item {
                    polygon: p as u32,
                    triangles: (poly.len() - 2) as u32,
                    centroid: bounds.center(),
                    bounds,
                    area: area as f32,
                }
            }));
            // Top-down: split until a node holds at most CLUSTER_TRIANGLES triangles.
            stack.clear();
            stack.push((0, items.len()));
            while let Some((lo, hi)) = stack.pop() {
                let node = &mut items[lo..hi];
                let triangles: usize = node.iter().map(|i| i.triangles as usize).sum();
                if triangles <= CLUSTER_TRIANGLES || node.len() == 1 {
                    c.push_cluster(k, node);
                    continue;
                }
                let mid = lo + split(node);
                stack.push((mid, hi));
                stack.push((lo, mid));
            }
        }
        c.object_first.push(c.object.len() as u32);
        c.starts.push(c.polygons.len() as u32);
        c
    }

    /// Appends a cluster of object `k` made of `items`, largest polygons first (the
    /// occlusion buffer takes a cluster's occluders from the front of its list).
    fn push_cluster(&mut self, k: usize, items: &mut [Item]) {
        items.sort_unstable_by(|a, b| b.area.total_cmp(&a.area).then(a.polygon.cmp(&b.polygon)));
        self.object.push(k as u32);
        self.starts.push(self.polygons.len() as u32);
        let mut bounds = Aabb::default();
        let mut triangles = 0u32;
        for i in items.iter() {
            self.polygons.push(i.polygon);
            self.areas.push(i.area);
            bounds = bounds.union(i.bounds);
            triangles += i.triangles;
        }
        self.bounds.push(bounds);
        self.triangles.push(triangles);
    }

    /// The number of clusters.
    #[must_use]
    pub fn len(&self) -> usize {
        self.object.len()
    }

    /// Whether there are none (a scene without faces).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.object.is_empty()
    }

    /// The object of cluster `c`.
    #[must_use]
    pub fn object(&self, c: usize) -> u32 {
        self.object[c]
    }

    /// The polygons of cluster `c`, numbered in its object's mesh, largest world-space
    /// area first.
    #[must_use]
    pub fn polygons(&self, c: usize) -> &[u32] {
        &self.polygons[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    /// The world-space areas of the polygons of cluster `c`, in the order of
    /// [`Self::polygons`] (largest first).
    #[must_use]
    pub fn areas(&self, c: usize) -> &[f32] {
        &self.areas[self.starts[c] as usize..self.starts[c + 1] as usize]
    }

    /// The world-space box of cluster `c`.
    #[must_use]
    pub fn bounds(&self, c: usize) -> &Aabb {
        &self.bounds[c]
    }

    /// The triangle count of cluster `c`.
    #[must_use]
    pub fn triangles(&self, c: usize) -> u32 {
        self.triangles[c]
    }

    /// The clusters of object `k`.
    #[must_use]
    pub fn of_object(&self, k: usize) -> std::ops::Range<usize> {
        self.object_first[k] as usize..self.object_first[k + 1] as usize
    }
}

/// A polygon while clusters are built.
#[derive(Clone, Copy, Debug)]
struct Item {
    polygon: u32,
    triangles: u32,
    centroid: DVec3,
    bounds: Aabb,
    area: f32,
}

/// The bins of a split along one axis.
const BINS: usize = 16;

/// Reorders `items` (more than one) into two non-empty halves and returns the size of
/// the first: the binned split of least surface-area cost (Wald, "On fast
/// construction of SAH-based bounding volume hierarchies", 2007) over the centroids,
/// or halves by count when the centroids coincide.
fn split(items: &mut [Item]) -> usize {
    let cb = items
        .iter()
        .fold(Aabb::default(), |b, i| b.with_point(i.centroid));
    let e = cb.extent();
    let mut best: Option<(f64, usize, usize)> = None; // cost, axis, first bin of the right
    for axis in 0..3 {
        if !(e[axis] > 0.0) {
            continue;
        }
        let bin = |i: &Item| {
            (((i.centroid[axis] - cb.min[axis]) / e[axis] * BINS as f64) as usize).min(BINS - 1)
        };
        let mut count = [0f64; BINS];
        let mut boxes = [Aabb::default(); BINS];
        for i in items.iter() {
            let b = bin(i);
            count[b] += f64::from(i.triangles);
            boxes[b] = boxes[b].union(i.bounds);
        }
        let mut right = [0f64; BINS];
        let (mut rb, mut rn) = (Aabb::default(), 0.0);
        for b in (1..BINS).rev() {
            rb = rb.union(boxes[b]);
            rn += count[b];
            right[b] = rb.half_area() * rn;
        }
        let (mut lb, mut ln) = (Aabb::default(), 0.0);
        for b in 1..BINS {
            lb = lb.union(boxes[b - 1]);
            ln += count[b - 1];
            if ln == 0.0 || right[b] == 0.0 {
                continue;
            }
            let cost = lb.half_area() * ln + right[b];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    if let Some((_, axis, b)) = best {
        let bin = |i: &Item| {
            (((i.centroid[axis] - cb.min[axis]) / e[axis] * BINS as f64) as usize).min(BINS - 1)
        };
        let mut left = 0;
        for j in 0..items.len() {
            if bin(&items[j]) < b {
                items.swap(left, j);
                left += 1;
            }
        }
        if left > 0 && left < items.len() {
            return left;
        }
    }
    items.len() / 2
}

/// The frustum stage of every culling method: objects outside the view volume (the
/// pipeline's own test, [`ViewTransform::object_containment`]), then, in objects that
/// cross its boundary, clusters whose boxes lie outside.
pub(crate) fn frustum(index: &SceneIndex<'_>, t: &ViewTransform, clusters: bool, c: &mut Culling) {
    let scene = index.scene();
    let planes = t.eye_frustum_planes();
    let all = index.clusters();
    for (k, o) in scene.objects().iter().enumerate() {
        if o.mesh.polygon_count() == 0 {
            continue;
        }
        match t.object_containment(&planes, o) {
            Containment::Outside => c.cull_object(k, CullReason::Frustum),
            Containment::Inside => {}
            Containment::Intersecting if clusters => {
                for cl in all.of_object(k) {
                    let b = all.bounds(cl);
                    let corners = b.corners().map(|p| t.world_to_clip(p));
                    if super::frustum::classify_clip_points(corners) == Containment::Outside {
                        c.cull_cluster(cl, CullReason::Frustum);
                    }
                }
            }
            Containment::Intersecting => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo;

    #[test]
    fn every_polygon_in_exactly_one_cluster_of_about_the_size() {
        let scene = demo::sphere(100, 100);
        let c = Clusters::new(&scene);
        let o = &scene.objects()[0];
        let mut seen = vec![0u32; o.mesh.polygon_count()];
        for cl in 0..c.len() {
            for &p in c.polygons(cl) {
                seen[p as usize] += 1;
                for &v in o.mesh.polygon(p as usize) {
                    let w = o.transform.transform_point3(o.mesh.positions()[v as usize]);
                    assert!(c.bounds(cl).contains(w));
                }
            }
            assert!(c.triangles(cl) as usize <= CLUSTER_TRIANGLES + 2);
        }
        assert!(seen.iter().all(|&n| n == 1));
        assert!(c.len() >= o.mesh.triangle_count() / (CLUSTER_TRIANGLES + 2));
    }
}
