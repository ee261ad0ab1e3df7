//! The arithmetic of the packet kernel, one lane per ray: the box test of one child
//! against the rays of a packet, and the watertight test of one triangle against eight
//! of them.
//!
//! [`PacketLanes`] is the crate's second lane abstraction, with another purpose than
//! the rasterizer's [`crate::raster::lanes::Lanes`] (eight `f64` lanes across the
//! pixels of a row or the edges of a polygon): here a lane is a ray of a packet, boxes
//! are tested in `f32` sixteen rays at a time and triangles in `f64` eight at a time,
//! and the results are ray masks. The two share nothing but the CPU tokens of
//! [`crate::cpu`].
//!
//! [`Portable`] is plain Rust (the reference, compiled for any processor, and also for
//! AVX2 where the compiler vectorizes it); [`Avx512`](crate::cpu::Avx512) computes the same with AVX-512
//! intrinsics: sixteen rays in one register for boxes, eight in `f64` for triangles,
//! with the comparisons producing the ray masks directly. Both run the same IEEE
//! operations in the same order on the same inputs (no fused multiply-add; `min` and
//! `max` as `a < b ? a : b` and `a > b ? a : b`, which is what `vminps`/`vmaxps` do,
//! NaN included), so their masks and parameters are equal bit for bit; the tests
//! compare them lane by lane.
//!
//! Safety: an [`Avx512`](crate::cpu::Avx512) value exists only after run-time detection of the features
//! (its constructor checks them), so holding one justifies the `unsafe` calls of its
//! target-feature functions; the other `unsafe` blocks are unaligned loads and stores
//! of whole arrays of the right length.

use glam::DVec3;

use super::ray_packet::{CHUNK, Frustum, Mask, PACKET, RayPacket};
use super::traverse::{WIDEN, max, min, widen_down, widen_up};
use super::{BvhNode, WIDTH};
use crate::accel::triangles::AxisOrder;

/// `op` over the lanes of `values` in `mask` (`empty` for the others), by halving:
/// the order of a vector reduction, so that the compiler keeps it in vectors.
#[inline(always)]
fn reduce_masked(
    values: &[f32; PACKET],
    mask: Mask,
    empty: f32,
    op: impl Fn(f32, f32) -> f32,
) -> f32 {
    let mut v = [empty; PACKET];
    for r in 0..PACKET {
        if mask >> r & 1 != 0 {
            v[r] = values[r];
        }
    }
    let mut width = PACKET / 2;
    while width > 0 {
        for r in 0..width {
            v[r] = op(v[r], v[r + width]);
        }
        width /= 2;
    }
    v[0]
}

/// What the packet traversal needs from lane arithmetic.
pub(super) trait PacketLanes: Copy {
    /// The rays of `mask` that enter child `k` of `n` (its grown box) within
    /// `[t_lo, t_hi[ray]]`, and the smallest of their entry distances (meaningless
    /// when none enters).
    fn enter(
        self,
        p: &RayPacket,
        n: &BvhNode,
        k: usize,
        t_lo: f32,
        t_hi: &[f32; PACKET],
        mask: Mask,
    ) -> (Mask, f32);

    /// The interval test of the whole packet against the eight children of `n`: a bit
    /// set for each child some ray may enter within `[t_lo, t_far]`, clear for those
    /// no ray can enter (empty slots included). `t_far` bounds the far limits of the
    /// rays considered.
    fn children(self, f: &Frustum, n: &BvhNode, t_lo: f32, t_far: f32) -> u32;

    /// The largest far limit of the rays of `mask`.
    fn far_limit(self, t_hi: &[f32; PACKET], mask: Mask) -> f32;

    /// The rays of `mask` whose far limit is not before `t`.
    fn not_before(self, t_hi: &[f32; PACKET], t: f32, mask: Mask) -> Mask;

    /// The watertight test of one triangle against the rays of chunk `c` (lanes
    /// `8c..8c + 8`), lane by lane the operations of
    /// [`WatertightRay::intersect`](crate::accel::triangles::WatertightRay::intersect):
    /// the rays that hit it strictly inside its edges within `[t_min, best[ray]]`, the
    /// rays exactly on one of its edges (left to the scalar test and its tie rule), as
    /// packet masks, and the parameters of the chunk's lanes.
    fn triangle<O: AxisOrder>(
        self,
        p: &RayPacket,
        tri: &[DVec3; 3],
        c: usize,
        t_min: f64,
        best: &[f64; PACKET],
    ) -> (Mask, Mask, [f64; CHUNK]);
}

/// Plain Rust lanes (any processor).
#[derive(Clone, Copy, Debug)]
pub(super) struct Portable;

impl PacketLanes for Portable {
    #[inline(always)]
    fn children(self, f: &Frustum, n: &BvhNode, t_lo: f32, t_far: f32) -> u32 {
        let mut near = [t_lo; WIDTH];
        let mut far = [t_far; WIDTH];
        for axis in 0..3 {
            let (entry, exit) = if f.positive[axis] {
                (&n.min[axis], &n.max[axis])
            } else {
                (&n.max[axis], &n.min[axis])
            };
            let (oe, ox) = (f.entry_origin[axis], f.exit_origin[axis]);
            let (i0, i1) = (f.inv_min[axis], f.inv_max[axis]);
            for k in 0..WIDTH {
                let de = entry[k] - oe;
                let dx = exit[k] - ox;
                near[k] = max(near[k], min(de * i0, de * i1));
                far[k] = min(far[k], max(dx * i0, dx * i1));
            }
        }
        let mut out = 0;
        for k in 0..WIDTH {
            out |= u32::from(widen_down(near[k]) <= widen_up(far[k])) << k;
        }
        out
    }

    #[inline(always)]
    fn far_limit(self, t_hi: &[f32; PACKET], mask: Mask) -> f32 {
        reduce_masked(t_hi, mask, f32::NEG_INFINITY, max)
    }

    #[inline(always)]
    fn not_before(self, t_hi: &[f32; PACKET], t: f32, mask: Mask) -> Mask {
        let mut out = 0;
        for (r, &hi) in t_hi.iter().enumerate() {
            out |= Mask::from(hi >= t) << r;
        }
        out & mask
    }

    #[inline(always)]
    fn enter(
        self,
        p: &RayPacket,
        n: &BvhNode,
        k: usize,
        t_lo: f32,
        t_hi: &[f32; PACKET],
        mask: Mask,
    ) -> (Mask, f32) {
        let mut near = [t_lo; PACKET];
        let mut far = *t_hi;
        for axis in 0..3 {
            let (lo, hi) = (n.min[axis][k], n.max[axis][k]);
            let (lower, upper, inv) = (&p.lower[axis], &p.upper[axis], &p.inv[axis]);
            for r in 0..PACKET {
                let a = (lo - lower[r]) * inv[r];
                let b = (hi - upper[r]) * inv[r];
                near[r] = max(near[r], min(a, b));
                far[r] = min(far[r], max(a, b));
            }
        }
        let mut entered = 0;
        for r in 0..PACKET {
            near[r] = widen_down(near[r]);
            entered |= Mask::from(near[r] <= widen_up(far[r])) << r;
        }
        let entered = entered & mask;
        // The smallest entry of the rays that enter.
        (entered, reduce_masked(&near, entered, f32::INFINITY, min))
    }

    #[inline(always)]
    fn triangle<O: AxisOrder>(
        self,
        p: &RayPacket,
        tri: &[DVec3; 3],
        c: usize,
        t_min: f64,
        best: &[f64; PACKET],
    ) -> (Mask, Mask, [f64; CHUNK]) {
        let lanes = c * CHUNK..(c + 1) * CHUNK;
        let (ox, oy, oz) = (
            &p.origin[O::X][lanes.clone()],
            &p.origin[O::Y][lanes.clone()],
            &p.origin[O::Z][lanes.clone()],
        );
        let (sx, sy, sz) = (
            &p.shear[0][lanes.clone()],
            &p.shear[1][lanes.clone()],
            &p.shear[2][lanes.clone()],
        );
        let best = &best[lanes];
        let (v0, v1, v2) = (tri[0], tri[1], tri[2]);
        let mut t = [0.0f64; CHUNK];
        let mut hit = [false; CHUNK];
        let mut edge = [false; CHUNK];
        for r in 0..CHUNK {
            let az = v0[O::Z] - oz[r];
            let bz = v1[O::Z] - oz[r];
            let cz = v2[O::Z] - oz[r];
            let ax = (v0[O::X] - ox[r]) - sx[r] * az;
            let ay = (v0[O::Y] - oy[r]) - sy[r] * az;
            let bx = (v1[O::X] - ox[r]) - sx[r] * bz;
            let by = (v1[O::Y] - oy[r]) - sy[r] * bz;
            let cx = (v2[O::X] - ox[r]) - sx[r] * cz;
            let cy = (v2[O::Y] - oy[r]) - sy[r] * cz;
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let outside = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
            let det = u + v + w;
            // A NaN determinant is refused, as by the scalar test.
            let proper = !outside & (det != 0.0) & !det.is_nan();
            let on_edge = (u == 0.0) | (v == 0.0) | (w == 0.0);
            let tt = (u * (sz[r] * az) + v * (sz[r] * bz) + w * (sz[r] * cz)) / det;
            t[r] = tt;
            hit[r] = proper & !on_edge & (tt >= t_min) & (tt <= best[r]);
            edge[r] = proper & on_edge;
        }
        let (mut hits, mut edges) = (0, 0);
        for r in 0..CHUNK {
            hits |= Mask::from(hit[r]) << r;
            edges |= Mask::from(edge[r]) << r;
        }
        (hits << (c * CHUNK), edges << (c * CHUNK), t)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use glam::DVec3;

    use super::{BvhNode, CHUNK, Frustum, Mask, PACKET, PacketLanes, RayPacket, WIDEN};
    use crate::accel::triangles::AxisOrder;

    /// AVX-512 lanes: the crate's one AVX-512 token, whose constructor checks every
    /// feature the functions below enable.
    use crate::cpu::Avx512;

    impl PacketLanes for Avx512 {
        #[inline(always)]
        fn children(self, f: &Frustum, n: &BvhNode, t_lo: f32, t_far: f32) -> u32 {
            // SAFETY: an `Avx512` exists only when the processor has the features.
            unsafe { children(self, f, n, t_lo, t_far) }
        }

        #[inline(always)]
        fn far_limit(self, t_hi: &[f32; PACKET], mask: Mask) -> f32 {
            // SAFETY: as above; `t_hi` is sixteen `f32`, one unaligned load.
            unsafe { _mm512_mask_reduce_max_ps(mask as u16, _mm512_loadu_ps(t_hi.as_ptr())) }
        }

        #[inline(always)]
        fn not_before(self, t_hi: &[f32; PACKET], t: f32, mask: Mask) -> Mask {
            // SAFETY: as above.
            unsafe {
                Mask::from(_mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(
                    mask as u16,
                    _mm512_loadu_ps(t_hi.as_ptr()),
                    _mm512_set1_ps(t),
                ))
            }
        }

        #[inline(always)]
        fn enter(
            self,
            p: &RayPacket,
            n: &BvhNode,
            k: usize,
            t_lo: f32,
            t_hi: &[f32; PACKET],
            mask: Mask,
        ) -> (Mask, f32) {
            // SAFETY: an `Avx512` exists only when the processor has the features.
            unsafe { enter(self, p, n, k, t_lo, t_hi, mask) }
        }

        #[inline(always)]
        fn triangle<O: AxisOrder>(
            self,
            p: &RayPacket,
            tri: &[DVec3; 3],
            c: usize,
            t_min: f64,
            best: &[f64; PACKET],
        ) -> (Mask, Mask, [f64; CHUNK]) {
            // SAFETY: as above.
            unsafe { triangle::<O>(self, p, tri, c, t_min, best) }
        }
    }

    const _: () = assert!(PACKET == 16 && CHUNK == 8);

    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    #[inline]
    fn children(_: Avx512, f: &Frustum, n: &BvhNode, t_lo: f32, t_far: f32) -> u32 {
        // SAFETY (loads): every array read is `[f32; 8]`, one 256-bit unaligned load.
        unsafe {
            let mut near = _mm256_set1_ps(t_lo);
            let mut far = _mm256_set1_ps(t_far);
            for axis in 0..3 {
                let (entry, exit) = if f.positive[axis] {
                    (&n.min[axis], &n.max[axis])
                } else {
                    (&n.max[axis], &n.min[axis])
                };
                let de = _mm256_sub_ps(
                    _mm256_loadu_ps(entry.as_ptr()),
                    _mm256_set1_ps(f.entry_origin[axis]),
                );
                let dx = _mm256_sub_ps(
                    _mm256_loadu_ps(exit.as_ptr()),
                    _mm256_set1_ps(f.exit_origin[axis]),
                );
                let (i0, i1) = (
                    _mm256_set1_ps(f.inv_min[axis]),
                    _mm256_set1_ps(f.inv_max[axis]),
                );
                near = _mm256_max_ps(
                    near,
                    _mm256_min_ps(_mm256_mul_ps(de, i0), _mm256_mul_ps(de, i1)),
                );
                far = _mm256_min_ps(
                    far,
                    _mm256_max_ps(_mm256_mul_ps(dx, i0), _mm256_mul_ps(dx, i1)),
                );
            }
            // `x ∓ γ |x|`, as `widen_down` and `widen_up` compute it.
            let gamma = _mm256_set1_ps(WIDEN);
            let abs = |x| _mm256_andnot_ps(_mm256_set1_ps(-0.0), x);
            let near = _mm256_sub_ps(near, _mm256_mul_ps(abs(near), gamma));
            let far = _mm256_add_ps(far, _mm256_mul_ps(abs(far), gamma));
            u32::from(_mm256_cmp_ps_mask::<_CMP_LE_OQ>(near, far))
        }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    #[inline]
    fn enter(
        _: Avx512,
        p: &RayPacket,
        n: &BvhNode,
        k: usize,
        t_lo: f32,
        t_hi: &[f32; PACKET],
        mask: Mask,
    ) -> (Mask, f32) {
        // SAFETY (loads): every array read is `[f32; 16]`, one 512-bit unaligned load.
        unsafe {
            let mut near = _mm512_set1_ps(t_lo);
            let mut far = _mm512_loadu_ps(t_hi.as_ptr());
            for axis in 0..3 {
                let lo = _mm512_set1_ps(n.min[axis][k]);
                let hi = _mm512_set1_ps(n.max[axis][k]);
                let inv = _mm512_loadu_ps(p.inv[axis].as_ptr());
                let a = _mm512_mul_ps(
                    _mm512_sub_ps(lo, _mm512_loadu_ps(p.lower[axis].as_ptr())),
                    inv,
                );
                let b = _mm512_mul_ps(
                    _mm512_sub_ps(hi, _mm512_loadu_ps(p.upper[axis].as_ptr())),
                    inv,
                );
                near = _mm512_max_ps(near, _mm512_min_ps(a, b));
                far = _mm512_min_ps(far, _mm512_max_ps(a, b));
            }
            // `x ∓ γ |x|`, as `widen_down` and `widen_up` compute it.
            let gamma = _mm512_set1_ps(WIDEN);
            let near = _mm512_sub_ps(near, _mm512_mul_ps(_mm512_abs_ps(near), gamma));
            let far = _mm512_add_ps(far, _mm512_mul_ps(_mm512_abs_ps(far), gamma));
            let entered = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(mask as u16, near, far);
            let first = _mm512_mask_reduce_min_ps(entered, near);
            (Mask::from(entered), first)
        }
    }

    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    #[inline]
    fn triangle<O: AxisOrder>(
        _: Avx512,
        p: &RayPacket,
        tri: &[DVec3; 3],
        c: usize,
        t_min: f64,
        best: &[f64; PACKET],
    ) -> (Mask, Mask, [f64; CHUNK]) {
        let at = c * CHUNK;
        let lanes = at..at + CHUNK;
        let load = |a: &[f64; PACKET]| {
            let chunk = &a[lanes.clone()];
            // SAFETY: `chunk` holds eight `f64`, one 512-bit unaligned load.
            unsafe { _mm512_loadu_pd(chunk.as_ptr()) }
        };
        let (ox, oy, oz) = (
            load(&p.origin[O::X]),
            load(&p.origin[O::Y]),
            load(&p.origin[O::Z]),
        );
        let (sx, sy, sz) = (load(&p.shear[0]), load(&p.shear[1]), load(&p.shear[2]));
        let best = load(best);
        let set = |x: f64| _mm512_set1_pd(x);
        let (v0, v1, v2) = (tri[0], tri[1], tri[2]);
        let az = _mm512_sub_pd(set(v0[O::Z]), oz);
        let bz = _mm512_sub_pd(set(v1[O::Z]), oz);
        let cz = _mm512_sub_pd(set(v2[O::Z]), oz);
        let sheared = |v: f64, o: __m512d, s: __m512d, z: __m512d| {
            _mm512_sub_pd(_mm512_sub_pd(set(v), o), _mm512_mul_pd(s, z))
        };
        let ax = sheared(v0[O::X], ox, sx, az);
        let ay = sheared(v0[O::Y], oy, sy, az);
        let bx = sheared(v1[O::X], ox, sx, bz);
        let by = sheared(v1[O::Y], oy, sy, bz);
        let cx = sheared(v2[O::X], ox, sx, cz);
        let cy = sheared(v2[O::Y], oy, sy, cz);
        let cross = |a: __m512d, b: __m512d, c: __m512d, d: __m512d| {
            _mm512_sub_pd(_mm512_mul_pd(a, b), _mm512_mul_pd(c, d))
        };
        let u = cross(cx, by, cy, bx);
        let v = cross(ax, cy, ay, cx);
        let w = cross(bx, ay, by, ax);
        let zero = _mm512_setzero_pd();
        let negative = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(u, zero)
            | _mm512_cmp_pd_mask::<_CMP_LT_OQ>(v, zero)
            | _mm512_cmp_pd_mask::<_CMP_LT_OQ>(w, zero);
        let positive = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(u, zero)
            | _mm512_cmp_pd_mask::<_CMP_GT_OQ>(v, zero)
            | _mm512_cmp_pd_mask::<_CMP_GT_OQ>(w, zero);
        let det = _mm512_add_pd(_mm512_add_pd(u, v), w);
        // Ordered not-equal: false for NaN, as `det != 0 && det == det`.
        let proper = !(negative & positive) & _mm512_cmp_pd_mask::<_CMP_NEQ_OQ>(det, zero);
        let on_edge = _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(u, zero)
            | _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(v, zero)
            | _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(w, zero);
        let num = _mm512_add_pd(
            _mm512_add_pd(
                _mm512_mul_pd(u, _mm512_mul_pd(sz, az)),
                _mm512_mul_pd(v, _mm512_mul_pd(sz, bz)),
            ),
            _mm512_mul_pd(w, _mm512_mul_pd(sz, cz)),
        );
        let t = _mm512_div_pd(num, det);
        let in_range = _mm512_cmp_pd_mask::<_CMP_GE_OQ>(t, set(t_min))
            & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(t, best);
        let hit = proper & !on_edge & in_range;
        let edge = proper & on_edge;
        let mut out = [0.0f64; CHUNK];
        // SAFETY: `out` holds eight `f64`, one 512-bit unaligned store.
        unsafe { _mm512_storeu_pd(out.as_mut_ptr(), t) };
        (Mask::from(hit) << at, Mask::from(edge) << at, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::traverse::BoxRay;
    use crate::accel::bvh::{WIDTH, f32_down, f32_up};
    use crate::accel::triangles::{OrderXzy, OrderYxz, PrimaryRays, TieRule, WatertightRay};
    #[cfg(target_arch = "x86_64")]
    use crate::cpu::Avx512;
    use crate::rng::SplitMix64;
    use crate::scene::{Camera, Viewport};

    fn tie() -> TieRule {
        let cam = Camera::perspective(DVec3::Z * 5.0, DVec3::ZERO, DVec3::Y, 60.0, 0.1, 100.0);
        PrimaryRays::new(&cam, Viewport::new(8, 8).unwrap()).tie_rule()
    }

    /// Sixteen rays along `axis` (negative when `down`): from integer points with
    /// exact axis directions (so triangles with integer vertices put some of them
    /// exactly on edges and vertices), or from random points in a narrow cone.
    fn rays(
        rng: &mut SplitMix64,
        axis: usize,
        down: bool,
        exact: bool,
        same_signs: bool,
    ) -> Vec<(DVec3, DVec3)> {
        (0..PACKET)
            .map(|_| {
                let mut d = DVec3::ZERO;
                d[axis] = if down { -1.0 } else { 1.0 };
                if exact {
                    let o = DVec3::new(
                        (rng.next_u64() % 5) as f64 - 2.0,
                        (rng.next_u64() % 5) as f64 - 2.0,
                        (rng.next_u64() % 5) as f64 - 2.0,
                    ) - d * 6.0;
                    (o, d)
                } else {
                    let o = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0) - d * 6.0;
                    // Directions whose components keep their signs across the packet
                    // (so it has a frustum), or not.
                    let (lo, hi) = if same_signs {
                        (0.05, 0.25)
                    } else {
                        (-0.2, 0.2)
                    };
                    let spread =
                        DVec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi));
                    (o, d + spread)
                }
            })
            .collect()
    }

    fn random_node(rng: &mut SplitMix64) -> BvhNode {
        let mut n = BvhNode::default();
        for k in 0..WIDTH - 1 {
            for axis in 0..3 {
                let a = rng.range(-3.0, 3.0);
                let b = a + rng.range(0.0, 2.0);
                n.min[axis][k] = f32_down(a);
                n.max[axis][k] = f32_up(b);
            }
            n.child[k] = k as u32;
        }
        n
    }

    /// Portable lanes against the single-ray box test and the scalar triangle test, and
    /// AVX-512 lanes (where the processor has them) against portable ones, bit for bit.
    fn compare<O: AxisOrder>(axis: usize, down: bool) {
        let mut rng = SplitMix64(axis as u64 * 2 + u64::from(down));
        let tie = tie();
        #[cfg(target_arch = "x86_64")]
        let fast = Avx512::new();
        #[cfg(target_arch = "x86_64")]
        if fast.is_none() {
            crate::cpu::simd_test_skipped(
                "AVX-512",
                "packet lanes with AVX-512 against portable ones",
            );
        }
        let (mut hits, mut edges) = (0, 0);
        let (mut frustums, mut kept, mut culled) = (0, 0, 0);
        for case in 0..300 {
            let exact = case % 2 == 0;
            let list = rays(&mut rng, axis, down, exact, case % 4 == 1);
            let p = RayPacket::new(&list, 10.0);
            assert!(p.is_coherent());
            frustums += usize::from(p.frustum.is_some());
            // Boxes: every child, random masks and far limits.
            let mut n = random_node(&mut rng);
            // Boxes that rays only graze: a corner on one of the rays.
            for k in 0..WIDTH - 1 {
                if rng.next_f64() < 0.5 {
                    let (o, d) = list[(rng.next_u64() % PACKET as u64) as usize];
                    let corner = o + d * rng.range(2.0, 9.0);
                    for axis in 0..3 {
                        let size = rng.range(0.0, 1.0);
                        let (lo, hi) = if rng.next_f64() < 0.5 {
                            (corner[axis] - size, corner[axis])
                        } else {
                            (corner[axis], corner[axis] + size)
                        };
                        n.min[axis][k] = f32_down(lo);
                        n.max[axis][k] = f32_up(hi);
                    }
                }
            }
            let mask = (rng.next_u64() as Mask) & 0xffff | 1;
            let t_hi: [f32; PACKET] = std::array::from_fn(|_| {
                if rng.next_f64() < 0.3 {
                    f32::INFINITY
                } else {
                    rng.range(0.0, 12.0) as f32
                }
            });
            // The interval test keeps every child some ray of the mask enters.
            let far = Portable.far_limit(&t_hi, mask);
            let candidates = p.frustum.map(|f| Portable.children(&f, &n, 0.0, far));
            let t = rng.range(0.0, 12.0) as f32;
            let later = Portable.not_before(&t_hi, t, mask);
            assert_eq!(
                later,
                (0..PACKET).fold(0, |m, r| m | Mask::from(t_hi[r] >= t) << r) & mask
            );
            #[cfg(target_arch = "x86_64")]
            if let Some(fast) = fast {
                assert_eq!(fast.far_limit(&t_hi, mask), far);
                assert_eq!(fast.not_before(&t_hi, t, mask), later);
                assert_eq!(
                    p.frustum.map(|f| fast.children(&f, &n, 0.0, far)),
                    candidates
                );
            }
            for k in 0..WIDTH {
                let (entered, first) = Portable.enter(&p, &n, k, 0.0, &t_hi, mask);
                if let Some(c) = candidates {
                    if entered != 0 {
                        assert!(c >> k & 1 != 0, "case {case}: child {k} entered but culled");
                        kept += 1;
                    } else if c >> k & 1 == 0 {
                        culled += 1;
                    }
                }
                let mut expected = 0;
                let mut smallest = f32::INFINITY;
                for (r, &(o, d)) in list.iter().enumerate() {
                    let e = BoxRay::new(o, d, 10.0).entries(&n, 0.0, t_hi[r])[k];
                    if mask >> r & 1 != 0 && e != f32::INFINITY {
                        expected |= 1 << r;
                        smallest = smallest.min(e);
                    }
                }
                assert_eq!(entered, expected, "case {case} child {k}");
                if entered != 0 {
                    assert_eq!(first, smallest);
                }
                #[cfg(target_arch = "x86_64")]
                if let Some(fast) = fast {
                    let (e2, f2) = fast.enter(&p, &n, k, 0.0, &t_hi, mask);
                    assert_eq!(e2, entered, "case {case} child {k}");
                    if entered != 0 {
                        assert_eq!(f2, first);
                    }
                }
            }
            // Triangles: integer vertices with exact rays (edges and vertices hit
            // exactly), or random ones.
            let mut v = || {
                if exact {
                    DVec3::new(
                        (rng.next_u64() % 7) as f64 - 3.0,
                        (rng.next_u64() % 7) as f64 - 3.0,
                        (rng.next_u64() % 7) as f64 - 3.0,
                    )
                } else {
                    DVec3::new(
                        rng.range(-2.0, 2.0),
                        rng.range(-2.0, 2.0),
                        rng.range(-2.0, 2.0),
                    )
                }
            };
            let tri = [v(), v(), v()];
            let best: [f64; PACKET] =
                std::array::from_fn(|r| if r % 3 == 0 { 7.0 } else { f64::INFINITY });
            for c in 0..PACKET / CHUNK {
                let (hit, edge, t) = Portable.triangle::<O>(&p, &tri, c, 0.5, &best);
                for r in c * CHUNK..(c + 1) * CHUNK {
                    let ray = WatertightRay::new(list[r].0, list[r].1).unwrap();
                    let scalar = ray.intersect::<O>(&tri, 0.5, best[r], &tie);
                    if hit >> r & 1 != 0 {
                        assert_eq!(scalar.map(f64::to_bits), Some(t[r - c * CHUNK].to_bits()));
                        hits += 1;
                    } else if edge >> r & 1 != 0 {
                        edges += 1;
                    } else {
                        assert_eq!(scalar, None, "case {case} lane {r}");
                    }
                }
                #[cfg(target_arch = "x86_64")]
                if let Some(fast) = fast {
                    let (h2, e2, t2) = fast.triangle::<O>(&p, &tri, c, 0.5, &best);
                    assert_eq!((h2, e2), (hit, edge), "case {case} chunk {c}");
                    for r in 0..CHUNK {
                        if (hit | edge) >> (c * CHUNK + r) & 1 != 0 {
                            assert_eq!(t2[r].to_bits(), t[r].to_bits());
                        }
                    }
                }
            }
        }
        // Both kinds of lanes occurred, and the interval test both kept and culled.
        assert!(hits > 100 && edges > 20, "{hits} {edges}");
        assert!(
            frustums > 100 && kept > 100 && culled > 100,
            "{frustums} {kept} {culled}"
        );
    }

    #[test]
    fn lanes_equal_the_single_ray_tests() {
        compare::<OrderYxz>(2, true);
        compare::<OrderXzy>(1, true);
    }
}
