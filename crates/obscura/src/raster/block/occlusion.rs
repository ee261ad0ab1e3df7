//! Occlusion culling (optional, [`BlockTarget::with_farthest`]): per block of the
//! grid the farthest key it holds; a block whose farthest key is larger than the
//! polygon's largest key over the block ([`nearest_key`], a rigorous bound) is
//! skipped, which changes nothing in the result. The polygon's whole part in the
//! region is tested first, against the smallest farthest key of the blocks it
//! overlaps: a polygon hidden in all of them is skipped with one test.
//!
//! Source: Greene, Kass and Miller, *Hierarchical Z-buffer visibility* (SIGGRAPH
//! 1993): a polygon is skipped where a conservative bound of its depth loses to the
//! farthest depth already stored over a region.

use super::{BLOCK, BlockSetup, BlockTarget};
use crate::raster::PixelRect;
use crate::raster::lanes::key_of;

impl BlockTarget<'_> {
    /// Whether the polygon `s` wins no pixel of `c` (pixels of the target), by the
    /// keys of all the grid blocks `c` overlaps: their smallest farthest key is
    /// larger than any key the polygon has in `c`. Used for a polygon's whole part in
    /// a tile before its blocks are walked, then for each block.
    #[inline(always)]
    pub(super) fn hides<const E: usize>(&self, s: &BlockSetup<E>, c: PixelRect) -> bool {
        if self.farthest.is_empty() || c.is_empty() || c.x0 < self.x0 || c.y0 < self.y0 {
            return false;
        }
        let bw = 2 * BLOCK;
        let per_row = self.stride / bw as usize;
        let (bx0, bx1) = (
            ((c.x0 - self.x0) / bw) as usize,
            ((c.x1 - 1 - self.x0) / bw) as usize + 1,
        );
        let (by0, by1) = (
            ((c.y0 - self.y0) / BLOCK) as usize,
            ((c.y1 - 1 - self.y0) / BLOCK) as usize + 1,
        );
        if bx1 > per_row {
            return false;
        }
        let mut far = f32::INFINITY;
        for by in by0..by1 {
            let Some(row) = self.farthest.get(by * per_row + bx0..by * per_row + bx1) else {
                return false;
            };
            for &f in row {
                // An empty pixel (key 0) or a NaN hides nothing.
                if !(f > 0.0) {
                    return false;
                }
                far = far.min(f);
            }
        }
        far > nearest_key(s, c)
    }

    /// Recomputes the farthest key of the grid block at `(bx, by)` if the target holds
    /// all of its pixels.
    #[inline(always)]
    pub(super) fn refresh(&mut self, bx: u32, by: u32) {
        let bw = 2 * BLOCK as usize;
        if self.farthest.is_empty()
            || bx < self.x0
            || by < self.y0
            || (bx - self.x0) as usize + bw > self.stride
            || by + BLOCK > self.y1
        {
            return;
        }
        let per_row = self.stride / bw;
        let at = ((by - self.y0) / BLOCK) as usize * per_row + (bx - self.x0) as usize / bw;
        let first = self.at(bx, by);
        let mut m = [f32::INFINITY; 16];
        for r in 0..BLOCK as usize {
            let row = &self.keys[first + r * self.stride..][..bw];
            for (m, &v) in m.iter_mut().zip(row) {
                *m = if v < *m { v } else { *m };
            }
        }
        if let Some(far) = self.farthest.get_mut(at) {
            *far = min16(m);
        }
    }
}

/// The smallest of sixteen keys, halving the lanes (vector instructions; the serial
/// fold with `f32::min` took 9 % of a culled city frame's z-buffer). The same value as
/// that fold for keys without NaN, which the buffers never hold (the depth test
/// stores no NaN; their empty value is `+0.0`).
#[inline(always)]
#[must_use]
pub(crate) fn min16(mut m: [f32; 16]) -> f32 {
    for half in [8, 4, 2, 1] {
        for i in 0..half {
            m[i] = if m[i + half] < m[i] {
                m[i + half]
            } else {
                m[i]
            };
        }
    }
    m[0]
}

/// An upper bound of the keys the rasterizer computes for polygon `s` in the pixels
/// of `c`, as stored (`f32`): the key expression is affine, so its largest value is at
/// a corner; a margin of `1e-12` of the terms' magnitudes covers the roundings of any
/// order of evaluation (a few units of `2^-53` each), and [`key_of`] is monotonic.
/// NaN for a non-finite plane.
#[inline(always)]
#[must_use]
pub fn nearest_key<const E: usize>(s: &BlockSetup<E>, c: PixelRect) -> f32 {
    let i = if s.dzdx > 0.0 { c.x1 - 1 } else { c.x0 };
    let j = if s.dzdy > 0.0 { c.y1 - 1 } else { c.y0 };
    let top = s.key(i, j);
    let reach = s.z0.abs()
        + s.dzdy.abs() * (f64::from(j) - f64::from(s.rect.y0)).abs()
        + s.dzdx.abs() * (f64::from(i) - f64::from(s.rect.x0)).abs();
    key_of(top + reach * 1e-12)
}
