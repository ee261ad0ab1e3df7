//! A uniform grid over the triangles of a scene, traversed front to back by a 3D-DDA.
//!
//! Source: seed 000 "Υποδιαίρεση Χώρου" (space divided into an ordered set of cells);
//! seed 002, the last slides of "Ray Casting": the scene is partitioned into a regular
//! grid of equal volumes, each holding the objects wholly or partly inside it; a ray is
//! tested only against the objects of the cells it passes, in the order it meets them,
//! and *a hit found in a cell is accepted only if it lies in that cell* — an object
//! spanning several cells may be hit farther along, in a later cell, where another
//! object could be nearer. Traversal: Amanatides and Woo, "A Fast Voxel Traversal
//! Algorithm for Ray Tracing" (1987).
//!
//! # Resolution
//! About `λ N` cells for `N` triangles (`λ` = [`GridOptions::density`], 2 by
//! default), shaped like the scene: `n_i = round(e_i k)` cells along an axis of extent
//! `e_i` with `k = cbrt(λ N / V)`; an axis that would get less than one cell (a flat
//! scene) gets one and the others share the budget (`k = sqrt(λ N / (e_a e_b))`).
//! At most [`GridOptions::max_cells`] cells and 2048 per axis.
//!
//! # Binning
//! A triangle goes into every cell its bounding box touches *and* that it really
//! overlaps, by the separating-axis test of Akenine-Möller ("Fast 3D Triangle-Box
//! Overlap Testing", 2001: the 3 box normals, the triangle's normal and the 9 edge
//! cross products). Cells are grown by `10^-7` of their size for this test, so a
//! triangle touching a cell's face is in both cells and rounding in the traversal
//! cannot lose it.
//!
//! # Traversal
//! The ray is clipped to the grid's box and `[t_min, t_max]`; each visited cell covers
//! `[t_enter, t_exit]` of the ray (consecutive cells share the boundary value, so the
//! intervals tile the ray exactly). A hit on a triangle of the cell is accepted only if
//! its parameter lies in that interval: a hit outside the cell is refused there (and
//! accepted in its own cell, which the triangle also occupies). The walk stops after
//! the first cell that produced a hit nearer than its exit (at exactly the exit, the
//! next cell may still offer an equal-distance hit with a lower face id).
//!
//! Mailboxing (Amanatides and Woo): a triangle spanning several cells would be tested
//! again in each. A per-thread [`Mailbox`] keeps, per triangle, the ray that tested it
//! last and the result — the hit parameter over the whole ray, or none — so a triangle
//! met again by the same ray is not re-tested; the cell rule is applied to the
//! remembered parameter, which is exactly what a new test would give.
//!
//! - Complexity: build O(N + refs); a ray visits O(n_x + n_y + n_z) cells at worst.
//! - Limitations: uniform cells suit uniformly spread scenes and waste memory and steps
//!   on uneven ones ("teapot in a stadium"); the mailbox costs 12 bytes per triangle
//!   per thread.

use std::time::Instant;

use glam::DVec3;

use crate::accel::triangles::{AxisOrder, ClosestHit, HitContext, SceneTriangles, WithAxisOrder};
use crate::geom::Aabb;

/// Grid parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct GridOptions {
    /// Target cells per triangle (λ).
    pub density: f64,
    /// The most cells allowed.
    pub max_cells: usize,
}

impl GridOptions {
    /// These options with another density (cells per triangle).
    #[must_use]
    pub fn with_density(mut self, density: f64) -> Self {
        self.density = density;
        self
    }
}

impl Default for GridOptions {
    fn default() -> Self {
        GridOptions {
            density: 2.0,
            max_cells: 1 << 24,
        }
    }
}

/// Figures of a build.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridStats {
    /// Milliseconds spent building.
    pub build_ms: f64,
    /// Cells.
    pub cells: usize,
    /// Triangle references stored (a triangle in k cells counts k times).
    pub refs: usize,
    /// Cells holding no triangle.
    pub empty_cells: usize,
}

/// A uniform grid (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct UniformGrid {
    bounds: Aabb,
    resolution: [u32; 3],
    cell_size: DVec3,
    starts: Vec<u32>,
    refs: Vec<u32>,
    stats: GridStats,
}

/// The mailbox of one thread: per triangle, the ray that tested it last and the result
/// (hit parameter over the whole ray, or NaN). Stamped by a ray counter, so nothing
/// needs clearing between rays.
#[derive(Clone, Debug, Default)]
pub struct Mailbox {
    ray: u32,
    stamp: Vec<u32>,
    result: Vec<f64>,
}

impl Mailbox {
    /// A mailbox for the triangles of a grid.
    #[must_use]
    pub fn new(triangles: &SceneTriangles) -> Self {
        Mailbox {
            ray: 0,
            stamp: vec![0; triangles.len()],
            result: vec![f64::NAN; triangles.len()],
        }
    }

    /// Starts a new ray.
    fn next_ray(&mut self) {
        self.ray = self.ray.wrapping_add(1);
        if self.ray == 0 {
            // After 2^32 rays the stamps would repeat: clear them once.
            self.stamp.fill(0);
            self.ray = 1;
        }
    }
}

/// What a traversal did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridCounters {
    /// Cells visited.
    pub cells: u64,
    /// Exact triangle tests run.
    pub triangles: u64,
    /// Tests answered by the mailbox (a triangle met again in a later cell).
    pub mailbox_hits: u64,
}

impl std::ops::AddAssign for GridCounters {
    fn add_assign(&mut self, o: Self) {
        self.cells += o.cells;
        self.triangles += o.triangles;
        self.mailbox_hits += o.mailbox_hits;
    }
}

/// The result of a grid traversal: the nearest hit and the cell it was accepted in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridHit {
    /// The nearest hit.
    pub hit: ClosestHit,
    /// The cell `(x, y, z)` where it was accepted (`None` without a hit).
    pub cell: Option<[u32; 3]>,
}

impl UniformGrid {
    /// Builds the grid over the triangles.
    #[must_use]
    pub fn build(triangles: &SceneTriangles, options: &GridOptions) -> Self {
        let start = Instant::now();
        let mut grid = UniformGrid::default();
        let n = triangles.len();
        let raw = triangles.bounds();
        if n == 0 || raw.is_empty() || n > u32::MAX as usize {
            grid.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
            return grid;
        }
        // Pad so that triangles on the boundary are inside and flat scenes get a
        // thickness.
        let e = raw.extent();
        let pad = (e.max_element() * 1e-6)
            .max(raw.min.abs().max(raw.max.abs()).max_element() * 1e-12)
            .max(1e-300);
        let bounds = Aabb {
            min: raw.min - DVec3::splat(pad),
            max: raw.max + DVec3::splat(pad),
        };
        let resolution = resolution(bounds.extent(), n, options);
        let cell_size = bounds.extent()
            / DVec3::new(
                f64::from(resolution[0]),
                f64::from(resolution[1]),
                f64::from(resolution[2]),
            );
        grid.bounds = bounds;
        grid.resolution = resolution;
        grid.cell_size = cell_size;
        let cells = resolution.iter().map(|&r| r as usize).product::<usize>();
        // (cell, triangle) pairs, then a counting sort by cell.
        let grow = cell_size * 1e-7;
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(n * 2);
        for (t, tri) in triangles.vertices().iter().enumerate() {
            let lo = tri[0].min(tri[1]).min(tri[2]) - grow;
            let hi = tri[0].max(tri[1]).max(tri[2]) + grow;
            let c0 = grid.cell_of(lo);
            let c1 = grid.cell_of(hi);
            let single = c0 == c1;
            for z in c0[2]..=c1[2] {
                for y in c0[1]..=c1[1] {
                    for x in c0[0]..=c1[0] {
                        let c = [x, y, z];
                        if single || {
                            let (bmin, bmax) = grid.cell_box(c);
                            triangle_overlaps_box(
                                tri,
                                (bmin + bmax) * 0.5,
                                (bmax - bmin) * 0.5 + grow,
                            )
                        } {
                            pairs.push((grid.cell_index(c) as u32, t as u32));
                        }
                    }
                }
            }
        }
        let mut starts = vec![0u32; cells + 1];
        for &(c, _) in &pairs {
            starts[c as usize + 1] += 1;
        }
        for i in 0..cells {
            starts[i + 1] += starts[i];
        }
        let mut fill = starts.clone();
        let mut refs = vec![0u32; pairs.len()];
        for &(c, t) in &pairs {
            refs[fill[c as usize] as usize] = t;
            fill[c as usize] += 1;
        }
        grid.stats = GridStats {
            build_ms: 0.0,
            cells,
            refs: refs.len(),
            empty_cells: starts.windows(2).filter(|w| w[0] == w[1]).count(),
        };
        grid.starts = starts;
        grid.refs = refs;
        grid.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        grid
    }

    /// The build figures.
    #[must_use]
    pub fn stats(&self) -> &GridStats {
        &self.stats
    }

    /// Cells along x, y, z.
    #[must_use]
    pub fn resolution(&self) -> [u32; 3] {
        self.resolution
    }

    /// The grid's box (the scene's, slightly padded).
    #[must_use]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The box of a cell: `(min, max)`.
    #[must_use]
    pub fn cell_box(&self, c: [u32; 3]) -> (DVec3, DVec3) {
        let lo = self.bounds.min
            + self.cell_size * DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]));
        let hi = self.bounds.min
            + self.cell_size
                * DVec3::new(
                    f64::from(c[0] + 1),
                    f64::from(c[1] + 1),
                    f64::from(c[2] + 1),
                );
        (lo, hi)
    }

    /// The triangles (indices into the [`SceneTriangles`] it was built from) of a cell.
    #[must_use]
    pub fn cell_triangles(&self, c: [u32; 3]) -> &[u32] {
        let i = self.cell_index(c);
        &self.refs[self.starts[i] as usize..self.starts[i + 1] as usize]
    }

    #[inline]
    fn cell_index(&self, c: [u32; 3]) -> usize {
        (c[2] as usize * self.resolution[1] as usize + c[1] as usize) * self.resolution[0] as usize
            + c[0] as usize
    }

    /// The cell holding `p`, clamped to the grid.
    fn cell_of(&self, p: DVec3) -> [u32; 3] {
        let q = (p - self.bounds.min) / self.cell_size;
        std::array::from_fn(|k| {
            let f = q[k].floor();
            if f.is_nan() || f < 0.0 {
                0
            } else {
                (f as u64).min(u64::from(self.resolution[k] - 1)) as u32
            }
        })
    }

    /// The nearest hit with `ctx.t_min <= t <= t_max`, walking the cells front to
    /// back and accepting a hit only inside the cell being visited. `triangles` must be
    /// the ones the grid was built from, `mailbox` made for them (one per thread).
    pub fn closest_hit(
        &self,
        triangles: &SceneTriangles,
        ctx: &HitContext<'_>,
        t_max: f64,
        mailbox: &mut Mailbox,
        counters: &mut GridCounters,
    ) -> GridHit {
        struct Run<'a, 'b> {
            grid: &'a UniformGrid,
            triangles: &'a SceneTriangles,
            ctx: &'a HitContext<'b>,
            t_max: f64,
            mailbox: &'a mut Mailbox,
            counters: &'a mut GridCounters,
        }
        impl WithAxisOrder for Run<'_, '_> {
            type Output = GridHit;
            fn run<O: AxisOrder>(self) -> GridHit {
                self.grid.walk::<O>(
                    self.triangles,
                    self.ctx,
                    self.t_max,
                    self.mailbox,
                    self.counters,
                )
            }
        }
        ctx.ray.dispatch(Run {
            grid: self,
            triangles,
            ctx,
            t_max,
            mailbox,
            counters,
        })
    }

    fn walk<O: AxisOrder>(
        &self,
        triangles: &SceneTriangles,
        ctx: &HitContext<'_>,
        t_max: f64,
        mailbox: &mut Mailbox,
        counters: &mut GridCounters,
    ) -> GridHit {
        let mut out = GridHit {
            hit: ClosestHit::new(t_max),
            cell: None,
        };
        if self.refs.is_empty() {
            return out;
        }
        let (o, d) = (ctx.ray.origin, ctx.ray.direction);
        let (mut t0, mut t1) = (ctx.t_min, t_max);
        for k in 0..3 {
            if !crate::geom::obb::slab(
                o[k],
                d[k],
                self.bounds.min[k],
                self.bounds.max[k],
                &mut t0,
                &mut t1,
            ) {
                return out;
            }
        }
        if !(t0 <= t1) {
            return out;
        }
        let mut cell = self.cell_of(o + d * t0);
        let step: [i64; 3] = std::array::from_fn(|k| {
            if d[k] > 0.0 {
                1
            } else if d[k] < 0.0 {
                -1
            } else {
                0
            }
        });
        // The parameter where the ray leaves the current cell through its face on
        // axis k, from the face's coordinate (not accumulated, so no drift).
        let exit = |k: usize, c: u32| -> f64 {
            match step[k] {
                1 => (self.bounds.min[k] + f64::from(c + 1) * self.cell_size[k] - o[k]) / d[k],
                -1 => (self.bounds.min[k] + f64::from(c) * self.cell_size[k] - o[k]) / d[k],
                _ => f64::INFINITY,
            }
        };
        let mut next = [exit(0, cell[0]), exit(1, cell[1]), exit(2, cell[2])];
        let (verts, polys) = (triangles.vertices(), triangles.triangle_polygons());
        let mut t_enter = t0;
        mailbox.next_ray();
        let ray_id = mailbox.ray;
        loop {
            let t_exit = next[0].min(next[1]).min(next[2]).min(t1).max(t_enter);
            counters.cells += 1;
            for &tri in self.cell_triangles(cell) {
                let slot = tri as usize;
                let t = if mailbox.stamp[slot] == ray_id {
                    counters.mailbox_hits += 1;
                    mailbox.result[slot]
                } else {
                    let poly = polys[tri as usize] as usize;
                    let t = if ctx.ignored[poly] {
                        f64::NAN
                    } else {
                        counters.triangles += 1;
                        ctx.ray
                            .intersect::<O>(&verts[tri as usize], ctx.t_min, t_max, &ctx.tie)
                            .unwrap_or(f64::NAN)
                    };
                    mailbox.stamp[slot] = ray_id;
                    mailbox.result[slot] = t;
                    t
                };
                // The seed's rule: only a hit inside this cell is accepted here.
                if t >= t_enter && t <= t_exit {
                    let before = out.hit;
                    out.hit.offer(t, ctx.faces[polys[tri as usize] as usize]);
                    if out.hit != before {
                        out.cell = Some(cell);
                    }
                }
            }
            if out.hit.is_hit() && out.hit.t < t_exit {
                return out;
            }
            // Step across the nearest face.
            let k = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            if !(next[k] <= t1) {
                return out;
            }
            let c = i64::from(cell[k]) + step[k];
            if c < 0 || c >= i64::from(self.resolution[k]) {
                return out;
            }
            cell[k] = c as u32;
            next[k] = exit(k, cell[k]);
            t_enter = t_exit;
        }
    }
}

/// Cells per axis for `n` triangles in a box of extent `e` (see the module doc).
fn resolution(e: DVec3, n: usize, options: &GridOptions) -> [u32; 3] {
    const MAX_AXIS: f64 = 2048.0;
    let target = (options.density.max(1e-3) * n as f64).clamp(1.0, options.max_cells.max(1) as f64);
    let mut res = [1.0f64; 3];
    let mut active: Vec<usize> = (0..3).filter(|&k| e[k] > 0.0).collect();
    for _ in 0..3 {
        if active.is_empty() {
            break;
        }
        let volume: f64 = active.iter().map(|&k| e[k]).product();
        let k_scale = (target / volume).powf(1.0 / active.len() as f64);
        let mut dropped = false;
        for &k in &active {
            res[k] = (e[k] * k_scale).round();
        }
        active.retain(|&k| {
            if res[k] < 1.0 {
                res[k] = 1.0;
                dropped = true;
                false
            } else {
                true
            }
        });
        if !dropped {
            break;
        }
    }
    let mut res = res.map(|r| r.clamp(1.0, MAX_AXIS));
    while res.iter().product::<f64>() > options.max_cells.max(1) as f64 {
        res = res.map(|r| (r * 0.9).floor().max(1.0));
    }
    res.map(|r| r as u32)
}

/// Whether a triangle overlaps the box `center ± half`, by separating axes
/// (Akenine-Möller 2001): the box normals, the triangle normal, and the 9 cross
/// products of box axes with triangle edges. Touching counts as overlapping.
#[must_use]
pub fn triangle_overlaps_box(tri: &[DVec3; 3], center: DVec3, half: DVec3) -> bool {
    let v = tri.map(|p| p - center);
    for k in 0..3 {
        let lo = v[0][k].min(v[1][k]).min(v[2][k]);
        let hi = v[0][k].max(v[1][k]).max(v[2][k]);
        if lo > half[k] || hi < -half[k] {
            return false;
        }
    }
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let normal = edges[0].cross(edges[1]);
    if normal.dot(v[0]).abs() > half.dot(normal.abs()) {
        return false;
    }
    for e in edges {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            let a = axis.cross(e);
            let p = [a.dot(v[0]), a.dot(v[1]), a.dot(v[2])];
            let r = half.dot(a.abs());
            let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
            if lo > r || hi < -r {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo::SplitMix64;

    #[test]
    fn triangle_box_overlap_agrees_with_sampling() {
        // Brute force: sample points of the triangle densely; if one falls inside the
        // box they overlap (the SAT must say so); if the SAT says no, none may.
        let mut rng = SplitMix64(21);
        let (mut yes, mut no) = (0, 0);
        for _ in 0..3000 {
            let tri = [0; 3].map(|_| {
                DVec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                )
            });
            let half = DVec3::new(
                rng.range(0.1, 0.8),
                rng.range(0.1, 0.8),
                rng.range(0.1, 0.8),
            );
            let sat = triangle_overlaps_box(&tri, DVec3::ZERO, half);
            let steps = 60;
            let mut sampled = false;
            'outer: for a in 0..=steps {
                for b in 0..=steps - a {
                    let (u, v) = (
                        f64::from(a) / f64::from(steps),
                        f64::from(b) / f64::from(steps),
                    );
                    let p = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
                    if p.abs().cmple(half).all() {
                        sampled = true;
                        break 'outer;
                    }
                }
            }
            if sampled {
                assert!(sat, "{tri:?} {half:?}");
            }
            if sat { yes += 1 } else { no += 1 }
        }
        assert!(yes > 300 && no > 300, "{yes} {no}");
        // A triangle crossing a box diagonally without any vertex inside.
        let big = [
            DVec3::new(-5.0, -5.0, 0.0),
            DVec3::new(5.0, -5.0, 0.0),
            DVec3::new(0.0, 5.0, 0.0),
        ];
        assert!(triangle_overlaps_box(&big, DVec3::ZERO, DVec3::splat(0.1)));
        // Its plane misses a box above it.
        assert!(!triangle_overlaps_box(
            &big,
            DVec3::new(0.0, 0.0, 0.5),
            DVec3::splat(0.1)
        ));
    }

    #[test]
    fn resolution_follows_the_heuristic() {
        let o = GridOptions::default();
        // A cube of 1000 triangles: 2000 cells, about 12.6 per axis.
        assert_eq!(resolution(DVec3::ONE, 1000, &o), [13, 13, 13]);
        // A flat square: 2 * 800 cells in 2D, 40 x 40 x 1.
        assert_eq!(resolution(DVec3::new(2.0, 0.0, 2.0), 800, &o), [40, 1, 40]);
        // Long and thin: the thin axes get one cell, the long one all of them.
        assert_eq!(
            resolution(DVec3::new(100.0, 0.01, 0.01), 50, &o),
            [100, 1, 1]
        );
        let capped = GridOptions {
            max_cells: 1000,
            ..o
        };
        let r = resolution(DVec3::ONE, 1_000_000, &capped);
        assert!(r.iter().map(|&x| x as usize).product::<usize>() <= 1000);
    }

    #[test]
    fn every_triangle_is_in_the_cells_it_overlaps() {
        let scene = crate::scene::demo::default_scene();
        let tris = SceneTriangles::new(&scene);
        let grid = UniformGrid::build(&tris, &GridOptions::default());
        let [nx, ny, nz] = grid.resolution();
        assert_eq!(grid.stats().cells, (nx * ny * nz) as usize);
        let mut listed = vec![0u32; tris.len()];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    for &t in grid.cell_triangles([x, y, z]) {
                        listed[t as usize] += 1;
                    }
                }
            }
        }
        assert_eq!(
            listed.iter().map(|&c| c as usize).sum::<usize>(),
            grid.stats().refs
        );
        // Every triangle is listed in the cell of each of its vertices and of points
        // inside it (cells found independently, from the cell boxes).
        let b = grid.bounds();
        let size = b.extent() / DVec3::new(f64::from(nx), f64::from(ny), f64::from(nz));
        let mut rng = SplitMix64(8);
        for (t, tri) in tris.vertices().iter().enumerate().step_by(7) {
            let (u, v) = (rng.next_f64() * 0.5, rng.next_f64() * 0.5);
            let inner = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
            for p in [tri[0], tri[1], tri[2], inner] {
                let c = ((p - b.min) / size).floor();
                let cell = [c.x as u32, c.y as u32, c.z as u32];
                let (lo, hi) = grid.cell_box(cell);
                assert!(p.cmpge(lo - size * 1e-9).all() && p.cmple(hi + size * 1e-9).all());
                assert!(
                    grid.cell_triangles(cell).contains(&(t as u32)),
                    "triangle {t} not in {cell:?}"
                );
            }
        }
        assert!(listed.iter().all(|&c| c >= 1));
    }
}
