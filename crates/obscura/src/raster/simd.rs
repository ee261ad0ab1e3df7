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
//!
//! - Input and output: those of [`RasterKernel`], bit for bit (tests compare every
//!   kernel with [`Portable`](super::kernel::Portable) on random polygons and spans).
//! - Limitations: x86-64 only; AVX-512 intrinsics would need Rust 1.89 (the crate's
//!   minimum is 1.88), so 512-bit registers are used only where the compiler chooses.
//! - Safety: every `unsafe` block is a target-feature call justified by the
//!   [`Avx2`] value (it exists only after run-time detection) or an unaligned load or
//!   store whose bounds the block's comment states.

use std::arch::x86_64::*;

use std::ops::Range;

use super::depth_span;
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
        span: Range<usize>,
        z: f64,
        step: f64,
        face: u32,
    ) -> u32 {
        // SAFETY: an `Avx2` exists only when the processor has the features enabled.
        unsafe { depth_test_linear_avx2(keys, ids, span, z, step, face) }
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
        // SAFETY: as above.
        unsafe { depth_test_short_avx2(keys, ids, span, z, d, face) }
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

/// Depth-tests the eight pixels from `at` with keys `nk` (negated, as `f32`; `+inf`
/// in lanes to leave alone), blending keys and ids; returns how many it wrote.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn test_eight(keys: &mut [f32], ids: &mut [u32], at: usize, nk: __m256, face: __m256i) -> u32 {
    let (k8, i8) = (&mut keys[at..at + 8], &mut ids[at..at + 8]);
    let kp = k8.as_mut_ptr();
    let ip = i8.as_mut_ptr().cast::<__m256i>();
    // SAFETY: `k8` and `i8` are 8 elements long; unaligned loads and stores.
    unsafe {
        let old = _mm256_loadu_ps(kp);
        let take = _mm256_cmp_ps::<_CMP_LT_OQ>(nk, old);
        // min(nk, old) is the blend of the two by `take` (equal values are equal, a
        // NaN key keeps `old`); written as a blend, the compiler makes a masked store
        // of it, several times slower here.
        _mm256_storeu_ps(kp, _mm256_min_ps(nk, old));
        let old_ids = _mm256_loadu_si256(ip);
        _mm256_storeu_si256(
            ip,
            _mm256_blendv_epi8(old_ids, face, _mm256_castps_si256(take)),
        );
        (_mm256_movemask_ps(take) as u32).count_ones()
    }
}

/// The negated `f32` keys `z + k step` of eight consecutive pixels from `k` (`k0`,
/// `k0 + 4` the lane offsets), exact as the module doc of `depth_span` shows.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn keys_eight(z: __m256d, step: __m256d, k0: __m256d, k4: __m256d) -> __m256 {
    let a = _mm256_add_pd(z, _mm256_mul_pd(k0, step));
    let b = _mm256_add_pd(z, _mm256_mul_pd(k4, step));
    _mm256_xor_ps(
        _mm256_set_m128(_mm256_cvtpd_ps(b), _mm256_cvtpd_ps(a)),
        _mm256_set1_ps(-0.0),
    )
}

/// Up to eight pixels with the serial chain of keys: the eight values computed one
/// after the other as the serial loop does (`z += d`), then tested together, without a
/// branch on the span's length.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn depth_test_short_avx2(
    keys: &mut [f32],
    ids: &mut [u32],
    span: Range<usize>,
    z: f64,
    d: f64,
    face: u32,
) -> u32 {
    let len = keys.len().min(ids.len());
    let (start, end) = (span.start.min(len), span.end.min(len));
    let n = end.saturating_sub(start);
    if n == 0 {
        return 0;
    }
    if n > 8 {
        return depth_span::depth_test_serial(
            &mut keys[start..end],
            &mut ids[start..end],
            z,
            d,
            face,
        )
        .0;
    }
    let z1 = z + d;
    let z2 = z1 + d;
    let z3 = z2 + d;
    let z4 = z3 + d;
    let z5 = z4 + d;
    let z6 = z5 + d;
    let z7 = z6 + d;
    let a = _mm256_setr_pd(z, z1, z2, z3);
    let b = _mm256_setr_pd(z4, z5, z6, z7);
    let nk = _mm256_xor_ps(
        _mm256_set_m128(_mm256_cvtpd_ps(b), _mm256_cvtpd_ps(a)),
        _mm256_set1_ps(-0.0),
    );
    let lanes = _mm256_cmpgt_epi32(
        _mm256_set1_epi32(n as i32),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    );
    let facev = _mm256_set1_epi32(face as i32);
    if start + 8 <= len {
        let nk = _mm256_blendv_ps(
            _mm256_set1_ps(f32::INFINITY),
            nk,
            _mm256_castsi256_ps(lanes),
        );
        return test_eight(keys, ids, start, nk, facev);
    }
    // At the end of the slice: masked loads and stores touch only the span's pixels.
    let kp = keys[start..].as_mut_ptr();
    let ip = ids[start..].as_mut_ptr().cast::<i32>();
    // SAFETY: the pointers are to element `start` of the slices, and the masks enable
    // only the `n` lanes left in them.
    unsafe {
        let old = _mm256_maskload_ps(kp, lanes);
        let take = _mm256_and_si256(
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(nk, old)),
            lanes,
        );
        _mm256_maskstore_ps(kp, take, nk);
        _mm256_maskstore_epi32(ip, take, facev);
        (_mm256_movemask_ps(_mm256_castsi256_ps(take)) as u32).count_ones()
    }
}

#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn depth_test_linear_avx2(
    keys: &mut [f32],
    ids: &mut [u32],
    span: Range<usize>,
    z: f64,
    step: f64,
    face: u32,
) -> u32 {
    let len = keys.len().min(ids.len());
    let (start, end) = (span.start.min(len), span.end.min(len));
    let zv = _mm256_set1_pd(z);
    let sv = _mm256_set1_pd(step);
    let mut lo = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    let mut hi = _mm256_setr_pd(4.0, 5.0, 6.0, 7.0);
    let eight = _mm256_set1_pd(8.0);
    let facev = _mm256_set1_epi32(face as i32);
    let mut written = 0;
    let mut k = start;
    while k + 8 <= end {
        written += test_eight(keys, ids, k, keys_eight(zv, sv, lo, hi), facev);
        lo = _mm256_add_pd(lo, eight);
        hi = _mm256_add_pd(hi, eight);
        k += 8;
    }
    let rem = end.saturating_sub(k);
    if rem == 0 {
        return written;
    }
    let lanes = _mm256_cmpgt_epi32(
        _mm256_set1_epi32(rem as i32),
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
    );
    let nk = keys_eight(zv, sv, lo, hi);
    if k + 8 <= len {
        // Eight pixels of the slice, those past the span with key +inf: never taken,
        // their key and id rewritten unchanged (within the caller's slice, so within
        // its rows: no other thread's).
        let nk = _mm256_blendv_ps(
            _mm256_set1_ps(f32::INFINITY),
            nk,
            _mm256_castsi256_ps(lanes),
        );
        return written + test_eight(keys, ids, k, nk, facev);
    }
    // At the end of the slice: masked loads and stores touch only the span's pixels.
    let kp = keys[k..].as_mut_ptr();
    let ip = ids[k..].as_mut_ptr().cast::<i32>();
    // SAFETY: the pointers are to element `k` of the slices, and the masks enable only
    // the `rem` lanes left in them.
    unsafe {
        let old = _mm256_maskload_ps(kp, lanes);
        let take = _mm256_and_si256(
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(nk, old)),
            lanes,
        );
        _mm256_maskstore_ps(kp, take, nk);
        _mm256_maskstore_epi32(ip, take, facev);
        written + (_mm256_movemask_ps(_mm256_castsi256_ps(take)) as u32).count_ones()
    }
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

/// The four lanes of a vector.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn lanes(v: __m256d) -> [f64; 4] {
    let mut a = [0.0; 4];
    // SAFETY: `a` holds four doubles; unaligned store.
    unsafe { _mm256_storeu_pd(a.as_mut_ptr(), v) };
    a
}

/// One edge of a polygon, every value broadcast to the four lanes (four rows).
#[derive(Clone, Copy)]
struct EdgeLanes {
    ox: __m256d,
    oy: __m256d,
    dx: __m256d,
    dy: __m256d,
    sign: __m256d,
    threshold: __m256d,
    inv_dy: __m256d,
    rising: __m256d,
    falling: __m256d,
    flat: __m256d,
}

impl EdgeLanes {
    #[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
    fn new(e: &EdgeFunction) -> Self {
        let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        let zero = _mm256_setzero_pd();
        // d(inside)/d(px) has the sign of -sign * dy.
        let slope = -e.sign * e.dy;
        let mask = |b: bool| if b { all } else { zero };
        EdgeLanes {
            ox: _mm256_set1_pd(e.ox),
            oy: _mm256_set1_pd(e.oy),
            dx: _mm256_set1_pd(e.dx),
            dy: _mm256_set1_pd(e.dy),
            sign: _mm256_set1_pd(e.sign),
            threshold: _mm256_set1_pd(if e.include_zero {
                -f64::from_bits(1)
            } else {
                0.0
            }),
            inv_dy: _mm256_set1_pd(1.0 / e.dy),
            rising: mask(slope > 0.0),
            falling: mask(slope < 0.0),
            flat: mask(slope == 0.0),
        }
    }

    /// EdgeFunction::inside_row at `px` for the row terms `row`: `sign * (row - dy *
    /// (px - ox))` above the threshold.
    #[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
    fn inside(&self, row: __m256d, px: __m256d) -> __m256d {
        let raw = _mm256_sub_pd(row, _mm256_mul_pd(self.dy, _mm256_sub_pd(px, self.ox)));
        _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_mul_pd(self.sign, raw), self.threshold)
    }
}

/// [`linear_run`](super::depth_span::linear_run) for four keys `z` at once, for a step
/// `d` and spans of `n` pixels: the step `D` of each lane and a mask of the lanes whose
/// whole span is one run (positive normal key, no tie, both ends inside the binade
/// with a margin of one unit). Other lanes are left to the scalar function.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn linear_runs(z: __m256d, d: __m256d, n: __m256d) -> (__m256d, __m256d) {
    let exp = _mm256_and_si256(
        _mm256_srli_epi64::<52>(_mm256_castpd_si256(z)),
        _mm256_set1_epi64x(0x7ff),
    );
    let exp_ok = _mm256_and_si256(
        _mm256_cmpgt_epi64(exp, _mm256_set1_epi64x(53)),
        _mm256_cmpgt_epi64(_mm256_set1_epi64x(2046), exp),
    );
    let zero = _mm256_setzero_pd();
    let positive = _mm256_cmp_pd::<_CMP_GT_OQ>(z, zero);
    let u = _mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_sub_epi64(
        exp,
        _mm256_set1_epi64x(52),
    )));
    let inv_u = _mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_sub_epi64(
        _mm256_set1_epi64x(2098),
        exp,
    )));
    let bottom = _mm256_castsi256_pd(_mm256_slli_epi64::<52>(exp));
    let r = _mm256_mul_pd(d, inv_u);
    // Nearest, ties to even: the same integer as f64::round except at ties, rejected.
    let ri = _mm256_round_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(r);
    let abs = |v: __m256d| _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
    let not_tie = _mm256_cmp_pd::<_CMP_LT_OQ>(abs(_mm256_sub_pd(r, ri)), _mm256_set1_pd(0.5));
    let small = _mm256_cmp_pd::<_CMP_LT_OQ>(abs(ri), _mm256_set1_pd(4_503_599_627_370_496.0));
    let step = _mm256_mul_pd(ri, u);
    let lo = _mm256_add_pd(bottom, u);
    let hi = _mm256_sub_pd(_mm256_add_pd(bottom, bottom), u);
    let within = |v: __m256d| {
        _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_LE_OQ>(lo, v),
            _mm256_cmp_pd::<_CMP_LE_OQ>(v, hi),
        )
    };
    let last = _mm256_add_pd(
        z,
        _mm256_mul_pd(_mm256_sub_pd(n, _mm256_set1_pd(1.0)), step),
    );
    let ok = _mm256_and_pd(
        _mm256_and_pd(_mm256_castsi256_pd(exp_ok), positive),
        _mm256_and_pd(
            _mm256_and_pd(not_tie, small),
            _mm256_and_pd(within(z), within(last)),
        ),
    );
    (step, ok)
}

/// [`RasterKernel::draw_wide`]: polygons of at most four edges draw four rows at a
/// time; others go row by row through [`row_span`].
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
    match edges.len() {
        3 => draw_rows4::<3>(kernel, edges, rect, rows, plane, target, face),
        4 => draw_rows4::<4>(kernel, edges, rect, rows, plane, target, face),
        _ => draw_rows_by_spans(kernel, edges, rect, rows, plane, target, face),
    }
}

/// Rows of a polygon of `E` edges, four at a time, one row per lane.
///
/// Per edge the crossing of each row gives a guess `g` of the boundary column, clamped
/// to the rectangle's columns `[x0, x1]`; the exact test at columns `g - 1` and `g`
/// confirms it: for an edge whose inside pixels are those at or right of the boundary,
/// `(g == x0 or not inside(g - 1)) and (g == x1 or inside(g))`, mirrored for the other
/// direction, and a horizontal edge either holds the whole row or none of it. Each
/// test is monotonic along the row, so a confirmed `g` is the edge's exact boundary,
/// and the span is the intersection of the edges' intervals, as [`row_span`] computes
/// it. A row with an unconfirmed guess (a crossing within rounding of a pixel centre)
/// takes [`row_span`]. The depth at each span's first pixel is the plane's (the same
/// operations per lane) and [`linear_runs`] finds the rows drawn in one linear run.
#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn draw_rows4<const E: usize>(
    kernel: Avx2,
    edges: &[EdgeFunction],
    rect: PixelRect,
    rows: Range<u32>,
    plane: &DepthPlane,
    target: &mut DepthTarget<'_>,
    face: u32,
) -> SpanCounts {
    let mut c = SpanCounts::default();
    if edges.len() != E || rect.is_empty() {
        return draw_rows_by_spans(kernel, edges, rect, rows, plane, target, face);
    }
    let mut lanes_of = [EdgeLanes::new(&edges[0]); E];
    for (l, e) in lanes_of.iter_mut().zip(edges) {
        *l = EdgeLanes::new(e);
    }
    let all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    let zero = _mm256_setzero_pd();
    let half = _mm256_set1_pd(0.5);
    let (x0, x1) = (
        _mm256_set1_pd(f64::from(rect.x0)),
        _mm256_set1_pd(f64::from(rect.x1)),
    );
    let (z0, pdx, pdy) = (
        _mm256_set1_pd(plane.z0),
        _mm256_set1_pd(plane.dzdx),
        _mm256_set1_pd(plane.dzdy),
    );
    let (px0, py0) = (_mm256_set1_pd(plane.x0), _mm256_set1_pd(plane.y0));
    let mut y = rows.start;
    while y < rows.end {
        // Row centres: exact whatever the order of the sums.
        let py = _mm256_add_pd(
            _mm256_set1_pd(f64::from(y)),
            _mm256_setr_pd(0.5, 1.5, 2.5, 3.5),
        );
        let (mut lo, mut hi, mut ok, mut empty) = (x0, x1, all, zero);
        for e in &lanes_of {
            // EdgeFunction::row_term: dx * (py - oy).
            let row = _mm256_mul_pd(e.dx, _mm256_sub_pd(py, e.oy));
            let cross = _mm256_add_pd(e.ox, _mm256_mul_pd(row, e.inv_dy));
            let g = _mm256_round_pd::<{ _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC }>(
                _mm256_sub_pd(cross, half),
            );
            // max returns its second operand for a NaN guess: x0.
            let g = _mm256_min_pd(_mm256_max_pd(g, x0), x1);
            let before = e.inside(row, _mm256_sub_pd(g, half));
            let at = e.inside(row, _mm256_add_pd(g, half));
            let at_lo = _mm256_cmp_pd::<_CMP_EQ_OQ>(g, x0);
            let at_hi = _mm256_cmp_pd::<_CMP_EQ_OQ>(g, x1);
            let rise_ok = _mm256_and_pd(
                _mm256_or_pd(at_lo, _mm256_andnot_pd(before, all)),
                _mm256_or_pd(at_hi, at),
            );
            let fall_ok = _mm256_and_pd(
                _mm256_or_pd(at_lo, before),
                _mm256_or_pd(at_hi, _mm256_andnot_pd(at, all)),
            );
            ok = _mm256_and_pd(
                ok,
                _mm256_or_pd(
                    _mm256_or_pd(
                        _mm256_and_pd(e.rising, rise_ok),
                        _mm256_and_pd(e.falling, fall_ok),
                    ),
                    e.flat,
                ),
            );
            empty = _mm256_or_pd(empty, _mm256_andnot_pd(at, e.flat));
            lo = _mm256_max_pd(lo, _mm256_blendv_pd(x0, g, e.rising));
            hi = _mm256_min_pd(hi, _mm256_blendv_pd(x1, g, e.falling));
        }
        // DepthPlane::at(lo + 0.5, py): z0 + dzdx (px - x0) + dzdy (py - y0), in order.
        let px = _mm256_add_pd(lo, half);
        let z = _mm256_add_pd(
            _mm256_add_pd(z0, _mm256_mul_pd(pdx, _mm256_sub_pd(px, px0))),
            _mm256_mul_pd(pdy, _mm256_sub_pd(py, py0)),
        );
        let (step, run) = linear_runs(z, pdx, _mm256_sub_pd(hi, lo));
        let (ok, empty, run) = (
            _mm256_movemask_pd(ok),
            _mm256_movemask_pd(empty),
            _mm256_movemask_pd(run),
        );
        let (lo, hi, z, step) = (lanes(lo), lanes(hi), lanes(z), lanes(step));
        for l in 0..4 {
            let yl = y + l as u32;
            if yl >= rows.end {
                break;
            }
            if empty & (1 << l) != 0 {
                continue;
            }
            if ok & (1 << l) == 0 {
                if let Some((a, b)) = row_span(edges, rect, yl, rect.x0, rect.x1) {
                    c.add(target.draw_span(kernel, yl, a, b, plane, face));
                }
                continue;
            }
            if lo[l] >= hi[l] {
                continue;
            }
            let (a, b) = (lo[l] as u32, hi[l] as u32);
            if run & (1 << l) != 0 {
                let (keys, ids) = target.row_mut(yl);
                let span = a as usize..b as usize;
                let written = kernel.depth_test_linear(keys, ids, span, z[l], step[l], face);
                c.add(SpanCounts {
                    tested: u64::from(b - a),
                    written: u64::from(written),
                });
            } else {
                c.add(target.draw_span(kernel, yl, a, b, plane, face));
            }
        }
        y = y.saturating_add(4);
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
            // A span inside a longer slice, at its start, middle or end.
            let a = [0, n / 3, n][round % 3].min(n);
            let b = (a + rng.next_u64() as usize % (n + 1)).min(n);
            let w1 = k.depth_test_linear(&mut keys, &mut ids, a..b, z, step, 99);
            let w2 = depth_span::depth_test_linear(&mut k2[a..b], &mut i2[a..b], z, step, 99);
            assert_eq!((w1, &ids), (w2, &i2));
            // The short kernel on the first (up to) eight of them, with the serial chain.
            let c = a..b.min(a + 8);
            let w1 = k.depth_test_short(&mut keys, &mut ids, c.clone(), z, step * 1.1, 7);
            let w2 = Portable.depth_test_short(&mut k2, &mut i2, c, z, step * 1.1, 7);
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
