//! The row walk. Narrow polygons: with [`Align::Polygon`](super::Align::Polygon), a polygon at most 16 pixels wide
//! (most triangles of a detailed model) is walked row by row from its first column,
//! every row tested against the edges, without a branch on whether the row has a
//! covered sample: such rows are frequent in thin triangles and unpredictable, and
//! the masked depth test of no pixel touches no memory. The rows' edge and depth
//! parts are computed eight rows at a time in lanes and read back as broadcasts from
//! memory: per row, a scalar part broadcast into a vector would take the shuffle
//! port that the compares into masks also need. Measured on the small triangles of
//! the Sponza atrium (169k of them, at most 64 pixels on a side): 17.1 ms drawn block
//! by block, 15.1 ms row by row with scalar row parts, 12.9 ms with row parts in
//! lanes. A polygon at most four pixels wide (slivers: 1.4 covered pixels a row on
//! the tall thin triangles of Sponza) takes two rows per lane vector, lanes 0-3 one
//! row and 4-7 the next, each lane computing its pixel's expressions as the
//! one-row walk does: half the row steps, 12.6 -> 12.3 ms ([`super::pairs`]).
//!
//! The block walk ([`super::blocks`]) draws each of its blocks' rows here too.
//!
//! Source: Pineda, *A parallel algorithm for polygon rasterization* (SIGGRAPH 1988):
//! edge functions evaluated across pixels in parallel.

use super::{BLOCK, BlockSetup, BlockTarget, Counts, LANE};
use crate::raster::lanes::Lanes;

/// Draws the rows `rows` (any number) of the columns `bx + l` for the lanes `l` of
/// `lanes` (16 of them when `WIDE`, else 8); `FULL` when every such sample is known to
/// be covered. The rows' edge and depth parts are computed eight rows at a time in
/// lanes and read back as broadcasts from memory (see the module doc).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_block<L: Lanes, const E: usize, const WIDE: bool, const FULL: bool>(
    l: L,
    s: &BlockSetup<E>,
    bx: u32,
    rows: std::ops::Range<u32>,
    lanes: u16,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    if lanes == 0 {
        return;
    }
    let Some(mut at) = rows_start(target, bx, &rows, 16 - lanes.leading_zeros() as usize) else {
        return;
    };
    let stride = target.stride;
    let (keys, ids) = (&mut *target.keys, &mut *target.ids);
    let lane = l.load(&LANE);
    // Depth: the column part per lane, the row part per row.
    let dx = f64::from(bx) - f64::from(s.rect.x0);
    let dzdx = l.splat(s.dzdx);
    let zc_lo = l.mul(dzdx, l.add_scalar(lane, dx));
    let zc_hi = if WIDE {
        l.mul(dzdx, l.add_scalar(lane, dx + 8.0))
    } else {
        zc_lo
    };
    // Coverage: per edge the column part `sdy (px - ox)` per lane and the row part
    // `sdx (py - oy)` per row. (Loops, not closures: a closure is not compiled for the
    // caller's instruction set, so the lane operations in it would not be inlined.)
    // Sample positions are small integers plus a half: exact.
    let px = l.add_scalar(lane, f64::from(bx) + 0.5);
    let px_hi = l.add_scalar(lane, f64::from(bx) + 8.5);
    let (mut col_lo, mut col_hi, mut bound) = ([px; E], [px; E], [px; E]);
    if !FULL {
        (col_lo, bound) = edge_columns(l, s, px);
        if WIDE {
            col_hi = edge_columns(l, s, px_hi).0;
        }
    }
    let (lanes_lo, lanes_hi) = (lanes as u8, (lanes >> 8) as u8);
    let mut y = rows.start;
    while y < rows.end {
        let zr = l.to_array(l.add_scalar(
            l.mul(
                l.splat(s.dzdy),
                l.add_scalar(lane, f64::from(y) - f64::from(s.rect.y0)),
            ),
            s.z0,
        ));
        let mut row = [[0.0; 8]; E];
        if !FULL {
            let py = l.add_scalar(lane, f64::from(y) + 0.5);
            for (row, (&sdx, &oy)) in row.iter_mut().zip(s.sdx.iter().zip(&s.oy)) {
                *row = l.to_array(l.mul(l.splat(sdx), l.sub_scalar(py, oy)));
            }
        }
        for (q, &zj) in zr.iter().enumerate().take((rows.end - y) as usize) {
            let cover = if FULL {
                lanes
            } else {
                let mut lo = lanes_lo;
                let mut hi = lanes_hi;
                // Independent compares, their masks combined after (a chain of masked
                // compares would wait for each other).
                for k in 0..E {
                    lo &= l.less(0xff, l.sub_scalar(col_lo[k], row[k][q]), bound[k]);
                    if WIDE {
                        hi &= l.less(0xff, l.sub_scalar(col_hi[k], row[k][q]), bound[k]);
                    }
                }
                u16::from(lo) | if WIDE { u16::from(hi) << 8 } else { 0 }
            };
            // No branch on an empty row (thin polygons have many, unpredictably): the
            // masked test of no pixel accesses nothing.
            counts.tested += u64::from(cover.count_ones());
            // SAFETY: `cover` is within `lanes`, whose pixels in these rows are inside
            // the slices (checked above for the last row).
            let taken =
                unsafe { test_row::<L, WIDE>(l, keys, ids, at, cover, [zc_lo, zc_hi], zj, face) };
            counts.written += u64::from(taken.count_ones());
            at += stride;
        }
        y += BLOCK;
    }
}

/// Where the first of `rows` starts at column `bx` in the target, if every row of
/// `rows` holds its pixels `bx..bx + reach` inside the target's slices: the depth tests
/// of the row walks then access them without checking. Only the last row needs the
/// check. (The callers clip the rows to the target, so it never fails.)
#[inline(always)]
pub(super) fn rows_start(
    target: &BlockTarget<'_>,
    bx: u32,
    rows: &std::ops::Range<u32>,
    reach: usize,
) -> Option<usize> {
    let last_row = rows.end.checked_sub(rows.start)?.checked_sub(1)? as usize;
    let at = target.at(bx, rows.start);
    let end = at + last_row * target.stride + reach;
    (end <= target.keys.len().min(target.ids.len())).then_some(at)
}

/// Per edge, the column part `sdy (px - ox)` of the edge expression at the lanes'
/// sample columns `px`, and the edge's bound, in lanes. (A loop, not a closure: a
/// closure is not compiled for the caller's instruction set.)
#[inline(always)]
pub(super) fn edge_columns<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    px: L::F,
) -> ([L::F; E], [L::F; E]) {
    let (mut col, mut bound) = ([px; E], [px; E]);
    for k in 0..E {
        col[k] = l.mul(l.splat(s.sdy[k]), l.sub_scalar(px, s.ox[k]));
        bound[k] = l.splat(s.bound[k]);
    }
    (col, bound)
}

/// Depth-tests the pixels `cover` of one row of a block at `at` (16 lanes when `WIDE`,
/// else the low 8), their keys the column parts `zc` (lanes 0-7, 8-15) plus the row's
/// part `zj`; returns the pixels taken.
///
/// # Safety
/// The pixels of `cover` in this row are inside the slices.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn test_row<L: Lanes, const WIDE: bool>(
    l: L,
    keys: &mut [f32],
    ids: &mut [u32],
    at: usize,
    cover: u16,
    zc: [L::F; 2],
    zj: f64,
    face: u32,
) -> u16 {
    let lo = l.add_scalar(zc[0], zj);
    // SAFETY: the caller's contract.
    unsafe {
        if WIDE {
            l.depth_test16(keys, ids, at, cover, lo, l.add_scalar(zc[1], zj), face)
        } else {
            u16::from(l.depth_test8(keys, ids, at, cover as u8, lo, face))
        }
    }
}
