//! Hidden-surface removal: every algorithm of the seeds behind one interface.
//!
//! Each algorithm takes the same [`PreparedView`] and returns the same [`Frame`] (face
//! id and eye-space depth per pixel), plus [`Stats`] that show how it worked. Any two
//! frames can be compared pixel by pixel; the test suite demands that they agree.
//!
//! | algorithm | module | seed |
//! | --- | --- | --- |
//! | z-buffer (reference) | [`zbuffer`] | 000, 002, 003, 004 |
//! | scanline | [`scanline`] | 003 |
//! | depth sort (Newell-Newell-Sancha), covering-matrix variant | [`depth_sort`] | 000, 002, 003 |
//! | BSP tree | [`bsp`] | 000 |
//! | Warnock area subdivision | [`warnock`] | 003 |
//! | ray casting: brute force, bounding volumes, BVH, uniform grid | [`raycast`] | 000, 002 |
//! | octree | [`octree`] | 000, 003 |
//!
//! Ties: nearer wins; on an exact depth tie the lower face id wins, in every algorithm.
//!
//! [`render`] builds what an algorithm needs (triangles, BVH, grid, BSP tree, octree)
//! for its one call. To render many views of a scene, render through a
//! [`SceneIndex`], which builds each once; the ray casters,
//! the BSP and the octree then take a [`View`] (the view's decisions, no screen
//! polygons).

pub mod bsp;
pub mod depth_sort;
mod image;
pub mod octree;
pub mod raycast;
pub mod scanline;
pub mod stats;
pub mod warnock;
pub mod zbuffer;

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

use crate::geom::BoundsKind;
use crate::index::SceneIndex;
use crate::raster::FillRule;
use crate::view::{PreparedView, View};
use crate::{Error, Frame, Result};

pub use stats::{AlgorithmStats, Stats};

/// A hidden-surface algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Algorithm {
    /// Z-buffer: the reference.
    ZBuffer,
    /// Scanline with an active edge list.
    Scanline,
    /// Depth sort with the five Newell tests.
    DepthSort,
    /// Depth sort by covering matrix and topological order (seed 003).
    DepthSortMatrix,
    /// Binary space partitioning tree.
    Bsp,
    /// Warnock area subdivision.
    Warnock,
    /// Ray casting, brute force.
    Raycast,
    /// Ray casting with per-object bounding volumes.
    RaycastBounds,
    /// Ray casting with a bounding-volume hierarchy.
    RaycastBvh,
    /// Ray casting through a uniform grid.
    RaycastGrid,
    /// Front-to-back rendering of a voxel octree.
    Octree,
}

impl Algorithm {
    /// Every algorithm, in the order `compare` shows them.
    pub const ALL: [Algorithm; 11] = [
        Algorithm::ZBuffer,
        Algorithm::Scanline,
        Algorithm::DepthSort,
        Algorithm::DepthSortMatrix,
        Algorithm::Bsp,
        Algorithm::Warnock,
        Algorithm::Raycast,
        Algorithm::RaycastBounds,
        Algorithm::RaycastBvh,
        Algorithm::RaycastGrid,
        Algorithm::Octree,
    ];

    /// The command-line name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::ZBuffer => "zbuffer",
            Algorithm::Scanline => "scanline",
            Algorithm::DepthSort => "depth-sort",
            Algorithm::DepthSortMatrix => "depth-sort-matrix",
            Algorithm::Bsp => "bsp",
            Algorithm::Warnock => "warnock",
            Algorithm::Raycast => "raycast",
            Algorithm::RaycastBounds => "raycast-bounds",
            Algorithm::RaycastBvh => "raycast-bvh",
            Algorithm::RaycastGrid => "raycast-grid",
            Algorithm::Octree => "octree",
        }
    }

    /// Whether the algorithm computes exact polygon visibility (all but the octree,
    /// which approximates the solids by voxels).
    #[must_use]
    pub fn is_exact(self) -> bool {
        self != Algorithm::Octree
    }

    /// Whether the algorithm reads the clipped screen polygons of a
    /// [`PreparedView`]; the others (ray casters, BSP, octree) read only the
    /// [`View`]'s decisions and the scene's structures.
    #[must_use]
    pub fn needs_polygons(self) -> bool {
        matches!(
            self,
            Algorithm::ZBuffer
                | Algorithm::Scanline
                | Algorithm::DepthSort
                | Algorithm::DepthSortMatrix
                | Algorithm::Warnock
        )
    }
}

impl fmt::Display for Algorithm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Algorithm {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Algorithm::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                Error::option(
                    "algorithm",
                    format!(
                        "unknown algorithm \"{s}\" (known: {})",
                        Algorithm::ALL.map(Algorithm::name).join(", ")
                    ),
                )
            })
    }
}

/// A progress callback: called with the fraction done, in 0..=1.
pub type Progress = Arc<dyn Fn(f64) + Send + Sync>;

/// Options shared by the algorithms (each reads what concerns it).
#[derive(Clone)]
#[non_exhaustive]
pub struct RenderOptions {
    /// Which samples on polygon edges are covered.
    pub fill_rule: FillRule,
    /// The bounding volume of `raycast-bounds`.
    pub bounds: BoundsKind,
    /// BSP construction options.
    pub bsp: crate::accel::bsp::BspOptions,
    /// Octree depth (the voxel grid is `2^depth` on a side).
    pub octree_depth: u32,
    /// Called as long work progresses.
    pub progress: Option<Progress>,
    /// The memory budget of the render in bytes (frame buffers, bins, fragments,
    /// splits, nodes, grids: see [`crate::budget`]); `None` takes the default, half of
    /// the memory available.
    pub memory_limit: Option<u64>,
    /// The time limit of the render (see [`crate::work`]): work whose estimate passes
    /// it is refused before it starts, and the loops whose length the input decides
    /// stop when it passes, with an [`Error::TimeLimit`]. `None` (the default): no
    /// limit.
    pub time_limit: Option<std::time::Duration>,
    /// A flag another thread can raise to stop the render with an
    /// [`Error::Stopped`] (checked where the time limit is).
    pub stop: Option<crate::work::StopFlag>,
    /// The deadline of the render in progress, made by [`render`] from `time_limit`
    /// and `stop`.
    pub(crate) deadline: crate::work::Deadline,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            fill_rule: FillRule::TopLeft,
            bounds: BoundsKind::Aabb,
            bsp: crate::accel::bsp::BspOptions::default(),
            octree_depth: 7,
            progress: None,
            memory_limit: None,
            time_limit: None,
            stop: None,
            deadline: crate::work::Deadline::default(),
        }
    }
}

impl fmt::Debug for RenderOptions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("RenderOptions")
            .field("fill_rule", &self.fill_rule)
            .field("bounds", &self.bounds)
            .field("bsp", &self.bsp)
            .field("octree_depth", &self.octree_depth)
            .field("progress", &self.progress.is_some())
            .field("memory_limit", &self.memory_limit)
            .field("time_limit", &self.time_limit)
            .field("stop", &self.stop.is_some())
            .finish()
    }
}

impl RenderOptions {
    /// These options with another fill rule.
    #[must_use]
    pub fn with_fill_rule(mut self, fill_rule: FillRule) -> Self {
        self.fill_rule = fill_rule;
        self
    }

    /// These options with another bounding volume for `raycast-bounds`.
    #[must_use]
    pub fn with_bounds(mut self, bounds: BoundsKind) -> Self {
        self.bounds = bounds;
        self
    }

    /// These options with other BSP construction options.
    #[must_use]
    pub fn with_bsp(mut self, bsp: crate::accel::bsp::BspOptions) -> Self {
        self.bsp = bsp;
        self
    }

    /// These options with another octree depth.
    #[must_use]
    pub fn with_octree_depth(mut self, depth: u32) -> Self {
        self.octree_depth = depth;
        self
    }

    /// These options with a progress callback.
    #[must_use]
    pub fn with_progress(mut self, progress: Progress) -> Self {
        self.progress = Some(progress);
        self
    }

    /// These options with a memory budget in bytes (`None`: the default).
    #[must_use]
    pub fn with_memory_limit(mut self, limit: Option<u64>) -> Self {
        self.memory_limit = limit;
        self
    }

    /// These options with a time limit (`None`: no limit; see [`crate::work`]).
    #[must_use]
    pub fn with_time_limit(mut self, limit: Option<std::time::Duration>) -> Self {
        self.time_limit = limit;
        self
    }

    /// These options with a stop flag: raising it from another thread stops the
    /// render with an [`Error::Stopped`].
    #[must_use]
    pub fn with_stop(mut self, stop: crate::work::StopFlag) -> Self {
        self.stop = Some(stop);
        self
    }

    /// `Ok` while the render in progress may go on (its time limit not passed, its
    /// stop flag not raised); else the error that ends it, naming `work`. Always `Ok`
    /// outside [`render`] unless a deadline was started with
    /// [`RenderOptions::started`].
    pub fn check_time(&self, work: &str) -> Result<()> {
        self.deadline.check(work)
    }

    /// These options with the deadline of a render starting now (what [`render`]
    /// does; for callers of an algorithm's own `render`).
    #[must_use]
    pub fn started(mut self) -> Self {
        self.deadline = crate::work::Deadline::new(self.time_limit, self.stop.clone());
        self
    }

    /// The memory budget these options give.
    #[must_use]
    pub fn budget(&self) -> crate::budget::MemoryBudget {
        crate::budget::MemoryBudget::from_option(self.memory_limit)
    }

    /// Reports progress if someone listens.
    pub fn report(&self, fraction: f64) {
        if let Some(p) = &self.progress {
            p(fraction.clamp(0.0, 1.0));
        }
    }
}

/// Renders a prepared view with an algorithm: the frame, and the algorithm's
/// [`AlgorithmStats`] with the milliseconds of the call (listed last, as `time_ms`).
///
/// ```
/// use obscura::{scene::{demo, Viewport}, view::{prepare, PrepareOptions}};
/// use obscura::surface::{render, Algorithm, RenderOptions};
/// let scene = demo::cube();
/// let vp = Viewport::new(64, 48).unwrap();
/// let view = prepare(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default()).unwrap();
/// let (frame, stats) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
/// assert!(frame.covered_pixels() > 0);
/// assert!(stats.zbuffer().unwrap().pixels_written > 0);
/// assert!(stats.time_ms >= 0.0);
/// ```
///
/// The structures an algorithm needs (triangles, BVH, grid, BSP tree, octree) are built
/// for this call; to build them once for many views, render through a
/// [`SceneIndex`].
pub fn render(
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<(Frame, Stats)> {
    render_indexed(&SceneIndex::new(view.scene()), algorithm, view, options)
}

/// [`render`] with the structures of `index` (which must be of the view's scene).
pub(crate) fn render_indexed(
    index: &SceneIndex<'_>,
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<(Frame, Stats)> {
    let start = Instant::now();
    let options = &begin(algorithm, options, |o| estimate(algorithm, view, o))?;
    check_budget(algorithm, view, options)?;
    use AlgorithmStats as S;
    let (frame, stats) = match algorithm {
        Algorithm::ZBuffer => zbuffer::render(view, options).map(|(f, s)| (f, S::ZBuffer(s))),
        Algorithm::Scanline => scanline::render(view, options).map(|(f, s)| (f, S::Scanline(s))),
        Algorithm::DepthSort => {
            depth_sort::render(view, options).map(|(f, s)| (f, S::DepthSort(s)))
        }
        Algorithm::DepthSortMatrix => {
            depth_sort::render_matrix(view, options).map(|(f, s)| (f, S::DepthSortMatrix(s)))
        }
        Algorithm::Warnock => warnock::render(view, options).map(|(f, s)| (f, S::Warnock(s))),
        _ => return render_view_unchecked(index, algorithm, view, options, start),
    }?;
    Ok((
        frame,
        Stats::new(stats, start.elapsed().as_secs_f64() * 1e3),
    ))
}

/// [`render_indexed`] into kept memory: the z-buffer draws into `frame` with `buffers`
/// ([`zbuffer::render_into`]); another algorithm's new frame replaces `frame`. The
/// same frame and stats as [`render_indexed`].
pub(crate) fn render_indexed_into(
    index: &SceneIndex<'_>,
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
    frame: &mut Frame,
    buffers: &mut zbuffer::Buffers,
) -> Result<Stats> {
    if algorithm != Algorithm::ZBuffer {
        let (f, stats) = render_indexed(index, algorithm, view, options)?;
        *frame = f;
        return Ok(stats);
    }
    let start = Instant::now();
    let options = &begin(algorithm, options, |o| estimate(algorithm, view, o))?;
    check_budget(algorithm, view, options)?;
    let stats = zbuffer::render_into(view, options, frame, buffers)?;
    Ok(Stats::new(
        AlgorithmStats::ZBuffer(stats),
        start.elapsed().as_secs_f64() * 1e3,
    ))
}

/// The options of a render starting now: its deadline started, ended at once when the
/// limit is spent or the stop flag raised, and the work refused when `estimate` (only
/// asked with a time limit) passes the time left (see [`crate::work`]).
fn begin(
    algorithm: Algorithm,
    options: &RenderOptions,
    estimate: impl FnOnce(&RenderOptions) -> Option<crate::work::Estimate>,
) -> Result<RenderOptions> {
    let options = options.clone().started();
    options.check_time(algorithm.name())?;
    if options.time_limit.is_some()
        && let Some(e) = estimate(&options)
    {
        options.deadline.admit(&e)?;
    }
    Ok(options)
}

/// Renders a [`View`] with an algorithm that needs no screen polygons
/// ([`Algorithm::needs_polygons`] false), the structures taken from `index`. The
/// budget check counts the view's front faces of kept objects for its polygons (the
/// polygons before outcode rejection and clipping, which are not built).
pub(crate) fn render_view_indexed(
    index: &SceneIndex<'_>,
    algorithm: Algorithm,
    view: &View<'_>,
    options: &RenderOptions,
) -> Result<(Frame, Stats)> {
    let start = Instant::now();
    let options = &begin(algorithm, options, |o| estimate_view(algorithm, view, o))?;
    let polygons = view
        .culled_polygons()
        .iter()
        .filter(|&&culled| !culled)
        .count() as u64;
    check_counts(
        algorithm,
        view,
        polygons,
        view.vertex_count() as u64,
        options,
    )?;
    render_view_unchecked(index, algorithm, view, options, start)
}

fn render_view_unchecked(
    index: &SceneIndex<'_>,
    algorithm: Algorithm,
    view: &View<'_>,
    options: &RenderOptions,
    start: Instant,
) -> Result<(Frame, Stats)> {
    use AlgorithmStats as S;
    use raycast::Acceleration;
    let (frame, stats) = match algorithm {
        Algorithm::Bsp => bsp::render_indexed(index, view, options).map(|(f, s)| (f, S::Bsp(s))),
        Algorithm::Raycast => {
            raycast::render_indexed(index, view, Acceleration::BruteForce, options)
        }
        Algorithm::RaycastBounds => {
            raycast::render_indexed(index, view, Acceleration::Bounds(options.bounds), options)
        }
        Algorithm::RaycastBvh => raycast::render_indexed(index, view, Acceleration::Bvh, options),
        Algorithm::RaycastGrid => raycast::render_indexed(index, view, Acceleration::Grid, options),
        Algorithm::Octree => {
            octree::render_indexed(index, view, options).map(|(f, s)| (f, S::Octree(s)))
        }
        _ => Err(Error::option(
            "algorithm",
            format!("{algorithm} needs the screen polygons of a prepared view"),
        )),
    }?;
    Ok((
        frame,
        Stats::new(stats, start.elapsed().as_secs_f64() * 1e3),
    ))
}

/// The work of `algorithm` on `view` where it is a product of counts known before it
/// starts (see [`crate::work`]), `None` where it is not (those algorithms check their
/// time limit as they run):
/// - brute-force ray casting tests every ray against every triangle;
/// - bounding-volume ray casting tests, for each object, the rays through the screen
///   rectangle of its box against its triangles (the whole image when the box reaches
///   behind the eye);
/// - the painter's algorithms (depth sort, its matrix variant, a back-to-front BSP)
///   paint every polygon whole: the sum of the view polygons' areas in pixels;
/// - the z-buffer tests at most every pixel of every polygon (only measured when the
///   bound "every polygon covers the image" passes a second);
/// - the octree's build meets each triangle in the voxels its area, perimeter and
///   corners reach at every level (an upper bound, see [`octree::check_budget`]).
#[must_use]
pub fn estimate(
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Option<crate::work::Estimate> {
    use crate::work::{Estimate, NS_PER_PAINTED_PIXEL};
    let pixels = view.viewport().pixel_count() as f64;
    let name = algorithm.name();
    match algorithm {
        Algorithm::DepthSort | Algorithm::DepthSortMatrix => Some(Estimate::new(
            name,
            "pixels painted",
            painted_pixels(view),
            NS_PER_PAINTED_PIXEL,
        )),
        Algorithm::Bsp if options.bsp.traversal == crate::accel::bsp::BspTraversal::BackToFront => {
            Some(Estimate::new(
                name,
                "pixels painted",
                painted_pixels(view),
                NS_PER_PAINTED_PIXEL,
            ))
        }
        // The z-buffer tests at most every pixel of every polygon; the sum of their
        // areas is only measured when the crude bound (every polygon the whole image)
        // could matter, so that ordinary views pay nothing for it.
        Algorithm::ZBuffer
            if view.polygon_count() as f64 * pixels * crate::work::NS_PER_ZBUFFER_PIXEL > 1e9 =>
        {
            Some(Estimate::new(
                name,
                "pixels tested",
                sampled_pixels(view, ZBUFFER_SAMPLE_STRIDE),
                crate::work::NS_PER_ZBUFFER_PIXEL,
            ))
        }
        _ => estimate_view(algorithm, view, options),
    }
}

/// The estimates of [`estimate`] that need no screen polygons (the ray casters and the
/// octree): what a [`View`] rendered without them is refused on.
#[must_use]
pub fn estimate_view(
    algorithm: Algorithm,
    view: &View<'_>,
    options: &RenderOptions,
) -> Option<crate::work::Estimate> {
    use crate::work::{Estimate, NS_PER_RAY_TRIANGLE};
    let vp = view.viewport();
    let pixels = vp.pixel_count() as f64;
    let name = algorithm.name();
    match algorithm {
        Algorithm::Raycast => Some(Estimate::new(
            name,
            "ray-triangle tests",
            pixels * view.scene().triangle_count() as f64,
            NS_PER_RAY_TRIANGLE,
        )),
        Algorithm::RaycastBounds => {
            let tests: f64 = view
                .scene()
                .objects()
                .iter()
                .map(|o| screen_rect_pixels(view, &o.bounds) * o.mesh.triangle_count() as f64)
                .sum();
            Some(Estimate::new(
                name,
                "ray-triangle tests",
                tests,
                NS_PER_RAY_TRIANGLE,
            ))
        }
        Algorithm::Octree => Some(Estimate::new(
            name,
            "triangle-voxel pairs",
            octree::estimated_pairs(view.scene(), options.octree_depth),
            crate::work::NS_PER_OCTREE_PAIR,
        )),
        _ => None,
    }
}

/// The sum of the view polygons' areas in pixels (each clipped to the view volume, so
/// none is larger than the image).
fn painted_pixels(view: &PreparedView<'_>) -> f64 {
    sampled_pixels(view, 1)
}

/// Every how many polygons the z-buffer's estimate measures one (and scales the sum):
/// measuring every eighth of Sponza's at 1920x1080 still took 0.7 ms of a 12 ms render
/// (the vertices are read out of order); every 64th is lost in the noise. The estimate
/// only decides a refusal up front; the z-buffer also checks its deadline per band of
/// rows.
const ZBUFFER_SAMPLE_STRIDE: usize = 64;

/// [`painted_pixels`] measured on every `stride`-th polygon, times `stride`.
fn sampled_pixels(view: &PreparedView<'_>, stride: usize) -> f64 {
    let (starts, indices, _) = view.polygon_arrays();
    let vertices = view.vertices();
    let stride = stride.max(1);
    stride as f64
        * starts
            .windows(2)
            .step_by(stride)
            .map(|w| {
                let ring = &indices[w[0] as usize..w[1] as usize];
                let Some(&last) = ring.last() else {
                    return 0.0;
                };
                let mut prev = &vertices[last as usize];
                let mut twice = 0.0;
                for &i in ring {
                    let v = &vertices[i as usize];
                    twice += prev.x * v.y - v.x * prev.y;
                    prev = v;
                }
                0.5 * f64::abs(twice)
            })
            .sum::<f64>()
}

/// The pixels of the image inside the screen rectangle of a world box (all of them
/// when a corner is at or behind the eye plane).
fn screen_rect_pixels(view: &View<'_>, b: &crate::geom::Aabb) -> f64 {
    let vp = view.viewport();
    let (w, h) = (f64::from(vp.width), f64::from(vp.height));
    if b.is_empty() {
        return 0.0;
    }
    let Some((x0, y0, x1, y1)) = view.transform().screen_box(b) else {
        return w * h;
    };
    let cw = (x1.min(w) - x0.max(0.0)).max(0.0);
    let ch = (y1.min(h) - y0.max(0.0)).max(0.0);
    if cw.is_finite() && ch.is_finite() {
        cw * ch
    } else {
        w * h
    }
}

/// The structure named by the budget error of a frame and its per-pixel buffers.
pub const FRAME_STRUCTURE: &str = "frame buffers (ids and depths per pixel)";

/// Estimates, before an algorithm runs, what it allocates in proportion to the image
/// and to the view's polygons, and refuses it over the budget of `options` (see
/// [`crate::budget`]). Per pixel: the frame's id and depth (8 bytes), and the keys of
/// the algorithms that paint with a depth test (8 more for depth sort and a
/// back-to-front BSP) or step a z-buffer row (the reference z-buffer, 4). Per polygon,
/// the algorithm's own copies: the scanline's edges and faces, the depth sort's work
/// set with room for its split budget (`8 P + 1024` pieces), Warnock's lists, the ray
/// casters' triangles and hierarchies. Structures that grow with the geometry are held
/// to the budget where they are built (BSP fragments, depth-sort splits, the
/// z-buffer's bins, octree nodes, the grid's cells).
pub fn check_budget(
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<()> {
    check_counts(
        algorithm,
        view,
        view.polygon_count() as u64,
        view.vertices().len() as u64,
        options,
    )
}

/// [`check_budget`] for a view with `view_polygons` polygons and `vertices` vertices.
fn check_counts(
    algorithm: Algorithm,
    view: &View<'_>,
    view_polygons: u64,
    vertices: u64,
    options: &RenderOptions,
) -> Result<()> {
    let budget = options.budget();
    let pixels = view.viewport().pixel_count() as u64;
    let painted_keys = matches!(algorithm, Algorithm::DepthSort | Algorithm::DepthSortMatrix)
        || (algorithm == Algorithm::Bsp
            && options.bsp.traversal == crate::accel::bsp::BspTraversal::BackToFront);
    let per_pixel = 8 + if painted_keys { 8 } else { 0 };
    budget.check_items(FRAME_STRUCTURE, pixels, per_pixel)?;
    // The ray casters build on the scene's triangles, the others on the view's.
    let polygons = if matches!(
        algorithm,
        Algorithm::Raycast
            | Algorithm::RaycastBounds
            | Algorithm::RaycastBvh
            | Algorithm::RaycastGrid
    ) {
        view.scene().triangle_count() as u64
    } else {
        view_polygons
    };
    // Bytes per view polygon and per view vertex of each algorithm's own copies.
    let (per_polygon, per_vertex, structure) = match algorithm {
        Algorithm::ZBuffer | Algorithm::Octree => return Ok(()),
        Algorithm::Scanline => (256, 0, "scanline edge table and faces"),
        Algorithm::DepthSort | Algorithm::DepthSortMatrix => {
            (9 * 160, 9 * 48, "depth-sort work set and split pieces")
        }
        Algorithm::Bsp => (160, 64, "BSP fragments"),
        Algorithm::Warnock => (256, 0, "Warnock face lists"),
        Algorithm::Raycast
        | Algorithm::RaycastBounds
        | Algorithm::RaycastBvh
        | Algorithm::RaycastGrid => (256, 0, "ray-casting triangles and hierarchy"),
    };
    let bytes = (polygons.saturating_add(1024))
        .saturating_mul(per_polygon)
        .saturating_add(vertices.saturating_mul(per_vertex))
        .saturating_add(pixels.saturating_mul(per_pixel));
    budget.check(structure, polygons, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for a in Algorithm::ALL {
            assert_eq!(a.name().parse::<Algorithm>().unwrap(), a);
        }
        assert!("nope".parse::<Algorithm>().is_err());
    }

    #[test]
    fn errors_name_library_parameters_not_cli_flags() {
        let errors = [
            "nope".parse::<Algorithm>().unwrap_err(),
            "nope".parse::<BoundsKind>().unwrap_err(),
            "nope"
                .parse::<crate::accel::bsp::BspTraversal>()
                .unwrap_err(),
            crate::accel::octree::check_depth(crate::accel::octree::MAX_DEPTH + 1).unwrap_err(),
        ];
        let named = [
            "algorithm",
            "RenderOptions::bounds",
            "BspOptions::traversal",
            "RenderOptions::octree_depth",
        ];
        for (e, name) in errors.iter().zip(named) {
            let text = e.to_string();
            assert!(text.contains(name) && !text.contains("--"), "{text}");
        }
    }
}
