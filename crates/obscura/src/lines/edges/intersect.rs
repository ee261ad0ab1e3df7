//! Intersection lines: where triangles of the scene pass through each other.
//!
//! Candidates are the pairs of triangles whose boxes overlap, found by querying the
//! scene's BVH ([`crate::SceneIndex::bvh`]) with each triangle's box. A pair is then
//! decided with exact orientation predicates (Shewchuk's adaptive `orient3d`, from
//! the `robust` crate): each triangle's vertices are classified against the other's
//! plane; a triangle wholly on one side, or two coplanar triangles, give nothing.
//! Otherwise each triangle meets the other's plane in a segment (its vertices on the
//! plane, and the points of its edges whose ends lie on opposite sides, interpolated
//! by the two orientation values); both segments lie on the line where the planes
//! meet, and their overlap is the intersection (Möller 1997, "A fast triangle-triangle
//! intersection test", with the signs decided exactly). Two triangles sharing an edge
//! never cross; two sharing one vertex give a segment only when they really cross
//! (touching at the vertex gives a point, which is dropped).
//!
//! The pieces found for the triangles of two convex polygons are merged into one
//! segment per polygon pair (the intersection of two convex polygons with the line
//! where their planes meet is one segment).
//!
//! # Limitations
//! - Coplanar overlapping triangles draw nothing (no line crosses them).
//! - A segment lying along a mesh edge (a T-junction) is found as an intersection
//!   line as well as drawn as the edge it lies on.

use std::collections::HashMap;

use glam::DVec3;

use crate::accel::bvh::{Bvh, Slot, WIDTH, f32_down, f32_up};
use crate::geom::Aabb;

/// A segment where two polygons of the scene cross (view independent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IntersectionSegment {
    /// The two polygons (scene-wide polygon numbers, lower first).
    pub polygons: [u32; 2],
    /// Its ends in world space.
    pub world: [DVec3; 2],
}

use crate::geom::orient3d;

/// Where triangle `t` meets the plane its orientation values `o` refer to: one or two
/// points (`None` when it lies wholly on one side or in the plane).
fn plane_crossing(t: &[DVec3; 3], o: [f64; 3]) -> Option<[DVec3; 2]> {
    let mut pts = [DVec3::ZERO; 3];
    let mut n = 0;
    for i in 0..3 {
        if o[i] == 0.0 {
            pts[n] = t[i];
            n += 1;
        }
    }
    if n == 3 {
        return None;
    }
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        if (o[i] < 0.0 && o[j] > 0.0) || (o[i] > 0.0 && o[j] < 0.0) {
            pts[n] = t[i] + (t[j] - t[i]) * (o[i] / (o[i] - o[j]));
            n += 1;
        }
    }
    match n {
        0 => None,
        1 => Some([pts[0], pts[0]]),
        _ => Some([pts[0], pts[1]]),
    }
}

/// The segment where two triangles cross, if they do along more than a point.
/// Triangles that share an edge (two vertices bitwise equal) never cross; coplanar
/// triangles give `None`.
#[must_use]
pub fn triangle_intersection(t1: &[DVec3; 3], t2: &[DVec3; 3]) -> Option<[DVec3; 2]> {
    let shared = t1
        .iter()
        .map(|p| usize::from(t2.contains(p)))
        .sum::<usize>();
    if shared >= 2 {
        return None;
    }
    // Nothing but a point (or nothing) when no vertex is strictly on each side and at
    // most one lies on the plane; coplanar triangles (all on the plane) give nothing.
    let side = |o: [f64; 3]| {
        let zeros = o.iter().filter(|&&x| x == 0.0).count();
        let crosses = o.iter().any(|&x| x > 0.0) && o.iter().any(|&x| x < 0.0);
        zeros == 3 || (!crosses && zeros <= 1)
    };
    // A shared vertex lies exactly on the other's plane: its orientation is 0 without
    // asking `orient3d`, whose exact (slow) path every zero would take.
    let o2 = t2.map(|p| {
        if t1.contains(&p) {
            0.0
        } else {
            orient3d(t1[0], t1[1], t1[2], p)
        }
    });
    if side(o2) {
        return None;
    }
    let o1 = t1.map(|p| {
        if t2.contains(&p) {
            0.0
        } else {
            orient3d(t2[0], t2[1], t2[2], p)
        }
    });
    if side(o1) {
        return None;
    }
    let s1 = plane_crossing(t1, o1)?;
    let s2 = plane_crossing(t2, o2)?;
    let d1 = s1[1] - s1[0];
    let d2 = s2[1] - s2[0];
    let d = if d1.length_squared() >= d2.length_squared() {
        d1
    } else {
        d2
    };
    if d == DVec3::ZERO {
        return None;
    }
    let order = |s: [DVec3; 2]| {
        if d.dot(s[0]) <= d.dot(s[1]) {
            s
        } else {
            [s[1], s[0]]
        }
    };
    let (s1, s2) = (order(s1), order(s2));
    let lo = if d.dot(s1[0]) >= d.dot(s2[0]) {
        s1[0]
    } else {
        s2[0]
    };
    let hi = if d.dot(s1[1]) <= d.dot(s2[1]) {
        s1[1]
    } else {
        s2[1]
    };
    (d.dot(hi) > d.dot(lo) && lo != hi).then_some([lo, hi])
}

/// Whether two boxes overlap (touching counts).
#[inline]
fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a.min.x <= b.max.x
        && b.min.x <= a.max.x
        && a.min.y <= b.max.y
        && b.min.y <= a.max.y
        && a.min.z <= b.max.z
        && b.min.z <= a.max.z
}

fn triangle_box(t: &[DVec3; 3]) -> Aabb {
    Aabb {
        min: t[0].min(t[1]).min(t[2]),
        max: t[0].max(t[1]).max(t[2]),
    }
}

/// The crossings of leaf-order triangle `i` with the triangles after it whose boxes
/// overlap its box: `(polygon a, polygon b, segment)`.
fn crossings_of(bvh: &Bvh, i: usize, stack: &mut Vec<u32>, out: &mut Vec<(u32, u32, [DVec3; 2])>) {
    let tris = bvh.triangles();
    let polys = bvh.triangle_polygons();
    let t = &tris[i];
    let b = triangle_box(t);
    // The query box in single precision, rounded outwards, against the nodes' boxes
    // as stored (empty slots have `+inf` corners and never overlap).
    let lo = [f32_down(b.min.x), f32_down(b.min.y), f32_down(b.min.z)];
    let hi = [f32_up(b.max.x), f32_up(b.max.y), f32_up(b.max.z)];
    stack.clear();
    stack.push(0);
    while let Some(n) = stack.pop() {
        let node = bvh.node(n);
        for k in 0..WIDTH {
            let overlap = (0..3).all(|a| node.min[a][k] <= hi[a] && lo[a] <= node.max[a][k]);
            if !overlap {
                continue;
            }
            match node.slot(k) {
                Slot::Node(c) => stack.push(c),
                Slot::Leaf { first, count } => {
                    let start = (first as usize).max(i + 1);
                    for j in start..(first + count) as usize {
                        if polys[j] == polys[i] || !overlaps(&triangle_box(&tris[j]), &b) {
                            continue;
                        }
                        if let Some(s) = triangle_intersection(t, &tris[j]) {
                            out.push((polys[i], polys[j], s));
                        }
                    }
                }
                Slot::Empty => {}
            }
        }
    }
}

/// Every intersection line of the triangles of `bvh` (a scene's BVH: its triangles
/// carry their scene polygon numbers), one segment per pair of crossing polygons,
/// sorted by polygon pair.
#[must_use]
pub fn intersection_lines(bvh: &Bvh) -> Vec<IntersectionSegment> {
    let n = bvh.triangles().len();
    if n == 0 || bvh.node_count() == 0 {
        return Vec::new();
    }
    const CHUNK: usize = 1024;
    let run = |c: usize| {
        let mut stack = Vec::new();
        let mut out = Vec::new();
        for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
            crossings_of(bvh, i, &mut stack, &mut out);
        }
        out
    };
    #[cfg(feature = "parallel")]
    let parts: Vec<Vec<(u32, u32, [DVec3; 2])>> = {
        use rayon::prelude::*;
        (0..n.div_ceil(CHUNK)).into_par_iter().map(run).collect()
    };
    #[cfg(not(feature = "parallel"))]
    let parts: Vec<Vec<(u32, u32, [DVec3; 2])>> = (0..n.div_ceil(CHUNK)).map(run).collect();
    // One segment per polygon pair: the extremes of its pieces along their line.
    let mut pairs: HashMap<(u32, u32), (DVec3, [DVec3; 2])> = HashMap::new();
    for (a, b, s) in parts.into_iter().flatten() {
        let (key, s) = if a < b { ((a, b), s) } else { ((b, a), s) };
        let e = pairs.entry(key).or_insert((s[1] - s[0], s));
        let d = e.0;
        for p in s {
            if d.dot(p) < d.dot(e.1[0]) {
                e.1[0] = p;
            }
            if d.dot(p) > d.dot(e.1[1]) {
                e.1[1] = p;
            }
        }
    }
    let mut out: Vec<IntersectionSegment> = pairs
        .into_iter()
        .map(|((a, b), (_, world))| IntersectionSegment {
            polygons: [a, b],
            world,
        })
        .collect();
    out.sort_by_key(|s| s.polygons);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orient3d_sign_convention() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        // a, b, c counter-clockwise seen from +z: a point above is negative.
        assert!(orient3d(a, b, c, DVec3::Z) < 0.0);
        assert!(orient3d(a, b, c, -DVec3::Z) > 0.0);
        assert_eq!(orient3d(a, b, c, DVec3::new(3.0, 7.0, 0.0)), 0.0);
    }

    #[test]
    fn crossing_triangles_and_touching_ones() {
        // A triangle in z = 0 and one in x = 0.25 through it: the segment on x = 0.25,
        // z = 0, y from 0 to 0.75 (the first triangle's hypotenuse x + y = 1).
        let t1 = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let t2 = [
            DVec3::new(0.25, -1.0, -1.0),
            DVec3::new(0.25, 3.0, -1.0),
            DVec3::new(0.25, -1.0, 3.0),
        ];
        let [p, q] = triangle_intersection(&t1, &t2).unwrap();
        let (lo, hi) = if p.y < q.y { (p, q) } else { (q, p) };
        assert!(lo.distance(DVec3::new(0.25, 0.0, 0.0)) < 1e-15, "{lo}");
        assert!(hi.distance(DVec3::new(0.25, 0.75, 0.0)) < 1e-15, "{hi}");
        // Sharing an edge: nothing; sharing a vertex and touching there only: nothing.
        let t3 = [DVec3::X, DVec3::ZERO, DVec3::new(0.5, -1.0, 1.0)];
        assert!(triangle_intersection(&t1, &t3).is_none());
        let t4 = [
            DVec3::X,
            DVec3::new(2.0, 0.0, 1.0),
            DVec3::new(2.0, 1.0, 1.0),
        ];
        assert!(triangle_intersection(&t1, &t4).is_none());
        // Sharing a vertex and crossing: from the vertex into both.
        let t5 = [
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, -1.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        let [p, q] = triangle_intersection(&t1, &t5).unwrap();
        let (lo, hi) = if p.x < q.x { (p, q) } else { (q, p) };
        assert_eq!(lo, DVec3::ZERO);
        assert!(hi.distance(DVec3::new(0.5, 0.5, 0.0)) < 1e-15, "{hi}");
        // Coplanar: nothing.
        let t6 = [
            DVec3::new(0.1, 0.1, 0.0),
            DVec3::new(2.0, 0.1, 0.0),
            DVec3::new(0.1, 2.0, 0.0),
        ];
        assert!(triangle_intersection(&t1, &t6).is_none());
    }
}
