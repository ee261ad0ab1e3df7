//! The z-buffer: the reference every other algorithm is checked against.
//!
//! Sources: seed 000 ("Αλγόριθμος Z-buffer"), 002 ("Algoritmo Z-Buffer"), 003
//! ("Buffer de adâncime"), 004 ("Алгоритм z-буфера"). For each polygon, for each pixel it
//! covers, compute the depth from the polygon's plane and keep it if it is nearer than
//! what the buffer holds. Along a span the depth is stepped incrementally,
//! `z(x + 1) = z(x) + dz/dx` (the seeds' `z - a/c`), re-anchored from the plane equation
//! at the start of every span so errors do not accumulate down the polygon.
//!
//! - Input: a [`PreparedView`]; output: a [`Frame`].
//! - Coverage: [`crate::raster::PolygonCoverage`] (pixel centres, top-left rule).
//! - Ties: the buffer stores the depth key as `f32` and a polygon must be strictly
//!   nearer to replace a pixel; polygons are drawn in ascending face id, so the lower id
//!   wins exact ties.
//! - Complexity: O(P s), P polygons of s pixels each, about O(p) for p pixels
//!   (seed 000's table).

use crate::frame::BACKGROUND;
use crate::surface::{RenderOptions, Stats};
use crate::view::PreparedView;
use crate::{Frame, Result};

/// Renders a prepared view with the z-buffer.
pub fn render(view: &PreparedView<'_>, options: &RenderOptions) -> Result<(Frame, Stats)> {
    let vp = view.viewport();
    let mut frame = Frame::new(vp)?;
    let w = vp.width as usize;
    let mut zbuf = vec![f32::NEG_INFINITY; vp.pixel_count()];
    let (mut tested, mut written, mut drawn) = (0u64, 0u64, 0u64);
    for poly in view.polygons() {
        let Some(coverage) = poly.coverage(options.fill_rule, vp.width, vp.height) else {
            continue;
        };
        let Some(plane) = poly.depth_plane() else {
            continue;
        };
        drawn += 1;
        for (y, x0, x1) in coverage.spans() {
            let row = y as usize * w;
            let mut z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
            for x in x0 as usize..x1 as usize {
                let zf = z as f32;
                if zf > zbuf[row + x] {
                    zbuf[row + x] = zf;
                    frame.ids[row + x] = poly.face;
                    written += 1;
                }
                z += plane.dzdx;
            }
            tested += u64::from(x1 - x0);
        }
    }
    let t = view.transform();
    for (d, (&z, &id)) in frame.depth.iter_mut().zip(zbuf.iter().zip(&frame.ids)) {
        if id != BACKGROUND {
            *d = t.depth_of_zq(f64::from(z)) as f32;
        }
    }
    let mut stats = Stats::default();
    stats.set("polygons", view.polygon_count() as f64);
    stats.set("polygons_drawn", drawn as f64);
    stats.set("pixels_tested", tested as f64);
    stats.set("pixels_written", written as f64);
    Ok((frame, stats))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::FillRule;
    use crate::scene::{Viewport, demo};
    use crate::view::{PrepareOptions, prepare};

    #[test]
    fn seed_004_task_picture() {
        let scene = demo::seed_task();
        let vp = Viewport::new(32, 32).unwrap();
        let view = prepare(
            &scene,
            scene.camera().unwrap(),
            vp,
            &PrepareOptions::default(),
        )
        .unwrap();
        let opts = RenderOptions {
            fill_rule: FillRule::Inclusive,
            ..RenderOptions::default()
        };
        let (frame, _) = render(&view, &opts).unwrap();
        let ones = frame.ids.iter().filter(|&&i| i == 0).count();
        let twos = frame.ids.iter().filter(|&&i| i == 1).count();
        assert_eq!((ones, twos), (308, 58));
    }
}
