//! Conservative triangle setup shared by both buffers: edge functions for inner
//! coverage, the depth-key plane, and the bounds on rounding that keep both on the
//! safe side.
//!
//! Buffer coordinates: buffer pixel `(i, j)` stands for the viewport pixels
//! `i d .. i d + d - 1` (and likewise in y) for the divisor `d`; a viewport pixel's
//! sample `(x + 0.5, y + 0.5)` maps to `X = x / d`, so the samples of buffer pixel
//! `i` span `X in [i, i + r]` with `r = (d - 1) / d`. A buffer pixel counts as covered
//! by a triangle only if every sample it stands for is inside the triangle (inner,
//! conservative coverage): as the triangle is convex, the test is the edge function
//! at `(i, j)` shifted by the least it takes over the square `[0, r]^2`.
//!
//! Depths are depth keys `zq` (larger is nearer: `near / depth` in perspective,
//! `(far - depth) / (far - near)` in parallel projection), affine in screen space for a
//! planar polygon in both projections. The buffer keeps, per pixel, a key that no
//! covering occluder is farther than (smaller than): a lower bound.

/// A triangle in buffer coordinates: `[X, Y, zq]` per vertex.
pub type Tri = [[f64; 3]; 3];

/// A triangle (`N = 3`) or a convex polygon of up to `N` edges set up for
/// rasterization (every value in buffer coordinates). A polygon of fewer than `N`
/// edges repeats its last edge: the same test twice, the same coverage.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup<const N: usize = 3> {
    /// Edge functions `a X + b Y + c`, positive inside, already shifted so that a
    /// positive value at `(i, j)` means the whole sample square is inside.
    pub a: [f64; N],
    pub b: [f64; N],
    pub c: [f64; N],
    /// Per edge, the magnitudes its constant was computed from (`|a X| + |b Y|` at the
    /// edge's first vertex, and the shift): its rounding is below `2^-52` of them.
    pub cmag: [f64; N],
    /// Depth-key plane `p X + q Y + r`.
    pub p: f64,
    pub q: f64,
    pub r: f64,
    /// The smallest (farthest) key of the vertices.
    pub zmin: f64,
    /// What is taken off every depth bound for the rounding of the plane.
    pub zslack: f64,
    /// Pixel bounds (inclusive), inside the buffer.
    pub x0: i32,
    pub y0: i32,
    pub x1: i32,
    pub y1: i32,
}

/// The relative margin taken off a buffer depth key (rounds towards "farther": kept),
/// larger than the rounding of the z-buffer's own `f32` keys by a wide factor.
pub(crate) const DEPTH_MARGIN: f64 = 4e-6;

/// Sets up triangle `v` for a buffer of `w x h` pixels whose samples span squares of
/// side `r`. `None` when it covers no buffer pixel for sure: outside, degenerate
/// (zero area), or so thin (width below 1e-7 of its length) that its depth plane
/// would be ill-conditioned; leaving a triangle out is always conservative.
#[inline(always)]
pub(crate) fn setup(v: &Tri, r: f64, w: u32, h: u32) -> Option<Setup> {
    if !v.iter().flatten().all(|c| c.is_finite()) {
        return None;
    }
    // Twice the signed area; the edge functions of a clockwise triangle are negated
    // (exactly) instead of two vertices swapped: no branch on the orientation.
    let signed =
        (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]);
    let sign = if signed < 0.0 { -1.0 } else { 1.0 };
    let a2 = signed * sign;
    let len2 = (0..3)
        .map(|k| {
            let (p, q) = (v[k], v[(k + 1) % 3]);
            (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
        })
        .fold(0.0, f64::max);
    if !(a2 > 1e-7 * len2) || !(a2 > 1e-9) {
        return None;
    }
    let xmin = v[0][0].min(v[1][0]).min(v[2][0]);
    let xmax = v[0][0].max(v[1][0]).max(v[2][0]) - r;
    let ymin = v[0][1].min(v[1][1]).min(v[2][1]);
    let ymax = v[0][1].max(v[1][1]).max(v[2][1]) - r;
    let x0 = xmin.ceil().max(0.0);
    let y0 = ymin.ceil().max(0.0);
    let x1 = xmax.floor().min(f64::from(w) - 1.0);
    let y1 = ymax.floor().min(f64::from(h) - 1.0);
    if !(x0 <= x1 && y0 <= y1) {
        return None;
    }
    let (mut a, mut b, mut c, mut cmag) = ([0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
    for k in 0..3 {
        let (p, q) = (v[k], v[(k + 1) % 3]);
        a[k] = -(q[1] - p[1]) * sign;
        b[k] = (q[0] - p[0]) * sign;
        c[k] = -(a[k] * p[0] + b[k] * p[1]) + a[k].min(0.0) * r + b[k].min(0.0) * r;
        cmag[k] = (a[k] * p[0]).abs() + (b[k] * p[1]).abs() + (a[k].abs() + b[k].abs()) * r;
    }
    let (dx1, dy1, dz1) = (v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2]);
    let (dx2, dy2, dz2) = (v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2]);
    // Numerators and denominator both change sign with the orientation. One division
    // (its reciprocal's rounding adds a relative 2^-52 to p and q, far inside `zslack`).
    let inv = 1.0 / signed;
    let p = (dz1 * dy2 - dz2 * dy1) * inv;
    let q = (dx1 * dz2 - dx2 * dz1) * inv;
    let rr = v[0][2] - p * v[0][0] - q * v[0][1];
    let zmin = v[0][2].min(v[1][2]).min(v[2][2]);
    let zmax = v[0][2].max(v[1][2]).max(v[2][2]);
    let ext = xmin.abs().max(xmax.abs()) + 16.0;
    let eyt = ymin.abs().max(ymax.abs()) + 16.0;
    let zslack = 1e-9 * (p.abs() * ext + q.abs() * eyt + rr.abs()) + DEPTH_MARGIN * zmax.abs();
    Some(Setup {
        a,
        b,
        c,
        cmag,
        p,
        q,
        r: rr,
        zmin,
        zslack,
        x0: x0 as i32,
        y0: y0 as i32,
        x1: x1 as i32,
        y1: y1 as i32,
    })
}

/// The most vertices a [`Poly`] may have.
pub const POLY_MAX: usize = 8;

/// A planar, strictly convex polygon of 3 to [`POLY_MAX`] vertices in buffer
/// coordinates (`[X, Y, zq]` per vertex), checked by [`Poly::new`]: rasterized as one
/// primitive, inner coverage against all its edges and one depth plane, so no pixel
/// along an inner diagonal is lost (as it is between the two triangles of a quad,
/// each of which leaves out the pixels whose samples straddle the diagonal).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Poly {
    n: usize,
    v: [[f64; 3]; POLY_MAX],
    /// The sign that makes the orientation counter-clockwise (`+1` or `-1`).
    sign: f64,
    /// The depth-key plane `p X + q Y + r` (through the largest triangle of vertices),
    /// and the largest distance in key of a vertex from it (taken off every bound).
    p: f64,
    q: f64,
    r: f64,
    dev: f64,
}

impl Poly {
    /// Checks `v` (buffer coordinates, either orientation): `None` unless it has 3 to
    /// [`POLY_MAX`] vertices (consecutive repeats dropped), all finite, every vertex
    /// strictly inside every edge line not through it by a margin above the rounding of
    /// the test (strictly convex: no three collinear, a single turn), and its keys on one
    /// plane within a relative `1e-6` (a polygon planar in the scene is, in screen space:
    /// the keys are affine there). A refused polygon is for the caller to split into
    /// triangles (drawing it as one would not be conservative).
    ///
    /// Why the test proves convexity: the exact orientation of every vertex against
    /// every edge differs from the computed one by less than `2^-50` of the magnitudes
    /// `|ex dy| + |ey dx|` (two differences, two products and one difference, each
    /// rounded by `2^-53`), far below the margin `1e-12` of them; so every other vertex
    /// lies strictly on the inner side of every edge. Each edge is then an edge of the
    /// convex hull traversed counter-clockwise (under `sign`), the vertices are in strictly
    /// convex position, and following the edges visits each hull vertex once: the
    /// polygon is its convex hull, the intersection of its edges' inner half-planes.
    #[must_use]
    pub fn new(v: &[[f64; 3]]) -> Option<Poly> {
        let mut w = [[0.0f64; 3]; POLY_MAX];
        let mut n = 0usize;
        for p in v {
            if !p.iter().all(|c| c.is_finite()) {
                return None;
            }
            if n > 0 && w[n - 1][0] == p[0] && w[n - 1][1] == p[1] {
                continue;
            }
            if n == POLY_MAX {
                return None;
            }
            w[n] = *p;
            n += 1;
        }
        while n > 1 && w[n - 1][0] == w[0][0] && w[n - 1][1] == w[0][1] {
            n -= 1;
        }
        if n < 3 {
            return None;
        }
        let o = w[0];
        let mut area = 0.0;
        for i in 1..n - 1 {
            area +=
                (w[i][0] - o[0]) * (w[i + 1][1] - o[1]) - (w[i + 1][0] - o[0]) * (w[i][1] - o[1]);
        }
        let sign = if area < 0.0 { -1.0 } else { 1.0 };
        for i in 0..n {
            let (a, b) = (w[i], w[(i + 1) % n]);
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            for (j, p) in w[..n].iter().enumerate() {
                if j == i || j == (i + 1) % n {
                    continue;
                }
                let (dx, dy) = (p[0] - a[0], p[1] - a[1]);
                let cross = (ex * dy - ey * dx) * sign;
                if !(cross > 1e-12 * ((ex * dy).abs() + (ey * dx).abs())) {
                    return None;
                }
            }
        }
        // The plane through the largest triangle of vertices (the best conditioned).
        let (mut best, mut tri) = (0.0, [0, 1, 2]);
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let (a, b, c) = (w[i], w[j], w[k]);
                    let s = ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs();
                    if s > best {
                        best = s;
                        tri = [i, j, k];
                    }
                }
            }
        }
        let [a, b, c] = tri.map(|i| w[i]);
        let len2 = (0..n)
            .map(|k| {
                let (p, q) = (w[k], w[(k + 1) % n]);
                (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
            })
            .fold(0.0, f64::max);
        // As for a triangle: a plane from a sliver is ill-conditioned.
        if !(best > 1e-7 * len2) || !(best > 1e-9) {
            return None;
        }
        let (dx1, dy1, dz1) = (b[0] - a[0], b[1] - a[1], b[2] - a[2]);
        let (dx2, dy2, dz2) = (c[0] - a[0], c[1] - a[1], c[2] - a[2]);
        let inv = 1.0 / (dx1 * dy2 - dx2 * dy1);
        let p = (dz1 * dy2 - dz2 * dy1) * inv;
        let q = (dx1 * dz2 - dx2 * dz1) * inv;
        let r = a[2] - p * a[0] - q * a[1];
        let mut dev = 0.0f64;
        let mut zmax = 0.0f64;
        for v in &w[..n] {
            dev = dev.max((v[2] - (p * v[0] + q * v[1] + r)).abs());
            zmax = zmax.max(v[2].abs());
        }
        if !(dev <= 1e-6 * zmax) {
            return None;
        }
        Some(Poly {
            n,
            v: w,
            sign,
            p,
            q,
            r,
            dev,
        })
    }

    /// The vertices (consecutive repeats dropped).
    #[must_use]
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.v[..self.n]
    }
}

/// Sets up polygon `poly` with `N >= poly.n` edges (the last repeated) as [`setup`]
/// does a triangle: the same edge functions and shifts per edge (inner coverage of a
/// convex polygon is inside every edge's half-plane: each edge is shifted by its own
/// least over the sample square), the polygon's plane, its farthest vertex key as the
/// floor, and the slack of a triangle plus the vertices' distance `dev` from the plane.
/// Why `dev` suffices: however the z-buffer splits the polygon into triangles of its
/// vertices, its key at a point is a convex combination of vertex keys, each within
/// `dev` of the plane, so at most `dev` farther than the (affine) plane there.
#[inline(always)]
pub(crate) fn poly_setup<const N: usize>(poly: &Poly, r: f64, w: u32, h: u32) -> Option<Setup<N>> {
    let n = poly.n;
    if n > N {
        return None;
    }
    let v = &poly.v[..n];
    let fold = |f: fn(f64, f64) -> f64, i: usize, init: f64| v.iter().map(|p| p[i]).fold(init, f);
    let xmin = fold(f64::min, 0, f64::INFINITY);
    let xmax = fold(f64::max, 0, f64::NEG_INFINITY) - r;
    let ymin = fold(f64::min, 1, f64::INFINITY);
    let ymax = fold(f64::max, 1, f64::NEG_INFINITY) - r;
    let x0 = xmin.ceil().max(0.0);
    let y0 = ymin.ceil().max(0.0);
    let x1 = xmax.floor().min(f64::from(w) - 1.0);
    let y1 = ymax.floor().min(f64::from(h) - 1.0);
    if !(x0 <= x1 && y0 <= y1) {
        return None;
    }
    let sign = poly.sign;
    let (mut a, mut b, mut c, mut cmag) = ([0.0; N], [0.0; N], [0.0; N], [0.0; N]);
    for k in 0..N {
        let e = k.min(n - 1);
        let (p, q) = (v[e], v[(e + 1) % n]);
        a[k] = -(q[1] - p[1]) * sign;
        b[k] = (q[0] - p[0]) * sign;
        c[k] = -(a[k] * p[0] + b[k] * p[1]) + a[k].min(0.0) * r + b[k].min(0.0) * r;
        cmag[k] = (a[k] * p[0]).abs() + (b[k] * p[1]).abs() + (a[k].abs() + b[k].abs()) * r;
    }
    let zmin = fold(f64::min, 2, f64::INFINITY);
    let zmax = fold(f64::max, 2, f64::NEG_INFINITY);
    let (p, q, rr) = (poly.p, poly.q, poly.r);
    let ext = xmin.abs().max(xmax.abs()) + 16.0;
    let eyt = ymin.abs().max(ymax.abs()) + 16.0;
    let zslack = 1e-9 * (p.abs() * ext + q.abs() * eyt + rr.abs())
        + DEPTH_MARGIN * zmax.abs().max(zmin.abs())
        + poly.dev;
    Some(Setup {
        a,
        b,
        c,
        cmag,
        p,
        q,
        r: rr,
        zmin,
        zslack,
        x0: x0 as i32,
        y0: y0 as i32,
        x1: x1 as i32,
        y1: y1 as i32,
    })
}

impl<const N: usize> Setup<N> {
    /// The key no covered sample of the rectangle of buffer pixels `[x, x + wx] x [y,
    /// y + wy]` (sample squares included: extent `+ r`) is farther than, rounded
    /// towards farther.
    #[inline(always)]
    pub(crate) fn far_key(&self, x: f64, y: f64, wx: f64, wy: f64) -> f64 {
        let plane = self.p * x + self.q * y + self.r + self.p.min(0.0) * wx + self.q.min(0.0) * wy;
        plane.max(self.zmin) - self.zslack
    }
}

/// `value` as an `f32` no larger than it: the largest `f32` at or below it (`-inf` below
/// every finite one, `f32::MAX` for a finite value above it; NaN stays NaN). Without
/// branches (one a triangle takes half the time would be mispredicted half the time):
/// rounded to nearest, then one step down when that went up, the step taken on the
/// bits (an `f32`'s magnitude is its bits less the sign, so a step towards `-inf` is
/// `-1` on a positive one and `+1` on a negative one; zero first becomes `-0.0`, whose
/// step down is the least negative `f32`).
#[inline(always)]
pub(crate) fn f32_down(value: f64) -> f32 {
    let f = value as f32;
    let up = u32::from(f64::from(f) > value);
    let f = if f == 0.0 { -0.0f32 } else { f };
    let bits = f.to_bits();
    let step = if bits >> 31 == 1 {
        up
    } else {
        up.wrapping_neg()
    };
    f32::from_bits(bits.wrapping_add(step))
}

/// `value` as an `f32` no smaller than it.
#[inline(always)]
pub(crate) fn f32_up(value: f64) -> f32 {
    let f = value as f32;
    if f64::from(f) < value { f.next_up() } else { f }
}
