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
//! cross products). Cells are grown for this test by `10^-7` of their size or by
//! `4 τ` (below), whichever is larger, so a triangle touching a cell's face is in
//! both cells and rounding in the traversal cannot lose it.
//!
//! # Traversal
//! The ray is clipped to the grid's box grown by `τ` and to `[t_min, t_max]`, and
//! walks the cells it crosses. A hit on a triangle of the cell is accepted only if it
//! lies in that cell grown by `τ` (its parameter is within the ray's interval in the
//! grown cell, from the cell's faces on each axis: `[entry_k - τ/|d_k|, exit_k +
//! τ/|d_k|]`): a hit in a later cell is refused there (and accepted in its own cell,
//! which the triangle also occupies). The walk stops after the first cell whose nearest
//! hit lies before the exit of the cell shrunk by `τ` (a triangle met in a later cell
//! is hit there or farther; at or after that point, a later cell may still offer a
//! nearer hit or an equal-distance one with a lower face id).
//!
//! # Rounding
//! The hit parameter and the faces' parameters are rounded values, with errors that
//! grow with the coordinates involved, not with the cells: the watertight test
//! subtracts the origin from the vertices and the walk subtracts it from the faces'
//! coordinates, each exact to about `4 ε` of `|o|∞ + |bounds|∞` as a position along
//! the ray (`ε` the `f64` epsilon). A cell can be far thinner than that: a flat scene's
//! box is a padding thick (`10^-6` of its extent), and a scene 1 across seen from
//! `10^11` away or 10^-10 across seen from 5 away has cells below the spacing of the
//! ray's parameters. Comparing the parameters exactly then lost hits that fall, by
//! rounding, just outside every cell (half the pixels of a flat triangle in such
//! views). So hits are accepted within `τ = 64 ε (|o|∞ + |bounds|∞)` of the cell
//! ([`ROUNDING`]): twice the two errors above with a factor 4 to spare for the test's
//! edge functions. `τ` is a relative bound, a few hundred units in the last place of
//! the largest coordinate: it cannot accept a hit the exact walk would place in a
//! distant cell, and since the stopping point is moved back by the same `τ`, no nearer
//! hit in a later cell is missed.
//!
//! Accepting within `τ` is only safe if the triangle is listed in the cell, so the
//! binning grows cells by `4 τ` for the largest origin the grid is built for
//! ([`GridOptions::ray_origins`], which the renderer sets from the camera), and no
//! cell is made finer than `1024 τ` (finer cells could not be told apart by the rays).
//! A ray from an origin farther than the grid was built for (its `τ` more than a
//! quarter of the growth) is traced against every triangle instead, and counted
//! ([`GridCounters::far_rays`]).
//!
//! Mailboxing (Amanatides and Woo): a triangle spanning several cells would be tested
//! again in each. A per-thread [`Mailbox`] keeps, per triangle, the ray that tested it
//! last and the result — the hit parameter over the whole ray, or none — so a triangle
//! met again by the same ray is not re-tested; the cell rule is applied to the
//! remembered parameter, which is exactly what a new test would give.
//!
//! - Complexity: build O(N + refs); a ray visits O(n_x + n_y + n_z) cells at worst.
//! - Limitations: uniform cells suit uniformly spread scenes and waste memory and steps
//!   on uneven ones ("teapot in a stadium"): a 160k-triangle sphere of radius 1 on a
//!   ground 1000 wide gets 503 x 1 x 503 cells of 2 units, its triangles fall in a few
//!   of them, and each ray that meets it tests about 25,000 triangles (2.8 s at
//!   160x120, where the BVH takes 2 triangle tests a ray). [`GridStats::largest_cell`]
//!   shows it, and the CLI says so. The mailbox costs 12 bytes per triangle per
//!   thread.

use std::time::Instant;

use glam::DVec3;

use crate::accel::triangles::{AxisOrder, ClosestHit, HitContext, SceneTriangles, WithAxisOrder};
use crate::clip::sutherland_hodgman::clip_polygon_box_into;
use crate::geom::Aabb;

/// Grid parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct GridOptions {
    /// Target cells per triangle (λ).
    pub density: f64,
    /// The most cells allowed.
    pub max_cells: usize,
    /// The largest coordinate (absolute value) of the origins of the rays the grid will
    /// trace: cells are grown and sized for their rounding (see "Rounding" in the
    /// module doc). Rays from farther origins are traced against every triangle.
    pub ray_origins: f64,
}

impl GridOptions {
    /// These options with another density (cells per triangle).
    #[must_use]
    pub fn with_density(mut self, density: f64) -> Self {
        self.density = density;
        self
    }

    /// These options for rays whose origins have coordinates up to `magnitude` in
    /// absolute value.
    #[must_use]
    pub(crate) fn with_ray_origins(mut self, magnitude: f64) -> Self {
        self.ray_origins = magnitude;
        self
    }
}

impl Default for GridOptions {
    fn default() -> Self {
        GridOptions {
            density: 2.0,
            max_cells: 1 << 24,
            ray_origins: 0.0,
        }
    }
}

/// The rounding bound of the traversal, relative to the coordinates involved: a ray
/// from `o` locates its hits and the cells' faces to within
/// `τ = ROUNDING (|o|∞ + |bounds|∞)` (see "Rounding" in the module doc).
pub const ROUNDING: f64 = 64.0 * f64::EPSILON;

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
    /// The most triangles any one cell holds (far above the average when a small dense
    /// object sits in a large scene: see the module doc's limitations).
    pub largest_cell: usize,
}

/// A uniform grid (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct UniformGrid {
    bounds: Aabb,
    /// `|bounds|∞`, the largest coordinate of the box in absolute value.
    magnitude: f64,
    /// The largest rounding bound `τ` the binning covers (a quarter of its growth).
    max_tau: f64,
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
    /// Rays from origins too far for the grid's cells (beyond
    /// [`GridOptions::ray_origins`]), traced against every triangle.
    pub far_rays: u64,
}

impl std::ops::AddAssign for GridCounters {
    fn add_assign(&mut self, o: Self) {
        self.cells += o.cells;
        self.triangles += o.triangles;
        self.mailbox_hits += o.mailbox_hits;
        self.far_rays += o.far_rays;
    }
}

/// The result of a grid traversal: the nearest hit and the cell it was accepted in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridHit {
    /// The nearest hit.
    pub hit: ClosestHit,
    /// The cell `(x, y, z)` where it was accepted (`None` without a hit, or for a
    /// ray traced against every triangle, see [`GridCounters::far_rays`]).
    pub cell: Option<[u32; 3]>,
}

/// The box of a clipped polygon (`None` when the clip left nothing).
fn extent(points: &[DVec3]) -> Option<(DVec3, DVec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    )
}

/// The structure named by the grid's budget errors.
pub(crate) const GRID_STRUCTURE: &str = "ray-casting grid cell references";

impl UniformGrid {
    /// Builds the grid over the triangles.
    #[must_use]
    pub fn build(triangles: &SceneTriangles, options: &GridOptions) -> Self {
        // No grid passes u64::MAX bytes: the build cannot fail on the budget.
        let unbounded = crate::budget::MemoryBudget::new(u64::MAX);
        Self::build_with_budget(triangles, options, &unbounded).unwrap_or_default()
    }

    /// [`UniformGrid::build`] held to a memory budget (see [`crate::budget`]): the
    /// (cell, triangle) references are counted as they are made (large triangles
    /// spanning many cells multiply them) and the build stops with an
    /// [`crate::Error::Budget`] when they, the cell table and the sorted references
    /// would pass it.
    pub(crate) fn build_with_budget(
        triangles: &SceneTriangles,
        options: &GridOptions,
        budget: &crate::budget::MemoryBudget,
    ) -> crate::Result<Self> {
        Self::build_until(
            triangles,
            options,
            budget,
            &crate::work::Deadline::default(),
        )
    }

    /// `UniformGrid::build_with_budget` that also stops with the deadline's error
    /// (see [`crate::work`]) when it passes during the build.
    pub fn build_until(
        triangles: &SceneTriangles,
        options: &GridOptions,
        budget: &crate::budget::MemoryBudget,
        deadline: &crate::work::Deadline,
    ) -> crate::Result<Self> {
        let start = Instant::now();
        let mut grid = UniformGrid::default();
        let n = triangles.len();
        let raw = triangles.bounds();
        if n == 0 || raw.is_empty() || n > u32::MAX as usize {
            grid.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
            return Ok(grid);
        }
        // Pad so that triangles on the boundary are inside and flat scenes get a
        // thickness.
        let e = raw.extent();
        let pad = (e.max_element() * 1e-6)
            .max(raw.magnitude() * 1e-12)
            .max(1e-300);
        let bounds = Aabb {
            min: raw.min - DVec3::splat(pad),
            max: raw.max + DVec3::splat(pad),
        };
        let magnitude = bounds.magnitude();
        // The rounding of the rays the grid is built for; cells no finer than 1024 of
        // it, so that growing them by 4 of it (below) keeps them nearly disjoint.
        let tau = ROUNDING * (options.ray_origins.abs() + magnitude);
        let resolution = resolution(bounds.extent(), n, options, 1024.0 * tau);
        let cell_size = bounds.extent()
            / DVec3::new(
                f64::from(resolution[0]),
                f64::from(resolution[1]),
                f64::from(resolution[2]),
            );
        grid.bounds = bounds;
        grid.magnitude = magnitude;
        grid.resolution = resolution;
        grid.cell_size = cell_size;
        let cells = resolution.iter().map(|&r| r as usize).product::<usize>();
        // (cell, triangle) pairs, then a counting sort by cell.
        let grow = (cell_size * 1e-7).max(DVec3::splat(4.0 * tau));
        grid.max_tau = grow.min_element() * 0.25;
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(n * 2);
        // Adds a (cell, triangle) pair, held to the budget as the vector grows: the
        // pairs (8 bytes, doubled by the growth), their sorted copy (4) and the two
        // cell tables.
        let push_pair = |pairs: &mut Vec<(u32, u32)>, cell: u32, t: u32| {
            if pairs.len() == pairs.capacity() {
                let count = pairs.len() as u64;
                let bytes = count * (16 + 4) + (cells as u64 + 1) * 8;
                budget.check(GRID_STRUCTURE, count, bytes)?;
                crate::budget::try_grow(budget, GRID_STRUCTURE, pairs, 1)?;
            }
            pairs.push((cell, t));
            Ok::<(), crate::Error>(())
        };
        let (mut piece, mut part, mut scratch) = (Vec::new(), Vec::new(), Vec::new());
        for (t, tri) in triangles.vertices().iter().enumerate() {
            // Once per triangle: a large one meets millions of cells.
            deadline.check("ray-casting grid construction")?;
            let lo = tri[0].min(tri[1]).min(tri[2]) - grow;
            let hi = tri[0].max(tri[1]).max(tri[2]) + grow;
            let c0 = grid.cell_of(lo);
            let c1 = grid.cell_of(hi);
            // Cells met: per layer of cells along z, the triangle clipped to the layer;
            // per row of that layer along y, the piece clipped to the row; its x extent
            // gives the row's cells. The same cells as testing each cell of the box
            // (the separating-axis test with the cells grown by `grow`), in time
            // proportional to the cells met rather than to the box's cells; the
            // layers and rows are widened a little more than `grow`, so that rounding
            // of the clipped vertices can only add cells, never lose one.
            if c0 == c1 {
                push_pair(&mut pairs, grid.cell_index(c0) as u32, t as u32)?;
                continue;
            }
            let wide = grow * 1.5;
            for z in c0[2]..=c1[2] {
                let (zmin, zmax) = grid.cell_box([c0[0], c0[1], z]);
                let layer = Aabb {
                    min: DVec3::new(lo.x - wide.x, lo.y - wide.y, zmin.z - wide.z),
                    max: DVec3::new(hi.x + wide.x, hi.y + wide.y, zmax.z + wide.z),
                };
                clip_polygon_box_into(tri, &layer, &mut piece, &mut scratch);
                let Some((plo, phi)) = extent(&piece) else {
                    continue;
                };
                let (y0, y1) = (grid.cell_of(plo - wide)[1], grid.cell_of(phi + wide)[1]);
                for y in y0.max(c0[1])..=y1.min(c1[1]) {
                    let (ymin, ymax) = grid.cell_box([c0[0], y, z]);
                    let row = Aabb {
                        min: DVec3::new(plo.x - wide.x, ymin.y - wide.y, plo.z - wide.z),
                        max: DVec3::new(phi.x + wide.x, ymax.y + wide.y, phi.z + wide.z),
                    };
                    clip_polygon_box_into(&piece, &row, &mut part, &mut scratch);
                    let Some((rlo, rhi)) = extent(&part) else {
                        continue;
                    };
                    let (x0, x1) = (grid.cell_of(rlo - wide)[0], grid.cell_of(rhi + wide)[0]);
                    for x in x0.max(c0[0])..=x1.min(c1[0]) {
                        push_pair(&mut pairs, grid.cell_index([x, y, z]) as u32, t as u32)?;
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
            largest_cell: starts
                .windows(2)
                .map(|w| (w[1] - w[0]) as usize)
                .max()
                .unwrap_or(0),
        };
        grid.starts = starts;
        grid.refs = refs;
        grid.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(grid)
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
        // The ray's rounding (see "Rounding" in the module doc).
        let tau = self.rounding(o);
        if !(tau <= self.max_tau) {
            counters.far_rays += 1;
            return self.every_triangle::<O>(triangles, ctx, t_max, counters);
        }
        let (mut t0, mut t1) = (ctx.t_min, t_max);
        for k in 0..3 {
            if !crate::geom::slab::slab(
                o[k],
                d[k],
                self.bounds.min[k] - tau,
                self.bounds.max[k] + tau,
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
        // The parameter where the ray enters the current cell's slab on axis k.
        let entry = |k: usize, c: u32| -> f64 {
            match step[k] {
                1 => (self.bounds.min[k] + f64::from(c) * self.cell_size[k] - o[k]) / d[k],
                -1 => (self.bounds.min[k] + f64::from(c + 1) * self.cell_size[k] - o[k]) / d[k],
                _ => f64::NEG_INFINITY,
            }
        };
        // The slack `τ / |d_k|` that grows the cell by `τ` on axis k, in ray parameter
        // (none on an axis the ray is parallel to: its slab is unbounded).
        let slack: [f64; 3] =
            std::array::from_fn(|k| if step[k] == 0 { 0.0 } else { tau / d[k].abs() });
        let mut next = [exit(0, cell[0]), exit(1, cell[1]), exit(2, cell[2])];
        // The ray's interval in the current cell grown by `τ`: `[max lo, min hi]`.
        let mut lo: [f64; 3] = std::array::from_fn(|k| entry(k, cell[k]) - slack[k]);
        let mut hi: [f64; 3] = std::array::from_fn(|k| next[k] + slack[k]);
        let (verts, polys) = (triangles.vertices(), triangles.triangle_polygons());
        mailbox.next_ray();
        let ray_id = mailbox.ray;
        loop {
            let t_enter = lo[0].max(lo[1]).max(lo[2]);
            let t_exit = hi[0].min(hi[1]).min(hi[2]);
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
                // The seed's rule: only a hit inside this cell (grown by `τ`) is
                // accepted here.
                if t >= t_enter && t <= t_exit {
                    let before = out.hit;
                    out.hit.offer(t, ctx.faces[polys[tri as usize] as usize]);
                    if out.hit != before {
                        out.cell = Some(cell);
                    }
                }
            }
            // Done when the hit is nearer than any point beyond the cell (shrunk by
            // `τ`) can be: a triangle met later has its hit there or farther.
            if out.hit.is_hit()
                && out.hit.t
                    < (next[0] - slack[0])
                        .min(next[1] - slack[1])
                        .min(next[2] - slack[2])
            {
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
            lo[k] = next[k] - slack[k];
            next[k] = exit(k, cell[k]);
            hi[k] = next[k] + slack[k];
        }
    }

    /// The nearest hit by testing every triangle, for a ray whose rounding the cells
    /// do not cover.
    #[cold]
    fn every_triangle<O: AxisOrder>(
        &self,
        triangles: &SceneTriangles,
        ctx: &HitContext<'_>,
        t_max: f64,
        counters: &mut GridCounters,
    ) -> GridHit {
        let hit = ctx.closest_of_all::<O>(triangles, t_max, &mut counters.triangles);
        GridHit { hit, cell: None }
    }

    /// The rounding bound `τ` of a ray from `origin` (see "Rounding" in the module
    /// doc): its hits are accepted in a cell when they lie in the cell grown by `τ`.
    #[must_use]
    pub fn rounding(&self, origin: DVec3) -> f64 {
        ROUNDING * (origin.abs().max_element() + self.magnitude)
    }

    /// Whether rays from origins with coordinates up to `magnitude` (absolute value)
    /// walk the cells (rather than being traced against every triangle, see
    /// [`GridCounters::far_rays`]): the grid was built for such origins or farther.
    #[must_use]
    pub(crate) fn serves_origins(&self, magnitude: f64) -> bool {
        self.refs.is_empty() || self.rounding(DVec3::splat(magnitude)) <= self.max_tau
    }
}

/// Cells per axis for `n` triangles in a box of extent `e` (see the module doc), none
/// smaller than `min_cell` where the axis allows more than one.
fn resolution(e: DVec3, n: usize, options: &GridOptions, min_cell: f64) -> [u32; 3] {
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
    let mut res: [f64; 3] = std::array::from_fn(|k| {
        let finest = if min_cell > 0.0 {
            (e[k] / min_cell).floor()
        } else {
            MAX_AXIS
        };
        res[k].min(finest).clamp(1.0, MAX_AXIS)
    });
    while res.iter().product::<f64>() > options.max_cells.max(1) as f64 {
        res = res.map(|r| (r * 0.9).floor().max(1.0));
    }
    res.map(|r| r as u32)
}

/// Whether a triangle overlaps the box `center ± half`, by separating axes
/// (Akenine-Möller 2001): the box normals, the triangle normal, and the 9 cross
/// products of box axes with triangle edges. Touching counts as overlapping. The
/// oracle of the tests that check the build's clipped layers and rows.
#[cfg(test)]
#[must_use]
pub(crate) fn triangle_overlaps_box(tri: &[DVec3; 3], center: DVec3, half: DVec3) -> bool {
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
    use crate::rng::SplitMix64;

    #[test]
    fn every_cell_a_triangle_meets_lists_it() {
        // Brute force: each cell of each triangle's box tested with the separating axes
        // (the cell grown as the build grows it) must list the triangle; the cells
        // listed beyond those are few (the build's margin).
        for (seed, size) in [(1, 0.3), (2, 1.5), (3, 4.0)] {
            let scene = crate::scene::random::random_triangles(300, seed, 2.0, size);
            let triangles = SceneTriangles::new(&scene);
            let grid = UniformGrid::build(&triangles, &GridOptions::default());
            let [rx, ry, rz] = grid.resolution();
            let grow = (grid.cell_size * 1e-7).max(DVec3::splat(grid.max_tau * 4.0));
            let (mut needed, mut listed) = (0usize, 0usize);
            for z in 0..rz {
                for y in 0..ry {
                    for x in 0..rx {
                        let (lo, hi) = grid.cell_box([x, y, z]);
                        let list = grid.cell_triangles([x, y, z]);
                        listed += list.len();
                        for (t, tri) in triangles.vertices().iter().enumerate() {
                            if triangle_overlaps_box(tri, (lo + hi) * 0.5, (hi - lo) * 0.5 + grow) {
                                needed += 1;
                                assert!(
                                    list.contains(&(t as u32)),
                                    "seed {seed}: cell {x},{y},{z} misses triangle {t}"
                                );
                            }
                        }
                    }
                }
            }
            assert!(
                needed > 0 && listed <= needed + needed / 10,
                "{listed} vs {needed}"
            );
        }
    }

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
        assert_eq!(resolution(DVec3::ONE, 1000, &o, 0.0), [13, 13, 13]);
        // A flat square: 2 * 800 cells in 2D, 40 x 40 x 1.
        assert_eq!(
            resolution(DVec3::new(2.0, 0.0, 2.0), 800, &o, 0.0),
            [40, 1, 40]
        );
        // Long and thin: the thin axes get one cell, the long one all of them.
        assert_eq!(
            resolution(DVec3::new(100.0, 0.01, 0.01), 50, &o, 0.0),
            [100, 1, 1]
        );
        let capped = GridOptions {
            max_cells: 1000,
            ..o
        };
        let r = resolution(DVec3::ONE, 1_000_000, &capped, 0.0);
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
