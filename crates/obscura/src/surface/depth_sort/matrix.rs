//! Depth sort by a covering matrix and a topological order (seed 003, "Eliminarea
//! suprafețelor acoperite - Depth-Sort").
//!
//! `M[i][j] = 1` when face `i` covers face `j` (their projections share a pixel and
//! `i` is in front); `A[i]`, the covering coefficient, counts the unpainted faces `i`
//! covers. Repeatedly a face with `A[i] = 0` is painted, `A[i]` set to -1, and `A[j]`
//! decremented for every face `j` covering it. The matrix is sparse, kept as
//! adjacency lists in both directions. Pairs whose planes cross each other (the
//! seed's case IV, "the faces intersect") are split first; when no face has
//! `A[i] = 0` the covering relation has a cycle, found by walking it, and a face of
//! the cycle is split by the plane of another.
//!
//! Papers: Newell, Newell and Sancha, "A solution to the hidden surface problem", ACM
//! 1972 (the priority order); Kahn, "Topological sorting of large networks", CACM
//! 5(11), 1962 (the order from the counts).

use std::cmp::Ordering;

use super::Counters;
use super::work::{TileGrid, WorkSet};

/// The relation of a pair of faces.
enum Relation {
    None,
    /// The first covers the second.
    Covers,
    /// The second covers the first.
    CoveredBy,
    /// They interpenetrate over a shared pixel: one must be split.
    Intersect,
}

struct Graph<'w> {
    ws: &'w mut WorkSet,
    alive: Vec<bool>,
    painted: Vec<bool>,
    /// Whether the face is in the graph (its relations are counted).
    linked: Vec<bool>,
    /// The covering coefficient A: unpainted live faces this face covers.
    covering: Vec<i64>,
    covers: Vec<Vec<u32>>,
    covered_by: Vec<Vec<u32>>,
    grid: TileGrid,
    ready: Vec<u32>,
    split_budget: u64,
    /// See [`super::comparison_budget`].
    comparison_budget: u64,
    candidates: Vec<u32>,
    /// Alive, unpainted faces.
    live: usize,
}

impl Graph<'_> {
    fn push_node(&mut self) {
        self.alive.push(true);
        self.painted.push(false);
        self.linked.push(false);
        self.covering.push(0);
        self.covers.push(Vec::new());
        self.covered_by.push(Vec::new());
        self.live += 1;
    }

    fn relation(&self, i: u32, j: u32, c: &mut Counters) -> Relation {
        c.comparisons += 1;
        let ws = &*self.ws;
        let (pi, pj) = (&ws.polys[i as usize], &ws.polys[j as usize]);
        if pi.face == pj.face {
            c.same_face += 1;
            return Relation::None;
        }
        if ws.x_disjoint(i, j) {
            c.test1 += 1;
            return Relation::None;
        }
        if ws.y_disjoint(i, j) {
            c.test2 += 1;
            return Relation::None;
        }
        let s = ws.sides(i, j);
        let (i_first, j_first) = if s.coplanar() {
            c.coplanar += 1;
            // The lower id must be painted last: it covers the other.
            (pi.face > pj.face, pi.face < pj.face)
        } else {
            (
                s.p_behind_q_plane() || s.q_before_p_plane(),
                s.q_behind_p_plane() || s.p_before_q_plane(),
            )
        };
        if i_first && j_first {
            // Each on the far side of the other's plane: their projections cannot
            // overlap (faces of a convex solid seen from outside).
            c.test3 += 1;
            return Relation::None;
        }
        if !ws.projections_overlap(i, j) {
            c.test5 += 1;
            return Relation::None;
        }
        match (i_first, j_first) {
            (true, false) => Relation::CoveredBy,
            (false, true) => Relation::Covers,
            // Both cross each other's planes: compare depths where they overlap.
            _ => match ws.nearer_over_overlap(i, j) {
                Some(Ordering::Greater) => {
                    c.overlap_depth += 1;
                    Relation::Covers
                }
                Some(_) => {
                    c.overlap_depth += 1;
                    Relation::CoveredBy
                }
                None => Relation::Intersect,
            },
        }
    }

    /// Removes a face (split) from the graph: the faces covering it cover one less.
    fn kill(&mut self, i: u32) {
        let k = i as usize;
        self.alive[k] = false;
        self.live -= 1;
        if !self.linked[k] {
            return;
        }
        for z in std::mem::take(&mut self.covered_by[k]) {
            let zk = z as usize;
            if self.alive[zk] && !self.painted[zk] {
                self.covering[zk] -= 1;
                if self.covering[zk] == 0 {
                    self.ready.push(z);
                }
            }
        }
    }

    /// Adds face `i` to the graph: its relations with every linked, unpainted face
    /// overlapping it. Interpenetrating pairs are split; the pieces go to `pending`.
    /// Returns false if `i` itself was split.
    fn link(&mut self, i: u32, pending: &mut Vec<u32>, c: &mut Counters) -> bool {
        let rect = self.ws.polys[i as usize].rect;
        let mut cands = std::mem::take(&mut self.candidates);
        {
            let (alive, painted) = (&self.alive, &self.painted);
            self.grid.query(
                &rect,
                |j| alive[j as usize] && !painted[j as usize],
                |_| false,
                &mut cands,
            );
        }
        let mut edges: Vec<(u32, u32)> = Vec::new();
        let mut self_split = false;
        if c.comparisons > self.comparison_budget {
            // Too much work: no more relations; what is left is painted depth-tested.
            self.ws.fallback = true;
            c.unsorted += 1;
            cands.clear();
        }
        if self.ws.out_of_time() {
            cands.clear();
        }
        for &j in &cands {
            let jk = j as usize;
            if j == i || !self.alive[jk] || self.painted[jk] || !self.linked[jk] {
                continue;
            }
            if c.comparisons.is_multiple_of(1 << 14) && self.ws.out_of_time() {
                break;
            }
            match self.relation(i, j, c) {
                Relation::None => {}
                Relation::Covers => edges.push((i, j)),
                Relation::CoveredBy => edges.push((j, i)),
                Relation::Intersect => {
                    if self.split_budget == 0 {
                        c.unresolved += 1;
                        self.ws.fallback = true;
                        continue;
                    }
                    let s = self.ws.sides(i, j);
                    if s.p_spans_q_plane() {
                        if let Some(pieces) = self.split(i, j, c) {
                            pending.extend(pieces);
                            self_split = true;
                            break;
                        }
                    } else if s.q_spans_p_plane()
                        && let Some(pieces) = self.split(j, i, c)
                    {
                        pending.extend(pieces);
                        continue;
                    }
                    c.unresolved += 1;
                    self.ws.fallback = true;
                }
            }
        }
        self.candidates = cands;
        if self_split {
            return false;
        }
        for (a, b) in edges {
            if !self.alive[a as usize] || !self.alive[b as usize] {
                continue;
            }
            c.relations += 1;
            self.covering[a as usize] += 1;
            self.covers[a as usize].push(b);
            self.covered_by[b as usize].push(a);
        }
        self.linked[i as usize] = true;
        let rect = self.ws.polys[i as usize].rect;
        self.grid.insert(i, &rect, |_| 0.0);
        if self.covering[i as usize] == 0 {
            self.ready.push(i);
        }
        true
    }

    fn split(&mut self, i: u32, by: u32, c: &mut Counters) -> Option<[u32; 2]> {
        let pieces = self.ws.split(i, by)?;
        c.splits += 1;
        self.split_budget = self.split_budget.saturating_sub(1);
        self.kill(i);
        for _ in pieces {
            self.push_node();
        }
        Some(pieces)
    }

    /// Links faces until none is pending (pieces of splits included).
    fn link_all(&mut self, mut pending: Vec<u32>, c: &mut Counters) {
        while let Some(i) = pending.pop() {
            if self.ws.over_budget.is_some() {
                return;
            }
            if self.alive[i as usize] {
                self.link(i, &mut pending, c);
            }
        }
    }

    /// A cycle of the covering relation among unpainted faces, found by walking
    /// from `start` along "covers" edges (every unpainted face covers another, so the
    /// walk must come back to a face it has seen).
    fn find_cycle(&self, start: u32) -> Vec<u32> {
        let mut path = vec![start];
        let mut on_path = std::collections::HashMap::new();
        on_path.insert(start, 0usize);
        let mut x = start;
        loop {
            let next = self.covers[x as usize]
                .iter()
                .copied()
                .find(|&y| self.alive[y as usize] && !self.painted[y as usize]);
            let Some(y) = next else {
                return Vec::new();
            };
            if let Some(&at) = on_path.get(&y) {
                return path.split_off(at);
            }
            on_path.insert(y, path.len());
            path.push(y);
            x = y;
        }
    }
}

/// Sorts the work set by the covering matrix and calls `paint` on every polygon
/// (view polygons and pieces) in a topological order of "is covered by".
pub(super) fn sort(
    ws: &mut WorkSet,
    counters: &mut Counters,
    progress: &mut dyn FnMut(f64),
    paint: &mut dyn FnMut(&WorkSet, u32),
) {
    let n = ws.polys.len();
    let (w, h) = ws.size();
    let grid = TileGrid::for_polygons(w, h, &ws.polys);
    let mut g = Graph {
        ws,
        alive: Vec::with_capacity(n),
        painted: Vec::with_capacity(n),
        linked: Vec::with_capacity(n),
        covering: Vec::with_capacity(n),
        covers: Vec::with_capacity(n),
        covered_by: Vec::with_capacity(n),
        grid,
        ready: Vec::new(),
        split_budget: super::split_budget(n),
        comparison_budget: super::comparison_budget(n),
        candidates: Vec::new(),
        live: 0,
    };
    for _ in 0..n {
        g.push_node();
    }
    // Link in ascending order (a stack: push in reverse).
    g.link_all((0..n as u32).rev().collect(), counters);
    let mut scan = 0usize;
    let mut done = 0usize;
    while g.live > 0 {
        if g.ws.out_of_time() {
            break;
        }
        let next = loop {
            match g.ready.pop() {
                Some(i) => {
                    let k = i as usize;
                    if g.alive[k] && !g.painted[k] && g.covering[k] == 0 {
                        break Some(i);
                    }
                }
                None => break None,
            }
        };
        if let Some(i) = next {
            let k = i as usize;
            g.painted[k] = true;
            g.covering[k] = -1;
            g.live -= 1;
            paint(g.ws, i);
            done += 1;
            if done.is_multiple_of(4096) {
                progress(done as f64 / g.alive.len().max(1) as f64);
            }
            for z in std::mem::take(&mut g.covered_by[k]) {
                let zk = z as usize;
                if g.alive[zk] && !g.painted[zk] {
                    g.covering[zk] -= 1;
                    if g.covering[zk] == 0 {
                        g.ready.push(z);
                    }
                }
            }
            continue;
        }
        // No face with A = 0: the relation has a cycle.
        while scan < g.alive.len() && (!g.alive[scan] || g.painted[scan]) {
            scan += 1;
        }
        if scan >= g.alive.len() {
            break;
        }
        let start = scan as u32;
        let cycle = g.find_cycle(start);
        counters.cycles += 1;
        let mut broken = false;
        if g.split_budget > 0 {
            'pairs: for (ai, &a) in cycle.iter().enumerate() {
                // Try the next face of the cycle first, then the others.
                for d in 1..cycle.len() {
                    let b = cycle[(ai + d) % cycle.len()];
                    if g.ws.polys[a as usize].face != g.ws.polys[b as usize].face
                        && g.ws.sides(a, b).p_spans_q_plane()
                        && let Some(pieces) = g.split(a, b, counters)
                    {
                        g.link_all(pieces.to_vec(), counters);
                        broken = true;
                        break 'pairs;
                    }
                }
            }
        }
        if broken {
            continue;
        }
        // No split possible (rounding, or the budget is spent): paint a face of the
        // cycle anyway.
        counters.unresolved += 1;
        g.ws.fallback = true;
        let i = cycle.first().copied().unwrap_or(start);
        g.covering[i as usize] = 0;
        g.ready.push(i);
    }
}
