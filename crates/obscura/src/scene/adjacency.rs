//! Edge adjacency: which polygons share an edge. Used to decide whether a mesh is
//! closed (so back faces can be culled) and convex, and by hidden-line drawing.
//!
//! Vertices are welded by exact position first, so triangle soups (every triangle with
//! its own three vertices, as in many OBJ exports) get their adjacency too.

use std::collections::HashMap;

use glam::DVec3;

use super::Mesh;

/// One undirected edge of a mesh with the polygons on either side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshEdge {
    /// The welded vertex ids of the ends, `a < b`.
    pub a: u32,
    /// See `a`.
    pub b: u32,
    /// The polygon that uses the edge in the direction `a -> b`, if any.
    pub forward: Option<u32>,
    /// The polygon that uses it as `b -> a`, if any.
    pub backward: Option<u32>,
    /// How many polygon sides lie on this edge (2 for a manifold interior edge).
    pub uses: u32,
}

/// The edges of a mesh with their polygons.
#[derive(Clone, Debug, Default)]
pub struct EdgeAdjacency {
    /// Welded vertex id of every mesh vertex.
    pub weld: Vec<u32>,
    /// Every undirected edge, sorted by `(a, b)`.
    pub edges: Vec<MeshEdge>,
}

impl EdgeAdjacency {
    /// Computes the adjacency of a mesh.
    #[must_use]
    pub fn new(mesh: &Mesh) -> Self {
        let weld = weld_positions(mesh.positions());
        // (min, max, direction bit, polygon) packed for one sort.
        let mut half: Vec<(u64, u32)> = Vec::with_capacity(mesh.polygon_count() * 3);
        for p in 0..mesh.polygon_count() {
            let poly = mesh.polygon(p);
            for k in 0..poly.len() {
                let u = weld[poly[k] as usize];
                let v = weld[poly[(k + 1) % poly.len()] as usize];
                if u == v {
                    continue;
                }
                let (a, b, dir) = if u < v { (u, v, 0) } else { (v, u, 1) };
                half.push(((u64::from(a) << 32 | u64::from(b)) << 1 | dir, p as u32));
            }
        }
        half.sort_unstable();
        let mut edges: Vec<MeshEdge> = Vec::with_capacity(half.len() / 2 + 1);
        for &(key, poly) in &half {
            let (a, b, dir) = ((key >> 33) as u32, (key >> 1) as u32, key & 1);
            match edges.last_mut() {
                Some(e) if e.a == a && e.b == b => {
                    e.uses += 1;
                    if dir == 0 {
                        e.forward.get_or_insert(poly);
                    } else {
                        e.backward.get_or_insert(poly);
                    }
                }
                _ => edges.push(MeshEdge {
                    a,
                    b,
                    forward: (dir == 0).then_some(poly),
                    backward: (dir == 1).then_some(poly),
                    uses: 1,
                }),
            }
        }
        EdgeAdjacency { weld, edges }
    }

    /// Closed: every edge is used exactly twice, once in each direction (an oriented
    /// 2-manifold without boundary, the condition for back-face culling).
    #[must_use]
    pub fn is_closed(&self) -> bool {
        !self.edges.is_empty()
            && self
                .edges
                .iter()
                .all(|e| e.uses == 2 && e.forward.is_some() && e.backward.is_some())
    }

    /// Number of edges used by one polygon only.
    #[must_use]
    pub fn boundary_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| e.uses == 1).count()
    }
}

/// Welded id per vertex: equal positions (bitwise, with -0 = +0) get the lowest index.
fn weld_positions(p: &[DVec3]) -> Vec<u32> {
    let key = |v: DVec3| {
        [
            (v.x + 0.0).to_bits(),
            (v.y + 0.0).to_bits(),
            (v.z + 0.0).to_bits(),
        ]
    };
    let mut map: HashMap<[u64; 3], u32> = HashMap::with_capacity(p.len());
    p.iter()
        .enumerate()
        .map(|(i, &v)| *map.entry(key(v)).or_insert(i as u32))
        .collect()
}

/// Whether a closed mesh is convex: across every edge, the far vertices of each
/// polygon lie on or behind the other polygon's plane (locally convex everywhere, which
/// for a closed connected surface means convex). `tolerance` is relative to the mesh size.
#[must_use]
pub fn is_convex_closed(mesh: &Mesh, adjacency: &EdgeAdjacency, tolerance: f64) -> bool {
    if !adjacency.is_closed() {
        return false;
    }
    let size = mesh.bounds().extent().length().max(f64::MIN_POSITIVE);
    let planes: Vec<_> = (0..mesh.polygon_count())
        .map(|i| mesh.polygon_plane(i))
        .collect();
    // Connectedness: one component (union-find over edges).
    let mut parent: Vec<u32> = (0..mesh.polygon_count() as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for e in &adjacency.edges {
        let (Some(f), Some(g)) = (e.forward, e.backward) else {
            return false;
        };
        let (Some(pf), Some(pg)) = (planes[f as usize], planes[g as usize]) else {
            return false;
        };
        let beyond = |plane: &crate::geom::Plane, poly: u32| {
            mesh.polygon(poly as usize)
                .iter()
                .any(|&v| plane.evaluate(mesh.positions()[v as usize]) > tolerance * size)
        };
        if beyond(&pf, g) || beyond(&pg, f) {
            return false;
        }
        let (rf, rg) = (find(&mut parent, f), find(&mut parent, g));
        parent[rf as usize] = rg;
    }
    let root = find(&mut parent, 0);
    (0..mesh.polygon_count() as u32).all(|i| find(&mut parent, i) == root)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo;

    #[test]
    fn cube_is_closed_and_convex() {
        let cube = demo::box_mesh(DVec3::splat(-1.0), DVec3::splat(1.0));
        let adj = EdgeAdjacency::new(&cube);
        assert!(adj.is_closed());
        assert_eq!(adj.edges.len(), 12); // quads are kept whole: the 12 cube edges
        assert!(is_convex_closed(&cube, &adj, 1e-9));
    }

    #[test]
    fn torus_is_closed_not_convex_and_open_grid_is_open() {
        let torus = demo::torus_mesh(1.0, 0.3, 12, 8);
        let adj = EdgeAdjacency::new(&torus);
        assert!(adj.is_closed());
        assert!(!is_convex_closed(&torus, &adj, 1e-9));
        let plane = demo::grid_mesh(2.0, 2.0, 3, 3);
        let adj = EdgeAdjacency::new(&plane);
        assert!(!adj.is_closed());
        assert_eq!(adj.boundary_edge_count(), 12);
    }
}
