//! Edge adjacency: which polygons share an edge. Used to decide whether a mesh is
//! closed (so back faces can be culled) and convex, and by hidden-line drawing.
//!
//! Vertices are welded by exact position first, so triangle soups (every triangle with
//! its own three vertices, as in many OBJ exports) get their adjacency too.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

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
    /// Computes the adjacency of a mesh in O(n) expected time: welding by hashing, then
    /// one radix sort of the half-edges packed into `u64` keys (falling back to a
    /// comparison sort for meshes too large to pack).
    #[must_use]
    pub fn new(mesh: &Mesh) -> Self {
        let weld = weld_positions(mesh.positions());
        let (starts, indices, _) = mesh.polygon_arrays();
        let polygons = mesh.polygon_count();
        let vbits = bits_for(weld.len());
        let pbits = bits_for(polygons);
        // Half-edges as (a, b, direction, polygon) with a < b: sorted, the two sides of
        // an edge become neighbours, forward before backward, lowest polygon first.
        let mut half: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(indices.len());
        for p in 0..polygons {
            let poly = &indices[starts[p] as usize..starts[p + 1] as usize];
            for k in 0..poly.len() {
                let u = weld[poly[k] as usize];
                let v = weld[poly[(k + 1) % poly.len()] as usize];
                if u != v {
                    let (a, b, dir) = if u < v { (u, v, 0) } else { (v, u, 1) };
                    half.push((a, b, dir, p as u32));
                }
            }
        }
        if 2 * vbits + 1 + pbits <= 64 {
            let (sb, sd) = (pbits + 1, pbits);
            let sa = sb + vbits;
            let mut keys: Vec<u64> = half
                .iter()
                .map(|&(a, b, d, p)| {
                    u64::from(a) << sa | u64::from(b) << sb | u64::from(d) << sd | u64::from(p)
                })
                .collect();
            radix_sort(&mut keys, sa + vbits);
            let mask = |bits: u32| (1u64 << bits) - 1;
            for (h, &k) in half.iter_mut().zip(&keys) {
                *h = (
                    (k >> sa & mask(vbits)) as u32,
                    (k >> sb & mask(vbits)) as u32,
                    (k >> sd & 1) as u32,
                    (k & mask(pbits)) as u32,
                );
            }
        } else {
            half.sort_unstable();
        }
        let mut edges: Vec<MeshEdge> = Vec::with_capacity(half.len() / 2 + 1);
        for &(a, b, dir, poly) in &half {
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

/// Bits needed to store values `0..n` (at least 1).
fn bits_for(n: usize) -> u32 {
    (usize::BITS - n.saturating_sub(1).leading_zeros()).max(1)
}

/// Sorts keys whose set bits all lie below `bits`: least-significant-digit radix sort
/// with 8-bit digits, skipping digits on which all keys agree.
fn radix_sort(keys: &mut Vec<u64>, bits: u32) {
    let mut scratch = vec![0u64; keys.len()];
    for shift in (0..bits).step_by(8) {
        let mut count = [0usize; 256];
        for &k in keys.iter() {
            count[(k >> shift & 0xff) as usize] += 1;
        }
        if count.contains(&keys.len()) {
            continue;
        }
        let mut offset = [0usize; 256];
        let mut sum = 0;
        for (o, c) in offset.iter_mut().zip(count) {
            *o = sum;
            sum += c;
        }
        for &k in keys.iter() {
            let d = (k >> shift & 0xff) as usize;
            scratch[offset[d]] = k;
            offset[d] += 1;
        }
        std::mem::swap(keys, &mut scratch);
    }
}

/// A small multiplicative hasher for bit patterns of coordinates: the standard library's
/// DoS-resistant hasher costs more than the rest of welding together.
#[derive(Default)]
struct BitsHasher(u64);

impl std::hash::Hasher for BitsHasher {
    fn finish(&self) -> u64 {
        self.0 ^ self.0 >> 29
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(23) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// Welded id per vertex: equal positions (bitwise, with -0 = +0) get the lowest index.
fn weld_positions(p: &[DVec3]) -> Vec<u32> {
    type Key = (u64, u64, u64);
    let key = |v: DVec3| -> Key {
        (
            (v.x + 0.0).to_bits(),
            (v.y + 0.0).to_bits(),
            (v.z + 0.0).to_bits(),
        )
    };
    let mut map: HashMap<Key, u32, BuildHasherDefault<BitsHasher>> =
        HashMap::with_capacity_and_hasher(p.len(), BuildHasherDefault::default());
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
    fn radix_sort_sorts() {
        let mut rng = crate::rng::SplitMix64(3);
        for bits in [1u32, 7, 8, 9, 37, 64] {
            let mask = if bits == 64 {
                u64::MAX
            } else {
                (1u64 << bits) - 1
            };
            let mut keys: Vec<u64> = (0..1000).map(|_| rng.next_u64() & mask).collect();
            let mut expected = keys.clone();
            expected.sort_unstable();
            radix_sort(&mut keys, bits);
            assert_eq!(keys, expected, "{bits} bits");
        }
        assert_eq!(
            (
                bits_for(0),
                bits_for(1),
                bits_for(2),
                bits_for(256),
                bits_for(257)
            ),
            (1, 1, 1, 8, 9)
        );
    }

    #[test]
    fn soups_are_welded() {
        // Six separate quads with their own vertices each still make a closed cube.
        let cube = demo::box_mesh(DVec3::splat(-1.0), DVec3::splat(1.0));
        let mut b = crate::scene::MeshBuilder::new();
        for p in 0..cube.polygon_count() {
            let base = b.vertex_count() as u32;
            for &v in cube.polygon(p) {
                b.push_position(cube.positions()[v as usize] * 1.0);
            }
            b.push_face(&[base, base + 1, base + 2, base + 3], None)
                .unwrap();
        }
        let soup = b.finish().0;
        let adj = EdgeAdjacency::new(&soup);
        assert!(adj.is_closed());
        assert_eq!(adj.edges.len(), 12);
        assert_eq!(
            adj.weld
                .iter()
                .collect::<std::collections::HashSet<_>>()
                .len(),
            8
        );
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
