//! The depth test along a span, computing exactly the depth keys of the seeds'
//! incremental rule, many pixels at a time.
//!
//! The z-buffer of seeds 000, 003 and 004 steps the depth along a span,
//! `z(x + 1) = z(x) + dz/dx`. In `f64` every step rounds, so the key at pixel `k` is
//! `z_k = fl(z_{k-1} + d)`: a chain in which each value needs the previous one, a
//! latency of one addition per pixel. This module computes the same `z_k`, bit for
//! bit, without the chain wherever that is possible.
//!
//! # Linear runs
//! Let `z` be a normal double with `2^e <= |z| < 2^(e+1)`; doubles of that binade are
//! the multiples of `u = 2^(e-52)`. Write `d = r u` and let `D = round(r) u`. If `r` is
//! not exactly half-way between two integers and every value `z + j D` (`j < m`) lies
//! in `[2^e + u, 2^(e+1) - u]` (sign mirrored for negative `z`), then
//! `z_j = z + j D` exactly for `j < m`: by induction, the exact sum `z_{j-1} + d` lies
//! within `u / 2` of the double `z_{j-1} + D`, inside the binade where doubles are `u`
//! apart, so round-to-nearest returns that double. Every `z + j D` is itself exact
//! (a multiple of `u` in the binade), so it can be evaluated per lane, in any order.
//! [`linear_run`] finds the longest such run; a span is cut into runs, with a single
//! serial step `fl(z + d)` between runs (where the chain crosses a power of two) and
//! serial steps when no run exists (a half-way `r`, a subnormal or non-finite key).
//!
//! # The test
//! The buffer stores the *negated* key as `f32`: `-key`, so that `+inf` (the
//! background depth of a fresh [`Frame`](crate::Frame)) is the empty buffer, and a
//! pixel is taken when `-(z_k as f32) < buffer`, which is `z_k as f32 > key`: the
//! reference's strict test, so the lower face id, drawn first, keeps exact ties.
//!
//! - Complexity: O(n) per span of n pixels; O(1) work per run, at most a few runs per
//!   span (one per power of two the key crosses).
//! - Limitations: keys that are negative, zero, subnormal or huge, and steps of exactly
//!   half a unit, have no linear run: they are stepped serially (same result, slower).
//!   Depth keys of a prepared view are positive and normal but for degenerate cameras.
//! - Source: seed 000 "Αλγόριθμος Z-buffer", seed 004 "Алгоритм z-буфера" (the
//!   incremental depth); Goldberg, *What every computer scientist should know about
//!   floating-point arithmetic* (1991) for the rounding facts.

use std::ops::Range;

use super::kernel::RasterKernel;

/// Spans of at most this many pixels go to
/// [`RasterKernel::depth_test_short`]:
/// their keys stepped serially, tested together.
pub const SHORT_SPAN: usize = 8;

/// Runs shorter than this are stepped serially: a run costs more to set up than a few
/// dependent additions.
pub const SERIAL_SPAN: usize = 4;

/// The longest run from key `z` with step `d` on which the serial chain is linear,
/// limited to `max`: returns `(D, m)` with `z_j = z + j D` exactly for `j < m`, where
/// `z_0 = z` and `z_j = fl(z_{j-1} + d)`. `m` is at least 1 when `max` is (the run of
/// `z` alone), and 0 only when `max` is 0.
#[inline]
#[must_use]
pub fn linear_run(z: f64, d: f64, max: usize) -> (f64, usize) {
    let single = (d, max.min(1));
    if max <= 1 {
        return single;
    }
    // The biased exponent; keys that are zero, subnormal, very small (u would not be
    // normal), very large (2^(e+1) would overflow), infinite or NaN are served serially.
    let exp = (z.to_bits() >> 52) & 0x7ff;
    if !(54..=2045).contains(&exp) {
        return single;
    }
    let u = f64::from_bits((exp - 52) << 52);
    // 1 / u, also a power of two: d * (1 / u) is the exact d / u unless it overflows or
    // underflows, and an underflow gives a tiny r that rounds to 0 as d / u would.
    let inv_u = f64::from_bits((2098 - exp) << 52);
    let r = d * inv_u;
    if !r.is_finite() {
        return single;
    }
    let ri = r.round();
    // r - ri is exact (Sterbenz, or ri = 0). A tie rounds to even: z-dependent.
    if (r - ri).abs() == 0.5 || ri.abs() >= 4_503_599_627_370_496.0 {
        return single;
    }
    let bottom = f64::from_bits(exp << 52);
    let (lo, hi) = if z > 0.0 {
        (bottom + u, 2.0 * bottom - u)
    } else {
        (-(2.0 * bottom - u), -(bottom + u))
    };
    // Checked before a zero step is trusted: at z = 2^e the doubles below are u / 2
    // apart, and a step of less than u / 2 downwards does move the key.
    if !(lo <= z && z <= hi) {
        return single;
    }
    let step = ri * u;
    if step == 0.0 {
        // |d| < u / 2 and z's neighbours are u away: fl(z + d) = z, the key never moves.
        return (0.0, max);
    }
    // The end point, evaluated exactly when it is inside [lo, hi] (and outside it when
    // it is not: the computation is monotonic and lo, hi are doubles), decides; a
    // monotonic sequence between two points of the interval stays in it.
    let inside = |m: usize| {
        let last = z + (m - 1) as f64 * step;
        lo <= last && last <= hi
    };
    if inside(max) {
        return (step, max);
    }
    let room = if step > 0.0 { hi - z } else { lo - z };
    let fits = (room / step).floor();
    let mut m = if fits >= (max - 1) as f64 {
        max
    } else {
        fits as usize + 1
    };
    // The quotient may be one off.
    while m > 1 && !inside(m) {
        m -= 1;
    }
    (step, m)
}

/// Depth-tests `keys.len()` pixels with keys `z_k` stepped serially from `z` by `d`:
/// stores `-(z_k as f32)` and `face` where it is below the buffer. Returns the number
/// of pixels written and the key after the last pixel.
#[inline(always)]
pub fn depth_test_serial(
    keys: &mut [f32],
    ids: &mut [u32],
    mut z: f64,
    d: f64,
    face: u32,
) -> (u32, f64) {
    let mut written = 0;
    for (k, id) in keys.iter_mut().zip(ids.iter_mut()) {
        let nk = -(z as f32);
        let take = nk < *k;
        *k = if take { nk } else { *k };
        *id = if take { face } else { *id };
        written += u32::from(take);
        z += d;
    }
    (written, z)
}

/// Depth-tests pixels whose keys are `z + k step` (a run of [`linear_run`]), eight
/// independent lanes at a time. Returns the number of pixels written.
#[inline(always)]
pub fn depth_test_linear(keys: &mut [f32], ids: &mut [u32], z: f64, step: f64, face: u32) -> u32 {
    const LANES: [f64; 8] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
    let n = keys.len().min(ids.len());
    let (keys, ids) = (&mut keys[..n], &mut ids[..n]);
    let mut written = 0u32;
    let mut base = 0.0f64;
    let mut kc = keys.chunks_exact_mut(8);
    let mut ic = ids.chunks_exact_mut(8);
    for (k8, i8) in (&mut kc).zip(&mut ic) {
        let mut count = 0u32;
        for l in 0..8 {
            let nk = -((z + (base + LANES[l]) * step) as f32);
            let take = nk < k8[l];
            k8[l] = if take { nk } else { k8[l] };
            i8[l] = if take { face } else { i8[l] };
            count += u32::from(take);
        }
        written += count;
        base += 8.0;
    }
    for (l, (k, id)) in kc
        .into_remainder()
        .iter_mut()
        .zip(ic.into_remainder().iter_mut())
        .enumerate()
    {
        let nk = -((z + (base + LANES[l]) * step) as f32);
        let take = nk < *k;
        *k = if take { nk } else { *k };
        *id = if take { face } else { *id };
        written += u32::from(take);
    }
    written
}

/// Depth-tests pixels `span` of the slices, the first key being `z` and the keys
/// stepping by `d`, giving the same result as [`depth_test_serial`] on them (the module
/// doc proves it), with the linear runs drawn by `kernel` (which may rewrite other
/// elements of the slices unchanged). Returns the number of pixels written.
#[inline(always)]
pub fn depth_test_span<K: RasterKernel>(
    kernel: K,
    keys: &mut [f32],
    ids: &mut [u32],
    span: Range<usize>,
    z: f64,
    d: f64,
    face: u32,
) -> u32 {
    let (start, end) = (span.start, span.end);
    let n = end.saturating_sub(start);
    if n <= SHORT_SPAN {
        return kernel.depth_test_short(keys, ids, span, z, d, face);
    }
    let (mut z, mut k, mut written) = (z, start, 0u32);
    while k < end {
        let (step, m) = linear_run(z, d, end - k);
        if m >= SERIAL_SPAN {
            written += kernel.depth_test_linear(keys, ids, k..k + m, z, step, face);
            // The chain value at the run's last pixel, then one serial step past it.
            z += (m - 1) as f64 * step;
            z += d;
            k += m;
        } else {
            let s = (end - k).min(SERIAL_SPAN);
            let (w, next) = depth_test_serial(&mut keys[k..k + s], &mut ids[k..k + s], z, d, face);
            written += w;
            z = next;
            k += s;
        }
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::kernel::Portable;
    use crate::scene::demo::SplitMix64;

    fn chain(z: f64, d: f64, n: usize) -> Vec<f64> {
        let mut v = Vec::with_capacity(n);
        let mut z = z;
        for _ in 0..n {
            v.push(z);
            z += d;
        }
        v
    }

    fn check_run(z: f64, d: f64, n: usize) -> usize {
        let (step, m) = linear_run(z, d, n);
        assert!(m >= 1 && m <= n);
        let c = chain(z, d, m);
        for (j, &cj) in c.iter().enumerate() {
            let lin = z + j as f64 * step;
            assert_eq!(lin.to_bits(), cj.to_bits(), "z {z:e} d {d:e} j {j} of {m}");
        }
        m
    }

    #[test]
    fn linear_runs_reproduce_the_serial_chain() {
        let mut rng = SplitMix64(99);
        let mut long = 0;
        for i in 0..20_000 {
            // Keys as the pipeline makes them (0..1], steps from tiny to large.
            let z = rng.range(1e-4, 1.0) * if i % 17 == 0 { -1.0 } else { 1.0 };
            let d = rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-12.0, -1.0));
            let m = check_run(z, d, 4000);
            if m > 100 {
                long += 1;
            }
        }
        assert!(long > 10_000, "{long}");
    }

    #[test]
    fn runs_stop_at_powers_of_two_and_ties() {
        // Approaching 0.5 from above with d < 0 must stop before the binade changes.
        let z = 0.5 + 1000.0 * f64::EPSILON;
        let d = -f64::EPSILON * 0.3;
        let m = check_run(z, d, 1_000_000);
        assert!(m < 1_000_000);
        // d exactly half a unit of z's binade: rounding to even depends on z.
        let z = 0.75;
        let u = f64::EPSILON / 2.0; // spacing in [0.5, 1)
        assert_eq!(linear_run(z, u / 2.0, 100).1, 1);
        assert_eq!(check_run(z, u / 2.0, 100), 1);
        // d below half a unit: the key stays, however long the span.
        assert_eq!(linear_run(z, u / 3.0, 100), (0.0, 100));
        assert_eq!(check_run(z, u / 3.0, 100), 100);
        // At a power of two the doubles below are twice as dense: a step too small to
        // move the key upwards moves it downwards.
        let d = -0.3 * u;
        assert_ne!(0.5 + d, 0.5);
        assert_eq!(check_run(0.5, d, 100), 1);
        assert_eq!(check_run(-0.5, -d, 100), 1);
        assert_eq!(check_run(0.5, -d, 100), 1);
        // Zero, subnormal, infinite and NaN keys or steps: serial.
        for (z, d) in [
            (0.0, 1e-3),
            (1e-310, 1e-3),
            (f64::INFINITY, 1.0),
            (f64::NAN, 1.0),
            (0.5, f64::NAN),
            (0.5, f64::INFINITY),
        ] {
            assert_eq!(linear_run(z, d, 10).1, 1);
        }
        assert_eq!(linear_run(0.5, 1e-3, 0).1, 0);
    }

    #[test]
    fn span_kernel_matches_the_serial_kernel() {
        let mut rng = SplitMix64(5);
        for round in 0..3000 {
            let n = [1, 5, 11, 12, 13, 40, 257, 1000][round % 8];
            let z = rng.range(1e-3, 1.0);
            let d = rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-9.0, -2.0));
            // A buffer holding keys near the span's, so that both outcomes happen.
            let mut keys: Vec<f32> = (0..n)
                .map(|k| {
                    let near = -((z + k as f64 * d) as f32);
                    match rng.next_u64() % 4 {
                        0 => f32::INFINITY,
                        1 => near,
                        2 => near + 1e-7,
                        _ => near - 1e-7,
                    }
                })
                .collect();
            let mut ids: Vec<u32> = (0..n as u32).collect();
            let (mut k2, mut i2) = (keys.clone(), ids.clone());
            let w1 = depth_test_span(Portable, &mut keys, &mut ids, 0..n, z, d, 7777);
            let (w2, _) = depth_test_serial(&mut k2, &mut i2, z, d, 7777);
            assert_eq!(w1, w2);
            assert_eq!(ids, i2);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&keys), bits(&k2));
        }
    }
}
