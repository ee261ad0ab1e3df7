//! Block rasterization: a convex polygon drawn into a depth buffer row by row (narrow
//! polygons) or in blocks of 16x8 pixels, eight pixels per lane vector, generic over
//! [`Lanes`].
//!
//! - Input: a polygon set up once ([`BlockSetup`]: its edges in the form below, its
//!   sample rectangle, its depth-key plane), a region of the image (a tile, a band of
//!   rows, the whole image) and rows of the buffer described in [`super::lanes`].
//! - Output: the buffer with the polygon's covered pixels depth-tested; counts of the
//!   pixels tested and taken.
//! - Coverage: exactly the shared rule of
//!   [`PolygonCoverage::covers`](super::PolygonCoverage::covers). Edge `e` with canonical origin `(ox, oy)`,
//!   direction `(dx, dy)` and orientation `sign` is stored as `sdx = sign dx`,
//!   `sdy = sign dy`; per sample the rasterizer computes
//!   `t = sdy (px - ox) - sdx (py - oy)`, which is `-sign (dx (py - oy) - dy (px - ox))`
//!   bit for bit (negation is exact and rounding to nearest is symmetric), and the
//!   sample is inside when `t < bound`, `bound` being `0` for an edge that excludes its
//!   samples and the smallest positive double for one that includes them.
//! - Depth: the seeds' plane of the depth key, evaluated per pixel:
//!   `z(i, j) = (z0 + dzdy (j - y0)) + dzdx (i - x0)` from the key `z0` at the first
//!   sample `(x0 + 0.5, y0 + 0.5)` of the polygon's rectangle, in `f64`. A pixel's key
//!   depends on the polygon and the pixel only, not on how the image is cut into
//!   blocks, tiles or bands. It differs from the reference's serial stepping
//!   `z += dz/dx` by a few units in the last place of the `f64`: the `f32` keys differ
//!   at most where the reference's keys are within one `f32` unit of each other.
//! - Complexity: per polygon O(n) setup for n edges; per row O(n) in the row walk;
//!   in the block walk, per block O(n) to classify it, then per row O(n) for a partly
//!   covered block and O(1) for a covered one. The
//!   part of the polygon in the region is classified first, as one block: a covered
//!   tile is drawn without edge tests, an uncovered one costs nothing more.
//! - Limitations: at most [`MAX_EDGES`] edges ([`BlockSetup::new`] refuses others).
//!   The caller picks the edge count `E` of a setup: 3 for triangles, 4 for quads, 8
//!   for the rest (unused edges hold every sample inside).
//! - Layout: [`BlockSetup`] and the batched triangle setups in `setup`; the view of
//!   the buffer a polygon is drawn into ([`BlockTarget`]) in `target`; [`draw`] picks
//!   one of three walks: two rows per lane vector (`pairs`), row by row (`rows`), or
//!   block by block (`blocks`); the occlusion bounds ([`nearest_key`],
//!   [`BlockTarget::with_farthest`]) in `occlusion`; [`resolve`] in `resolve`.
//! - Sources: seed 000 "Αλγόριθμος Z-buffer" (the depth test, the plane); Pineda, *A
//!   parallel algorithm for polygon rasterization* (SIGGRAPH 1988, edge functions);
//!   Greene, *Hierarchical polygon tiling with coverage masks* (SIGGRAPH 1996, block
//!   classification by corners).

mod blocks;
mod occlusion;
mod pairs;
mod resolve;
mod rows;
mod setup;
mod target;
#[cfg(test)]
mod tests;

pub(crate) use occlusion::min16;
pub use occlusion::nearest_key;
pub use resolve::resolve;
#[cfg(test)]
pub use setup::TriangleBatch;
pub use setup::{BlockSetup, TrianglePoints, triangle, triangles8};
pub use target::BlockTarget;

use super::PixelRect;
use super::lanes::{Lanes, lanes_below16};

/// The most edges a [`BlockSetup`] holds (one lane each when blocks are classified).
pub const MAX_EDGES: usize = 8;

/// Rows of a block, and columns of a narrow one (a wide block has twice as many).
pub const BLOCK: u32 = 8;

/// Lane offsets `0, 1, ..., 7`.
const LANE: [f64; 8] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];

/// Pixels tested (covered) and taken by a drawing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Covered pixels, each depth-tested.
    pub tested: u64,
    /// Pixels that passed the test and were written.
    pub written: u64,
}

/// Where blocks start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// At the polygon's rectangle (fewest blocks); a polygon at most 16 pixels wide
    /// is walked row by row instead (see the row walk, `rows.rs`).
    Polygon,
    /// On the image's grid of 16x8 blocks (no block crosses a tile's border, and a
    /// row of a block is one cache line of keys when the rows are aligned).
    Grid,
}

/// The mask of lanes `a..b` of a block row (`a <= b <= 16`).
#[inline(always)]
fn lane_range(a: u32, b: u32) -> u16 {
    lanes_below16(b as usize) & !lanes_below16(a as usize)
}

/// Draws the polygon `s` into the pixels of `region` (image coordinates) that the
/// target holds, with encoded id `face`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn draw<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    region: PixelRect,
    align: Align,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let t = target.rect();
    let r = PixelRect {
        x0: s.rect.x0.max(region.x0).max(t.x0),
        y0: s.rect.y0.max(region.y0).max(t.y0),
        x1: s.rect.x1.min(region.x1).min(t.x1),
        y1: s.rect.y1.min(region.y1).min(t.y1),
    };
    if r.is_empty() {
        return;
    }
    // A narrow polygon: row by row from its first column, every row tested against
    // the edges, without classifying blocks (its blocks are almost all partly covered).
    let (rows, lanes) = (r.y0..r.y1, lane_range(0, r.x1 - r.x0));
    if align == Align::Polygon && r.x1 - r.x0 <= pairs::PAIR_WIDTH {
        pairs::draw_pairs::<L, E>(l, s, r.x0, rows, lanes as u8, target, face, counts);
    } else if align == Align::Polygon && r.x1 - r.x0 <= BLOCK {
        rows::draw_block::<L, E, false, false>(l, s, r.x0, rows, lanes, target, face, counts);
    } else if align == Align::Polygon && r.x1 - r.x0 <= 2 * BLOCK {
        rows::draw_block::<L, E, true, false>(l, s, r.x0, rows, lanes, target, face, counts);
    } else {
        let (bx0, by0) = match align {
            Align::Polygon => (r.x0, r.y0),
            Align::Grid => (r.x0 & !(2 * BLOCK - 1), r.y0 & !(BLOCK - 1)),
        };
        blocks::draw_blocks::<L, E>(l, s, r, bx0, by0, target, face, counts);
    }
}
