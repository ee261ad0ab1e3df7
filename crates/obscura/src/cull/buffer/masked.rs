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
//!
//! The raster: a triangle is set up once (`tile_setup`: its three edge functions and
//! depth plane in `f32`, with the margins that cover every rounding of the tile loop
//! folded into their constants, proved there); a tile then costs its three edge values
//! (`e + ex i + ey j`), one evaluation of its 32 pixels per edge (`e + a dx + b dy >
//! 0`: 2 AVX-512 or 4 AVX2 vectors) and its depth bound; the AVX-512 kernel merges the
//! tiles of a row (up to 16) in vector lanes. Every kernel runs the same `f32`
//! operations, so they leave the same bits.
//!
//! A planar convex polygon ([`Poly`], up to eight vertices) is one primitive of the
//! same raster with four or eight edge functions instead of three (a quad's two
//! triangles would each leave out the pixels whose samples straddle the shared
//! diagonal: inner coverage gives them to neither); triangles keep their own,
//! three-edge build of the same code.

use super::raster::{Poly, Setup, Tri, f32_down, poly_setup, setup};
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
    /// Per tile, row by row (each in its own array, so a row of tiles is a vector):
    /// the working layer's coverage, the bits of pixels outside the buffer (right and
    /// bottom borders), the reference key (every pixel) and the working layer's key.
    mask: Vec<u32>,
    pad: Vec<u32>,
    z0: Vec<f32>,
    z1: Vec<f32>,
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
            if let Some(cpu) = kernel.avx512() {
                // SAFETY: `Avx512::new` checked every feature `draw_avx512` enables.
                unsafe { draw_avx512(cpu, self, tris) };
                return;
            }
            if let Some(cpu) = kernel.avx2() {
                // SAFETY: `Avx2::new` checked every feature `draw_avx2` enables.
                unsafe { draw_avx2(cpu, self, tris) };
                return;
            }
        }
        let _ = kernel;
        draw_impl(Portable, self, tris);
    }

    /// Draws convex polygons, then triangles (see [`MaskedBuffer::draw_polygons`] and
    /// [`MaskedBuffer::draw`]): the same call as the occlusion buffer's other kind.
    pub fn draw_occluders(&mut self, tris: &[Tri], polys: &[Poly], kernel: Kernel) {
        self.draw_polygons(polys, kernel);
        self.draw(tris, kernel);
    }

    /// Draws convex polygons (buffer coordinates, see [`Poly`]), each as one primitive,
    /// with the kernel asked for; every kernel leaves the same bits.
    pub fn draw_polygons(&mut self, polys: &[Poly], kernel: Kernel) {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(cpu) = kernel.avx512() {
                // SAFETY: `Avx512::new` checked every feature `draw_polys_avx512` enables.
                unsafe { draw_polys_avx512(cpu, self, polys) };
                return;
            }
            if let Some(cpu) = kernel.avx2() {
                // SAFETY: `Avx2::new` checked every feature `draw_polys_avx2` enables.
                unsafe { draw_polys_avx2(cpu, self, polys) };
                return;
            }
        }
        let _ = kernel;
        draw_polys_impl(Portable, self, polys);
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

    /// Merges a triangle's coverage `m` of tile `t` with its farthest key `zt` there;
    /// nothing when `m` is empty or `zt` is not nearer than `z0`. Without branches (the
    /// cases are selected, every field written back): which case a tile takes is as
    /// good as random, and a mispredicted branch costs more than the whole merge.
    /// Equal, case by case, to the rule of the [module documentation](self):
    /// - a triangle that fills the tile (with the pixels outside the buffer) moves
    ///   `z0` up to `zt`, and empties the working layer unless it is nearer than `zt`;
    /// - otherwise its coverage joins the working layer (`z1` the farther of the two)
    ///   or replaces it when the layer is empty or the triangle lies nearer `z0` than
    ///   `z1` does; a working layer that then fills the tile becomes the reference.
    #[inline(always)]
    fn merge(&mut self, t: usize, m: u32, zt: f32) {
        let (z0, mask, z1, pad) = (self.z0[t], self.mask[t], self.z1[t], self.pad[t]);
        let skip = (m == 0) | !(zt > z0);
        let full = m | pad == FULL;
        // The triangle fills the tile.
        let keep = z1 > zt;
        let (fz0, fmask, fz1) = (
            zt,
            if keep { mask } else { 0 },
            if keep { z1 } else { f32::NEG_INFINITY },
        );
        // It joins or replaces the working layer.
        let replace = (mask == 0) | (z1 - zt > zt - z0);
        let pm = if replace { m } else { mask | m };
        let pz1 = if replace { zt } else { min(z1, zt) };
        let promote = pm | pad == FULL;
        let (qz0, qmask, qz1) = if promote {
            (pz1, 0, f32::NEG_INFINITY)
        } else {
            (z0, pm, pz1)
        };
        let (nz0, nmask, nz1) = if full {
            (fz0, fmask, fz1)
        } else {
            (qz0, qmask, qz1)
        };
        let (nz0, nmask, nz1) = if skip {
            (z0, mask, z1)
        } else {
            (nz0, nmask, nz1)
        };
        self.z0[t] = nz0;
        self.mask[t] = nmask;
        self.z1[t] = nz1;
    }
}

/// A triangle (`N = 3`) or convex polygon (`N` edges) set up once for the tile loop:
/// every value `f32`, the margins for the rounding of the loop folded into the
/// constants (see [`tile_setup`]), so a tile costs its `N` edge values, one vector
/// evaluation of 32 pixels per edge and one depth.
#[derive(Clone, Copy, Debug)]
struct TileSetup<const N: usize> {
    /// Tiles `tx0 ..= tx1`, `ty0 ..= ty1`.
    tx0: usize,
    ty0: usize,
    tx1: usize,
    ty1: usize,
    /// Per edge, its value at the first tile's corner pixel less the margin.
    e: [f32; N],
    /// Per edge, its step from one tile to the next in x (`8 a`) and in y (`4 b`).
    ex: [f32; N],
    ey: [f32; N],
    /// Per edge, its slopes `a` and `b` in `f32`: the step from a tile's corner pixel
    /// to its pixel `(dx, dy)` is `a dx + b dy` ([`Lanes::offsets`]).
    a: [f32; N],
    b: [f32; N],
    /// The depth-key bound at the first tile (the plane's least over the tile, less the
    /// margins), its steps per tile, and the floor every bound may take (the farthest
    /// vertex's key less the slack).
    z: f32,
    zx: f32,
    zy: f32,
    zmin: f32,
}

/// The margin, relative to the magnitudes the loop adds up, that covers every rounding
/// of the tile loop in `f32` (seven roundings of at most `2^-24` each, and the
/// rounding of the slopes to `f32`: at most `8 * 2^-24 = 2^-21`; a factor four
/// beyond).
const F32_LOOP: f64 = 1.0 / (1u64 << 19) as f64;
/// The margin, relative to the magnitudes of the set-up, that covers its rounding in
/// `f64` (a few roundings of `2^-53` each: `2^-48` is a factor ten beyond).
const F64_SETUP: f64 = 1.0 / (1u64 << 48) as f64;

/// Sets up triangle or convex polygon `s` for the tile loop, or `None` when a value is
/// not finite (leaving a triangle out is conservative).
///
/// Why a pixel the loop marks covered is covered (every sample inside). Let `F(X, Y) =
/// a X + b Y + c` be the set-up's edge function (exact reals: positive at a pixel's
/// corner means its whole sample square is inside, see [`super::raster`]), `(X0, Y0)`
/// the first tile's corner, `W` and `H` the extent of the tiles in pixels and `S = |G|
/// + |a| W + |b| H` with `G = F(X0, Y0)`. The loop computes, for the pixel `(X0 + u, Y0
/// + v)` (`u < W`, `v < H`), `((e + ey j) + ex i) + off` in `f32` with `e <= G - M`,
/// the slopes `af = f32(a)` (`|a - af| <= 2^-24 |a|`, scaled exactly by 8 and 4) and the
/// offsets `af dx + bf dy`. Each of its seven roundings errs by at most `2^-24` of a
/// sum of terms bounded by `|e| + |af| u + |bf| v <= 2 S`, and the slopes' rounding
/// adds at most `2^-24 (|a| W + |b| H)`: in all below `2^-20 S`. The value `G` itself,
/// computed in `f64` from the set-up (whose own `a`, `b`, `c` carry rounding relative
/// `2^-52` to the vertices'), errs by less than `2^-48 T` with `T` the magnitudes
/// that made it (`cmag`). With `M = 2^-19 S + 2^-48 T`, a computed value above zero
/// means `F > M - 2^-20 S - 2^-48 T > 0` at the pixel: every sample inside.
///
/// The depth the same way: the loop computes `(z + zy j) + zx i`, `z` rounded down
/// from the plane's least value over the first tile (`P(X0, Y0) + min(p, 0) wx +
/// min(q, 0) wy`, every sample of its pixels) less the set-up's slack and a margin
/// `2^-19 (|z| + |p| W + |q| H)` for the loop's five roundings and the slopes'; the
/// plane is affine, so the least over tile `(i, j)` is the first tile's plus `8 p i + 4
/// q j`. The floor `zmin` (the farthest vertex's key, no key of the triangle is
/// farther) is rounded down too; so the bound never passes the triangle's key.
///
/// A convex polygon of `N` edges: its inner coverage is the intersection of its edges'
/// inner half-planes (see [`Poly::new`]), each edge's function shifted by its own least
/// over the sample square ([`poly_setup`]), so the argument above holds edge by edge,
/// the margin `M` computed per edge from its own magnitudes: a pixel marked has every
/// computed edge value above zero, hence every exact one, hence every sample inside the
/// polygon. Its depth is one plane with the slack of [`poly_setup`] (which covers the
/// vertices' distance from the plane) and the floor its farthest vertex key: the same
/// argument holds word for word.
#[inline(always)]
fn tile_setup<const N: usize>(s: &Setup<N>, r: f64) -> Option<TileSetup<N>> {
    let (tx0, tx1) = (s.x0 as usize / TW, s.x1 as usize / TW);
    let (ty0, ty1) = (s.y0 as usize / TH, s.y1 as usize / TH);
    let (x0, y0) = ((tx0 * TW) as f64, (ty0 * TH) as f64);
    let w = ((tx1 - tx0 + 1) * TW) as f64;
    let h = ((ty1 - ty0 + 1) * TH) as f64;
    let mut e = [0.0f32; N];
    let mut ex = [0.0f32; N];
    let mut ey = [0.0f32; N];
    let mut af = [0.0f32; N];
    let mut bf = [0.0f32; N];
    let mut bounded = true;
    for k in 0..N {
        let (a, b) = (s.a[k], s.b[k]);
        let g = a * x0 + b * y0 + s.c[k];
        let sum = g.abs() + a.abs() * w + b.abs() * h;
        bounded &= sum < 1e30;
        let m = F32_LOOP * sum + F64_SETUP * (s.cmag[k] + a.abs() * x0 + b.abs() * y0);
        e[k] = f32_down(g - m);
        af[k] = a as f32;
        bf[k] = b as f32;
        ex[k] = af[k] * TW as f32;
        ey[k] = bf[k] * TH as f32;
    }
    let wx = TW as f64 - 1.0 + r;
    let wy = TH as f64 - 1.0 + r;
    let plane = s.p * x0 + s.q * y0 + s.r + s.p.min(0.0) * wx + s.q.min(0.0) * wy - s.zslack;
    let zsum = plane.abs() + s.p.abs() * w + s.q.abs() * h;
    bounded &= zsum < 1e30 && s.zmin.abs() + s.zslack < 1e30;
    let zm = F32_LOOP * zsum;
    let (pf, qf) = (s.p as f32, s.q as f32);
    let t = TileSetup {
        tx0,
        ty0,
        tx1,
        ty1,
        e,
        ex,
        ey,
        a: af,
        b: bf,
        z: f32_down(plane - zm),
        zx: pf * TW as f32,
        zy: qf * TH as f32,
        zmin: f32_down(s.zmin - s.zslack),
    };
    // Every magnitude the loop adds up stays far from `f32`'s overflow (`<` fails on
    // NaN too), so the bounds above hold for every value it computes.
    bounded.then_some(t)
}

/// Per pixel of a tile (`dy * 8 + dx`), its `dx` and `dy`.
const DX: [f32; TW * TH] = {
    let mut v = [0.0; TW * TH];
    let mut p = 0;
    while p < TW * TH {
        v[p] = (p % TW) as f32;
        p += 1;
    }
    v
};
const DY: [f32; TW * TH] = {
    let mut v = [0.0; TW * TH];
    let mut p = 0;
    while p < TW * TH {
        v[p] = (p / TW) as f32;
        p += 1;
    }
    v
};

/// The lanes a tile's coverage is computed with: portable scalar code, AVX2 (eight
/// pixels at once) or AVX-512 (sixteen). All run the same `f32` operations (`e + off`,
/// then `> 0`), so they give the same bits.
trait Lanes: Copy {
    /// The per-pixel offsets of one edge, held the way the lanes want them.
    type Edge: Copy;
    /// The offsets `a dx + b dy` (in this order of operations) of pixel `dy * 8 + dx`
    /// from its tile's corner pixel, per edge of slopes `a[k]`, `b[k]`.
    fn offsets<const N: usize>(self, a: [f32; N], b: [f32; N]) -> [Self::Edge; N];
    /// The pixels of a tile inside all `N` edges whose values at the tile's corner
    /// pixel are `e`: bit `dy * 8 + dx` when every `e[k] + off[k][dy * 8 + dx] > 0`.
    fn mask<const N: usize>(self, off: &[Self::Edge; N], e: [f32; N]) -> u32;

    /// Draws `count` tiles `t + l` of one row: tile `l`'s edge values `e[k] + ex[k]
    /// (i0 + l)`, its depth bound `max(zrow + zx (i0 + l), zmin)` with `[zrow, zx, i0,
    /// zmin] = z` (`i0 + l`, the tile's index in the triangle's row, exact in `f32`).
    /// This default merges tile by tile ([`MaskedBuffer::merge`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn row<const N: usize>(
        self,
        buf: &mut MaskedBuffer,
        off: &[Self::Edge; N],
        t: usize,
        count: usize,
        e: [f32; N],
        ex: [f32; N],
        z: [f32; 4],
    ) {
        let [zrow, zx, i0, zmin] = z;
        let mut i = i0;
        for l in 0..count {
            let m = self.mask(off, step(e, ex, i));
            let zt = max(zrow + zx * i, zmin);
            buf.merge(t + l, m, zt);
            i += 1.0;
        }
    }
}

/// `e[k] + ex[k] i` per edge (the edge values `i` steps along).
#[inline(always)]
fn step<const N: usize>(e: [f32; N], ex: [f32; N], i: f32) -> [f32; N] {
    let mut v = e;
    for k in 0..N {
        v[k] = e[k] + ex[k] * i;
    }
    v
}

/// `a > b ? a : b`, the vector instructions' maximum (which picks `b` for equal
/// zeros of either sign, or a NaN, where `f32::max` may pick either): every kernel
/// takes these, so they agree to the bit.
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// `a < b ? a : b`, the vector instructions' minimum (see [`max`]).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The tiles of a row merged at once (the lanes of an AVX-512 vector).
const ROW: usize = 16;

/// The portable lanes.
#[derive(Clone, Copy)]
struct Portable;

impl Lanes for Portable {
    type Edge = [f32; TW * TH];
    #[inline(always)]
    fn offsets<const N: usize>(self, a: [f32; N], b: [f32; N]) -> [Self::Edge; N] {
        let mut o = [[0.0f32; TW * TH]; N];
        for k in 0..N {
            for p in 0..TW * TH {
                o[k][p] = a[k] * DX[p] + b[k] * DY[p];
            }
        }
        o
    }
    #[inline(always)]
    // Pixel `p` of every edge's offsets: an index is clearer than `N` zipped iterators.
    #[allow(clippy::needless_range_loop)]
    fn mask<const N: usize>(self, off: &[Self::Edge; N], e: [f32; N]) -> u32 {
        let mut m = 0u32;
        for p in 0..TW * TH {
            let mut inside = true;
            for k in 0..N {
                inside &= e[k] + off[k][p] > 0.0;
            }
            m |= u32::from(inside) << p;
        }
        m
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for crate::cpu::Avx2 {
    type Edge = [std::arch::x86_64::__m256; 4];
    #[inline(always)]
    fn offsets<const N: usize>(self, a: [f32; N], b: [f32; N]) -> [Self::Edge; N] {
        use std::arch::x86_64::{
            _mm256_add_ps, _mm256_loadu_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setzero_ps,
        };
        // SAFETY: a value of `Avx2` exists only on a processor with AVX2; each load
        // reads 8 of the 32 floats of `DX` or `DY`.
        unsafe {
            let mut o = [[_mm256_setzero_ps(); 4]; N];
            for k in 0..N {
                let (av, bv) = (_mm256_set1_ps(a[k]), _mm256_set1_ps(b[k]));
                for q in 0..4 {
                    let dx = _mm256_loadu_ps(DX[q * 8..].as_ptr());
                    let dy = _mm256_loadu_ps(DY[q * 8..].as_ptr());
                    o[k][q] = _mm256_add_ps(_mm256_mul_ps(av, dx), _mm256_mul_ps(bv, dy));
                }
            }
            o
        }
    }
    #[inline(always)]
    // Vector `q` of every edge's offsets (see the portable lanes).
    #[allow(clippy::needless_range_loop)]
    fn mask<const N: usize>(self, off: &[Self::Edge; N], e: [f32; N]) -> u32 {
        use std::arch::x86_64::{
            _CMP_GT_OQ, _mm256_add_ps, _mm256_and_ps, _mm256_cmp_ps, _mm256_movemask_ps,
            _mm256_set1_ps, _mm256_setzero_ps,
        };
        // SAFETY: a value of `Avx2` exists only on a processor with AVX2; these are
        // arithmetic intrinsics on registers.
        unsafe {
            let zero = _mm256_setzero_ps();
            let mut ev = [zero; N];
            for k in 0..N {
                ev[k] = _mm256_set1_ps(e[k]);
            }
            let mut m = 0u32;
            for q in 0..4 {
                let mut c = _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_add_ps(ev[0], off[0][q]), zero);
                for k in 1..N {
                    let ck = _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_add_ps(ev[k], off[k][q]), zero);
                    c = _mm256_and_ps(c, ck);
                }
                m |= (_mm256_movemask_ps(c) as u32) << (q * 8);
            }
            m
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for crate::cpu::Avx512 {
    type Edge = [std::arch::x86_64::__m512; 2];
    #[inline(always)]
    fn offsets<const N: usize>(self, a: [f32; N], b: [f32; N]) -> [Self::Edge; N] {
        use std::arch::x86_64::{
            _mm512_add_ps, _mm512_loadu_ps, _mm512_mul_ps, _mm512_set1_ps, _mm512_setzero_ps,
        };
        // SAFETY: a value of `Avx512` exists only on a processor with AVX-512 F; each
        // load reads 16 of the 32 floats of `DX` or `DY`.
        unsafe {
            let mut o = [[_mm512_setzero_ps(); 2]; N];
            for k in 0..N {
                let (av, bv) = (_mm512_set1_ps(a[k]), _mm512_set1_ps(b[k]));
                for q in 0..2 {
                    let dx = _mm512_loadu_ps(DX[q * 16..].as_ptr());
                    let dy = _mm512_loadu_ps(DY[q * 16..].as_ptr());
                    o[k][q] = _mm512_add_ps(_mm512_mul_ps(av, dx), _mm512_mul_ps(bv, dy));
                }
            }
            o
        }
    }
    #[inline(always)]
    fn mask<const N: usize>(self, off: &[Self::Edge; N], e: [f32; N]) -> u32 {
        use std::arch::x86_64::{
            _CMP_GT_OQ, _mm512_add_ps, _mm512_cmp_ps_mask, _mm512_mask_cmp_ps_mask, _mm512_set1_ps,
            _mm512_setzero_ps,
        };
        // SAFETY: a value of `Avx512` exists only on a processor with AVX-512 F;
        // these are arithmetic intrinsics on registers.
        unsafe {
            let zero = _mm512_setzero_ps();
            let mut ev = [zero; N];
            for k in 0..N {
                ev[k] = _mm512_set1_ps(e[k]);
            }
            let mut half = [0u32; 2];
            for (q, h) in half.iter_mut().enumerate() {
                let mut m = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(_mm512_add_ps(ev[0], off[0][q]), zero);
                for k in 1..N {
                    m = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(
                        m,
                        _mm512_add_ps(ev[k], off[k][q]),
                        zero,
                    );
                }
                *h = u32::from(m);
            }
            half[0] | half[1] << 16
        }
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn row<const N: usize>(
        self,
        buf: &mut MaskedBuffer,
        off: &[Self::Edge; N],
        t: usize,
        count: usize,
        e: [f32; N],
        ex: [f32; N],
        z: [f32; 4],
    ) {
        use std::arch::x86_64::{_mm512_mask_set1_epi32, _mm512_setzero_si512 as zeros};
        let [_, _, i0, _] = z;
        // The masks gathered in a register (built in memory, a vector load would wait
        // for the scalar stores to retire).
        // SAFETY: a value of `Avx512` exists only on a processor with AVX-512 F; these
        // are register intrinsics.
        let mut m = unsafe { zeros() };
        let mut i = i0;
        for l in 0..count {
            let bits = self.mask(off, step(e, ex, i));
            // SAFETY: as above.
            m = unsafe { _mm512_mask_set1_epi32(m, 1 << l, bits as i32) };
            i += 1.0;
        }
        self.merge_row(buf, t, count, m, z);
    }
}

#[cfg(target_arch = "x86_64")]
impl crate::cpu::Avx512 {
    /// Merges the coverage `m` (lane `l`) of tiles `t + l`, `l < count`, of one row
    /// (see [`Lanes::row`]): [`MaskedBuffer::merge`] in lanes.
    #[inline(always)]
    fn merge_row(
        self,
        buf: &mut MaskedBuffer,
        t: usize,
        count: usize,
        m: std::arch::x86_64::__m512i,
        z: [f32; 4],
    ) {
        use std::arch::x86_64::{
            _CMP_GT_OQ, _MM_CMPINT_EQ, _MM_CMPINT_NE, _mm512_add_ps, _mm512_cmp_epi32_mask,
            _mm512_cmp_ps_mask, _mm512_loadu_ps, _mm512_mask_blend_epi32, _mm512_mask_blend_ps,
            _mm512_mask_cmp_ps_mask, _mm512_mask_storeu_epi32, _mm512_mask_storeu_ps,
            _mm512_maskz_loadu_epi32, _mm512_maskz_loadu_ps, _mm512_max_ps, _mm512_min_ps,
            _mm512_mul_ps, _mm512_or_si512, _mm512_set1_epi32, _mm512_set1_ps,
            _mm512_setzero_si512, _mm512_sub_ps,
        };
        let [zrow, zx, i0, zmin] = z;
        let n = count;
        assert!(n <= ROW && t + n <= buf.z0.len());
        let k = ((1u32 << n) - 1) as u16;
        // SAFETY: a value of `Avx512` exists only on a processor with AVX-512 F; the
        // loads and stores touch lanes `0 .. n` only (mask `k`), tiles `t .. t + n`,
        // inside the arrays (asserted).
        unsafe {
            let lanes = _mm512_add_ps(_mm512_set1_ps(i0), _mm512_loadu_ps(LANE.as_ptr()));
            let zt = _mm512_max_ps(
                _mm512_add_ps(
                    _mm512_set1_ps(zrow),
                    _mm512_mul_ps(_mm512_set1_ps(zx), lanes),
                ),
                _mm512_set1_ps(zmin),
            );
            let z0 = _mm512_maskz_loadu_ps(k, buf.z0.as_ptr().add(t));
            let z1 = _mm512_maskz_loadu_ps(k, buf.z1.as_ptr().add(t));
            let mask = _mm512_maskz_loadu_epi32(k, buf.mask.as_ptr().add(t).cast());
            let pad = _mm512_maskz_loadu_epi32(k, buf.pad.as_ptr().add(t).cast());
            let zero = _mm512_setzero_si512();
            let ones = _mm512_set1_epi32(-1);
            let ninf = _mm512_set1_ps(f32::NEG_INFINITY);
            // The tiles to change: some coverage and nearer than z0.
            let go = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(
                _mm512_cmp_epi32_mask::<_MM_CMPINT_NE>(m, zero) & k,
                zt,
                z0,
            );
            let full = _mm512_cmp_epi32_mask::<_MM_CMPINT_EQ>(_mm512_or_si512(m, pad), ones);
            let keep = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(z1, zt);
            let replace = _mm512_cmp_epi32_mask::<_MM_CMPINT_EQ>(mask, zero)
                | _mm512_cmp_ps_mask::<_CMP_GT_OQ>(_mm512_sub_ps(z1, zt), _mm512_sub_ps(zt, z0));
            let pm = _mm512_mask_blend_epi32(replace, _mm512_or_si512(mask, m), m);
            let pz1 = _mm512_mask_blend_ps(replace, _mm512_min_ps(z1, zt), zt);
            let promote = _mm512_cmp_epi32_mask::<_MM_CMPINT_EQ>(_mm512_or_si512(pm, pad), ones);
            // Not full: join/replace, then promote.
            let nz0 = _mm512_mask_blend_ps(promote, z0, pz1);
            let nmask = _mm512_mask_blend_epi32(promote, pm, zero);
            let nz1 = _mm512_mask_blend_ps(promote, pz1, ninf);
            // Full: z0 = zt, the working layer kept only when nearer.
            let nz0 = _mm512_mask_blend_ps(full, nz0, zt);
            let nmask =
                _mm512_mask_blend_epi32(full, nmask, _mm512_mask_blend_epi32(keep, zero, mask));
            let nz1 = _mm512_mask_blend_ps(full, nz1, _mm512_mask_blend_ps(keep, ninf, z1));
            _mm512_mask_storeu_ps(buf.z0.as_mut_ptr().add(t), go, nz0);
            _mm512_mask_storeu_ps(buf.z1.as_mut_ptr().add(t), go, nz1);
            _mm512_mask_storeu_epi32(buf.mask.as_mut_ptr().add(t).cast(), go, nmask);
        }
    }
}

/// The lane numbers `0 .. 16` as `f32`.
#[cfg(target_arch = "x86_64")]
const LANE: [f32; ROW] = [
    0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0,
];

/// Rasterizes one set-up triangle or polygon.
#[inline(always)]
fn draw_setup<L: Lanes, const N: usize>(lanes: L, buf: &mut MaskedBuffer, s: &TileSetup<N>) {
    let off = lanes.offsets(s.a, s.b);
    let mut j = 0.0f32;
    for ty in s.ty0..=s.ty1 {
        let row = step(s.e, s.ey, j);
        let zrow = s.z + s.zy * j;
        let base = ty * buf.tiles_x + s.tx0;
        let n = s.tx1 - s.tx0 + 1;
        // The row in runs of up to `ROW` tiles: their masks, then one merge.
        let mut first = 0;
        while first < n {
            let count = (n - first).min(ROW);
            lanes.row(
                buf,
                &off,
                base + first,
                count,
                row,
                s.ex,
                [zrow, s.zx, first as f32, s.zmin],
            );
            first += count;
        }
        j += 1.0;
    }
}

#[inline(always)]
fn draw_impl<L: Lanes>(lanes: L, buf: &mut MaskedBuffer, tris: &[Tri]) {
    let (w, h, r) = (buf.width, buf.height, buf.r);
    for t in tris {
        if let Some(s) = setup(t, r, w, h).and_then(|s| tile_setup(&s, r)) {
            draw_setup(lanes, buf, &s);
        }
    }
}

/// Polygons of up to four edges are drawn with four (a triangle repeats an edge), the
/// others with [`super::raster::POLY_MAX`].
#[inline(always)]
fn draw_polys_impl<L: Lanes>(lanes: L, buf: &mut MaskedBuffer, polys: &[Poly]) {
    let (w, h, r) = (buf.width, buf.height, buf.r);
    for poly in polys {
        if poly.vertices().len() <= 4 {
            if let Some(s) = poly_setup::<4>(poly, r, w, h).and_then(|s| tile_setup(&s, r)) {
                draw_setup(lanes, buf, &s);
            }
        } else if let Some(s) =
            poly_setup::<{ super::raster::POLY_MAX }>(poly, r, w, h).and_then(|s| tile_setup(&s, r))
        {
            draw_setup(lanes, buf, &s);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_polys_avx2(cpu: crate::cpu::Avx2, buf: &mut MaskedBuffer, polys: &[Poly]) {
    draw_polys_impl(cpu, buf, polys);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_polys_avx512(cpu: crate::cpu::Avx512, buf: &mut MaskedBuffer, polys: &[Poly]) {
    draw_polys_impl(cpu, buf, polys);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_avx2(cpu: crate::cpu::Avx2, buf: &mut MaskedBuffer, tris: &[Tri]) {
    draw_impl(cpu, buf, tris);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_avx512(cpu: crate::cpu::Avx512, buf: &mut MaskedBuffer, tris: &[Tri]) {
    draw_impl(cpu, buf, tris);
}

/// The portable build of the drawing (for the tests that compare kernels).
#[cfg(test)]
pub(crate) fn draw_portable(buf: &mut MaskedBuffer, tris: &[Tri]) {
    draw_impl(Portable, buf, tris);
}

/// The portable build of the polygon drawing (for the tests that compare kernels).
#[cfg(test)]
pub(crate) fn draw_polys_portable(buf: &mut MaskedBuffer, polys: &[Poly]) {
    draw_polys_impl(Portable, buf, polys);
}

#[cfg(test)]
impl MaskedBuffer {
    /// The raw state, for comparisons of kernels.
    pub(crate) fn state(&self) -> (Vec<u32>, Vec<f32>, Vec<f32>) {
        (self.mask.clone(), self.z0.clone(), self.z1.clone())
    }
}
