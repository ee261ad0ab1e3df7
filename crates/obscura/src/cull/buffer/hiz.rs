//! The hierarchical z-buffer option (Greene, Kass and Miller, "Hierarchical Z-buffer
//! visibility", SIGGRAPH 1993): a depth key per pixel, the farthest of every covering
//! occluder's conservative key (inner coverage, keys rounded towards farther: see
//! [`super::raster`]), and a pyramid whose texels keep the farthest key of their 2 x 2
//! children. A box is tested from the level where its rectangle spans two texels or
//! fewer, descending only into texels its nearest key does not pass.

use super::raster::{POLY_MAX, Poly, Setup, Tri, f32_down, poly_setup, setup};
use crate::cpu::Kernel;

/// The pyramid (see the [module documentation](self)); reused frame to frame.
#[derive(Clone, Debug, Default)]
pub struct HizBuffer {
    r: f64,
    /// Per level: width, height, keys (level 0: the pixels).
    levels: Vec<(usize, usize, Vec<f32>)>,
}

impl HizBuffer {
    /// Empties the buffer and sets its size (see [`super::masked::MaskedBuffer::reset`]).
    pub fn reset(&mut self, width: u32, height: u32, r: f64) {
        self.r = r;
        let (mut w, mut h) = (width as usize, height as usize);
        let mut k = 0;
        loop {
            if self.levels.len() <= k {
                self.levels.push((0, 0, Vec::new()));
            }
            let l = &mut self.levels[k];
            l.0 = w;
            l.1 = h;
            l.2.clear();
            l.2.resize(w * h, f32::NEG_INFINITY);
            k += 1;
            if w <= 1 && h <= 1 {
                break;
            }
            w = w.div_ceil(2);
            h = h.div_ceil(2);
        }
        self.levels.truncate(k);
    }

    /// The size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].0 as u32, self.levels[0].1 as u32)
    }

    /// Draws triangles (buffer coordinates) and rebuilds the pyramid.
    pub fn draw(&mut self, tris: &[Tri], kernel: Kernel) {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(cpu) = kernel.avx2() {
                // SAFETY: `Avx2::new` checked every feature `draw_avx2` enables.
                unsafe { draw_avx2(cpu, self, tris) };
                self.build();
                return;
            }
        }
        let _ = kernel;
        draw_impl(self, tris);
        self.build();
    }

    /// Draws convex polygons (buffer coordinates, see [`Poly`]), each as one primitive
    /// (inner coverage against all its edges, its one plane), and rebuilds the pyramid.
    pub fn draw_polygons(&mut self, polys: &[Poly], kernel: Kernel) {
        self.draw_occluders(&[], polys, kernel);
    }

    /// Draws triangles and convex polygons, then rebuilds the pyramid once (the
    /// rebuild costs as much as the raster of a few hundred occluders: draw both
    /// kinds with this rather than one call each).
    pub fn draw_occluders(&mut self, tris: &[Tri], polys: &[Poly], kernel: Kernel) {
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(cpu) = kernel.avx2() {
                // SAFETY: `Avx2::new` checked every feature `draw_avx2` and
                // `draw_polys_avx2` enable.
                unsafe {
                    draw_polys_avx2(cpu, self, polys);
                    draw_avx2(cpu, self, tris);
                }
                self.build();
                return;
            }
        }
        let _ = kernel;
        draw_polys_impl(self, polys);
        draw_impl(self, tris);
        self.build();
    }

    /// The farthest-of-children pyramid above level 0.
    fn build(&mut self) {
        for k in 1..self.levels.len() {
            let (lo, hi) = self.levels.split_at_mut(k);
            let (cw, ch, child) = &lo[k - 1];
            let (w, h, keys) = &mut hi[0];
            for y in 0..*h {
                for x in 0..*w {
                    let mut m = f32::INFINITY;
                    for cy in 2 * y..(2 * y + 2).min(*ch) {
                        for cx in 2 * x..(2 * x + 2).min(*cw) {
                            m = m.min(child[cy * cw + cx]);
                        }
                    }
                    keys[y * *w + x] = m;
                }
            }
        }
    }

    /// The key bound of pixel `(x, y)` (see [`super::masked::MaskedBuffer::bound`]).
    #[must_use]
    pub fn bound(&self, x: u32, y: u32) -> f32 {
        let (w, _, keys) = &self.levels[0];
        keys[y as usize * w + x as usize]
    }

    /// Whether a box of nearest key `key` is hidden at every pixel of `[x0, x1] x [y0,
    /// y1]` (inclusive, inside the buffer).
    #[must_use]
    pub fn hidden(&self, x0: u32, y0: u32, x1: u32, y1: u32, key: f32) -> bool {
        let span = (x1 - x0).max(y1 - y0) as usize + 1;
        // The level where the rectangle spans at most two texels per axis.
        let mut level = 0;
        while level + 1 < self.levels.len() && (span >> level) > 1 {
            level += 1;
        }
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize, y1 as usize);
        let (w, _, keys) = &self.levels[level];
        for ty in y0 >> level..=y1 >> level {
            for tx in x0 >> level..=x1 >> level {
                if key < keys[ty * w + tx] {
                    continue;
                }
                if !self.hidden_in(level, tx, ty, [x0, y0, x1, y1], key) {
                    return false;
                }
            }
        }
        true
    }

    /// Whether the box is hidden inside texel `(tx, ty)` of `level`, which it does not
    /// pass at that level: descend.
    fn hidden_in(&self, level: usize, tx: usize, ty: usize, r: [usize; 4], key: f32) -> bool {
        if level == 0 {
            return false;
        }
        let l = level - 1;
        let (w, h, keys) = &self.levels[l];
        for cy in (2 * ty).max(r[1] >> l)..=(2 * ty + 1).min(r[3] >> l).min(h - 1) {
            for cx in (2 * tx).max(r[0] >> l)..=(2 * tx + 1).min(r[2] >> l).min(w - 1) {
                if key < keys[cy * w + cx] {
                    continue;
                }
                if !self.hidden_in(l, cx, cy, r, key) {
                    return false;
                }
            }
        }
        true
    }
}

#[inline(always)]
fn draw_impl(buf: &mut HizBuffer, tris: &[Tri]) {
    let r = buf.r;
    let (w, h) = (buf.levels[0].0 as u32, buf.levels[0].1 as u32);
    for t in tris {
        if let Some(s) = setup(t, r, w, h) {
            fill(buf, &s);
        }
    }
}

#[inline(always)]
fn draw_polys_impl(buf: &mut HizBuffer, polys: &[Poly]) {
    let r = buf.r;
    let (w, h) = (buf.levels[0].0 as u32, buf.levels[0].1 as u32);
    // Up to four edges with four (a triangle repeats one), the others with eight.
    for p in polys {
        if p.vertices().len() <= 4 {
            if let Some(s) = poly_setup::<4>(p, r, w, h) {
                fill(buf, &s);
            }
        } else if let Some(s) = poly_setup::<POLY_MAX>(p, r, w, h) {
            fill(buf, &s);
        }
    }
}

/// Level 0 takes the farthest key of `s` over each pixel whose samples it covers (every
/// edge's value above its rounding bound).
#[inline(always)]
fn fill<const N: usize>(buf: &mut HizBuffer, s: &Setup<N>) {
    let r = buf.r;
    let (w, _, keys) = &mut buf.levels[0];
    for y in s.y0..=s.y1 {
        let yf = f64::from(y);
        let e: [f64; N] = std::array::from_fn(|k| s.b[k] * yf + s.c[k]);
        let row = &mut keys[y as usize * *w..][..*w];
        for x in s.x0..=s.x1 {
            let xf = f64::from(x);
            let inside = (0..N).all(|k| {
                let v = s.a[k] * xf + e[k];
                v - (v.abs() + s.a[k].abs() + s.b[k].abs()) * 1e-12 > 0.0
            });
            if inside {
                let z = f32_down(s.far_key(xf, yf, r, r));
                let cell = &mut row[x as usize];
                *cell = cell.max(z);
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_polys_avx2(_: crate::cpu::Avx2, buf: &mut HizBuffer, polys: &[Poly]) {
    draw_polys_impl(buf, polys);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn draw_avx2(_: crate::cpu::Avx2, buf: &mut HizBuffer, tris: &[Tri]) {
    draw_impl(buf, tris);
}

#[cfg(test)]
impl HizBuffer {
    /// Level 0, for comparisons of kernels.
    pub(crate) fn pixels(&self) -> &[f32] {
        &self.levels[0].2
    }
}
