//! Block rasterization: a convex polygon drawn into a depth buffer row by row (narrow
//! polygons) or in blocks of 16x8 pixels, eight pixels per lane vector, generic over
//! [`Lanes`].
//!
//! - Input: a polygon set up once ([`BlockSetup`]: its edges in the form below, its
//!   sample rectangle, its depth-key plane), a region of the image (a tile, a band of
//!   rows, the whole image) and rows of the buffer described in [`super::lanes`].
//! - Output: the buffer with the polygon's covered pixels depth-tested; counts of the
//!   pixels tested and taken.
//! - Coverage: exactly the shared rule of
//!   [`PolygonCoverage::covers`](super::PolygonCoverage::covers). Edge `e` with canonical origin `(ox, oy)`,
//!   direction `(dx, dy)` and orientation `sign` is stored as `sdx = sign dx`,
//!   `sdy = sign dy`; per sample the rasterizer computes
//!   `t = sdy (px - ox) - sdx (py - oy)`, which is `-sign (dx (py - oy) - dy (px - ox))`
//!   bit for bit (negation is exact and rounding to nearest is symmetric), and the
//!   sample is inside when `t < bound`, `bound` being `0` for an edge that excludes its
//!   samples and the smallest positive double for one that includes them.
//! - Narrow polygons: with [`Align::Polygon`], a polygon at most 16 pixels wide
//!   (most triangles of a detailed model) is walked row by row from its first column,
//!   every row tested against the edges, without a branch on whether the row has a
//!   covered sample: such rows are frequent in thin triangles and unpredictable, and
//!   the masked depth test of no pixel touches no memory. The rows' edge and depth
//!   parts are computed eight rows at a time in lanes and read back as broadcasts from
//!   memory: per row, a scalar part broadcast into a vector would take the shuffle
//!   port that the compares into masks also need. Measured on the small triangles of
//!   the Sponza atrium (169k of them, at most 64 pixels on a side): 17.1 ms drawn block
//!   by block, 15.1 ms row by row with scalar row parts, 12.9 ms with row parts in
//!   lanes. A polygon at most four pixels wide (slivers: 1.4 covered pixels a row on
//!   the tall thin triangles of Sponza) takes two rows per lane vector, lanes 0-3 one
//!   row and 4-7 the next, each lane computing its pixel's expressions as the
//!   one-row walk does: half the row steps, 12.6 -> 12.3 ms.
//! - Blocks: a wider polygon is walked block by block; each block is first
//!   classified by its corner samples. Every step of the edge expression is monotonic
//!   in `px` along a row and in `py` along a column, so the sample of a block that is
//!   most inside an edge (resp. most outside) is a corner chosen by the signs of `sdy`
//!   and `sdx`: if that corner is outside some edge no sample of the block is covered
//!   (the block is skipped), and if the other corner is inside every edge all are (the
//!   block is drawn without edge tests). The classification is exact, not
//!   conservative. Both walks draw rows with the same function (`draw_block`), so a
//!   pixel's coverage and key do not depend on the walk.
//! - Depth: the seeds' plane of the depth key, evaluated per pixel:
//!   `z(i, j) = (z0 + dzdy (j - y0)) + dzdx (i - x0)` from the key `z0` at the first
//!   sample `(x0 + 0.5, y0 + 0.5)` of the polygon's rectangle, in `f64`. A pixel's key
//!   depends on the polygon and the pixel only, not on how the image is cut into
//!   blocks, tiles or bands. It differs from the reference's serial stepping
//!   `z += dz/dx` by a few units in the last place of the `f64`: the `f32` keys differ
//!   at most where the reference's keys are within one `f32` unit of each other.
//! - Complexity: per polygon O(n) setup for n edges; per row O(n) in the row walk;
//!   in the block walk, per block O(n) to classify it, then per row O(n) for a partly
//!   covered block and O(1) for a covered one. The
//!   part of the polygon in the region is classified first, as one block: a covered
//!   tile is drawn without edge tests, an uncovered one costs nothing more.
//! - Occlusion culling (optional, [`BlockTarget::with_farthest`]): per block of the
//!   grid the farthest key it holds; a block whose farthest key is larger than the
//!   polygon's largest key over the block ([`nearest_key`], a rigorous bound) is
//!   skipped, which changes nothing in the result. The polygon's whole part in the
//!   region is tested first, against the smallest farthest key of the blocks it
//!   overlaps: a polygon hidden in all of them is skipped with one test.
//! - Limitations: at most [`MAX_EDGES`] edges ([`BlockSetup::new`] refuses others).
//!   The caller picks the edge count `E` of a setup: 3 for triangles, 4 for quads, 8
//!   for the rest (unused edges hold every sample inside).
//! - Sources: seed 000 "Αλγόριθμος Z-buffer" (the depth test, the plane); Pineda, *A
//!   parallel algorithm for polygon rasterization* (SIGGRAPH 1988, edge functions);
//!   Greene, *Hierarchical polygon tiling with coverage masks* (SIGGRAPH 1996, block
//!   classification by corners).

use super::lanes::{Lanes, key_of, lanes_below, lanes_below16};
use super::{DepthPlane, EdgeFunction, FillRule, PixelRect};

/// The most edges a [`BlockSetup`] holds (one lane each when blocks are classified).
pub const MAX_EDGES: usize = 8;

/// Rows of a block, and columns of a narrow one (a wide block has twice as many).
pub const BLOCK: u32 = 8;

/// Lane offsets `0, 1, ..., 7`.
const LANE: [f64; 8] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];

/// A convex polygon of at most `E` edges set up for block rasterization (see the
/// module doc). Unused edges (when the polygon has fewer) hold every sample inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockSetup<const E: usize> {
    /// Canonical edge origins.
    pub ox: [f64; E],
    /// Canonical edge origins.
    pub oy: [f64; E],
    /// `sign * dx` per edge.
    pub sdx: [f64; E],
    /// `sign * dy` per edge.
    pub sdy: [f64; E],
    /// `0` or the smallest positive double: a sample is inside the edge when its `t`
    /// is below this; `+inf` for unused edges.
    pub bound: [f64; E],
    /// The pixels whose samples lie in the polygon's box, clipped to the image.
    pub rect: PixelRect,
    /// Depth key at the sample of the rectangle's first pixel.
    pub z0: f64,
    /// Key change per pixel to the right.
    pub dzdx: f64,
    /// Key change per pixel down.
    pub dzdy: f64,
}

/// `bound` of an edge that includes (or not) the samples on it.
#[inline(always)]
fn bound_of(include_zero: bool) -> f64 {
    if include_zero { f64::from_bits(1) } else { 0.0 }
}

impl<const E: usize> BlockSetup<E> {
    /// The setup of a polygon with these edges (as [`EdgeFunction::new`] makes them),
    /// sample rectangle and plane; `None` with more than `E` (or [`MAX_EDGES`]) edges
    /// or an empty rectangle.
    #[inline(always)]
    #[must_use]
    pub fn new(edges: &[EdgeFunction], rect: PixelRect, plane: &DepthPlane) -> Option<Self> {
        if edges.len() > E || E > MAX_EDGES || rect.is_empty() {
            return None;
        }
        let mut s = BlockSetup {
            ox: [0.0; E],
            oy: [0.0; E],
            sdx: [0.0; E],
            sdy: [0.0; E],
            bound: [f64::INFINITY; E],
            rect,
            z0: plane.at(f64::from(rect.x0) + 0.5, f64::from(rect.y0) + 0.5),
            dzdx: plane.dzdx,
            dzdy: plane.dzdy,
        };
        for (k, e) in edges.iter().enumerate() {
            s.ox[k] = e.ox;
            s.oy[k] = e.oy;
            s.sdx[k] = e.sign * e.dx;
            s.sdy[k] = e.sign * e.dy;
            s.bound[k] = bound_of(e.include_zero);
        }
        Some(s)
    }

    /// Whether sample `(px, py)` is inside every edge (the per-pixel rule, for tests).
    #[must_use]
    pub fn covers_sample(&self, px: f64, py: f64) -> bool {
        (0..E).all(|k| {
            let t = self.sdy[k] * (px - self.ox[k]) - self.sdx[k] * (py - self.oy[k]);
            t < self.bound[k]
        })
    }

    /// The depth key of pixel `(i, j)` (the module doc's expression).
    #[inline(always)]
    #[must_use]
    pub fn key(&self, i: u32, j: u32) -> f64 {
        let zr = self.z0 + self.dzdy * (f64::from(j) - f64::from(self.rect.y0));
        zr + self.dzdx * (f64::from(i) - f64::from(self.rect.x0))
    }
}

/// The setup of the triangle with vertices `(x, y, zq)` for a `width x height` image:
/// the edges and rectangle of [`PolygonCoverage::new`](super::PolygonCoverage::new) and
/// the plane of [`DepthPlane::from_points`] (what
/// [`TriangleSetup`](super::TriangleSetup) computes, in the block rasterizer's form).
/// `None` exactly when the triangle covers no sample by the coverage rule's setup: no
/// sample in its box, or a zero or non-finite area.
#[inline(always)]
#[must_use]
pub fn triangle(
    p: [(f64, f64, f64); 3],
    fill: FillRule,
    width: u32,
    height: u32,
) -> Option<BlockSetup<3>> {
    let t = super::TriangleSetup::new(p, fill, width, height)?;
    // One division: the plane need not be DepthPlane::from_points' to the last bit.
    let [a, b, c] = p;
    let (ax, ay, az) = (b.0 - a.0, b.1 - a.1, b.2 - a.2);
    let (bx, by, bz) = (c.0 - a.0, c.1 - a.1, c.2 - a.2);
    let inv = 1.0 / (0.0 + (ax * by - ay * bx));
    let plane = DepthPlane {
        dzdx: (az * by - bz * ay) * inv,
        dzdy: (ax * bz - bx * az) * inv,
        ..t.plane
    };
    BlockSetup::new(&t.edges, t.rect, &plane)
}

/// Eight triangles set up at once, lane by lane (see [`triangles8`]): each array holds
/// one value per triangle.
#[derive(Clone, Copy, Debug)]
pub struct TriangleBatch {
    /// Canonical edge origins, per edge.
    pub ox: [[f64; 8]; 3],
    /// Canonical edge origins, per edge.
    pub oy: [[f64; 8]; 3],
    /// `sign * dx`, per edge.
    pub sdx: [[f64; 8]; 3],
    /// `sign * dy`, per edge.
    pub sdy: [[f64; 8]; 3],
    /// The bound of the coverage test, per edge.
    pub bound: [[f64; 8]; 3],
    /// Sample rectangles: first columns.
    pub x0: [u32; 8],
    /// Sample rectangles: first rows.
    pub y0: [u32; 8],
    /// Sample rectangles: columns past the last.
    pub x1: [u32; 8],
    /// Sample rectangles: rows past the last.
    pub y1: [u32; 8],
    /// Keys at the first sample of the rectangles.
    pub z0: [f64; 8],
    /// Key changes per pixel to the right.
    pub dzdx: [f64; 8],
    /// Key changes per pixel down.
    pub dzdy: [f64; 8],
    /// The lanes whose triangle covers some sample (where [`triangle`] gives a setup).
    pub valid: u8,
}

impl TriangleBatch {
    /// The setup of lane `l` (`l < 8`): what [`triangle`] gives for that triangle
    /// when the lane is valid.
    #[inline(always)]
    #[must_use]
    pub fn get(&self, l: usize) -> BlockSetup<3> {
        let l = l & 7;
        BlockSetup {
            ox: [self.ox[0][l], self.ox[1][l], self.ox[2][l]],
            oy: [self.oy[0][l], self.oy[1][l], self.oy[2][l]],
            sdx: [self.sdx[0][l], self.sdx[1][l], self.sdx[2][l]],
            sdy: [self.sdy[0][l], self.sdy[1][l], self.sdy[2][l]],
            bound: [self.bound[0][l], self.bound[1][l], self.bound[2][l]],
            rect: PixelRect {
                x0: self.x0[l],
                y0: self.y0[l],
                x1: self.x1[l],
                y1: self.y1[l],
            },
            z0: self.z0[l],
            dzdx: self.dzdx[l],
            dzdy: self.dzdy[l],
        }
    }
}

/// The vertices of eight triangles, lane by lane: `x[v][l]` is the x of vertex `v` of
/// triangle `l` (likewise `y` and the depth key `zq`).
#[derive(Clone, Copy, Debug, Default)]
pub struct TrianglePoints {
    /// Screen x per vertex, per triangle.
    pub x: [[f64; 8]; 3],
    /// Screen y per vertex, per triangle.
    pub y: [[f64; 8]; 3],
    /// Depth key per vertex, per triangle.
    pub zq: [[f64; 8]; 3],
}

/// Applies `f` to each lane: written as loops over fixed-size arrays so that the
/// compiler turns each into vector instructions of the caller's instruction set.
#[inline(always)]
fn lanes<T: Copy + Default>(f: impl Fn(usize) -> T) -> [T; 8] {
    let mut o = [T::default(); 8];
    for (l, o) in o.iter_mut().enumerate() {
        *o = f(l);
    }
    o
}

/// `v as u32` for a whole number `v` in `0..2^32`: adding `2^52` puts it in the low
/// bits of the mantissa, exactly. The compiler turns this into vector instructions,
/// which it does not do for the conversion to an unsigned integer (four of them per
/// lane of [`triangles8`] were scalar).
#[inline(always)]
fn whole_to_u32(v: f64) -> u32 {
    (v + 4_503_599_627_370_496.0).to_bits() as u32
}

/// [`triangle`] for eight triangles at once: lane `l` of the result holds what
/// `triangle` gives for triangle `l` (bit for bit: each lane evaluates the same
/// expressions in the same order), and is valid exactly when `triangle` gives a setup.
/// Straight-line code over lanes, without a branch per triangle: the compiler
/// vectorizes it, about three times cheaper per triangle than [`triangle`].
#[inline(always)]
#[must_use]
pub fn triangles8(p: &TrianglePoints, fill: FillRule, width: u32, height: u32) -> TriangleBatch {
    let (x, y, zq) = (&p.x, &p.y, &p.zq);
    // triangle_rect_and_area
    let minx = lanes(|l| x[0][l].min(x[1][l]).min(x[2][l]));
    let maxx = lanes(|l| x[0][l].max(x[1][l]).max(x[2][l]));
    let miny = lanes(|l| y[0][l].min(y[1][l]).min(y[2][l]));
    let maxy = lanes(|l| y[0][l].max(y[1][l]).max(y[2][l]));
    let (w, h) = (f64::from(width), f64::from(height));
    let x0 = lanes(|l| whole_to_u32((minx[l] - 0.5).ceil().max(0.0).min(w)));
    let y0 = lanes(|l| whole_to_u32((miny[l] - 0.5).ceil().max(0.0).min(h)));
    let x1 = lanes(|l| whole_to_u32(((maxx[l] - 0.5).floor() + 1.0).max(0.0).min(w)));
    let y1 = lanes(|l| whole_to_u32(((maxy[l] - 0.5).floor() + 1.0).max(0.0).min(h)));
    // The fan area from vertex 0, as `coverage::fan_area2` sums it.
    let ax = lanes(|l| x[1][l] - x[0][l]);
    let ay = lanes(|l| y[1][l] - y[0][l]);
    let az = lanes(|l| zq[1][l] - zq[0][l]);
    let bx = lanes(|l| x[2][l] - x[0][l]);
    let by = lanes(|l| y[2][l] - y[0][l]);
    let bz = lanes(|l| zq[2][l] - zq[0][l]);
    let area2 = lanes(|l| 0.0 + (ax[l] * by[l] - ay[l] * bx[l]));
    let ok = lanes(|l| {
        let finite =
            minx[l].is_finite() & miny[l].is_finite() & maxx[l].is_finite() & maxy[l].is_finite();
        finite & (x0[l] < x1[l]) & (y0[l] < y1[l]) & (area2[l] != 0.0) & area2[l].is_finite()
    });
    let valid = ok
        .iter()
        .enumerate()
        .fold(0u8, |m, (l, &v)| m | (u8::from(v) << l));
    // triangle: the edges as `triangle_edge` orients them.
    let area_sign = lanes(|l| area2[l].signum());
    let inclusive = fill == FillRule::Inclusive;
    let mut batch = TriangleBatch {
        ox: [[0.0; 8]; 3],
        oy: [[0.0; 8]; 3],
        sdx: [[0.0; 8]; 3],
        sdy: [[0.0; 8]; 3],
        bound: [[0.0; 8]; 3],
        x0,
        y0,
        x1,
        y1,
        z0: [0.0; 8],
        dzdx: [0.0; 8],
        dzdy: [0.0; 8],
        valid,
    };
    for (k, (i, j)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
        // `|` and `&`, not `||` and `&&`: no branch, so the lanes stay vectors.
        let less = lanes(|l| (y[i][l] < y[j][l]) | ((y[i][l] == y[j][l]) & (x[i][l] < x[j][l])));
        let (ox, oy) = (
            lanes(|l| if less[l] { x[i][l] } else { x[j][l] }),
            lanes(|l| if less[l] { y[i][l] } else { y[j][l] }),
        );
        let (ex, ey) = (
            lanes(|l| if less[l] { x[j][l] } else { x[i][l] }),
            lanes(|l| if less[l] { y[j][l] } else { y[i][l] }),
        );
        let sign = lanes(|l| if less[l] { area_sign[l] } else { -area_sign[l] });
        let sdx = lanes(|l| (ex[l] - ox[l]) * sign[l]);
        let sdy = lanes(|l| (ey[l] - oy[l]) * sign[l]);
        batch.bound[k] = lanes(|l| {
            let top_left = ((sdy[l] == 0.0) & (sdx[l] > 0.0)) | (sdy[l] < 0.0);
            bound_of(inclusive | top_left)
        });
        (batch.ox[k], batch.oy[k], batch.sdx[k], batch.sdy[k]) = (ox, oy, sdx, sdy);
    }
    // The plane, with one division, and its key at the rectangle's first sample
    // (`DepthPlane::at`).
    let inv = lanes(|l| 1.0 / area2[l]);
    batch.dzdx = lanes(|l| (az[l] * by[l] - bz[l] * ay[l]) * inv[l]);
    batch.dzdy = lanes(|l| (ax[l] * bz[l] - bx[l] * az[l]) * inv[l]);
    batch.z0 = lanes(|l| {
        let (px, py) = (f64::from(x0[l]) + 0.5, f64::from(y0[l]) + 0.5);
        zq[0][l] + batch.dzdx[l] * (px - x[0][l]) + batch.dzdy[l] * (py - y[0][l])
    });
    batch
}

/// Pixels tested (covered) and taken by a drawing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Covered pixels, each depth-tested.
    pub tested: u64,
    /// Pixels that passed the test and were written.
    pub written: u64,
}

/// A rectangle of an image held row after row: depth keys and encoded ids (see
/// [`super::lanes`]) of the columns `x0..x0 + stride` and rows `y0..`.
#[derive(Debug)]
pub struct BlockTarget<'a> {
    keys: &'a mut [f32],
    ids: &'a mut [u32],
    stride: usize,
    x0: u32,
    y0: u32,
    y1: u32,
    /// Per block of the grid (see [`BlockTarget::with_farthest`]), a key no larger
    /// than any its pixels hold; empty when blocks are not culled.
    farthest: &'a mut [f32],
}

impl<'a> BlockTarget<'a> {
    /// The target of columns `x0..x0 + stride` and rows `y0..` of an image; the slices
    /// hold whole rows (`None` when they do not, or differ in length).
    #[must_use]
    pub fn new(
        keys: &'a mut [f32],
        ids: &'a mut [u32],
        stride: usize,
        x0: u32,
        y0: u32,
    ) -> Option<Self> {
        if stride == 0 || keys.len() != ids.len() || !keys.len().is_multiple_of(stride) {
            return None;
        }
        let rows = u32::try_from(keys.len() / stride).ok()?;
        Some(BlockTarget {
            keys,
            ids,
            stride,
            x0,
            y0,
            y1: y0.checked_add(rows)?,
            farthest: &mut [],
        })
    }

    /// The target with occlusion culling: `farthest` holds, per block of
    /// `2 BLOCK x BLOCK` pixels of the grid from the target's first pixel (row after
    /// row of `stride / (2 BLOCK)` blocks), a key no larger than any key its pixels
    /// hold. [`draw`] with [`Align::Grid`] skips the blocks whose key is larger than
    /// every key the polygon has there: the polygon wins none of their pixels, not even
    /// a tie, so the result is the same. The keys only grow while drawing, so a
    /// value computed before stays valid (only less effective); [`draw`] recomputes
    /// the value of each whole block it writes to.
    #[must_use]
    pub fn with_farthest(mut self, farthest: &'a mut [f32]) -> Self {
        self.farthest = farthest;
        self
    }

    /// Whether the polygon `s` wins no pixel of `c` (pixels of the target), by the
    /// keys of all the grid blocks `c` overlaps: their smallest farthest key is
    /// larger than any key the polygon has in `c`. Used for a polygon's whole part in
    /// a tile before its blocks are walked, then for each block.
    #[inline(always)]
    fn hides<const E: usize>(&self, s: &BlockSetup<E>, c: PixelRect) -> bool {
        if self.farthest.is_empty() || c.is_empty() || c.x0 < self.x0 || c.y0 < self.y0 {
            return false;
        }
        let bw = 2 * BLOCK;
        let per_row = self.stride / bw as usize;
        let (bx0, bx1) = (
            ((c.x0 - self.x0) / bw) as usize,
            ((c.x1 - 1 - self.x0) / bw) as usize + 1,
        );
        let (by0, by1) = (
            ((c.y0 - self.y0) / BLOCK) as usize,
            ((c.y1 - 1 - self.y0) / BLOCK) as usize + 1,
        );
        if bx1 > per_row {
            return false;
        }
        let mut far = f32::INFINITY;
        for by in by0..by1 {
            let Some(row) = self.farthest.get(by * per_row + bx0..by * per_row + bx1) else {
                return false;
            };
            for &f in row {
                // An empty pixel (key 0) or a NaN hides nothing.
                if !(f > 0.0) {
                    return false;
                }
                far = far.min(f);
            }
        }
        far > nearest_key(s, c)
    }

    /// Recomputes the farthest key of the grid block at `(bx, by)` if the target holds
    /// all of its pixels.
    #[inline(always)]
    fn refresh(&mut self, bx: u32, by: u32) {
        let bw = 2 * BLOCK as usize;
        if self.farthest.is_empty()
            || bx < self.x0
            || by < self.y0
            || (bx - self.x0) as usize + bw > self.stride
            || by + BLOCK > self.y1
        {
            return;
        }
        let per_row = self.stride / bw;
        let at = ((by - self.y0) / BLOCK) as usize * per_row + (bx - self.x0) as usize / bw;
        let first = self.at(bx, by);
        let mut m = [f32::INFINITY; 16];
        for r in 0..BLOCK as usize {
            let row = &self.keys[first + r * self.stride..][..bw];
            for (m, &v) in m.iter_mut().zip(row) {
                *m = if v < *m { v } else { *m };
            }
        }
        if let Some(far) = self.farthest.get_mut(at) {
            *far = m.into_iter().fold(f32::INFINITY, f32::min);
        }
    }

    /// The pixels it holds.
    #[must_use]
    pub fn rect(&self) -> PixelRect {
        PixelRect {
            x0: self.x0,
            y0: self.y0,
            x1: self.x0.saturating_add(self.stride as u32),
            y1: self.y1,
        }
    }

    /// The index of pixel `(x, y)` (inside [`BlockTarget::rect`]) in the slices.
    #[inline(always)]
    fn at(&self, x: u32, y: u32) -> usize {
        (y - self.y0) as usize * self.stride + (x - self.x0) as usize
    }

    /// The keys and ids of the pixels `x..x + n` of row `y` (inside the rectangle).
    #[must_use]
    pub fn row(&self, x: u32, y: u32, n: usize) -> (&[f32], &[u32]) {
        let at = self.at(x, y);
        (&self.keys[at..at + n], &self.ids[at..at + n])
    }

    /// The keys and ids of the pixels `x..x + n` of row `y` (inside the rectangle).
    pub(crate) fn row_mut(&mut self, x: u32, y: u32, n: usize) -> (&mut [f32], &mut [u32]) {
        let at = self.at(x, y);
        (&mut self.keys[at..at + n], &mut self.ids[at..at + n])
    }
}

/// An upper bound of the keys the rasterizer computes for polygon `s` in the pixels
/// of `c`, as stored (`f32`): the key expression is affine, so its largest value is at
/// a corner; a margin of `1e-12` of the terms' magnitudes covers the roundings of any
/// order of evaluation (a few units of `2^-53` each), and [`key_of`] is monotonic.
/// NaN for a non-finite plane.
#[inline(always)]
#[must_use]
pub fn nearest_key<const E: usize>(s: &BlockSetup<E>, c: PixelRect) -> f32 {
    let i = if s.dzdx > 0.0 { c.x1 - 1 } else { c.x0 };
    let j = if s.dzdy > 0.0 { c.y1 - 1 } else { c.y0 };
    let top = s.key(i, j);
    let reach = s.z0.abs()
        + s.dzdy.abs() * (f64::from(j) - f64::from(s.rect.y0)).abs()
        + s.dzdx.abs() * (f64::from(i) - f64::from(s.rect.x0)).abs();
    key_of(top + reach * 1e-12)
}

/// Where blocks start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    /// At the polygon's rectangle (fewest blocks); a polygon at most 16 pixels wide
    /// is walked row by row instead (see the module doc).
    Polygon,
    /// On the image's grid of 16x8 blocks (no block crosses a tile's border, and a
    /// row of a block is one cache line of keys when the rows are aligned).
    Grid,
}

/// The polygon's edges in lanes (one edge per lane), for classifying blocks.
struct EdgeLanes<F> {
    ox: F,
    oy: F,
    sdx: F,
    sdy: F,
    bound: F,
    /// Lanes where `sdy > 0`: `t` grows to the right, the leftmost sample is most inside.
    rising_x: u8,
    /// Lanes where `sdx > 0`: `t` shrinks downwards, the lowest sample is most inside.
    falling_y: u8,
    used: u8,
}

impl<F: Copy> EdgeLanes<F> {
    #[inline(always)]
    fn new<L: Lanes<F = F>, const E: usize>(l: L, s: &BlockSetup<E>) -> Self {
        let mut rising_x = 0u8;
        let mut falling_y = 0u8;
        for k in 0..E {
            rising_x |= u8::from(s.sdy[k] > 0.0) << k;
            falling_y |= u8::from(s.sdx[k] > 0.0) << k;
        }
        // Built from values, not stored and reloaded: a vector load of scalars just
        // stored stalls until the stores reach the cache.
        let pad = |a: &[f64; E], v: f64| {
            let mut o = [v; 8];
            let mut k = 0;
            while k < E {
                o[k] = a[k];
                k += 1;
            }
            o
        };
        EdgeLanes {
            ox: l.set(pad(&s.ox, 0.0)),
            oy: l.set(pad(&s.oy, 0.0)),
            sdx: l.set(pad(&s.sdx, 0.0)),
            sdy: l.set(pad(&s.sdy, 0.0)),
            bound: l.set(pad(&s.bound, f64::INFINITY)),
            rising_x,
            falling_y,
            used: lanes_below(E),
        }
    }
}

/// How samples lie with respect to a polygon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Outside,
    Inside,
    Partial,
}

/// Classifies the samples of the pixels `r` by their corners (see the module doc).
#[inline(always)]
fn classify<L: Lanes>(l: L, e: &EdgeLanes<L::F>, r: PixelRect) -> Class {
    let (left, right) = (
        l.splat(f64::from(r.x0) + 0.5),
        l.splat(f64::from(r.x1) - 0.5),
    );
    let (top, bottom) = (
        l.splat(f64::from(r.y0) + 0.5),
        l.splat(f64::from(r.y1) - 0.5),
    );
    let (px, py) = (
        l.select(e.rising_x, left, right),
        l.select(e.falling_y, bottom, top),
    );
    let best = l.sub(l.mul(e.sdy, l.sub(px, e.ox)), l.mul(e.sdx, l.sub(py, e.oy)));
    if l.less(e.used, best, e.bound) != e.used {
        return Class::Outside;
    }
    let (px, py) = (
        l.select(e.rising_x, right, left),
        l.select(e.falling_y, top, bottom),
    );
    let worst = l.sub(l.mul(e.sdy, l.sub(px, e.ox)), l.mul(e.sdx, l.sub(py, e.oy)));
    if l.less(e.used, worst, e.bound) == e.used {
        Class::Inside
    } else {
        Class::Partial
    }
}

/// The mask of lanes `a..b` of a block row (`a <= b <= 16`).
#[inline(always)]
fn lane_range(a: u32, b: u32) -> u16 {
    lanes_below16(b as usize) & !lanes_below16(a as usize)
}

/// Draws the polygon `s` into the pixels of `region` (image coordinates) that the
/// target holds, with encoded id `face`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn draw<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    region: PixelRect,
    align: Align,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let t = target.rect();
    let r = PixelRect {
        x0: s.rect.x0.max(region.x0).max(t.x0),
        y0: s.rect.y0.max(region.y0).max(t.y0),
        x1: s.rect.x1.min(region.x1).min(t.x1),
        y1: s.rect.y1.min(region.y1).min(t.y1),
    };
    if r.is_empty() {
        return;
    }
    // A narrow polygon: row by row from its first column, every row tested against
    // the edges, without classifying blocks (its blocks are almost all partly covered).
    let (rows, lanes) = (r.y0..r.y1, lane_range(0, r.x1 - r.x0));
    if align == Align::Polygon && r.x1 - r.x0 <= PAIR_WIDTH {
        draw_pairs::<L, E>(l, s, r.x0, rows, lanes as u8, target, face, counts);
    } else if align == Align::Polygon && r.x1 - r.x0 <= BLOCK {
        draw_block::<L, E, false, false>(l, s, r.x0, rows, lanes, target, face, counts);
    } else if align == Align::Polygon && r.x1 - r.x0 <= 2 * BLOCK {
        draw_block::<L, E, true, false>(l, s, r.x0, rows, lanes, target, face, counts);
    } else {
        let (bx0, by0) = match align {
            Align::Polygon => (r.x0, r.y0),
            Align::Grid => (r.x0 & !(2 * BLOCK - 1), r.y0 & !(BLOCK - 1)),
        };
        draw_blocks::<L, E>(l, s, r, bx0, by0, target, face, counts);
    }
}

/// [`draw`] with blocks of 16 columns and 8 rows from `(bx0, by0)`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn draw_blocks<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    r: PixelRect,
    bx0: u32,
    by0: u32,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let bw = 2 * BLOCK;
    if r.x1 - bx0 <= bw && r.y1 - by0 <= BLOCK {
        let lanes = lane_range(r.x0 - bx0, r.x1 - bx0);
        draw_block::<L, E, true, false>(l, s, bx0, r.y0..r.y1, lanes, target, face, counts);
        return;
    }
    if target.hides(s, r) {
        return;
    }
    let edges = EdgeLanes::new(l, s);
    // The whole part first: a tile inside a big polygon needs no edge test at all.
    let all_inside = match classify(l, &edges, r) {
        Class::Outside => return,
        Class::Inside => true,
        Class::Partial => false,
    };
    let mut by = by0;
    while by < r.y1 {
        let (cy0, cy1) = (by.max(r.y0), (by + BLOCK).min(r.y1));
        let mut bx = bx0;
        while bx < r.x1 {
            let (cx0, cx1) = (bx.max(r.x0), (bx + bw).min(r.x1));
            let c = PixelRect {
                x0: cx0,
                y0: cy0,
                x1: cx1,
                y1: cy1,
            };
            if target.hides(s, c) {
                bx += bw;
                continue;
            }
            let full = all_inside
                || match classify(l, &edges, c) {
                    Class::Outside => {
                        bx += bw;
                        continue;
                    }
                    Class::Inside => true,
                    Class::Partial => false,
                };
            let lanes = lane_range(cx0 - bx, cx1 - bx);
            let written = counts.written;
            if full {
                draw_block::<L, E, true, true>(l, s, bx, cy0..cy1, lanes, target, face, counts);
            } else {
                draw_block::<L, E, true, false>(l, s, bx, cy0..cy1, lanes, target, face, counts);
            }
            if counts.written != written {
                target.refresh(bx, by);
            }
            bx += bw;
        }
        by += BLOCK;
    }
}

/// Draws the rows `rows` (any number) of the columns `bx + l` for the lanes `l` of
/// `lanes` (16 of them when `WIDE`, else 8); `FULL` when every such sample is known to
/// be covered. The rows' edge and depth parts are computed eight rows at a time in
/// lanes and read back as broadcasts from memory (see the module doc).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn draw_block<L: Lanes, const E: usize, const WIDE: bool, const FULL: bool>(
    l: L,
    s: &BlockSetup<E>,
    bx: u32,
    rows: std::ops::Range<u32>,
    lanes: u16,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    if lanes == 0 {
        return;
    }
    let Some(mut at) = rows_start(target, bx, &rows, 16 - lanes.leading_zeros() as usize) else {
        return;
    };
    let stride = target.stride;
    let (keys, ids) = (&mut *target.keys, &mut *target.ids);
    let lane = l.load(&LANE);
    // Depth: the column part per lane, the row part per row.
    let dx = f64::from(bx) - f64::from(s.rect.x0);
    let dzdx = l.splat(s.dzdx);
    let zc_lo = l.mul(dzdx, l.add_scalar(lane, dx));
    let zc_hi = if WIDE {
        l.mul(dzdx, l.add_scalar(lane, dx + 8.0))
    } else {
        zc_lo
    };
    // Coverage: per edge the column part `sdy (px - ox)` per lane and the row part
    // `sdx (py - oy)` per row. (Loops, not closures: a closure is not compiled for the
    // caller's instruction set, so the lane operations in it would not be inlined.)
    // Sample positions are small integers plus a half: exact.
    let px = l.add_scalar(lane, f64::from(bx) + 0.5);
    let px_hi = l.add_scalar(lane, f64::from(bx) + 8.5);
    let (mut col_lo, mut col_hi, mut bound) = ([px; E], [px; E], [px; E]);
    if !FULL {
        (col_lo, bound) = edge_columns(l, s, px);
        if WIDE {
            col_hi = edge_columns(l, s, px_hi).0;
        }
    }
    let (lanes_lo, lanes_hi) = (lanes as u8, (lanes >> 8) as u8);
    let mut y = rows.start;
    while y < rows.end {
        let zr = l.to_array(l.add_scalar(
            l.mul(
                l.splat(s.dzdy),
                l.add_scalar(lane, f64::from(y) - f64::from(s.rect.y0)),
            ),
            s.z0,
        ));
        let mut row = [[0.0; 8]; E];
        if !FULL {
            let py = l.add_scalar(lane, f64::from(y) + 0.5);
            for (row, (&sdx, &oy)) in row.iter_mut().zip(s.sdx.iter().zip(&s.oy)) {
                *row = l.to_array(l.mul(l.splat(sdx), l.sub_scalar(py, oy)));
            }
        }
        for (q, &zj) in zr.iter().enumerate().take((rows.end - y) as usize) {
            let cover = if FULL {
                lanes
            } else {
                let mut lo = lanes_lo;
                let mut hi = lanes_hi;
                // Independent compares, their masks combined after (a chain of masked
                // compares would wait for each other).
                for k in 0..E {
                    lo &= l.less(0xff, l.sub_scalar(col_lo[k], row[k][q]), bound[k]);
                    if WIDE {
                        hi &= l.less(0xff, l.sub_scalar(col_hi[k], row[k][q]), bound[k]);
                    }
                }
                u16::from(lo) | if WIDE { u16::from(hi) << 8 } else { 0 }
            };
            // No branch on an empty row (thin polygons have many, unpredictably): the
            // masked test of no pixel accesses nothing.
            counts.tested += u64::from(cover.count_ones());
            // SAFETY: `cover` is within `lanes`, whose pixels in these rows are inside
            // the slices (checked above for the last row).
            let taken =
                unsafe { test_row::<L, WIDE>(l, keys, ids, at, cover, [zc_lo, zc_hi], zj, face) };
            counts.written += u64::from(taken.count_ones());
            at += stride;
        }
        y += BLOCK;
    }
}

/// Where the first of `rows` starts at column `bx` in the target, if every row of
/// `rows` holds its pixels `bx..bx + reach` inside the target's slices: the depth tests
/// of the row walks then access them without checking. Only the last row needs the
/// check. (The callers clip the rows to the target, so it never fails.)
#[inline(always)]
fn rows_start(
    target: &BlockTarget<'_>,
    bx: u32,
    rows: &std::ops::Range<u32>,
    reach: usize,
) -> Option<usize> {
    let last_row = rows.end.checked_sub(rows.start)?.checked_sub(1)? as usize;
    let at = target.at(bx, rows.start);
    let end = at + last_row * target.stride + reach;
    (end <= target.keys.len().min(target.ids.len())).then_some(at)
}

/// Per edge, the column part `sdy (px - ox)` of the edge expression at the lanes'
/// sample columns `px`, and the edge's bound, in lanes. (A loop, not a closure: a
/// closure is not compiled for the caller's instruction set.)
#[inline(always)]
fn edge_columns<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    px: L::F,
) -> ([L::F; E], [L::F; E]) {
    let (mut col, mut bound) = ([px; E], [px; E]);
    for k in 0..E {
        col[k] = l.mul(l.splat(s.sdy[k]), l.sub_scalar(px, s.ox[k]));
        bound[k] = l.splat(s.bound[k]);
    }
    (col, bound)
}

/// Polygons at most this many pixels wide are drawn two rows per lane vector.
const PAIR_WIDTH: u32 = 4;
/// The column of each lane in [`draw_pairs`].
const PAIR_COLUMN: [f64; 8] = [0.0, 1.0, 2.0, 3.0, 0.0, 1.0, 2.0, 3.0];
/// The row (of the two) of each lane in [`draw_pairs`].
const PAIR_ROW: [f64; 8] = [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];

/// Draws the rows `rows` of the columns `bx + c` for the bits `c` of `lanes` (of the
/// four lowest), two rows per lane vector: lanes 0-3 a row, 4-7 the next. Every lane
/// computes the same expressions as [`draw_block`] does for its pixel (the column and
/// row parts of the edges and of the depth, in the same order), so the two give the
/// same coverage and keys; a polygon at most four pixels wide (thin slivers are common
/// in real meshes) then takes half as many row steps.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn draw_pairs<L: Lanes, const E: usize>(
    l: L,
    s: &BlockSetup<E>,
    bx: u32,
    rows: std::ops::Range<u32>,
    lanes: u8,
    target: &mut BlockTarget<'_>,
    face: u32,
    counts: &mut Counts,
) {
    let lanes = lanes & 15;
    if lanes == 0 {
        return;
    }
    let Some(mut at) = rows_start(target, bx, &rows, 8 - lanes.leading_zeros() as usize) else {
        return;
    };
    let stride = target.stride;
    let (keys, ids) = (&mut *target.keys, &mut *target.ids);
    let (column, row_of) = (l.load(&PAIR_COLUMN), l.load(&PAIR_ROW));
    let zc = l.mul(
        l.splat(s.dzdx),
        l.add_scalar(column, f64::from(bx) - f64::from(s.rect.x0)),
    );
    let (col, bound) = edge_columns(l, s, l.add_scalar(column, f64::from(bx) + 0.5));
    let mut y = rows.start;
    while y < rows.end {
        // The second row only if there is one.
        let mut cover = if rows.end - y >= 2 {
            lanes | lanes << 4
        } else {
            lanes
        };
        let py = l.add_scalar(row_of, f64::from(y) + 0.5);
        for k in 0..E {
            let row = l.mul(l.splat(s.sdx[k]), l.sub_scalar(py, s.oy[k]));
            cover &= l.less(0xff, l.sub(col[k], row), bound[k]);
        }
        let zr = l.add_scalar(
            l.mul(
                l.splat(s.dzdy),
                l.add_scalar(row_of, f64::from(y) - f64::from(s.rect.y0)),
            ),
            s.z0,
        );
        counts.tested += u64::from(cover.count_ones());
        // SAFETY: `cover` is within `lanes` of rows `y` and `y + 1` (only when it is in
        // `rows`), whose pixels are inside the slices (checked above for the last row).
        let taken = unsafe { l.depth_test_pair(keys, ids, at, stride, cover, l.add(zc, zr), face) };
        counts.written += u64::from(taken.count_ones());
        at += 2 * stride;
        y += 2;
    }
}

/// Depth-tests the pixels `cover` of one row of a block at `at` (16 lanes when `WIDE`,
/// else the low 8), their keys the column parts `zc` (lanes 0-7, 8-15) plus the row's
/// part `zj`; returns the pixels taken.
///
/// # Safety
/// The pixels of `cover` in this row are inside the slices.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn test_row<L: Lanes, const WIDE: bool>(
    l: L,
    keys: &mut [f32],
    ids: &mut [u32],
    at: usize,
    cover: u16,
    zc: [L::F; 2],
    zj: f64,
    face: u32,
) -> u16 {
    let lo = l.add_scalar(zc[0], zj);
    // SAFETY: the caller's contract.
    unsafe {
        if WIDE {
            l.depth_test16(keys, ids, at, cover, lo, l.add_scalar(zc[1], zj), face)
        } else {
            u16::from(l.depth_test8(keys, ids, at, cover as u8, lo, face))
        }
    }
}

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
    depth: super::lanes::DepthOfKey,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo::SplitMix64;

    /// The bits of a setup, for comparisons that tell `-0.0` from `0.0` and accept
    /// equal NaNs.
    fn setup_bits(s: &BlockSetup<3>) -> Vec<u64> {
        let mut v: Vec<u64> = [s.ox, s.oy, s.sdx, s.sdy, s.bound]
            .iter()
            .flatten()
            .map(|x| x.to_bits())
            .collect();
        v.extend([s.z0, s.dzdx, s.dzdy].map(f64::to_bits));
        v.extend([s.rect.x0, s.rect.y0, s.rect.x1, s.rect.y1].map(u64::from));
        v
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn triangles8_avx512(
        _: super::super::avx512::Avx512,
        p: &TrianglePoints,
        fill: FillRule,
        w: u32,
        h: u32,
    ) -> TriangleBatch {
        triangles8(p, fill, w, h)
    }

    /// A random triangle of one of the kinds the setups must agree on.
    fn random_triangle(rng: &mut SplitMix64) -> [(f64, f64, f64); 3] {
        let kind = rng.next_u64() % 8;
        let scale = [0.3, 2.0, 9.0, 40.0, 300.0, 1e-6, 5e8, 4.0][kind as usize];
        let (cx, cy) = (rng.range(-20.0, 140.0), rng.range(-20.0, 100.0));
        let mut p = [(0.0, 0.0, 0.0); 3];
        for q in &mut p {
            *q = (
                cx + rng.range(-1.0, 1.0) * scale,
                cy + rng.range(-1.0, 1.0) * scale,
                rng.range(0.001, 1.0),
            );
            if kind == 7 {
                // On the pixel-centre grid and its lines: ties on edges and samples.
                *q = ((q.0 * 2.0).round() / 2.0, (q.1 * 2.0).round() / 2.0, q.2);
            }
        }
        match rng.next_u64() % 16 {
            0 => p[2] = p[0], // two equal points: no area
            1 => p[2] = (2.0 * p[1].0 - p[0].0, 2.0 * p[1].1 - p[0].1, p[2].2), // collinear
            2 => p[1].0 = f64::NAN,
            3 => p[2].1 = f64::INFINITY,
            4 => p[0].2 = f64::NAN, // a non-finite depth
            5 => p[1].1 = p[0].1,   // a horizontal edge
            _ => {}
        }
        p
    }

    #[test]
    fn eight_triangles_at_once_are_set_up_as_one_at_a_time() {
        let mut rng = SplitMix64(41);
        let (w, h) = (120, 80);
        let mut valid = 0;
        #[cfg(target_arch = "x86_64")]
        let fast = crate::cpu::Avx512::new();
        #[cfg(target_arch = "x86_64")]
        if fast.is_none() {
            crate::cpu::simd_test_skipped(
                "AVX-512",
                "eight triangles set up with AVX-512 against one at a time",
            );
        }
        for _ in 0..4000 {
            let tris: Vec<_> = (0..8).map(|_| random_triangle(&mut rng)).collect();
            let mut pts = TrianglePoints::default();
            for (l, t) in tris.iter().enumerate() {
                for (v, q) in t.iter().enumerate() {
                    (pts.x[v][l], pts.y[v][l], pts.zq[v][l]) = *q;
                }
            }
            for fill in [FillRule::TopLeft, FillRule::Inclusive] {
                let mut batches = vec![triangles8(&pts, fill, w, h)];
                #[cfg(target_arch = "x86_64")]
                if let Some(cpu) = fast {
                    // SAFETY: `Avx512::new` checked every feature `triangles8_avx512` enables.
                    batches.push(unsafe { triangles8_avx512(cpu, &pts, fill, w, h) });
                }
                for batch in &batches {
                    for (l, t) in tris.iter().enumerate() {
                        let one = triangle(*t, fill, w, h);
                        assert_eq!(batch.valid >> l & 1 == 1, one.is_some(), "{t:?}");
                        if let Some(one) = one {
                            valid += 1;
                            assert_eq!(setup_bits(&batch.get(l)), setup_bits(&one), "{t:?}");
                        }
                    }
                }
            }
        }
        // Most random triangles are valid; the special kinds make the rest.
        assert!(valid > 20_000, "{valid}");
    }

    /// One triangle drawn alone into an empty `w x h` buffer with `align`: its keys,
    /// ids and counts.
    fn draw_alone<L: Lanes>(
        l: L,
        s: &BlockSetup<3>,
        align: Align,
        w: u32,
        h: u32,
    ) -> (Vec<f32>, Vec<u32>, Counts) {
        let (mut keys, mut ids) = (vec![0.0; (w * h) as usize], vec![0; (w * h) as usize]);
        let mut counts = Counts::default();
        let mut target = BlockTarget::new(&mut keys, &mut ids, w as usize, 0, 0).unwrap();
        let whole = target.rect();
        // Then twice more over the same keys: exact ties everywhere, which the larger
        // encoded id (9) wins and the smaller (8) loses.
        for face in [7, 9, 8] {
            draw(l, s, whole, align, &mut target, face, &mut counts);
        }
        (keys, ids, counts)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
    fn draw_alone_avx512(
        l: super::super::avx512::Avx512,
        s: &BlockSetup<3>,
        align: Align,
        w: u32,
        h: u32,
    ) -> (Vec<f32>, Vec<u32>, Counts) {
        draw_alone(l, s, align, w, h)
    }

    #[test]
    fn narrow_polygons_drawn_row_by_row_cover_the_samples_of_the_rule() {
        // Polygons at most 16 pixels wide drawn with `Align::Polygon` take the
        // row-by-row walk (two rows at a time up to four pixels wide); with
        // `Align::Grid` the block walk, which classifies blocks (and skips the edge
        // tests in covered ones). Both must give exactly the pixels whose sample the
        // per-pixel rule covers, with the same keys, and break ties alike.
        let mut rng = SplitMix64(23);
        let (w, h) = (120, 80);
        let (mut paired, mut narrow, mut wide) = (0, 0, 0);
        #[cfg(target_arch = "x86_64")]
        let fast = crate::cpu::Avx512::new();
        #[cfg(target_arch = "x86_64")]
        if fast.is_none() {
            crate::cpu::simd_test_skipped(
                "AVX-512",
                "polygons drawn with AVX-512 lanes against portable ones",
            );
        }
        for _ in 0..6000 {
            let t = random_triangle(&mut rng);
            for fill in [FillRule::TopLeft, FillRule::Inclusive] {
                let Some(s) = triangle(t, fill, w, h) else {
                    continue;
                };
                let width = s.rect.x1 - s.rect.x0;
                // (A non-finite depth wins no pixel: not what this test is about.)
                if width > 2 * BLOCK || !(s.z0 + s.dzdx + s.dzdy).is_finite() {
                    continue;
                }
                if width <= PAIR_WIDTH {
                    paired += 1;
                } else if width <= BLOCK {
                    narrow += 1;
                } else {
                    wide += 1;
                }
                let mut runs = vec![
                    draw_alone(super::super::lanes::Portable, &s, Align::Polygon, w, h),
                    draw_alone(super::super::lanes::Portable, &s, Align::Grid, w, h),
                ];
                #[cfg(target_arch = "x86_64")]
                if let Some(l) = fast {
                    for align in [Align::Polygon, Align::Grid] {
                        // SAFETY: `Avx512::new` checked every feature `draw_alone_avx512` enables.
                        runs.push(unsafe { draw_alone_avx512(l, &s, align, w, h) });
                    }
                }
                let (keys, ids, counts) = &runs[0];
                let mut covered = 0;
                for j in 0..h {
                    for i in 0..w {
                        let at = (j * w + i) as usize;
                        let inside = s.covers_sample(f64::from(i) + 0.5, f64::from(j) + 0.5);
                        covered += u64::from(inside);
                        assert_eq!(ids[at] == 9, inside, "{t:?} {fill:?} pixel ({i}, {j})");
                        assert_eq!(keys[at] > 0.0, inside, "{t:?} {fill:?} pixel ({i}, {j})");
                    }
                }
                assert_eq!(counts.tested, 3 * covered, "{t:?}");
                assert_eq!(counts.written, 2 * covered, "{t:?}");
                for (k, run) in runs.iter().enumerate().skip(1) {
                    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&run.0), bits(keys), "run {k}: {t:?} {fill:?}");
                    assert_eq!(&run.1, ids, "run {k}: {t:?} {fill:?}");
                    assert_eq!(run.2, *counts, "run {k}: {t:?} {fill:?}");
                }
            }
        }
        assert!(
            paired > 300 && narrow > 300 && wide > 300,
            "{paired} paired, {narrow} narrow, {wide} wide"
        );
    }

    #[test]
    fn whole_numbers_convert_as_the_cast_does() {
        let mut rng = SplitMix64(5);
        let specials = [0.0, -0.0, 1.0, 1920.0, 16384.0, 65535.0, 4_294_967_295.0];
        let random = (0..10_000).map(|_| (rng.next_u64() >> 32) as f64);
        for v in specials.into_iter().chain(random) {
            assert_eq!(whole_to_u32(v), v as u32, "{v}");
        }
    }

    #[test]
    fn nearest_key_bounds_every_key_of_the_rectangle() {
        let mut rng = SplitMix64(17);
        let mut tight = 0;
        for round in 0..3000 {
            let x0 = (rng.next_u64() % 200) as u32;
            let y0 = (rng.next_u64() % 200) as u32;
            let rect = PixelRect {
                x0,
                y0,
                x1: x0 + 1 + (rng.next_u64() % 40) as u32,
                y1: y0 + 1 + (rng.next_u64() % 40) as u32,
            };
            let scale = [1.0, 1e-3, 1e3][round % 3];
            let s = BlockSetup::<0> {
                ox: [],
                oy: [],
                sdx: [],
                sdy: [],
                bound: [],
                rect,
                z0: rng.range(-0.1, 1.0),
                dzdx: rng.range(-1e-2, 1e-2) * scale,
                dzdy: rng.range(-1e-2, 1e-2) / scale,
            };
            let near = nearest_key(&s, rect);
            let mut top = 0.0f32;
            for j in rect.y0..rect.y1 {
                for i in rect.x0..rect.x1 {
                    // Both orders of the sum: the row part first (as `key`), the column
                    // part first.
                    let a = key_of(s.key(i, j));
                    let b = key_of(
                        s.z0 + (s.dzdx * (f64::from(i) - f64::from(rect.x0))
                            + s.dzdy * (f64::from(j) - f64::from(rect.y0))),
                    );
                    assert!(a <= near && b <= near, "{s:?}: {a} {b} {near}");
                    top = top.max(a);
                }
            }
            tight += usize::from(top == near);
        }
        // The margin is far below an f32 unit: the bound is usually the largest key.
        assert!(tight > 2500, "{tight}");
        let nan = BlockSetup::<0> {
            ox: [],
            oy: [],
            sdx: [],
            sdy: [],
            bound: [],
            rect: PixelRect {
                x0: 0,
                y0: 0,
                x1: 2,
                y1: 2,
            },
            z0: f64::NAN,
            dzdx: 0.0,
            dzdy: 0.0,
        };
        assert!(nearest_key(&nan, nan.rect).is_nan());
    }
}
