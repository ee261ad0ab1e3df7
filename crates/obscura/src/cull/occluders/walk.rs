//! A binary bounding-volume hierarchy over the clusters' boxes, built once per scene
//! ([`crate::SceneIndex::cluster_bvh`]), and its walk against shadow volumes: as the
//! seed puts it, starting from the highest level, a node wholly inside a shadow volume
//! is culled with everything under it, a node wholly outside every one is kept with
//! everything under it, a straddling node is opened. Each node carries down only the
//! occluders it straddles, so a deep node is tested against few.

use super::shadow::{BoxClass, ShadowVolume};
use crate::cull::clusters::Clusters;
use crate::cull::occlusion::CullReason;
use crate::geom::Aabb;

/// Clusters per leaf at most.
pub const LEAF_CLUSTERS: usize = 2;

/// A node: its box and either two children or a run of clusters.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    bounds: Aabb,
    /// Leaf: first entry in `order`; inner: the first child (the second follows it).
    first: u32,
    /// Leaf: how many clusters; inner: 0.
    count: u32,
}

/// The hierarchy over the clusters of a scene (see the [module documentation](self)).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusterBvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    /// Per cluster, its box.
    boxes: Vec<Aabb>,
}

impl ClusterBvh {
    /// The hierarchy of `clusters`: median split of the cluster centres along the
    /// longest axis of their spread, down to [`LEAF_CLUSTERS`] per leaf.
    #[must_use]
    pub fn new(clusters: &Clusters) -> ClusterBvh {
        let n = clusters.len();
        let mut bvh = ClusterBvh {
            nodes: Vec::with_capacity(2 * n.max(1)),
            order: (0..n as u32).collect(),
            boxes: (0..n).map(|c| *clusters.bounds(c)).collect(),
        };
        if n == 0 {
            return bvh;
        }
        let centres: Vec<_> = (0..n).map(|c| clusters.bounds(c).center()).collect();
        bvh.nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        let mut stack = vec![(0usize, 0usize, n)];
        while let Some((node, lo, hi)) = stack.pop() {
            let ids = &mut bvh.order[lo..hi];
            let bounds = ids
                .iter()
                .fold(Aabb::EMPTY, |b, &c| b.union(*clusters.bounds(c as usize)));
            if hi - lo <= LEAF_CLUSTERS {
                bvh.nodes[node] = Node {
                    bounds,
                    first: lo as u32,
                    count: (hi - lo) as u32,
                };
                continue;
            }
            let spread = ids
                .iter()
                .fold(Aabb::EMPTY, |b, &c| b.with_point(centres[c as usize]));
            let e = spread.extent();
            let axis = if e.x >= e.y && e.x >= e.z {
                0
            } else if e.y >= e.z {
                1
            } else {
                2
            };
            let mid = (hi - lo) / 2;
            ids.select_nth_unstable_by(mid, |&a, &b| {
                centres[a as usize][axis].total_cmp(&centres[b as usize][axis])
            });
            let left = bvh.nodes.len();
            let empty = Node {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            };
            bvh.nodes.push(empty);
            bvh.nodes.push(empty);
            bvh.nodes[node] = Node {
                bounds,
                first: left as u32,
                count: 0,
            };
            stack.push((left, lo, lo + mid));
            stack.push((left + 1, lo + mid, hi));
        }
        bvh
    }

    /// The number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The box of the root (empty for a scene without clusters).
    #[must_use]
    pub fn root_bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds)
    }

    /// Walks the hierarchy against `volumes` (best first) and marks in `decisions`
    /// (per cluster, `None` = kept so far) every cluster inside one of them with
    /// [`CullReason::Occluder`] of the first such volume's index in `volumes`. Clusters
    /// already decided stay as they are. Returns the nodes visited.
    pub fn walk(&self, volumes: &[ShadowVolume], decisions: &mut [Option<CullReason>]) -> usize {
        if self.nodes.is_empty() || volumes.is_empty() {
            return 0;
        }
        let mut active: Vec<u32> = (0..volumes.len() as u32).collect();
        let mut visited = 0;
        self.visit(0, 0, &mut active, volumes, decisions, &mut visited);
        visited
    }

    #[allow(clippy::too_many_arguments)]
    fn visit(
        &self,
        node: usize,
        from: usize,
        active: &mut Vec<u32>,
        volumes: &[ShadowVolume],
        decisions: &mut [Option<CullReason>],
        visited: &mut usize,
    ) {
        *visited += 1;
        let n = self.nodes[node];
        let to = active.len();
        for a in from..to {
            let v = active[a];
            match volumes[v as usize].classify(&n.bounds) {
                BoxClass::Inside => {
                    // Volumes are tried best first: the first that holds it names it.
                    let reason = CullReason::Occluder(v);
                    active.truncate(to);
                    self.mark(node, reason, decisions);
                    return;
                }
                BoxClass::Outside => {}
                BoxClass::Straddling => active.push(v),
            }
        }
        if active.len() > to {
            if n.count == 0 {
                let first = n.first as usize;
                self.visit(first, to, active, volumes, decisions, visited);
                self.visit(first + 1, to, active, volumes, decisions, visited);
            } else if n.count > 1 {
                // Open the leaf: each cluster against what its node straddles.
                for i in n.first..n.first + n.count {
                    let c = self.order[i as usize] as usize;
                    if decisions[c].is_some() {
                        continue;
                    }
                    *visited += 1;
                    let b = &self.boxes[c];
                    if let Some(&v) = active[to..]
                        .iter()
                        .find(|&&v| volumes[v as usize].classify(b) == BoxClass::Inside)
                    {
                        decisions[c] = Some(CullReason::Occluder(v));
                    }
                }
            }
        }
        active.truncate(to);
    }

    /// Culls every cluster under `node` not decided yet.
    fn mark(&self, node: usize, reason: CullReason, decisions: &mut [Option<CullReason>]) {
        let n = self.nodes[node];
        if n.count == 0 {
            self.mark(n.first as usize, reason, decisions);
            self.mark(n.first as usize + 1, reason, decisions);
        } else {
            for &c in &self.order[n.first as usize..(n.first + n.count) as usize] {
                let d = &mut decisions[c as usize];
                if d.is_none() {
                    *d = Some(reason);
                }
            }
        }
    }
}
