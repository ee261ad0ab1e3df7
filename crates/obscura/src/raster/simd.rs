//! AVX2 versions of the raster kernels (x86-64 only), for processors that have it
//! (detected at run time; [`Avx2::new`] is the only way to get the kernel, so holding
//! one proves the instructions exist).
//!
//! - [`RasterKernel::depth_test_linear`]: eight pixels per step: their keys
//!   `z + k step` in two vectors of four doubles (exact, so the order of operations
//!   does not matter), converted to eight floats, compared with the buffer, and the
//!   keys and ids blended in.
//! - [`RasterKernel::draw_narrow`]: the (up to) eight columns of a narrow polygon
//!   tested against each edge in one or two vectors of four doubles, with the
//!   expression of [`NarrowEdges`] (the same operations in the same order as the
//!   portable kernel); triangles and quads get loops specialized for their edge count,
//!   with every per-polygon constant in a register.
//!
//! Compiled inside a function that enables AVX-512, the same intrinsics become
//! AVX-512 instructions where the compiler finds them better (masked stores).

use std::arch::x86_64::*;

use std::ops::Range;

use super::kernel::{
    DepthTarget, RasterKernel, SpanCounts, draw_rows_by_spans, is_narrow, mask_span,
};
use super::setup::NarrowEdges;
use super::{DepthPlane, EdgeFunction, PixelRect, row_span};

/// The AVX2 kernels. A value exists only on a processor with AVX2, POPCNT, BMI1 and
/// LZCNT.
#[derive(Clone, Copy, Debug)]
pub struct Avx2 {
    _proof: (),
}

impl Avx2 {
    /// The kernels, if this processor runs them.
    #[must_use]
    pub fn new() -> Option<Self> {
        (is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("popcnt")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("lzcnt"))
        .then_some(Avx2 { _proof: () })
    }
}

impl RasterKernel for Avx2 {
    #[inline(always)]
    fn depth_test_linear(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        z: f64,
        step: f64,
        face: u32,
    ) -> u32 {
        // SAFETY: an `Avx2` exists only when the processor has the features enabled.
        unsafe { depth_test_linear_avx2(keys, ids, z, step, face) }
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
        // SAFETY: as above.
        unsafe { draw_narrow_avx2(self, edges, rect, rows, plane, target, face) }
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
        // SAFETY: as above.
        unsafe { draw_wide_avx2(self, edges, rect, rows, plane, target, face) }
    }
}

#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn depth_test_linear_avx2(keys: &mut [f32], ids: &mut [u32], z: f64, step: f64, face: u32) -> u32 {
    let n = keys.len().min(ids.len());
    let (keys, ids) = (&mut keys[..n], &mut ids[..n]);
    let zv = _mm256_set1_pd(z);
    let sv = _mm256_set1_pd(step);
    let mut lo = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    let mut hi = _mm256_setr_pd(4.0, 5.0, 6.0, 7.0);
    let eight = _mm256_set1_pd(8.0);
    let sign = _mm256_set1_ps(-0.0);
    let facev = _mm256_set1_epi32(face as i32);
    let mut written = 0;
    let mut kc = keys.chunks_exact_mut(8);
    let mut ic = ids.chunks_exact_mut(8);
    for (k8, i8) in (&mut kc).zip(&mut ic) {
        let a = _mm256_add_pd(zv, _mm256_mul_pd(lo, sv));
        let b = _mm256_add_pd(zv, _mm256_mul_pd(hi, sv));
        let nk = _mm256_xor_ps(
            _mm256_set_m128(_mm256_cvtpd_ps(b), _mm256_cvtpd_ps(a)),
            sign,
        );
        let kp = k8.as_mut_ptr();
        let ip = i8.as_mut_ptr().cast::<__m256i>();
        // SAFETY: `k8` and `i8` are 8 elements long; unaligned loads and stores.
        unsafe {
            let old = _mm256_loadu_ps(kp);
            let take = _mm256_cmp_ps::<_CMP_LT_OQ>(nk, old);
            _mm256_storeu_ps(kp, _mm256_blendv_ps(old, nk, take));
            let old_ids = _mm256_loadu_si256(ip);
            let new_ids = _mm256_blendv_epi8(old_ids, facev, _mm256_castps_si256(take));
            _mm256_storeu_si256(ip, new_ids);
            written += (_mm256_movemask_ps(take) as u32).count_ones();
        }
        lo = _mm256_add_pd(lo, eight);
        hi = _mm256_add_pd(hi, eight);
    }
    let rem = kc.into_remainder().len();
    if rem > 0 {
        // The last pixels with masked loads and stores: lanes past the span are neither
        // read nor written.
        let done = n - rem;
        let a = _mm256_add_pd(zv, _mm256_mul_pd(lo, sv));
        let b = _mm256_add_pd(zv, _mm256_mul_pd(hi, sv));
        let nk = _mm256_xor_ps(
            _mm256_set_m128(_mm256_cvtpd_ps(b), _mm256_cvtpd_ps(a)),
            sign,
        );
        let lanes = _mm256_cmpgt_epi32(
            _mm256_set1_epi32(rem as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        );
        let kp = keys[done..].as_mut_ptr();
        let ip = ids[done..].as_mut_ptr().cast::<i32>();
        // SAFETY: the pointers are to element `done` of the slices, and the masks enable
        // only the `rem` lanes that remain in them.
        unsafe {
            let old = _mm256_maskload_ps(kp, lanes);
            let take = _mm256_and_si256(
                _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(nk, old)),
                lanes,
            );
            _mm256_maskstore_ps(kp, take, nk);
            _mm256_maskstore_epi32(ip, take, facev);
            written += (_mm256_movemask_ps(_mm256_castsi256_ps(take)) as u32).count_ones();
        }
    }
    written
}

/// The covered columns of row `j` of a narrow polygon, any number of edges.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn narrow_row_mask_avx2(edges: &NarrowEdges, j: u32) -> u32 {
    let py = f64::from(j) + 0.5;
    let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    let (mut lo, mut hi) = (all, all);
    for k in 0..edges.count.min(edges.columns.len()) {
        let row = _mm256_set1_pd(edges.row(k, py));
        let thr = _mm256_set1_pd(edges.threshold[k]);
        let c = &edges.columns[k];
        // SAFETY: `c` is 8 doubles long.
        let (c0, c1) = unsafe {
            (
                _mm256_loadu_pd(c.as_ptr()),
                _mm256_loadu_pd(c.as_ptr().add(4)),
            )
        };
        lo = _mm256_and_pd(lo, _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_sub_pd(row, c0), thr));
        hi = _mm256_and_pd(hi, _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_sub_pd(row, c1), thr));
    }
    let m = (_mm256_movemask_pd(lo) | (_mm256_movemask_pd(hi) << 4)) as u32;
    m & edges.lanes()
}

#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn draw_narrow_avx2(
    kernel: Avx2,
    edges: &[EdgeFunction],
    rect: PixelRect,
    rows: Range<u32>,
    plane: &DepthPlane,
    target: &mut DepthTarget<'_>,
    face: u32,
) -> SpanCounts {
    if !is_narrow(edges, rect) {
        return SpanCounts::default();
    }
    let wide = rect.x1 - rect.x0 > 4;
    match (edges.len(), wide) {
        (3, false) => narrow_rows::<3, false>(kernel, edges, rect, rows, plane, target, face),
        (3, true) => narrow_rows::<3, true>(kernel, edges, rect, rows, plane, target, face),
        (4, false) => narrow_rows::<4, false>(kernel, edges, rect, rows, plane, target, face),
        (4, true) => narrow_rows::<4, true>(kernel, edges, rect, rows, plane, target, face),
        _ => {
            let mut narrow = NarrowEdges::default();
            narrow.set(edges, rect);
            let mut c = SpanCounts::default();
            for y in rows {
                let m = narrow_row_mask_avx2(&narrow, y);
                if m != 0 {
                    let (a, b) = mask_span(rect.x0, m);
                    c.add(target.draw_span(kernel, y, a, b, plane, face));
                }
            }
            c
        }
    }
}

/// [`draw_narrow_avx2`] for `E` edges and one (`WIDE` false: at most four columns) or
/// two vectors of columns, every per-polygon value held in a local.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn narrow_rows<const E: usize, const WIDE: bool>(
    kernel: Avx2,
    edges: &[EdgeFunction],
    rect: PixelRect,
    rows: Range<u32>,
    plane: &DepthPlane,
    target: &mut DepthTarget<'_>,
    face: u32,
) -> SpanCounts {
    let x0 = rect.x0;
    // Pixel centres (i + 0.5) of the columns: exact, whatever the order of the sums.
    let px0 = _mm256_add_pd(
        _mm256_set1_pd(f64::from(x0)),
        _mm256_setr_pd(0.5, 1.5, 2.5, 3.5),
    );
    let px1 = _mm256_add_pd(px0, _mm256_set1_pd(4.0));
    let zero = _mm256_setzero_pd();
    let (mut col0, mut col1, mut thr) = ([zero; E], [zero; E], [zero; E]);
    let (mut sign, mut dx, mut oy) = ([0.0; E], [0.0; E], [0.0; E]);
    for (k, e) in edges.iter().take(E).enumerate() {
        let (s, dy, ox) = (
            _mm256_set1_pd(e.sign),
            _mm256_set1_pd(e.dy),
            _mm256_set1_pd(e.ox),
        );
        // NarrowEdges::set's `sign * (dy * (px - ox))`.
        col0[k] = _mm256_mul_pd(s, _mm256_mul_pd(dy, _mm256_sub_pd(px0, ox)));
        if WIDE {
            col1[k] = _mm256_mul_pd(s, _mm256_mul_pd(dy, _mm256_sub_pd(px1, ox)));
        }
        thr[k] = _mm256_set1_pd(if e.include_zero {
            -f64::from_bits(1)
        } else {
            0.0
        });
        (sign[k], dx[k], oy[k]) = (e.sign, e.dx, e.oy);
    }
    let lanes = (1u32 << (rect.x1 - x0)) - 1;
    let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    let mut c = SpanCounts::default();
    for y in rows {
        let py = f64::from(y) + 0.5;
        let (mut lo, mut hi) = (all, all);
        for k in 0..E {
            // NarrowEdges::row's `sign * (dx * (py - oy))`.
            let r = _mm256_set1_pd(sign[k] * (dx[k] * (py - oy[k])));
            lo = _mm256_and_pd(
                lo,
                _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_sub_pd(r, col0[k]), thr[k]),
            );
            if WIDE {
                hi = _mm256_and_pd(
                    hi,
                    _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_sub_pd(r, col1[k]), thr[k]),
                );
            }
        }
        let mut m = _mm256_movemask_pd(lo) as u32;
        if WIDE {
            m |= (_mm256_movemask_pd(hi) as u32) << 4;
        }
        m &= lanes;
        if m != 0 {
            let (a, b) = mask_span(x0, m);
            c.add(target.draw_span(kernel, y, a, b, plane, face));
        }
    }
    c
}

/// [`RasterKernel::draw_wide`]: polygons of at most four edges get every row's span
/// from one vector of four edges; others go row by row through [`row_span`].
///
/// Per edge (lane) the crossing of the row gives a guess `g` of the boundary column,
/// clamped to the rectangle's columns `[x0, x1]`; the exact test at columns `g - 1`
/// and `g` confirms it: for an edge whose inside pixels are those at or right of the
/// boundary, `(g == x0 or not inside(g - 1)) and (g == x1 or inside(g))`, mirrored for
/// the other direction; a horizontal edge must hold the row inside. Each test is
/// monotonic along the row, so a confirmed `g` is the edge's exact boundary and the
/// span is the intersection of the edges' intervals, as [`row_span`] computes it. A row
/// with an unconfirmed guess (a crossing within rounding of a pixel centre) or a
/// horizontal edge excluding it takes [`row_span`].
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn draw_wide_avx2(
    kernel: Avx2,
    edges: &[EdgeFunction],
    rect: PixelRect,
    rows: Range<u32>,
    plane: &DepthPlane,
    target: &mut DepthTarget<'_>,
    face: u32,
) -> SpanCounts {
    if edges.len() > 4 || rect.is_empty() {
        return draw_rows_by_spans(kernel, edges, rect, rows, plane, target, face);
    }
    // Lanes beyond the polygon's edges hold an edge that every sample is on and
    // includes: horizontal, always inside.
    let (mut ox, mut oy, mut dx, mut dy) = ([0.0; 4], [0.0; 4], [0.0; 4], [0.0; 4]);
    let (mut sign, mut thr, mut inv) = ([1.0; 4], [-f64::from_bits(1); 4], [0.0; 4]);
    for (k, e) in edges.iter().enumerate() {
        (ox[k], oy[k], dx[k], dy[k], sign[k]) = (e.ox, e.oy, e.dx, e.dy, e.sign);
        thr[k] = if e.include_zero {
            -f64::from_bits(1)
        } else {
            0.0
        };
        inv[k] = 1.0 / e.dy;
    }
    let load = |a: &[f64; 4]| _mm256_setr_pd(a[0], a[1], a[2], a[3]);
    let (ox, oy, dx, dy) = (load(&ox), load(&oy), load(&dx), load(&dy));
    let (sign, thr, inv) = (load(&sign), load(&thr), load(&inv));
    let zero = _mm256_setzero_pd();
    // d(inside)/d(px) has the sign of -sign * dy.
    let slope = _mm256_mul_pd(_mm256_sub_pd(zero, sign), dy);
    let rising = _mm256_cmp_pd::<_CMP_GT_OQ>(slope, zero);
    let falling = _mm256_cmp_pd::<_CMP_LT_OQ>(slope, zero);
    let flat = _mm256_cmp_pd::<_CMP_EQ_OQ>(slope, zero);
    let (x0, x1) = (f64::from(rect.x0), f64::from(rect.x1));
    let (lo_x, hi_x) = (_mm256_set1_pd(x0), _mm256_set1_pd(x1));
    let half = _mm256_set1_pd(0.5);
    let inside = |row: __m256d, px: __m256d| {
        // EdgeFunction::inside_row: sign * (row - dy * (px - ox)), against 0.
        let e = _mm256_mul_pd(
            sign,
            _mm256_sub_pd(row, _mm256_mul_pd(dy, _mm256_sub_pd(px, ox))),
        );
        _mm256_cmp_pd::<_CMP_GT_OQ>(e, thr)
    };
    let mut c = SpanCounts::default();
    for y in rows {
        let py = _mm256_set1_pd(f64::from(y) + 0.5);
        // EdgeFunction::row_term: dx * (py - oy).
        let row = _mm256_mul_pd(dx, _mm256_sub_pd(py, oy));
        let cross = _mm256_add_pd(ox, _mm256_mul_pd(row, inv));
        let g = _mm256_round_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(_mm256_sub_pd(
            cross, half,
        ));
        // max/min return their second operand for a NaN guess: x0.
        let g = _mm256_min_pd(_mm256_max_pd(g, lo_x), hi_x);
        let before = inside(row, _mm256_sub_pd(g, half));
        let at = inside(row, _mm256_add_pd(g, half));
        let at_lo = _mm256_cmp_pd::<_CMP_EQ_OQ>(g, lo_x);
        let at_hi = _mm256_cmp_pd::<_CMP_EQ_OQ>(g, hi_x);
        let rise_ok = _mm256_and_pd(
            _mm256_or_pd(at_lo, _mm256_andnot_pd(before, rising)),
            _mm256_or_pd(at_hi, at),
        );
        let fall_ok = _mm256_and_pd(
            _mm256_or_pd(at_lo, before),
            _mm256_or_pd(at_hi, _mm256_andnot_pd(at, falling)),
        );
        let ok = _mm256_or_pd(
            _mm256_or_pd(
                _mm256_and_pd(rising, rise_ok),
                _mm256_and_pd(falling, fall_ok),
            ),
            _mm256_and_pd(flat, at),
        );
        let span = if _mm256_movemask_pd(ok) == 0xf {
            let lo = _mm256_blendv_pd(lo_x, g, rising);
            let hi = _mm256_blendv_pd(hi_x, g, falling);
            let lo = _mm256_max_pd(lo, _mm256_permute4x64_pd::<0b0100_1110>(lo));
            let lo = _mm256_max_pd(lo, _mm256_permute_pd::<0b0101>(lo));
            let hi = _mm256_min_pd(hi, _mm256_permute4x64_pd::<0b0100_1110>(hi));
            let hi = _mm256_min_pd(hi, _mm256_permute_pd::<0b0101>(hi));
            let (a, b) = (_mm256_cvtsd_f64(lo), _mm256_cvtsd_f64(hi));
            (a < b).then_some((a as u32, b as u32))
        } else {
            row_span(edges, rect, y, rect.x0, rect.x1)
        };
        if let Some((a, b)) = span {
            c.add(target.draw_span(kernel, y, a, b, plane, face));
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::depth_span;
    use crate::raster::kernel::Portable;
    use crate::raster::{FillRule, PolygonSetup};
    use crate::scene::demo::SplitMix64;

    #[test]
    fn avx2_kernels_equal_the_portable_ones() {
        let Some(kernel) = Avx2::new() else {
            return; // nothing to compare on this processor
        };
        let k = kernel;
        let mut rng = SplitMix64(11);
        for round in 0..2000 {
            let n = round % 70;
            let z = rng.range(1e-3, 1.0);
            let step = rng.range(-1e-4, 1e-4);
            let mut keys: Vec<f32> = (0..n)
                .map(|i| match rng.next_u64() % 3 {
                    0 => f32::INFINITY,
                    1 => -((z + i as f64 * step) as f32),
                    _ => -(rng.range(0.0, 1.0) as f32),
                })
                .collect();
            let mut ids: Vec<u32> = (0..n as u32).collect();
            let (mut k2, mut i2) = (keys.clone(), ids.clone());
            let w1 = k.depth_test_linear(&mut keys, &mut ids, z, step, 99);
            let w2 = depth_span::depth_test_linear(&mut k2, &mut i2, z, step, 99);
            assert_eq!((w1, &ids), (w2, &i2));
            for (i, (a, b)) in keys.iter().zip(&k2).enumerate() {
                assert_eq!(
                    a.to_bits(),
                    b.to_bits(),
                    "{i} of {n}: {a} {b} z {z} step {step}"
                );
            }
        }
        let (w, h) = (64u32, 48u32);
        let mut setup = PolygonSetup::<16>::new();
        let (mut narrow_tested, mut wide_tested) = (0, 0);
        for round in 0..8000 {
            let c = (rng.range(-10.0, 74.0), rng.range(-10.0, 58.0));
            let s = [0.7, 2.0, 4.5, 15.0, 60.0, 1e5][round % 6];
            let n = 3 + round % 6;
            let pts: Vec<(f64, f64, f64)> = (0..n)
                .map(|i| {
                    let a = (i as f64 + rng.range(0.0, 0.5)) * std::f64::consts::TAU / n as f64;
                    // Vertices on pixel centres half the time: horizontal edges and
                    // samples exactly on edges.
                    let snap = |v: f64| if round % 4 < 2 { v.round() + 0.5 } else { v };
                    (
                        snap(c.0 + s * a.cos()),
                        snap(c.1 + s * a.sin()),
                        rng.range(0.2, 0.3),
                    )
                })
                .collect();
            let fill = [FillRule::TopLeft, FillRule::Inclusive][round % 2];
            if !setup.set(&pts, fill, w, h) {
                continue;
            }
            let plane = setup.depth_plane().unwrap();
            let r = setup.rect();
            // Equal buffers holding keys near the polygon's, so both outcomes occur.
            let keys: Vec<f32> = (0..w * h)
                .map(|_| match rng.next_u64() % 3 {
                    0 => f32::INFINITY,
                    _ => -(rng.range(0.2, 0.3) as f32),
                })
                .collect();
            let ids: Vec<u32> = (0..w * h).collect();
            let covered = (0..h)
                .flat_map(|j| (0..w).map(move |i| (i, j)))
                .filter(|&(i, j)| setup.covers(i, j))
                .count() as u64;
            let run = |narrow: bool, simd: bool| {
                let (mut k, mut i) = (keys.clone(), ids.clone());
                let mut t = DepthTarget {
                    keys: &mut k,
                    ids: &mut i,
                    width: w as usize,
                    y0: 0,
                };
                let (e, rows) = (setup.edges(), r.y0..r.y1);
                let c = match (narrow, simd) {
                    (true, true) => kernel.draw_narrow(e, r, rows, &plane, &mut t, 9999),
                    (true, false) => Portable.draw_narrow(e, r, rows, &plane, &mut t, 9999),
                    (false, true) => kernel.draw_wide(e, r, rows, &plane, &mut t, 9999),
                    (false, false) => Portable.draw_wide(e, r, rows, &plane, &mut t, 9999),
                };
                (c, i, k.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
            };
            let expect = run(false, false);
            assert_eq!(expect.0.tested, covered, "{pts:?}");
            assert!(run(false, true) == expect, "wide {pts:?}");
            wide_tested += 1;
            if is_narrow(setup.edges(), r) {
                assert!(run(true, false) == expect, "narrow portable {pts:?}");
                assert!(run(true, true) == expect, "narrow {pts:?}");
                narrow_tested += 1;
            }
        }
        assert!(
            narrow_tested > 1000 && wide_tested > 4000,
            "{narrow_tested} {wide_tested}"
        );
    }
}
