//! Rounding to whole pixels without C library calls (`ceil` and `floor` are calls on
//! targets without a rounding instruction, such as x86-64's baseline): the one
//! rounding of the pixel rule's sample ranges, used by [`super::sample_rect`], the
//! triangle setups, the z-buffer's bands and the scanline's rows.

/// Above this every `f64` is an integer.
const ALL_INTEGERS: f64 = 4_503_599_627_370_496.0;
/// Below this (in magnitude) adding and subtracting [`ROUND_TO_INTEGER`] rounds to the
/// nearest integer.
const ROUNDS_EXACTLY: f64 = 2_251_799_813_685_248.0;
/// `1.5 * 2^52`: a sum with it has no fraction bits left.
const ROUND_TO_INTEGER: f64 = 6_755_399_441_055_744.0;

/// `v` rounded to an integer, the nearest one for `|v| < 2^51` (no C library call
/// on targets without a rounding instruction); else by truncation, or `v` itself
/// from `2^52` on (every such `f64` is an integer) and for NaN.
#[inline(always)]
fn round_near(v: f64) -> f64 {
    if v.abs() < ROUNDS_EXACTLY {
        (v + ROUND_TO_INTEGER) - ROUND_TO_INTEGER
    } else if v.abs() < ALL_INTEGERS {
        v as i64 as f64
    } else {
        v
    }
}

/// `v.ceil()` without a C library call; NaN stays NaN.
#[inline(always)]
pub(crate) fn round_up(v: f64) -> f64 {
    let t = round_near(v);
    if t < v { t + 1.0 } else { t }
}

/// `v.floor()` without a C library call; NaN stays NaN.
#[inline(always)]
pub(crate) fn round_down(v: f64) -> f64 {
    let t = round_near(v);
    if t > v { t - 1.0 } else { t }
}

/// [`sample_rect`](super::sample_rect)'s pixel range (it calls this) of `[lo, hi]` on an axis of `n` pixels, with its
/// rounding done by truncation (no C library call where the target has no rounding
/// instruction): `ceil(lo - 0.5)` to `floor(hi - 0.5) + 1`, clamped to `0..=n`.
#[inline(always)]
pub(crate) fn sample_range(lo: f64, hi: f64, n: u32) -> (u32, u32) {
    let n = f64::from(n);
    let a = round_up(lo - 0.5).max(0.0).min(n);
    let b = (round_down(hi - 0.5) + 1.0).max(0.0).min(n);
    (a as u32, b as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_by_truncation_matches_the_library() {
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.5,
            -2.5,
            1e-300,
            -1e-300,
            7.999_999_999,
            -7.999_999_999,
            1e15 + 0.5,
            -1e15 - 0.5,
            2_251_799_813_685_247.5,
            -2_251_799_813_685_247.5,
            3e15 + 0.5,
            -3e15 - 0.5,
            4_503_599_627_370_495.5,
            1e20,
            -1e20,
            0.49999999999999994,
            -0.49999999999999994,
            1.5,
            -1.5,
            1e300,
        ] {
            assert_eq!(round_up(v), v.ceil(), "{v}");
            assert_eq!(round_down(v), v.floor(), "{v}");
        }
        assert!(round_up(f64::NAN).is_nan() && round_down(f64::INFINITY).is_infinite());
    }
}
