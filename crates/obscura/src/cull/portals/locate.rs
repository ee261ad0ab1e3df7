//! The viewer's cell in O(log n): a BSP tree over the cells' boundary planes (seed 000
//! "από-Περιοχή (2)": "a balanced BSP tree locates the cell holding a point in
//! O(log2 nc)").
//!
//! Build: at each node, among the boundary planes of the node's cells, the plane that
//! splits the fewest cells and best balances the two sides (score `4 * split + |front -
//! back|`, as in Fuchs, Kedem and Naylor's tree and its later balanced variants) divides
//! the cells by their vertices ([`CellShape`]); a cell on both sides goes to both. A
//! leaf holds the few cells no plane separates. Query: descend by the side of the point
//! (both sides within a tolerance of the plane), then test the leaf's cells exactly as
//! the linear scan does, and keep the lowest index: the answers are the scan's, which
//! the tests check on thousands of random points. Cells without planes, open or empty
//! cells, are tested on every query (a list beside the tree).

use glam::DVec3;

use super::model::CellGraph;
use super::validate::CellShape;
use crate::geom::Plane;

/// How far (in normalized plane distance) a cell vertex may be on the wrong side of a
/// splitting plane and still count as on one side only.
const CLASSIFY_EPS: f64 = 1e-7;
/// How close to a splitting plane a query point descends both sides.
const QUERY_EPS: f64 = 1e-6;

#[derive(Clone, Debug)]
enum Node {
    Split { plane: Plane, front: u32, back: u32 },
    Leaf { cells: Vec<u32> },
}

/// The BSP tree over a [`CellGraph`]'s cell boundaries (built by [`CellIndex::new`];
/// [`CellGraph::locate`] builds one on first use and keeps it).
#[derive(Clone, Debug, Default)]
pub struct CellIndex {
    nodes: Vec<Node>,
    /// Cells tested on every query: no planes, open or empty.
    always: Vec<u32>,
    /// Number of cells of the graph it was built for.
    cell_count: usize,
    /// The largest coordinate of a cell vertex: tolerances scale with it.
    scale: f64,
}

/// Whether `p` is in cell `c`: the linear scan's test, exactly.
pub(crate) fn in_cell(graph: &CellGraph, c: usize, p: DVec3) -> bool {
    let planes = &graph.cells[c].planes;
    !planes.is_empty() && planes.iter().all(|pl| pl.signed_distance(p) <= 1e-9)
}

impl CellIndex {
    /// Builds the tree over the cells of `graph`.
    #[must_use]
    pub fn new(graph: &CellGraph) -> CellIndex {
        let mut always = Vec::new();
        let mut items: Vec<(u32, Vec<DVec3>)> = Vec::new();
        for (i, cell) in graph.cells.iter().enumerate() {
            let shape = CellShape::new(&cell.planes);
            if cell.planes.is_empty() || shape.open || shape.vertices.len() < 4 {
                if !cell.planes.is_empty() {
                    always.push(i as u32);
                }
                continue;
            }
            items.push((i as u32, shape.vertices));
        }
        // Candidate planes: every boundary plane, normalized, duplicates (either
        // orientation) merged.
        let mut planes: Vec<Plane> = Vec::new();
        for (i, _) in &items {
            for pl in &graph.cells[*i as usize].planes {
                let pl = pl.normalized();
                let dup = planes.iter().any(|q| {
                    ((q.normal - pl.normal).length() < 1e-9 && (q.d - pl.d).abs() < 1e-9)
                        || ((q.normal + pl.normal).length() < 1e-9 && (q.d + pl.d).abs() < 1e-9)
                });
                if !dup {
                    planes.push(pl);
                }
            }
        }
        let mut index = CellIndex {
            nodes: Vec::new(),
            always,
            cell_count: graph.cells.len(),
            scale: items
                .iter()
                .flat_map(|(_, v)| v.iter().map(|p| p.abs().max_element()))
                .fold(0.0, f64::max),
        };
        let all: Vec<usize> = (0..items.len()).collect();
        index.build(&items, &planes, all, 0);
        index
    }

    fn build(
        &mut self,
        items: &[(u32, Vec<DVec3>)],
        planes: &[Plane],
        set: Vec<usize>,
        depth: usize,
    ) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(Node::Leaf { cells: Vec::new() });
        let leaf = |set: &[usize]| Node::Leaf {
            cells: set.iter().map(|&k| items[k].0).collect(),
        };
        if set.len() <= 1 || depth > 64 {
            self.nodes[id as usize] = leaf(&set);
            return id;
        }
        // Choose the plane.
        let mut best: Option<(i64, usize)> = None;
        for (pi, pl) in planes.iter().enumerate() {
            let (mut f, mut b, mut s) = (0i64, 0i64, 0i64);
            for &k in &set {
                let (front, back) = sides(pl, &items[k].1, self.scale);
                match (front, back) {
                    (true, true) => s += 1,
                    (true, false) => f += 1,
                    _ => b += 1,
                }
            }
            if f + s == 0 || b + s == 0 || (f == 0 && b == 0) {
                continue; // separates nothing
            }
            let score = 4 * s + (f - b).abs();
            if best.is_none_or(|(bs, _)| score < bs) {
                best = Some((score, pi));
            }
        }
        let Some((_, pi)) = best else {
            self.nodes[id as usize] = leaf(&set);
            return id;
        };
        let pl = planes[pi];
        let (mut fs, mut bs) = (Vec::new(), Vec::new());
        for &k in &set {
            let (front, back) = sides(&pl, &items[k].1, self.scale);
            if front {
                fs.push(k);
            }
            if back {
                bs.push(k);
            }
        }
        if fs.len() == set.len() && bs.len() == set.len() {
            self.nodes[id as usize] = leaf(&set);
            return id;
        }
        let front = self.build(items, planes, fs, depth + 1);
        let back = self.build(items, planes, bs, depth + 1);
        self.nodes[id as usize] = Node::Split {
            plane: pl,
            front,
            back,
        };
        id
    }

    /// The depth of the tree (1 for a single leaf).
    #[must_use]
    pub fn depth(&self) -> usize {
        fn d(nodes: &[Node], i: u32) -> usize {
            match &nodes[i as usize] {
                Node::Leaf { .. } => 1,
                Node::Split { front, back, .. } => 1 + d(nodes, *front).max(d(nodes, *back)),
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            d(&self.nodes, 0)
        }
    }

    /// The number of cells the tree was built for.
    #[must_use]
    pub fn cell_count(&self) -> usize {
        self.cell_count
    }

    /// The cell of `graph` (the graph the index was built for) holding `p`: the same
    /// answer as a linear scan (the lowest-index cell whose planes all have `p` within
    /// 1e-9 behind), `None` outside every cell. A graph with another number of cells
    /// than the index was built for is scanned linearly.
    #[must_use]
    pub fn locate(&self, graph: &CellGraph, p: DVec3) -> Option<u32> {
        if graph.cells.len() != self.cell_count {
            return (0..graph.cells.len())
                .find(|&c| in_cell(graph, c, p))
                .map(|c| c as u32);
        }
        let mut best: Option<u32> = self
            .always
            .iter()
            .copied()
            .filter(|&c| in_cell(graph, c as usize, p))
            .min();
        if !self.nodes.is_empty() {
            self.descend(graph, 0, p, &mut best);
        }
        best
    }

    fn descend(&self, graph: &CellGraph, node: u32, p: DVec3, best: &mut Option<u32>) {
        let mut node = node;
        loop {
            match &self.nodes[node as usize] {
                Node::Leaf { cells } => {
                    for &c in cells {
                        if best.is_none_or(|b| c < b) && in_cell(graph, c as usize, p) {
                            *best = Some(c);
                        }
                    }
                    return;
                }
                Node::Split { plane, front, back } => {
                    let d = plane.evaluate(p);
                    if d.is_nan() {
                        return;
                    }
                    let eps = QUERY_EPS * (1.0 + self.scale);
                    if d > eps {
                        node = *front;
                    } else if d < -eps {
                        node = *back;
                    } else {
                        self.descend(graph, *front, p, best);
                        node = *back;
                    }
                }
            }
        }
    }
}

/// Whether a cell's vertices reach the front and the back of a plane.
fn sides(pl: &Plane, vertices: &[DVec3], scale: f64) -> (bool, bool) {
    let (mut front, mut back) = (false, false);
    let eps = CLASSIFY_EPS * (1.0 + scale);
    for &v in vertices {
        let d = pl.evaluate(v);
        front |= d > eps;
        back |= d < -eps;
    }
    // A cell touching the plane from one side is on that side only; one lying wholly
    // on it (flat: never built, empty cells are in `always`) would be on neither: keep
    // it on both.
    if !front && !back {
        (true, true)
    } else {
        (front, back)
    }
}
