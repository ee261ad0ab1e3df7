//! Clusters: big meshes cut into groups of about [`CLUSTER_TRIANGLES`] triangles, each
//! with its own world-space box, so that a scene made of one big object (Sponza) can
//! be culled piece by piece.
//!
//! Each object's polygons are ordered along a Morton (Z-order) curve of their
//! centroids, then cut into runs of about [`CLUSTER_TRIANGLES`] triangles: neighbours
//! in space end up in the same cluster, so its box stays small. An object of fewer
//! triangles is one cluster. Built once per scene ([`SceneIndex::clusters`]).

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
    /// Polygon numbers local to the object (its mesh's polygons), cluster by cluster.
    polygons: Vec<u32>,
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
        let mut order: Vec<(u64, u32)> = Vec::new();
        for (k, o) in scene.objects().iter().enumerate() {
            c.object_first.push(c.object.len() as u32);
            let mesh = &o.mesh;
            let n = mesh.polygon_count();
            if n == 0 {
                continue;
            }
            let (starts, indices, _) = mesh.polygon_arrays();
            let positions = mesh.positions();
            let world: Vec<DVec3> = positions
                .iter()
                .map(|&p| o.transform.transform_point3(p))
                .collect();
            let centroid = |p: usize| {
                let poly = &indices[starts[p] as usize..starts[p + 1] as usize];
                poly.iter().map(|&i| world[i as usize]).sum::<DVec3>() / poly.len() as f64
            };
            let b = Aabb::from_points(world.iter().copied());
            let size = b.extent().max(DVec3::splat(1e-300));
            order.clear();
            order.extend((0..n).map(|p| {
                let q = ((centroid(p) - b.min) / size).clamp(DVec3::ZERO, DVec3::ONE);
                let cell = |v: f64| (v * 2_097_151.0) as u64;
                (morton3(cell(q.x), cell(q.y), cell(q.z)), p as u32)
            }));
            order.sort_unstable();
            let mut run_triangles = 0usize;
            let mut run_bounds = Aabb::default();
            for (i, &(_, p)) in order.iter().enumerate() {
                if i == 0 || run_triangles >= CLUSTER_TRIANGLES {
                    if i > 0 {
                        c.close(run_bounds, run_triangles);
                    }
                    c.object.push(k as u32);
                    c.starts.push(c.polygons.len() as u32);
                    run_triangles = 0;
                    run_bounds = Aabb::default();
                }
                let poly = &indices[starts[p as usize] as usize..starts[p as usize + 1] as usize];
                run_triangles += poly.len() - 2;
                for &v in poly {
                    run_bounds = run_bounds.with_point(world[v as usize]);
                }
                c.polygons.push(p);
            }
            c.close(run_bounds, run_triangles);
        }
        c.object_first.push(c.object.len() as u32);
        c.starts.push(c.polygons.len() as u32);
        c
    }

    fn close(&mut self, bounds: Aabb, triangles: usize) {
        self.bounds.push(bounds);
        self.triangles.push(triangles as u32);
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

    /// The polygons of cluster `c`, numbered in its object's mesh.
    #[must_use]
    pub fn polygons(&self, c: usize) -> &[u32] {
        &self.polygons[self.starts[c] as usize..self.starts[c + 1] as usize]
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

/// Interleaves the low 21 bits of three coordinates.
fn morton3(x: u64, y: u64, z: u64) -> u64 {
    fn spread(v: u64) -> u64 {
        let mut v = v & 0x1f_ffff;
        v = (v | v << 32) & 0x1f_0000_0000_ffff;
        v = (v | v << 16) & 0x1f_0000_ff00_00ff;
        v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
        v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
        (v | v << 2) & 0x1249_2492_4924_9249
    }
    spread(x) | spread(y) << 1 | spread(z) << 2
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

    #[test]
    fn morton_interleaves() {
        assert_eq!(morton3(1, 0, 0), 1);
        assert_eq!(morton3(0, 1, 0), 2);
        assert_eq!(morton3(0, 0, 1), 4);
        assert_eq!(morton3(3, 0, 0), 9);
    }
}
