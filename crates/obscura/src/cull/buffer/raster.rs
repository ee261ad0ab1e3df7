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

/// A triangle set up for rasterization (every value in buffer coordinates).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup {
    /// Edge functions `a X + b Y + c`, positive inside, already shifted so that a
    /// positive value at `(i, j)` means the whole sample square is inside.
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub c: [f64; 3],
    /// Per edge, the magnitudes its constant was computed from (`|a X| + |b Y|` at the
    /// edge's first vertex, and the shift): its rounding is below `2^-52` of them.
    pub cmag: [f64; 3],
    /// Depth-key plane `p X + q Y + r`.
    pub p: f64,
    pub q: f64,
    pub r: f64,
    /// The smallest (farthest) key of the three vertices.
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

impl Setup {
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
