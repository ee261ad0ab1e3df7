//! Eight-lane arithmetic for the block rasterizer ([`super::block`]): one trait, a
//! portable implementation in plain Rust ([`Portable`]) and, on x86-64, one in AVX-512
//! intrinsics ([`Avx512`](super::avx512::Avx512)). The rasterizer is written once,
//! generic over the trait, so every implementation runs the same operations in the
//! same order and gives the same bits (the tests compare them).
//!
//! A lane vector holds eight `f64` (one row of an 8x8 block of pixels, or the eight
//! edges of a polygon); a mask is a `u8`, bit `l` for lane `l`.
//!
//! This is one of the crate's two lane abstractions, each for its own kind of lane:
//! here pixels and edges of the rasterizer; the BVH's packet traversal has its own
//! (`accel::bvh::packet_lanes`, one lane per ray, `f32` boxes and ray masks). Both
//! take their AVX-512 proof from the one token, [`crate::cpu::Avx512`].
//!
//! # The depth buffer
//! The rasterizer draws into rows of depth *keys* (`f32`, larger is nearer, `0` where
//! nothing was drawn) and *encoded ids* (`!face`, `0` where nothing was drawn), so that
//! a buffer of zero bits (fresh pages from the kernel) is an empty buffer. A pixel is
//! taken when its key is larger, or equal with a larger encoded id (a lower face id):
//! the order in which polygons are drawn does not change the result, and the lower face
//! id wins exact ties as in the reference z-buffer. Keys are clamped below to
//! [`MIN_KEY`] so that a drawn pixel always beats an empty one.
//!
//! - Complexity: O(1) per lane vector.
//! - Source: the depth test of seed 000 ("Αλγόριθμος Z-buffer"); wide evaluation as in
//!   Pineda, *A parallel algorithm for polygon rasterization* (SIGGRAPH 1988).

/// The smallest key a drawn pixel stores (the smallest positive `f32`): keys at or
/// below zero (possible only at the far plane of an orthographic view) still beat the
/// empty buffer.
pub const MIN_KEY: f32 = f32::from_bits(1);

/// The key stored for the depth key `z`: `z` rounded to `f32`, at least [`MIN_KEY`]
/// (NaN stays NaN, and is never stored: it fails every comparison).
#[inline(always)]
#[must_use]
pub fn key_of(z: f64) -> f32 {
    let k = z as f32;
    // The operand order of x86's `max`: the second operand when either is NaN.
    if MIN_KEY > k { MIN_KEY } else { k }
}

/// How the converted depths are computed from keys (by the rasterizer's lanes, `Lanes::resolve`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DepthOfKey {
    /// Perspective: `depth = near / key`, in `f32` (within one unit in the last place
    /// of the `f64` quotient).
    Perspective {
        /// The near plane distance, rounded to `f32`.
        near: f32,
    },
    /// Orthographic: `depth = far - key (far - near)`, in `f64` (the difference loses
    /// too much in `f32` near the near plane).
    Orthographic {
        /// The far plane distance.
        far: f64,
        /// `far - near`.
        range: f64,
    },
}

impl DepthOfKey {
    /// The depth of one key (what every implementation of `Lanes::resolve` computes).
    #[inline(always)]
    #[must_use]
    pub fn depth(self, key: f32) -> f32 {
        match self {
            DepthOfKey::Perspective { near } => near / key,
            DepthOfKey::Orthographic { far, range } => (far - f64::from(key) * range) as f32,
        }
    }
}

/// Eight-lane operations the block rasterizer needs.
pub trait Lanes: Copy {
    /// Eight `f64`.
    type F: Copy;

    /// All lanes `v`.
    fn splat(self, v: f64) -> Self::F;
    /// The lanes of an array.
    fn load(self, a: &[f64; 8]) -> Self::F;
    /// The lanes as an array.
    fn to_array(self, v: Self::F) -> [f64; 8];
    /// The lanes `a[0], ..., a[7]` built from values (in registers where the
    /// implementation can: no store and reload).
    fn set(self, a: [f64; 8]) -> Self::F;
    /// `a + b` per lane.
    fn add(self, a: Self::F, b: Self::F) -> Self::F;
    /// `a - b` per lane.
    fn sub(self, a: Self::F, b: Self::F) -> Self::F;
    /// `a * b` per lane.
    fn mul(self, a: Self::F, b: Self::F) -> Self::F;
    /// `a + b` per lane, `b` one number.
    fn add_scalar(self, a: Self::F, b: f64) -> Self::F;
    /// `a - b` per lane, `b` one number.
    fn sub_scalar(self, a: Self::F, b: f64) -> Self::F;
    /// Lanes of `a` where `m` has a bit, of `b` elsewhere.
    fn select(self, m: u8, a: Self::F, b: Self::F) -> Self::F;
    /// The lanes of `m` where `a < b` (false for NaN).
    fn less(self, m: u8, a: Self::F, b: Self::F) -> u8;

    /// Depth-tests the pixels `at + l` of the slices for the bits `l` of `cover`, with
    /// keys [`key_of`]`(z[l])` (lanes 0 to 7 from `lo`, 8 to 15 from `hi`): takes those
    /// whose key is larger than the buffer's, or equal with `face` (an encoded id)
    /// larger than the buffer's id. Returns the pixels taken.
    ///
    /// # Safety
    /// Every pixel `at + l` for a bit `l` of `cover` is inside both slices (the
    /// portable lanes check it anyway; vector lanes access memory without a check).
    #[allow(clippy::too_many_arguments)]
    unsafe fn depth_test16(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u16,
        lo: Self::F,
        hi: Self::F,
        face: u32,
    ) -> u16;

    /// [`Lanes::depth_test16`] for eight pixels.
    ///
    /// # Safety
    /// As for [`Lanes::depth_test16`].
    unsafe fn depth_test8(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u8,
        z: Self::F,
        face: u32,
    ) -> u8;

    /// [`Lanes::depth_test8`] for two rows of four pixels: lane `l < 4` is pixel
    /// `at + l`, lane `l >= 4` pixel `at + stride + l - 4`.
    ///
    /// # Safety
    /// Every pixel of a bit of `cover` is inside both slices.
    #[allow(clippy::too_many_arguments)]
    unsafe fn depth_test_pair(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        stride: usize,
        cover: u8,
        z: Self::F,
        face: u32,
    ) -> u8;

    /// Turns keys and encoded ids into depths and face ids: `depth(key)` and `!id`
    /// where the id is not 0, `+inf` and [`BACKGROUND`](crate::frame::BACKGROUND)
    /// where it is. The four slices have the same length (else the shortest counts).
    fn resolve(
        self,
        keys: &[f32],
        ids: &[u32],
        depth_out: &mut [f32],
        ids_out: &mut [u32],
        depth: DepthOfKey,
    );

    /// [`Lanes::resolve`] with the depths written over the keys and the face ids over
    /// the encoded ids.
    fn resolve_in_place(self, keys: &mut [f32], ids: &mut [u32], depth: DepthOfKey);
}

/// The mask of the lanes `0..n` (all for `n >= 8`).
#[inline(always)]
#[must_use]
pub(crate) fn lanes_below(n: usize) -> u8 {
    if n >= 8 { 0xff } else { (1u8 << n) - 1 }
}

/// The mask of the lanes `0..n` of sixteen (all for `n >= 16`).
#[inline(always)]
#[must_use]
pub(crate) fn lanes_below16(n: usize) -> u16 {
    if n >= 16 { 0xffff } else { (1u16 << n) - 1 }
}

/// The portable depth test of one pixel: whether the key `k` with encoded id `face`
/// takes the pixel holding `key` and `id`.
#[inline(always)]
fn takes(k: f32, face: u32, key: f32, id: u32) -> bool {
    k > key || (k == key && face > id)
}

/// The portable lanes: arrays, one lane after the other.
#[derive(Clone, Copy, Debug, Default)]
pub struct Portable;

impl Lanes for Portable {
    type F = [f64; 8];

    #[inline(always)]
    fn splat(self, v: f64) -> [f64; 8] {
        [v; 8]
    }
    #[inline(always)]
    fn load(self, a: &[f64; 8]) -> [f64; 8] {
        *a
    }
    #[inline(always)]
    fn to_array(self, v: [f64; 8]) -> [f64; 8] {
        v
    }
    #[inline(always)]
    fn set(self, a: [f64; 8]) -> [f64; 8] {
        a
    }
    #[inline(always)]
    fn add(self, a: [f64; 8], b: [f64; 8]) -> [f64; 8] {
        let mut o = a;
        for l in 0..8 {
            o[l] = a[l] + b[l];
        }
        o
    }
    #[inline(always)]
    fn sub(self, a: [f64; 8], b: [f64; 8]) -> [f64; 8] {
        let mut o = a;
        for l in 0..8 {
            o[l] = a[l] - b[l];
        }
        o
    }
    #[inline(always)]
    fn mul(self, a: [f64; 8], b: [f64; 8]) -> [f64; 8] {
        let mut o = a;
        for l in 0..8 {
            o[l] = a[l] * b[l];
        }
        o
    }
    #[inline(always)]
    fn add_scalar(self, a: [f64; 8], b: f64) -> [f64; 8] {
        self.add(a, [b; 8])
    }
    #[inline(always)]
    fn sub_scalar(self, a: [f64; 8], b: f64) -> [f64; 8] {
        self.sub(a, [b; 8])
    }
    #[inline(always)]
    fn select(self, m: u8, a: [f64; 8], b: [f64; 8]) -> [f64; 8] {
        let mut o = b;
        for l in 0..8 {
            if m >> l & 1 != 0 {
                o[l] = a[l];
            }
        }
        o
    }
    #[inline(always)]
    fn less(self, m: u8, a: [f64; 8], b: [f64; 8]) -> u8 {
        let mut out = 0;
        for l in 0..8 {
            out |= u8::from(a[l] < b[l]) << l;
        }
        out & m
    }

    #[inline(always)]
    unsafe fn depth_test16(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u16,
        lo: [f64; 8],
        hi: [f64; 8],
        face: u32,
    ) -> u16 {
        let z = |l: usize| if l < 8 { lo[l] } else { hi[l - 8] };
        test_pixels(keys, ids, cover, 16, |l| at.saturating_add(l), z, face)
    }

    #[inline(always)]
    unsafe fn depth_test8(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        cover: u8,
        z: [f64; 8],
        face: u32,
    ) -> u8 {
        // SAFETY: the portable test checks every index itself.
        unsafe { self.depth_test16(keys, ids, at, u16::from(cover), z, z, face) as u8 }
    }

    #[inline(always)]
    unsafe fn depth_test_pair(
        self,
        keys: &mut [f32],
        ids: &mut [u32],
        at: usize,
        stride: usize,
        cover: u8,
        z: [f64; 8],
        face: u32,
    ) -> u8 {
        let pixel = |l: usize| at.saturating_add((l >> 2) * stride + (l & 3));
        test_pixels(keys, ids, u16::from(cover), 8, pixel, |l| z[l], face) as u8
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
        for (((&k, &id), d), o) in keys.iter().zip(ids).zip(depth_out).zip(ids_out) {
            *d = if id != 0 {
                depth.depth(k)
            } else {
                f32::INFINITY
            };
            *o = !id;
        }
    }

    #[inline(always)]
    fn resolve_in_place(self, keys: &mut [f32], ids: &mut [u32], depth: DepthOfKey) {
        for (k, id) in keys.iter_mut().zip(ids) {
            *k = if *id != 0 {
                depth.depth(*k)
            } else {
                f32::INFINITY
            };
            *id = !*id;
        }
    }
}

/// The portable depth test of lanes `0..lanes` (see [`Lanes::depth_test16`]): lane `l`
/// of `cover` is pixel `pixel(l)`, its key [`key_of`]`(z(l))`; a pixel outside the
/// slices is skipped. Returns the lanes taken.
#[inline(always)]
fn test_pixels(
    keys: &mut [f32],
    ids: &mut [u32],
    cover: u16,
    lanes: usize,
    pixel: impl Fn(usize) -> usize,
    z: impl Fn(usize) -> f64,
    face: u32,
) -> u16 {
    let n = keys.len().min(ids.len());
    let mut taken = 0u16;
    for l in 0..lanes {
        let i = pixel(l);
        if cover >> l & 1 == 0 || i >= n {
            continue;
        }
        let k = key_of(z(l));
        if takes(k, face, keys[i], ids[i]) {
            keys[i] = k;
            ids[i] = face;
            taken |= 1 << l;
        }
    }
    taken
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_clamped_and_nan_kept() {
        assert_eq!(key_of(0.5), 0.5);
        assert_eq!(key_of(0.0), MIN_KEY);
        assert_eq!(key_of(-3.0), MIN_KEY);
        assert_eq!(key_of(1e-300), MIN_KEY);
        assert!(key_of(f64::NAN).is_nan());
        assert_eq!(key_of(f64::INFINITY), f32::INFINITY);
        assert_eq!(lanes_below(0), 0);
        assert_eq!(lanes_below(3), 0b111);
        assert_eq!(lanes_below(9), 0xff);
        assert_eq!(lanes_below16(9), 0x1ff);
        assert_eq!(lanes_below16(16), 0xffff);
    }

    #[test]
    fn portable_depth_test_takes_nearer_and_lower_ids_on_ties() {
        // Buffer: empty, key 0.5 id !7, key 0.5 id !7, key 0.5 id !7, key 0.25 id !3.
        let mut keys = [0.0, 0.5, 0.5, 0.5, 0.25];
        let mut ids = [0, !7, !7, !7, !3];
        // Face 5 (lower than 7) at 0.5 wins the tie, at 0.4 loses; face 9 at 0.5 loses.
        let z = [0.1, 0.5, 0.4, 0.5, 0.3, 9.0, 9.0, 9.0];
        // SAFETY (here and below): the portable test checks its indices.
        let taken = unsafe { Portable.depth_test8(&mut keys[..3], &mut ids[..3], 0, 0xff, z, !5) };
        assert_eq!(taken, 0b011);
        assert_eq!(keys, [0.1, 0.5, 0.5, 0.5, 0.25]);
        assert_eq!(ids, [!5, !5, !7, !7, !3]);
        // Only lane 1 (pixel 4, key 0.25 < 0.5) is tested, and taken.
        let taken = unsafe { Portable.depth_test16(&mut keys, &mut ids, 3, 0b10, z, z, !9) };
        assert_eq!(taken, 0b10);
        assert_eq!((keys[4], ids[4]), (0.5, !9));
        // Lanes 8.. come from the second vector.
        let (mut k, mut i) = ([0.0f32; 10], [0u32; 10]);
        let taken = unsafe { Portable.depth_test16(&mut k, &mut i, 0, 0x300, z, [0.75; 8], !1) };
        assert_eq!(
            (taken, k[8], k[9], i[9], k[0]),
            (0x300, 0.75, 0.75, !1, 0.0)
        );
        let (mut d, mut o) = ([0.0f32; 5], [0u32; 5]);
        Portable.resolve(
            &keys,
            &ids,
            &mut d,
            &mut o,
            DepthOfKey::Perspective { near: 1.0 },
        );
        assert_eq!(d, [10.0, 2.0, 2.0, 2.0, 2.0]);
        assert_eq!(o, [5, 5, 7, 7, 9]);
        let ortho = DepthOfKey::Orthographic {
            far: 10.0,
            range: 8.0,
        };
        let (mut d, mut o) = ([0.0f32; 2], [0u32; 2]);
        Portable.resolve(&[0.0, 0.25], &[0, !2], &mut d, &mut o, ortho);
        assert_eq!(d, [f32::INFINITY, 8.0]);
        assert_eq!(o, [crate::frame::BACKGROUND, 2]);
    }
}
