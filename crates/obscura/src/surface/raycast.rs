//! Ray casting: one ray per pixel centre, the nearest face it hits — four ways.
//!
//! Sources: seed 000 "Αλγόριθμος Εκπομπής Ακτίνων (1)-(2)" (for each pixel a ray from
//! the viewpoint; the nearest of its intersections with all primitives is the visible
//! one; O(pP)), "Περιβάλλοντες Όγκοι (1)-(7)" and "Υποδιαίρεση Χώρου"; seed 002 "Ray
//! Casting" (bounding volumes, hierarchies, a uniform grid walked front to back).
//!
//! # The independent check
//! Rays are generated from the [`Camera`](crate::Camera) in world space
//! ([`crate::scene::Camera::ray`] through `(i + 0.5, j + 0.5)`), not from the prepared
//! view's screen polygons: the scene's world-space triangles, the camera and the
//! view's culling decisions are all this module uses of the [`View`], so agreeing with the
//! z-buffer checks the whole pipeline (transforms, clipping, projection, coverage).
//!
//! - Perspective rays have `direction · forward = 1`, so the ray parameter `t` *is* the
//!   eye-space depth; orthographic rays start on the eye plane with the unit forward
//!   direction. Hits are accepted for `near <= t <= far` (the clipping planes).
//! - Culling: the faces the view culls ([`View::culled_polygons`]: back faces, and
//!   the faces of objects outside the frustum) are ignored. The view decides them
//!   once, for every algorithm; rays never re-derive them.
//! - Ties: nearer wins; at exactly the same `t` the lower face id.
//! - Faces are fan-triangulated; the watertight `f64` test
//!   ([`crate::accel::triangles`]) decides rays through edges by the top-left rule, so
//!   no ray slips between two triangles and pixel centres exactly on an edge go to the
//!   same face as in the z-buffer.
//!
//! # The four accelerations
//! | variant | per ray | stats |
//! | --- | --- | --- |
//! | [`Acceleration::BruteForce`] | every triangle (the seeds' `RayCasting`) | triangle tests |
//! | [`Acceleration::Bounds`] | each object's bounding volume, then the triangles of the objects hit, nearest volume first, stopping at a volume behind the nearest hit | bound tests and hits, tests saved |
//! | [`Acceleration::Bvh`] | [`crate::accel::bvh`]: binned-SAH hierarchy, ordered traversal of packets of 4x4 rays (`accel/bvh/packet.rs`) | build, nodes, depth, node visits per ray and per packet, Mrays/s |
//! | [`Acceleration::Grid`] | [`crate::accel::grid`]: uniform grid, 3D-DDA, hits accepted only in the current cell | cells, refs, cells per ray |
//!
//! All four run the same exact test on the same triangles, so they return the same
//! frame; they differ only in how many tests they need.
//!
//! - Input: a [`View`] (for its scene, camera, viewport and culling decisions); the
//!   triangles and the BVH or grid are built per call by [`render`], once per scene by
//!   [`render_indexed`] (a [`SceneIndex`]).
//!   Output: a [`Frame`] (face id and eye-space depth `t` as `f32`) and the variant's
//!   stats ([`RaycastStats`], [`RaycastBoundsStats`], [`RaycastBvhStats`],
//!   [`RaycastGridStats`]).
//! - Complexity: brute force O(p T) for p pixels and T triangles; bounds O(p (K + T_hit))
//!   for K objects; BVH about O(p log T); grid O(p (cells per ray + refs per cell)).
//! - Order and parallelism: pixels are traced in 8x8 tiles (neighbouring rays visit the
//!   same nodes and triangles, which stay in cache; the BVH traces each tile as four
//!   packets of 4x4 rays, each ray still getting its own exact hit); bands of 8 rows
//!   are the unit of work, run on rayon's current pool with the `parallel` feature
//!   (the CLI's `--threads`; 1 is single-threaded), sequentially without it.
//! - Limitations: one sample per pixel (no anti-aliasing); the depth is the hit's `t`,
//!   not the rasterizers' interpolated key, so depths agree with the z-buffer's to
//!   `f32` rounding, not bit for bit.

use std::ops::AddAssign;
use std::time::Instant;

use glam::DVec3;

use crate::accel::bvh::Bvh;
use crate::accel::bvh::packet::{PACKET, PACKET_SIDE, PacketContext, PacketStack, RayPacket};
use crate::accel::bvh::traverse::TraceCounters;
use crate::accel::grid::{GridCounters, GridOptions, Mailbox, UniformGrid};
use crate::accel::triangles::{
    AxisOrder, ClosestHit, HitContext, PrimaryRays, SceneTriangles, WatertightRay, WithAxisOrder,
};
use crate::geom::{Aabb, BoundsKind, Kdop, KdopKind, Obb, RaySlabs, Sphere};
use crate::index::SceneIndex;
use crate::surface::RenderOptions;
use crate::surface::stats::{
    AlgorithmStats, RayStats, RaycastBoundsStats, RaycastBvhStats, RaycastGridStats, RaycastStats,
};
use crate::view::View;
use crate::{Frame, Result};

/// How rays find the faces they may hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acceleration {
    /// Every ray against every face.
    BruteForce,
    /// Per-object bounding volumes first.
    Bounds(BoundsKind),
    /// A bounding-volume hierarchy.
    Bvh,
    /// A uniform grid.
    Grid,
}

/// What the rays did, summed over all of them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounters {
    /// Rays cast.
    pub rays: u64,
    /// Rays that hit a face.
    pub hits: u64,
    /// Bounding volumes tested (bounds variant), or BVH nodes visited.
    pub bound_tests: u64,
    /// Bounding volumes a ray met (bounds variant).
    pub bound_hits: u64,
    /// Exact triangle tests.
    pub triangle_tests: u64,
    /// Grid cells visited.
    pub cells: u64,
    /// Grid hits whose point is not inside the cell that accepted them (must stay 0).
    pub hits_outside_cell: u64,
    /// Grid tests answered by the mailbox.
    pub mailbox_hits: u64,
    /// Grid rays from origins too far for its cells, traced against every triangle.
    pub far_rays: u64,
    /// BVH nodes visited by packets of rays (each counts once for the packet).
    pub packet_nodes: u64,
}

impl AddAssign for RayCounters {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.bound_tests += o.bound_tests;
        self.bound_hits += o.bound_hits;
        self.triangle_tests += o.triangle_tests;
        self.cells += o.cells;
        self.hits_outside_cell += o.hits_outside_cell;
        self.mailbox_hits += o.mailbox_hits;
        self.far_rays += o.far_rays;
        self.packet_nodes += o.packet_nodes;
    }
}

/// Renders by casting one ray per pixel from the camera in world space; the
/// triangles and the hierarchy or grid are built for this call (see
/// [`render_indexed`] to build them once per scene).
pub fn render(
    view: &View<'_>,
    acceleration: Acceleration,
    options: &RenderOptions,
) -> Result<(Frame, AlgorithmStats)> {
    render_indexed(&SceneIndex::new(view.scene()), view, acceleration, options)
}

/// [`render`] with the triangles, hierarchy and grid of a scene index (built on first
/// use, then shared by every view).
pub fn render_indexed(
    index: &SceneIndex<'_>,
    view: &View<'_>,
    acceleration: Acceleration,
    options: &RenderOptions,
) -> Result<(Frame, AlgorithmStats)> {
    let (triangles, soup_ms) = index.triangles_timed();
    let triangles_ms = Some(*soup_ms);
    Ok(match acceleration {
        Acceleration::BruteForce => {
            let (frame, s) = render_brute_force(view, triangles, options)?;
            (
                frame,
                AlgorithmStats::Raycast(RaycastStats { triangles_ms, ..s }),
            )
        }
        Acceleration::Bounds(kind) => {
            let (frame, s) = render_bounds(view, triangles, kind, options)?;
            let s = RaycastBoundsStats { triangles_ms, ..s };
            (frame, AlgorithmStats::RaycastBounds(s))
        }
        Acceleration::Bvh => {
            let (frame, s) = render_bvh(view, triangles, index.bvh(), options)?;
            (
                frame,
                AlgorithmStats::RaycastBvh(RaycastBvhStats { triangles_ms, ..s }),
            )
        }
        Acceleration::Grid => {
            // Cells sized for the rounding of this view's rays (see `accel::grid`).
            let origins = PrimaryRays::new(view.camera(), view.viewport()).origin_magnitude();
            let grid = index.grid(
                &GridOptions::default().with_ray_origins(origins),
                &options.budget(),
                &options.deadline,
            )?;
            let (frame, s) = render_grid(view, triangles, &grid, options)?;
            (
                frame,
                AlgorithmStats::RaycastGrid(RaycastGridStats { triangles_ms, ..s }),
            )
        }
    })
}

/// Brute force: every ray against every triangle (seed 000's `RayCasting`).
pub(crate) fn render_brute_force(
    view: &View<'_>,
    triangles: &SceneTriangles,
    options: &RenderOptions,
) -> Result<(Frame, RaycastStats)> {
    struct Run<'a, 'b> {
        ctx: &'a HitContext<'b>,
        triangles: &'a SceneTriangles,
        far: f64,
        counters: &'a mut RayCounters,
    }
    impl WithAxisOrder for Run<'_, '_> {
        type Output = ClosestHit;
        fn run<O: AxisOrder>(self) -> ClosestHit {
            self.ctx.closest_of_all::<O>(
                self.triangles,
                self.far,
                &mut self.counters.triangle_tests,
            )
        }
    }
    let setup = Setup::new(view, triangles, options)?;
    let start = Instant::now();
    let (frame, counters) = setup.cast(options, |ctx, counters| {
        ctx.ray.dispatch(Run {
            ctx,
            triangles,
            far: setup.rays.far,
            counters,
        })
    })?;
    let stats = RaycastStats {
        ray: setup.stats(&counters, ms_since(start)),
        triangle_tests_per_ray: per(counters.triangle_tests, counters.rays),
        triangles_ms: None,
    };
    Ok((frame, stats))
}

/// A bounding volume of one object, grown by a small margin so rounding in its ray
/// test cannot lose a hit on a triangle that touches it.
#[derive(Clone, Copy, Debug)]
enum ObjectBound {
    Sphere(Sphere),
    Aabb(Aabb),
    Obb(Obb),
    Kdop(Kdop),
}

impl ObjectBound {
    fn new(kind: BoundsKind, points: &[DVec3], margin: f64) -> Option<Self> {
        Some(match kind {
            BoundsKind::Sphere => {
                let s = Sphere::bounding(points)?;
                ObjectBound::Sphere(Sphere {
                    center: s.center,
                    radius: s.radius + margin,
                })
            }
            BoundsKind::Aabb => {
                let b = Aabb::from_points(points.iter().copied());
                if b.is_empty() {
                    return None;
                }
                ObjectBound::Aabb(Aabb {
                    min: b.min - DVec3::splat(margin),
                    max: b.max + DVec3::splat(margin),
                })
            }
            BoundsKind::Obb => ObjectBound::Obb(Obb::from_points(points)?.expanded(margin)),
            BoundsKind::Kdop => {
                ObjectBound::Kdop(Kdop::from_points(points, KdopKind::K26)?.expanded(margin))
            }
        })
    }

    /// The ray's interval inside the volume; `slabs` are the ray's projections on the
    /// k-DOP directions (the first three are the axes), computed once per ray.
    fn interval(&self, o: DVec3, d: DVec3, slabs: &RaySlabs) -> Option<(f64, f64)> {
        match self {
            ObjectBound::Sphere(s) => s.ray_interval(o, d),
            ObjectBound::Aabb(b) => b.ray_interval_projected(slabs),
            ObjectBound::Obb(b) => b.ray_interval(o, d),
            ObjectBound::Kdop(k) => k.ray_interval_projected(slabs),
        }
    }
}

/// Per-object bounding volumes tested first (seed 000 "Περιβάλλοντες Όγκοι (1)-(4)",
/// seed 002 "Ottimizzazione dei calcoli di intersezione"): a ray that misses an
/// object's volume cannot hit the object. The objects whose volume it meets are tested
/// nearest volume first, and the search stops at a volume that starts behind the
/// nearest hit found.
pub(crate) fn render_bounds(
    view: &View<'_>,
    triangles: &SceneTriangles,
    kind: BoundsKind,
    options: &RenderOptions,
) -> Result<(Frame, RaycastBoundsStats)> {
    struct Run<'a, 'b> {
        ctx: &'a HitContext<'b>,
        triangles: &'a SceneTriangles,
        bounds: &'a [(u32, ObjectBound)],
        candidates: &'a mut Vec<(f64, u32)>,
        far: f64,
        counters: &'a mut RayCounters,
    }
    impl WithAxisOrder for Run<'_, '_> {
        type Output = ClosestHit;
        fn run<O: AxisOrder>(self) -> ClosestHit {
            let (o, d) = (self.ctx.ray.origin, self.ctx.ray.direction);
            let slabs = RaySlabs::new(o, d);
            self.candidates.clear();
            for &(k, ref b) in self.bounds {
                self.counters.bound_tests += 1;
                if let Some((t0, t1)) = b.interval(o, d, &slabs)
                    && t1 >= self.ctx.t_min
                    && t0 <= self.far
                {
                    self.counters.bound_hits += 1;
                    self.candidates.push((t0.max(self.ctx.t_min), k));
                }
            }
            self.candidates.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let mut closest = ClosestHit::new(self.far);
            let (verts, polys) = (
                self.triangles.vertices(),
                self.triangles.triangle_polygons(),
            );
            for &(t0, k) in self.candidates.iter() {
                if t0 > closest.t {
                    break;
                }
                let range = self.triangles.object_triangles()[k as usize].clone();
                let range = range.start as usize..range.end as usize;
                for (tri, &poly) in verts[range.clone()].iter().zip(&polys[range]) {
                    self.counters.triangle_tests +=
                        u64::from(self.ctx.test::<O>(tri, poly, self.far, &mut closest));
                }
            }
            closest
        }
    }
    let setup = Setup::new(view, triangles, options)?;
    let build = Instant::now();
    let margin = 1e-9 * setup.scale.max(f64::MIN_POSITIVE);
    let mut points: Vec<DVec3> = Vec::new();
    let bounds: Vec<(u32, ObjectBound)> = triangles
        .object_triangles()
        .iter()
        .enumerate()
        .filter_map(|(k, range)| {
            points.clear();
            points.extend(
                triangles.vertices()[range.start as usize..range.end as usize]
                    .iter()
                    .flatten(),
            );
            ObjectBound::new(kind, &points, margin).map(|b| (k as u32, b))
        })
        .collect();
    let build_ms = ms_since(build);
    let start = Instant::now();
    let (frame, counters) = setup.cast_bands(options, |band, counters| {
        let mut candidates: Vec<(f64, u32)> = Vec::with_capacity(bounds.len());
        setup.cast_band(band, counters, |ctx, counters| {
            ctx.ray.dispatch(Run {
                ctx,
                triangles,
                bounds: &bounds,
                candidates: &mut candidates,
                far: setup.rays.far,
                counters,
            })
        })
    })?;
    let brute = counters.rays * setup.front_triangles;
    let stats = RaycastBoundsStats {
        ray: setup.stats(&counters, ms_since(start)),
        bounds_build_ms: build_ms,
        objects: bounds.len() as u64,
        bound_tests: counters.bound_tests,
        bound_hits: counters.bound_hits,
        triangle_tests_brute_force: brute,
        triangle_tests_saved: brute.saturating_sub(counters.triangle_tests),
        saved_fraction: if brute == 0 {
            0.0
        } else {
            1.0 - counters.triangle_tests as f64 / brute as f64
        },
        triangles_ms: None,
    };
    Ok((frame, stats))
}

/// Through a bounding-volume hierarchy built beforehand from the same triangles (so one
/// build serves many views).
pub fn render_bvh(
    view: &View<'_>,
    triangles: &SceneTriangles,
    bvh: &Bvh,
    options: &RenderOptions,
) -> Result<(Frame, RaycastBvhStats)> {
    let setup = Setup::new(view, triangles, options)?;
    let start = Instant::now();
    let (frame, counters) = setup.cast_bands(options, |band, counters| {
        let mut stack = PacketStack::default();
        let mut packet = RayPacket::default();
        let ctx = PacketContext {
            ignored: &setup.ignored,
            faces: setup.faces,
            t_min: setup.rays.near,
            tie: setup.rays.tie_rule(),
        };
        setup.cast_band_packets(band, counters, |rays, counters| {
            packet.prepare(rays, bvh.scale());
            let mut c = TraceCounters::default();
            let hits = bvh.closest_hits(&packet, &ctx, setup.rays.far, &mut stack, &mut c);
            counters.bound_tests += c.nodes;
            counters.packet_nodes += c.packet_nodes;
            counters.triangle_tests += c.triangles;
            hits
        });
    })?;
    let b = bvh.stats();
    let stats = RaycastBvhStats {
        ray: setup.stats(&counters, ms_since(start)),
        packet_node_visits_per_ray: per(counters.packet_nodes, counters.rays),
        build_ms: b.build_ms,
        binary_nodes: b.binary_nodes as u64,
        binary_depth: b.binary_depth as u64,
        nodes: b.nodes as u64,
        leaves: b.leaves as u64,
        depth: b.depth as u64,
        sah_cost: b.sah_cost,
        node_visits_per_ray: per(counters.bound_tests, counters.rays),
        triangle_tests_per_ray: per(counters.triangle_tests, counters.rays),
        triangles_ms: None,
    };
    Ok((frame, stats))
}

/// Through a uniform grid built beforehand from the same triangles.
pub fn render_grid(
    view: &View<'_>,
    triangles: &SceneTriangles,
    grid: &UniformGrid,
    options: &RenderOptions,
) -> Result<(Frame, RaycastGridStats)> {
    let setup = Setup::new(view, triangles, options)?;
    let start = Instant::now();
    let (frame, counters) = setup.cast_bands(options, |band, counters| {
        let mut mailbox = Mailbox::new(triangles);
        setup.cast_band(band, counters, |ctx, counters| {
            let mut c = GridCounters::default();
            let out = grid.closest_hit(triangles, ctx, setup.rays.far, &mut mailbox, &mut c);
            counters.cells += c.cells;
            counters.triangle_tests += c.triangles;
            counters.mailbox_hits += c.mailbox_hits;
            counters.far_rays += c.far_rays;
            if let Some(cell) = out.cell {
                // The seed's rule, checked independently of the traversal's parameters:
                // the accepted point must lie in the accepted cell.
                let (lo, hi) = grid.cell_box(cell);
                let p = ctx.ray.origin + ctx.ray.direction * out.hit.t;
                // The cell is grown by the ray's rounding bound `τ` for acceptance;
                // computing `p` rounds by less than `τ` again.
                let tol = (hi - lo) * 1e-6 + DVec3::splat(2.0 * grid.rounding(ctx.ray.origin));
                if !(p.cmpge(lo - tol).all() && p.cmple(hi + tol).all()) {
                    counters.hits_outside_cell += 1;
                }
            }
            out.hit
        })
    })?;
    let g = grid.stats();
    let [nx, ny, nz] = grid.resolution();
    let stats = RaycastGridStats {
        ray: setup.stats(&counters, ms_since(start)),
        build_ms: g.build_ms,
        cells: g.cells as u64,
        resolution_x: nx,
        resolution_y: ny,
        resolution_z: nz,
        refs: g.refs as u64,
        refs_per_cell: per(g.refs as u64, g.cells as u64),
        empty_cells: g.empty_cells as u64,
        largest_cell: g.largest_cell as u64,
        cells_per_ray: per(counters.cells, counters.rays),
        triangle_tests_per_ray: per(counters.triangle_tests, counters.rays),
        mailbox_hits: counters.mailbox_hits,
        hits_outside_cell: counters.hits_outside_cell,
        far_rays: counters.far_rays,
        triangles_ms: None,
    };
    Ok((frame, stats))
}

/// Pixels are traced in square tiles of this side (bands of this many rows are the
/// unit of parallel work).
const TILE: usize = 8;

/// What every variant shares for one view: rays, ignored polygons, face ids.
struct Setup<'a> {
    rays: PrimaryRays,
    /// The window coordinate of each column's centre.
    window_x: Vec<f64>,
    ignored: Vec<bool>,
    faces: &'a [u32],
    width: usize,
    height: usize,
    viewport: crate::Viewport,
    front_triangles: u64,
    scale: f64,
    triangle_count: usize,
    /// The render's deadline (see [`crate::work`]), checked once per tile of rays:
    /// past it, the remaining tiles are skipped and the render ends with its error.
    deadline: crate::work::Deadline,
}

impl<'a> Setup<'a> {
    fn new(
        view: &View<'_>,
        triangles: &'a SceneTriangles,
        options: &RenderOptions,
    ) -> Result<Self> {
        let fill = options.fill_rule;
        let camera = view.camera();
        // The view's decisions (objects outside the frustum, back faces), numbered as
        // the triangles number polygons: in scene order.
        let ignored = view.culled_polygons();
        if ignored.len() != triangles.polygon_count() {
            return Err(crate::Error::option(
                "triangles",
                "the triangles were built from another scene than the view's",
            ));
        }
        let front_triangles = triangles
            .triangle_polygons()
            .iter()
            .filter(|&&p| !ignored[p as usize])
            .count() as u64;
        let b = triangles.bounds();
        let scale = if b.is_empty() {
            1.0
        } else {
            b.magnitude() + b.extent().max_element()
        };
        let vp = view.viewport();
        let rays = PrimaryRays::new(camera, vp).with_fill_rule(fill);
        Ok(Setup {
            window_x: (0..vp.width)
                .map(|i| rays.window_x(f64::from(i) + 0.5))
                .collect(),
            rays,
            ignored,
            faces: triangles.polygon_faces(),
            width: vp.width as usize,
            height: vp.height as usize,
            viewport: vp,
            front_triangles,
            scale,
            triangle_count: triangles.len(),
            deadline: options.deadline.clone(),
        })
    }

    /// Casts every pixel's ray with `trace`.
    fn cast<F>(&self, options: &RenderOptions, trace: F) -> Result<(Frame, RayCounters)>
    where
        F: Fn(&HitContext<'_>, &mut RayCounters) -> ClosestHit + Sync,
    {
        self.cast_bands(options, |band, counters| {
            self.cast_band(band, counters, &trace);
        })
    }

    /// Fills one band of rows, tile by tile: `band = (first row, ids, depth)`.
    /// Tiles of [`TILE`] x [`TILE`] pixels keep consecutive rays close in both
    /// directions, so the nodes and triangles they visit stay in the cache.
    fn cast_band<F>(
        &self,
        band: (usize, &mut [u32], &mut [f32]),
        counters: &mut RayCounters,
        mut trace: F,
    ) where
        F: FnMut(&HitContext<'_>, &mut RayCounters) -> ClosestHit,
    {
        let (j0, ids, depth) = band;
        let w = self.width;
        let rows = ids.len() / w.max(1);
        let tie = self.rays.tie_rule();
        for x0 in (0..w).step_by(TILE) {
            if self.deadline.is_over() {
                return;
            }
            let x1 = (x0 + TILE).min(w);
            for r in 0..rows {
                let sy = self.rays.window_y((j0 + r) as f64 + 0.5);
                for i in x0..x1 {
                    let (origin, direction) = self.rays.ray_at(self.window_x[i], sy);
                    counters.rays += 1;
                    let Some(ray) = WatertightRay::new(origin, direction) else {
                        continue;
                    };
                    let ctx = HitContext {
                        ray,
                        ignored: &self.ignored,
                        faces: self.faces,
                        t_min: self.rays.near,
                        tie,
                    };
                    let hit = trace(&ctx, counters);
                    if hit.is_hit() {
                        counters.hits += 1;
                        ids[r * w + i] = hit.face;
                        depth[r * w + i] = hit.t as f32;
                    }
                }
            }
        }
    }

    /// Fills one band of rows packet by packet (blocks of [`PACKET_SIDE`] x
    /// [`PACKET_SIDE`] pixels, in tiles of [`TILE`] columns): `trace` gets the rays of
    /// a block (row by row; fewer at the image's edges) and returns their hits.
    fn cast_band_packets<F>(
        &self,
        band: (usize, &mut [u32], &mut [f32]),
        counters: &mut RayCounters,
        mut trace: F,
    ) where
        F: FnMut(&[(DVec3, DVec3)], &mut RayCounters) -> [ClosestHit; PACKET],
    {
        let (j0, ids, depth) = band;
        let w = self.width;
        let rows = ids.len() / w.max(1);
        let mut rays: Vec<(DVec3, DVec3)> = Vec::with_capacity(PACKET);
        let mut pixels: Vec<usize> = Vec::with_capacity(PACKET);
        for x0 in (0..w).step_by(TILE) {
            if self.deadline.is_over() {
                return;
            }
            let x1 = (x0 + TILE).min(w);
            for r0 in (0..rows).step_by(PACKET_SIDE) {
                for i0 in (x0..x1).step_by(PACKET_SIDE) {
                    rays.clear();
                    pixels.clear();
                    for r in r0..(r0 + PACKET_SIDE).min(rows) {
                        let sy = self.rays.window_y((j0 + r) as f64 + 0.5);
                        for i in i0..(i0 + PACKET_SIDE).min(x1) {
                            rays.push(self.rays.ray_at(self.window_x[i], sy));
                            pixels.push(r * w + i);
                        }
                    }
                    counters.rays += rays.len() as u64;
                    let hits = trace(&rays, counters);
                    for (hit, &p) in hits.iter().zip(&pixels) {
                        if hit.is_hit() {
                            counters.hits += 1;
                            ids[p] = hit.face;
                            depth[p] = hit.t as f32;
                        }
                    }
                }
            }
        }
    }

    /// Runs `band` on every band of [`TILE`] rows of a new frame, in parallel when the
    /// `parallel` feature is on, summing the counters.
    fn cast_bands<F>(&self, options: &RenderOptions, band: F) -> Result<(Frame, RayCounters)>
    where
        F: Fn((usize, &mut [u32], &mut [f32]), &mut RayCounters) + Sync,
    {
        let mut frame = Frame::new(self.viewport)?;
        let (w, h) = (self.width, self.height);
        let bands = h.div_ceil(TILE);
        let done = std::sync::atomic::AtomicUsize::new(0);
        let step = (bands / 50).max(1);
        let one = |b: usize, ids: &mut [u32], depth: &mut [f32]| {
            let mut c = RayCounters::default();
            band((b * TILE, ids, depth), &mut c);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(step) {
                options.report(n as f64 / bands as f64);
            }
            c
        };
        #[cfg(feature = "parallel")]
        let counters = {
            use rayon::prelude::*;
            frame
                .ids
                .par_chunks_mut(w * TILE)
                .zip(frame.depth.par_chunks_mut(w * TILE))
                .enumerate()
                .map(|(b, (ids, depth))| one(b, ids, depth))
                .reduce(RayCounters::default, |mut a, b| {
                    a += b;
                    a
                })
        };
        #[cfg(not(feature = "parallel"))]
        let counters = {
            let mut total = RayCounters::default();
            for (b, (ids, depth)) in frame
                .ids
                .chunks_mut(w * TILE)
                .zip(frame.depth.chunks_mut(w * TILE))
                .enumerate()
            {
                total += one(b, ids, depth);
            }
            total
        };
        // Tiles skipped past the deadline leave the frame unfinished: never returned.
        if self.deadline.is_over() {
            options.check_time("rays")?;
        }
        options.report(1.0);
        Ok((frame, counters))
    }

    /// The stats every variant reports.
    fn stats(&self, c: &RayCounters, trace_ms: f64) -> RayStats {
        RayStats {
            triangles: self.triangle_count as u64,
            front_triangles: self.front_triangles,
            rays: c.rays,
            hits: c.hits,
            triangle_tests: c.triangle_tests,
            trace_ms,
            mrays_per_s: if trace_ms > 0.0 {
                c.rays as f64 / trace_ms / 1e3
            } else {
                0.0
            },
        }
    }
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn per(a: u64, b: u64) -> f64 {
    if b == 0 { 0.0 } else { a as f64 / b as f64 }
}
