//! What the scanline and Warnock algorithms share: the prepared polygons with their
//! coverage and depth-key plane, the nearest-face rule on stored (`f32`) keys, a safe
//! test that one affine key is nearer than another everywhere between sample points,
//! and writing a run of pixels to the frame.
//!
//! # Why keys are compared as `f32`
//! The reference z-buffer stores depth keys as `f32` and lets a polygon win only when
//! it is strictly nearer, drawing polygons in ascending order; so two faces whose keys
//! round to the same `f32` go to the lower one. Deciding pixels on the same rounded
//! keys makes these algorithms agree with it at near-ties too (coplanar overlapping
//! faces, pixels on the line where two faces interpenetrate). Decisions taken for a
//! whole span or window ([`surely_nearer`]) demand a margin of a few `f32` steps, so
//! they hold for every rounded key in between; anything closer is decided per pixel.

use crate::frame::Frame;
use crate::raster::{DepthPlane, EdgeFunction, FillRule, PixelRect, PolygonCoverage};
use crate::view::{PreparedView, ViewTransform};

/// A prepared polygon that covers at least one sample of the image.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ScreenFace {
    /// Its depth key as an affine function of screen position.
    pub plane: DepthPlane,
    /// The pixels whose samples lie in its bounding box (clipped to the image).
    pub rect: PixelRect,
    /// The scene-wide face id written to the frame.
    pub face: u32,
    /// Its index in the [`PreparedView`].
    pub polygon: u32,
    /// Its edge functions in [`ScreenFaces::edges`].
    edges: (u32, u32),
}

/// The polygons of a view that cover at least one sample and have a finite depth
/// plane, in view order (ascending face ids): position is the tie-break order, as
/// polygon order is for the z-buffer. Edge functions are kept in one flat array
/// (what [`PolygonCoverage`] computed for each, so coverage is the shared rule's).
#[derive(Clone, Debug)]
pub(crate) struct ScreenFaces {
    /// The faces.
    pub faces: Vec<ScreenFace>,
    edges: Vec<EdgeFunction>,
    fill: FillRule,
}

impl ScreenFaces {
    /// The faces of a view under a fill rule.
    pub fn new(view: &PreparedView<'_>, fill: FillRule) -> Self {
        let vp = view.viewport();
        let mut faces = Vec::with_capacity(view.polygon_count());
        let mut edges = Vec::with_capacity(view.polygon_count() * 3);
        for (k, poly) in view.polygons().enumerate() {
            let Some(coverage) = poly.coverage(fill, vp.width, vp.height) else {
                continue;
            };
            let Some(plane) = poly.depth_plane() else {
                continue;
            };
            let finite = [plane.x0, plane.y0, plane.z0, plane.dzdx, plane.dzdy]
                .iter()
                .all(|v| v.is_finite());
            if !finite {
                continue;
            }
            let a = edges.len() as u32;
            edges.extend_from_slice(coverage.edges());
            faces.push(ScreenFace {
                plane,
                rect: coverage.rect(),
                face: poly.face,
                polygon: k as u32,
                edges: (a, edges.len() as u32),
            });
        }
        ScreenFaces { faces, edges, fill }
    }

    /// Number of faces.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// The edge functions of face `f`.
    #[inline]
    pub fn edges_of(&self, f: usize) -> &[EdgeFunction] {
        let (a, b) = self.faces[f].edges;
        &self.edges[a as usize..b as usize]
    }

    /// The shared coverage of face `f`, rebuilt from its polygon (for
    /// [`PolygonCoverage::row_span`]).
    pub fn coverage(&self, view: &PreparedView<'_>, f: usize) -> Option<PolygonCoverage> {
        let vp = view.viewport();
        view.polygon(self.faces[f].polygon as usize)
            .coverage(self.fill, vp.width, vp.height)
    }
}

/// The stored key of a plane at a sample point.
#[inline(always)]
pub(crate) fn stored_key(plane: &DepthPlane, px: f64, py: f64) -> f32 {
    plane.at(px, py) as f32
}

/// Whether face `a` with stored key `ka` hides face `b` with key `kb` at a pixel:
/// strictly nearer, or as near with the lower index.
#[inline(always)]
pub(crate) fn hides(ka: f32, a: u32, kb: f32, b: u32) -> bool {
    ka > kb || (ka == kb && a < b)
}

/// Relative margin of [`surely_nearer`]: two `f32` steps of the larger key.
const MARGIN_RELATIVE: f64 = 1.0 / (1u64 << 22) as f64;
/// Absolute margin of [`surely_nearer`]: covers the rounding of evaluating a plane in
/// `f64` far from its anchor (terms of order one, errors of order 1e-16).
const MARGIN_ABSOLUTE: f64 = 1e-15;

/// Whether key `a` is nearer than key `b` by enough that `a`'s stored key is strictly
/// greater than `b`'s, whatever rounding either evaluation suffered. Applied at the
/// end points of an interval of an affine difference, it holds in between.
#[inline(always)]
pub(crate) fn surely_nearer(a: f64, b: f64) -> bool {
    a - b > (a.abs() + b.abs()) * MARGIN_RELATIVE + MARGIN_ABSOLUTE
}

/// The sample points at the corners of a non-empty pixel rectangle.
#[inline]
pub(crate) fn corner_samples(r: PixelRect) -> [(f64, f64); 4] {
    let (xa, xb) = (f64::from(r.x0) + 0.5, f64::from(r.x1) - 0.5);
    let (ya, yb) = (f64::from(r.y0) + 0.5, f64::from(r.y1) - 0.5);
    [(xa, ya), (xb, ya), (xa, yb), (xb, yb)]
}

/// The intersection of two pixel rectangles (possibly empty).
#[inline]
pub(crate) fn intersect(a: PixelRect, b: PixelRect) -> PixelRect {
    PixelRect {
        x0: a.x0.max(b.x0),
        y0: a.y0.max(b.y0),
        x1: a.x1.min(b.x1),
        y1: a.y1.min(b.y1),
    }
}

/// Whether the face with plane `near` and sample box `near_box` hides the one with
/// `far` and `far_box` at every sample both can cover: their depth keys are affine,
/// so checking the corners of the overlap of their sample boxes (which holds the
/// overlap of the polygons) with a margin suffices. Conservative: `false` when the
/// planes cross inside the box even if the polygons do not overlap there. Returns the
/// number of key comparisons made with the answer.
#[inline]
pub(crate) fn hides_over_overlap(
    near: &DepthPlane,
    near_box: PixelRect,
    far: &DepthPlane,
    far_box: PixelRect,
) -> (bool, u64) {
    let r = intersect(near_box, far_box);
    if r.is_empty() {
        return (true, 0);
    }
    let mut n = 0;
    for (px, py) in corner_samples(r) {
        n += 1;
        if !surely_nearer(near.at(px, py), far.at(px, py)) {
            return (false, n);
        }
    }
    (true, n)
}

/// Writes the face with id `face` and depth-key plane `plane` to pixels `x0..x1` of
/// row `y`: its id and the eye depth of its stored key (stepped along the row as the
/// seeds do, re-anchored per run).
#[inline]
pub(crate) fn fill_run(
    frame: &mut Frame,
    t: &ViewTransform,
    y: u32,
    x0: u32,
    x1: u32,
    plane: &DepthPlane,
    face: u32,
) {
    if x0 >= x1 {
        return;
    }
    let w = frame.width as usize;
    let row = y as usize * w;
    let (a, b) = (row + x0 as usize, row + x1 as usize);
    let mut z = plane.at(f64::from(x0) + 0.5, f64::from(y) + 0.5);
    frame.ids[a..b].fill(face);
    for d in &mut frame.depth[a..b] {
        *d = t.depth_of_key(z as f32);
        z += plane.dzdx;
    }
}

/// Writes face id `face` with stored key `key` to one pixel.
#[inline]
pub(crate) fn set_pixel(frame: &mut Frame, t: &ViewTransform, x: u32, y: u32, face: u32, key: f32) {
    let k = frame.index(x, y);
    frame.ids[k] = face;
    frame.depth[k] = t.depth_of_key(key);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margin_guarantees_strict_order_of_rounded_keys() {
        // Keys one f32 step apart may round to the same value; the margin refuses them.
        let a = 0.05f64;
        let step = f64::from(f32::EPSILON) * a;
        assert!(!surely_nearer(a + step * 0.5, a));
        assert!(!surely_nearer(a, a));
        assert!(surely_nearer(a + step * 8.0, a));
        assert!(((a + step * 8.0) as f32) > (a as f32));
        assert!(!surely_nearer(f64::NAN, a) && !surely_nearer(a, f64::NAN));
    }

    #[test]
    fn ties_go_to_the_lower_index() {
        assert!(hides(1.0, 3, 1.0, 5));
        assert!(!hides(1.0, 5, 1.0, 3));
        assert!(hides(2.0, 5, 1.0, 3));
        assert!(!hides(f32::NAN, 0, 1.0, 3));
    }
}
