//! AVX2 versions of the raster kernels (x86-64 only), for processors that have it
//! (detected at run time; [`Avx2::new`] is the only way to get the kernel, so holding
//! one proves the instructions exist).
//!
//! - [`RasterKernel::depth_test_linear`]: eight pixels per step: their keys
//!   `z + k step` in two vectors of four doubles (exact, so the order of operations
//!   does not matter), converted to eight floats, compared with the buffer, and the
//!   keys and ids blended in.
//! - [`RasterKernel::narrow_row_mask`]: the eight columns of a narrow polygon tested
//!   against each edge in two vectors of four doubles, with the expression of
//!   [`NarrowEdges`] (the same operations in the same order as the portable kernel).
//!
//! Compiled inside a function that enables AVX-512, the same intrinsics become
//! AVX-512 instructions where the compiler finds them better (masked stores).

use std::arch::x86_64::*;

use super::kernel::RasterKernel;
use super::setup::NarrowEdges;

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
    fn narrow_row_mask(self, edges: &NarrowEdges, j: u32) -> u32 {
        // SAFETY: as above.
        unsafe { narrow_row_mask_avx2(edges, j) }
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
    let done = n / 8 * 8;
    let base = done as f64;
    for (l, (k, id)) in kc
        .into_remainder()
        .iter_mut()
        .zip(ic.into_remainder().iter_mut())
        .enumerate()
    {
        let nk = -((z + (base + l as f64) * step) as f32);
        if nk < *k {
            *k = nk;
            *id = face;
            written += 1;
        }
    }
    written
}

#[target_feature(enable = "avx2,popcnt,bmi1,lzcnt")]
fn narrow_row_mask_avx2(edges: &NarrowEdges, j: u32) -> u32 {
    let py = f64::from(j) + 0.5;
    let mut lo = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    let mut hi = lo;
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
        let t0 = _mm256_sub_pd(row, c0);
        let t1 = _mm256_sub_pd(row, c1);
        lo = _mm256_and_pd(lo, _mm256_cmp_pd::<_CMP_GT_OQ>(t0, thr));
        hi = _mm256_and_pd(hi, _mm256_cmp_pd::<_CMP_GT_OQ>(t1, thr));
    }
    let m = (_mm256_movemask_pd(lo) | (_mm256_movemask_pd(hi) << 4)) as u32;
    m & edges.lanes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::depth_span;
    use crate::raster::{FillRule, PolygonSetup};
    use crate::scene::demo::SplitMix64;

    #[test]
    fn avx2_kernels_equal_the_portable_ones() {
        let Some(k) = Avx2::new() else {
            return; // nothing to compare on this processor
        };
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
        let mut setup = PolygonSetup::<16>::new();
        let mut narrow = NarrowEdges::default();
        let mut tested = 0;
        for round in 0..5000 {
            let c = (rng.range(0.0, 20.0), rng.range(0.0, 20.0));
            let s = [0.7, 2.0, 4.5][round % 3];
            let n = 3 + round % 4;
            let pts: Vec<(f64, f64, f64)> = (0..n)
                .map(|i| {
                    let a = (i as f64 + rng.range(0.0, 0.5)) * std::f64::consts::TAU / n as f64;
                    let snap = |v: f64| if round % 2 == 0 { v.round() + 0.5 } else { v };
                    (snap(c.0 + s * a.cos()), snap(c.1 + s * a.sin()), 0.5)
                })
                .collect();
            let fill = [FillRule::TopLeft, FillRule::Inclusive][round % 2];
            if !setup.set(&pts, fill, 24, 24) || !narrow.set(setup.edges(), setup.rect()) {
                continue;
            }
            let r = setup.rect();
            for j in r.y0..r.y1 {
                assert_eq!(k.narrow_row_mask(&narrow, j), narrow.row_mask(j), "{pts:?}");
                tested += 1;
            }
        }
        assert!(tested > 5000, "{tested}");
    }
}
