//! The pair walk: a polygon at most [`PAIR_WIDTH`] pixels wide drawn two rows per
//! lane vector (see [`super::rows`] for the row walk it shortens).

use super::rows::{edge_columns, rows_start};
use super::{BlockSetup, BlockTarget, Counts};
use crate::raster::lanes::Lanes;

/// Polygons at most this many pixels wide are drawn two rows per lane vector.
pub(super) const PAIR_WIDTH: u32 = 4;
/// The column of each lane in [`draw_pairs`].
const PAIR_COLUMN: [f64; 8] = [0.0, 1.0, 2.0, 3.0, 0.0, 1.0, 2.0, 3.0];
/// The row (of the two) of each lane in [`draw_pairs`].
const PAIR_ROW: [f64; 8] = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];

/// Draws the rows `rows` of the columns `bx + c` for the bits `c` of `lanes` (of the
/// four lowest), two rows per lane vector: lanes 0-3 a row, 4-7 the next. Every lane
/// computes the same expressions as [`draw_block`](super::rows::draw_block) does for its pixel (the column and
/// row parts of the edges and of the depth, in the same order), so the two give the
/// same coverage and keys; a polygon at most four pixels wide (thin slivers are common
/// in real meshes) then takes half as many row steps.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_pairs<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    bx: u32,
    rows: std::ops::Range<u32>,
    lanes: u8,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let lanes = lanes & 15;
    if lanes == 0 {
        return;
    }
    let Some(mut at) = rows_start(target, bx, &rows, 8 - lanes.leading_zeros() as usize) else {
        return;
    };
    let stride = target.stride;
    let (keys, ids) = (&mut *target.keys, &mut *target.ids);
    let (column, row_of) = (l.load(&PAIR_COLUMN), l.load(&PAIR_ROW));
    let zc = l.mul(
        l.splat(s.dzdx),
        l.add_scalar(column, f64::from(bx) - f64::from(s.rect.x0)),
    );
    let (col, bound) = edge_columns(l, s, l.add_scalar(column, f64::from(bx) + 0.5));
    let mut y = rows.start;
    while y < rows.end {
        // The second row only if there is one.
        let mut cover = if rows.end - y >= 2 {
            lanes | lanes << 4
        } else {
            lanes
        };
        let py = l.add_scalar(row_of, f64::from(y) + 0.5);
        for k in 0..E {
            let row = l.mul(l.splat(s.sdx[k]), l.sub_scalar(py, s.oy[k]));
            cover &= l.less(0xff, l.sub(col[k], row), bound[k]);
        }
        let zr = l.add_scalar(
            l.mul(
                l.splat(s.dzdy),
                l.add_scalar(row_of, f64::from(y) - f64::from(s.rect.y0)),
            ),
            s.z0,
        );
        counts.tested += u64::from(cover.count_ones());
        // SAFETY: `cover` is within `lanes` of rows `y` and `y + 1` (only when it is in
        // `rows`), whose pixels are inside the slices (checked above for the last row).
        let taken = unsafe { l.depth_test_pair(keys, ids, at, stride, cover, l.add(zc, zr), face) };
        counts.written += u64::from(taken.count_ones());
        at += 2 * stride;
        y += 2;
    }
}
