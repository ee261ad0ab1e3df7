//! How far the z-buffer's time on a scene is from what its visible work costs.
//!
//! ```text
//! cargo bench -p obscura --bench zbuffer_bounds [-- SCENE [RUNS]]
//! ```
//!
//! SCENE defaults to `../shared/data/sponza.obj` seen from the atrium camera of that
//! folder's README (`--eye 0,-10,2 --target 0,10,4 --up 0,0,1 --fov 60`, 1920x1080);
//! any other scene is seen from its default camera. Everything runs on one thread and
//! each figure is the minimum of RUNS runs (default 20). It prints:
//!
//! 1. `prepare` and the z-buffer (`render_with(.., 1)`) with the z-buffer's phases: every
//!    polygon set up and the small ones (at most 64 pixels on a side) drawn at once, the
//!    big ones binned, the tiles drawn and the frame resolved;
//! 2. how many faces the finished frame shows;
//! 3. the small triangles drawn alone with the z-buffer's block rasterizer (set up
//!    beforehand, so the time is the drawing only), into a cleared frame;
//! 4. the same for only the small triangles that an *oracle* occlusion culler would
//!    keep: those not hidden, by their nearest key, in every 8x4 block of the finished
//!    frame they overlap (the frame's keys taken a millionth nearer, so the oracle
//!    culls at least what an exact one would). No real culler knows the finished frame
//!    while drawing, and none culls for free, so this time bounds from below what the
//!    small triangles cost with any occlusion culling;
//! 5. a lower bound of the frame time: (4) plus the tiles phase (the big polygons, which
//!    culling the small ones cannot make cheaper, and the resolve of the frame), leaving
//!    out `prepare`, the setup of every polygon and the binning.
//!
//! This is the measurement behind the speed figures of `docs/performance.md`
//! ("Where the z-buffer's time goes", "Coverage") and the closing notes of the
//! z-buffer's issue.

use std::time::Instant;

mod common;

use obscura::raster::block::{self, Align, BlockSetup, BlockTarget, Counts};
use obscura::raster::lanes::{DepthOfKey, Lanes, Portable};
use obscura::raster::{FillRule, PixelRect};
use obscura::surface::RenderOptions;
use obscura::surface::zbuffer::{BIG, Kernel, render_with};
use obscura::{PrepareOptions, PreparedView, prepare};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let common::Measured {
        path,
        scene,
        camera,
        viewport,
        runs,
    } = common::from_args(20)?;
    let options = RenderOptions::default();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    Ok(pool.install(|| -> Result<(), obscura::Error> {
        // 1. The z-buffer as it is.
        let (mut prepare_ms, mut render_ms) = (f64::INFINITY, f64::INFINITY);
        let mut phases = [f64::INFINITY; 3];
        for _ in 0..runs {
            let t0 = Instant::now();
            let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
            let t1 = Instant::now();
            let (_, stats) = render_with(&view, &options, Kernel::detect(), 1)?;
            prepare_ms = prepare_ms.min((t1 - t0).as_secs_f64() * 1e3);
            render_ms = render_ms.min(t1.elapsed().as_secs_f64() * 1e3);
            let measured = stats.fast.map_or([f64::NAN; 3], |f| {
                [f.setup_and_small_ms, f.binning_ms, f.tiles_ms]
            });
            for (p, ms) in phases.iter_mut().zip(measured) {
                *p = p.min(ms);
            }
        }
        println!("scene {path}, 1920x1080, one thread, minimum of {runs} runs");
        println!("prepare                                  {prepare_ms:8.2} ms");
        println!("z-buffer                                 {render_ms:8.2} ms");
        println!(
            "  setup of every polygon, small drawn    {:8.2} ms",
            phases[0]
        );
        println!(
            "  big polygons binned                    {:8.2} ms",
            phases[1]
        );
        println!(
            "  tiles (big polygons, resolve)          {:8.2} ms",
            phases[2]
        );

        // 2. What the finished frame shows.
        let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
        let (frame, _) = render_with(&view, &options, Kernel::detect(), 1)?;
        let mut shown: Vec<u32> = frame.ids.clone();
        shown.sort_unstable();
        shown.dedup();
        shown.retain(|&id| id != obscura::BACKGROUND);

        // 3. and 4. The small triangles drawn alone, all of them and the oracle's.
        let small = small_triangles(&view);
        let kept = oracle_kept(&view, &frame, &small);
        let all_ms = draw_time(&small, runs);
        let kept_ms = draw_time(&kept, runs);
        println!(
            "faces drawn {}, shown in the frame {}",
            view.polygon_count(),
            shown.len()
        );
        println!(
            "small triangles drawn alone             {all_ms:8.2} ms  ({} triangles)",
            small.len()
        );
        println!(
            "  only those an oracle culler keeps     {kept_ms:8.2} ms  ({} triangles)",
            kept.len()
        );
        println!(
            "lower bound: oracle's small + tiles     {:8.2} ms",
            kept_ms + phases[2]
        );
        Ok(())
    })?)
}

/// The view's triangles with a sample and at most [`BIG`] pixels on a side, set up
/// for the block rasterizer, with their encoded ids.
fn small_triangles(view: &PreparedView<'_>) -> Vec<(BlockSetup<3>, u32)> {
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
    out
}

/// The triangles of `small` not hidden in every 8x4 block of the finished frame they
/// overlap (the block's farthest key above the triangle's nearest).
fn oracle_kept(
    view: &PreparedView<'_>,
    frame: &obscura::Frame,
    small: &[(BlockSetup<3>, u32)],
) -> Vec<(BlockSetup<3>, u32)> {
    const BW: usize = 8;
    const BH: usize = 4;
    let (w, h) = (frame.width as usize, frame.height as usize);
    let near = match view.transform().key_depths() {
        DepthOfKey::Perspective { near } => f64::from(near),
        DepthOfKey::Orthographic { .. } => return small.to_vec(),
    };
    let (nx, ny) = (w.div_ceil(BW), h.div_ceil(BH));
    let mut farthest = vec![f64::INFINITY; nx * ny];
    for y in 0..h {
        for x in 0..w {
            let d = f64::from(frame.depth[y * w + x]);
            // A millionth nearer than the stored key: the oracle culls at least as much
            // as the exact test would.
            let key = if d.is_finite() {
                near / d * (1.0 + 1e-6)
            } else {
                0.0
            };
            let f = &mut farthest[(y / BH) * nx + x / BW];
            *f = f.min(key);
        }
    }
    small
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
        .collect()
}

/// The minimum over `runs` of the milliseconds to draw the triangles into a cleared
/// 1920x1080 buffer with the fastest kernel.
fn draw_time(tris: &[(BlockSetup<3>, u32)], runs: usize) -> f64 {
    let (mut keys, mut ids) = (vec![0f32; 1920 * 1080], vec![0u32; 1920 * 1080]);
    let mut best = f64::INFINITY;
    for _ in 0..runs {
        keys.fill(0.0);
        ids.fill(0);
        let t = Instant::now();
        draw_fastest(tris, &mut keys, &mut ids);
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    best
}

fn draw_fastest(tris: &[(BlockSetup<3>, u32)], keys: &mut [f32], ids: &mut [u32]) {
    #[cfg(target_arch = "x86_64")]
    if let Some(l) = obscura::raster::avx512::Avx512::new() {
        // SAFETY: `Avx512::new` checked the instructions `draw_avx512` enables.
        unsafe { draw_avx512(l, tris, keys, ids) };
        return;
    }
    draw(Portable, tris, keys, ids);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq,popcnt,bmi1,bmi2,lzcnt")]
fn draw_avx512(
    l: obscura::raster::avx512::Avx512,
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
