//! The z-buffer: the reference every other algorithm is checked against.
//!
//! Sources: seed 000 ("Αλγόριθμος Z-buffer"), 002 ("Algoritmo Z-Buffer"), 003
//! ("Buffer de adâncime"), 004 ("Алгоритм z-буфера"). For each polygon, for each pixel it
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
//! # Two implementations, one result
//! [`render_reference`] is the seeds' algorithm written plainly, one
//! [`PolygonCoverage`](crate::raster::PolygonCoverage) per polygon. [`render`] computes
//! the same frame (ids, depths and stats bit for bit; the tests check it on random
//! scenes) faster:
//! - polygon setup without allocation ([`PolygonSetup`](crate::raster::PolygonSetup)),
//!   rejecting polygons whose box holds no sample before any edge is set up;
//! - narrow polygons tested pixel by pixel over their box, wide ones by row spans;
//! - the incremental depth computed in exact linear runs, eight pixels at a time
//!   ([`crate::raster::depth_span`]);
//! - the frame's depth array used as the buffer (no second buffer);
//! - the kernels compiled for AVX2 or AVX-512 when the processor has them (chosen at
//!   run time; the same code, so the same results, as the portable build);
//! - with the `parallel` feature and more than one thread, the image cut into bands of
//!   rows drawn in parallel, each band drawing its polygons in ascending order; on one
//!   thread, bands too when the polygons are large (each band's buffers stay in cache
//!   while the polygons overdraw them).

mod bands;
mod fast;

use crate::frame::BACKGROUND;
use crate::surface::{RenderOptions, Stats};
use crate::view::PreparedView;
use crate::{Frame, Result};

pub use fast::Kernel;

/// Renders a prepared view with the z-buffer (the fast implementation; same result as
/// [`render_reference`]).
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, Stats)> {
    render_with(view, options, Kernel::detect(), bands::thread_count())
}

/// Renders with a chosen kernel and number of threads (1 draws on the calling thread;
/// more need the `parallel` feature and draw on rayon's current pool). For tests and
/// benchmarks that compare kernels; [`render`] picks the best.
pub fn render_with(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
) -> Result<(Frame, Stats)> {
    let schedule = if threads > 1 || bands::prefers_bands(view) {
        Schedule::Bands
    } else {
        Schedule::Whole
    };
    render_scheduled(view, options, kernel, threads, schedule)
}

/// How the frame is cut into units of work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Schedule {
    /// The whole frame at once: every polygon once, in order.
    Whole,
    /// Bands of rows, each with the polygons that reach it, in order.
    Bands,
}

fn render_scheduled(
    view: &PreparedView<'_>,
    options: &RenderOptions,
    kernel: Kernel,
    threads: usize,
    schedule: Schedule,
) -> Result<(Frame, Stats)> {
    let mut frame = Frame::new(view.viewport())?;
    let counts = if schedule == Schedule::Bands {
        bands::draw_banded(view, options.fill_rule, kernel, threads, &mut frame)
    } else {
        let c = fast::draw_all(view, options.fill_rule, kernel, &mut frame);
        fast::keys_to_depths(view.transform(), kernel, &mut frame);
        c
    };
    Ok((frame, counts.stats(view)))
}

/// Counts of what the z-buffer did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Counts {
    drawn: u64,
    tested: u64,
    written: u64,
}

impl Counts {
    fn add(&mut self, o: Counts) {
        self.drawn += o.drawn;
        self.tested += o.tested;
        self.written += o.written;
    }

    fn stats(self, view: &PreparedView<'_>) -> Stats {
        let mut stats = Stats::default();
        stats.set("polygons", view.polygon_count() as f64);
        stats.set("polygons_drawn", self.drawn as f64);
        stats.set("pixels_tested", self.tested as f64);
        stats.set("pixels_written", self.written as f64);
        stats
    }
}

/// The z-buffer as the seeds write it: per polygon its coverage and depth plane, per
/// span the depth stepped from the plane at the span's start. Slow (three allocations
/// per polygon) but plain; [`render`] must give the same frame.
pub fn render_reference(
    view: &PreparedView<'_>,
    options: &RenderOptions,
) -> Result<(Frame, Stats)> {
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
            *d = t.depth_of_zq(f64::from(z)) as f32;
        }
    }
    Ok((frame, c.stats(view)))
}

#[cfg(test)]
mod tests;
