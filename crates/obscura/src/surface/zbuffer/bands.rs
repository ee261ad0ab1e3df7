//! Bands of rows as units of parallel work: polygons are binned by the rows they span,
//! then each band draws its polygons into its own rows of the frame and resolves them.
//!
//! A pixel belongs to one band, and its key and the depth test depend on the polygon
//! and the pixel only (not on the order of drawing): the frame is identical whatever
//! the number of bands or threads.

use crate::Frame;
use crate::raster::{FillRule, sample_range};
use crate::view::PreparedView;

use super::Counts;
use super::fast::{Band, Scratch, TILE, draw_band};
use crate::cpu::Kernel;

/// Rows per band: one row of tiles.
pub(super) const BAND_ROWS: u32 = TILE;

/// Threads available to the z-buffer: rayon's current pool with the `parallel`
/// feature, else 1.
pub(super) fn thread_count() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// The bands `[b0, b1)` whose rows hold the samples of a polygon with vertices between
/// rows `miny` and `maxy` (the rows of `sample_rect`, by its [`sample_range`]); `None`
/// when there are none.
#[inline]
fn band_range(miny: f64, maxy: f64, height: u32) -> Option<(u32, u32)> {
    if !(miny.is_finite() && maxy.is_finite()) {
        return None;
    }
    let (y0, y1) = sample_range(miny, maxy, height);
    (y0 < y1).then(|| (y0 / BAND_ROWS, (y1 - 1) / BAND_ROWS + 1))
}

/// Per band, the polygons of `range` that may cover a sample in it, ascending.
fn bin(view: &PreparedView<'_>, range: std::ops::Range<usize>, bands: usize) -> Vec<Vec<u32>> {
    let (starts, indices, _) = view.polygon_arrays();
    let vertices = view.vertices();
    let height = view.viewport().height;
    let mut lists = vec![Vec::new(); bands];
    for p in range {
        let (s, e) = (starts[p] as usize, starts[p + 1] as usize);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &i in &indices[s..e] {
            let y = vertices[i as usize].y;
            lo = lo.min(y);
            hi = hi.max(y);
        }
        if let Some((b0, b1)) = band_range(lo, hi, height) {
            for list in &mut lists[b0 as usize..b1 as usize] {
                list.push(p as u32);
            }
        }
    }
    lists
}

/// Draws the view into the frame band by band (whatever the frame held before), on `threads` threads when the
/// `parallel` feature is on (else, or with one thread, in order on this one).
pub(super) fn draw_banded(
    view: &PreparedView<'_>,
    fill: FillRule,
    kernel: Kernel,
    threads: usize,
    frame: &mut Frame,
    deadline: &crate::work::Deadline,
) -> Counts {
    let (width, height) = (frame.width, frame.height);
    let bands = height.div_ceil(BAND_ROWS) as usize;
    let n = view.polygon_count();
    let chunks = threads.max(1);
    let per = n.div_ceil(chunks).max(1);
    let ranges: Vec<std::ops::Range<usize>> =
        (0..n).step_by(per).map(|s| s..(s + per).min(n)).collect();
    let rows = BAND_ROWS as usize * width as usize;
    let draw = |b: usize, keys: &mut [f32], ids: &mut [u32], lists: &[Vec<Vec<u32>>]| {
        // Past the deadline the bands left are skipped; the caller returns its error.
        if deadline.is_over() {
            return Counts::default();
        }
        let mut band = Band {
            keys,
            ids,
            width,
            height,
            y0: b as u32 * BAND_ROWS,
        };
        let polys = lists.iter().flat_map(|l| l[b].iter().map(|&p| p as usize));
        draw_band(
            view,
            polys,
            fill,
            kernel,
            &mut band,
            &mut Scratch::default(),
        )
    };
    #[cfg(feature = "parallel")]
    if threads > 1 {
        use rayon::prelude::*;
        let lists: Vec<Vec<Vec<u32>>> = ranges
            .into_par_iter()
            .map(|r| bin(view, r, bands))
            .collect();
        return frame
            .depth
            .par_chunks_mut(rows)
            .zip(frame.ids.par_chunks_mut(rows))
            .enumerate()
            .map(|(b, (keys, ids))| draw(b, keys, ids, &lists))
            .reduce(Counts::default, |mut a, b| {
                a.add(b);
                a
            });
    }
    let lists: Vec<Vec<Vec<u32>>> = ranges.into_iter().map(|r| bin(view, r, bands)).collect();
    let mut total = Counts::default();
    for (b, (keys, ids)) in frame
        .depth
        .chunks_mut(rows)
        .zip(frame.ids.chunks_mut(rows))
        .enumerate()
    {
        total.add(draw(b, keys, ids, &lists));
    }
    total
}
