//! Painting screen-space polygons into a [`Frame`], for the list-priority algorithms
//! (depth sort, BSP) that decide visibility by the order in which they paint.
//!
//! Two modes:
//! - [`PaintMode::Overwrite`]: every covered pixel takes the polygon's id and depth,
//!   whatever it held (the painter's algorithm: paint back to front, the nearest
//!   polygon is painted last).
//! - [`PaintMode::WriteOnce`]: a pixel is written only if nothing has been painted there
//!   yet (front to back: the first polygon to reach a pixel is the nearest). The painter
//!   counts uncovered pixels per row and in total, skips full rows without computing
//!   their spans, and reports when every pixel is covered so the caller can stop (seed
//!   000, "Αλγόριθμος Ταξινόμησης Κατά Βάθος (5)": "drawing stops when every pixel of
//!   the image has been covered at least once").
//!
//! Coverage is [`PolygonCoverage`] (the shared top-left rule), so the painted pixels are
//! exactly those the z-buffer would consider for the same polygon. The depth written
//! is the eye-space depth of the polygon's depth-key plane at the pixel centre,
//! computed as the z-buffer does (key stepped along the span, stored through `f32`).
//!
//! Cost: O(rows + pixels) per polygon.

use crate::frame::BACKGROUND;
use crate::raster::{DepthPlane, FillRule, PolygonCoverage};
use crate::view::{PreparedView, ViewTransform, ViewVertex};
use crate::{Frame, Result};

/// How [`Painter::paint`] treats pixels already painted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PaintMode {
    /// Later polygons overwrite earlier ones (back to front).
    Overwrite,
    /// Only unpainted pixels are written (front to back).
    WriteOnce,
}

/// A frame being painted polygon by polygon.
pub(crate) struct Painter {
    frame: Frame,
    transform: ViewTransform,
    fill: FillRule,
    mode: PaintMode,
    /// Unpainted pixels per row (write-once mode).
    row_uncovered: Vec<u32>,
    uncovered: u64,
    /// Polygons that covered at least one pixel sample.
    pub polygons_painted: u64,
    /// Pixel writes.
    pub pixels_written: u64,
    screen: Vec<(f64, f64)>,
    keyed: Vec<(f64, f64, f64)>,
}

impl Painter {
    /// A background frame for the view.
    pub fn new(view: &PreparedView<'_>, fill: FillRule, mode: PaintMode) -> Result<Self> {
        let vp = view.viewport();
        let frame = Frame::new(vp)?;
        Ok(Painter {
            frame,
            transform: *view.transform(),
            fill,
            mode,
            row_uncovered: vec![vp.width; vp.height as usize],
            uncovered: vp.pixel_count() as u64,
            polygons_painted: 0,
            pixels_written: 0,
            screen: Vec::new(),
            keyed: Vec::new(),
        })
    }

    /// Whether every pixel has been painted (only tracked in write-once mode).
    pub fn is_complete(&self) -> bool {
        self.mode == PaintMode::WriteOnce && self.uncovered == 0
    }

    /// Paints a convex polygon given by its projected vertices, with the depth plane
    /// through them. Returns the number of pixels written.
    pub fn paint_vertices(&mut self, vertices: &[ViewVertex], face: u32) -> u64 {
        self.keyed.clear();
        self.keyed.extend(vertices.iter().map(|v| (v.x, v.y, v.zq)));
        let Some(plane) = DepthPlane::from_points(&self.keyed) else {
            return 0;
        };
        self.screen.clear();
        self.screen.extend(vertices.iter().map(|v| (v.x, v.y)));
        let screen = std::mem::take(&mut self.screen);
        let n = self.paint(&screen, &plane, face);
        self.screen = screen;
        n
    }

    /// Paints a convex polygon given by screen points, with depth keys from `plane`.
    /// Returns the number of pixels written.
    pub fn paint(&mut self, screen: &[(f64, f64)], plane: &DepthPlane, face: u32) -> u64 {
        let (w, h) = (self.frame.width, self.frame.height);
        let Some(coverage) = PolygonCoverage::new(screen, self.fill, w, h) else {
            return 0;
        };
        let width = w as usize;
        let mut written = 0u64;
        let mut any = false;
        let r = coverage.rect();
        for y in r.y0..r.y1 {
            if self.mode == PaintMode::WriteOnce && self.row_uncovered[y as usize] == 0 {
                continue;
            }
            let Some((x0, x1)) = coverage.row_span(y) else {
                continue;
            };
            any = true;
            let row = y as usize * width;
            let mut z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
            let mut row_written = 0u32;
            for x in x0 as usize..x1 as usize {
                let k = row + x;
                if self.mode == PaintMode::Overwrite || self.frame.ids[k] == BACKGROUND {
                    self.frame.ids[k] = face;
                    self.frame.depth[k] = self.transform.depth_of_zq(f64::from(z as f32)) as f32;
                    row_written += 1;
                }
                z += plane.dzdx;
            }
            if self.mode == PaintMode::WriteOnce {
                self.row_uncovered[y as usize] -= row_written;
                self.uncovered -= u64::from(row_written);
            }
            written += u64::from(row_written);
        }
        self.polygons_painted += u64::from(any);
        self.pixels_written += written;
        written
    }

    /// The painted frame.
    pub fn finish(self) -> Frame {
        self.frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Scene, Viewport};
    use crate::view::{PrepareOptions, prepare};
    use glam::DVec3;

    fn empty_view(scene: &Scene, w: u32, h: u32) -> PreparedView<'_> {
        let cam = Camera::orthographic(DVec3::Z, DVec3::ZERO, DVec3::Y, 2.0, 0.1, 10.0);
        let vp = Viewport::new(u64::from(w), u64::from(h)).unwrap();
        prepare(scene, &cam, vp, &PrepareOptions::default()).unwrap()
    }

    fn flat(z: f64) -> DepthPlane {
        DepthPlane {
            x0: 0.0,
            y0: 0.0,
            z0: z,
            dzdx: 0.0,
            dzdy: 0.0,
        }
    }

    #[test]
    fn overwrite_keeps_the_last_and_write_once_the_first() {
        let scene = Scene::new();
        let view = empty_view(&scene, 8, 8);
        let a = [(0.0, 0.0), (6.0, 0.0), (6.0, 6.0), (0.0, 6.0)];
        let b = [(2.0, 2.0), (8.0, 2.0), (8.0, 8.0), (2.0, 8.0)];
        let mut over = Painter::new(&view, FillRule::TopLeft, PaintMode::Overwrite).unwrap();
        assert_eq!(over.paint(&a, &flat(0.5), 1), 36);
        assert_eq!(over.paint(&b, &flat(0.5), 2), 36);
        let f = over.finish();
        assert_eq!((f.id(3, 3), f.id(0, 0), f.id(7, 7)), (2, 1, 2));
        let mut once = Painter::new(&view, FillRule::TopLeft, PaintMode::WriteOnce).unwrap();
        once.paint(&a, &flat(0.5), 1);
        // Only the 36 - 16 pixels of b outside a are new.
        assert_eq!(once.paint(&b, &flat(0.5), 2), 20);
        assert!(!once.is_complete());
        let full = [(0.0, 0.0), (8.0, 0.0), (8.0, 8.0), (0.0, 8.0)];
        assert_eq!(once.paint(&full, &flat(0.5), 3), 64 - 56);
        assert!(once.is_complete());
        let f = once.finish();
        assert_eq!((f.id(3, 3), f.id(7, 7), f.id(7, 0)), (1, 2, 3));
        // The orthographic key 0.5 maps to the middle of [near, far].
        assert!((f.depth[0] - 5.05).abs() < 1e-5);
    }
}
