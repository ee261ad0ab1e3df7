//! What the crate's benches and the CLI's `bench` command need of its internals, and
//! no more: not API (hidden from the documentation, free to change).
//!
//! - [`SplitMix64`]: the crate's deterministic generator, so that the benches' random
//!   inputs are the tests' ones.
//! - [`scaled_triangles`]: the generated scenes of `obscura bench`.
//! - [`SmallTriangles`]: the `zbuffer_bounds` measurement's small triangles, set up for
//!   the z-buffer's block rasterizer and drawn alone with its fastest kernel.

pub use crate::rng::SplitMix64;
pub use crate::scene::random::scaled_triangles;

use crate::raster::block::{self, Align, BlockSetup, BlockTarget, Counts};
use crate::raster::lanes::{DepthOfKey, Lanes, Portable};
use crate::raster::{FillRule, PixelRect};
use crate::surface::zbuffer::BIG;
use crate::{Frame, PreparedView};

/// The triangles of a prepared view that have a sample and at most
/// [`BIG`] pixels on a side, set up for the block rasterizer, with their encoded ids.
#[derive(Clone, Debug, Default)]
pub struct SmallTriangles(Vec<(BlockSetup<3>, u32)>);

impl SmallTriangles {
    /// The small triangles of `view` (its polygons of three vertices).
    #[must_use]
    pub fn of(view: &PreparedView<'_>) -> Self {
        let (starts, indices, faces) = view.polygon_arrays();
        let v = view.vertices();
        let vp = view.viewport();
        let mut out = Vec::new();
        for p in 0..view.polygon_count() {
            let (a, b) = (starts[p] as usize, starts[p + 1] as usize);
            let &[i, j, k] = &indices[a..b] else {
                continue;
            };
            let point = |q: u32| {
                let q = &v[q as usize];
                (q.x, q.y, q.zq)
            };
            let Some(t) = block::triangle(
                [point(i), point(j), point(k)],
                FillRule::TopLeft,
                vp.width,
                vp.height,
            ) else {
                continue;
            };
            if t.rect.x1 - t.rect.x0 <= BIG && t.rect.y1 - t.rect.y0 <= BIG {
                out.push((t, !faces[p]));
            }
        }
        SmallTriangles(out)
    }

    /// How many triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Those not hidden in every 8x4 block of the finished `frame` of `view` they
    /// overlap (the block's farthest key, taken a millionth nearer, above the
    /// triangle's nearest): what an oracle occlusion culler would keep.
    #[must_use]
    pub fn oracle_kept(&self, view: &PreparedView<'_>, frame: &Frame) -> Self {
        const BW: usize = 8;
        const BH: usize = 4;
        let (w, h) = (frame.width as usize, frame.height as usize);
        let near = match view.transform().key_depths() {
            DepthOfKey::Perspective { near } => f64::from(near),
            DepthOfKey::Orthographic { .. } => return self.clone(),
        };
        let (nx, ny) = (w.div_ceil(BW), h.div_ceil(BH));
        let mut farthest = vec![f64::INFINITY; nx * ny];
        for y in 0..h {
            for x in 0..w {
                let d = f64::from(frame.depth[y * w + x]);
                // A millionth nearer than the stored key: the oracle culls at least as
                // much as the exact test would.
                let key = if d.is_finite() {
                    near / d * (1.0 + 1e-6)
                } else {
                    0.0
                };
                let f = &mut farthest[(y / BH) * nx + x / BW];
                *f = f.min(key);
            }
        }
        let kept = self
            .0
            .iter()
            .filter(|(t, _)| {
                let r = t.rect;
                let nearest = f64::from(block::nearest_key(t, r));
                let hidden = (r.y0 as usize / BH..=(r.y1 as usize - 1) / BH).all(|by| {
                    (r.x0 as usize / BW..=(r.x1 as usize - 1) / BW)
                        .all(|bx| farthest[by * nx + bx] > nearest)
                });
                !hidden
            })
            .copied()
            .collect();
        SmallTriangles(kept)
    }

    /// The minimum over `runs` of the milliseconds to draw the triangles into a
    /// cleared 1920x1080 buffer with the fastest kernel.
    #[must_use]
    pub fn draw_ms(&self, runs: usize) -> f64 {
        let (mut keys, mut ids) = (vec![0f32; 1920 * 1080], vec![0u32; 1920 * 1080]);
        let mut best = f64::INFINITY;
        for _ in 0..runs {
            keys.fill(0.0);
            ids.fill(0);
            let t = std::time::Instant::now();
            draw_fastest(&self.0, &mut keys, &mut ids);
            best = best.min(t.elapsed().as_secs_f64() * 1e3);
        }
        best
    }
}

fn draw_fastest(tris: &[(BlockSetup<3>, u32)], keys: &mut [f32], ids: &mut [u32]) {
    #[cfg(target_arch = "x86_64")]
    if let Some(l) = crate::raster::avx512::Avx512::new() {
        // SAFETY: `Avx512::new` checked the instructions `draw_avx512` enables.
        unsafe { draw_avx512(l, tris, keys, ids) };
        return;
    }
    draw(Portable, tris, keys, ids);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_avx512(
    l: crate::raster::avx512::Avx512,
    tris: &[(BlockSetup<3>, u32)],
    keys: &mut [f32],
    ids: &mut [u32],
) {
    draw(l, tris, keys, ids);
}

#[inline(always)]
fn draw<L: Lanes>(l: L, tris: &[(BlockSetup<3>, u32)], keys: &mut [f32], ids: &mut [u32]) {
    let whole = PixelRect {
        x0: 0,
        y0: 0,
        x1: 1920,
        y1: 1080,
    };
    let Some(mut target) = BlockTarget::new(keys, ids, 1920, 0, 0) else {
        return;
    };
    let mut counts = Counts::default();
    for (t, face) in tris {
        block::draw(l, t, whole, Align::Polygon, &mut target, *face, &mut counts);
    }
    std::hint::black_box(counts);
}
