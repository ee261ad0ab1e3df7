//! The block rasterizer's buffer resolved into a frame: keys to depths, encoded ids to
//! face ids.

use super::BlockTarget;
use crate::raster::PixelRect;
use crate::raster::lanes::{DepthOfKey, Lanes};

/// Writes the depths and face ids of the target's pixels in `region` to the rows of a
/// frame (`depth` and `ids`, `width` pixels per row, starting at image row `frame_y0`):
/// see [`Lanes::resolve`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn resolve<L: Lanes>(
    l: L,
    target: &BlockTarget<'_>,
    region: PixelRect,
    depth_out: &mut [f32],
    ids_out: &mut [u32],
    width: usize,
    frame_y0: u32,
    depth: DepthOfKey,
) {
    let t = target.rect();
    let (x0, x1) = (region.x0.max(t.x0), region.x1.min(t.x1).min(width as u32));
    if x0 >= x1 {
        return;
    }
    let n = (x1 - x0) as usize;
    for y in region.y0.max(t.y0).max(frame_y0)..region.y1.min(t.y1) {
        let (keys, ids) = target.row(x0, y, n);
        let at = (y - frame_y0) as usize * width + x0 as usize;
        let Some((d, o)) = depth_out
            .get_mut(at..at + n)
            .zip(ids_out.get_mut(at..at + n))
        else {
            return;
        };
        l.resolve(keys, ids, d, o, depth);
    }
}
