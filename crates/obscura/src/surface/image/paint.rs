//! Painting screen-space polygons into a [`Frame`], for the list-priority algorithms
//! (depth sort, BSP) that decide visibility by the order in which they paint.
//!
//! Two modes:
//! - [`PaintMode::Overwrite`]: every covered pixel takes the polygon's id and depth,
//!   whatever it held (the painter's algorithm: paint back to front, the nearest
//!   polygon is painted last).
//! - [`PaintMode::WriteOnce`]: a pixel is written only if nothing has been painted there
//!   yet (front to back: the first polygon to reach a pixel is the nearest). The painter
//!   counts uncovered pixels per 8x8 block and in total, skips polygons whose box lies
//!   in full blocks and rows of full blocks without computing their spans, and reports
//!   when every pixel is covered so the caller can stop (seed 000, "Αλγόριθμος
//!   Ταξινόμησης Κατά Βάθος (5)": "drawing stops when every pixel of the image has been
//!   covered at least once").
//!
//! - [`PaintMode::DepthTest`]: a pixel is written only if the polygon's depth key there
//!   is nearer than the key painted (on an exact tie, if its face id is lower): the
//!   z-buffer's test. Depth sort switches to it when it leaves a conflict unresolved
//!   (see its module doc), so that the polygons painted from then on, in whatever
//!   order, still give the z-buffer's image.
//!
//! Coverage is [`PolygonCoverage`] (the shared top-left rule), so the painted pixels are
//! exactly those the z-buffer would consider for the same polygon. The depth written
//! is the eye-space depth of the polygon's depth-key plane at the pixel centre,
//! computed as the z-buffer does (the plane's key at the centre, stored through `f32`).
//!
//! A piece of a polygon that the caller cut by planes (BSP's and depth sort's
//! splits) can be painted as the pixels of the *whole* polygon that lie on its sides of
//! the cuts ([`Painter::paint_piece`], with [`ScreenCut`]s): the pieces of one polygon
//! then cover each of its pixels exactly once, where painting each piece's own
//! vertices would leave cracks at T-junctions (a piece cut again puts a rounded vertex
//! on the edge its sibling shares, and a pixel centre on that edge falls between them).
//!
//! Cost: O(rows + pixels) per polygon.
//!
//! Source: Newell, Newell and Sancha, *A solution to the hidden surface problem* (ACM
//! National Conference, 1972), painting in depth order.

use glam::DVec3;

use crate::accel::triangles::PrimaryRays;
use crate::frame::BACKGROUND;
use crate::geom::Plane;
use crate::raster::{DepthPlane, FillRule, PixelRect, PolygonCoverage};
use crate::view::{View, ViewTransform, ViewVertex};
use crate::{Frame, Result};

/// How [`Painter::paint`] treats pixels already painted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PaintMode {
    /// Later polygons overwrite earlier ones (back to front).
    Overwrite,
    /// Only unpainted pixels are written (front to back).
    WriteOnce,
    /// Only pixels where the polygon is nearer than what is painted are written.
    DepthTest,
}

/// A frame being painted polygon by polygon.
pub(crate) struct Painter {
    frame: Frame,
    transform: ViewTransform,
    fill: FillRule,
    mode: PaintMode,
    /// Unpainted pixels per block of `BLOCK x BLOCK` pixels (write-once mode).
    block_uncovered: Vec<u16>,
    blocks_x: usize,
    uncovered: u64,
    /// Polygons skipped because every block under their box was full.
    pub polygons_occluded: u64,
    /// Polygons that covered at least one pixel sample.
    pub polygons_painted: u64,
    /// Pixel writes.
    pub pixels_written: u64,
    screen: Vec<(f64, f64)>,
    keyed: Vec<(f64, f64, f64)>,
    /// The `f32` depth key of each painted pixel (0 where nothing is), kept unless the
    /// painter is write-once: [`PaintMode::DepthTest`] compares with it.
    keys: Vec<f32>,
}

/// One side of a plane `n` across a polygon of plane `m`, as the pixels whose ray meets
/// `m` at a point on that side: `n` at that point is `V = E + t G`, with `E = n(o)`
/// and `G = n . r` for the pixel's ray `o + t r`, and `t = -m(o) / (m . r)` where the
/// ray meets `m`. `E`, `G` and the numerator and denominator of `t` are affine in the
/// pixel centre `(sx, sy)`: each is kept as `[c, cx, cy]` for `c + cx sx + cy sy`. The
/// cut keeps the pixels with `V >= 0` when `non_negative`, the others (`V < 0` or NaN)
/// otherwise.
///
/// Consistency: a cut and its opposite (the same numbers, the other side) split any
/// set of pixels in two, each pixel on exactly one side, since `V` is evaluated the
/// same way for both. And the cuts of one plane across different polygons agree on
/// the side of the pixels whose ray lies in the plane (a plane seen edge-on: the
/// viewpoint in it): there `E` and `G` are the same numbers for every polygon, so
/// their signs, not the polygon's `t >= 0`, decide; with an affine form per polygon,
/// such a pixel fell on one side for one polygon and on the other for the next, and
/// the farther one could be painted first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ScreenCut {
    e: [f64; 3],
    g: [f64; 3],
    num: [f64; 3],
    den: [f64; 3],
    non_negative: bool,
}

impl ScreenCut {
    /// Whether pixel `(x, y)` is on the cut's side.
    #[inline]
    pub fn keeps(&self, x: u32, y: u32) -> bool {
        let (sx, sy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
        let at = |c: &[f64; 3]| c[0] + c[1] * sx + c[2] * sy;
        let t = -at(&self.num) / at(&self.den);
        let v = at(&self.e) + t * at(&self.g);
        (v >= 0.0) == self.non_negative
    }
}

/// The pixel rays of a view in some frame (the BSP tree's, eye space), as affine
/// functions of the pixel centre `(sx, sy)`: origin `o0 + sx ox + sy oy`, direction
/// `r0 + sx rx + sy ry` (a perspective camera's origin is fixed, an orthographic
/// one's direction). They give the [`ScreenCut`] of a plane across a polygon.
pub(crate) struct PixelRays {
    o: [DVec3; 3],
    r: [DVec3; 3],
}

impl PixelRays {
    /// The view's rays (world space, [`PrimaryRays`]) carried into another frame by
    /// an affine map of world space: `point` maps points, `vector` its linear part.
    pub fn new(
        view: &View<'_>,
        point: impl Fn(DVec3) -> DVec3,
        vector: impl Fn(DVec3) -> DVec3,
    ) -> Self {
        let rays = PrimaryRays::new(view.camera(), view.viewport());
        let (o0, r0) = rays.ray(0.0, 0.0);
        let (o1, r1) = rays.ray(1.0, 0.0);
        let (o2, r2) = rays.ray(0.0, 1.0);
        let v = vector;
        PixelRays {
            o: [point(o0), v(o1 - o0), v(o2 - o0)],
            r: [v(r0), v(r1 - r0), v(r2 - r0)],
        }
    }

    /// The cut of a piece of a polygon of plane `m` by the plane `n` (both in the
    /// rays' frame), keeping the side `front` (`n` positive): see [`ScreenCut`].
    pub fn cut(&self, m: &Plane, n: &Plane, front: bool) -> ScreenCut {
        let affine = |p: &Plane, at: &[DVec3; 3], point: bool| {
            let d = if point { p.d } else { 0.0 };
            [
                p.normal.dot(at[0]) + d,
                p.normal.dot(at[1]),
                p.normal.dot(at[2]),
            ]
        };
        ScreenCut {
            e: affine(n, &self.o, true),
            g: affine(n, &self.r, false),
            num: affine(m, &self.o, true),
            den: affine(m, &self.r, false),
            non_negative: front,
        }
    }
}

/// The box `(min x, min y, max x, max y)` of screen points (infinities for none).
fn screen_box(points: impl Iterator<Item = (f64, f64)>) -> (f64, f64, f64, f64) {
    points.fold(
        (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |(x0, y0, x1, y1), (x, y)| (x0.min(x), y0.min(y), x1.max(x), y1.max(y)),
    )
}

/// The pixels that may hold samples of a piece projected to `screen`: its box widened
/// by two pixels (far above the rounding of its split vertices), within a `width x
/// height` image.
pub(crate) fn piece_region(screen: &[ViewVertex], width: f64, height: f64) -> PixelRect {
    let (minx, miny, maxx, maxy) = screen_box(screen.iter().map(|v| (v.x, v.y)));
    let clamp = |v: f64, hi: f64| v.clamp(0.0, hi) as u32;
    PixelRect {
        x0: clamp((minx - 2.0).floor(), width),
        y0: clamp((miny - 2.0).floor(), height),
        x1: clamp((maxx + 2.0).ceil(), width),
        y1: clamp((maxy + 2.0).ceil(), height),
    }
}

/// Side of the coverage blocks of write-once painting, in pixels.
const BLOCK: u32 = 8;

impl Painter {
    /// A background frame for the view.
    pub fn new(view: &View<'_>, fill: FillRule, mode: PaintMode) -> Result<Self> {
        let vp = view.viewport();
        let frame = Frame::new(vp)?;
        let (bx, by) = (vp.width.div_ceil(BLOCK), vp.height.div_ceil(BLOCK));
        let mut block_uncovered = Vec::with_capacity((bx * by) as usize);
        for j in 0..by {
            let h = BLOCK.min(vp.height - j * BLOCK);
            for i in 0..bx {
                let w = BLOCK.min(vp.width - i * BLOCK);
                block_uncovered.push((w * h) as u16);
            }
        }
        let keys = if mode == PaintMode::WriteOnce {
            Vec::new()
        } else {
            vec![0.0; vp.pixel_count()]
        };
        Ok(Painter {
            keys,
            frame,
            transform: *view.transform(),
            fill,
            mode,
            block_uncovered,
            blocks_x: bx as usize,
            uncovered: vp.pixel_count() as u64,
            polygons_occluded: 0,
            polygons_painted: 0,
            pixels_written: 0,
            screen: Vec::new(),
            keyed: Vec::new(),
        })
    }

    /// Switches between overwriting and depth-tested painting (a write-once painter
    /// keeps its mode: it tracks no keys).
    pub fn set_mode(&mut self, mode: PaintMode) {
        if self.mode != PaintMode::WriteOnce && mode != PaintMode::WriteOnce {
            self.mode = mode;
        }
    }

    /// Whether every pixel has been painted (only tracked in write-once mode).
    pub fn is_complete(&self) -> bool {
        self.mode == PaintMode::WriteOnce && self.uncovered == 0
    }

    /// Paints a convex polygon given by its projected vertices, with the depth plane
    /// through them. Returns the number of pixels written.
    pub fn paint_vertices(&mut self, vertices: &[ViewVertex], face: u32) -> u64 {
        self.with_points(vertices, |p, screen, plane| p.paint(screen, plane, face))
    }

    /// Calls `paint` with the screen points of `vertices` and the depth plane through
    /// them (0 pixels when they have none).
    fn with_points(
        &mut self,
        vertices: &[ViewVertex],
        paint: impl FnOnce(&mut Self, &[(f64, f64)], &DepthPlane) -> u64,
    ) -> u64 {
        self.keyed.clear();
        self.keyed.extend(vertices.iter().map(|v| (v.x, v.y, v.zq)));
        let Some(plane) = DepthPlane::from_points(&self.keyed) else {
            return 0;
        };
        self.screen.clear();
        self.screen.extend(vertices.iter().map(|v| (v.x, v.y)));
        let screen = std::mem::take(&mut self.screen);
        let n = paint(self, &screen, &plane);
        self.screen = screen;
        n
    }

    /// Whether every block of block row `by` between block columns `bx0..bx1` is full.
    fn blocks_full(&self, by: u32, bx0: u32, bx1: u32) -> bool {
        let row = by as usize * self.blocks_x;
        self.block_uncovered[row + bx0 as usize..row + bx1 as usize]
            .iter()
            .all(|&n| n == 0)
    }

    /// [`Painter::paint_piece`] with the whole polygon given by its projected vertices
    /// (the depth plane through them gives the keys, as [`Painter::paint_vertices`]).
    pub fn paint_piece_of(
        &mut self,
        whole: &[ViewVertex],
        region: PixelRect,
        cuts: &[ScreenCut],
        face: u32,
    ) -> u64 {
        self.with_points(whole, |p, screen, plane| {
            p.paint_piece(screen, plane, region, cuts, face)
        })
    }

    /// Paints a piece of a convex polygon: the pixels of the whole polygon (screen
    /// points `whole`, depth keys from `plane`) inside `region` and on the side of
    /// every cut. `region` must hold every pixel of the piece (the caller widens the
    /// piece's own box: [`piece_region`]). Returns the number of pixels written.
    pub fn paint_piece(
        &mut self,
        whole: &[(f64, f64)],
        plane: &DepthPlane,
        region: PixelRect,
        cuts: &[ScreenCut],
        face: u32,
    ) -> u64 {
        if self.mode == PaintMode::WriteOnce
            && self.box_covered(
                f64::from(region.x0),
                f64::from(region.y0),
                f64::from(region.x1),
                f64::from(region.y1),
            )
        {
            self.polygons_occluded += 1;
            return 0;
        }
        self.paint_within(whole, plane, face, region, cuts)
    }

    /// Paints a convex polygon given by screen points, with depth keys from `plane`.
    /// Returns the number of pixels written.
    pub fn paint(&mut self, screen: &[(f64, f64)], plane: &DepthPlane, face: u32) -> u64 {
        if self.mode == PaintMode::WriteOnce && self.occluded(screen) {
            self.polygons_occluded += 1;
            return 0;
        }
        let all = PixelRect {
            x0: 0,
            y0: 0,
            x1: u32::MAX,
            y1: u32::MAX,
        };
        self.paint_within(screen, plane, face, all, &[])
    }

    /// [`Painter::paint`] restricted to the pixels of `region` on the side of every
    /// cut. A pixel's key is the whole polygon's plane at its centre, so it is the
    /// same whichever piece paints it.
    fn paint_within(
        &mut self,
        screen: &[(f64, f64)],
        plane: &DepthPlane,
        face: u32,
        region: PixelRect,
        cuts: &[ScreenCut],
    ) -> u64 {
        let (w, h) = (self.frame.width, self.frame.height);
        let once = self.mode == PaintMode::WriteOnce;
        let Some(coverage) = PolygonCoverage::new(screen, self.fill, w, h) else {
            return 0;
        };
        let width = w as usize;
        let mut written = 0u64;
        let mut any = false;
        let r = coverage.rect();
        let (bx0, bx1) = (r.x0 / BLOCK, (r.x1 - 1) / BLOCK + 1);
        for y in r.y0.max(region.y0)..r.y1.min(region.y1) {
            if once && self.blocks_full(y / BLOCK, bx0, bx1) {
                continue;
            }
            let Some((x0, x1)) = coverage.row_span(y) else {
                continue;
            };
            // The pixels of the span within the region; of those, the cuts keep some.
            let (x0, x1) = (x0.max(region.x0), x1.min(region.x1));
            let keep = |x: u32| cuts.iter().all(|c| c.keeps(x, y));
            let row = y as usize * width;
            let sy = f64::from(y) + 0.5;
            // The key of the plane at the pixel's centre (not stepped from the span's
            // start), the same whichever piece paints the pixel.
            let key = |x: u32| plane.at(f64::from(x) + 0.5, sy) as f32;
            let mut row_written = 0u32;
            if once {
                let block_row = (y / BLOCK) as usize * self.blocks_x;
                for x in x0..x1 {
                    let k = row + x as usize;
                    let kept = keep(x);
                    any |= kept;
                    if kept && self.frame.ids[k] == BACKGROUND {
                        self.frame.ids[k] = face;
                        self.frame.depth[k] = self.transform.depth_of_key(key(x));
                        self.block_uncovered[block_row + (x / BLOCK) as usize] -= 1;
                        row_written += 1;
                    }
                }
                self.uncovered -= u64::from(row_written);
            } else if self.mode == PaintMode::DepthTest {
                for x in x0..x1 {
                    let k = row + x as usize;
                    let zf = key(x);
                    let old = self.keys[k];
                    let kept = keep(x);
                    any |= kept;
                    if kept && (zf > old || (zf == old && face < self.frame.ids[k])) {
                        self.keys[k] = zf;
                        self.frame.ids[k] = face;
                        self.frame.depth[k] = self.transform.depth_of_key(zf);
                        row_written += 1;
                    }
                }
            } else {
                for x in x0..x1 {
                    let kept = keep(x);
                    any |= kept;
                    if kept {
                        let k = row + x as usize;
                        let zf = key(x);
                        self.keys[k] = zf;
                        self.frame.ids[k] = face;
                        self.frame.depth[k] = self.transform.depth_of_key(zf);
                        row_written += 1;
                    }
                }
            }
            written += u64::from(row_written);
        }
        self.polygons_painted += u64::from(any);
        self.pixels_written += written;
        written
    }

    /// Whether every block under the polygon's bounding box is already full (a
    /// conservative test: the box is widened to whole pixels).
    fn occluded(&self, screen: &[(f64, f64)]) -> bool {
        let (minx, miny, maxx, maxy) = screen_box(screen.iter().copied());
        self.box_covered(minx, miny, maxx, maxy)
    }

    /// Whether everything a screen box `[minx, maxx] x [miny, maxy]` could cover is
    /// already painted (write-once mode; whole blocks are checked, so the answer is
    /// conservative). Non-finite boxes are never covered.
    pub fn box_covered(&self, minx: f64, miny: f64, maxx: f64, maxy: f64) -> bool {
        if self.mode != PaintMode::WriteOnce
            || !(minx.is_finite() && miny.is_finite() && maxx.is_finite() && maxy.is_finite())
        {
            return false;
        }
        let (w, h) = (f64::from(self.frame.width), f64::from(self.frame.height));
        let clamp = |v: f64, hi: f64| v.clamp(0.0, hi - 1.0) as u32;
        let (x0, x1) = (clamp(minx.floor(), w), clamp(maxx.ceil(), w));
        let (y0, y1) = (clamp(miny.floor(), h), clamp(maxy.ceil(), h));
        let (bx0, bx1) = (x0 / BLOCK, x1 / BLOCK + 1);
        (y0 / BLOCK..=y1 / BLOCK).all(|by| self.blocks_full(by, bx0, bx1))
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
    use crate::view::{PrepareOptions, PreparedView, prepare};
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
    fn write_once_skips_full_blocks_only() {
        // A 20x12 image: blocks of 8 make a 3x2 grid with partial blocks at the edges.
        let scene = Scene::new();
        let view = empty_view(&scene, 20, 12);
        let mut once = Painter::new(&view, FillRule::TopLeft, PaintMode::WriteOnce).unwrap();
        let left = [(0.0, 0.0), (8.0, 0.0), (8.0, 12.0), (0.0, 12.0)];
        assert_eq!(once.paint(&left, &flat(0.5), 1), 96);
        // Inside the full left blocks: skipped.
        let inner = [(1.0, 1.0), (7.0, 1.0), (7.0, 11.0)];
        assert_eq!(once.paint(&inner, &flat(0.9), 2), 0);
        assert_eq!(once.polygons_occluded, 1);
        // Reaching one pixel into the next block: painted there only.
        let reach = [(1.0, 1.0), (9.0, 1.0), (9.0, 2.0), (1.0, 2.0)];
        assert_eq!(once.paint(&reach, &flat(0.9), 3), 1);
        let f = once.finish();
        assert_eq!((f.id(8, 1), f.id(7, 1), f.id(9, 1)), (3, 1, BACKGROUND));
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
        // Everything under a full image is occluded without computing its coverage.
        assert_eq!(once.paint(&b, &flat(0.9), 4), 0);
        assert_eq!(once.polygons_occluded, 1);
        assert_eq!(once.polygons_painted, 3);
        let f = once.finish();
        assert_eq!((f.id(3, 3), f.id(7, 7), f.id(7, 0)), (1, 2, 3));
        // The orthographic key 0.5 maps to the middle of [near, far].
        assert!((f.depth[0] - 5.05).abs() < 1e-5);
    }
}
