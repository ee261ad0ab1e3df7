//! The adjacency graph of cells and portals, and stab trees: from a source cell, the
//! portal sequences a line of sight can pass (seed 000 "από-Περιοχή (2)").
//!
//! A line of sight from cell `S` into cell `C` crosses a sequence of portals `P1 .. Pk`
//! in order along the line (the cells are convex, so the line meets each at most once).
//! The stab tree of `S` holds every such sequence that may be stabbed. Deciding exactly
//! whether a line stabs `k` convex polygons in 3D is hard; this module over-estimates,
//! which keeps the PVS conservative (never a visible cell missed):
//!
//! - Any two portals can be stabbed, so every sequence of length 1 and 2 is kept.
//! - For longer sequences the walk keeps a *source* `S` (the first portal, itself
//!   clipped) and a *pass* polygon (the last portal, clipped). A plane through an edge
//!   of one and a vertex of the other that puts `S` on one side and the pass on the
//!   other is a separating plane (Teller's): a line that meets `S`, then the pass, then
//!   the next portal must reach the next portal on the pass's side. The next portal is
//!   clipped to the side each separating plane allows (the anti-penumbra shrink), and
//!   the source to the side the planes between the new portal and the pass allow; the
//!   sequence ends when either becomes empty.
//! - Every clip keeps points within a tolerance of the plane, and a plane is skipped
//!   when `S` and the pass touch where it meets them (a shared corner, where the
//!   argument fails). Skipping a plane or keeping more only enlarges what is kept.
//!
//! A walk that passes its budget of sequences stops and marks every cell the graph can
//! reach from the source (marked [`StabTree::complete`] `false`): over-estimated, never
//! wrong.
//!
//! Paper: S. Teller and C. Séquin, "Visibility preprocessing for interactive
//! walkthroughs", SIGGRAPH 1991 (stab trees, separating and supporting planes).

use glam::DVec3;

use super::model::CellGraph;
use crate::Result;
use crate::work::Deadline;

/// The adjacency graph: per cell, its portals and the cells across them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Adjacency {
    /// Per cell, `(portal, cell across)` in portal order.
    pub neighbours: Vec<Vec<(u32, u32)>>,
}

impl Adjacency {
    /// The adjacency of a cell graph. Portals naming a cell that does not exist, or
    /// joining a cell to itself, are left out (the graph's validation reports them).
    #[must_use]
    pub fn new(graph: &CellGraph) -> Adjacency {
        let n = graph.cells.len();
        let mut neighbours = vec![Vec::new(); n];
        for (i, p) in graph.portals.iter().enumerate() {
            let [a, b] = p.cells;
            if a == b || a as usize >= n || b as usize >= n || p.polygon.len() < 3 {
                continue;
            }
            neighbours[a as usize].push((i as u32, b));
            neighbours[b as usize].push((i as u32, a));
        }
        Adjacency { neighbours }
    }

    /// The cells reachable from `from` through portals (itself included), as flags.
    #[must_use]
    pub fn reachable(&self, from: u32) -> Vec<bool> {
        let mut seen = vec![false; self.neighbours.len()];
        let mut stack = vec![from];
        seen[from as usize] = true;
        while let Some(c) = stack.pop() {
            for &(_, o) in &self.neighbours[c as usize] {
                if !seen[o as usize] {
                    seen[o as usize] = true;
                    stack.push(o);
                }
            }
        }
        seen
    }
}

/// A node of a stab tree: a cell reached through a portal sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct StabNode {
    /// The cell reached.
    pub cell: u32,
    /// The portal crossed last (`None` for the root, the source cell).
    pub portal: Option<u32>,
    /// The parent node (`None` for the root).
    pub parent: Option<u32>,
    /// The part of the portal lines of sight from the source may cross (the portal
    /// clipped by the separating planes; empty for the root).
    pub polygon: Vec<DVec3>,
}

/// The stab tree of one source cell.
#[derive(Clone, Debug, PartialEq)]
pub struct StabTree {
    /// The source cell.
    pub source: u32,
    /// The nodes, the root (the source) first, each after its parent.
    pub nodes: Vec<StabNode>,
    /// `false` when the walk passed its budget: every cell reachable from the source
    /// is then taken as visible ([`Self::visible`]).
    pub complete: bool,
    /// The portal sequences tested.
    pub sequences: u64,
}

impl StabTree {
    /// Per cell of the graph: visible from the source (reached by the tree, or, for an
    /// incomplete tree, reachable at all).
    #[must_use]
    pub fn visible(&self, adjacency: &Adjacency) -> Vec<bool> {
        if !self.complete {
            return adjacency.reachable(self.source);
        }
        let mut v = vec![false; adjacency.neighbours.len()];
        for n in &self.nodes {
            v[n.cell as usize] = true;
        }
        v
    }
}

/// The tolerance of a graph: lengths below it count as zero (`1e-9` of its largest
/// coordinate, at least `1e-12`).
pub(crate) fn tolerance(graph: &CellGraph) -> f64 {
    let scale = graph
        .portals
        .iter()
        .flat_map(|p| p.polygon.iter())
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    (scale * 1e-9).max(1e-12)
}

/// The stab tree of `source`: every portal sequence from it that a line of sight may
/// pass (over-estimated, see the [module documentation](self)), at most
/// `max_sequences` sequences tested.
///
/// # Errors
/// [`crate::Error::TimeLimit`] or [`crate::Error::Stopped`] from the deadline; an
/// invalid option for a source that is not a cell.
pub fn stab_tree(
    graph: &CellGraph,
    adjacency: &Adjacency,
    source: u32,
    max_sequences: u64,
    deadline: &Deadline,
) -> Result<StabTree> {
    if source as usize >= graph.cells.len() {
        return Err(crate::Error::option(
            "source",
            format!("cell {source} does not exist ({} cells)", graph.cells.len()),
        ));
    }
    deadline.check("PVS precomputation (stab trees)")?;
    let mut w = Walk {
        graph,
        adjacency,
        eps: tolerance(graph),
        on_path: vec![false; graph.cells.len()],
        tree: StabTree {
            source,
            nodes: vec![StabNode {
                cell: source,
                portal: None,
                parent: None,
                polygon: Vec::new(),
            }],
            complete: true,
            sequences: 0,
        },
        max_sequences,
        deadline,
    };
    w.on_path[source as usize] = true;
    for &(p, next) in &adjacency.neighbours[source as usize] {
        if !w.step()? {
            break;
        }
        let poly = graph.portals[p as usize].polygon.clone();
        let node = w.push(next, p, 0, poly.clone());
        w.on_path[next as usize] = true;
        let go_on = w.descend(&poly, &poly, next, node)?;
        w.on_path[next as usize] = false;
        if !go_on {
            break;
        }
    }
    Ok(w.tree)
}

struct Walk<'a> {
    graph: &'a CellGraph,
    adjacency: &'a Adjacency,
    eps: f64,
    on_path: Vec<bool>,
    tree: StabTree,
    max_sequences: u64,
    deadline: &'a Deadline,
}

impl Walk<'_> {
    /// Counts a sequence; `false` once the budget is spent (the tree is then marked
    /// incomplete).
    fn step(&mut self) -> Result<bool> {
        self.tree.sequences += 1;
        if self.tree.sequences.is_multiple_of(256) {
            self.deadline.check("PVS precomputation (stab trees)")?;
        }
        if self.tree.sequences > self.max_sequences {
            self.tree.complete = false;
            return Ok(false);
        }
        Ok(true)
    }

    fn push(&mut self, cell: u32, portal: u32, parent: u32, polygon: Vec<DVec3>) -> u32 {
        self.tree.nodes.push(StabNode {
            cell,
            portal: Some(portal),
            parent: Some(parent),
            polygon,
        });
        (self.tree.nodes.len() - 1) as u32
    }

    /// Extends the sequences whose source part is `source` and last (clipped) portal
    /// `pass`, which led into `cell` (node `node`). `false` when the budget ran out.
    fn descend(&mut self, source: &[DVec3], pass: &[DVec3], cell: u32, node: u32) -> Result<bool> {
        let neighbours = &self.adjacency.neighbours[cell as usize];
        for &(p, next) in neighbours {
            if self.on_path[next as usize] {
                continue;
            }
            if !self.step()? {
                return Ok(false);
            }
            let target = &self.graph.portals[p as usize].polygon;
            let Some(target) = clip_by_separating(source, pass, target, self.eps) else {
                continue;
            };
            let Some(new_source) = clip_by_separating(&target, pass, source, self.eps) else {
                continue;
            };
            let child = self.push(next, p, node, target.clone());
            self.on_path[next as usize] = true;
            let go_on = self.descend(&new_source, &target, next, child)?;
            self.on_path[next as usize] = false;
            if !go_on {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// Clips `target` to the side of every separating plane of `a` and `b` (through an
/// edge of one and a vertex of the other, `a` on one side and `b` on the other) on
/// which `b` lies: what a line meeting `a`, then `b`, then `target` can reach. `None`
/// when nothing is left.
pub(crate) fn clip_by_separating(
    a: &[DVec3],
    b: &[DVec3],
    target: &[DVec3],
    eps: f64,
) -> Option<Vec<DVec3>> {
    let mut out = target.to_vec();
    for (edges, verts) in [(a, b), (b, a)] {
        let m = edges.len();
        for i in 0..m {
            let (e0, e1) = (edges[i], edges[(i + 1) % m]);
            for &v in verts {
                let n = (e1 - e0).cross(v - e0);
                let len = n.length();
                if !(len > eps * (e1 - e0).length().max(eps)) {
                    continue;
                }
                let n = n / len;
                let d = -n.dot(e0);
                // Orient so that `a` is behind (<= 0) and `b` in front (>= 0).
                let (n, d) = match separates(a, b, n, d, eps) {
                    Some(true) => (n, d),
                    Some(false) => (-n, -d),
                    None => continue,
                };
                if touch_on_plane(a, b, n, d, eps) {
                    continue;
                }
                // Keep the target where n·p + d >= -eps: clip by (-n, -d) <= eps.
                out = clip_polygon(&out, -n, -d, eps);
                if out.len() < 3 {
                    return None;
                }
            }
        }
    }
    Some(out)
}

/// `Some(true)` if `a` lies on the negative side of the plane and `b` on the positive
/// (within `eps`), `Some(false)` for the reverse, `None` if it does not separate them.
fn separates(a: &[DVec3], b: &[DVec3], n: DVec3, d: f64, eps: f64) -> Option<bool> {
    let side = |poly: &[DVec3]| {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &p in poly {
            let s = n.dot(p) + d;
            lo = lo.min(s);
            hi = hi.max(s);
        }
        (lo, hi)
    };
    let (alo, ahi) = side(a);
    let (blo, bhi) = side(b);
    if ahi <= eps && blo >= -eps {
        Some(true)
    } else if alo >= -eps && bhi <= eps {
        Some(false)
    } else {
        None
    }
}

/// Whether `a` and `b` come within `eps` of each other on the plane (where the
/// separating-plane argument fails). The parts of each on the plane are their
/// vertices within `eps` of it; more than two such vertices (a polygon lying in the
/// plane) count as touching.
fn touch_on_plane(a: &[DVec3], b: &[DVec3], n: DVec3, d: f64, eps: f64) -> bool {
    let on = |poly: &[DVec3]| -> Vec<DVec3> {
        poly.iter()
            .copied()
            .filter(|&p| (n.dot(p) + d).abs() <= eps)
            .collect()
    };
    let (oa, ob) = (on(a), on(b));
    if oa.is_empty() || ob.is_empty() {
        return false;
    }
    if oa.len() > 2 || ob.len() > 2 {
        return true;
    }
    let seg = |v: &[DVec3]| (v[0], *v.last().expect("non-empty"));
    let (p0, p1) = seg(&oa);
    let (q0, q1) = seg(&ob);
    segment_distance(p0, p1, q0, q1) <= 4.0 * eps
}

/// The distance between segments `p0 p1` and `q0 q1` (either may be a point).
pub(crate) fn segment_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let (u, v, w) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c) = (u.dot(u), u.dot(v), v.dot(v));
    let (dd, e) = (u.dot(w), v.dot(w));
    let denom = a * c - b * b;
    // Candidate parameters on p, then the matching ones on q, clamped.
    let mut s = if a > 0.0 && denom > 1e-300 {
        ((b * e - c * dd) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = if c > 0.0 { (b * s + e) / c } else { 0.0 };
    if t < 0.0 {
        t = 0.0;
        s = if a > 0.0 {
            (-dd / a).clamp(0.0, 1.0)
        } else {
            0.0
        };
    } else if t > 1.0 {
        t = 1.0;
        s = if a > 0.0 {
            ((b - dd) / a).clamp(0.0, 1.0)
        } else {
            0.0
        };
    }
    ((p0 + u * s) - (q0 + v * t)).length()
}

/// Clips a convex polygon to the half-space `n·p + d <= eps` (Sutherland-Hodgman on
/// one plane). Points within `eps` of the plane count as inside.
pub(crate) fn clip_polygon(poly: &[DVec3], n: DVec3, d: f64, eps: f64) -> Vec<DVec3> {
    let m = poly.len();
    let dist: Vec<f64> = poly.iter().map(|&p| n.dot(p) + d - eps).collect();
    if dist.iter().all(|&s| s <= 0.0) {
        return poly.to_vec();
    }
    let mut out = Vec::with_capacity(m + 1);
    for i in 0..m {
        let j = (i + 1) % m;
        let (p, q, dp, dq) = (poly[i], poly[j], dist[i], dist[j]);
        if dp <= 0.0 {
            out.push(p);
        }
        if (dp <= 0.0) != (dq <= 0.0) {
            let t = dp / (dp - dq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_distance_cases() {
        let d = segment_distance(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 1.0, 0.0),
            DVec3::new(0.5, 2.0, 0.0),
        );
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, -1.0, 1.0),
            DVec3::new(0.5, 1.0, 1.0),
        );
        assert!((d - 1.0).abs() < 1e-12);
        let d = segment_distance(DVec3::ZERO, DVec3::ZERO, DVec3::Y, DVec3::Y);
        assert!((d - 1.0).abs() < 1e-12);
    }

    #[test]
    fn three_staggered_doors_cannot_be_stabbed() {
        // Doors in parallel walls x = 0, 4, 8: low, high, low (z ranges); full height.
        let door = |x: f64, z0: f64, z1: f64| {
            vec![
                DVec3::new(x, 0.0, z0),
                DVec3::new(x, 0.0, z1),
                DVec3::new(x, 3.0, z1),
                DVec3::new(x, 3.0, z0),
            ]
        };
        let (a, b) = (door(0.0, 0.0, 1.5), door(4.0, 2.5, 4.0));
        assert!(clip_by_separating(&a, &b, &door(8.0, 0.0, 1.5), 1e-9).is_none());
        // A high third door is reachable, and clipped to the part lines can reach.
        let c = clip_by_separating(&a, &b, &door(8.0, 2.5, 4.0), 1e-9).unwrap();
        let zmin = c.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        assert!(zmin >= 3.5 - 1e-6, "{c:?}");
    }
}
