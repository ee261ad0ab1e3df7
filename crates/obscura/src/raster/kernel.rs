//! The innermost loops of rasterization behind one trait, so a drawing loop can be
//! compiled once per instruction set: [`Portable`] (plain Rust, any processor) and, on
//! x86-64, [`Avx2`](super::simd::Avx2) (explicit AVX2 intrinsics). Every
//! implementation gives bit-identical results; the tests compare them.
//!
//! The kernels draw into a [`DepthTarget`]: rows of negated `f32` depth keys and face
//! ids (see [`depth_span`] for the depth test). Coverage is the shared rule of
//! `raster::coverage`, evaluated with its canonical expression; depth is the seeds'
//! incremental rule (seed 000 "Αλγόριθμος Z-buffer"). Cost: O(1) per row plus O(n)
//! per span of n pixels.

use std::ops::Range;

use super::depth_span::{self, depth_test_span};
use super::setup::{NARROW_EDGES, NARROW_WIDTH, NarrowEdges};
use super::{DepthPlane, EdgeFunction, PixelRect, row_span};

/// Rows `y0..` of an image `width` pixels wide: negated depth keys and face ids, row
/// after row.
#[derive(Debug)]
pub struct DepthTarget<'a> {
    /// `-key` per pixel (`+inf` where nothing was drawn).
    pub keys: &'a mut [f32],
    /// Face id per pixel.
    pub ids: &'a mut [u32],
    /// Pixels per row.
    pub width: usize,
    /// The image row of the first row.
    pub y0: u32,
}

/// How many pixels a kernel depth-tested and how many it wrote.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpanCounts {
    /// Pixels depth-tested (covered).
    pub tested: u64,
    /// Pixels that passed the test and were written.
    pub written: u64,
}

impl SpanCounts {
    /// Adds another count.
    #[inline(always)]
    pub fn add(&mut self, o: SpanCounts) {
        self.tested += o.tested;
        self.written += o.written;
    }
}

impl DepthTarget<'_> {
    /// The keys and ids of image row `y`.
    #[inline(always)]
    pub fn row_mut(&mut self, y: u32) -> (&mut [f32], &mut [u32]) {
        let row = (y - self.y0) as usize * self.width;
        (
            &mut self.keys[row..row + self.width],
            &mut self.ids[row..row + self.width],
        )
    }

    /// Depth-tests the span `[x0, x1)` of image row `y` against the polygon with depth
    /// plane `plane`: the key starts from the plane at the span's first sample and is
    /// stepped by `dzdx`, as the reference z-buffer does.
    #[inline(always)]
    pub fn draw_span<K: RasterKernel>(
        &mut self,
        kernel: K,
        y: u32,
        x0: u32,
        x1: u32,
        plane: &DepthPlane,
        face: u32,
    ) -> SpanCounts {
        let z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
        let (keys, ids) = self.row_mut(y);
        let span = x0 as usize..x1 as usize;
        let written = depth_test_span(kernel, keys, ids, span, z, plane.dzdx, face);
        SpanCounts {
            tested: u64::from(x1 - x0),
            written: u64::from(written),
        }
    }
}

/// Kernels a rasterizer's drawing loop is generic over.
pub trait RasterKernel: Copy {
    /// Depth-tests pixels `span` of the slices, whose keys are `z + k step` for the
    /// `k`-th of them (a run of [`depth_span::linear_run`]): stores `-(key as f32)` and
    /// `face` where that is below the buffer; returns the number of pixels written.
    /// Other elements of the slices may be rewritten with their own values.
    fn depth_test_linear(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        span: Range<usize>,
        z: f64,
        step: f64,
        face: u32,
    ) -> u32;

    /// Depth-tests pixels `span` of the slices, at most [`depth_span::SHORT_SPAN`] of them, with keys
    /// stepped serially from `z` by `d` (exactly [`depth_span::depth_test_serial`]);
    /// returns the number of pixels written. Other elements of the slices may be
    /// rewritten with their own values.
    fn depth_test_short(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        span: Range<usize>,
        z: f64,
        d: f64,
        face: u32,
    ) -> u32;

    /// Draws rows `rows` of a convex polygon whose sample rectangle `rect` is at most
    /// [`NARROW_WIDTH`] pixels wide and which has at most [`NARROW_EDGES`] edges: each
    /// row's covered columns tested together (see [`NarrowEdges`]), then its span
    /// depth-tested. Wider polygons or more edges draw nothing (a caller's error).
    fn draw_narrow(
        self,
        edges: &[EdgeFunction],
        rect: PixelRect,
        rows: Range<u32>,
        plane: &DepthPlane,
        target: &mut DepthTarget<'_>,
        face: u32,
    ) -> SpanCounts;

    /// Draws rows `rows` of any convex polygon, row by row: the span of
    /// [`row_span`] in `rect`'s columns, depth-tested.
    fn draw_wide(
        self,
        edges: &[EdgeFunction],
        rect: PixelRect,
        rows: Range<u32>,
        plane: &DepthPlane,
        target: &mut DepthTarget<'_>,
        face: u32,
    ) -> SpanCounts;
}

/// The portable kernels: plain Rust.
#[derive(Clone, Copy, Debug, Default)]
pub struct Portable;

impl RasterKernel for Portable {
    #[inline(always)]
    fn depth_test_linear(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        span: Range<usize>,
        z: f64,
        step: f64,
        face: u32,
    ) -> u32 {
        depth_span::depth_test_linear(&mut keys[span.clone()], &mut ids[span], z, step, face)
    }

    #[inline(always)]
    fn depth_test_short(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        span: Range<usize>,
        z: f64,
        d: f64,
        face: u32,
    ) -> u32 {
        depth_span::depth_test_serial(&mut keys[span.clone()], &mut ids[span], z, d, face).0
    }

    #[inline(always)]
    fn draw_narrow(
        self,
        edges: &[EdgeFunction],
        rect: PixelRect,
        rows: Range<u32>,
        plane: &DepthPlane,
        target: &mut DepthTarget<'_>,
        face: u32,
    ) -> SpanCounts {
        let mut narrow = NarrowEdges::default();
        let mut c = SpanCounts::default();
        if !narrow.set(edges, rect) {
            return c;
        }
        for y in rows {
            let m = narrow.row_mask(y);
            if m != 0 {
                let (a, b) = mask_span(narrow.x0(), m);
                c.add(target.draw_span(self, y, a, b, plane, face));
            }
        }
        c
    }

    #[inline(always)]
    fn draw_wide(
        self,
        edges: &[EdgeFunction],
        rect: PixelRect,
        rows: Range<u32>,
        plane: &DepthPlane,
        target: &mut DepthTarget<'_>,
        face: u32,
    ) -> SpanCounts {
        draw_rows_by_spans(self, edges, rect, rows, plane, target, face)
    }
}

/// [`RasterKernel::draw_wide`] with [`row_span`] for every row.
#[inline(always)]
pub(crate) fn draw_rows_by_spans<K: RasterKernel>(
    kernel: K,
    edges: &[EdgeFunction],
    rect: PixelRect,
    rows: Range<u32>,
    plane: &DepthPlane,
    target: &mut DepthTarget<'_>,
    face: u32,
) -> SpanCounts {
    let mut c = SpanCounts::default();
    for y in rows {
        if let Some((a, b)) = row_span(edges, rect, y, rect.x0, rect.x1) {
            c.add(target.draw_span(kernel, y, a, b, plane, face));
        }
    }
    c
}

/// The span `[a, b)` of a non-empty row mask whose bit 0 is column `x0`. The covered
/// pixels of a row are contiguous (see [`super::row_span`]), so the mask's lowest and
/// highest bits bound them.
#[inline(always)]
#[must_use]
pub fn mask_span(x0: u32, mask: u32) -> (u32, u32) {
    debug_assert!(mask != 0);
    let (a, b) = (x0 + mask.trailing_zeros(), x0 + 32 - mask.leading_zeros());
    debug_assert_eq!(
        mask.count_ones(),
        b - a,
        "covered pixels of a row are contiguous"
    );
    (a, b)
}

/// Whether [`RasterKernel::draw_narrow`] takes a polygon.
#[inline(always)]
#[must_use]
pub fn is_narrow(edges: &[EdgeFunction], rect: PixelRect) -> bool {
    !rect.is_empty() && rect.x1 - rect.x0 <= NARROW_WIDTH && edges.len() <= NARROW_EDGES
}
