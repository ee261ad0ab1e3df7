//! The masked occlusion buffer (Hasselgren, Andersson and Akenine-Möller, "Masked
//! Software Occlusion Culling", HPG 2016): per tile of 8 x 4 pixels a 32-bit coverage
//! mask and two depth keys. Key `z0` bounds every pixel of the tile (no occluder
//! there is farther); key `z1` bounds the pixels of the working layer, the mask.
//! A triangle's inner coverage of the tile and its farthest key over the tile merge in
//! by the paper's rule: into the working layer, or replacing it when the triangle lies
//! nearer the reference layer than the working one (the paper's heuristic; either way
//! each bound stays a bound); a mask that fills the tile moves its key to `z0`.
//!
//! Unlike the paper, coverage is inner (a pixel counts only if all its samples are
//! inside the triangle, with a margin for rounding) and depths round towards
//! farther, so the buffer never claims an occluder where the z-buffer would not draw
//! one: the test built on it is conservative.

use super::raster::{Setup, Tri, f32_down, setup};
use crate::cpu::Kernel;

/// A full tile mask.
const FULL: u32 = u32::MAX;
/// Tile width and height in pixels.
pub(crate) const TW: usize = 8;
pub(crate) const TH: usize = 4;

/// The masked buffer (see the [module documentation](self)). Reused frame to frame:
/// [`MaskedBuffer::reset`] allocates only when the size grows.
#[derive(Clone, Debug, Default)]
pub struct MaskedBuffer {
    width: u32,
    height: u32,
    tiles_x: usize,
    tiles_y: usize,
    r: f64,
    mask: Vec<u32>,
    z0: Vec<f32>,
    z1: Vec<f32>,
    /// Per tile, the bits of pixels outside the buffer (right and bottom borders).
    pad: Vec<u32>,
}

impl MaskedBuffer {
    /// Empties the buffer and sets its size, `width x height` pixels whose samples
    /// span squares of side `r` (see [`super::raster`]).
    pub fn reset(&mut self, width: u32, height: u32, r: f64) {
        self.width = width;
        self.height = height;
        self.r = r;
        self.tiles_x = (width as usize).div_ceil(TW);
        self.tiles_y = (height as usize).div_ceil(TH);
        let n = self.tiles_x * self.tiles_y;
        self.mask.clear();
        self.mask.resize(n, 0);
        self.z0.clear();
        self.z0.resize(n, f32::NEG_INFINITY);
        self.z1.clear();
        self.z1.resize(n, f32::NEG_INFINITY);
        self.pad.clear();
        self.pad.resize(n, 0);
        // Only the last column and row of tiles hold pixels outside the buffer.
        let border = |t: usize, tiles: usize| t + 1 == tiles;
        for ty in 0..self.tiles_y {
            for tx in 0..self.tiles_x {
                if !border(tx, self.tiles_x) && !border(ty, self.tiles_y) {
                    continue;
                }
                let mut m = 0u32;
                for dy in 0..TH {
                    for dx in 0..TW {
                        if tx * TW + dx >= width as usize || ty * TH + dy >= height as usize {
                            m |= 1 << (dy * TW + dx);
                        }
                    }
                }
                self.pad[ty * self.tiles_x + tx] = m;
            }
        }
    }

    /// The size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Draws triangles (buffer coordinates) with the kernel asked for (the best one
    /// below it that this processor has); every kernel leaves the same bits.
    pub fn draw(&mut self, tris: &[Tri], kernel: Kernel) {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(cpu) = kernel.avx2() {
                // SAFETY: `Avx2::new` checked every feature `draw_avx2` enables.
                unsafe { draw_avx2(cpu, self, tris) };
                return;
            }
        }
        let _ = kernel;
        draw_impl(Portable, self, tris);
    }

    /// The key bound of pixel `(x, y)`: no occluder covering it is farther;
    /// `-inf` where none is known.
    #[must_use]
    pub fn bound(&self, x: u32, y: u32) -> f32 {
        let (x, y) = (x as usize, y as usize);
        let t = (y / TH) * self.tiles_x + x / TW;
        let bit = 1u32 << ((y % TH) * TW + x % TW);
        if self.mask[t] & bit != 0 {
            self.z0[t].max(self.z1[t])
        } else {
            self.z0[t]
        }
    }

    /// Whether a box whose nearest key is `key` is hidden at every pixel of the
    /// rectangle `[x0, x1] x [y0, y1]` (inclusive, inside the buffer).
    #[must_use]
    pub fn hidden(&self, x0: u32, y0: u32, x1: u32, y1: u32, key: f32) -> bool {
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize, y1 as usize);
        for ty in y0 / TH..=y1 / TH {
            let ra = y0.max(ty * TH) - ty * TH;
            let rb = y1.min(ty * TH + TH - 1) - ty * TH;
            let rows: u32 = (ra..=rb).fold(0, |m, dy| m | 0xff << (dy * TW));
            let row = ty * self.tiles_x;
            for tx in x0 / TW..=x1 / TW {
                let t = row + tx;
                let z0 = self.z0[t];
                if key < z0 {
                    continue;
                }
                let ca = x0.max(tx * TW) - tx * TW;
                let cb = x1.min(tx * TW + TW - 1) - tx * TW;
                let cols = (0xffu32 >> (TW - 1 - (cb - ca))) << ca;
                let cols4 = cols * 0x0101_0101;
                let want = rows & cols4;
                if key < self.z1[t] && want & !self.mask[t] == 0 {
                    continue;
                }
                return false;
            }
        }
        true
    }

    /// Merges a triangle's coverage `m` of tile `t` with its farthest key `zt` there.
    #[inline(always)]
    fn merge(&mut self, t: usize, m: u32, zt: f32) {
        let z0 = self.z0[t];
        if !(zt > z0) {
            return;
        }
        let pad = self.pad[t];
        if m | pad == FULL {
            self.z0[t] = zt;
            if !(self.z1[t] > zt) {
                self.mask[t] = 0;
                self.z1[t] = f32::NEG_INFINITY;
            }
            return;
        }
        let (mut mask, mut z1) = (self.mask[t], self.z1[t]);
        if mask == 0 || z1 - zt > zt - z0 {
            mask = m;
            z1 = zt;
        } else {
            mask |= m;
            z1 = z1.min(zt);
        }
        if mask | pad == FULL {
            self.z0[t] = z1;
            mask = 0;
            z1 = f32::NEG_INFINITY;
        }
        self.mask[t] = mask;
        self.z1[t] = z1;
    }
}

/// The lanes an edge's coverage of a tile is computed with: portable scalar code, or
/// AVX2 (eight pixels of a tile row at once). Both run the same `f32` operations in the
/// same order (`row + a * dx`, then `> 0`), so they give the same bits.
trait Lanes: Copy {
    /// The coverage of one edge over a tile whose corner pixel's value is `e`
    /// (already less its margin), steps `a` (x) and `b` (y).
    fn edge_mask(self, e: f32, a: f32, b: f32) -> u32;
}

/// The portable lanes.
#[derive(Clone, Copy)]
struct Portable;

impl Lanes for Portable {
    #[inline(always)]
    fn edge_mask(self, e: f32, a: f32, b: f32) -> u32 {
        edge_mask(e, a, b)
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for crate::cpu::Avx2 {
    #[inline(always)]
    fn edge_mask(self, e: f32, a: f32, b: f32) -> u32 {
        use std::arch::x86_64::{
            _CMP_GT_OQ, _mm256_add_ps, _mm256_cmp_ps, _mm256_movemask_ps, _mm256_mul_ps,
            _mm256_set1_ps, _mm256_setr_ps, _mm256_setzero_ps,
        };
        // SAFETY: a value of `Avx2` exists only on a processor with AVX2
        // (`cpu::Avx2::new` checks it); these are arithmetic intrinsics on registers.
        unsafe {
            let dx = _mm256_setr_ps(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
            let ax = _mm256_mul_ps(_mm256_set1_ps(a), dx);
            let zero = _mm256_setzero_ps();
            let mut m = 0u32;
            for dy in 0..TH {
                let row = e + b * dy as f32;
                let lanes = _mm256_add_ps(_mm256_set1_ps(row), ax);
                let bits = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(lanes, zero)) as u32;
                m |= bits << (dy * TW);
            }
            m
        }
    }
}

/// The coverage of one edge over a tile (see [`Lanes::edge_mask`]), portable.
#[inline(always)]
fn edge_mask(e: f32, a: f32, b: f32) -> u32 {
    let mut m = 0u32;
    for dy in 0..TH {
        let row = e + b * dy as f32;
        let mut lanes = [0.0f32; TW];
        for (dx, l) in lanes.iter_mut().enumerate() {
            *l = row + a * dx as f32;
        }
        let mut bits = 0u32;
        for (dx, l) in lanes.iter().enumerate() {
            bits |= u32::from(*l > 0.0) << dx;
        }
        m |= bits << (dy * TW);
    }
    m
}

/// The relative bound on the rounding of an edge value evaluated in `f32` over a tile
/// (conversion of the corner value and of the steps, two additions).
const EDGE_ROUNDING: f64 = 1.0 / (1u64 << 18) as f64;

/// Rasterizes one set-up triangle.
#[inline(always)]
fn draw_setup<L: Lanes>(lanes: L, buf: &mut MaskedBuffer, s: &Setup) {
    let (tx0, tx1) = (s.x0 as usize / TW, s.x1 as usize / TW);
    let (ty0, ty1) = (s.y0 as usize / TH, s.y1 as usize / TH);
    let af = s.a.map(|a| a as f32);
    let bf = s.b.map(|b| b as f32);
    let span =
        [0, 1, 2].map(|k| (TW as f64 - 1.0) * s.a[k].abs() + (TH as f64 - 1.0) * s.b[k].abs());
    let wx = TW as f64 - 1.0 + buf.r;
    let wy = TH as f64 - 1.0 + buf.r;
    for ty in ty0..=ty1 {
        let y = (ty * TH) as f64;
        for tx in tx0..=tx1 {
            let x = (tx * TW) as f64;
            let mut mask = FULL;
            let mut empty = false;
            for k in 0..3 {
                let e = s.a[k] * x + s.b[k] * y + s.c[k];
                let e = e - (e.abs() + span[k]) * EDGE_ROUNDING;
                let lo =
                    e + s.a[k].min(0.0) * (TW as f64 - 1.0) + s.b[k].min(0.0) * (TH as f64 - 1.0);
                if lo - span[k] * EDGE_ROUNDING > 0.0 {
                    continue;
                }
                let hi =
                    e + s.a[k].max(0.0) * (TW as f64 - 1.0) + s.b[k].max(0.0) * (TH as f64 - 1.0);
                if !(hi > 0.0) {
                    empty = true;
                    break;
                }
                mask &= lanes.edge_mask(f32_down(e), af[k], bf[k]);
            }
            if empty || mask == 0 {
                continue;
            }
            let zt = f32_down(s.far_key(x, y, wx, wy));
            buf.merge(ty * buf.tiles_x + tx, mask, zt);
        }
    }
}

#[inline(always)]
fn draw_impl<L: Lanes>(lanes: L, buf: &mut MaskedBuffer, tris: &[Tri]) {
    let (w, h, r) = (buf.width, buf.height, buf.r);
    for t in tris {
        if let Some(s) = setup(t, r, w, h) {
            draw_setup(lanes, buf, &s);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_avx2(cpu: crate::cpu::Avx2, buf: &mut MaskedBuffer, tris: &[Tri]) {
    draw_impl(cpu, buf, tris);
}

/// The portable build of the drawing (for the tests that compare kernels).
#[cfg(test)]
pub(crate) fn draw_portable(buf: &mut MaskedBuffer, tris: &[Tri]) {
    draw_impl(Portable, buf, tris);
}

#[cfg(test)]
impl MaskedBuffer {
    /// The raw state, for comparisons of kernels.
    pub(crate) fn state(&self) -> (&[u32], &[f32], &[f32]) {
        (&self.mask, &self.z0, &self.z1)
    }
}
