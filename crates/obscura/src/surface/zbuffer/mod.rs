//! The z-buffer: the reference every other algorithm is checked against.
//!
//! Sources: seed 000 ("Αλγόριθμος Z-buffer"), 002 ("Algoritmo Z-Buffer"), 003
//! ("Buffer de adâncime"), 004 ("Алгоритм z-буфера"); Catmull, *A subdivision
//! algorithm for computer display of curved surfaces* (PhD thesis, University of Utah,
//! 1974), the z-buffer. For each polygon, for each pixel it
//! covers, compute the depth from the polygon's plane and keep it if it is nearer than
//! what the buffer holds. Along a span the depth is stepped incrementally,
//! `z(x + 1) = z(x) + dz/dx` (the seeds' `z - a/c`), re-anchored from the plane equation
//! at the start of every span so errors do not accumulate down the polygon.
//!
//! - Input: a [`PreparedView`]; output: a [`Frame`].
//! - Coverage: [`crate::raster::PolygonCoverage`] (pixel centres, top-left rule).
//! - Ties: the buffer stores the depth key as `f32` and a polygon must be strictly
//!   nearer to replace a pixel; polygons are drawn in ascending face id, so the lower id
//!   wins exact ties.
//! - Complexity: O(P s), P polygons of s pixels each, about O(p) for p pixels
//!   (seed 000's table).
//!
//! # Two implementations, one picture
//! [`render_reference`] is the seeds' algorithm written plainly, one
//! [`PolygonCoverage`](crate::raster::PolygonCoverage) per polygon, the depth stepped
//! serially along each span. [`render`] computes the same picture faster with the block
//! rasterizer of `raster/block/`:
//! - coverage by the shared rule's canonical edge expression, evaluated in lanes (a
//!   deliberate twin of [`EdgeFunction::inside`](crate::raster::EdgeFunction::inside),
//!   which `raster::block`'s tests compare with it pixel by pixel): narrow polygons row
//!   by row, wider ones in 16x8 blocks classified exactly by their corners (covered
//!   blocks drawn without edge tests);
//! - the depth key evaluated per pixel from the plane (no serial chain, so any pixel
//!   in any order, eight or sixteen per instruction) instead of stepped along the span;
//! - the depth test takes the nearer key and, on an exactly equal key, the lower face
//!   id, so the drawing order does not matter: small polygons are drawn at once, big
//!   ones tile by tile (64x64 pixels whose buffers stay in the first-level cache);
//! - occlusion culling of the big polygons: per 16x8 block of a tile the farthest key
//!   it holds, kept up to date as blocks are written; a tile's big polygons are drawn
//!   nearest first and skip the blocks whose farthest key is nearer than any of
//!   theirs (exact: such a polygon wins no pixel there, not even a tie; Greene, Kass
//!   and Miller, *Hierarchical Z-buffer visibility*, SIGGRAPH 1993);
//! - a frame of zero bits as the empty buffer, cleared lazily: a 64x64 tile of the frame
//!   is cleared when the first small polygon reaches it, a tile only big polygons reach
//!   starts from an empty tile buffer in cache, and a tile no polygon reaches is written
//!   as background once; so a new frame's pages are first touched where it is drawn,
//!   and a kept frame ([`render_into`], [`Buffers`]) needs no clearing pass;
//! - the kernels compiled for AVX2 or AVX-512 when the processor has them (chosen at
//!   run time; the same operations in the same order, so the same bits, as the
//!   portable build: the tests compare them);
//! - with the `parallel` feature and more than one thread, the image cut into bands of
//!   rows drawn in parallel (the same frame as one thread: a pixel's result depends on
//!   the polygons covering it only).
//!
//! Stats: `polygons`, `polygons_drawn` (those covering a sample), `pixels_tested`,
//! `pixels_written`; the fast path adds `big_polygons` (drawn tile by tile) and the
//! milliseconds of its phases, `setup_and_small_ms` (every polygon set up, the small
//! ones drawn), `binning_ms` and `tiles_ms` (the big ones drawn, the frame resolved),
//! summed over the bands when several threads draw.
//!
//! # Tolerance
//! The per-pixel plane and the reference's serial stepping differ by a few units in
//! the last place of the `f64` key, so after rounding to `f32` a key may differ by one
//! unit of the `f32`. Hence the fast frame's ids equal the reference's at every pixel
//! except where the two nearest polygons' keys are within two units of an `f32`
//! (relative `2 f32::EPSILON`; a brute-force oracle over all polygons checks every
//! differing pixel in the tests), and its depths are within that relative tolerance of
//! the reference's. Coverage and the polygons drawn are exactly the reference's; the
//! pixels tested are fewer (culled blocks are not tested) and the pixels written may
//! differ (they count overwrites, which depend on the order). Keys at or below zero (degenerate cameras only: keys of a prepared view
//! are positive) are clamped to the smallest positive `f32` by the fast path.

mod bands;
mod fast;

use crate::frame::BACKGROUND;
use crate::surface::RenderOptions;
use crate::surface::stats::{ZBufferFastStats, ZBufferStats};
use crate::view::PreparedView;
use crate::{Frame, Result};

pub use crate::cpu::Kernel;
pub use fast::BIG;

/// Renders a prepared view with the z-buffer (the fast implementation; same result as
/// [`render_reference`]).
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, ZBufferStats)> {
    render_with(view, options, Kernel::detect(), bands::thread_count())
}

/// The buffers the z-buffer keeps from one frame to the next: the bins of its tiles, its
/// big polygons and their order, and its tile buffer. With [`render_into`] and a kept
/// [`Frame`], a renderer drawing many frames (a viewer, a walk, a benchmark) allocates
/// nothing and faults in no page after the first frame, as engines keep their render
/// targets. The contents never carry over from one frame to the next.
#[derive(Debug, Default)]
pub struct Buffers(fast::Scratch);

impl Buffers {
    /// Empty buffers (they grow on first use).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

/// [`render`] into an existing frame with kept buffers: the frame is made the size of
/// the view's viewport (reusing its memory when it holds enough pixels, else replaced
/// by a new one) and drawn whole, so it ends exactly as the frame [`render`] returns,
/// whatever it held before (another view's picture, another size). On an error its
/// contents are unspecified.
///
/// ```
/// use obscura::{scene::{demo, Viewport}, view::{prepare, PrepareOptions}, Frame};
/// use obscura::surface::{zbuffer, RenderOptions};
/// let scene = demo::cube();
/// let vp = Viewport::new(64, 48).unwrap();
/// let view = prepare(&scene, &scene.default_camera(vp.aspect()), vp, &PrepareOptions::default()).unwrap();
/// let mut frame = Frame::new(Viewport::new(8, 8).unwrap()).unwrap();
/// let mut buffers = zbuffer::Buffers::new();
/// for _ in 0..2 {
///     zbuffer::render_into(&view, &RenderOptions::default(), &mut frame, &mut buffers).unwrap();
/// }
/// assert_eq!(frame, zbuffer::render(&view, &RenderOptions::default()).unwrap().0);
/// ```
///
/// # Errors
/// As [`render`].
pub fn render_into(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    frame: &mut Frame,
    buffers: &mut Buffers,
) -> Result<ZBufferStats> {
    render_into_with(
        view,
        options,
        Kernel::detect(),
        bands::thread_count(),
        frame,
        buffers,
    )
}

/// Renders with a chosen kernel and number of threads (1 draws on the calling thread;
/// more need the `parallel` feature and draw on rayon's current pool). For tests and
/// benchmarks that compare kernels; [`render`] picks the best.
pub fn render_with(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
) -> Result<(Frame, ZBufferStats)> {
    render_scheduled(view, options, kernel, threads, schedule_of(threads))
}

/// [`render_into`] with a chosen kernel and number of threads (see [`render_with`]).
fn render_into_with(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
    frame: &mut Frame,
    buffers: &mut Buffers,
) -> Result<ZBufferStats> {
    let schedule = schedule_of(threads);
    render_scheduled_into(view, options, kernel, threads, schedule, frame, buffers)
}

/// Bands of rows for several threads, else the whole frame at once.
fn schedule_of(threads: usize) -> Schedule {
    if threads > 1 {
        Schedule::Bands
    } else {
        Schedule::Whole
    }
}

/// How the frame is cut into units of work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Schedule {
    /// The whole frame at once: every polygon once.
    Whole,
    /// Bands of rows, each with the polygons that reach it.
    Bands,
}

/// A new frame drawn with the schedule (a fresh frame of zero bits: its pages are first
/// touched where the drawing first writes them).
fn render_scheduled(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
    schedule: Schedule,
) -> Result<(Frame, ZBufferStats)> {
    let mut frame = Frame::zeroed(view.viewport())?;
    let buffers = &mut Buffers::default();
    let stats = render_scheduled_into(
        view, options, kernel, threads, schedule, &mut frame, buffers,
    )?;
    Ok((frame, stats))
}

/// Draws the view into `frame` (reshaped to its viewport) with the schedule.
fn render_scheduled_into(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
    schedule: Schedule,
    frame: &mut Frame,
    buffers: &mut Buffers,
) -> Result<ZBufferStats> {
    let bands = match schedule {
        Schedule::Bands => view.viewport().height.div_ceil(bands::BAND_ROWS),
        Schedule::Whole => 1,
    };
    check_budget(view, options, bands)?;
    frame.reshape(view.viewport())?;
    let counts = if schedule == Schedule::Bands {
        bands::draw_banded(
            view,
            options.fill_rule,
            kernel,
            threads,
            frame,
            &options.deadline,
        )
    } else {
        fast::draw_all(view, options.fill_rule, kernel, frame, &mut buffers.0)
    };
    // Bands skipped past the deadline leave the frame unfinished: never returned.
    options.check_time("z-buffer bands")?;
    Ok(counts.fast_stats(view))
}

/// The structure named by the z-buffer's budget errors.
pub const BUDGET_STRUCTURE: &str = "z-buffer big-polygon bins";

/// Refuses, before drawing, a view whose big polygons (wider or taller than [`BIG`]
/// pixels, kept with their setups and put in the bins of the 64x64 tiles they overlap)
/// would take more than the budget of `options` (see [`crate::budget`]): 16.6 million
/// large triangles at 320x240 needed 3.7 GB. Per big polygon: its setup and order
/// entry in each band of rows it reaches, 4 bytes per tile it overlaps; per small one,
/// 4 bytes per band when drawn in bands. First the bound with every polygon big and
/// covering every tile; only when that passes the budget, the polygons' boxes are
/// measured (one pass over the view's vertices).
fn check_budget(view: &PreparedView<'_>, options: &RenderOptions, bands: u32) -> Result<()> {
    let budget = options.budget();
    let vp = view.viewport();
    let (tiles_x, tiles_y) = (
        vp.width.div_ceil(fast::TILE),
        vp.height.div_ceil(fast::TILE),
    );
    let bands_u = u64::from(bands);
    let per_band = fast::BIG_ENTRY_BYTES + 4;
    let worst = u64::from(tiles_x) * u64::from(tiles_y) * 4 + bands_u * per_band;
    let n = view.polygon_count() as u64;
    if n.saturating_mul(worst) <= budget.limit() {
        return Ok(());
    }
    let (starts, indices, _) = view.polygon_arrays();
    let vertices = view.vertices();
    let (w, h) = (f64::from(vp.width), f64::from(vp.height));
    let (mut bytes, mut big) = (0u64, 0u64);
    for p in 0..view.polygon_count() {
        let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
        let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for &i in &indices[starts[p] as usize..starts[p + 1] as usize] {
            let v = &vertices[i as usize];
            (x0, x1, y0, y1) = (x0.min(v.x), x1.max(v.x), y0.min(v.y), y1.max(v.y));
        }
        // Pixels (with a margin of one) of the box, clipped to the image.
        let (x0, x1) = ((x0 - 1.0).clamp(0.0, w), (x1 + 1.0).clamp(0.0, w));
        let (y0, y1) = ((y0 - 1.0).clamp(0.0, h), (y1 + 1.0).clamp(0.0, h));
        if !(x1 > x0 && y1 > y0) {
            continue;
        }
        let band_rows = f64::from(bands::BAND_ROWS);
        let reached = if bands > 1 {
            ((y1 / band_rows).ceil() - (y0 / band_rows).floor()).max(1.0) as u64
        } else {
            1
        };
        if x1 - x0 > f64::from(BIG) || y1 - y0 > f64::from(BIG) {
            big += 1;
            let tile = f64::from(fast::TILE);
            let tiles = ((x1 / tile).ceil() - (x0 / tile).floor()).max(1.0)
                * ((y1 / tile).ceil() - (y0 / tile).floor()).max(1.0);
            bytes = bytes.saturating_add(reached * per_band + 4 * tiles as u64);
        } else if bands > 1 {
            bytes = bytes.saturating_add(4 * reached);
        }
    }
    budget.check(BUDGET_STRUCTURE, big, bytes)
}

/// Counts of what the z-buffer did, and the seconds of its phases.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Counts {
    drawn: u64,
    tested: u64,
    written: u64,
    /// Polygons kept for the tiles (wider or taller than the small ones).
    big: u64,
    /// Seconds: every polygon set up and the small ones drawn; the big ones sorted
    /// and binned; the tiles drawn and the frame resolved.
    seconds: [f64; 3],
}

impl Counts {
    fn add(&mut self, o: Counts) {
        self.drawn += o.drawn;
        self.tested += o.tested;
        self.written += o.written;
        self.big += o.big;
        for (a, b) in self.seconds.iter_mut().zip(o.seconds) {
            *a += b;
        }
    }

    fn stats(self, view: &PreparedView<'_>) -> ZBufferStats {
        ZBufferStats {
            polygons: view.polygon_count() as u64,
            polygons_drawn: self.drawn,
            pixels_tested: self.tested,
            pixels_written: self.written,
            fast: None,
        }
    }

    /// [`Counts::stats`] with the fast path's own figures: the big polygons and the
    /// milliseconds of each phase (summed over bands, so thread time when several
    /// threads draw).
    fn fast_stats(self, view: &PreparedView<'_>) -> ZBufferStats {
        let ms = |s: f64| (s * 1e5).round() / 100.0;
        ZBufferStats {
            fast: Some(ZBufferFastStats {
                big_polygons: self.big,
                setup_and_small_ms: ms(self.seconds[0]),
                binning_ms: ms(self.seconds[1]),
                tiles_ms: ms(self.seconds[2]),
            }),
            ..self.stats(view)
        }
    }
}

/// The z-buffer as the seeds write it: per polygon its coverage and depth plane, per
/// span the depth stepped from the plane at the span's start. Slow (three allocations
/// per polygon) but plain; [`render`] must give the same frame.
pub fn render_reference(
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<(Frame, ZBufferStats)> {
    let vp = view.viewport();
    let mut frame = Frame::new(vp)?;
    let w = vp.width as usize;
    let mut zbuf = vec![f32::NEG_INFINITY; vp.pixel_count()];
    let mut c = Counts::default();
    for poly in view.polygons() {
        let Some(coverage) = poly.coverage(options.fill_rule, vp.width, vp.height) else {
            continue;
        };
        let Some(plane) = poly.depth_plane() else {
            continue;
        };
        c.drawn += 1;
        for (y, x0, x1) in coverage.spans() {
            let row = y as usize * w;
            let mut z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
            for x in x0 as usize..x1 as usize {
                let zf = z as f32;
                if zf > zbuf[row + x] {
                    zbuf[row + x] = zf;
                    frame.ids[row + x] = poly.face;
                    c.written += 1;
                }
                z += plane.dzdx;
            }
            c.tested += u64::from(x1 - x0);
        }
    }
    let t = view.transform();
    for (d, (&z, &id)) in frame.depth.iter_mut().zip(zbuf.iter().zip(&frame.ids)) {
        if id != BACKGROUND {
            *d = t.depth_of_key(z);
        }
    }
    Ok((frame, c.stats(view)))
}

#[cfg(test)]
mod tests;
