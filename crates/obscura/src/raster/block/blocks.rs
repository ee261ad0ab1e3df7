//! The block walk: a polygon wider than the row walks take is walked block by block; each block is first
//! classified by its corner samples. Every step of the edge expression is monotonic
//! in `px` along a row and in `py` along a column, so the sample of a block that is
//! most inside an edge (resp. most outside) is a corner chosen by the signs of `sdy`
//! and `sdx`: if that corner is outside some edge no sample of the block is covered
//! (the block is skipped), and if the other corner is inside every edge all are (the
//! block is drawn without edge tests). The classification is exact, not
//! conservative. Both walks draw rows with the same function (`draw_block`), so a
//! pixel's coverage and key do not depend on the walk.
//!
//! Source: Greene, *Hierarchical polygon tiling with coverage masks* (SIGGRAPH 1996):
//! blocks classified by their corners against each edge.

use super::rows::draw_block;
use super::{BLOCK, BlockSetup, BlockTarget, Counts, lane_range};
use crate::raster::PixelRect;
use crate::raster::lanes::{Lanes, lanes_below};

/// The polygon's edges in lanes (one edge per lane), for classifying blocks.
struct EdgeLanes<F> {
    ox: F,
    oy: F,
    sdx: F,
    sdy: F,
    bound: F,
    /// Lanes where `sdy > 0`: `t` grows to the right, the leftmost sample is most inside.
    rising_x: u8,
    /// Lanes where `sdx > 0`: `t` shrinks downwards, the lowest sample is most inside.
    falling_y: u8,
    used: u8,
}

impl<F: Copy> EdgeLanes<F> {
    #[inline(always)]
    fn new<L: Lanes<F = F>, const E: usize>(l: L, s: &BlockSetup<E>) -> Self {
        let mut rising_x = 0u8;
        let mut falling_y = 0u8;
        for k in 0..E {
            rising_x |= u8::from(s.sdy[k] > 0.0) << k;
            falling_y |= u8::from(s.sdx[k] > 0.0) << k;
        }
        // Built from values, not stored and reloaded: a vector load of scalars just
        // stored stalls until the stores reach the cache.
        let pad = |a: &[f64; E], v: f64| {
            let mut o = [v; 8];
            let mut k = 0;
            while k < E {
                o[k] = a[k];
                k += 1;
            }
            o
        };
        EdgeLanes {
            ox: l.set(pad(&s.ox, 0.0)),
            oy: l.set(pad(&s.oy, 0.0)),
            sdx: l.set(pad(&s.sdx, 0.0)),
            sdy: l.set(pad(&s.sdy, 0.0)),
            bound: l.set(pad(&s.bound, f64::INFINITY)),
            rising_x,
            falling_y,
            used: lanes_below(E),
        }
    }
}

/// How samples lie with respect to a polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Outside,
    Inside,
    Partial,
}

/// Classifies the samples of the pixels `r` by their corners (see the module doc).
#[inline(always)]
fn classify<L: Lanes>(l: L, e: &EdgeLanes<L::F>, r: PixelRect) -> Class {
    let (left, right) = (
        l.splat(f64::from(r.x0) + 0.5),
        l.splat(f64::from(r.x1) - 0.5),
    );
    let (top, bottom) = (
        l.splat(f64::from(r.y0) + 0.5),
        l.splat(f64::from(r.y1) - 0.5),
    );
    let (px, py) = (
        l.select(e.rising_x, left, right),
        l.select(e.falling_y, bottom, top),
    );
    let best = l.sub(l.mul(e.sdy, l.sub(px, e.ox)), l.mul(e.sdx, l.sub(py, e.oy)));
    if l.less(e.used, best, e.bound) != e.used {
        return Class::Outside;
    }
    let (px, py) = (
        l.select(e.rising_x, right, left),
        l.select(e.falling_y, top, bottom),
    );
    let worst = l.sub(l.mul(e.sdy, l.sub(px, e.ox)), l.mul(e.sdx, l.sub(py, e.oy)));
    if l.less(e.used, worst, e.bound) == e.used {
        Class::Inside
    } else {
        Class::Partial
    }
}

/// [`draw`] with blocks of 16 columns and 8 rows from `(bx0, by0)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_blocks<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    r: PixelRect,
    bx0: u32,
    by0: u32,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let bw = 2 * BLOCK;
    if r.x1 - bx0 <= bw && r.y1 - by0 <= BLOCK {
        let lanes = lane_range(r.x0 - bx0, r.x1 - bx0);
        draw_block::<L, E, true, false>(l, s, bx0, r.y0..r.y1, lanes, target, face, counts);
        return;
    }
    if target.hides(s, r) {
        return;
    }
    let edges = EdgeLanes::new(l, s);
    // The whole part first: a tile inside a big polygon needs no edge test at all.
    let all_inside = match classify(l, &edges, r) {
        Class::Outside => return,
        Class::Inside => true,
        Class::Partial => false,
    };
    let mut by = by0;
    while by < r.y1 {
        let (cy0, cy1) = (by.max(r.y0), (by + BLOCK).min(r.y1));
        let mut bx = bx0;
        while bx < r.x1 {
            let (cx0, cx1) = (bx.max(r.x0), (bx + bw).min(r.x1));
            let c = PixelRect {
                x0: cx0,
                y0: cy0,
                x1: cx1,
                y1: cy1,
            };
            if target.hides(s, c) {
                bx += bw;
                continue;
            }
            let full = all_inside
                || match classify(l, &edges, c) {
                    Class::Outside => {
                        bx += bw;
                        continue;
                    }
                    Class::Inside => true,
                    Class::Partial => false,
                };
            let lanes = lane_range(cx0 - bx, cx1 - bx);
            let written = counts.written;
            if full {
                draw_block::<L, E, true, true>(l, s, bx, cy0..cy1, lanes, target, face, counts);
            } else {
                draw_block::<L, E, true, false>(l, s, bx, cy0..cy1, lanes, target, face, counts);
            }
            if counts.written != written {
                target.refresh(bx, by);
            }
            bx += bw;
        }
        by += BLOCK;
    }
}
