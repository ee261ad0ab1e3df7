//! Setting polygons up for the block rasterizer: [`BlockSetup`] from the shared
//! coverage rule's edges, one triangle at a time ([`triangle`]) or eight at once, lane
//! by lane ([`triangles8`]).

use super::MAX_EDGES;
use crate::raster::{DepthPlane, EdgeFunction, FillRule, PixelRect};

/// A convex polygon of at most `E` edges set up for block rasterization (see the
/// module doc of [`super`]). Unused edges (when the polygon has fewer) hold every sample inside.
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
    #[cfg(test)]
    #[must_use]
    pub fn covers_sample(&self, px: f64, py: f64) -> bool {
        (0..E).all(|k| {
            let t = self.sdy[k] * (px - self.ox[k]) - self.sdx[k] * (py - self.oy[k]);
            t < self.bound[k]
        })
    }

    /// The depth key of pixel `(i, j)` (the expression of [`super`]'s doc).
    #[inline(always)]
    #[must_use]
    pub fn key(&self, i: u32, j: u32) -> f64 {
        let zr = self.z0 + self.dzdy * (f64::from(j) - f64::from(self.rect.y0));
        zr + self.dzdx * (f64::from(i) - f64::from(self.rect.x0))
    }
}

/// The setup of the triangle with vertices `(x, y, zq)` for a `width x height` image:
/// the edges and rectangle of [`PolygonCoverage::new`](crate::raster::PolygonCoverage::new) and
/// the plane of [`DepthPlane::from_points`] (what
/// [`TriangleSetup`](crate::raster::TriangleSetup) computes, in the block rasterizer's form).
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
    let t = crate::raster::TriangleSetup::new(p, fill, width, height)?;
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
pub(super) fn whole_to_u32(v: f64) -> u32 {
    (v + 4_503_599_627_370_496.0).to_bits() as u32
}

/// [`triangle`] for eight triangles at once: lane `l` of the result holds what
/// `triangle` gives for triangle `l`, and is valid exactly when `triangle` gives a
/// setup. A deliberate lane-wise twin of [`triangle`] (which calls the shared
/// [`TriangleSetup`](crate::raster::TriangleSetup)): each lane evaluates the same
/// expressions in the same order, and the test
/// `eight_triangles_at_once_are_set_up_as_one_at_a_time` compares the two bit for bit,
/// portable and AVX-512.
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
