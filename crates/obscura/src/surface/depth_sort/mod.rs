//! Depth sort (the painter's algorithm of Newell, Newell and Sancha), and the
//! covering-matrix variant.
//!
//! Sources: seed 000, "Αλγόριθμος Ταξινόμησης Κατά Βάθος (1)-(5)"; seed 002, "Depth
//! Sort" (the swap example P, Q, R and cyclic overlap); seed 003, "Depth-Sort" (the
//! covering matrix M, the coefficients A_i and the topological loop). Newell, Newell
//! and Sancha, "A solution to the hidden surface problem", ACM 1972.
//!
//! # Newell-Newell-Sancha ([`render`], [`paint_order`])
//! Polygons are sorted by their farthest depth. The farthest, `P`, is painted unless
//! an unpainted `Q` whose depth extent reaches behind `P`'s nearest point could be
//! hidden by it; for each such `Q` the tests, in order of cost, say that `P` cannot
//! hide `Q`:
//! 1. their x extents do not overlap (pixel boxes);
//! 2. their y extents do not overlap;
//! 3. `P` is entirely on the far side of `Q`'s plane (the side without the viewpoint);
//! 4. `Q` is entirely on the near side of `P`'s plane;
//! 5. their projections share no pixel (separating axis test of the two convex
//!    polygons, then the samples both cover).
//!
//! If all fail, tests 3 and 4 are retried with `P` and `Q` swapped; if `Q` may go
//! first it moves to the head of the list and is marked. When tests 3 and 4 fail both
//! ways (each polygon crosses the other's plane, which does not mean that they
//! intersect: two perpendicular walls of separate buildings do), the depths over the
//! overlap of their projections decide (the difference of two depth-key planes is
//! affine, so its signs at the corners of the convex overlap region tell which is in
//! front everywhere; seed 003: "the common zone can even be analysed pixel by
//! pixel"). Only if they cross inside that region do they interpenetrate, and `P` (or
//! `Q`) is split by the other's plane: "R is split in two by the plane of Q and the
//! pieces replace it" (seed 000). A marked polygon that would have to move again
//! closes a cycle (cyclic overlap), and one polygon of the cycle is split by the
//! plane of another. So splits happen only for cycles and interpenetration. Coplanar
//! overlapping polygons are ordered by face id, the lower painted last, so that it
//! wins exact ties as in the z-buffer.
//!
//! # Covering matrix ([`render_matrix`], [`paint_order_matrix`])
//! Seed 003: `M[i][j] = 1` when face `i` covers face `j`, `A[i]` counts the faces `i`
//! covers, a face with `A[i] = 0` is painted and the faces covering it decremented.
//! The relation of a pair comes from the same tests (extents, planes, overlap
//! depths); interpenetrating pairs (seed 003's case IV) are split while the relation
//! is built; a cycle of the relation (no face with `A = 0`) is found by walking it and
//! broken by a split.
//! Stored as adjacency lists (the matrix is sparse).
//!
//! # Details common to both
//! - Input: a [`PreparedView`]; the eye-space polygons (tests 3 and 4 with the
//!   viewpoint at the eye for perspective, at infinity along +z for parallel
//!   projections) and their projections. Output: a [`Frame`] equal to the z-buffer's.
//! - Splitting is done in eye space with [`split_polygon`](crate::clip::split) and
//!   the new vertices projected (for the tests that follow); each piece records the
//!   planes that cut it and its sides of them.
//! - Painting: back to front, overwriting ([`crate::raster::PolygonCoverage`], the
//!   shared top-left rule). A piece is painted as the pixels of its whole polygon (its
//!   coverage and depth-key plane) on its sides of its cuts
//!   (the painter in `surface::paint`), so the pieces of a polygon cover each of its pixels
//!   exactly once: painted by their own vertices, a piece cut again left a crack along
//!   the edge its sibling kept whole (a T-junction).
//! - Candidates: a grid of screen tiles (about twice the median polygon box) lists
//!   the polygons touching each tile, so a polygon is compared only with polygons
//!   whose boxes may overlap its own; for Newell's variant each tile lists them
//!   farthest first and the scan of a tile stops at the first polygon entirely nearer
//!   than `P` (the depth-extent test, without looking at the rest).
//! - Tolerance: a vertex within 1e-9 of the largest eye coordinate (plus the
//!   polygon's own non-planarity) of a plane counts as on it.
//! - Complexity: O(P log P) for the sort and O(P k) for k overlapping candidates per
//!   polygon on ordinary scenes; O(P^2) comparisons at worst (seed 000), and each
//!   split adds a polygon. A split budget (`8 P + 1024`) guarantees termination on
//!   degenerate input, and the memory budget ([`RenderOptions::memory_limit`]) bounds
//!   the pieces' bytes (each piece copies the cuts that made it): a split that would
//!   pass it ends the render with [`crate::Error::Budget`]; past it (or when rounding prevents a split), a conflict is
//!   painted as found and counted in `unresolved`, and from then on every polygon is
//!   painted depth-tested against what is painted (the z-buffer's test): those
//!   painted before lie behind all that remain, so the image is still the
//!   z-buffer's. A comparison budget (`1024 P + 2^24`) bounds the work the same way:
//!   past it the remaining polygons are painted (the matrix: linked without relations)
//!   unsorted, depth-tested, counted in `unsorted`.
//! - A polygon that had to wait at the head keeps its candidate list and resumes its
//!   scan where it stopped (those before cannot be hidden by it), until a split.
//! - Stats: `polygons` (of the view), `polygons_sorted` (covering a sample),
//!   `comparisons`, and which test decided them: `decided_depth` (only candidates
//!   met before a tile's scan stops), `decided_same_face` (pieces of one face),
//!   `decided_test1_x` ... `decided_test5`, `decided_coplanar`,
//!   `decided_overlap_depth`; Newell's `swaps` (with `swap_test3`, `swap_test4`,
//!   `swap_overlap_depth` saying why) and `cycles`; the matrix's `relations` (edges
//!   of M), `decided_planes_both_orders` and `cycles_broken`; `splits`, `unresolved`,
//!   `unsorted`,
//!   `polygons_painted`, `pixels_written`.
//! - Limitations: single-threaded; polygons whose box spans much of the image are
//!   listed in many tiles and met once per tile by the scans that reach them.

mod matrix;
mod newell;
mod work;

use crate::surface::paint::{PaintMode, Painter};
use crate::surface::{RenderOptions, Stats};
use crate::view::{PreparedView, ViewVertex};
use crate::{Frame, Result};

use work::WorkSet;

/// The number of splits allowed for `n` polygons before conflicts are left
/// unresolved (a guard against endless splitting on degenerate input).
fn split_budget(n: usize) -> u64 {
    8 * n as u64 + 1024
}

/// The number of comparisons allowed for `n` polygons before the remaining ones are
/// painted without sorting, each depth-tested (a guard against the O(P^2) worst case:
/// thousands of long thin overlapping triangles took minutes). Sponza's atrium view
/// (204k polygons) needs 15M comparisons with Newell's tests and 44M with the matrix,
/// a fifth of its budget.
fn comparison_budget(n: usize) -> u64 {
    1024 * n as u64 + (1 << 24)
}

/// How often each test decided, and what was done.
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    comparisons: u64,
    depth: u64,
    same_face: u64,
    test1: u64,
    test2: u64,
    test3: u64,
    test4: u64,
    test5: u64,
    coplanar: u64,
    swaps: u64,
    swap_test3: u64,
    swap_test4: u64,
    overlap_depth: u64,
    swap_overlap_depth: u64,
    cycles: u64,
    splits: u64,
    unresolved: u64,
    /// Polygons painted (or, for the matrix, linked) past the comparison budget.
    unsorted: u64,
    relations: u64,
}

/// A polygon of a paint order: one of the view's polygons or a piece of one.
#[derive(Clone, Debug)]
pub struct OrderedPolygon {
    /// The face id.
    pub face: u32,
    /// The object index.
    pub object: u32,
    /// Index of the view polygon it is or comes from.
    pub source: usize,
    /// Its projected vertices (with eye-space positions).
    pub vertices: Vec<ViewVertex>,
}

/// The back-to-front order depth sort found, with its statistics.
#[derive(Clone, Debug)]
pub struct PaintOrder {
    /// Polygons in painting order (farthest first). View polygons covering no pixel
    /// sample are left out.
    pub polygons: Vec<OrderedPolygon>,
    /// The statistics [`render`] reports (without the painting counts).
    pub stats: Stats,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Variant {
    Newell,
    Matrix,
}

fn run(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    variant: Variant,
    paint: &mut dyn FnMut(&WorkSet, u32),
) -> Result<Stats> {
    let mut ws = WorkSet::from_view(view, options.fill_rule);
    ws.budget = options.budget();
    let sorted = ws.polys.len();
    let mut c = Counters::default();
    let mut progress = |f: f64| options.report(f);
    match variant {
        Variant::Newell => newell::sort(&mut ws, &mut c, &mut progress, paint),
        Variant::Matrix => matrix::sort(&mut ws, &mut c, &mut progress, paint),
    }
    let mut stats = Stats::default();
    stats.set("polygons", ws.view_polygons as f64);
    stats.set("polygons_sorted", sorted as f64);
    stats.set("comparisons", c.comparisons as f64);
    if variant == Variant::Newell {
        stats.set("decided_depth", c.depth as f64);
    }
    stats.set("decided_same_face", c.same_face as f64);
    stats.set("decided_test1_x", c.test1 as f64);
    stats.set("decided_test2_y", c.test2 as f64);
    match variant {
        Variant::Newell => {
            stats.set("decided_test3", c.test3 as f64);
            stats.set("decided_test4", c.test4 as f64);
        }
        Variant::Matrix => stats.set("decided_planes_both_orders", c.test3 as f64),
    }
    stats.set("decided_test5", c.test5 as f64);
    stats.set("decided_coplanar", c.coplanar as f64);
    stats.set("decided_overlap_depth", c.overlap_depth as f64);
    match variant {
        Variant::Newell => {
            stats.set("swaps", c.swaps as f64);
            stats.set("swap_test3", c.swap_test3 as f64);
            stats.set("swap_test4", c.swap_test4 as f64);
            stats.set("swap_overlap_depth", c.swap_overlap_depth as f64);
            stats.set("cycles", c.cycles as f64);
        }
        Variant::Matrix => {
            stats.set("relations", c.relations as f64);
            stats.set("cycles_broken", c.cycles as f64);
        }
    }
    stats.set("splits", c.splits as f64);
    stats.set("unresolved", c.unresolved as f64);
    stats.set("unsorted", c.unsorted as f64);
    match ws.over_budget {
        Some(e) => Err(e),
        None => Ok(stats),
    }
}

fn render_variant(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    variant: Variant,
) -> Result<(Frame, Stats)> {
    let mut painter = Painter::new(view, options.fill_rule, PaintMode::Overwrite)?;
    let mut screen = Vec::new();
    let mut stats = run(view, options, variant, &mut |ws, i| {
        let Some(plane) = ws.depth_plane(i) else {
            return;
        };
        if ws.fallback {
            painter.set_mode(PaintMode::DepthTest);
        }
        let face = ws.polys[i as usize].face;
        if ws.cuts(i).is_empty() {
            screen.clear();
            screen.extend(ws.vertices(i).iter().map(|v| (v.x, v.y)));
            painter.paint(&screen, plane, face);
        } else {
            // A piece: the whole polygon's pixels on its sides of its cuts, so the
            // pieces of a polygon cover each of its pixels once (see `paint`).
            screen.clear();
            screen.extend(ws.whole_vertices(i).iter().map(|v| (v.x, v.y)));
            let region = ws.polys[i as usize].rect;
            painter.paint_piece(&screen, plane, region, ws.cuts(i), face);
        }
    })?;
    stats.set("polygons_painted", painter.polygons_painted as f64);
    stats.set("pixels_written", painter.pixels_written as f64);
    Ok((painter.finish(), stats))
}

fn order_variant(view: &PreparedView<'_>, options: &RenderOptions, variant: Variant) -> PaintOrder {
    let mut polygons = Vec::new();
    // A paint order has no error to return: it is computed without a budget (no set
    // passes u64::MAX bytes, so `run` cannot fail here).
    let options = &options.clone().with_memory_limit(Some(u64::MAX));
    let stats = run(view, options, variant, &mut |ws, i| {
        let p = &ws.polys[i as usize];
        polygons.push(OrderedPolygon {
            face: p.face,
            object: p.object,
            source: p.source as usize,
            vertices: ws.vertices(i).to_vec(),
        });
    })
    .unwrap_or_default();
    PaintOrder { polygons, stats }
}

/// Renders a prepared view by depth sort with the five tests (see the module doc).
///
/// ```
/// use obscura::{scene::{demo, Viewport}, prepare, PrepareOptions};
/// use obscura::surface::{render, Algorithm, RenderOptions};
/// let scene = demo::default_scene();
/// let vp = Viewport::new(64, 48).unwrap();
/// let view = prepare(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default()).unwrap();
/// let (frame, stats) = render(Algorithm::DepthSort, &view, &RenderOptions::default()).unwrap();
/// let (z, _) = render(Algorithm::ZBuffer, &view, &RenderOptions::default()).unwrap();
/// assert_eq!(frame.ids, z.ids);
/// assert!(stats.get("splits").unwrap() > 0.0); // the demo's panels interpenetrate
/// ```
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, Stats)> {
    render_variant(view, options, Variant::Newell)
}

/// Renders a prepared view by depth sort with a covering matrix (seed 003).
pub fn render_matrix(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, Stats)> {
    render_variant(view, options, Variant::Matrix)
}

/// The back-to-front order [`render`] paints, with the pieces of split polygons.
#[must_use]
pub fn paint_order(view: &PreparedView<'_>, options: &RenderOptions) -> PaintOrder {
    order_variant(view, options, Variant::Newell)
}

/// The order [`render_matrix`] paints, with the pieces of split polygons.
#[must_use]
pub fn paint_order_matrix(view: &PreparedView<'_>, options: &RenderOptions) -> PaintOrder {
    order_variant(view, options, Variant::Matrix)
}
