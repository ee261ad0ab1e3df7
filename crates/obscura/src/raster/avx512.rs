//! AVX-512 lanes for the block rasterizer (x86-64 only): [`Lanes`] with eight `f64` in
//! a 512-bit register and masks in mask registers, for processors that have AVX-512 F,
//! VL, BW and DQ (detected at run time; [`Avx512::new`], of [`crate::cpu`], is the only
//! way to get the value, so holding one proves the instructions exist).
//!
//! Each operation is the one of [`Portable`](super::lanes::Portable) on eight lanes at
//! once, with the same rounding (IEEE operations, no fused multiply-add, conversions
//! rounding to nearest), so both give the same bits; the tests compare them. The depth
//! test loads and stores only the lanes it is given (masked loads and stores), so rows
//! shorter than eight pixels are safe.
//!
//! - Limitations: the functions only pay inside code compiled for AVX-512 (the
//!   z-buffer's drawing loop is, behind run-time detection); elsewhere each operation
//!   is a call.
//! - Safety: every `unsafe` block calls AVX-512 intrinsics, justified by the
//!   [`Avx512`] value, and the masked memory accesses touch only lanes inside the
//!   slices (stated where they are made).
//! - Source: Intel, *Intel 64 and IA-32 Architectures Software Developer's Manual*,
//!   volume 2 (the instructions behind `core::arch::x86_64`'s intrinsics).

use std::arch::x86_64::*;

use super::lanes::{DepthOfKey, Lanes, MIN_KEY, lanes_below, lanes_below16};

/// AVX-512 lanes: the crate's one AVX-512 token ([`crate::cpu::Avx512`]), whose
/// constructor checks every feature the kernels that take it enable.
pub use crate::cpu::Avx512;

impl Lanes for Avx512 {
    type F = __m512d;

    #[inline(always)]
    fn splat(self, v: f64) -> __m512d {
        // SAFETY (this and every block below): an `Avx512` exists only when the
        // processor has the instructions.
        unsafe { _mm512_set1_pd(v) }
    }
    #[inline(always)]
    fn load(self, a: &[f64; 8]) -> __m512d {
        // SAFETY: as above; `a` holds eight doubles.
        unsafe { _mm512_loadu_pd(a.as_ptr()) }
    }
    #[inline(always)]
    fn to_array(self, v: __m512d) -> [f64; 8] {
        let mut a = [0.0; 8];
        // SAFETY: as above; `a` holds eight doubles.
        unsafe { _mm512_storeu_pd(a.as_mut_ptr(), v) };
        a
    }
    #[inline(always)]
    fn set(self, a: [f64; 8]) -> __m512d {
        unsafe { _mm512_setr_pd(a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]) }
    }
    #[inline(always)]
    fn add(self, a: __m512d, b: __m512d) -> __m512d {
        unsafe { _mm512_add_pd(a, b) }
    }
    #[inline(always)]
    fn sub(self, a: __m512d, b: __m512d) -> __m512d {
        unsafe { _mm512_sub_pd(a, b) }
    }
    #[inline(always)]
    fn mul(self, a: __m512d, b: __m512d) -> __m512d {
        unsafe { _mm512_mul_pd(a, b) }
    }
    #[inline(always)]
    fn add_scalar(self, a: __m512d, b: f64) -> __m512d {
        unsafe { _mm512_add_pd(a, _mm512_set1_pd(b)) }
    }
    #[inline(always)]
    fn sub_scalar(self, a: __m512d, b: f64) -> __m512d {
        unsafe { _mm512_sub_pd(a, _mm512_set1_pd(b)) }
    }
    #[inline(always)]
    fn select(self, m: u8, a: __m512d, b: __m512d) -> __m512d {
        // blend takes its second operand where the mask is set.
        unsafe { _mm512_mask_blend_pd(m, b, a) }
    }
    #[inline(always)]
    fn less(self, m: u8, a: __m512d, b: __m512d) -> u8 {
        unsafe { _mm512_mask_cmp_pd_mask::<_CMP_LT_OQ>(m, a, b) }
    }

    #[inline(always)]
    unsafe fn depth_test16(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u16,
        lo: __m512d,
        hi: __m512d,
        face: u32,
    ) -> u16 {
        debug_assert!(
            cover == 0 || at + 16 - cover.leading_zeros() as usize <= keys.len().min(ids.len())
        );
        // SAFETY: the caller guarantees that the pixels of `cover` are inside the
        // slices (so `at` is too when `cover` is not empty, and an empty `cover`
        // accesses nothing); the loads and stores are masked by `cover` or a subset of
        // it, and masked-off lanes are not accessed.
        unsafe {
            let (kp, ip) = (
                keys.as_mut_ptr().wrapping_add(at),
                ids.as_mut_ptr().wrapping_add(at),
            );
            let key = _mm512_insertf32x8::<1>(
                _mm512_castps256_ps512(_mm512_cvtpd_ps(lo)),
                _mm512_cvtpd_ps(hi),
            );
            let key = _mm512_max_ps(_mm512_set1_ps(MIN_KEY), key);
            let old = _mm512_maskz_loadu_ps(cover, kp);
            let mut take = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(cover, key, old);
            let tie = _mm512_mask_cmp_ps_mask::<_CMP_EQ_OQ>(cover, key, old);
            let facev = _mm512_set1_epi32(face as i32);
            if tie != 0 {
                let old_ids = _mm512_maskz_loadu_epi32(tie, ip.cast::<i32>());
                take |= _mm512_mask_cmpgt_epu32_mask(tie, facev, old_ids);
            }
            _mm512_mask_storeu_ps(kp, take, key);
            _mm512_mask_storeu_epi32(ip.cast::<i32>(), take, facev);
            take
        }
    }

    #[inline(always)]
    unsafe fn depth_test8(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u8,
        z: __m512d,
        face: u32,
    ) -> u8 {
        debug_assert!(
            cover == 0 || at + 8 - cover.leading_zeros() as usize <= keys.len().min(ids.len())
        );
        // SAFETY: as in `depth_test16`.
        unsafe {
            let (kp, ip) = (
                keys.as_mut_ptr().wrapping_add(at),
                ids.as_mut_ptr().wrapping_add(at),
            );
            let key = _mm256_max_ps(_mm256_set1_ps(MIN_KEY), _mm512_cvtpd_ps(z));
            let old = _mm256_maskz_loadu_ps(cover, kp);
            let mut take = _mm256_mask_cmp_ps_mask::<_CMP_GT_OQ>(cover, key, old);
            let tie = _mm256_mask_cmp_ps_mask::<_CMP_EQ_OQ>(cover, key, old);
            let facev = _mm256_set1_epi32(face as i32);
            if tie != 0 {
                let old_ids = _mm256_maskz_loadu_epi32(tie, ip.cast::<i32>());
                take |= _mm256_mask_cmpgt_epu32_mask(tie, facev, old_ids);
            }
            _mm256_mask_storeu_ps(kp, take, key);
            _mm256_mask_storeu_epi32(ip.cast::<i32>(), take, facev);
            take
        }
    }

    #[inline(always)]
    unsafe fn depth_test_pair(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        stride: usize,
        cover: u8,
        z: __m512d,
        face: u32,
    ) -> u8 {
        // SAFETY: as in `depth_test16`: the accesses are masked by `cover` or a subset
        // of it, row by row (lanes 0-3 the first row, 4-7 the second).
        unsafe {
            let (kp, ip) = (
                keys.as_mut_ptr().wrapping_add(at),
                ids.as_mut_ptr().wrapping_add(at),
            );
            let (kq, iq) = (kp.wrapping_add(stride), ip.wrapping_add(stride));
            let (c0, c1) = (cover & 15, cover >> 4);
            let key = _mm256_max_ps(_mm256_set1_ps(MIN_KEY), _mm512_cvtpd_ps(z));
            let old = _mm256_insertf128_ps::<1>(
                _mm256_castps128_ps256(_mm_maskz_loadu_ps(c0, kp)),
                _mm_maskz_loadu_ps(c1, kq),
            );
            let mut take = _mm256_mask_cmp_ps_mask::<_CMP_GT_OQ>(cover, key, old);
            let tie = _mm256_mask_cmp_ps_mask::<_CMP_EQ_OQ>(cover, key, old);
            let face4 = _mm_set1_epi32(face as i32);
            if tie != 0 {
                let old_ids = _mm256_inserti128_si256::<1>(
                    _mm256_castsi128_si256(_mm_maskz_loadu_epi32(tie & 15, ip.cast::<i32>())),
                    _mm_maskz_loadu_epi32(tie >> 4, iq.cast::<i32>()),
                );
                take |= _mm256_mask_cmpgt_epu32_mask(tie, _mm256_set1_epi32(face as i32), old_ids);
            }
            _mm_mask_storeu_ps(kp, take & 15, _mm256_castps256_ps128(key));
            _mm_mask_storeu_ps(kq, take >> 4, _mm256_extractf128_ps::<1>(key));
            _mm_mask_storeu_epi32(ip.cast::<i32>(), take & 15, face4);
            _mm_mask_storeu_epi32(iq.cast::<i32>(), take >> 4, face4);
            take
        }
    }

    #[inline(always)]
    fn resolve(
        self,
        keys: &[f32],
        ids: &[u32],
        depth_out: &mut [f32],
        ids_out: &mut [u32],
        depth: DepthOfKey,
    ) {
        let n = keys
            .len()
            .min(ids.len())
            .min(depth_out.len())
            .min(ids_out.len());
        let (kp, ip) = (keys.as_ptr(), ids.as_ptr().cast::<i32>());
        let (dp, op) = (depth_out.as_mut_ptr(), ids_out.as_mut_ptr().cast::<i32>());
        // SAFETY: four slices of at least `n` elements each.
        unsafe { resolve_raw(kp, ip, dp, op, n, depth) }
    }

    #[inline(always)]
    fn resolve_in_place(self, keys: &mut [f32], ids: &mut [u32], depth: DepthOfKey) {
        let n = keys.len().min(ids.len());
        let (dp, op) = (keys.as_mut_ptr(), ids.as_mut_ptr().cast::<i32>());
        // SAFETY: two slices of at least `n` elements each, read then written lane by
        // lane through the same pointers.
        unsafe { resolve_raw(dp, op, dp, op, n, depth) }
    }
}

/// [`Lanes::resolve`] on raw pointers (outputs may be the inputs).
///
/// # Safety
/// The processor has AVX-512 F, VL, BW and DQ; the four pointers are valid for `n`
/// elements (reads through `kp`, `ip`, writes through `dp`, `op`).
#[inline(always)]
unsafe fn resolve_raw(
    kp: *const f32,
    ip: *const i32,
    dp: *mut f32,
    op: *mut i32,
    n: usize,
    depth: DepthOfKey,
) {
    let mut k = 0;
    match depth {
        DepthOfKey::Perspective { near } => {
            // SAFETY: every access is to the lanes `k..k + 16` masked to those below
            // `n` (the caller's contract).
            unsafe {
                let nearv = _mm512_set1_ps(near);
                let inf = _mm512_set1_ps(f32::INFINITY);
                let ones = _mm512_set1_epi32(-1);
                while k < n {
                    let m = lanes_below16(n - k);
                    let key = _mm512_maskz_loadu_ps(m, kp.add(k));
                    let id = _mm512_maskz_loadu_epi32(m, ip.add(k));
                    let drawn = _mm512_test_epi32_mask(id, id);
                    let d = _mm512_mask_blend_ps(drawn, inf, _mm512_div_ps(nearv, key));
                    _mm512_mask_storeu_ps(dp.add(k), m, d);
                    _mm512_mask_storeu_epi32(op.add(k), m, _mm512_xor_si512(id, ones));
                    k += 16;
                }
            }
        }
        DepthOfKey::Orthographic { far, range } => {
            // SAFETY: as above, eight lanes at a time.
            unsafe {
                let (farv, rangev) = (_mm512_set1_pd(far), _mm512_set1_pd(range));
                let inf = _mm256_set1_ps(f32::INFINITY);
                let ones = _mm256_set1_epi32(-1);
                while k < n {
                    let m = lanes_below(n - k);
                    let key = _mm256_maskz_loadu_ps(m, kp.add(k));
                    let id = _mm256_maskz_loadu_epi32(m, ip.add(k));
                    let drawn = _mm256_test_epi32_mask(id, id);
                    let d = _mm512_cvtpd_ps(_mm512_sub_pd(
                        farv,
                        _mm512_mul_pd(_mm512_cvtps_pd(key), rangev),
                    ));
                    _mm256_mask_storeu_ps(dp.add(k), m, _mm256_mask_blend_ps(drawn, inf, d));
                    _mm256_mask_storeu_epi32(op.add(k), m, _mm256_xor_si256(id, ones));
                    k += 8;
                }
            }
        }
    }
}
