//! Resolving a frame of stored keys: depth keys and encoded ids, as the z-buffer's
//! block rasterizer leaves them (see [`crate::raster::lanes`]), turned into eye-space
//! depths and face ids. The z-buffer resolves its own tiles so; the scanline, which
//! stores the same keys, resolves its whole frame here, so the two give the same
//! depths bit for bit.

use crate::Frame;
#[cfg(target_arch = "x86_64")]
use crate::cpu::Avx512;
use crate::raster::lanes::{DepthOfKey, Lanes, Portable};
use crate::view::ViewTransform;

/// Turns a whole frame of keys and encoded ids (`!id`, 0 where nothing was drawn)
/// into depths and face ids, as the z-buffer's own tiles are resolved: the same
/// [`Lanes::resolve_in_place`], with the fastest kernel this processor runs, so an
/// algorithm that stores keys gives the z-buffer's depths bit for bit.
pub(crate) fn resolve_frame(frame: &mut Frame, t: &ViewTransform) {
    let depth = t.key_depths();
    #[cfg(target_arch = "x86_64")]
    if let Some(l) = Avx512::new() {
        // SAFETY: `Avx512::new` checked every feature `resolve_frame_avx512` enables.
        unsafe { resolve_frame_avx512(l, frame, depth) };
        return;
    }
    Portable.resolve_in_place(&mut frame.depth, &mut frame.ids, depth);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn resolve_frame_avx512(l: Avx512, frame: &mut Frame, depth: DepthOfKey) {
    l.resolve_in_place(&mut frame.depth, &mut frame.ids, depth);
}
