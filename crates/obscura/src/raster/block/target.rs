//! The view of a depth buffer a polygon is drawn into: a rectangle of an image held
//! row after row, with per-block farthest keys when occlusion culling is on
//! ([`super::occlusion`]).

use crate::raster::PixelRect;

/// A rectangle of an image held row after row: depth keys and encoded ids (see
/// [`crate::raster::lanes`]) of the columns `x0..x0 + stride` and rows `y0..`.
#[derive(Debug)]
pub struct BlockTarget<'a> {
    pub(super) keys: &'a mut [f32],
    pub(super) ids: &'a mut [u32],
    pub(super) stride: usize,
    pub(super) x0: u32,
    pub(super) y0: u32,
    pub(super) y1: u32,
    /// Per block of the grid (see [`BlockTarget::with_farthest`]), a key no larger
    /// than any its pixels hold; empty when blocks are not culled.
    pub(super) farthest: &'a mut [f32],
}

impl<'a> BlockTarget<'a> {
    /// The target of columns `x0..x0 + stride` and rows `y0..` of an image; the slices
    /// hold whole rows (`None` when they do not, or differ in length).
    #[must_use]
    pub fn new(
        keys: &'a mut [f32],
        ids: &'a mut [u32],
        stride: usize,
        x0: u32,
        y0: u32,
    ) -> Option<Self> {
        if stride == 0 || keys.len() != ids.len() || !keys.len().is_multiple_of(stride) {
            return None;
        }
        let rows = u32::try_from(keys.len() / stride).ok()?;
        Some(BlockTarget {
            keys,
            ids,
            stride,
            x0,
            y0,
            y1: y0.checked_add(rows)?,
            farthest: &mut [],
        })
    }

    /// The target with occlusion culling: `farthest` holds, per block of
    /// `2 BLOCK x BLOCK` pixels of the grid from the target's first pixel (row after
    /// row of `stride / (2 BLOCK)` blocks), a key no larger than any key its pixels
    /// hold. [`draw`](super::draw) with [`Align::Grid`](super::Align::Grid) skips the blocks whose key is larger than
    /// every key the polygon has there: the polygon wins none of their pixels, not even
    /// a tie, so the result is the same. The keys only grow while drawing, so a
    /// value computed before stays valid (only less effective); [`draw`](super::draw) recomputes
    /// the value of each whole block it writes to.
    #[must_use]
    pub fn with_farthest(mut self, farthest: &'a mut [f32]) -> Self {
        self.farthest = farthest;
        self
    }

    /// The pixels it holds.
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        PixelRect {
            x0: self.x0,
            y0: self.y0,
            x1: self.x0.saturating_add(self.stride as u32),
            y1: self.y1,
        }
    }

    /// The index of pixel `(x, y)` (inside [`BlockTarget::rect`]) in the slices.
    #[inline(always)]
    pub(super) fn at(&self, x: u32, y: u32) -> usize {
        (y - self.y0) as usize * self.stride + (x - self.x0) as usize
    }

    /// The keys and ids of the pixels `x..x + n` of row `y` (inside the rectangle).
    #[must_use]
    pub fn row(&self, x: u32, y: u32, n: usize) -> (&[f32], &[u32]) {
        let at = self.at(x, y);
        (&self.keys[at..at + n], &self.ids[at..at + n])
    }

    /// The keys and ids of the pixels `x..x + n` of row `y` (inside the rectangle).
    pub fn row_mut(&mut self, x: u32, y: u32, n: usize) -> (&mut [f32], &mut [u32]) {
        let at = self.at(x, y);
        (&mut self.keys[at..at + n], &mut self.ids[at..at + n])
    }
}
