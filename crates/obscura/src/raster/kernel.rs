//! The innermost loops of rasterization behind one trait, so a drawing loop can be
//! compiled once per instruction set: [`Portable`] (plain Rust, any processor) and, on
//! x86-64, [`Avx2`](super::simd::Avx2) (explicit AVX2 intrinsics). Every
//! implementation gives bit-identical results; the tests compare them.

use super::depth_span;
use super::setup::NarrowEdges;

/// Kernels a rasterizer's drawing loop is generic over.
pub trait RasterKernel: Copy {
    /// Depth-tests pixels whose keys are `z + k step` (a run of
    /// [`depth_span::linear_run`]): stores `-(key as f32)` and `face` where that is
    /// below the buffer; returns the number of pixels written.
    fn depth_test_linear(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        z: f64,
        step: f64,
        face: u32,
    ) -> u32;

    /// The covered columns of row `j` of a narrow polygon (see
    /// [`NarrowEdges::row_mask`]).
    fn narrow_row_mask(self, edges: &NarrowEdges, j: u32) -> u32;
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
        z: f64,
        step: f64,
        face: u32,
    ) -> u32 {
        depth_span::depth_test_linear(keys, ids, z, step, face)
    }

    #[inline(always)]
    fn narrow_row_mask(self, edges: &NarrowEdges, j: u32) -> u32 {
        edges.row_mask(j)
    }
}
