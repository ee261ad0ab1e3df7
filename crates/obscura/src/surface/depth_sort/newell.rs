//! The list-priority algorithm of Newell, Newell and Sancha with the five tests.
//!
//! The list is kept as a max-heap on the farthest depth (the seed's sort) with a
//! stack on top of it holding the polygons moved to the head. The head `P` is painted
//! when no other unpainted polygon `Q` whose depth extent reaches behind `P`'s
//! nearest point can be hidden by `P`; otherwise the tests are swapped, and if `Q`
//! may go first it is moved to the head and marked. A marked polygon that would have
//! to move again closes a cycle: the stack from the head down to it is the cycle, and
//! one of its polygons is split by the plane of another. After a split the stack
//! goes back to the heap and the marks are cleared.
//!
//! Paper: Newell, Newell and Sancha, "A solution to the hidden surface problem",
//! Proceedings of the ACM Annual Conference, 1972.

use std::cmp::{Ordering, Reverse};
use std::collections::{BinaryHeap, HashMap};

use super::Counters;
use super::work::{Sides, TileGrid, WorkSet};

#[derive(Clone, Copy, PartialEq, Eq)]
enum State {
    InHeap,
    InStack,
    Painted,
    Dead,
}

/// A heap entry: farthest depth first.
#[derive(Clone, Copy, PartialEq)]
struct Entry {
    dmax: f64,
    poly: u32,
    generation: u32,
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        self.dmax
            .total_cmp(&other.dmax)
            .then(Reverse(self.poly).cmp(&Reverse(other.poly)))
    }
}

struct Sorter<'w> {
    ws: &'w mut WorkSet,
    state: Vec<State>,
    marked: Vec<bool>,
    generation: Vec<u32>,
    heap: BinaryHeap<Entry>,
    stack: Vec<u32>,
    grid: TileGrid,
    split_budget: u64,
    /// For polygons waiting in the stack: their candidates and where the scan stopped.
    /// Those before it cannot be hidden by the polygon, and stay so until a split
    /// (which clears this).
    resume: HashMap<u32, (Vec<u32>, usize)>,
}

impl Sorter<'_> {
    fn push_heap(&mut self, i: u32) {
        let k = i as usize;
        self.state[k] = State::InHeap;
        self.marked[k] = false;
        self.generation[k] += 1;
        self.heap.push(Entry {
            dmax: self.ws.polys[k].dmax,
            poly: i,
            generation: self.generation[k],
        });
    }

    /// Adds polygon `i` (the next index) to the list and the grid, whose tiles keep
    /// their polygons farthest first.
    fn add(&mut self, i: u32) {
        let k = i as usize;
        if self.state.len() <= k {
            self.state.resize(k + 1, State::Dead);
            self.marked.resize(k + 1, false);
            self.generation.resize(k + 1, 0);
        }
        let rect = self.ws.polys[k].rect;
        let polys = &self.ws.polys;
        self.grid.insert(i, &rect, |j| -polys[j as usize].dmax);
        self.push_heap(i);
    }

    /// The head of the list, taking the farthest polygon of the heap when the stack
    /// is empty.
    fn head(&mut self) -> Option<u32> {
        if let Some(&p) = self.stack.last() {
            return Some(p);
        }
        while let Some(e) = self.heap.pop() {
            let k = e.poly as usize;
            if self.state[k] == State::InHeap && self.generation[k] == e.generation {
                self.state[k] = State::InStack;
                self.stack.push(e.poly);
                return Some(e.poly);
            }
        }
        None
    }

    /// Moves `q` to the head and marks it.
    fn move_to_head(&mut self, q: u32) {
        let k = q as usize;
        if self.state[k] == State::InStack
            && let Some(pos) = self.stack.iter().position(|&s| s == q)
        {
            self.stack.remove(pos);
        }
        self.state[k] = State::InStack;
        self.marked[k] = true;
        self.stack.push(q);
    }

    /// Replaces `i` by its two pieces split by `by`'s plane; every stacked polygon
    /// goes back to the heap unmarked.
    fn split(&mut self, i: u32, by: u32, counters: &mut Counters) -> bool {
        let Some(pieces) = self.ws.split(i, by) else {
            return false;
        };
        counters.splits += 1;
        self.split_budget = self.split_budget.saturating_sub(1);
        self.state[i as usize] = State::Dead;
        self.resume.clear();
        for s in std::mem::take(&mut self.stack) {
            if s != i {
                self.push_heap(s);
            }
        }
        for p in pieces {
            self.add(p);
        }
        true
    }
}

/// Sorts the work set and calls `paint` on every polygon (view polygons and pieces)
/// in back-to-front order.
pub(super) fn sort(
    ws: &mut WorkSet,
    counters: &mut Counters,
    progress: &mut dyn FnMut(f64),
    paint: &mut dyn FnMut(&WorkSet, u32),
) {
    let n = ws.polys.len();
    let (w, h) = ws.size();
    let grid = TileGrid::for_polygons(w, h, &ws.polys);
    let mut s = Sorter {
        ws,
        state: Vec::with_capacity(n),
        marked: Vec::with_capacity(n),
        generation: Vec::with_capacity(n),
        heap: BinaryHeap::with_capacity(n),
        stack: Vec::new(),
        grid,
        split_budget: super::split_budget(n),
        resume: HashMap::new(),
    };
    // Farthest first, so that every tile's list is built by appending.
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| {
        s.ws.polys[b as usize]
            .dmax
            .total_cmp(&s.ws.polys[a as usize].dmax)
    });
    for i in order {
        s.add(i);
    }
    let mut spare = Vec::new();
    let mut painted = 0usize;
    let budget = super::comparison_budget(n);
    while let Some(p) = s.head() {
        if s.ws.out_of_time() {
            return;
        }
        let pk = p as usize;
        if counters.comparisons > budget {
            // Too much work (thousands of long overlapping slivers): the rest is
            // painted in its current order, depth-tested.
            s.ws.fallback = true;
            counters.unsorted += 1;
            s.resume.remove(&p);
            s.stack.pop();
            s.state[pk] = State::Painted;
            paint(s.ws, p);
            continue;
        }
        let (prect, pdmin, pface) = {
            let pp = &s.ws.polys[pk];
            (pp.rect, pp.dmin, pp.face)
        };
        let (candidates, start) = match s.resume.remove(&p) {
            Some(r) => r,
            None => {
                let mut c = std::mem::take(&mut spare);
                let (state, polys) = (&s.state, &s.ws.polys);
                // Test 0 in the grid: a tile's polygons come farthest first, so the
                // scan of a tile ends at the first one entirely nearer than P.
                s.grid.query(
                    &prect,
                    |i| matches!(state[i as usize], State::InHeap | State::InStack),
                    |i| polys[i as usize].dmax < pdmin,
                    &mut c,
                );
                (c, 0)
            }
        };
        // The first polygon P hides, and whether it may go first (swap) or the two
        // interpenetrate (split).
        let mut blocker: Option<(u32, Sides, bool)> = None;
        let mut stopped = candidates.len();
        for (at, &q) in candidates.iter().enumerate().skip(start) {
            if q == p || !matches!(s.state[q as usize], State::InHeap | State::InStack) {
                continue;
            }
            counters.comparisons += 1;
            if counters.comparisons.is_multiple_of(1 << 14) && s.ws.out_of_time() {
                return;
            }
            let qq = &s.ws.polys[q as usize];
            // Test 0: Q is entirely nearer than P (strictly, so that equal-depth
            // coplanar faces still meet the tie rule).
            if qq.dmax < pdmin {
                counters.depth += 1;
                continue;
            }
            if qq.face == pface {
                counters.same_face += 1;
                continue;
            }
            if s.ws.x_disjoint(p, q) {
                counters.test1 += 1;
                continue;
            }
            if s.ws.y_disjoint(p, q) {
                counters.test2 += 1;
                continue;
            }
            let sides = s.ws.sides(p, q);
            if sides.coplanar() {
                // Coplanar: the lower face id is painted last (it wins ties).
                if pface > qq.face {
                    counters.coplanar += 1;
                    continue;
                }
            } else if sides.p_behind_q_plane() {
                counters.test3 += 1;
                continue;
            } else if sides.q_before_p_plane() {
                counters.test4 += 1;
                continue;
            }
            if !s.ws.projections_overlap(p, q) {
                counters.test5 += 1;
                continue;
            }
            stopped = at;
            // P may hide Q: can Q go first (tests 3 and 4 with P and Q swapped)?
            if sides.coplanar() {
                blocker = Some((q, sides, true));
                break;
            }
            if sides.q_behind_p_plane() {
                counters.swap_test3 += 1;
                blocker = Some((q, sides, true));
                break;
            }
            if sides.p_before_q_plane() {
                counters.swap_test4 += 1;
                blocker = Some((q, sides, true));
                break;
            }
            // Both cross each other's planes: compare depths where they overlap.
            match s.ws.nearer_over_overlap(p, q) {
                Some(Ordering::Less) => {
                    counters.overlap_depth += 1;
                    stopped = candidates.len();
                    continue;
                }
                Some(_) => {
                    counters.swap_overlap_depth += 1;
                    blocker = Some((q, sides, true));
                }
                None => blocker = Some((q, sides, false)),
            }
            break;
        }
        if blocker.is_some() {
            s.resume.insert(p, (candidates, stopped));
        } else {
            spare = candidates;
        }
        let Some((q, sides, swapped)) = blocker else {
            s.stack.pop();
            s.state[pk] = State::Painted;
            paint(s.ws, p);
            painted += 1;
            if painted.is_multiple_of(4096) {
                progress(painted as f64 / (s.state.len() as f64).max(1.0));
            }
            continue;
        };
        if swapped && !s.marked[q as usize] {
            counters.swaps += 1;
            s.move_to_head(q);
            continue;
        }
        if s.split_budget > 0 {
            let done = if swapped {
                // Q already moved once: the stack from the head down to Q is a cycle.
                counters.cycles += 1;
                split_cycle(&mut s, p, q, &sides, counters)
            } else if sides.p_spans_q_plane() {
                // Interpenetration: cut P by Q's plane.
                s.split(p, q, counters)
            } else if sides.q_spans_p_plane() {
                s.split(q, p, counters)
            } else {
                false
            };
            if done {
                continue;
            }
        }
        // No order and no split (rounding, or the split budget is spent): paint P,
        // and depth-test it and every later polygon.
        counters.unresolved += 1;
        s.ws.fallback = true;
        s.resume.remove(&p);
        s.stack.pop();
        s.state[pk] = State::Painted;
        paint(s.ws, p);
        painted += 1;
    }
}

/// Breaks the cycle made of the stack from the head `p` down to `q`: splits a
/// polygon of it by the plane of another, trying `p` by `q`, `q` by `p`, then any
/// pair of the cycle (one always crosses another's plane: polygons that cross no
/// plane of each other can be ordered, as a BSP autopartition without splits shows).
fn split_cycle(s: &mut Sorter<'_>, p: u32, q: u32, sides: &Sides, counters: &mut Counters) -> bool {
    if sides.p_spans_q_plane() {
        return s.split(p, q, counters);
    }
    if sides.q_spans_p_plane() {
        return s.split(q, p, counters);
    }
    let Some(pos) = s.stack.iter().rposition(|&x| x == q) else {
        return false;
    };
    let cycle: Vec<u32> = s.stack[pos..].to_vec();
    for &a in cycle.iter().rev() {
        for &b in &cycle {
            if a != b
                && s.ws.polys[a as usize].face != s.ws.polys[b as usize].face
                && s.ws.sides(a, b).p_spans_q_plane()
            {
                return s.split(a, b, counters);
            }
        }
    }
    false
}
