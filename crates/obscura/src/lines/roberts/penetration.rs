//! Penetration (seed 004, stage II step 4): the points where an edge of one body
//! enters or leaves another (the corners on `a = 0` of the edge test) and the lines
//! joining them, the intersection lines of the two surfaces.
//!
//! The seed joins every pair of penetration points of two bodies and tests the joins
//! against both bodies. Here two points are joined only when they share a plane of
//! each body: every piece of the intersection line lies on one face of each body, so
//! these joins are exactly its pieces, and no join crosses either body's inside.

use glam::DVec3;

use super::body::{Body, Space};
use super::edge::{Row, edge_scale, inside_interval};

/// A piece of the intersection line of two bodies.
#[derive(Clone, Copy, Debug)]
pub(super) struct Join {
    /// World ends.
    pub world: [DVec3; 2],
    /// The plane of the first body and of the second it lies on.
    pub planes: [usize; 2],
}

/// A penetration point: where it is, and the planes of each body it lies on (two of
/// the body whose edge pierces, one of the pierced body).
#[derive(Clone, Copy, Debug)]
struct Point {
    world: DVec3,
    planes: [[Option<usize>; 2]; 2],
}

/// The penetration points of the edges of `a` through `b` (`first`: whether `a` is
/// the pair's first body), appended to `out`.
fn pierce(space: &Space, a: &Body, b: &Body, first: bool, out: &mut Vec<Point>) {
    let g = glam::DVec4::Z;
    let mut rows: Vec<Row> = Vec::with_capacity(b.columns.len());
    for e in &a.edges {
        let s = space.point(e.world[0]);
        let d = space.point(e.world[1]) - s;
        rows.clear();
        rows.extend(b.columns.iter().map(|v| Row {
            p: s.dot(*v),
            q: d.dot(*v),
            w: g.dot(*v),
        }));
        let Some((t_in, j_in, t_out, j_out)) = inside_interval(&rows, edge_scale(s, d)) else {
            continue;
        };
        for (t, j) in [(t_in, j_in), (t_out, j_out)] {
            let Some(j) = j else { continue };
            let own = [Some(e.planes[0]), Some(e.planes[1])];
            let other = [Some(j), None];
            out.push(Point {
                world: e.world[0] + (e.world[1] - e.world[0]) * t,
                planes: if first { [own, other] } else { [other, own] },
            });
        }
    }
}

/// The intersection line of bodies `a` and `b` as pieces, each on one plane of each.
pub(super) fn joins(space: &Space, a: &Body, b: &Body) -> (usize, Vec<Join>) {
    let mut points = Vec::new();
    pierce(space, a, b, true, &mut points);
    pierce(space, b, a, false, &mut points);
    let mut buckets: std::collections::BTreeMap<(usize, usize), Vec<DVec3>> =
        std::collections::BTreeMap::new();
    for p in &points {
        for pa in p.planes[0].iter().flatten() {
            for pb in p.planes[1].iter().flatten() {
                buckets.entry((*pa, *pb)).or_default().push(p.world);
            }
        }
    }
    let size = a.world.union(b.world).extent().max_element();
    let mut out = Vec::new();
    for ((pa, pb), pts) in buckets {
        // The two points farthest apart (the others, if any, repeat them: a point where
        // an edge of one body meets an edge of the other is found from both).
        let mut best = (0.0, 0, 0);
        for i in 0..pts.len() {
            for j in i + 1..pts.len() {
                let d = pts[i].distance_squared(pts[j]);
                if d > best.0 {
                    best = (d, i, j);
                }
            }
        }
        if best.0.sqrt() > 1e-9 * size {
            out.push(Join {
                world: [pts[best.1], pts[best.2]],
                planes: [pa, pb],
            });
        }
    }
    (points.len(), out)
}
