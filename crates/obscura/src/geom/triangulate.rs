//! Triangulation of simple polygons by ear clipping (Meisters, "Polygons have ears",
//! American Mathematical Monthly 82, 1975; the two-ears theorem it rests on), on a
//! linked ring with a grid of the reflex and flat corners, under a work bound past
//! which the rest is fanned. Used by the loaders for non-planar or concave n-gons.

use glam::{DVec2, DVec3};

use super::polygon::{newell_normal, project};

/// Triangulates a simple polygon (planar or nearly so) by ear clipping in its Newell
/// plane. Returns triangles as index triples into `points`, counter-clockwise in the
/// same sense as the polygon: `n - 2` of them for `n` points, with the polygon's area.
///
/// The polygon is a doubly linked ring; the scan for ears goes on from the last ear
/// instead of starting over, and only vertices whose corner is reflex or flat are tested
/// against a candidate ear, through a uniform grid (cells the triangle crosses, row by
/// row, skipping empty ones). Typical polygons (stars, combs, spirals, outlines) take
/// about 2n ear tests of a few grid entries each: a 100,000-vertex star takes a few
/// hundred milliseconds at most. Long thin ears grazing a long row of not yet clipped
/// reflex vertices still cost time proportional to that row (a long bar carrying
/// thousands of teeth, clipped from the wrong end, is quadratic: about 10 s for 100,000
/// vertices).
///
/// Degenerate input:
/// - collinear runs are kept as vertices (no T-junctions with neighbouring faces):
///   flat corners are never clipped as ears and block ears like reflex ones;
/// - polygons that touch themselves, such as a hole joined to the outline by a
///   zero-width cut (two coincident edges), or repeated points, triangulate like simple
///   ones: a vertex at the same place as the first or last corner of a candidate ear does
///   not block it;
/// - when a whole turn of the ring finds no ear (spikes, self-intersections, rounding),
///   spike tips and repeated points are clipped as zero-area triangles (which callers may
///   drop), or else the best candidate is clipped anyway (see `EarClipper::unstick`), so
///   the result always has `n - 2` triangles, though for self-intersecting polygons some
///   may overlap or turn clockwise;
/// - the work is bounded (see `EAR_WORK_PER_VERTEX`): past the bound, whatever remains
///   is fanned. Polygons with no defined plane (zero or non-finite Newell normal) are
///   fanned from the first vertex.
///
/// ```
/// use obscura::geom::triangulate;
/// use glam::DVec3;
/// // An L-shaped (concave) hexagon.
/// let l = [(0.,0.),(2.,0.),(2.,1.),(1.,1.),(1.,2.),(0.,2.)].map(|(x,y)| DVec3::new(x,y,0.));
/// let tris = triangulate(&l);
/// assert_eq!(tris.len(), 4);
/// ```
#[must_use]
pub fn triangulate(points: &[DVec3]) -> Vec<[u32; 3]> {
    triangulate_reporting(points).triangles
}

/// A triangulation, and whether it is only partly ear clipping.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangulation {
    /// The triangles, as [`triangulate`] returns them.
    pub triangles: Vec<[u32; 3]>,
    /// The work bound ran out (see [`triangulate`]) and the rest of the polygon was
    /// fanned: if it was not convex, some triangles overlap or lie outside it.
    pub fanned: bool,
}

/// [`triangulate`], also telling whether the work bound cut it short, so that callers
/// can warn about the fanned rest.
#[must_use]
pub fn triangulate_reporting(points: &[DVec3]) -> Triangulation {
    triangulate_within(points, ear_work_budget(points.len()))
}

/// [`triangulate_reporting`] with a given work bound instead of [`triangulate`]'s
/// (callers' tests of the fanned case use a tiny one).
pub(crate) fn triangulate_within(points: &[DVec3], budget: usize) -> Triangulation {
    let complete = |triangles| Triangulation {
        triangles,
        fanned: false,
    };
    let count = points.len();
    if count < 3 {
        return complete(Vec::new());
    }
    if count == 3 {
        return complete(vec![[0, 1, 2]]);
    }
    let fan = || {
        (1..count as u32 - 1)
            .map(|i| [0, i, i + 1])
            .collect::<Vec<_>>()
    };
    let n = newell_normal(points);
    if n == DVec3::ZERO || !n.is_finite() {
        return complete(fan());
    }
    let p = project(points, n);
    if !p.iter().all(|q| q.is_finite()) {
        return complete(fan());
    }
    EarClipper::new(p).run(budget)
}

/// The work [`triangulate`] may spend on `n` vertices (see [`EAR_WORK_PER_VERTEX`]).
fn ear_work_budget(n: usize) -> usize {
    EAR_WORK_BASE
        .saturating_add(EAR_WORK_PER_VERTEX.saturating_mul(n))
        .saturating_add((n.saturating_mul(n) / 4).min(EAR_WORK_QUADRATIC_CAP))
}

/// Twice the signed area of the triangle `abc`: positive when it turns counter-clockwise.
fn area2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether `q` lies in the counter-clockwise triangle `t`: strictly inside if `strict`,
/// else inside, on its boundary, or less than `margin` outside it (a distance).
fn in_triangle(t: [DVec2; 3], q: DVec2, strict: bool, margin: f64) -> bool {
    (0..3).all(|k| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        let turn = area2(a, b, q);
        if strict {
            turn > 0.0
        } else {
            // `turn / |ab|` is the distance from the side's line.
            turn >= -margin * (b - a).length()
        }
    })
}

/// The x extent of the part of triangle `t` between heights `y0` and `y1`, or `None` if
/// it has none.
fn x_extent(t: [DVec2; 3], y0: f64, y1: f64) -> Option<(f64, f64)> {
    let mut extent: Option<(f64, f64)> = None;
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let (p, q) = if p.y <= q.y { (p, q) } else { (q, p) };
        if q.y < y0 || p.y > y1 {
            continue;
        }
        let (xa, xb) = if q.y > p.y {
            let at = |y: f64| p.x + (q.x - p.x) * ((y - p.y) / (q.y - p.y));
            (at(p.y.max(y0)), at(q.y.min(y1)))
        } else {
            (p.x, q.x)
        };
        let (lo, hi) = extent.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
        extent = Some((lo.min(xa).min(xb), hi.max(xa).max(xb)));
    }
    extent
}

/// No vertex (end of a list, or no link).
const NONE: usize = usize::MAX;

/// Work (ear tests, grid rows, cells and entries visited) [`triangulate`] may spend per
/// vertex, plus [`EAR_WORK_BASE`] and a quarter of the vertex count squared, before it
/// gives up and fans what is left. Typical simple polygons need about 10 to 130 units per
/// vertex (stars, combs and spirals of 20,000 vertices); the quadratic term lets the
/// known slow shapes (see [`triangulate`]) finish correctly: a 100,000-vertex bar of
/// teeth needs 1.6e9. The quadratic term is capped at [`EAR_WORK_QUADRATIC_CAP`]. The
/// bound stops hostile input (heavily self-intersecting polygons whose every candidate
/// ear is blocked, or a million-vertex comb met from the wrong end) from taking cubic or
/// unbounded quadratic time.
const EAR_WORK_PER_VERTEX: usize = 1000;
/// See [`EAR_WORK_PER_VERTEX`].
const EAR_WORK_BASE: usize = 1 << 20;
/// The most the quadratic term of the work bound grants (about 13 s at the 6 ns per
/// unit measured on the 100,000-vertex comb): without it, a face of a million vertices
/// in a file of 8 MB could ask for 2.5e11 units, half an hour.
const EAR_WORK_QUADRATIC_CAP: usize = 1 << 31;

/// What a vertex's corner (with its current neighbours) is to ear clipping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Corner {
    /// Turns strictly counter-clockwise: a candidate ear.
    Convex,
    /// Reflex, flat, or not computable: may lie in a candidate ear. Flat vertices count:
    /// a vertex of a straight run lying on an ear's third side would leave a zero-width
    /// remainder (zero-area triangles later).
    Blocking,
}

impl Corner {
    fn of(a: DVec2, b: DVec2, c: DVec2) -> Self {
        if area2(a, b, c) > 0.0 {
            Corner::Convex
        } else {
            Corner::Blocking
        }
    }
}

/// A uniform grid listing the polygon's blocking vertices (see [`Corner`]): the only
/// vertices that can spoil an ear (if a vertex lies in a convex corner's triangle, the
/// one deepest inside is not convex). About one cell per
/// listed vertex, in the proportions of the polygon's bounding box. Cells are singly
/// linked lists threaded through the vertices; vertices that stopped blocking or were
/// clipped are unlinked when a query walks past them. A bit per cell tells whether its
/// list is empty, so that queries skip runs of empty cells 64 at a time (long triangles
/// cross many cells once the vertices around them are clipped).
struct CornerGrid {
    origin: DVec2,
    /// Cells per unit along each axis.
    scale: DVec2,
    nx: usize,
    ny: usize,
    /// The first vertex listed in each cell, row by row.
    head: Vec<usize>,
    /// The next vertex listed in the same cell, per vertex.
    link: Vec<usize>,
    /// Whether a vertex is listed.
    listed: Vec<bool>,
    /// Words of occupancy bits per row.
    words: usize,
    /// One bit per cell, set when its list may be non-empty, row by row.
    occupied: Vec<u64>,
}

impl CornerGrid {
    /// An empty grid over the box `lo..hi` for `vertices` vertices, about `expected` of
    /// them to be listed.
    fn new(lo: DVec2, hi: DVec2, vertices: usize, expected: usize) -> Self {
        let size = hi - lo;
        let k = expected.max(1) as f64;
        let (nx, ny) = if size.x > 0.0 && size.y > 0.0 {
            // `clamp` also tames the infinite ratio of a box flat to rounding.
            let nx = (k * size.x / size.y).sqrt().ceil().clamp(1.0, k);
            (nx, (k / nx).ceil().clamp(1.0, k))
        } else if size.x > 0.0 {
            (k, 1.0)
        } else {
            (1.0, k)
        };
        let per_unit = |cells: f64, extent: f64| {
            if extent > 0.0 { cells / extent } else { 0.0 }
        };
        let (nx, ny) = (nx as usize, ny as usize);
        let words = nx.div_ceil(64);
        CornerGrid {
            origin: lo,
            scale: DVec2::new(per_unit(nx as f64, size.x), per_unit(ny as f64, size.y)),
            nx,
            ny,
            head: vec![NONE; nx * ny],
            link: vec![NONE; vertices],
            listed: vec![false; vertices],
            words,
            occupied: vec![0; words * ny],
        }
    }

    /// The column of the cells holding abscissa `x`. Points outside the box go to the
    /// nearest cell; the map is monotonic, so a range query visits every cell that can
    /// hold a point of the range.
    fn column(&self, x: f64) -> usize {
        // `as` saturates (NaN gives 0), and truncation is monotonic.
        (((x - self.origin.x) * self.scale.x) as i64).clamp(0, self.nx as i64 - 1) as usize
    }

    /// The row of the cells holding ordinate `y` (as [`CornerGrid::column`]).
    fn row(&self, y: f64) -> usize {
        (((y - self.origin.y) * self.scale.y) as i64).clamp(0, self.ny as i64 - 1) as usize
    }

    /// Lists vertex `v` at `q`, unless it is listed already.
    fn insert(&mut self, v: usize, q: DVec2) {
        if self.listed[v] {
            return;
        }
        let (i, j) = (self.column(q.x), self.row(q.y));
        let cell = j * self.nx + i;
        self.link[v] = self.head[cell];
        self.head[cell] = v;
        self.listed[v] = true;
        self.occupied[j * self.words + i / 64] |= 1 << (i % 64);
    }

    /// The next column from `i` to `last` in `row` whose cell is occupied, if any.
    fn next_occupied(&self, row: usize, i: usize, last: usize) -> Option<usize> {
        let bits = &self.occupied[row * self.words..(row + 1) * self.words];
        let mut w = i / 64;
        let mut word = bits[w] & (u64::MAX << (i % 64));
        loop {
            if word != 0 {
                let found = w * 64 + word.trailing_zeros() as usize;
                return (found <= last).then_some(found);
            }
            w += 1;
            if w * 64 > last {
                return None;
            }
            word = bits[w];
        }
    }

    /// The range of columns to visit in `row` for triangle `t`, whose columns span
    /// `i0..=i1`: those the part of `t` within the row (widened by half a row) overlaps,
    /// plus one on each side for rounding. Long thin triangles, common late in ear
    /// clipping, overlap far fewer cells than their bounding box.
    fn columns_in_row(&self, t: [DVec2; 3], row: usize, i0: usize, i1: usize) -> (usize, usize) {
        if i1 - i0 < 3 || self.scale.y == 0.0 {
            return (i0, i1);
        }
        let height = 1.0 / self.scale.y;
        let y0 = if row == 0 {
            f64::NEG_INFINITY
        } else {
            self.origin.y + (row as f64 - 0.5) * height
        };
        let y1 = if row + 1 == self.ny {
            f64::INFINITY
        } else {
            self.origin.y + (row as f64 + 1.5) * height
        };
        match x_extent(t, y0, y1) {
            Some((lo, hi)) => (
                self.column(lo).saturating_sub(1).max(i0),
                (self.column(hi) + 1).min(i1),
            ),
            // Empty: an inverted range.
            None => (1, 0),
        }
    }
}

/// The state of ear clipping: the remaining polygon as a doubly linked ring of vertices,
/// each corner's kind, the grid of the blocking ones, and the triangles so far.
struct EarClipper {
    p: Vec<DVec2>,
    prev: Vec<usize>,
    next: Vec<usize>,
    corner: Vec<Corner>,
    clipped: Vec<bool>,
    /// Blocking vertices in the ring.
    blocking: usize,
    /// Vertices in the ring.
    remaining: usize,
    grid: CornerGrid,
    /// How far outside an ear a vertex still blocks it: a millionth of a millionth of
    /// the polygon's size, for vertices on an ear's side that rounding (of a plane's
    /// rotation, say) moved slightly out. Clipping such an ear would leave a remainder of
    /// zero width there, and later ears would cross it.
    margin: f64,
    /// Work units spent (see [`EAR_WORK_PER_VERTEX`]).
    work: usize,
    out: Vec<[u32; 3]>,
}

impl EarClipper {
    /// The ring of the projected polygon `p` (counter-clockwise overall).
    fn new(p: Vec<DVec2>) -> Self {
        let count = p.len();
        let prev: Vec<usize> = (0..count).map(|i| (i + count - 1) % count).collect();
        let next: Vec<usize> = (0..count).map(|i| (i + 1) % count).collect();
        let corner: Vec<Corner> = (0..count)
            .map(|i| Corner::of(p[prev[i]], p[i], p[next[i]]))
            .collect();
        let blocking = corner.iter().filter(|&&c| c == Corner::Blocking).count();
        let (lo, hi) = p
            .iter()
            .fold((p[0], p[0]), |(lo, hi), &q| (lo.min(q), hi.max(q)));
        let mut grid = CornerGrid::new(lo, hi, count, blocking);
        for (i, &q) in p.iter().enumerate() {
            if corner[i] == Corner::Blocking {
                grid.insert(i, q);
            }
        }
        EarClipper {
            p,
            prev,
            next,
            corner,
            clipped: vec![false; count],
            blocking,
            remaining: count,
            grid,
            margin: 1e-12 * (hi - lo).length(),
            work: 0,
            out: Vec::with_capacity(count - 2),
        }
    }

    /// Whether the corner at `b` is an ear: strictly convex, and no blocking vertex of the
    /// ring lies in its triangle. Vertices at the same place as one of the triangle's
    /// corners (the two ends of a zero-width cut, repeated points) do not count: their
    /// edges lie outside the corner's angle in a polygon that only touches itself. With
    /// `strict`, vertices on the triangle's boundary do not count either.
    fn is_ear(&mut self, b: usize, strict: bool) -> bool {
        let (a, c) = (self.prev[b], self.next[b]);
        self.work += 1;
        if self.corner[b] != Corner::Convex {
            return false;
        }
        if self.blocking == 0 {
            return true;
        }
        let (pa, pb, pc) = (self.p[a], self.p[b], self.p[c]);
        let grid = &mut self.grid;
        let (lo, hi) = (pa.min(pb).min(pc), pa.max(pb).max(pc));
        let (i0, i1) = (grid.column(lo.x), grid.column(hi.x));
        for j in grid.row(lo.y)..=grid.row(hi.y) {
            let (k0, k1) = grid.columns_in_row([pa, pb, pc], j, i0, i1);
            self.work += 1;
            let mut next_column = k0;
            while next_column <= k1 {
                let Some(i) = grid.next_occupied(j, next_column, k1) else {
                    break;
                };
                next_column = i + 1;
                let cell = j * grid.nx + i;
                self.work += 1;
                let mut before = NONE;
                let mut v = grid.head[cell];
                while v != NONE {
                    self.work += 1;
                    let after = grid.link[v];
                    if self.clipped[v] || self.corner[v] != Corner::Blocking {
                        // Unlink it (`update` lists it again if it turns blocking).
                        if before == NONE {
                            grid.head[cell] = after;
                        } else {
                            grid.link[before] = after;
                        }
                        grid.listed[v] = false;
                        v = after;
                        continue;
                    }
                    let q = self.p[v];
                    if v != a
                        && v != c
                        && q != pa
                        && q != pc
                        && in_triangle([pa, pb, pc], q, strict, self.margin)
                    {
                        return false;
                    }
                    before = v;
                    v = after;
                }
                if grid.head[cell] == NONE {
                    grid.occupied[j * grid.words + i / 64] &= !(1 << (i % 64));
                }
            }
        }
        true
    }

    /// Recomputes the kind of `v`'s corner after a neighbour changed.
    fn update(&mut self, v: usize) {
        let was = self.corner[v];
        let now = Corner::of(self.p[self.prev[v]], self.p[v], self.p[self.next[v]]);
        self.corner[v] = now;
        if was != Corner::Blocking && now == Corner::Blocking {
            // Only after clipping a bad ear (self-intersecting input), a spike tip, or by
            // rounding: clipping an ear makes its neighbours' angles smaller.
            self.blocking += 1;
            self.grid.insert(v, self.p[v]);
        } else if was == Corner::Blocking && now != Corner::Blocking {
            self.blocking -= 1;
        }
    }

    /// Emits the triangle of `b`'s corner and takes `b` out of the ring.
    fn clip(&mut self, b: usize) {
        let (a, c) = (self.prev[b], self.next[b]);
        self.out.push([a as u32, b as u32, c as u32]);
        self.next[a] = c;
        self.prev[c] = a;
        self.clipped[b] = true;
        self.remaining -= 1;
        if self.corner[b] == Corner::Blocking {
            self.blocking -= 1;
        }
        self.update(a);
        self.update(c);
    }

    /// Called when a whole turn of the ring from `start` found no ear, which happens only
    /// for polygons that touch or cross themselves (or by rounding): clips something
    /// anyway and returns where to resume. In order of preference:
    /// 1. every spike tip and repeated point (a flat corner whose neighbours lie on the
    ///    same side; its triangle has zero area and the region is unchanged);
    /// 2. the first ear found when vertices on a triangle's boundary are allowed;
    /// 3. the first strictly convex corner, an ear or not;
    /// 4. `start` itself (no corner is convex: the rest turns clockwise).
    fn unstick(&mut self, start: usize) -> usize {
        let turn = self.remaining;
        let mut v = start;
        let mut steps = 0;
        let mut dropped = false;
        while steps < turn && self.remaining > 3 {
            self.work += 1;
            let (a, c) = (self.prev[v], self.next[v]);
            let (pa, pv, pc) = (self.p[a], self.p[v], self.p[c]);
            if area2(pa, pv, pc) == 0.0 && (pa - pv).dot(pc - pv) >= 0.0 {
                self.clip(v);
                dropped = true;
                // The spike's base may be a spike tip now.
                v = a;
            } else {
                v = c;
                steps += 1;
            }
        }
        if dropped {
            return v;
        }
        let mut v = start;
        for _ in 0..turn {
            if self.is_ear(v, true) {
                return self.clip_and_resume(v);
            }
            v = self.next[v];
        }
        for _ in 0..turn {
            self.work += 1;
            if self.corner[v] == Corner::Convex {
                return self.clip_and_resume(v);
            }
            v = self.next[v];
        }
        self.clip_and_resume(start)
    }

    /// Clips `b` and returns its former predecessor.
    fn clip_and_resume(&mut self, b: usize) -> usize {
        let a = self.prev[b];
        self.clip(b);
        a
    }

    /// Clips ears until three vertices remain, then emits the last triangle.
    /// Past `budget` units of work, the rest is fanned.
    fn run(mut self, budget: usize) -> Triangulation {
        let mut cur = 0;
        // Where a turn of the ring without an ear ends.
        let mut stop = cur;
        while self.remaining > 3 {
            if self.work > budget {
                // Fan the rest: bounded time for hostile input.
                let first = cur;
                let mut v = self.next[first];
                while self.next[v] != first {
                    self.out.push([first as u32, v as u32, self.next[v] as u32]);
                    v = self.next[v];
                }
                return Triangulation {
                    triangles: self.out,
                    fanned: true,
                };
            }
            if self.is_ear(cur, false) {
                // Resume at the ear's predecessor, then its successor: only their corners
                // changed, and the next ear is often one of them (in a thin band, the
                // only ears are at its ends, which zip up from there; resuming further
                // on would go round the whole ring for each).
                cur = self.clip_and_resume(cur);
                stop = cur;
                continue;
            }
            cur = self.next[cur];
            if cur == stop {
                cur = self.unstick(cur);
                stop = cur;
            }
        }
        self.out
            .push([self.prev[cur] as u32, cur as u32, self.next[cur] as u32]);
        Triangulation {
            triangles: self.out,
            fanned: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::polygon_area;

    fn pts(v: &[(f64, f64)]) -> Vec<DVec3> {
        v.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect()
    }

    #[test]
    fn ear_clipping_preserves_area() {
        let l = pts(&[(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]);
        let tris = triangulate(&l);
        let total: f64 = tris
            .iter()
            .map(|t| polygon_area(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]]))
            .sum();
        assert!((total - 3.0).abs() < 1e-12);
        // every triangle keeps the polygon's orientation
        for t in &tris {
            let n = newell_normal(&[l[t[0] as usize], l[t[1] as usize], l[t[2] as usize]]);
            assert!(n.z > 0.0);
        }
    }

    /// Twice the signed area of a 2D polygon (shoelace).
    fn shoelace2(p: &[DVec2]) -> f64 {
        (0..p.len())
            .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
            .sum()
    }

    /// Crossing-number point-in-polygon test (even-odd rule); coincident edges, such as
    /// the two sides of a zero-width cut, cancel out.
    fn inside(p: &[DVec2], q: DVec2) -> bool {
        let mut odd = false;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if (a.y > q.y) != (b.y > q.y) {
                let x = a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if q.x < x {
                    odd = !odd;
                }
            }
        }
        odd
    }

    /// Checks that `tris` triangulates `points`: `n - 2` triangles of distinct in-range
    /// indices, each counter-clockwise (or flat, up to rounding) in the polygon's
    /// projected plane, whose
    /// areas add up to the polygon's (relative 1e-9); and, when `is_inside` is given, that
    /// every triangle of non-negligible area has its centroid inside the polygon.
    /// Positive areas that add up to the area, all inside, cannot overlap.
    fn check_triangulation(
        points: &[DVec3],
        tris: &[[u32; 3]],
        is_inside: Option<&dyn Fn(DVec2) -> bool>,
    ) -> Result<(), String> {
        let n = points.len();
        if tris.len() != n - 2 {
            return Err(format!("{} triangles for {n} points", tris.len()));
        }
        let p = project(points, newell_normal(points));
        let total = shoelace2(&p);
        if !(total > 0.0) {
            return Err(format!("projected polygon not counter-clockwise: {total}"));
        }
        let mut sum = 0.0;
        for t in tris {
            let [a, b, c] = t.map(|i| i as usize);
            if a >= n || b >= n || c >= n || a == b || b == c || a == c {
                return Err(format!("bad triangle {t:?}"));
            }
            let area = area2(p[a], p[b], p[c]);
            // Rounding: points placed on a rotated plane are only nearly collinear.
            if area < -1e-12 * total {
                return Err(format!("clockwise triangle {t:?}: {area}"));
            }
            sum += area;
            if let Some(is_inside) = is_inside {
                let centroid = (p[a] + p[b] + p[c]) / 3.0;
                if area > 1e-9 * total && !is_inside(centroid) {
                    return Err(format!("triangle {t:?} outside, centroid {centroid}"));
                }
            }
        }
        if (sum - total).abs() > 1e-9 * total {
            return Err(format!("triangle areas {sum} != polygon area {total}"));
        }
        Ok(())
    }

    /// [`check_triangulation`] with the crossing-number test against the polygon itself.
    fn check(points: &[DVec3]) -> Result<(), String> {
        let p = project(points, newell_normal(points));
        check_triangulation(points, &triangulate(points), Some(&|q| inside(&p, q)))
    }

    /// Places 2D points on a plane through `origin` with the given orientation, reversed
    /// when `flip` (the triangulation must follow the polygon's sense either way).
    fn embed(p: &[(f64, f64)], yaw: f64, pitch: f64, origin: DVec3, flip: bool) -> Vec<DVec3> {
        let r = glam::DMat3::from_euler(glam::EulerRot::ZXY, yaw, pitch, 0.3 * yaw);
        let mut v: Vec<DVec3> = p
            .iter()
            .map(|&(x, y)| origin + r * DVec3::new(x, y, 0.0))
            .collect();
        if flip {
            v.reverse();
        }
        v
    }

    /// A star-shaped polygon: vertices at increasing angles around the origin, at the
    /// given radii; `jitter` (each in 0..1) moves each angle within its sector.
    fn star(radii: &[f64], jitter: &[f64]) -> Vec<(f64, f64)> {
        let n = radii.len();
        (0..n)
            .map(|i| {
                let a =
                    (i as f64 + 0.9 * jitter[i % jitter.len()]) * std::f64::consts::TAU / n as f64;
                (radii[i] * a.cos(), radii[i] * a.sin())
            })
            .collect()
    }

    /// A comb: a base bar under teeth of the given (gap before, width, height), so
    /// every tooth is a notch of reflex vertices. Returns the outline, counter-clockwise,
    /// and an exact inside test.
    fn comb(teeth: &[(f64, f64, f64)]) -> (Vec<(f64, f64)>, impl Fn(DVec2) -> bool) {
        let mut boxes = Vec::new(); // (x0, x1, height)
        let mut x = 0.0;
        for &(gap, width, height) in teeth {
            x += gap;
            boxes.push((x, x + width, height));
            x += width;
        }
        let end = x + 1.0;
        let mut outline = vec![(0.0, -1.0), (end, -1.0), (end, 0.0)];
        for &(x0, x1, h) in boxes.iter().rev() {
            outline.extend([(x1, 0.0), (x1, h), (x0, h), (x0, 0.0)]);
        }
        outline.push((0.0, 0.0));
        let is_inside = move |q: DVec2| {
            (q.y > -1.0 && q.y < 0.0 && q.x > 0.0 && q.x < end)
                || boxes
                    .iter()
                    .any(|&(x0, x1, h)| q.x > x0 && q.x < x1 && q.y >= 0.0 && q.y < h)
        };
        (outline, is_inside)
    }

    /// A spiral band `turns` round, `samples` points along each side: the thin, winding
    /// shape of the 16,000-vertex fuzzing find, where every ear is a sliver.
    fn spiral(turns: f64, samples: usize, width: f64) -> Vec<(f64, f64)> {
        let pitch = 1.0;
        let side = |offset: f64| {
            (0..samples).map(move |i| {
                let t = turns * std::f64::consts::TAU * i as f64 / (samples - 1) as f64;
                let r = 1.0 + pitch * t / std::f64::consts::TAU + offset;
                (r * t.cos(), r * t.sin())
            })
        };
        let mut v: Vec<(f64, f64)> = side(0.0).collect();
        v.extend(side(width * pitch).collect::<Vec<_>>().into_iter().rev());
        v
    }

    /// A small deterministic generator for the big cases.
    fn xorshift(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn big_comb_and_star_triangulate_correctly() {
        let mut s = 0x9e37_79b9_7f4a_7c15;
        let teeth: Vec<_> = (0..5000)
            .map(|_| {
                let gap = 0.1 + xorshift(&mut s);
                let width = 0.1 + xorshift(&mut s);
                let height = 0.5 + 20.0 * xorshift(&mut s);
                (gap, width, height)
            })
            .collect();
        let (outline, is_inside) = comb(&teeth);
        let points = pts(&outline);
        assert_eq!(points.len(), 20_004);
        let tris = triangulate(&points);
        check_triangulation(&points, &tris, Some(&is_inside)).unwrap();

        // A star: inside tested against the sector's edge (fast for 20,000 vertices).
        let n = 20_000;
        let radii: Vec<f64> = (0..n).map(|_| 0.2 + xorshift(&mut s)).collect();
        let outline = star(&radii, &[0.0]);
        let p: Vec<DVec2> = outline.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        let star_inside = |q: DVec2| {
            let a = q.y.atan2(q.x).rem_euclid(std::f64::consts::TAU);
            let i = ((a / std::f64::consts::TAU * n as f64) as usize).min(n - 1);
            area2(p[i], p[(i + 1) % n], q) > 0.0
        };
        let points = pts(&outline);
        check_triangulation(&points, &triangulate(&points), Some(&star_inside)).unwrap();
    }

    #[test]
    fn big_spiral_triangulates_correctly() {
        // 20,000 vertices, like the fuzzing find; centroids by the area and orientation
        // checks only (the crossing test would be quadratic).
        let points = pts(&spiral(12.0, 10_000, 0.5));
        check_triangulation(&points, &triangulate(&points), None).unwrap();
    }

    #[test]
    fn collinear_runs_are_kept() {
        // A square with 5 extra points on every side, and an L with collinear points on
        // its reflex sides: no zero-area triangle is needed.
        let mut square = Vec::new();
        for k in 0..4 {
            let (c, d) = [
                ((0., 0.), (1., 0.)),
                ((6., 0.), (0., 1.)),
                ((6., 6.), (-1., 0.)),
                ((0., 6.), (0., -1.)),
            ][k];
            for i in 0..6 {
                square.push((c.0 + d.0 * i as f64, c.1 + d.1 * i as f64));
            }
        }
        let l = [
            (0., 0.),
            (2., 0.),
            (4., 0.),
            (4., 1.),
            (4., 2.),
            (3., 2.),
            (2., 2.),
            (2., 3.),
            (2., 4.),
            (1., 4.),
            (0., 4.),
            (0., 2.),
        ];
        for poly in [square, l.to_vec()] {
            let points = pts(&poly);
            check(&points).unwrap();
            let tris = triangulate(&points);
            assert!(
                tris.iter()
                    .all(|t| polygon_area(&t.map(|i| points[i as usize])) > 0.0),
                "{poly:?}: {tris:?}"
            );
        }
    }

    #[test]
    fn a_spent_work_bound_fans_the_rest_and_says_so() {
        // A comb of 40 teeth: 40 units of work are far too few.
        let teeth: Vec<_> = (0..40).map(|_| (0.5, 0.5, 3.0)).collect();
        let (outline, is_inside) = comb(&teeth);
        let points = pts(&outline);
        let n = points.len();
        let p = project(&points, newell_normal(&points));
        let short = EarClipper::new(p).run(40);
        assert!(short.fanned);
        assert_eq!(short.triangles.len(), n - 2);
        assert!(
            check_triangulation(&points, &short.triangles, Some(&is_inside)).is_err(),
            "a fanned comb has triangles outside it"
        );
        // With the real bound: complete and correct.
        let full = triangulate_reporting(&points);
        assert!(!full.fanned);
        check_triangulation(&points, &full.triangles, Some(&is_inside)).unwrap();
    }

    #[test]
    fn repeated_points_and_spikes() {
        // An L (reflex corner (1, 1) at index 3) with that vertex repeated three times,
        // with its first vertex repeated at the end, and with a zero-width spike out of
        // its reflex corner, outwards and inwards.
        let l = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)];
        let with = |at: usize, extra: &[(f64, f64)]| {
            let mut v = l.to_vec();
            v.splice(at..at, extra.iter().copied());
            v
        };
        let polys = [
            with(4, &[(1., 1.), (1., 1.)]),
            with(6, &[(0., 0.)]),
            with(4, &[(3., 3.), (1., 1.)]),
            with(4, &[(0.5, 0.5), (1., 1.)]),
        ];
        for poly in polys {
            let points = pts(&poly);
            check(&points).unwrap_or_else(|e| panic!("{poly:?}: {e}"));
        }
    }

    #[test]
    fn hole_joined_by_a_zero_width_cut() {
        // A 10 x 10 square with a 2 x 2 hole, joined by a cut from (10, 5) to (6, 5); the
        // hole is traversed clockwise.
        let poly = [
            (0., 0.),
            (10., 0.),
            (10., 5.),
            (6., 5.),
            (6., 4.),
            (4., 4.),
            (4., 6.),
            (6., 6.),
            (6., 5.),
            (10., 5.),
            (10., 10.),
            (0., 10.),
        ];
        let points = pts(&poly);
        check(&points).unwrap();
        let area: f64 = triangulate(&points)
            .iter()
            .map(|t| polygon_area(&t.map(|i| points[i as usize])))
            .sum();
        assert!((area - 96.0).abs() < 1e-9, "{area}");
        // Two holes, the second joined to the first, with cuts ending at corners.
        let poly = [
            (0., 0.),
            (10., 0.),
            (10., 10.),
            (8., 8.),
            (8., 6.),
            (6., 6.),
            (6., 8.),
            (4., 4.),
            (4., 2.),
            (2., 2.),
            (2., 4.),
            (4., 4.),
            (6., 8.),
            (8., 8.),
            (10., 10.),
            (0., 10.),
        ];
        check(&pts(&poly)).unwrap();
    }

    #[test]
    fn a_vertex_at_an_ear_corner_does_not_block_it() {
        // A 10 x 10 square with a 2 x 2 hole joined by a cut from (3, 0) to the hole's
        // corner (4, 6). The cut's upper end is two vertices: 2, a reflex corner (it
        // blocks ears), and 6, a sharp convex one. The corner at 7, the cut's lower end
        // on the way back, is an ear: its triangle (4, 6), (3, 0), (3.5, 0) holds no
        // vertex but vertex 2, at its first corner, which must not count.
        let points = pts(&[
            (0., 0.),
            (3., 0.),
            (4., 6.),
            (6., 6.),
            (6., 4.),
            (4., 4.),
            (4., 6.),
            (3., 0.),
            (3.5, 0.),
            (10., 0.),
            (10., 10.),
            (0., 10.),
        ]);
        let mut clipper = EarClipper::new(project(&points, newell_normal(&points)));
        assert_eq!(clipper.corner[2], Corner::Blocking);
        assert_eq!(clipper.corner[6], Corner::Convex);
        assert!(clipper.is_ear(7, false));
        // A blocking vertex elsewhere in the triangle does block it: the hole's corner
        // (4, 4) moved to (3.4, 1), still reflex.
        let mut inside = points.clone();
        inside[5] = DVec3::new(3.4, 1.0, 0.0);
        let mut clipper = EarClipper::new(project(&inside, newell_normal(&inside)));
        assert_eq!(clipper.corner[5], Corner::Blocking);
        assert!(!clipper.is_ear(7, false));
        check(&points).unwrap();
    }

    #[test]
    fn self_intersecting_polygons_terminate() {
        // Bow ties, a pentagram traced as a 5-gon, a figure eight: n - 2 triangles of
        // valid indices (or the fan, for a zero Newell normal).
        let star5: Vec<(f64, f64)> = (0..5)
            .map(|i| {
                let a = i as f64 * 2.0 * std::f64::consts::TAU / 5.0;
                (a.cos(), a.sin())
            })
            .collect();
        let polys = [
            vec![(0., 0.), (1., 1.), (1., 0.), (0., 1.)],
            vec![(0., 0.), (3., 3.), (3., 0.), (0., 1.)],
            star5,
            vec![
                (0., 0.),
                (2., 0.),
                (2., 2.),
                (1., 2.),
                (1., -1.),
                (3., -1.),
                (3., 1.),
                (0., 1.),
            ],
        ];
        for poly in polys {
            let points = pts(&poly);
            let tris = triangulate(&points);
            assert_eq!(tris.len(), points.len() - 2, "{poly:?}");
            for t in &tris {
                assert!(t.iter().all(|&i| (i as usize) < points.len()));
                assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
            }
        }
    }

    #[test]
    fn hostile_polygons_take_bounded_time() {
        // 20,000 random points: a polygon crossing itself everywhere, whose candidate
        // ears are nearly all blocked. Must finish quickly with n - 2 triangles.
        let mut s = 12345;
        let points: Vec<DVec3> = (0..20_000)
            .map(|_| DVec3::new(xorshift(&mut s), xorshift(&mut s), 0.0))
            .collect();
        let tris = triangulate(&points);
        assert_eq!(tris.len(), points.len() - 2);
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn stars(
                radii in prop::collection::vec(0.05..1.0f64, 3..200),
                jitter in prop::collection::vec(0.0..1.0f64, 1..20),
                yaw in 0.0..6.3f64,
                pitch in 0.0..6.3f64,
                flip in any::<bool>(),
            ) {
                let points = embed(&star(&radii, &jitter), yaw, pitch, DVec3::new(3.0, -2.0, 1.0), flip);
                prop_assert_eq!(check(&points), Ok(()));
            }

            #[test]
            fn combs(
                teeth in prop::collection::vec((0.05..2.0f64, 0.05..2.0f64, 0.05..10.0f64), 1..50),
                yaw in 0.0..6.3f64,
                flip in any::<bool>(),
            ) {
                let (outline, _) = comb(&teeth);
                let points = embed(&outline, yaw, 0.4, DVec3::ZERO, flip);
                prop_assert_eq!(check(&points), Ok(()));
            }

            #[test]
            fn spirals(
                turns in 0.3..6.0f64,
                per_turn in 8..40usize,
                width in 0.05..0.95f64,
                flip in any::<bool>(),
            ) {
                let samples = ((turns * per_turn as f64) as usize).max(2);
                // Simple only if a chord's sag, `r (1 - cos(step / 2))` at the largest
                // radius, stays below both the strip's width and the gap to the next
                // turn (coarse spirals of wide strips cross themselves).
                let step = turns * std::f64::consts::TAU / (samples - 1) as f64;
                let sag = (2.0 + turns) * (1.0 - (step / 2.0).cos());
                prop_assume!(1.5 * sag < width.min(1.0 - width));
                let points = embed(&spiral(turns, samples, width), 0.0, 0.0, DVec3::ZERO, flip);
                prop_assert_eq!(check(&points), Ok(()));
            }

            /// A star with a polygonal hole around its centre, joined to one of its
            /// vertices by a zero-width cut along the ray from the centre.
            #[test]
            fn stars_with_a_hole(
                radii in prop::collection::vec(0.3..1.0f64, 3..100),
                hole in 3..30usize,
                at in any::<prop::sample::Index>(),
            ) {
                let outline = star(&radii, &[0.0]);
                let k = at.index(outline.len());
                let angle = k as f64 * std::f64::consts::TAU / outline.len() as f64;
                // Clockwise, starting and ending on the cut's ray; inside every sector.
                let h: Vec<(f64, f64)> = (0..=hole)
                    .map(|i| {
                        let a = angle - i as f64 * std::f64::consts::TAU / hole as f64;
                        (0.1 * a.cos(), 0.1 * a.sin())
                    })
                    .collect();
                let mut poly = outline[..=k].to_vec();
                poly.extend(h);
                poly.extend_from_slice(&outline[k..]);
                let points = pts(&poly);
                prop_assert_eq!(check(&points), Ok(()));
            }

            /// Random points: usually self-intersecting. Only termination and the
            /// triangle count are promised.
            #[test]
            fn random_polygons(raw in prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64), 3..300)) {
                let points = pts(&raw);
                let tris = triangulate(&points);
                let normal = newell_normal(&points);
                prop_assert_eq!(tris.len(), points.len() - 2);
                prop_assert!(tris.iter().flatten().all(|&i| (i as usize) < points.len()));
                let _ = normal;
            }
        }
    }
}
