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

pub mod bsp;
pub mod depth_sort;
pub mod octree;
mod paint;
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
use crate::raster::FillRule;
use crate::view::PreparedView;
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
pub fn render(
    algorithm: Algorithm,
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<(Frame, Stats)> {
    let start = Instant::now();
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
        Algorithm::Bsp => bsp::render(view, options).map(|(f, s)| (f, S::Bsp(s))),
        Algorithm::Warnock => warnock::render(view, options).map(|(f, s)| (f, S::Warnock(s))),
        Algorithm::Raycast => raycast::render(view, raycast::Acceleration::BruteForce, options),
        Algorithm::RaycastBounds => {
            raycast::render(view, raycast::Acceleration::Bounds(options.bounds), options)
        }
        Algorithm::RaycastBvh => raycast::render(view, raycast::Acceleration::Bvh, options),
        Algorithm::RaycastGrid => raycast::render(view, raycast::Acceleration::Grid, options),
        Algorithm::Octree => octree::render(view, options).map(|(f, s)| (f, S::Octree(s))),
    }?;
    Ok((
        frame,
        Stats::new(stats, start.elapsed().as_secs_f64() * 1e3),
    ))
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
        view.polygon_count() as u64
    };
    let vertices = view.vertices().len() as u64;
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
